"""A user's own bags, manifests and schedulers: bags of every writer rosbags has (ROS 1, ROS 2
sqlite3 and mcap) score as the same poses in a TUM file; a topic of another type, a bag without
pose topics, a misspelt file in a bag folder and a bad message are named as such; a manifest's
misspelt built-in name, empty session name or single [session] table say what to write; a
tls:// scheduler without TLS settings is one error, not a traceback (loopback only)."""

from __future__ import annotations

import socket
import threading
from pathlib import Path

import numpy as np
import pytest
from helpers import write
from scipy.spatial.transform import Rotation

import lorisnb as ln
from lorisnb.errors import EvaluationError, ParseError
from lorisnb.io.datasets.manifest import read_manifest
from lorisnb.io.readers.bags import read_bag

pytest.importorskip("rosbags")

PS = "geometry_msgs/msg/PoseStamped"


def _trajectories(n: int = 200) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Stamps, ground truth (positions, quaternions) and a noisy estimate of it (positions, quaternions)."""
    rng = np.random.default_rng(7)
    t = 1700000000.0 + np.arange(n) * 0.05
    pos = np.c_[np.cos(t - t[0]), np.sin(t - t[0]), 0.1 * (t - t[0])]
    rot = Rotation.from_euler("z", (t - t[0])[:, None] * 0.5)
    est_pos = pos + rng.normal(0, 0.02, pos.shape)
    est_rot = Rotation.from_rotvec(rng.normal(0, 0.02, (n, 3))) * rot
    return t, pos, rot.as_quat(), est_pos, est_rot.as_quat()


def _bag(path: Path, ros: int, topics: dict[str, tuple[str, list]], storage: str = "sqlite3") -> Path:
    """A bag with ``{topic: (msgtype, [(stamp, position, quaternion), ...])}``; PoseStamped, Pose
    (no header) and std_msgs String (a topic of another type) messages."""
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC if ros == 1 else Stores.ROS2_HUMBLE)
    T = ts.types

    def message(kind: str, t: float, p, q):
        if kind == "std_msgs/msg/String":
            return T[kind](data="not a pose")
        sec = int(t)
        stamp = T["builtin_interfaces/msg/Time"](sec=sec, nanosec=int(round((t - sec) * 1e9)))
        header = T["std_msgs/msg/Header"](**({"seq": 0} if ros == 1 else {}), stamp=stamp, frame_id="map")
        pose = T["geometry_msgs/msg/Pose"](
            position=T["geometry_msgs/msg/Point"](x=p[0], y=p[1], z=p[2]),
            orientation=T["geometry_msgs/msg/Quaternion"](x=q[0], y=q[1], z=q[2], w=q[3]),
        )
        return pose if kind == "geometry_msgs/msg/Pose" else T[kind](header=header, pose=pose)

    if ros == 1:
        from rosbags.rosbag1 import Writer

        writer = Writer(path)
    else:
        from rosbags.rosbag2 import StoragePlugin
        from rosbags.rosbag2 import Writer as Writer2

        plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
        writer = Writer2(path, version=8, storage_plugin=plugin)  # type: ignore[assignment]
    with writer:
        for topic, (kind, poses) in topics.items():
            conn = writer.add_connection(topic, kind, typestore=ts)
            for t, p, q in poses:
                m = message(kind, float(t), p, q)
                data = ts.serialize_ros1(m, kind) if ros == 1 else ts.serialize_cdr(m, kind)
                writer.write(conn, int(round(t * 1e9)) + 5 * 10**9, data)  # receive times 5 s after the stamps
    return path


def _poses(t, p, q) -> list:
    return list(zip(t, p, q, strict=True))


def _tum(path: Path, t, p, q) -> Path:
    np.savetxt(path, np.c_[t, p, q], fmt="%.17g")
    return path


@pytest.mark.parametrize(("ros", "storage"), [(1, ""), (2, "sqlite3"), (2, "mcap")])
def test_a_bag_scores_as_the_same_poses_in_a_tum_file(tmp_path, ros, storage):
    t, gp, gq, ep, eq = _trajectories()
    gt = _tum(tmp_path / "gt.txt", t, gp, gq)
    est_txt = _tum(tmp_path / "est.txt", t, ep, eq)
    bag = _bag(
        tmp_path / ("est.bag" if ros == 1 else f"est_{storage}"), ros, {"/est": (PS, _poses(t, ep, eq))}, storage
    )
    tum = ln.evaluate_pairs([est_txt], gt, "tum", eps=0.05, phi=5.0).sequences()
    got = ln.evaluate_pairs([bag], gt, "tum", fmt="bag", gt_fmt="tum", eps=0.05, phi=5.0).sequences()
    assert len(got) == len(tum) == 1
    assert int(got["matched"].iloc[0]) == int(tum["matched"].iloc[0]) == 200  # header stamps, not receive times
    for col in ("ate_rmse", "aoe_rmse", "cr", "cr_t", "c_ate_rmse", "rpe_trans_rmse"):
        assert got[col].iloc[0] == pytest.approx(tum[col].iloc[0], rel=1e-9, abs=1e-12), col
    assert 0.02 < tum["ate_rmse"].iloc[0] < 0.05


@pytest.mark.parametrize("ros", [1, 2])
def test_a_topic_of_another_type_is_named_with_its_type(tmp_path, ros):
    t, gp, gq, *_ = _trajectories(5)
    poses = _poses(t, gp, gq)
    bag = _bag(
        tmp_path / ("b.bag" if ros == 1 else "b"), ros, {"/est": (PS, poses), "/str": ("std_msgs/msg/String", poses)}
    )
    with pytest.raises(ParseError, match=r"topic '/str' holds std_msgs/msg/String messages, not poses; expected "
                       r"PoseStamped, .*; pose topics in this bag: /est \(PoseStamped\)"):  # fmt: skip
        read_bag(bag, topic="/str")
    with pytest.raises(ParseError, match=r"no pose topic '/odom'; pose topics in this bag: /est \(PoseStamped\)"):
        read_bag(bag, topic="/odom")


def test_a_bag_without_pose_topics_lists_its_topics(tmp_path):
    t, gp, gq, *_ = _trajectories(5)
    bag = _bag(tmp_path / "b", 2, {"/pose": ("geometry_msgs/msg/Pose", _poses(t, gp, gq))})
    with pytest.raises(ParseError, match=r"no pose topic in this bag; its topics: /pose \(geometry_msgs/msg/Pose\)"):
        read_bag(bag)


def test_the_choice_of_a_topic_names_the_ground_truth_options(tmp_path):
    t, gp, gq, ep, eq = _trajectories()
    bag = _bag(tmp_path / "gt.bag", 1, {"/a": (PS, _poses(t, gp, gq)), "/b": (PS, _poses(t, gp, gq))})
    est = _tum(tmp_path / "est.txt", t, ep, eq)
    ev = ln.evaluate_pairs([est], bag, "tum", gt_fmt="bag")
    assert ev.exit_status() == 1
    (failure,) = ev.failures
    assert "--gt-topic or --gt-tf for the ground truth" in failure.error
    assert "/a (PoseStamped), /b (PoseStamped)" in failure.error


def test_a_misspelt_file_of_a_bag_folder_is_not_found(tmp_path):
    t, gp, gq, *_ = _trajectories(20)
    bag = _bag(tmp_path / "run", 2, {"/est": (PS, _poses(t, gp, gq))})
    (db3,) = bag.glob("*.db3")
    assert len(read_bag(db3)) == 20  # the bag's own file: the whole bag
    with pytest.raises(ParseError, match=r"run/rn\.db3: file not found"):
        read_bag(bag / "rn.db3")


def test_a_bad_message_is_named_by_its_number_not_a_line(tmp_path):
    t, gp, gq, *_ = _trajectories(5)
    q = gq.copy()
    q[2] = 0.0
    bag = _bag(tmp_path / "b.bag", 1, {"/est": (PS, _poses(t, gp, q))})
    with pytest.raises(ParseError, match=r"b\.bag /est, message 3: quaternion has zero norm") as info:
        read_bag(bag)
    assert "line" not in str(info.value)


@pytest.mark.parametrize(
    ("given", "near"),
    [
        ("euroc_vicon_room1", "euroc-vicon-room1"),
        ("EuRoC-Vicon-Room1", "euroc-vicon-room1"),
        ("tum-fr1-office.toml", "tum-fr1-office"),
        ("openlors", "openloris"),
    ],
)
def test_a_misspelt_built_in_manifest_gets_its_name(tmp_path, monkeypatch, given, near):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ParseError, match=rf"^{given}: manifest not found \(did you mean '{near}'\?\); expected"):
        read_manifest(given)


SESSION = '[[session]]\nname = "s1"\ngroundtruth = "gt.txt"\n'


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            '[[session]]\nname = ""\ngroundtruth = "gt.txt"\n',
            r"\[\[session\]\] 1: name = '': expected a non-empty name",
        ),
        (
            '[[session]]\nname = "s1"\ngroundtruth = " "\n',
            r"\[\[session\]\] 1: groundtruth = ' ': expected a non-empty",
        ),
        (
            '[session]\nname = "s1"\ngroundtruth = "gt.txt"\n',
            r"no \[\[session\]\] table \(\[session\] is one table: "
            r"write \[\[session\]\], two brackets, before each session\)",
        ),  # fmt: skip
    ],
)
def test_a_session_table_that_names_nothing_is_refused(tmp_path, text, message):
    t, gp, gq, *_ = _trajectories(5)
    _tum(tmp_path / "gt.txt", t, gp, gq)
    with pytest.raises(ParseError, match=message):
        read_manifest(write(tmp_path, "m.toml", text))
    assert [s.name for s in read_manifest(write(tmp_path, "ok.toml", SESSION)).sessions] == ["s1"]


def test_a_tls_scheduler_without_tls_settings_is_one_error(monkeypatch):
    pytest.importorskip("distributed")
    import dask

    from lorisnb.tools.evaluation.pool import connect_scheduler

    server = socket.create_server(("127.0.0.1", 0))  # loopback: accepts, then says nothing
    port = server.getsockname()[1]
    accepted: list[socket.socket] = []
    thread = threading.Thread(target=lambda: accepted.append(server.accept()[0]), daemon=True)
    thread.start()
    try:
        with dask.config.set({"distributed.comm.tls.ca-file": None, "distributed.comm.tls.client.cert": None}):
            with pytest.raises(
                EvaluationError, match=rf"^--scheduler tls://127\.0\.0\.1:{port}: tls:// needs Dask's TLS"
            ):
                connect_scheduler(f"tls://127.0.0.1:{port}", timeout=2.0)
    finally:
        thread.join(timeout=2.0)
        for s in accepted:
            s.close()
        server.close()


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_a_bag_folder_in_a_walked_folder_is_one_input(tmp_path, storage):
    """A ROS 2 bag folder found by walking a results folder is one input, not also its .db3 /
    .mcap file (both held the same run: "... both hold ..." and exit status 2)."""
    from lorisnb.tools.evaluation.inputs import result_files

    t, gp, gq, ep, eq = _trajectories()
    gt = _tum(tmp_path / "gt.txt", t, gp, gq)
    (tmp_path / "runs" / "alg").mkdir(parents=True)
    bag = _bag(tmp_path / "runs" / "alg" / "run_3", 2, {"/est": (PS, _poses(t, ep, eq))}, storage)
    assert [f for f, _ in result_files([tmp_path / "runs"], (".txt", ".bag", ".db3", ".mcap"))] == [bag]
    got = ln.evaluate_pairs([tmp_path / "runs"], gt, "tum", fmt="bag", gt_fmt="tum").sequences()
    assert len(got) == 1 and int(got["matched"].iloc[0]) == 200


@pytest.mark.parametrize("ros", [1, 2])
def test_a_tf_chain_keeps_the_last_pose_of_a_repeated_stamp_as_a_pose_topic_does(tmp_path, ros):
    """Every pose written twice at one stamp, the second 5 cm further along x: the pose topic keeps
    the second at every stamp, the TF chain kept it too except at the last stamp (the span's end
    took the first), so the two routes of the same poses scored differently."""
    from types import SimpleNamespace

    from helpers import write_bag

    t, p, q, _, _ = _trajectories()
    twice = SimpleNamespace(stamps=np.repeat(t, 2), positions=np.repeat(p, 2, axis=0) + np.tile([[0, 0, 0], [0.05, 0, 0]],
                            (len(t), 1)), quaternions=np.repeat(q, 2, axis=0))  # fmt: skip
    bag = write_bag(tmp_path / ("b.bag" if ros == 1 else "b"), twice, ros, tf=("world", "odom", "base"))
    with pytest.warns(ln.LorisWarning, match="kept the last pose of each stamp"):
        chain = read_bag(bag, tf="world:base")
    with pytest.warns(ln.LorisWarning):
        topic = read_bag(bag, topic="/pose")
    np.testing.assert_allclose(chain.positions, p + [0.05, 0, 0], atol=1e-12)  # the last of each stamp, the end too
    np.testing.assert_allclose(chain.positions, topic.positions, atol=1e-12)
