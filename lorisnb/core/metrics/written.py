"""Errors of poses composed as their files wrote them (KITTI's 7-digit rotation blocks, not
quite rotations), the way evo composes them: relative poses ``P1^-1 P2`` with the *transposed*
rotation block as the inverse (evo's ``lie_algebra.relative_se3``), and the angle of a block by
scipy's ``Rotation.from_matrix`` (evo's ``so3_log_angle``). The quaternions' route
(:mod:`lorisnb.core.metrics.openloris`) takes each block's nearest rotation first; on exact
rotations both agree to rounding, on KITTI files they differ by up to about 2e-5 relative.
"""

from __future__ import annotations

import numpy as np


def block_angles_deg(blocks: np.ndarray) -> np.ndarray:
    """(N,) angle of each (N, 3, 3) block, degrees: scipy's ``Rotation.from_matrix(b).magnitude()``
    (evo's ``so3_log_angle(b, degrees=True)``)."""
    from scipy.spatial.transform import (
        Rotation,
    )  # here: reading a file imports no scipy (tests/package/test_startup.py)

    b = np.asarray(blocks, float)
    if len(b) == 0:
        return np.zeros(0)
    return np.degrees(Rotation.from_matrix(b).magnitude())


def written_aoe(gt_blocks: np.ndarray, est_blocks: np.ndarray) -> np.ndarray:
    """evo's APE angle of each pose, degrees: the angle of ``R_est^T R_gt`` (``relative_se3(est, ref)``)."""
    return block_angles_deg(np.einsum("nji,njk->nik", est_blocks, gt_blocks))


def written_rpe(
    gt_positions: np.ndarray,
    gt_blocks: np.ndarray,
    est_positions: np.ndarray,
    est_blocks: np.ndarray,
    i: np.ndarray,
    j: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """evo's RPE of the pairs (i, j): ``E = rel(rel(Q_i, Q_j), rel(P_i, P_j))`` with ``rel(A, B) =
    [R_A^T R_B | R_A^T (t_B - t_A)]``; returns ``|t_E|`` (metres) and the angle of ``R_E`` (degrees)."""
    rg_i, rg_j, re_i, re_j = gt_blocks[i], gt_blocks[j], est_blocks[i], est_blocks[j]
    q_r = np.einsum("nji,njk->nik", rg_i, rg_j)
    q_t = np.einsum("nji,nj->ni", rg_i, gt_positions[j] - gt_positions[i])
    p_r = np.einsum("nji,njk->nik", re_i, re_j)
    p_t = np.einsum("nji,nj->ni", re_i, est_positions[j] - est_positions[i])
    e_r = np.einsum("nji,njk->nik", q_r, p_r)
    e_t = np.einsum("nji,nj->ni", q_r, p_t - q_t)
    return np.linalg.norm(e_t, axis=1), block_angles_deg(e_r)
