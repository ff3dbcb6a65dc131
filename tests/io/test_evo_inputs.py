"""evo's inputs (issue 23): repeated stamps kept as evo's readers keep them, TUM / EuRoC / KITTI
read as evo reads them, lone ROS 2 ``.mcap`` / ``.db3`` files, several topics of one bag, evo's TF
id syntax, and evo's ``--save_results`` zip files read into lorisnb's table (made with evo's API)."""

from __future__ import annotations

import copy
import shutil

import numpy as np
import pytest
from evo.core import metrics as em
from evo.core import sync
from evo.main_ape import ape
from evo.main_rpe import rpe
from evo.tools import file_interface as fi
from rosbags.rosbag2 import Reader as Rosbag2Reader

from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.errors import LorisWarning, ParseError, ValidationError
from lorisnb.io import read_tum
from lorisnb.io.readers.bags import read_bag, read_bag_topics, tf_chain
from lorisnb.io.readers.evo_results import read_evo_result
from lorisnb.io.readers.plain import read_euroc, read_kitti, read_trajectory
from lorisnb.tools.peers.evo_import import evo_results_table


def _traj(n=60, seed=0, t0=100.0):
    rng = np.random.default_rng(seed)
    stamps = t0 + np.cumsum(rng.uniform(0.05, 0.1, n))
    pos = np.cumsum(rng.normal(scale=0.1, size=(n, 3)), axis=0)
    q = rng.normal(size=(n, 4))
    return Trajectory(stamps, pos, q / np.linalg.norm(q, axis=1)[:, None])


def test_repeated_stamps_kept_as_evo_reads_them(data, tmp_path):
    path = data.tum / "fr2_desk_groundtruth.txt"
    evo_traj = fi.read_tum_trajectory_file(path)
    kept = read_tum(path, repeated="keep")
    dropped = read_tum(path)
    assert len(kept) == evo_traj.num_poses == len(dropped) + 1  # the ground truth repeats one stamp
    np.testing.assert_array_equal(kept.stamps, evo_traj.timestamps)
    np.testing.assert_array_equal(kept.positions, evo_traj.positions_xyz)
    np.testing.assert_array_equal(kept.quaternions, evo_traj.orientations_quat_wxyz[:, [1, 2, 3, 0]])
    with pytest.raises(ValidationError, match="repeated"):
        read_tum(path, repeated="first")
    # a stamp going backwards: both rules sort; "keep" keeps both poses of the repeated stamp in file order
    f = tmp_path / "t.txt"
    f.write_text("1 0 0 0 0 0 0 1\n3 1 0 0 0 0 0 1\n2 2 0 0 0 0 0 1\n3 3 0 0 0 0 0 1\n")
    assert read_tum(f, repeated="keep").positions[:, 0].tolist() == [0, 2, 1, 3]
    assert read_tum(f).positions[:, 0].tolist() == [0, 2, 3]


def test_euroc_and_kitti_read_as_evo(tmp_path):
    t = _traj(80, 3)
    t = Trajectory.from_checked(
        np.repeat(t.stamps, [2] + [1] * 79)[:80], t.positions, t.quaternions
    )  # a repeated stamp
    rows = [f"{int(round(s * 1e9))}," + ",".join(f"{v:.17g}" for v in (*p, q[3], q[0], q[1], q[2])) + ",0,0,0"
            for s, p, q in zip(t.stamps, t.positions, t.quaternions, strict=True)]  # fmt: skip
    f = tmp_path / "data.csv"
    f.write_text("#timestamp,p_x,p_y,p_z,q_w,q_x,q_y,q_z,v_x,v_y,v_z\n" + "\n".join(rows) + "\n")
    ours, theirs = read_euroc(f, repeated="keep"), fi.read_euroc_csv_trajectory(f)
    np.testing.assert_array_equal(ours.stamps, theirs.timestamps)  # nanoseconds / 1e9, bit for bit
    np.testing.assert_array_equal(ours.quaternions, theirs.orientations_quat_wxyz[:, [1, 2, 3, 0]])
    assert len(read_euroc(f)) == len(ours) - 1
    k = tmp_path / "poses.txt"
    mats = np.concatenate([t.rotations().as_matrix(), t.positions[:, :, None]], axis=2).reshape(-1, 12)
    k.write_text("\n".join(" ".join(f"{v:.6e}" for v in m) for m in mats) + "\n")  # KITTI's 7 digits
    path = fi.read_kitti_poses_file(k)
    kt = read_kitti(k)
    np.testing.assert_allclose(kt.positions, path.positions_xyz, rtol=0, atol=1e-12)
    with pytest.raises(ParseError, match="strictly increasing"):
        read_kitti(k, t.stamps)
    assert len(read_kitti(k, t.stamps, repeated="keep")) == 80


def _two_topic_mcap(folder, a: Trajectory, b: Trajectory, storage="mcap"):
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(folder, version=8, storage_plugin=plugin) as w:
        for topic, traj in (("/gt", a), ("/est", b)):
            conn = w.add_connection(topic, "geometry_msgs/msg/PoseStamped", typestore=ts)
            for t, p, q in zip(traj.stamps, traj.positions, traj.quaternions, strict=True):
                sec = int(np.floor(t))
                stamp = T["builtin_interfaces/msg/Time"](sec=sec, nanosec=int(round((t - sec) * 1e9)))
                pose = T["geometry_msgs/msg/Pose"](
                    position=T["geometry_msgs/msg/Point"](x=p[0], y=p[1], z=p[2]),
                    orientation=T["geometry_msgs/msg/Quaternion"](x=q[0], y=q[1], z=q[2], w=q[3]),
                )
                msg = T["geometry_msgs/msg/PoseStamped"](header=T["std_msgs/msg/Header"](stamp=stamp, frame_id="map"),
                                                         pose=pose)  # fmt: skip
                w.write(conn, int(round(t * 1e9)), ts.serialize_cdr(msg, "geometry_msgs/msg/PoseStamped"))
    return folder


@pytest.mark.parametrize("storage, suffix", [("mcap", ".mcap"), ("sqlite3", ".db3")])
def test_lone_ros2_file_and_several_topics_as_evo_reads_them(tmp_path, storage, suffix):
    gt, est = _traj(90, 1), _traj(40, 2)
    folder = _two_topic_mcap(tmp_path / "bag", gt, est, storage)
    lone = tmp_path / f"lone{suffix}"
    shutil.copy(next(folder.glob(f"*{suffix}")), lone)
    topics = read_bag_topics(lone)
    assert sorted(topics) == ["/est", "/gt"]
    assert read_bag(lone, topic="/gt").stamps.tolist() == topics["/gt"].stamps.tolist()
    assert read_trajectory(lone, "bag", topic="/est").stamps.size == 40
    reader = Rosbag2Reader(lone)
    reader.open()
    try:
        for name in ("/gt", "/est"):
            theirs = fi.read_bag_trajectory(reader, name)
            np.testing.assert_array_equal(topics[name].stamps, theirs.timestamps)
            np.testing.assert_array_equal(topics[name].positions, theirs.positions_xyz)
    finally:
        reader.close()
    assert sorted(read_bag_topics(folder / next(folder.glob(f"*{suffix}")).name, ["/gt"])) == ["/gt"]


def test_evo_tf_id_is_a_synonym():
    assert tf_chain("/tf:map.base_link") == "map:base_link"
    assert tf_chain("/tf:world.base:/tf_static") == "world:base"
    assert tf_chain("/pose") is None and tf_chain("map:base") is None


def test_tf_chain_read_with_evo_syntax(tmp_path):
    from helpers import write_bag

    t = _traj(30, 4)
    bag = write_bag(tmp_path / "tf.bag", t, 1, tf=("world", "odom", "base"))
    a = read_bag(bag, tf="world:base")
    b = read_bag(bag, topic="/tf:world.base")
    c = read_bag_topics(bag, ["/tf:world.base", "/pose"])
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(c["/tf:world.base"].positions, a.positions)
    assert len(c["/pose"]) == 30


def test_evo_result_zips_become_table_rows(data, tmp_path):
    ref = fi.read_tum_trajectory_file(data.tum / "freiburg1_xyz-groundtruth.txt")
    est = fi.read_tum_trajectory_file(data.tum / "freiburg1_xyz-rgbdslam.txt")
    r, e = sync.associate_trajectories(ref, est, max_diff=0.01)
    c = copy.deepcopy
    results = {
        "ape_t": ape(c(r), c(e), em.PoseRelation.translation_part, align=True),
        "ape_r": ape(c(r), c(e), em.PoseRelation.rotation_angle_rad, align=True),
        "rpe_t": rpe(c(r), c(e), em.PoseRelation.translation_part, delta=1.0, delta_unit=em.Unit.meters, align=True),
        "rpe_full": rpe(
            c(r), c(e), em.PoseRelation.full_transformation, delta=1, delta_unit=em.Unit.frames, align=True
        ),
    }
    for name, res in results.items():
        res.info["ref_name"], res.info["est_name"] = "groundtruth.txt", "rgbdslam.txt"
        fi.save_res_file(tmp_path / f"{name}.zip", res)
    one = read_evo_result(tmp_path / "ape_t.zip")
    assert (one.metric, one.relation) == ("ape", "trans_part")
    assert one.stats == pytest.approx(results["ape_t"].stats, rel=0)
    table = evo_results_table([tmp_path])
    assert len(table) == 2  # two evo_rpe runs (1 m, 1 frame): a row each, each with the same APE run
    assert table["rpe_delta"].str.contains("(m)", regex=False).sum() == 1 and table["ate_rmse"].nunique() == 1
    row = table.set_index("rpe_pairs").loc[len(results["rpe_t"].np_arrays["error_array"])]
    assert row["algorithm"] == "rgbdslam" and row["matched"] == r.num_poses
    for k, v in results["ape_t"].stats.items():
        assert row[f"ate_{k}"] == pytest.approx(v, rel=1e-15)
    assert row["aoe_rmse"] == pytest.approx(np.degrees(results["ape_r"].stats["rmse"]), rel=1e-12)
    assert row["aoe_sse"] == pytest.approx(np.degrees(1.0) ** 2 * results["ape_r"].stats["sse"], rel=1e-12)
    assert row["rpe_trans_max"] == pytest.approx(results["rpe_t"].stats["max"], rel=1e-15)
    full = table[table["rpe_full_rmse"].notna()].iloc[0]
    assert full["rpe_full_rmse"] == pytest.approx(results["rpe_full"].stats["rmse"], rel=1e-15)
    assert "Umeyama" in row["alignment"]
    bad = tmp_path / "x.zip"
    bad.write_text("no zip")
    with pytest.raises(ParseError, match="evo --save_results"):
        read_evo_result(bad)


def test_crosscheck_reading_shows_where_and_why(data, tmp_path):
    from lorisnb.tools.peers.crosscheck_reading import crosscheck_reading

    t = crosscheck_reading(data.tum / "fr2_desk_groundtruth.txt").set_index("quantity")
    assert not t.loc["poses", "agrees"] and "repeated" in t.loc["poses", "note"]
    assert t.loc["poses", "evo"] - t.loc["poses", "lorisnb"] == 1
    assert t.loc[["poses (repeated kept)", "stamps", "positions", "orientations"], "agrees"].all()
    k = tmp_path / "poses.txt"
    tr = _traj(50, 6)
    mats = np.concatenate([tr.rotations().as_matrix(), tr.positions[:, :, None]], axis=2).reshape(-1, 12)
    k.write_text("\n".join(" ".join(f"{v:.6e}" for v in m) for m in mats) + "\n")
    kt = crosscheck_reading(k, "kitti").set_index("quantity")
    assert 1e-8 < kt.loc["rotation block", "lorisnb"] < 1e-5 and kt.loc["rotation block", "agrees"]
    folder = _two_topic_mcap(tmp_path / "bag", _traj(30, 1), _traj(20, 2))
    lone = tmp_path / "lone.mcap"
    shutil.copy(next(folder.glob("*.mcap")), lone)
    b = crosscheck_reading(lone, "bag", "/est")
    assert b["agrees"].all() and b["n_pairs"].iloc[0] == 20


def test_several_topics_of_one_bag_in_one_run(tmp_path):
    from test_evo_parity import write_two_topic_bag

    from lorisnb.cli import main

    gt, est = _traj(200, 8), _traj(200, 9)
    est = Trajectory(gt.stamps, est.positions * 0.01 + gt.positions, gt.quaternions)
    bag = write_two_topic_bag(tmp_path / "run.bag", gt, est, 1)
    out = tmp_path / "t.csv"
    args = ["evaluate", str(bag), "--gt", str(bag), "--format", "bag", "--gt-topic", "/gt", "--conventions", "evo"]
    assert main([*args, "--topic", "/gt,/est", "--csv", str(out), "--no-progress"]) == 0
    import pandas as pd

    both = pd.read_csv(out).set_index("algorithm")
    assert sorted(both.index) == ["run:/est", "run:/gt"] and (both["file"] == "run.bag").all()
    assert both.loc["run:/gt", "ate_max"] == 0.0 and both.loc["run:/est", "ate_max"] > 0.0
    single = tmp_path / "s.csv"
    assert main([*args, "--topic", "/est", "--csv", str(single), "--no-progress"]) == 0
    assert pd.read_csv(single).iloc[0]["ate_rmse"] == both.loc["run:/est", "ate_rmse"]


def test_point_stamped_topic_as_evo_reads_it(tmp_path):
    from rosbags.rosbag1 import Reader, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    T = ts.types
    t = _traj(25, 11)
    bag = tmp_path / "points.bag"
    with Writer(bag) as w:
        conn = w.add_connection("/gps", "geometry_msgs/msg/PointStamped", typestore=ts)
        for s, p in zip(t.stamps, t.positions, strict=True):
            sec = int(np.floor(s))
            head = T["std_msgs/msg/Header"](seq=0, stamp=T["builtin_interfaces/msg/Time"](
                sec=sec, nanosec=int(round((s - sec) * 1e9))), frame_id="map")  # fmt: skip
            msg = T["geometry_msgs/msg/PointStamped"](
                header=head, point=T["geometry_msgs/msg/Point"](x=p[0], y=p[1], z=p[2])
            )
            w.write(conn, int(round(s * 1e9)), ts.serialize_ros1(msg, "geometry_msgs/msg/PointStamped"))
    with pytest.warns(LorisWarning, match="PointStamped messages .* AOE and anything with phi measure nothing"):
        ours = read_bag(bag)  # the only position topic: said to have no orientation, not scored as if it had
    assert ours.meta["positions_only"]
    r = Reader(bag)
    r.open()
    try:
        theirs = fi.read_bag_trajectory(r, "/gps")
    finally:
        r.close()
    np.testing.assert_array_equal(ours.stamps, theirs.timestamps)
    np.testing.assert_array_equal(ours.positions, theirs.positions_xyz)
    assert (ours.quaternions == [0.0, 0.0, 0.0, 1.0]).all()
