"""The plausibility checks of the one pipeline (:func:`lorisnb.core.pipeline.sessions.evaluate_sessions`),
for every input kind: each looks at a few poses and returns a message of
:mod:`lorisnb.core.pipeline.plausibility` (or None). They never change a number.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from lorisnb.core.alignment.association import Association, associate
from lorisnb.core.alignment.geometry import (
    PositionPairs,
    Sim3,
    quat_angle_deg,
    quat_conj_multiply,
    quat_from_matrix,
    quat_multiply,
    quat_normalize,
    umeyama,
)
from lorisnb.core.metrics import openloris as metrics
from lorisnb.core.pipeline import plausibility
from lorisnb.core.trajectory.frames import FRAMES, relative_extrinsic
from lorisnb.core.trajectory.poses import Trajectory, path_length, time_spans

PLAUSIBILITY_POSES = 300  # estimate poses a plausibility check looks at (evenly spread)


def spread(n: int, k: int) -> np.ndarray:
    """At most ``k`` indices of ``range(n)``, evenly spread, first and last included."""
    return np.round(np.linspace(0, n - 1, min(n, k))).astype(int) if n else np.zeros(0, int)


def spreads_all(matched: int) -> bool:
    """Whether :func:`spread_pairs` of ``matched`` poses holds every one of them (in order): then
    they are the positions a fit on all matched poses is computed on, and the fit takes them
    (:func:`~lorisnb.core.alignment.geometry.umeyama`'s ``pairs``)."""
    return 0 < matched <= 10 * PLAUSIBILITY_POSES


def spread_pairs(est_positions: np.ndarray, a: Association) -> PositionPairs | None:
    """The matched positions the alignment checks look at (at most 3,000, evenly spread), with what
    a fit and its degeneracy test share (:class:`~lorisnb.core.alignment.geometry.PositionPairs`),
    for :func:`scale_note` and :func:`degenerate_note` of one sequence; None with nothing matched."""
    if len(a) == 0:
        return None
    if spreads_all(len(a)):  # every matched pose: the fit's own arrays (a.est_rows: a view where consecutive)
        return PositionPairs.of(a.est_rows(est_positions), a.gt_positions)
    few = spread(len(a), 10 * PLAUSIBILITY_POSES)
    return PositionPairs.of(est_positions[a.est_index[few]], a.gt_positions[few])


def scale_note(label: str, pairs: PositionPairs | None, a: Association, fitted: Sim3, hint: str) -> str | None:
    """The best Sim(3) scale of the matched positions is far from 1 and fixes most of the error of
    the alignment used (``fitted``): a monocular trajectory? (on the spread poses of
    :func:`spread_pairs`)."""
    if len(a) <= 2 or pairs is None:
        return None
    sim = pairs.fit(with_scale=True)
    if plausibility.scale_in_range(sim.scale):
        return None
    p_est, p_gt = pairs.source, pairs.target
    return plausibility.scale_far_from_one(
        label, sim.scale, float(metrics.rmse(metrics.ate(fitted.apply(p_est), p_gt))),
        float(metrics.rmse(metrics.ate(sim.apply(p_est), p_gt))), lambda: path_length(a.gt_positions), hint,
    )  # fmt: skip


def median_aoe_by_frame(
    est: Trajectory,
    gt_base: Trajectory,
    scene: str,
    with_scale: bool,
    max_gap: float,
    gt_frame: str = "base_link",
    *,
    max_poses: int = PLAUSIBILITY_POSES,
    swapped_in: str | None = None,
) -> tuple[dict[str, float], float]:
    """Median AOE (deg) of one sequence with its ground truth moved to each sensor frame, and (with
    ``swapped_in``) the median AOE in that frame with each quaternion read ``qw qx qy qz``.

    A check, not a metric: at most ``max_poses`` estimate poses, evenly spread, are associated
    once with the ground truth as given and aligned once on its positions; the interpolated
    ground-truth orientations are then turned to each frame (``R_gt @ R_gt_frame``). Moving the
    positions by each frame's lever arm (a few centimetres) would change the alignment by far less
    than the tens of degrees this check looks for; the positions do not depend on the quaternion
    order either, so one alignment serves both questions. NaN where nothing matched."""
    if len(est) > max_poses:
        est = est.subset(spread(len(est), max_poses))
    a = associate(gt_base, est.stamps, max_gap)
    if len(a) < 3 or a.gt_quaternions is None:
        return {}, np.nan
    p_est = est.positions[a.est_index]
    q_est = est.quaternions[a.est_index]
    sim = umeyama(p_est, a.gt_positions, with_scale)
    q_rot = quat_from_matrix(sim.rotation)
    q_aligned = quat_multiply(q_rot, quat_normalize(q_est))
    offsets = np.stack([relative_extrinsic(scene, gt_frame, fr)[1] for fr in FRAMES])  # (7, 4)
    q_gt_fr = quat_multiply(a.gt_quaternions[None, :, :], offsets[:, None, :])  # every frame at once
    angles = quat_angle_deg(quat_conj_multiply(q_gt_fr, q_aligned[None, :, :]))
    by_frame = dict(zip(FRAMES, np.median(angles, axis=1).tolist(), strict=True))
    if swapped_in not in FRAMES:
        return by_frame, np.nan
    q_swapped = quat_multiply(q_rot, quat_normalize(np.roll(q_est, -1, axis=1)))
    k = FRAMES.index(swapped_in)
    return by_frame, float(np.median(quat_angle_deg(quat_conj_multiply(q_gt_fr[k], q_swapped))))


def median_aoe_swapped(
    est: Trajectory, a: Association, alignment: Sim3, max_poses: int = PLAUSIBILITY_POSES, shift: int = -1
) -> float:
    """Median AOE (deg) of matched poses with each estimate quaternion's components moved by ``shift``
    places, after the alignment used (at most ``max_poses`` evenly spread poses; NaN where nothing
    matched). ``shift=-1``: a file's ``qw qx qy qz`` read as ``qx qy qz qw`` (TUM's order), read
    right; ``shift=1``: a file's ``qx qy qz qw`` read as ``qw qx qy qz`` (EuRoC's order), read right."""
    if len(a) < 3 or a.gt_quaternions is None:
        return np.nan
    few = spread(len(a), max_poses)
    q_rot = quat_from_matrix(alignment.rotation)
    q_swapped = quat_multiply(q_rot, quat_normalize(np.roll(est.quaternions[a.est_index[few]], shift, axis=1)))
    return float(np.median(quat_angle_deg(quat_conj_multiply(a.gt_quaternions[few], q_swapped))))


def frame_notes(
    label: str,
    est: Trajectory,
    gt_base: Trajectory,
    scene: str,
    frame: str,
    gt_frame: str,
    with_scale: bool,
    max_gap: float,
    median_aoe: float,
) -> list[str | None]:
    """OpenLORIS files: the quaternion-order and sensor-frame checks of a sequence whose AOE is large."""
    by_frame, swapped = median_aoe_by_frame(est, gt_base, scene, with_scale, max_gap, gt_frame, swapped_in=frame)
    return [
        plausibility.quaternion_order(label, median_aoe, swapped),
        plausibility.frame_mismatch(label, frame, by_frame),
    ]


def other_spans(
    groundtruth: Mapping[int, Trajectory], scene: str, seq: int, more: Mapping[str, tuple[float, float]] | None
) -> dict[str, tuple[float, float]]:
    """Time spans of the other ground-truth sequences (this scene's first), for the time-overlap check."""
    spans = {f"{scene}-{k}": span for k, span in time_spans(groundtruth).items() if k != seq}
    spans.update({k: v for k, v in (more or {}).items() if k not in spans and k != f"{scene}-{seq}"})
    return spans


def degenerate_note(
    label: str,
    est_positions: np.ndarray,
    a: Association,
    pairs: PositionPairs | None,
    with_scale: bool = False,
    applied_to: Sequence[int] = (),
) -> str | None:
    """:func:`lorisnb.core.pipeline.plausibility.degenerate_fit` of an alignment fitted on the matched
    poses ``a`` (``with_scale``: a Sim(3) one; ``applied_to``: the other sequences it aligns): judged
    on the spread poses of :func:`spread_pairs` first (a long sequence that is not degenerate is found
    so at once), on all of them only when those few are."""
    if pairs is not None and pairs.degenerate() is None:
        return None
    return plausibility.degenerate_fit(label, est_positions[a.est_index], a.gt_positions, with_scale, applied_to)
