"""The Trajectory constructor checks its arrays as the file readers check a file's rows (unsorted,
repeated, NaN and malformed poses built in Python), on real data (TUM RGB-D fr1_xyz); the Python
API's other arguments (session mappings, ``motion_filter``); bag topics with unset or repeated
header stamps."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import write, write_bag

import lorisnb as ln
from lorisnb.errors import LorisWarning, ParseError, ValidationError
from lorisnb.io import read_bag


@pytest.fixture(scope="module")
def fr1(data):
    """(ground truth, rgbdslam estimate) of fr1_xyz, read from the files."""
    return ln.read_tum(data.tum / "freiburg1_xyz-groundtruth.txt"), ln.read_tum(data.tum / "freiburg1_xyz-rgbdslam.txt")


def _cr(gt, est) -> dict:
    t = ln.score(ln.session_errors({1: gt}, {1: est}), eps=0.05, phi=5, delta=1, tau=60)
    return t[["matched", "ate_rmse", "cr", "cr_t"]].iloc[0].to_dict()


def _shuffled(t: ln.Trajectory, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    perm = np.random.default_rng(seed).permutation(len(t))
    return t.stamps[perm], t.positions[perm], t.quaternions[perm]


def test_shuffled_rows_are_sorted_with_a_warning_and_score_as_read(fr1):
    gt, est = fr1
    with pytest.warns(LorisWarning, match=r"stamps are not increasing .* sorted them"):
        shuffled = ln.Trajectory(*_shuffled(est))
    assert np.all(np.diff(shuffled.stamps) > 0)
    np.testing.assert_array_equal(shuffled.positions, est.positions)
    np.testing.assert_array_equal(shuffled.quaternions, est.quaternions)
    sorted_rows, shuffled_rows = _cr(gt, est), _cr(gt, shuffled)
    assert sorted_rows == shuffled_rows  # was cr -107.2, cr_t -136.0 (trial finding 1)
    assert sorted_rows["matched"] == 788 and 0.88 < sorted_rows["cr"] < 0.89


def test_only_repeated_stamps_are_not_said_to_be_sorted(fr1):
    """Rows in order with one stamp repeated: the last pose of it kept, and nothing said sorted."""
    _, est = fr1
    s, p, q = est.stamps.copy(), est.positions, est.quaternions
    s[101] = s[100]
    with pytest.warns(LorisWarning, match="stamps are not increasing") as said:
        t = ln.Trajectory(s, p, q)
    text = str(said[0].message)
    assert " repeats after " in text and "sorted them" not in text
    assert len(t) == len(est) - 1 and np.array_equal(t.positions[100], p[101])


def test_unsorted_groundtruth_is_sorted_not_reported_as_gaps(fr1):
    gt, est = fr1
    with pytest.warns(LorisWarning, match="not increasing"):
        shuffled_gt = ln.Trajectory(*_shuffled(gt, seed=1))
    errors = ln.session_errors({1: shuffled_gt}, {1: est})
    assert not [w for w in errors.warnings if "gap" in w]  # was "1436 gaps" and every pose unmatched
    assert _cr(shuffled_gt, est) == _cr(gt, est)


def test_repeated_stamp_keeps_the_last_pose_as_read_tum_does(fr1, tmp_path):
    _, est = fr1
    s, p, q = est.stamps.copy(), est.positions.copy(), est.quaternions.copy()
    s[11] = s[10]  # row 11 repeats row 10's stamp: read_tum keeps the later row
    p[11] += 0.5
    text = "\n".join(" ".join(f"{v:.9f}" for v in (s[i], *p[i], *q[i])) for i in range(len(s))) + "\n"
    with pytest.warns(LorisWarning, match="kept the last pose"):
        from_file = ln.read_tum(write(tmp_path, "dup.txt", text))
    with pytest.warns(LorisWarning, match=r"first at index 11: .* repeats"):
        built = ln.Trajectory(s, p, q)
    assert len(built) == len(from_file) == len(est) - 1
    np.testing.assert_allclose(built.stamps, from_file.stamps, atol=1e-9)
    np.testing.assert_allclose(built.positions, from_file.positions, atol=1e-9)
    np.testing.assert_array_equal(built.positions[10], p[11])


def test_nan_position_is_skipped_as_the_readers_skip_it(fr1):
    gt, est = fr1
    p = est.positions.copy()
    p[60] = np.nan
    with pytest.warns(LorisWarning, match=r"1 of 788 pose\(s\) with NaN .*first at index 60"):
        t = ln.Trajectory(est.stamps, p, est.quaternions)
    assert len(t) == 787 and est.stamps[60] not in t.stamps
    assert _cr(gt, t)["matched"] == 787  # was numpy's LinAlgError: SVD did not converge


@pytest.mark.parametrize(
    "change, message",
    [
        (
            lambda s, p, q: (np.where(np.arange(len(s)) == 5, np.nan, s), p, q),
            r"stamps: stamp 5 is nan; expected finite",
        ),
        (lambda s, p, q: (s, p, np.where(np.arange(len(s))[:, None] == 7, 0.0, q)), r"quaternions: row 7 .* zero"),
        (lambda s, p, q: (s, p[:, :2], q), r"positions: shape \(788, 2\) for 788 stamps; expected \(788, 3\)"),
        (lambda s, p, q: (s, p, q[:-1]), r"quaternions: shape \(787, 4\) for 788 stamps"),
        (lambda s, p, q: (s[:, None], p, q), r"stamps: shape \(788, 1\); expected \(N,\)"),
        (lambda s, p, q: (s, [["a", "b", "c"]] * len(s), q), r"positions: expected numbers"),
    ],
)
def test_bad_arrays_are_refused_saying_what_to_pass(fr1, change, message):
    _, est = fr1
    with pytest.raises(ValidationError, match=message):
        ln.Trajectory(*change(est.stamps, est.positions, est.quaternions))


def test_lists_are_taken_as_arrays(fr1):
    _, est = fr1
    t = ln.Trajectory(est.stamps.tolist(), est.positions.tolist(), est.quaternions.tolist())
    assert t.stamps.dtype == float and t.positions.shape == (788, 3)
    np.testing.assert_array_equal(t.quaternions, est.quaternions)


def test_checked_arrays_are_not_copied_nor_checked_again(fr1):
    _, est = fr1
    again = ln.Trajectory(est.stamps, est.positions, est.quaternions, est.lines)
    assert again.stamps is est.stamps and again.positions is est.positions  # float arrays kept as they are
    sub = est.subset(np.arange(0, len(est), 2))
    assert len(sub) == 394 and np.all(np.diff(sub.stamps) > 0)
    with pytest.warns(LorisWarning, match="not increasing"):
        back = est.subset(np.arange(len(est))[::-1])  # indices that do not increase: sorted as the constructor does
    np.testing.assert_array_equal(back.stamps, est.stamps)


def test_session_errors_takes_one_trajectory_as_session_1(fr1):
    gt, est = fr1
    one = ln.session_errors(gt, est)
    assert one.sequences[0].seq == 1
    assert one.sequences[0].matched == ln.session_errors({1: gt}, {1: est}).sequences[0].matched == 788
    with pytest.raises(ValidationError, match=r"groundtruth: expected a dict \{session number: Trajectory\}"):
        ln.session_errors([gt], est)
    with pytest.raises(ValidationError, match=r"estimates\[1\]: expected a Trajectory"):
        ln.session_errors(gt, {1: "est.txt"})


@pytest.mark.parametrize("value", [0.1, [0.1], (0.1, 5, 1), {"d": 0.1}])
def test_motion_filter_needs_metres_and_degrees(value):
    with pytest.raises(ValidationError, match="motion_filter: expected two numbers, metres and degrees"):
        ln.make_spec("evo", motion_filter=value)
    assert ln.make_spec("evo", motion_filter=(0.1, 5)).motion_filter == (0.1, 5.0)


def test_bag_with_unset_header_stamps_is_refused_naming_the_topic(fr1, tmp_path):
    _, est = fr1
    zero = ln.Trajectory.from_checked(np.zeros(len(est)), est.positions, est.quaternions)
    bag = write_bag(tmp_path / "zero.bag", zero, 1, topic="/orb/pose")
    with pytest.raises(ParseError, match=r"all 788 messages of /orb/pose have header stamp 0"):
        read_bag(bag, topic="/orb/pose")


def test_bag_with_repeated_stamps_warns_as_read_tum(fr1, tmp_path):
    _, est = fr1
    s = est.stamps.copy()
    s[101:111] = s[100]  # ten messages repeat a stamp
    bag = write_bag(tmp_path / "dup.bag", ln.Trajectory.from_checked(s, est.positions, est.quaternions), 1)
    with pytest.warns(LorisWarning, match=r"/pose: timestamps are not increasing \(10 times; first at message 102"):
        t = read_bag(bag, topic="/pose")
    assert len(t) == len(est) - 10
    np.testing.assert_allclose(t.positions[100], est.positions[110])  # the last pose of the repeated stamp


def test_tf_chain_with_unset_header_stamps_is_refused_naming_the_link(fr1, tmp_path):
    _, est = fr1
    zero = ln.Trajectory.from_checked(np.zeros(50), est.positions[:50], est.quaternions[:50])
    bag = write_bag(tmp_path / "tf.bag", zero, 1, tf=("world", "odom", "base"))
    with pytest.raises(ParseError, match=r"all 50 messages of the TF link odom->base have header stamp 0"):
        read_bag(bag, tf="world:base")


def test_kitti_stamps_given_must_be_finite(fr1, tmp_path):
    _, est = fr1
    t = est.subset(np.arange(20))
    mats = np.concatenate([t.rotations().as_matrix(), t.positions[:, :, None]], axis=2).reshape(-1, 12)
    k = write(tmp_path, "poses.txt", "\n".join(" ".join(f"{v:.9f}" for v in m) for m in mats) + "\n")
    stamps = t.stamps.copy()
    stamps[3] = np.nan
    with pytest.raises(ParseError, match="stamp 4 given for this KITTI file is not finite"):
        ln.read_kitti(k, stamps=stamps)
    np.testing.assert_allclose(ln.read_kitti(k, stamps=t.stamps).positions, t.positions, atol=1e-9)
