"""evo's remaining evaluation options on matched poses (evo 1.38, ``evo.core.trajectory``), as
``evo_ape`` / ``evo_rpe`` apply them after the sync, in this order: the alignment (``-a``, ``-as``,
the scale only with ``-s`` alone: :func:`scale_alignment`; or ``--align_origin``:
:func:`origin_alignment`), then ``--project_to_plane`` (:func:`project_to_plane`).
"""

from __future__ import annotations

import numpy as np

from lorisnb.core.alignment.geometry import Sim3, quat_normalize, quat_to_matrix, umeyama
from lorisnb.errors import EvaluationError, ValidationError

PLANES = ("xy", "xz", "yz")
_NULL_AXIS = {"xy": 2, "xz": 1, "yz": 0}
_EPS = np.finfo(float).eps * 4.0


def scale_alignment(est_positions: np.ndarray, gt_positions: np.ndarray, frames: int | None = None) -> Sim3:
    """evo's scale correction alone (``-s`` without ``-a``): the Umeyama Sim(3) scale fitted on the
    first ``frames`` matched positions (None: all), applied about the origin (no rotation, no
    translation): ``p -> s p``."""
    p_e, p_g = np.asarray(est_positions, float), np.asarray(gt_positions, float)
    n = len(p_e) if frames is None else min(int(frames), len(p_e))
    if n < 2 and len(p_e) >= 2:  # (frames=1: the spec refuses it for sim3, and for the scale alone)
        raise ValidationError(f"align_frames={frames} with align='scale': a scale needs at least 2 poses; give "
                              "align_frames >= 2 (--align-frames), or leave it out to fit on all matched poses")  # fmt: skip
    if n < 2:
        raise ValidationError(f"a scale correction needs at least 2 matched poses, got {len(p_e)}; align='none' "
                              "scores them without it")  # fmt: skip
    if (why := evo_rank_refusal(p_e[:n], p_g[:n])) is not None:
        raise EvaluationError(
            f"no scale correction can be determined: {why}; evo's -s fits a whole Umeyama Sim(3) for its scale "
            "and refuses such positions ('Degenerate covariance rank, Umeyama alignment is not possible'); fit the "
            "scale on more poses (--align-frames N, or all), or score without it (--align none)"
        )
    return Sim3(np.eye(3), np.zeros(3), umeyama(p_e[:n], p_g[:n], with_scale=True).scale)


def evo_rank_refusal(est_positions: np.ndarray, gt_positions: np.ndarray) -> str | None:
    """Why evo's ``umeyama_alignment`` refuses these matched positions, or None: its cross-covariance
    ``1/n sum (g_i - mean g)(e_i - mean e)^T`` has fewer than 2 singular values above machine epsilon
    (absolute), as evo 1.38 tests it (2 poses, positions on one line, a point)."""
    p_e, p_g = np.asarray(est_positions, float), np.asarray(gt_positions, float)
    n = len(p_e)
    cov = (p_g - p_g.mean(axis=0)).T @ (p_e - p_e.mean(axis=0)) * (1.0 / n)
    d = np.linalg.svd(cov, compute_uv=False)
    rank = int(np.count_nonzero(d > np.finfo(float).eps))
    if rank >= 2:
        return None
    return (f"the cross-covariance of the {n} matched positions has rank {rank} (evo needs 2: "
            f"{'2 poses' if n == 2 else 'positions on one line or one point'})")  # fmt: skip


def origin_alignment(
    est_position: np.ndarray, est_quaternion: np.ndarray, gt_position: np.ndarray, gt_quaternion: np.ndarray,
    est_block: np.ndarray | None = None, gt_block: np.ndarray | None = None,
) -> Sim3:  # fmt: skip
    """evo's ``--align_origin``: the rigid transform taking the first matched estimate pose onto the
    first matched reference pose, ``T_gt0 T_est0^-1`` (quaternions ``xyzw``, positions metres); with
    both poses' rotation blocks as written (KITTI files, ``est_block``, ``gt_block``), of those, the
    inverse a transpose, as evo composes them (the rotation is then not quite one)."""
    if est_block is not None and gt_block is not None:
        r_g, r_e = np.asarray(gt_block, float), np.asarray(est_block, float)
    else:
        r_g = quat_to_matrix(quat_normalize(np.asarray(gt_quaternion, float)))
        r_e = quat_to_matrix(quat_normalize(np.asarray(est_quaternion, float)))
    rot = r_g @ r_e.T
    return Sim3(rot, np.asarray(gt_position, float) - rot @ np.asarray(est_position, float), 1.0)


def project_to_plane(positions: np.ndarray, quaternions: np.ndarray, plane: str) -> tuple[np.ndarray, np.ndarray]:
    """evo's ``project(plane)``: the coordinate normal to ``plane`` (``xy``, ``xz``, ``yz``) set to
    0, and each orientation replaced by the rotation about that normal by the static-xyz Euler
    angle of that axis (``euler_from_matrix(R, "sxyz")``). Returns new (positions, quaternions
    ``xyzw``)."""
    if plane not in PLANES:
        raise ValidationError(f"project_to_plane {plane!r}: expected one of {', '.join(PLANES)}")
    axis = _NULL_AXIS[plane]
    p = np.array(positions, float, copy=True)
    p[:, axis] = 0.0
    m = quat_to_matrix(quat_normalize(quaternions))
    cy = np.sqrt(m[:, 0, 0] * m[:, 0, 0] + m[:, 1, 0] * m[:, 1, 0])
    regular = cy > _EPS
    if axis == 0:
        angle = np.where(regular, np.arctan2(m[:, 2, 1], m[:, 2, 2]), np.arctan2(-m[:, 1, 2], m[:, 1, 1]))
    elif axis == 1:
        angle = np.arctan2(-m[:, 2, 0], cy)
    else:
        angle = np.where(regular, np.arctan2(m[:, 1, 0], m[:, 0, 0]), 0.0)
    half = angle / 2.0
    q = np.zeros((len(p), 4))
    q[:, axis] = np.sin(half)
    q[:, 3] = np.cos(half)
    return p, q
