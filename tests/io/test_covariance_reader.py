"""Reading trajectories with pose covariances (:mod:`lorisnb.io.readers.covariance`): ov_eval's text
layout and ROS bags (PoseWithCovarianceStamped, Odometry), the covariances following their poses,
bad lines named, and ``lorisnb consistency`` on them."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import synthetic_covariances, write, write_bag, write_ov_eval_file

from lorisnb.cli import main
from lorisnb.core.metrics.consistency import PoseCovariances
from lorisnb.errors import ParseError, ValidationError
from lorisnb.io.readers.covariance import read_covariances
from lorisnb.io.readers.plain import read_tum

GT, EST = "freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"


@pytest.fixture(scope="module")
def real(data):
    est = read_tum(data.tum / EST, warn=False)
    return est, synthetic_covariances(est.stamps)


def test_text_layout_round_trips(real, tmp_path):
    est, (co, cp) = real
    traj, cov = read_covariances(write_ov_eval_file(tmp_path / "e.txt", est, co, cp))
    np.testing.assert_array_equal(traj.stamps, est.stamps)
    np.testing.assert_array_equal(traj.positions, est.positions)
    np.testing.assert_allclose(cov.orientation, co, rtol=1e-15)
    np.testing.assert_allclose(cov.position, cp, rtol=1e-15)


def test_unsorted_lines_keep_their_covariances(real, tmp_path):
    est, (co, cp) = real
    path = write_ov_eval_file(tmp_path / "e.txt", est, co, cp)
    lines = path.read_text().splitlines()
    body = lines[1:]
    body[10], body[11] = body[11], body[10]  # two poses out of order
    path.write_text("\n".join([lines[0], *body]) + "\n")
    with pytest.warns(UserWarning, match="not increasing"):
        traj, cov = read_covariances(path)
    np.testing.assert_array_equal(traj.stamps, est.stamps)
    np.testing.assert_allclose(cov.position, cp, rtol=1e-15)


@pytest.mark.parametrize(
    ("line", "match"),
    [
        ("1.0 0 0 0 0 0 0 1", r"line 3: .*8 fields; expected 20 numbers.*required=False"),
        ("1.0 0 0 0 0 0 0 1 1 0 0 1 0 1 1 0 0 1 0 x", r"line 3"),
        ("1.0 0 0 0 0 0 0 0 1 0 0 1 0 1 1 0 0 1 0 1", r"line 3: .*quaternion"),
    ],
)
def test_a_bad_line_is_named(tmp_path, line, match):
    good = "0.5 0 0 0 0 0 0 1 1 0 0 1 0 1 1 0 0 1 0 1"
    path = write(tmp_path, "e.txt", f"# header\n{good}\n{line}\n")
    with pytest.raises(ParseError, match=match):
        read_covariances(path)


def test_a_tum_file_is_read_without_covariances_only_when_allowed(data):
    with pytest.raises(ParseError, match="8 fields"):
        read_covariances(data.tum / EST)
    traj, cov = read_covariances(data.tum / EST, required=False)
    assert cov is None and len(traj) == len(read_tum(data.tum / EST, warn=False))


@pytest.mark.parametrize(("ros", "msgtype"), [(1, "geometry_msgs/msg/PoseWithCovarianceStamped"),
                                              (2, "nav_msgs/msg/Odometry")])  # fmt: skip
def test_bag_covariances_are_the_text_layouts(real, tmp_path, ros, msgtype):
    """A bag's 6x6 covariance (x, y, z, then rotations) gives the same blocks as ov_eval's Recorder
    writes: the position block top left, the orientation block bottom right."""
    est, (co, cp) = real
    six = np.zeros((len(est), 6, 6))
    six[:, :3, :3], six[:, 3:, 3:] = cp, co
    six[:, :3, 3:] = 1e-7  # cross terms: not part of either block
    six[:, 3:, :3] = 1e-7
    bag = write_bag(tmp_path / ("b.bag" if ros == 1 else "b2"), est, ros, msgtype=msgtype, topic="/ov_msckf/poseimu",
                    covariances=six.reshape(-1, 36))  # fmt: skip
    traj, cov = read_covariances(bag)
    np.testing.assert_allclose(traj.stamps, est.stamps, atol=1e-9)
    np.testing.assert_allclose(cov.orientation, co, rtol=1e-12)
    np.testing.assert_allclose(cov.position, cp, rtol=1e-12)


def test_a_bad_covariance_in_a_bag_names_its_message(real, tmp_path):
    est, _ = real
    six = np.tile(np.eye(6).reshape(1, 36), (len(est), 1))
    six[4, 0] = np.nan
    bag = write_bag(tmp_path / "b.bag", est, 1, msgtype="geometry_msgs/msg/PoseWithCovarianceStamped", topic="/p",
                    covariances=six)  # fmt: skip
    with pytest.raises(ParseError, match=r"b.bag /p, message 5: the covariance of this message is not finite"):
        read_covariances(bag)


def test_a_bag_without_covariances(real, tmp_path):
    est, _ = real
    bag = write_bag(tmp_path / "p.bag", est, 1, topic="/pose")
    with pytest.raises(ParseError, match="such topics in this bag: none"):
        read_covariances(bag)
    traj, cov = read_covariances(bag, required=False)
    assert cov is None and len(traj) == len(est)
    with pytest.raises(ParseError, match="'/odom' is not in this bag"):
        read_covariances(bag, topic="/odom")


def test_a_topic_for_a_text_file_is_refused(real, tmp_path):
    est, (co, cp) = real
    with pytest.raises(ValidationError, match="no topics"):
        read_covariances(write_ov_eval_file(tmp_path / "e.txt", est, co, cp), topic="/pose")


def test_from_ros_and_from_upper_agree():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(4, 6, 6))
    six = a @ a.transpose(0, 2, 1)
    c = PoseCovariances.from_ros(six.reshape(-1, 36))
    iu = ([0, 0, 0, 1, 1, 2], [0, 1, 2, 1, 2, 2])
    upper = np.concatenate([six[:, 3:, 3:][:, iu[0], iu[1]], six[:, :3, :3][:, iu[0], iu[1]]], axis=1)
    d = PoseCovariances.from_upper(upper)
    np.testing.assert_allclose(c.orientation, d.orientation)
    np.testing.assert_allclose(c.position, d.position)


@pytest.mark.thorough
def test_command_line(real, data, tmp_path, capsys):
    est, (co, cp) = real
    path = write_ov_eval_file(tmp_path / "e.txt", est, co, cp)
    out, summary, plot = tmp_path / "poses.csv", tmp_path / "summary.csv", tmp_path / "axes.png"
    args = ["consistency", str(path), str(data.tum / GT), "--csv", str(out), "--summary-csv", str(summary),
            "--plot", str(plot)]  # fmt: skip
    assert main(args) == 0
    printed = capsys.readouterr().out
    assert "nees_pos" in printed and "NEES mean: orientation 2.94644, position 1.78398" in printed
    import pandas as pd

    poses = pd.read_csv(out)
    assert len(poses) == 786 and {"nees_ori", "pos_x_3sigma", "yaw_3sigma", "ate2d_yaw"} <= set(poses.columns)
    assert pd.read_csv(summary).set_index("series").loc["ate_pos", "count"] == 786
    assert plot.stat().st_size > 10_000
    assert main(args) == 2  # outputs exist: refused without --force, nothing overwritten
    assert "exists" in capsys.readouterr().err
    bad = ["consistency", str(path), str(data.tum / GT), "--gt-topic", "/pose"]
    assert main(bad) == 2
    assert "--gt-format bag" in capsys.readouterr().err
    elsewhere = write(tmp_path, "far.txt", "".join(f"{9e8 + i} 0 0 {i} 0 0 0 1\n" for i in range(10)))
    assert main(["consistency", str(path), str(elsewhere)]) == 1  # nothing pairs: not scored
    assert "share a clock" in capsys.readouterr().err
    assert main(["consistency", str(data.tum / EST), str(data.tum / GT), "--align", "se3"]) == 0
    err = capsys.readouterr().err
    assert "carries no covariances" in err
    assert main(["consistency", str(path), str(data.tum / GT), "--seq", "2"]) == 2  # a TUM ground truth has no seq
    assert "--seq applies to an OpenLORIS ground truth" in capsys.readouterr().err
    for digits in ("0", "100", "2.5"):  # 100 printed 50-digit numbers: a float64 holds 17
        with pytest.raises(SystemExit):
            main(["consistency", str(path), str(data.tum / GT), "--digits", digits])
        assert "expected a whole number of significant digits from 1 to 17" in capsys.readouterr().err


def test_command_line_on_an_openloris_ground_truth_takes_its_sequence(data, tmp_path, capsys):
    """A ground truth of several sequences (OpenLORIS cafe): --seq names the estimate's; without it
    the reader asks for it (exit 1, nothing scored)."""
    from lorisnb.io import load_groundtruth

    g = load_groundtruth("cafe", data).sequences[2]
    est = tmp_path / "cafe2.txt"
    rng = np.random.default_rng(0)
    np.savetxt(est, np.column_stack([g.stamps, g.positions + rng.normal(0, 0.02, g.positions.shape), g.quaternions]),
               fmt="%.9f")  # fmt: skip
    gt = data.root / "openloris-scene" / "groundtruth" / "gt_cafe_1.txt"
    assert main(["consistency", str(est), str(gt), "--gt-format", "openloris"]) == 1
    assert "seq" in capsys.readouterr().err
    assert main(["consistency", str(est), str(gt), "--gt-format", "openloris", "--seq", "2", "--align", "none"]) == 0
    out = capsys.readouterr().out
    assert f"{len(g)} of {len(g)} estimate poses matched" in out
