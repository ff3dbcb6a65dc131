"""OpenVINS ``ov_eval``'s metrics of an estimate with pose covariances
(:mod:`lorisnb.core.metrics.consistency`): NEES, per-axis errors with 3-sigma bounds, yaw-only and 2D
ATE, against ov_eval's own ``ResultTrajectory`` compiled here (tests/peers.py) on real TUM RGB-D
poses (fr1/xyz, RGBD-SLAM's estimate; the estimate has no covariances, so it is given
:func:`helpers.synthetic_covariances`), for every alignment ov_eval offers and for an estimate
denser than its ground truth (where ov_eval's association rule matters). Where ov_eval cannot be
built the numbers it printed on 2026-11-28 for the first case are checked (:data:`RECORDED`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers import synthetic_covariances, write_ov_eval_file
from peers import build_ov_eval, run_ov_eval

from lorisnb.core.metrics.consistency import (
    SERIES,
    PoseCovariances,
    associate_sequential,
    ov_eval_errors,
    statistics,
)
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.errors import EvaluationError, ValidationError
from lorisnb.io.readers.covariance import read_covariances
from lorisnb.io.readers.plain import read_tum

GT, EST = "freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"

#: What ov_eval printed (``%.17g``: rmse, mean, count) for EST with its synthetic covariances against
#: GT, posyaw (tests/peers.py's driver, open_vins 6948812, 2026-11-28).
RECORDED = {
    "ate_ori": (1.4141083813071009, 1.3868731894193704, 786),
    "ate_pos": (0.014046763444015327, 0.012740809756118396, 786),
    "ate2d_yaw": (1.2831163736433242, 1.2496789659693779, 786),
    "ate2d_pos": (0.012809766230782393, 0.011289161133704383, 786),
    "nees_ori": (3.5574722622669483, 2.9464378889677301, 786),
    "nees_pos": (3.0026332301220013, 1.7839766513002755, 786),
    "pos_x": (0.010619589759364598, None, 786),
    "ori_z": (1.2830801709066375, -1.2496465762175963, 786),
    "roll": (0.50563123478709393, 0.021505475058270756, 786),
    "yaw": (1.2793496692751716, -1.2446432145778432, 786),
}


@pytest.fixture(scope="module")
def ov(tmp_path_factory) -> Path:
    return build_ov_eval(tmp_path_factory.mktemp("ov_eval"))


@pytest.fixture(scope="module")
def pair(data, tmp_path_factory) -> tuple[Path, Path]:
    est = read_tum(data.tum / EST, warn=False)
    path = write_ov_eval_file(tmp_path_factory.mktemp("cov") / "est_cov.txt", est, *synthetic_covariances(est.stamps))
    return path, data.tum / GT


def ours(est_path: Path, gt_path: Path, align: str):
    est, cov = read_covariances(est_path, required=False)
    return ov_eval_errors(est, read_tum(gt_path, warn=False), cov, align=align)


def same_as_ov_eval(res, stats: dict, rows: dict) -> None:
    """Every statistic and every per-pose value, stamp and bound of ov_eval's series equal lorisnb's."""
    summary = res.summary.set_index("series")
    compared = 0
    for name, theirs in stats.items():
        if theirs[-1] == 0:  # ov_eval had nothing (no covariances: no NEES)
            assert name not in summary.index
            continue
        mine = summary.loc[name, ["rmse", "mean", "median", "std", "min", "max", "count"]].to_numpy(float)
        scale = max(1e-12, float(np.abs(theirs[:6]).max()))
        np.testing.assert_allclose(mine, theirs, rtol=1e-9, atol=1e-12 * scale, err_msg=name)
        per = rows[name]
        col = res.poses[name].to_numpy()
        col = col[~np.isnan(col)] if name.startswith("nees") else col
        np.testing.assert_allclose(col, per[:, 1], rtol=1e-9, atol=1e-12 * scale, err_msg=name)
        if not name.startswith("nees"):
            np.testing.assert_array_equal(res.poses["t"].to_numpy(), per[:, 0])
        if (per[:, 2] >= 0).all():
            np.testing.assert_allclose(res.poses[f"{name}_3sigma"], per[:, 2], rtol=1e-9, err_msg=name)
        compared += 1
    assert compared == len(stats) - sum(1 for v in stats.values() if v[-1] == 0) >= 13


@pytest.mark.slow  # builds ov_eval from source (about a minute of Eigen); make test-all runs it
@pytest.mark.parametrize("align", ["posyaw", "se3", "sim3", "none"])
def test_every_series_equals_ov_eval(ov, pair, align):
    est, gt = pair
    stats, rows = run_ov_eval(ov, est, gt, align)
    res = ours(est, gt, align)
    assert set(stats) == set(SERIES)
    same_as_ov_eval(res, stats, rows)
    assert res.summary.set_index("series").loc["nees_pos", "count"] == 786


@pytest.mark.slow
def test_a_ground_truth_with_repeated_stamps_pairs_as_ov_eval(ov, data, tmp_path, capsys):
    """ov_eval reads every ground-truth row in file order and its scan stops at the first row of a
    repeated stamp; lorisnb kept the last (the official tool's rule) and the ATE was 0.148 m
    against ov_eval's 0.052 m. Through the command line as a user runs it, with ov_eval's path length."""
    from lorisnb.cli import main

    gt = read_tum(data.tum / GT, warn=False)
    g = np.column_stack([gt.stamps, gt.positions, gt.quaternions])[:2000]
    rng = np.random.default_rng(3)
    rows = []
    for k, r in enumerate(g):
        if k % 9 == 4:  # a row of the same stamp, 5 cm off, before the true one
            rows.append(np.concatenate([r[:1], r[1:4] + rng.normal(0, 0.05, 3), r[4:]]))
        rows.append(r)
    path = tmp_path / "gt_repeated.txt"
    np.savetxt(path, np.array(rows), fmt="%.17g")
    est_path = tmp_path / "est.txt"
    e = g[::4].copy()
    e[:, 0] += 0.003
    e[:, 1:4] += rng.normal(0, 0.01, (len(e), 3))
    np.savetxt(est_path, e, fmt="%.17g")
    stats, per = run_ov_eval(ov, est_path, path, "posyaw")
    res = ov_eval_errors(read_tum(est_path, warn=False), read_tum(path, warn=False, repeated="keep"), align="posyaw")
    same_as_ov_eval(res, stats, per)
    assert main(["consistency", str(est_path), str(path), "--align", "posyaw", "--digits", "17"]) == 0
    out = capsys.readouterr().out
    ate = next(line.split() for line in out.splitlines() if line.split()[:1] == ["ate_pos"])
    assert float(ate[2]) == pytest.approx(stats["ate_pos"][0], rel=1e-12)


@pytest.mark.slow
def test_an_estimate_denser_than_its_ground_truth_pairs_as_ov_eval(ov, data, tmp_path):
    """Three estimate poses near each 100 Hz ground-truth pose: ov_eval's rule gives each ground-truth
    pose to one of them only (the nearest after the previous match), not to the nearest of all."""
    gt = read_tum(data.tum / GT, warn=False)
    g = np.column_stack([gt.stamps, gt.positions, gt.quaternions])[:1500]
    rng = np.random.default_rng(0)
    parts = []
    for off in (-0.004, 0.0005, 0.003):
        r = g.copy()
        r[:, 0] += off
        r[:, 1:4] += rng.normal(0, 0.01, (len(r), 3))
        parts.append(r)
    e = np.concatenate(parts)
    e = e[np.argsort(e[:, 0], kind="stable")]
    e = e[np.concatenate([[True], np.diff(e[:, 0]) > 0])]
    path = tmp_path / "dense.txt"
    np.savetxt(path, e, fmt="%.17g")
    stats, rows = run_ov_eval(ov, path, data.tum / GT, "posyaw")
    res = ours(path, data.tum / GT, "posyaw")
    assert "nees_ori" not in res.poses and len(res.poses) == stats["ate_pos"][-1] >= 1500
    same_as_ov_eval(res, stats, rows)


def test_recorded_ov_eval_numbers(pair):
    """Everywhere the data is: the numbers ov_eval printed for the posyaw case (module docstring)."""
    s = ours(*pair, "posyaw").summary.set_index("series")
    for name, (rmse, mean, count) in RECORDED.items():
        assert s.loc[name, "count"] == count, name
        assert s.loc[name, "rmse"] == pytest.approx(rmse, rel=1e-9), name
        if mean is not None:
            assert s.loc[name, "mean"] == pytest.approx(mean, rel=1e-9), name


def test_consistent_covariances_give_nees_near_three_and_997_per_mille_inside(data):
    """The meaning of the numbers: an estimate whose errors are drawn from its own covariance (about
    its body axes for orientation, as OpenVINS' covariance is) has a mean NEES near 3 for both parts
    and about 99.7 % of its errors inside the 3-sigma bounds; one whose covariance is 4 times too
    small (overconfident) has a NEES near 12."""
    gt = read_tum(data.tum / GT, warn=False)
    n = len(gt)
    rng = np.random.default_rng(1)
    co, cp = synthetic_covariances(gt.stamps)
    dp = np.einsum("nij,nj->ni", np.linalg.cholesky(cp), rng.normal(size=(n, 3)))
    dtheta = np.einsum("nij,nj->ni", np.linalg.cholesky(co), rng.normal(size=(n, 3)))
    from scipy.spatial.transform import Rotation

    r_est = Rotation.from_quat(gt.quaternions) * Rotation.from_rotvec(dtheta)
    est = Trajectory(gt.stamps, gt.positions + dp, r_est.as_quat())
    res = ov_eval_errors(est, gt, PoseCovariances(co, cp), align="none")
    s = res.summary.set_index("series")
    assert s.loc["nees_pos", "mean"] == pytest.approx(3.0, abs=0.15)
    assert s.loc["nees_ori", "mean"] == pytest.approx(3.0, abs=0.15)
    assert s.loc[["pos_x", "pos_y", "pos_z"], "within_3sigma"].min() > 0.99
    tight = ov_eval_errors(est, gt, PoseCovariances(co / 4, cp / 4), align="none").summary.set_index("series")
    assert tight.loc["nees_pos", "mean"] == pytest.approx(12.0, rel=0.06)


def test_statistics_are_ov_evals():
    v = np.array([3.0, -1.0, 2.0, 7.0])
    s = statistics(v)
    assert s["median"] == 2.5 and s["std"] == pytest.approx(np.std(v, ddof=1)) and s["rmse"] == np.sqrt(np.mean(v**2))
    assert statistics(np.zeros(0))["count"] == 0


def test_association_is_ov_evals_rule():
    gt = np.array([0.0, 0.01, 0.02, 0.03])
    # 0.011 and 0.012 both nearest 0.01: the second takes the next one after it (0.02, 8 ms away)
    gi, ei = associate_sequential(gt, np.array([0.011, 0.012, 0.5]))
    assert gi.tolist() == [1, 2] and ei.tolist() == [0, 1]
    gi, _ = associate_sequential(np.array([0.0, 0.25, 0.5]), np.array([0.125, 0.375]), 0.2)  # ties: the earlier
    assert gi.tolist() == [0, 1]
    gi, _ = associate_sequential(gt, np.array([0.05]), 0.02)  # exactly max_diff away: not paired
    assert gi.size == 0


def test_bad_covariances_and_pairs_are_refused(data):
    gt = read_tum(data.tum / GT, warn=False)
    with pytest.raises(ValidationError, match=r"\(N, 3, 3\)"):
        PoseCovariances(np.zeros((3, 3)), np.zeros((1, 3, 3)))
    with pytest.raises(ValidationError, match="finite"):
        PoseCovariances(np.full((1, 3, 3), np.nan), np.zeros((1, 3, 3)))
    with pytest.raises(ValidationError, match="one per pose"):
        ov_eval_errors(gt, gt, PoseCovariances(np.zeros((2, 3, 3)), np.zeros((2, 3, 3))))
    with pytest.raises(ValidationError, match="align"):
        ov_eval_errors(gt, gt, align="kabsch")
    later = Trajectory(gt.stamps + 100.0, gt.positions, gt.quaternions)
    with pytest.raises(EvaluationError, match="share a clock"):
        ov_eval_errors(later, gt)
    zero = PoseCovariances(np.zeros((len(gt), 3, 3)), np.zeros((len(gt), 3, 3)))
    res = ov_eval_errors(gt, gt, zero, align="none")  # no covariance to invert: no NEES, said by the count
    assert res.summary.set_index("series").loc["nees_pos", "count"] == 0


def _covariance_cases(data, out: Path) -> dict[str, Path]:
    """fr1/xyz's estimate with covariances ov_eval and a symmetric-positive-definite check disagree on:
    every 7th position block indefinite (its z variance negated), and rank-1 position blocks plus
    1e-14 m^2 (near-singular: the NEES is rounding magnified by 1e14)."""
    est = read_tum(data.tum / EST, warn=False)
    co, cp = synthetic_covariances(est.stamps)
    indefinite = cp.copy()
    indefinite[::7, 2, 2] *= -1
    u = np.random.default_rng(3).normal(size=(len(est), 3))
    near = 1e-4 * np.einsum("ni,nj->nij", u, u) + 1e-14 * np.eye(3)
    return {
        "indefinite": write_ov_eval_file(out / "indefinite.txt", est, co, indefinite),
        "near_singular": write_ov_eval_file(out / "near_singular.txt", est, co, near),
    }


@pytest.mark.slow
@pytest.mark.parametrize("case", ["indefinite", "near_singular"])
def test_covariances_that_are_not_positive_definite_give_ov_evals_nees(ov, data, tmp_path, case):
    """ov_eval inverts each covariance with Eigen's cofactors and keeps every NEES that is not NaN
    (negative for an indefinite block): lorisnb dropped the poses whose block was not positive
    definite (673 of 786 poses) and solved near-singular ones another way (mean NEES 1.3e10 for
    ov_eval's 7.8e9)."""
    est = _covariance_cases(data, tmp_path)[case]
    stats, rows = run_ov_eval(ov, est, data.tum / GT, "posyaw")
    res = ours(est, data.tum / GT, "posyaw")
    same_as_ov_eval(res, stats, rows)
    assert res.summary.set_index("series").loc["nees_pos", "count"] == 786
    if case == "indefinite":
        assert res.poses["nees_pos"].min() < 0 and any(
            "113 of 786" in n and "not positive definite" in n for n in res.notes
        )


def _half_turn(data, out: Path) -> Path:
    """fr1/xyz's estimate turned by exactly pi about each body x axis: against a ground truth of 4
    decimals (quaternions not quite unit), a few orientation errors fall a hair past a half turn."""
    from scipy.spatial.transform import Rotation

    est = read_tum(data.tum / EST, warn=False)
    q = (Rotation.from_quat(est.quaternions) * Rotation.from_rotvec([np.pi, 0, 0])).as_quat()
    return write_ov_eval_file(out / "half_turn.txt", Trajectory(est.stamps, est.positions, q),
                              *synthetic_covariances(est.stamps))  # fmt: skip


@pytest.mark.slow
def test_a_half_turn_ov_eval_stops_on_is_said(ov, data, tmp_path):
    """ov_core's log_so3 gives NaN there and ov_eval stops (an assertion); lorisnb's statistics of
    those series are NaN too, and a note says which poses and why."""
    import subprocess

    est = _half_turn(data, tmp_path)
    done = subprocess.run([str(ov), str(est), str(data.tum / GT), "none"], capture_output=True, text=True, timeout=300)
    assert done.returncode != 0 and "isnan" in done.stderr
    res = ours(est, data.tum / GT, "none")
    assert np.isnan(res.summary.set_index("series").loc["ate_ori", "rmse"])
    assert any("half turn" in n and "ate_ori" in n for n in res.notes)


def test_not_positive_definite_covariances_are_said(data, tmp_path):
    """Everywhere the data is: an indefinite block has a NEES (as ov_eval's) and a note; a zero one none."""
    res = ours(_covariance_cases(data, tmp_path)["indefinite"], data.tum / GT, "posyaw")
    s = res.summary.set_index("series")
    assert s.loc["nees_pos", "count"] == 786 and res.poses["nees_pos"].min() < 0
    assert [n for n in res.notes if "not positive definite" in n]
    half = ours(_half_turn(data, tmp_path), data.tum / GT, "none")
    assert [n for n in half.notes if "half turn" in n]


@pytest.mark.slow
@pytest.mark.parametrize(("scale", "warned"), [(1.0, False), (0.95, True), (1.1, False), (2.5, True)])
def test_the_path_length_warning_is_ov_evals(ov, data, tmp_path, scale, warned):
    """ov_eval warns when the two whole files' path lengths differ by more than 10 % (a scale
    error, or different spans); lorisnb said nothing. Both now say it on the same files, and every
    number still agrees."""
    import subprocess

    est = read_tum(data.tum / EST, warn=False)
    scaled = Trajectory(est.stamps, est.positions * scale, est.quaternions)
    path = write_ov_eval_file(tmp_path / "scaled.txt", scaled, *synthetic_covariances(est.stamps))
    done = subprocess.run([str(ov), str(path), str(data.tum / GT), "posyaw"], capture_output=True, text=True,
                          timeout=300)  # fmt: skip
    res = ours(path, data.tum / GT, "posyaw")
    theirs = "bad ratio" in done.stdout
    assert theirs == any("times as long as the ground truth" in n for n in res.notes)
    assert theirs == warned  # fr1/xyz's estimate is 0.945 times as long as its ground truth
    same_as_ov_eval(res, *run_ov_eval(ov, path, data.tum / GT, "posyaw"))
