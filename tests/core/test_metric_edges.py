"""The paper's metrics (Eq. 1-4, C-ATE) at their edges, on tiny hand-built trajectories whose
exact values follow from the definitions (OpenLORIS-Scene paper, Sec. IV; the official tool's
``calculate_correctness`` computes the same): first pose wrong, late start, gaps longer than delta,
thresholds met exactly, one pose, no pose inside the ground truth, several sequences of one
lifelong file, and a diverged pose far outside any threshold."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from helpers import circle, openloris_text, write
from scipy.spatial.transform import Rotation

import lorisnb as ln
from lorisnb.core import Trajectory, durations_table, sequence_grid

# Ground truth: 0 .. 10 s at 10 Hz along x (x = t metres), heading along x. Its span is 10 s.
T_GT = np.round(np.arange(101) * 0.1, 10)


def line(stamps, x, yaw_deg=None) -> Trajectory:
    t = np.asarray(stamps, float)
    pos = np.column_stack([np.asarray(x, float), np.zeros(len(t)), np.zeros(len(t))])
    yaw = np.zeros(len(t)) if yaw_deg is None else np.asarray(yaw_deg, float)
    return Trajectory.from_rotations(t, pos, Rotation.from_euler("z", yaw[:, None], degrees=True))


GT = line(T_GT, T_GT)


def grid(est: Trajectory, eps=np.inf, phi=np.inf, delta=1.0, tau=60.0) -> dict[str, np.ndarray]:
    """Every metric of ``est`` against GT (no alignment: the errors are as built), over a grid."""
    e = ln.sequence_errors(GT, est, align="none")
    return sequence_grid(e, np.atleast_1d(eps), np.atleast_1d(phi), np.atleast_1d(delta), np.atleast_1d(tau))


def one(g: dict[str, np.ndarray], name: str) -> float:
    return float(g[name].reshape(-1)[0])


def test_first_pose_wrong_scores_no_relocalization_whatever_tau():
    # poses at 0, 1, 2, 3 s; the first 5 m off. Eq. (4): c(p_0) = 0, so CS-R = 0 for every tau;
    # the three correct poses hold min(1, 1) s each (the last until t_max = 10 s, capped at delta)
    g = grid(line([0, 1, 2, 3], [5, 1, 2, 3]), eps=1.0, tau=[1e-6, 1.0, 60.0, np.inf])
    assert g["cs_r"].reshape(-1).tolist() == [0.0, 0.0, 0.0, 0.0]
    assert one(g, "correct_time") == pytest.approx(3.0)
    assert one(g, "cr") == pytest.approx(0.3)  # 3 s of the 10 s span


def test_late_start_relocalization_and_tracking_rates():
    # first pose at t0 = 4 s: CS-R = exp(-4 / tau); CR = 3 / 10; CR-T = 3 / (10 - 4)
    g = grid(line([4, 5, 6], [4, 5, 6]), tau=[10.0, np.inf])
    assert g["cs_r"].reshape(-1).tolist() == pytest.approx([np.exp(-0.4), 1.0])
    assert one(g, "reloc_time") == pytest.approx(4.0)
    assert one(g, "cr") == pytest.approx(0.3) and one(g, "cr_t") == pytest.approx(0.5)
    # tau tiny: the score vanishes, it is not NaN
    assert one(grid(line([4, 5], [4, 5]), tau=1e-9), "cs_r") == 0.0


def test_gaps_longer_than_delta_count_delta_only():
    # poses at 0, 1, 5, 6: intervals 1, 4, 1, 4 (the last to t_max = 10), each capped at delta = 1
    g = grid(line([0, 1, 5, 6], [0, 1, 5, 6]), delta=[1.0, 2.5, np.inf])
    assert g["correct_time"].reshape(-1).tolist() == pytest.approx([4.0, 1 + 2.5 + 1 + 2.5, 10.0])
    assert g["cr"].reshape(-1).tolist() == pytest.approx([0.4, 0.7, 1.0])


def test_thresholds_are_inclusive():
    # Eq. (1) uses <=: an ATE of exactly 0.5 m is correct at eps = 0.5, wrong just below
    g = grid(line([0, 1], [0.5, 1.0]), eps=[0.5, np.nextafter(0.5, 0)])
    assert g["c_matched"].reshape(-1).tolist() == [2.0, 1.0]
    # eps = phi = 0: exact poses are correct, the others not
    g = grid(line([0, 1, 2], [0, 1, 2.25]), eps=0.0, phi=0.0)
    assert one(g, "c_matched") == 2.0 and one(g, "c_ate_rmse") == 0.0


def test_one_pose_and_one_pose_at_the_end():
    # one correct pose at 3 s: it holds min(10 - 3, 1) = 1 s; CR-T = 1 / 7; CS-R = exp(-3 / 60)
    g = grid(line([3], [3]))
    assert (one(g, "correct_time"), one(g, "cr"), one(g, "cr_t")) == pytest.approx((1.0, 0.1, 1 / 7))
    assert one(g, "cs_r") == pytest.approx(np.exp(-3 / 60))
    # one pose at t_max: it holds nothing, and CR-T (0 s tracked) is 0, not a division by zero
    g = grid(line([10], [10]))
    assert (one(g, "correct_time"), one(g, "cr"), one(g, "cr_t"), one(g, "track_time")) == (0.0, 0.0, 0.0, 0.0)
    assert one(g, "cs_r") == pytest.approx(np.exp(-10 / 60))


def test_estimate_outside_the_groundtruth_span_scores_zero():
    g = grid(line([20, 21], [20, 21]))
    assert one(g, "c_matched") == 0 and one(g, "cr") == 0.0 and one(g, "cs_r") == 0.0
    assert one(g, "reloc_time") == np.inf and np.isnan(one(g, "ate_rmse"))


def test_estimate_rate_other_than_the_groundtruth_rate():
    # 0.5 Hz from 1 s: five poses hold 1 s each (delta); CR = 5 / 10, CR-T = 5 / 9
    g = grid(line([1, 3, 5, 7, 9], [1, 3, 5, 7, 9]))
    assert (one(g, "cr"), one(g, "cr_t")) == pytest.approx((0.5, 5 / 9))
    # 4 Hz with delta = 0.2 s: 40 intervals of 0.25 s, each 0.2 s (the pose at 10 s holds 0)
    t = np.round(np.arange(41) * 0.25, 10)
    assert one(grid(line(t, t), delta=0.2), "correct_time") == pytest.approx(8.0)


def _moved(t: Trajectory, first_off: float = 0.0, far: int | None = None) -> Trajectory:
    """``t`` in another world frame (turned 90 deg, shifted), its first pose ``first_off`` metres
    off along x, and the pose ``far`` diverged to 1e160 m."""
    turn = Rotation.from_euler("z", 90, degrees=True)
    p = turn.apply(t.positions) + [10.0, -3.0, 0.5]
    p[0, 0] += first_off
    if far is not None:
        p[far] = [1e160, 0.0, 0.0]
    return Trajectory.from_rotations(t.stamps.copy(), p, turn * t.rotations())


def _lifelong(tmp_path, seq2: Trajectory):
    g1, g2, g3 = circle(), circle(t0=2000.0), circle(t0=3000.0)  # 200 poses at 10 Hz: 19.9 s each
    gt = ln.read_openloris(write(tmp_path, "gt_cafe_1.txt", openloris_text({1: g1, 2: g2, 3: g3})))
    text = openloris_text({1: _moved(g1), 2: seq2(g2)}) + "seq: 3\n"  # seq 3 declared, no output
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        errors = ln.compute_errors(ln.read_openloris(write(tmp_path, "alg/cafe.txt", text)), gt, algorithm="alg")
    return errors, gt


def test_lifelong_file_aligned_on_its_first_sequence_and_missing_output_counted(tmp_path):
    errors, gt = _lifelong(tmp_path, lambda g: _moved(g, first_off=5.0))
    assert errors.mode == "lifelong" and errors.aligned_on == 1
    table = ln.score(errors, eps=1.0, phi=30.0, delta=1.0, tau=60.0).set_index("seq")
    # seq 2 moved as seq 1 is: the alignment of seq 1 makes it exact but its first pose (5 m off):
    # CS-R 0, 199 correct poses holding 0.1 s each but the last, at t_max (0 s): 19.8 s
    assert table.loc[2, "cs_r"] == 0.0 and table.loc[2, "c_matched"] == 199
    assert table.loc[2, "correct_time"] == pytest.approx(19.8)
    assert table.loc[1, "cr"] == pytest.approx(1.0) and table.loc[1, "cs_r"] == pytest.approx(1.0)
    assert table.loc[3, "cr"] == 0.0 and table.loc[3, "matched"] == 0
    # the scene: correct time over all three sequences' time; CS-R the mean over the three
    scene = ln.aggregate_scenes(table.reset_index(), durations_table({"cafe": gt})).iloc[0]
    assert scene["cr"] == pytest.approx((19.9 + 19.8) / (3 * 19.9))
    assert scene["cs_r"] == pytest.approx(1 / 3)
    assert scene["cr_t"] == pytest.approx((19.9 + 19.8) / (19.9 + 19.9))


def test_a_diverged_pose_leaves_c_ate_of_the_correct_poses(tmp_path):
    # seq 2 exact but pose 100 diverged to 1e160 m (its ATE squared overflows): it is not correct,
    # so C-ATE is the RMSE of the 199 others, 0, and C-AOE too (it was NaN: 0 * inf in a product)
    errors, _ = _lifelong(tmp_path, lambda g: _moved(g, far=100))
    row = ln.score(errors, eps=1.0, phi=30.0).set_index("seq").loc[2]
    assert row["c_matched"] == 199
    assert row["c_ate_rmse"] == pytest.approx(0.0, abs=1e-9)
    assert row["c_aoe_rmse"] == pytest.approx(0.0, abs=1e-6)
    # at eps = infinity the diverged pose is correct: its square counts, as it does in the ATE
    assert ln.score(errors).set_index("seq").loc[2, "c_ate_rmse"] == np.inf
