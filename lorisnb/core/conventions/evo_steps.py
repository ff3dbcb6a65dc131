"""evo's steps inside the one pipeline (:func:`lorisnb.core.pipeline.sessions.evaluate_sessions`), in evo's
order: before matching, ``downsample`` and ``motion_filter`` on both trajectories, then the time
window ``t_start``/``t_end`` on the ground truth (:func:`prepare`); the evo associations
(:func:`evo_match`); after the alignment, ``project_to_plane`` (:func:`projected`). And rpg's
length of the whole ground truth (:func:`whole_length`), which the pipeline records.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from lorisnb.core.alignment.association import Association
from lorisnb.core.alignment.geometry import quat_angle_deg, quat_conj_multiply, quat_normalize
from lorisnb.core.conventions.evo_options import project_to_plane
from lorisnb.core.conventions.evo_sync import (
    evo_associate,
    evo_downsample,
    evo_interpolate,
    evo_motion_filter,
    time_window,
)
from lorisnb.core.metrics import openloris as metrics
from lorisnb.core.pipeline.model import SequenceErrors
from lorisnb.core.spec.evalspec import EvalSpec
from lorisnb.core.trajectory.poses import Trajectory, written_blocks


def prepare(gt: Trajectory, est: Trajectory, spec: EvalSpec) -> tuple[Trajectory, Trajectory]:
    """The trajectories as evo matches them: each downsampled and motion-filtered, then the ground
    truth cut to the time window (unchanged when the spec sets none of these)."""
    if spec.downsample is not None:
        gt, est = (t.subset(evo_downsample(len(t), spec.downsample)) for t in (gt, est))
    if spec.motion_filter is not None:
        d, a = spec.motion_filter
        gt, est = (t.subset(evo_motion_filter(t.positions, t.quaternions, d, a)) if len(t) > 1 else t
                   for t in (gt, est))  # fmt: skip
    if spec.t_start is not None or spec.t_end is not None:
        gt = time_window(gt, spec.t_start, spec.t_end)
    return gt, est


def prepared_away(label: str, gt: tuple[int, int], est: tuple[int, int], spec: EvalSpec) -> str | None:
    """Why nothing matched when :func:`prepare`'s options thinned the trajectories (``gt`` and
    ``est``: poses before and after), or None when the spec sets none of them."""
    steps = [
        f"downsample {spec.downsample}" if spec.downsample is not None else "",
        f"motion filter {spec.motion_filter[0]:g} m / {spec.motion_filter[1]:g} deg" if spec.motion_filter else "",
        "time window" if spec.t_start is not None or spec.t_end is not None else "",
    ]
    steps = [x for x in steps if x]
    if not steps:
        return None
    return (
        f"{label}: no estimate stamp matches the ground truth after {' and '.join(steps)}: the ground truth keeps "
        f"{gt[1]} of {gt[0]} pose(s), the estimate {est[1]} of {est[0]}; loosen or drop {' / '.join(steps)}"
    )


def evo_match(gt: Trajectory, est: Trajectory, spec: EvalSpec) -> tuple[Association, Trajectory]:
    """The matched poses by ``evo-nearest`` or ``evo-interpolate`` (:mod:`lorisnb.core.conventions.evo_sync`)
    and the estimate they index: ``est`` itself, or, when evo interpolates the estimate (its
    trajectory is the longer one), the estimate interpolated at the matched ground-truth stamps.
    Stamps are on the ground truth's clock (estimate stamps + ``t_offset``)."""
    g_start = float(gt.stamps[0]) if len(gt) else np.nan
    g_end = float(gt.stamps[-1]) if len(gt) else np.nan
    gi, ej, short = evo_associate(gt.stamps, est.stamps, spec.max_diff, spec.t_offset)
    if ej.size == 0:
        return Association(ej, np.zeros(0), np.zeros((0, 3)), None, g_start, g_end), est
    if spec.association == "evo-interpolate":
        if short == "gt":
            e2 = evo_interpolate(est, gt.stamps[gi] - spec.t_offset)
            idx = np.arange(gi.size)
            return Association(idx, e2.stamps + spec.t_offset, gt.positions[gi], quat_normalize(gt.quaternions[gi]),
                               g_start, g_end), e2  # fmt: skip
        g2 = evo_interpolate(gt, est.stamps[ej] + spec.t_offset)
        return Association(ej, est.stamps[ej] + spec.t_offset, g2.positions, g2.quaternions, g_start, g_end), est
    blocks = written_blocks(gt) if spec.as_written else None  # nearest stamps: poses as written (interpolated: not)
    return Association(ej, est.stamps[ej] + spec.t_offset, gt.positions[gi], quat_normalize(gt.quaternions[gi]),
                       g_start, g_end, None if blocks is None else blocks[gi]), est  # fmt: skip


def whole_length(traj: Trajectory) -> float:
    """Path length of a whole trajectory, metres (rpg's ``traj_length`` of the ground truth as
    read), in blocks of rows: no temporary as large as the trajectory."""
    p, n, total = traj.positions, len(traj), 0.0
    for lo in range(0, n - 1, 1 << 18):  # blocks of 262,144 steps, not poses
        hi = min(n - 1, lo + (1 << 18))
        d = p[lo + 1 : hi + 1] - p[lo:hi]
        total += float(np.sqrt(np.einsum("ij,ij->i", d, d)).sum())
    return total


def projected(e: SequenceErrors, plane: str) -> SequenceErrors:
    """The errors of the aligned poses projected to ``plane`` (evo's ``--project_to_plane``): ATE
    and AOE taken again, the RPE to be computed on the projected poses."""
    if e.matched == 0 or e.est_quaternions is None or e.gt_quaternions is None:
        return e
    pe, qe = project_to_plane(e.est_positions, e.est_quaternions, plane)
    pg, qg = project_to_plane(e.gt_positions, e.gt_quaternions, plane)
    return replace(
        e, est_positions=pe, est_quaternions=qe, gt_positions=pg, gt_quaternions=qg, ate=metrics.ate(pe, pg),
        aoe=quat_angle_deg(quat_conj_multiply(qg, qe)), est_blocks=None, gt_blocks=None,
    )  # fmt: skip
