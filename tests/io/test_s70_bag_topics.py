"""Bags, topics and TF chains as an adversarial tester found them (s70):

- ``--topic /pose,/odom`` over a folder of two algorithms' bags was refused (both bags' rows were
  labelled ``/pose``, the topic alone, so the two algorithms collided); a bag given alone lost its
  name. Each row is now ``'<algorithm>:<topic>'``.
- a manifest session's notes named the algorithm's folder (``res/x, seq 2``), not the session's
  estimate file;
- a manifest's bag without a topic was told to use ``--topic or --tf``, which a manifest refuses;
  the message now names the manifest's keys;
- a TF chain dropped the poses outside a slower link's transforms without a word.
"""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import ParseError
from lorisnb.io.readers.bags import read_bag


def _rows(path: Path) -> tuple[np.ndarray, np.ndarray]:
    rows = [x.split() for x in path.read_text().splitlines() if x.strip() and not x.startswith("#")]
    a = np.array(rows, float)
    return a[:, 0], a[:, 1:]


def _types():
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    ts.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage"))
    return ts


def _header(T, t: float, frame: str = "world"):
    sec = int(np.floor(t))
    stamp = T["builtin_interfaces/msg/Time"](sec=sec, nanosec=int(round((t - sec) * 1e9)))
    return T["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id=frame)


def _pose(T, v):
    return T["geometry_msgs/msg/Pose"](
        position=T["geometry_msgs/msg/Point"](x=v[0], y=v[1], z=v[2]),
        orientation=T["geometry_msgs/msg/Quaternion"](x=v[3], y=v[4], z=v[5], w=v[6]),
    )


def _transform(T, v):
    return T["geometry_msgs/msg/Transform"](
        translation=T["geometry_msgs/msg/Vector3"](x=v[0], y=v[1], z=v[2]),
        rotation=T["geometry_msgs/msg/Quaternion"](x=v[3], y=v[4], z=v[5], w=v[6]),
    )


def _two_topic_bag(path: Path, stamps: np.ndarray, poses: np.ndarray, odom_shift: float = 0.0) -> Path:
    """A ROS 1 bag with the poses both as ``/pose`` (PoseStamped) and ``/odom`` (Odometry; its
    stamps ``odom_shift`` seconds later)."""
    from rosbags.rosbag1 import Writer

    ts = _types()
    T = ts.types
    path.parent.mkdir(parents=True, exist_ok=True)
    zero = T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)
    twist = T["geometry_msgs/msg/TwistWithCovariance"](
        twist=T["geometry_msgs/msg/Twist"](linear=zero, angular=zero), covariance=np.zeros(36)
    )
    with Writer(path) as w:
        cp = w.add_connection("/pose", "geometry_msgs/msg/PoseStamped", typestore=ts)
        co = w.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=ts)
        for t, v in zip(stamps, poses, strict=True):
            ns = int(round(t * 1e9))
            m = T["geometry_msgs/msg/PoseStamped"](header=_header(T, t), pose=_pose(T, v))
            w.write(cp, ns, ts.serialize_ros1(m, "geometry_msgs/msg/PoseStamped"))
            cov = T["geometry_msgs/msg/PoseWithCovariance"](pose=_pose(T, v), covariance=np.zeros(36))
            o = T["nav_msgs/msg/Odometry"](header=_header(T, t + odom_shift), child_frame_id="base", pose=cov,
                                           twist=twist)  # fmt: skip
            w.write(co, ns, ts.serialize_ros1(o, "nav_msgs/msg/Odometry"))
    return path


@pytest.fixture(scope="module")
def xyz(data):
    """fr1/xyz's rgbdslam estimate (788 poses) and ground truth."""
    est = data.tum / "freiburg1_xyz-rgbdslam.txt"
    return est, data.tum / "freiburg1_xyz-groundtruth.txt"


@pytest.fixture(scope="module")
def bags(xyz, tmp_path_factory):
    """res/algA/run.bag (the whole estimate) and res/algB/run.bag (its first 400 poses), each with
    /pose and /odom; and the estimate alone as orb.bag."""
    folder = tmp_path_factory.mktemp("s70bags")
    t, v = _rows(xyz[0])
    _two_topic_bag(folder / "res" / "algA" / "run.bag", t, v)
    _two_topic_bag(folder / "res" / "algB" / "run.bag", t[:400], v[:400])
    _two_topic_bag(folder / "orb.bag", t, v)
    return folder


def _quiet(f, *a, **k):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return f(*a, **k)


def test_several_topics_of_a_folder_of_algorithms_bags_are_told_apart(bags, xyz, capsys):
    ev = _quiet(ln.evaluate_pairs, bags / "res", xyz[1], fmt="bag", gt_fmt="tum", topic="/pose,/odom")
    assert not ev.failures
    rows = ev.sequences().set_index("algorithm")
    assert sorted(rows.index) == ["algA:/odom", "algA:/pose", "algB:/odom", "algB:/pose"]
    assert rows.loc["algA:/pose", "poses"] == rows.loc["algA:/odom", "poses"] == 788
    assert rows.loc["algB:/pose", "poses"] == rows.loc["algB:/odom", "poses"] == 400
    assert rows.loc["algA:/pose", "ate_rmse"] == pytest.approx(rows.loc["algA:/odom", "ate_rmse"], rel=1e-12)
    rc = main(["evaluate", str(bags / "res"), "--gt", str(xyz[1]), "--format", "bag", "--gt-format", "tum",
               "--topic", "/pose,/odom", "--no-progress"])  # fmt: skip
    out = capsys.readouterr()
    assert rc == 0, out.err
    assert "both hold" not in out.err
    for label in ("algA:/pose", "algA:/odom", "algB:/pose", "algB:/odom"):
        assert label in out.out


def test_several_topics_of_a_bag_given_alone_keep_its_name(bags, xyz, tmp_path, capsys):
    ev = _quiet(ln.evaluate_pairs, bags / "orb.bag", xyz[1], fmt="bag", gt_fmt="tum", topic="/pose,/odom")
    assert list(ev.sequences()["algorithm"]) == ["orb:/pose", "orb:/odom"]
    one = _quiet(ln.evaluate_pairs, bags / "orb.bag", xyz[1], fmt="bag", gt_fmt="tum", topic="/pose")
    assert list(one.sequences()["algorithm"]) == ["orb"]  # one topic: the bag's name, as before
    csv = tmp_path / "rows.csv"
    rc = main(["evaluate", str(bags / "orb.bag"), "--gt", str(xyz[1]), "--format", "bag", "--gt-format", "tum",
               "--topic", "/pose,/odom", "--csv", str(csv), "--no-progress"])  # fmt: skip
    assert rc == 0, capsys.readouterr().err
    text = csv.read_text()
    assert "orb:/pose" in text and "orb:/odom" in text


def _tf_bag(path: Path, stamps: np.ndarray, poses: np.ndarray, slow: list[float]) -> Path:
    """The poses as the TF chain map -> odom -> base_link: ``map -> odom`` a constant offset sent on
    /tf at the stamps ``slow``, ``odom -> base_link`` at every pose."""
    from rosbags.rosbag1 import Writer
    from scipy.spatial.transform import Rotation

    ts = _types()
    T = ts.types
    off, q_off = np.array([1.0, 2.0, 0.5]), Rotation.from_euler("z", 30, degrees=True)
    with Writer(path) as w:
        c = w.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=ts)

        def send(t: float, parent: str, child: str, v) -> None:
            tr = T["geometry_msgs/msg/TransformStamped"](header=_header(T, t, parent), child_frame_id=child,
                                                         transform=_transform(T, v))  # fmt: skip
            m = T["tf2_msgs/msg/TFMessage"](transforms=[tr])
            w.write(c, int(round(t * 1e9)), ts.serialize_ros1(m, "tf2_msgs/msg/TFMessage"))

        for t in slow:
            send(t, "map", "odom", [*off, *q_off.as_quat()])
        for t, v in zip(stamps, poses, strict=True):
            q = q_off.inv() * Rotation.from_quat(v[3:])
            send(t, "odom", "base_link", [*q_off.inv().apply(v[:3] - off), *q.as_quat()])
    return path


def test_the_notes_on_one_of_several_topics_name_the_topic(xyz, tmp_path, capsys):
    """A note about one topic of a bag read on several names the topic: the same bag's notes
    were said once for every topic, leaving the user to guess which topic was meant."""
    t, v = _rows(xyz[0])
    bag = _two_topic_bag(tmp_path / "orb.bag", t, v, odom_shift=5000.0)  # /odom: another recording's time
    ev = _quiet(ln.evaluate_pairs, bag, xyz[1], fmt="bag", gt_fmt="tum", topic="/pose,/odom")
    said = [w for w in ev.warnings if "no estimate stamp" in w]
    assert len(said) == 1 and said[0].startswith(f"{bag} (topic /odom), seq 1: "), said
    rows = ev.sequences().set_index("algorithm")
    assert rows.loc["orb:/pose", "matched"] > 700 and rows.loc["orb:/odom", "matched"] == 0
    rc = main(["evaluate", str(bag), "--gt", str(xyz[1]), "--format", "bag", "--gt-format", "tum",
               "--topic", "/pose,/odom", "--no-progress"])  # fmt: skip
    err = capsys.readouterr().err
    assert rc == 1 and f"warning: {bag} (topic /odom), seq 1: no estimate stamp" in err, err


def test_a_tf_chain_says_the_poses_a_slower_link_drops(xyz, tmp_path, capsys):
    """map -> odom every 5 s (the tester's tf5.bag): the poses after its last transform are dropped,
    as tf2 and evo drop them, and now said."""
    t, v = _rows(xyz[0])
    slow = list(np.arange(t[0], t[-1], 5.0))
    bag = _tf_bag(tmp_path / "tf5.bag", t, v, slow)
    dropped = int((t > slow[-1]).sum())
    assert dropped > 0
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        chain = read_bag(bag, tf="map:base_link")
    assert len(chain) == len(t) - dropped  # the numbers are kept: not extrapolated
    assert np.allclose(chain.positions, v[: len(chain), :3], atol=1e-6)
    said = [str(w.message) for w in caught if "dropped" in str(w.message)]
    assert len(said) == 1
    assert said[0].startswith(f"{bag} TF map:base_link: {dropped} of {len(t)} poses of the chain dropped")
    assert "the link map->odom" in said[0] and f"{slow[-1]:.3f} s" in said[0]
    rc = main(["evaluate", str(bag), "--gt", str(xyz[1]), "--format", "bag", "--gt-format", "tum", "--tf",
               "map:base_link", "--no-progress"])  # fmt: skip
    err = capsys.readouterr().err
    assert rc == 0 and f"{dropped} of {len(t)} poses of the chain dropped" in err and "map->odom" in err
    full = _tf_bag(tmp_path / "full.bag", t, v, [*slow, float(t[-1])])  # the link over the whole run: no note
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert len(read_bag(full, tf="map:base_link")) == len(t)
    assert not [w for w in caught if "dropped" in str(w.message)]


def test_a_tf_chain_no_pose_of_which_a_link_brackets_is_refused(xyz, tmp_path):
    """Every pose of the chain outside the slow link's transforms: refused naming the link."""
    t, v = _rows(xyz[0])
    bag = _tf_bag(tmp_path / "before.bag", t[:40], v[:40], [t[0] - 10.0, t[0] - 5.0])
    with pytest.raises(ParseError, match="40 of 40 poses of the chain dropped: no transform of the link map->odom"):
        _quiet(read_bag, bag, tf="map:base_link")


def _manifest(folder: Path, body: str) -> Path:
    m = folder / "m.toml"
    m.write_text(body)
    return m


def test_a_manifest_sessions_notes_name_its_estimate_file(xyz, tmp_path, capsys, monkeypatch):
    """A session whose estimate is of another recording (5,000 s later): its note names the file
    and the session, not the algorithm's folder."""
    gt = tmp_path / "gt"
    gt.mkdir()
    shutil.copy(xyz[1], gt / "a.txt")
    shutil.copy(xyz[1], gt / "b.txt")
    res = tmp_path / "res" / "x"
    res.mkdir(parents=True)
    shutil.copy(xyz[0], res / "a.txt")
    lines = [x.split() for x in xyz[0].read_text().splitlines() if x.strip() and not x.startswith("#")]
    (res / "b.txt").write_text("".join(f"{float(r[0]) + 5000.0:.6f} {' '.join(r[1:])}\n" for r in lines))
    m = _manifest(tmp_path, 'name = "two"\nscene = "mix"\nroot = "gt"\ngroundtruth_format = "tum"\n'
                  'estimate_format = "tum"\n[[session]]\nname = "a"\ngroundtruth = "a.txt"\n'
                  '[[session]]\nname = "b"\ngroundtruth = "b.txt"\n')  # fmt: skip
    monkeypatch.chdir(tmp_path)
    ev = _quiet(ln.evaluate_manifest, "m.toml", "res/x")
    said = [w for w in ev.warnings if "no estimate stamp" in w]
    assert len(said) == 1 and said[0].startswith("res/x/b.txt (session 'b', seq 2): "), said
    assert not any(w.startswith("res/x, seq") for w in ev.warnings)
    rows = ev.sequences().set_index("seq")
    assert rows.loc[1, "matched"] > 700 and rows.loc[2, "matched"] == 0
    rc = main(["evaluate", "res/x", "--manifest", str(m.name), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 1 and "warning: res/x/b.txt (session 'b', seq 2): no estimate stamp" in err, err


def test_a_manifest_bag_without_a_topic_is_told_the_manifests_keys(bags, xyz, tmp_path, capsys):
    (tmp_path / "gt").mkdir()
    shutil.copy(bags / "orb.bag", tmp_path / "gt" / "g.bag")
    (tmp_path / "res" / "orb").mkdir(parents=True)
    shutil.copy(bags / "orb.bag", tmp_path / "res" / "orb" / "s.bag")
    head = 'name = "b"\nscene = "desk"\nroot = "gt"\ngroundtruth_format = "bag"\nestimate_format = "bag"\n'
    session = '[[session]]\nname = "s"\ngroundtruth = "g.bag"\n'
    m = _manifest(tmp_path, head + 'groundtruth_topic = "/pose"\n' + session)
    ev = _quiet(ln.evaluate_manifest, m, tmp_path / "res")
    assert len(ev.failures) == 1
    error = ev.failures[0].error
    assert f"estimate_topic = '/topic' or estimate_tf = 'parent:child' in {m}" in error, error
    assert "--topic" not in error and "--tf" not in error
    rc = main(["evaluate", str(tmp_path / "res"), "--manifest", str(m), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 1 and "estimate_topic = '/topic'" in err and "--topic" not in err
    m = _manifest(tmp_path, head + 'estimate_topic = "/pose"\n' + session)  # the ground truth's key missing
    ev = _quiet(ln.evaluate_manifest, m, tmp_path / "res")
    error = ev.failures[0].error
    assert f"groundtruth_topic = '/topic' or groundtruth_tf = 'parent:child' in {m}" in error, error
    assert "--gt-topic" not in error
    m = _manifest(tmp_path, head + 'estimate_tf = "map"\ngroundtruth_topic = "/pose"\n' + session)
    error = _quiet(ln.evaluate_manifest, m, tmp_path / "res").failures[0].error
    assert "estimate_tf = 'map': expected 'parent:child' frame names" in error and "--tf" not in error, error


def test_several_topics_of_a_monocular_algorithms_bag_are_aligned_as_it_is(xyz, tmp_path):
    """``dso:/pose`` is dso's row: scale="auto" aligns it with Sim(3), as ``dso`` alone (one topic) is;
    the exact name decided before, so a second topic turned the alignment to SE(3)."""
    t, v = _rows(xyz[0])
    bag = _two_topic_bag(tmp_path / "res" / "dso" / "run.bag", t, v)
    both = _quiet(ln.evaluate_pairs, tmp_path / "res", xyz[1], fmt="bag", gt_fmt="tum", topic="/pose,/odom",
                  scale="auto").sequences().set_index("algorithm")  # fmt: skip
    one = _quiet(ln.evaluate_pairs, tmp_path / "res", xyz[1], fmt="bag", gt_fmt="tum", topic="/pose",
                 scale="auto").sequences().set_index("algorithm")  # fmt: skip
    sim3 = _quiet(ln.evaluate_pairs, bag, xyz[1], fmt="bag", gt_fmt="tum", topic="/pose", align="sim3").sequences()
    se3 = _quiet(ln.evaluate_pairs, bag, xyz[1], fmt="bag", gt_fmt="tum", topic="/pose", align="se3").sequences()
    assert float(sim3["ate_rmse"].iloc[0]) != float(se3["ate_rmse"].iloc[0])  # the two alignments differ here
    assert float(one.loc["dso", "ate_rmse"]) == float(sim3["ate_rmse"].iloc[0])
    for label in ("dso:/pose", "dso:/odom"):
        assert float(both.loc[label, "ate_rmse"]) == pytest.approx(float(sim3["ate_rmse"].iloc[0]), rel=1e-12)
