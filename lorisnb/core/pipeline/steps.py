"""The steps of the one pipeline (:func:`lorisnb.core.pipeline.sessions.evaluate_sessions`), each on arrays
and trajectories: OpenLORIS ground truth moved to a sensor frame, the estimate composed with a body
transform, matching in time by the spec's association, an alignment applied, per-pose errors."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from lorisnb.core.alignment.association import Association, associate, groundtruth_in_frame
from lorisnb.core.alignment.geometry import (
    Sim3,
    quat_angle_deg,
    quat_conj_multiply,
    quat_from_matrix,
    quat_multiply,
    quat_normalize,
    quat_rotate,
    quat_to_matrix,
    ros_quaternion_from_matrix,
)
from lorisnb.core.alignment.index_pairs import match_by_index
from lorisnb.core.conventions.choices import associate_nearest
from lorisnb.core.metrics import openloris as metrics
from lorisnb.core.metrics.written import written_aoe
from lorisnb.core.pipeline.model import ResultFile, SequenceErrors
from lorisnb.core.spec.evalspec import EvalSpec
from lorisnb.core.trajectory.blocks import blockwise
from lorisnb.core.trajectory.frames import FRAMES
from lorisnb.core.trajectory.poses import Trajectory, written_blocks
from lorisnb.errors import EvaluationError, ParseError

DEFAULT = EvalSpec()  # lorisnb's own: interpolation within 0.5 s, SE(3) on all matched poses


def apply_alignment(
    sim: Sim3, positions: np.ndarray, quaternions: np.ndarray, official_interpolation: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """Apply an alignment to poses: positions (N, 3) metres and orientations (N, 4) quaternions
    ``xyzw`` (normalized here); unit quaternions out. With ``official_interpolation`` and a scale,
    the orientation is extracted from ``s * R * R_p`` as the official tool does (its slip (b))."""
    pos = sim.apply(positions)
    if official_interpolation and sim.scale != 1.0:
        blocks = sim.scale * np.einsum("ij,njk->nik", sim.rotation, quat_to_matrix(quaternions))
        return pos, quat_normalize(ros_quaternion_from_matrix(blocks))
    return pos, quat_normalize(quat_multiply(quat_from_matrix(sim.rotation), quat_normalize(quaternions)))


def errors_after_alignment(
    seq: int, est: Trajectory, a: Association, sim: Sim3, official_interpolation: bool = False
) -> SequenceErrors:
    """Per-pose ATE (m) and AOE (deg) of the matched poses of ``est`` after alignment ``sim``
    (in row blocks, :mod:`lorisnb.core.trajectory.blocks`)."""
    if len(a) == 0 or a.gt_quaternions is None:
        return SequenceErrors.unmatched(seq, len(est), a.gt_start, a.gt_end)
    m = len(a)
    pos, q = np.empty((m, 3)), np.empty((m, 4))
    ate, aoe = np.empty(m), np.empty(m)
    gt_q = a.gt_quaternions

    def rows(lo: int, hi: int) -> None:
        k = a.est_index[lo:hi]
        p_k, q_k = np.take(est.positions, k, axis=0), np.take(est.quaternions, k, axis=0)  # without the GIL
        pos[lo:hi], q[lo:hi] = apply_alignment(sim, p_k, q_k, official_interpolation)
        ate[lo:hi] = metrics.ate(pos[lo:hi], a.gt_positions[lo:hi])
        aoe[lo:hi] = quat_angle_deg(quat_conj_multiply(gt_q[lo:hi], q[lo:hi]))  # unit on both sides

    blockwise(rows, m)
    est_blocks = written_blocks(est) if a.gt_blocks is not None else None
    read = None  # the matched poses as read, for the numbers of a spec that reads them so (tartanair_tools')
    if a.gt_read_quaternions is not None:
        k = a.est_index
        read = np.hstack([a.gt_positions, a.gt_read_quaternions, est.positions[k], est.quaternions[k]])
    if (
        est_blocks is not None and a.gt_blocks is not None
    ):  # as written, turned by the alignment's rotation (as evo and the devkit compose them)
        est_blocks = np.einsum("ij,njk->nik", sim.rotation, est_blocks[a.est_index])
        aoe = written_aoe(a.gt_blocks, est_blocks)  # evo's angle of R_est^T R_gt, the blocks as written
    return SequenceErrors(
        seq=seq, poses=len(est), stamps=a.stamps, ate=ate, aoe=aoe, est_positions=pos, gt_positions=a.gt_positions,
        est_quaternions=q, gt_quaternions=gt_q, gt_start=a.gt_start, gt_end=a.gt_end, scale=sim.scale,
        est_blocks=est_blocks, gt_blocks=a.gt_blocks if est_blocks is not None else None, read_poses=read,
    )  # fmt: skip


def match(gt: Trajectory, est: Trajectory, spec: EvalSpec = DEFAULT, label: str = "estimate") -> Association:
    """Matched poses of ``est`` and ``gt`` by the spec's association (estimate stamps shifted by
    ``t_offset`` first); for ``nearest`` the ground-truth poses are taken as they are; ``index``
    pairs pose i with pose i (an error naming ``label`` for files of different lengths)."""
    if spec.association == "index":
        a = match_by_index(gt, est, label, spec.as_written)
        return replace(a, gt_read_quaternions=gt.quaternions) if spec.poses_as_read and len(a) else a
    stamps = est.stamps + spec.t_offset if spec.t_offset else est.stamps
    if spec.association == "interpolate":
        return associate(gt, stamps, spec.max_gap, spec.official_interpolation)
    g_start = float(gt.stamps[0]) if len(gt) else np.nan
    g_end = float(gt.stamps[-1]) if len(gt) else np.nan
    gi, ej = associate_nearest(gt.stamps, stamps, spec.max_diff)
    if ej.size == 0:
        return Association(ej, np.zeros(0), np.zeros((0, 3)), None, g_start, g_end)
    blocks = written_blocks(gt) if spec.as_written else None
    return Association(ej, stamps[ej], gt.positions[gi], quat_normalize(gt.quaternions[gi]), g_start, g_end,
                       None if blocks is None else blocks[gi],
                       gt.quaternions[gi] if spec.poses_as_read else None)  # fmt: skip


def with_transform(est: Trajectory, transform: Sim3 | np.ndarray | tuple | None) -> Trajectory:
    """Estimate poses composed on the right with ``T_est_gt`` (poses of the ground-truth body;
    None: unchanged). A new trajectory; ``est`` is not changed."""
    if transform is None:
        return est
    m = transform.matrix() if isinstance(transform, Sim3) else np.asarray(transform, float)
    if m.shape != (4, 4):
        raise EvaluationError(f"transform: expected a 4x4 matrix T_est_gt, got shape {m.shape}")
    q_off = quat_from_matrix(m[:3, :3])
    q = quat_normalize(est.quaternions)
    pos = est.positions + quat_rotate(q, m[:3, 3])
    return Trajectory.from_checked(est.stamps, pos, quat_multiply(q, q_off), est.lines, dict(est.meta))


def groundtruth_frame(groundtruth: ResultFile) -> str:
    """The sensor frame an OpenLORIS ground truth is given in (``frame:`` header, default
    ``base_link``); ParseError for an unknown frame."""
    gt_frame = groundtruth.header.get("frame", "base_link")
    if gt_frame not in FRAMES:
        raise ParseError(
            groundtruth.path, groundtruth.header_lines.get("frame"),
            f"unknown ground-truth frame {gt_frame!r}; expected one of {', '.join(FRAMES)}",
        )  # fmt: skip
    return gt_frame


def moved_groundtruth(
    groundtruth: ResultFile, scene: str, frame: str, official_interpolation: bool = False
) -> dict[int, Trajectory]:
    """Every sequence of an OpenLORIS ground truth moved to sensor ``frame``
    (:func:`~lorisnb.core.alignment.association.groundtruth_in_frame`); new trajectories."""
    gt_frame = groundtruth_frame(groundtruth)
    return {
        s: groundtruth_in_frame(t, scene, frame, official_interpolation, gt_frame)
        for s, t in groundtruth.sequences.items()
    }
