"""Difficulty measures that compare across datasets of very different size: indoor OpenLORIS,
outdoor ORDSLAM and TUM RGB-D.

* trajectory statistics of the ground truth: length, extent, duration, speed, angular speed;
* ``ate_pct_length``: ATE RMSE as a percentage of the distance travelled (the ORDSLAM paper reports
  about 1 % of a 12 m path);
* ``rpe_pct``: translational RPE RMSE over pairs ``rpe_metres`` apart along the ground truth, per
  metre travelled (drift, %);
* ``cr_scaled``: CR (Eq. 2) with eps a fraction of the sequence's extent (bounding-box diagonal),
  phi = infinity, so a 10 m room and a 200 m market loop are judged alike;
* ``tracked_share``: CR with no threshold, the share of the ground-truth time with output poses.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from lorisnb.core.alignment.geometry import quat_angle_deg, quat_conjugate, quat_multiply, quat_normalize
from lorisnb.core.metrics import openloris as metrics
from lorisnb.core.pipeline.model import SequenceErrors
from lorisnb.core.spec import validate
from lorisnb.core.spec.validate import choice
from lorisnb.core.trajectory.poses import Trajectory, size


def trajectory_stats(traj: Trajectory) -> dict:
    """Length (m), extent (m, bounding-box diagonal), duration (s), mean speed (m/s), mean angular
    speed (deg/s, total rotation angle between consecutive poses over the duration), poses, rate (Hz)."""
    n = len(traj)
    if n < 2:
        return dict(
            poses=n,
            length_m=0.0,
            extent_m=0.0,
            duration_s=0.0,
            speed_mps=np.nan,
            angular_speed_dps=np.nan,
            rate_hz=np.nan,
        )
    q = quat_normalize(traj.quaternions)
    turn = quat_angle_deg(quat_multiply(quat_conjugate(q[:-1]), q[1:])).sum()
    dur = traj.duration
    return dict(
        poses=n,
        length_m=traj.path_length,
        extent_m=traj.extent,
        duration_s=dur,
        speed_mps=traj.path_length / dur if dur > 0 else np.nan,
        angular_speed_dps=turn / dur if dur > 0 else np.nan,
        rate_hz=(n - 1) / dur if dur > 0 else np.nan,
    )


def difficulty_measures(
    e: SequenceErrors,
    gt: Trajectory,
    eps_fraction: float = 0.1,
    rpe_metres: float = 1.0,
    delta: float = 1.0,
    relative_to: str = "extent",
) -> dict:
    """The normalized measures of one evaluated sequence (see the module docstring).

    Args:
        e: per-pose errors of the sequence (:func:`lorisnb.core.pipeline.sessions.compute_errors` or
            :func:`lorisnb.core.pipeline.sessions.sequence_errors`).
        gt: the sequence's full ground truth (for its length and extent).
        eps_fraction: eps as a fraction of the whole ground truth's size for ``cr_scaled``
            (:func:`lorisnb.core.trajectory.poses.size`; ``eps="relative:F"`` takes the size of the
            ground truth the estimate matched instead: the two differ where a run tracked part of
            its sequence).
        relative_to: that size: ``extent`` (bounding-box diagonal) or ``length`` (distance travelled).
        rpe_metres: distance along the ground truth over which the RPE is taken, metres.
    """
    relative_to = choice("relative_to", relative_to, ("extent", "length"))
    fraction = validate.fraction("eps_fraction", eps_fraction)
    rpe_metres = validate.positive("rpe_metres", rpe_metres, "metres")  # -1 gave negative RPE percentages
    delta = validate.threshold("delta", delta)
    st = trajectory_stats(gt)
    eps = fraction * size(gt.positions, relative_to)  # of the whole sequence, whatever was tracked
    out = dict(
        length_m=st["length_m"],
        extent_m=st["extent_m"],
        duration_s=st["duration_s"],
        matched=e.matched,
        eps_scaled_m=eps,
    )
    if e.matched == 0:
        return out | dict(ate_rmse_m=np.nan, ate_pct_length=np.nan, rpe_pct=np.nan, cr_scaled=0.0, tracked_share=0.0)
    ate_rmse = float(metrics.rmse(e.ate))
    i, j, tr, _ = e.rpe(rpe_metres, "m")
    span = (e.gt_start, e.gt_end)
    held_all = metrics.correct_time(e.stamps, np.ones(e.matched, bool), e.gt_end, delta, e.gt_start)
    ok = metrics.correctness(e.ate, e.aoe, eps, np.inf)
    held_ok = metrics.correct_time(e.stamps, ok, e.gt_end, delta, e.gt_start)
    return out | dict(
        ate_rmse_m=ate_rmse,
        ate_pct_length=100.0 * ate_rmse / st["length_m"] if st["length_m"] > 0 else np.nan,
        rpe_pct=100.0 * float(metrics.rmse(tr)) / rpe_metres if len(i) else np.nan,
        cr_scaled=float(metrics.correct_rate(held_ok, *span)),
        tracked_share=float(metrics.correct_rate(held_all, *span)),
    )


def summarize(table: pd.DataFrame, by: list[str]) -> pd.DataFrame:
    """Group a per-sequence difficulty table: medians of the measures, total length and count."""
    cols = [c for c in ("ate_pct_length", "rpe_pct", "cr_scaled", "tracked_share", "ate_rmse_m") if c in table]
    agg = table.groupby(by, dropna=False, observed=True).agg(
        sequences=("length_m", "size"), length_m=("length_m", "sum"), **{c: (c, "median") for c in cols}
    )
    return agg.reset_index()
