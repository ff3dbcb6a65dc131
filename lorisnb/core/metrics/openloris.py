"""The OpenLORIS-Scene metrics as pure functions on arrays.

Equation numbers refer to Shi et al., "Are We Ready for Service Robots? The OpenLORIS-Scene
Datasets for Lifelong SLAM", ICRA 2020 (``../shared/papers/openloris-scene-2020.md``).

Every threshold argument broadcasts: pass arrays of eps / phi / delta / tau shaped for a grid and
get the grid back (that is how :mod:`lorisnb.core.lifelong.sweep` evaluates thousands of settings at once).
Units: metres, degrees, seconds.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Union

import numpy as np

from lorisnb.core.alignment.geometry import (
    as_quaternions,
    quat_angle_deg,
    quat_conj_multiply,
    quat_conjugate,
    quat_multiply,
    quat_rotate,
)
from lorisnb.core.trajectory.blocks import blockwise

if TYPE_CHECKING:
    from scipy.spatial.transform import Rotation

#: Orientations: a scipy ``Rotation`` or (N, 4) quaternions ``xyzw``.
Orientations = Union["Rotation", np.ndarray]


def ate(est_positions: np.ndarray, gt_positions: np.ndarray) -> np.ndarray:
    """Absolute trajectory error of each pose: position distance, metres."""
    d = np.asarray(est_positions, float) - np.asarray(gt_positions, float)
    return np.sqrt(np.einsum("...i,...i->...", d, d))


def aoe(est_rotations: Orientations, gt_rotations: Orientations) -> np.ndarray:
    """Absolute orientation error of each pose: angle of ``R_gt^-1 R_est``, degrees in [0, 180].
    Orientations are scipy ``Rotation`` objects or (N, 4) quaternions ``xyzw``."""
    q_est, q_gt = as_quaternions(est_rotations), as_quaternions(gt_rotations)
    return quat_angle_deg(quat_conj_multiply(q_gt, q_est))


def correctness(ate_m: np.ndarray, aoe_deg: np.ndarray, eps, phi) -> np.ndarray:
    """Eq. (1): c = (ATE <= eps) and (AOE <= phi). Broadcasts over thresholds."""
    return (np.asarray(ate_m) <= eps) & (np.asarray(aoe_deg) <= phi)


def valid_intervals(stamps: np.ndarray, t_end: float, t_start: float = -np.inf) -> np.ndarray:
    """``t_{k+1} - t_k`` for each matched pose, with ``t_{N+1} = t_end`` (Eq. 2), seconds.

    Stamps are first clipped to the ground truth's span ``[t_start, t_end]``: a pose matched by
    nearest stamps may lie up to ``max_diff`` outside it, and its time counts only inside (no
    interval is negative, and the correct time never exceeds the span: CR <= 1). Interpolated
    poses always lie inside, so the official tool's numbers are unchanged."""
    stamps = np.asarray(stamps, float)
    if stamps.size == 0:
        return stamps
    return np.diff(np.append(np.clip(stamps, t_start, t_end), t_end))


def correct_time(stamps: np.ndarray, correct: np.ndarray, t_end: float, delta, t_start: float = -np.inf) -> np.ndarray:
    """Numerator of Eq. (2)/(3): sum over poses of ``min(t_{k+1} - t_k, delta) * c_k``, seconds,
    inside the ground truth's span ``[t_start, t_end]`` (:func:`valid_intervals`).

    ``correct`` may carry leading grid axes (``(..., N)``); ``delta`` broadcasts against them.
    """
    dt = valid_intervals(stamps, t_end, t_start)
    delta = np.asarray(delta, float)
    held = np.minimum(dt, delta[..., None]) if delta.ndim else np.minimum(dt, delta)
    return np.sum(np.where(correct, held, 0.0), axis=-1)


def correct_rate(correct_seconds, t_min: float, t_max: float) -> np.ndarray:
    """Eq. (2): CR = correct time / (t_max - t_min)."""
    span = t_max - t_min
    return np.asarray(correct_seconds, float) / span if span > 0 else np.zeros_like(correct_seconds, float)


def correct_rate_tracking(correct_seconds, t0: float, t_max: float) -> np.ndarray:
    """Eq. (3): CR-T = correct time / (t_max - t0), t0 the first matched estimate (0 if t0 = t_max)."""
    span = t_max - t0
    return np.asarray(correct_seconds, float) / span if span > 0 else np.zeros_like(correct_seconds, float)


def relocalization_time(t0: float, t_min: float) -> float:
    """Time to (re-)localize: ``max(0, t0 - t_min)``, seconds."""
    return max(0.0, float(t0 - t_min))


def relocalization_score(t0: float, t_min: float, first_correct, tau) -> np.ndarray:
    """Eq. (4): CS-R = exp(-(t0 - t_min) / tau) * c(p_0). Broadcasts over ``tau`` and
    ``first_correct``."""
    return np.where(first_correct, np.exp(-relocalization_time(t0, t_min) / np.asarray(tau, float)), 0.0)


def rmse(values: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
    """Root mean square over the last axis (of the entries where ``mask`` is true); NaN if empty."""
    v = np.asarray(values, float)
    if mask is None:
        return np.sqrt(np.mean(v * v, axis=-1)) if v.shape[-1] else np.full(v.shape[:-1], np.nan)
    m = np.asarray(mask, bool)
    n = m.sum(axis=-1)
    s = np.sum(np.where(m, v * v, 0.0), axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(n > 0, np.sqrt(s / np.maximum(n, 1)), np.nan)


RPE_UNITS = ("s", "f", "m")
#: The metrics that are rates between 0 and 1 (CR, CR-T, CS-R); the others are errors (RMSE >= 0).
RATES = ("cr", "cr_t", "cs_r")


def rpe_pairs(
    stamps: np.ndarray, gt_positions: np.ndarray, delta: float, unit: str = "s", all_pairs: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs (i, j) for the relative pose error over ``delta``.

    Units: ``s`` seconds (j is the pose whose stamp is closest to ``t_i + delta``, as the TUM
    RGB-D tool does; starts whose ``t_i + delta`` lies past the last stamp are left out), ``f`` frames (``j = i + delta``), ``m`` metres travelled along the ground
    truth (j is the first pose at least ``delta`` metres further along the path).

    ``all_pairs`` uses every i (TUM's definition); otherwise only every ``delta``-th start, as
    evo does by default.
    """
    n = len(stamps)
    if n < 2:
        return np.zeros(0, int), np.zeros(0, int)
    if unit == "f":
        step = int(delta)
        if step < 1:
            raise ValueError(f"RPE delta in frames must be a positive integer, got {delta}")
        i = np.arange(0, n - step) if all_pairs else np.arange(0, n - step, step)
        return i, i + step
    if unit == "s":
        j = np.empty(n, np.intp)
        keep = np.empty(n, bool)

        def closest(lo: int, hi: int) -> None:  # the pose closest to t_i + delta, for a block of starts
            target = stamps[lo:hi] + delta  # increasing, as the stamps: search between its first and last
            w0, w1 = np.searchsorted(stamps, (target[0], target[-1]))
            k = np.clip(np.searchsorted(stamps[w0 : w1 + 1], target) + w0, 1, n - 1)
            closer_left = np.abs(np.take(stamps, k - 1) - target) <= np.abs(np.take(stamps, k) - target)
            k = np.where(closer_left, k - 1, k)
            j[lo:hi] = k
            keep[lo:hi] = (k > np.arange(lo, hi)) & (target <= stamps[-1] + 1e-9)

        blockwise(closest, n)
        i = np.flatnonzero(keep)
        j = j[i]
    elif unit == "m":
        dist = np.concatenate(([0.0], np.cumsum(np.linalg.norm(np.diff(gt_positions, axis=0), axis=1))))
        j = np.searchsorted(dist, dist + delta, side="left")
        i = np.arange(n)
        keep = j < n
        i, j = i[keep], j[keep]
    else:
        raise ValueError(f"unknown RPE unit {unit!r}; expected one of {RPE_UNITS}")
    if not all_pairs and i.size:
        # non-overlapping: chain from the first start
        chosen = []
        nxt = np.full(n, -1)
        nxt[i] = j
        k = int(i[0])
        while 0 <= k < n and nxt[k] >= 0:  # walks segments, not poses: at most n / step steps
            chosen.append(k)
            k = int(nxt[k])
        i = np.array(chosen, dtype=int)
        j = nxt[i]
    return i, j


def rpe(
    gt_positions: np.ndarray,
    gt_rotations: Orientations,
    est_positions: np.ndarray,
    est_rotations: Orientations,
    i: np.ndarray,
    j: np.ndarray,
    *,
    assume_unit: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """Relative pose error of pairs (i, j), TUM definition:
    ``E = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j)`` with Q ground truth, P estimate.

    Orientations are scipy ``Rotation`` objects or (N, 4) quaternions ``xyzw`` (normalized here
    unless ``assume_unit``). Computed in row blocks (:mod:`lorisnb.core.trajectory.blocks`) through each
    pose's ``D_k = R(Q_k) R(P_k)^-1``: E's angle is that of ``D_j^-1 D_i`` (E's rotation
    ``R(Q_j)^-1 D_i R(P_j)`` is a conjugate of it) and its translation's length is
    ``|D_i (p_j - p_i) - (q_j - q_i)|`` (a rotation keeps lengths): equal to the definition to
    rounding, with a third of its quaternion products per pair.
    Returns (translational error in metres, rotational error in degrees) per pair.
    """
    i, j = np.asarray(i, np.intp), np.asarray(j, np.intp)
    if len(i) == 0:
        return np.zeros(0), np.zeros(0)
    if assume_unit:
        qg, qe = np.asarray(gt_rotations, float), np.asarray(est_rotations, float)
    else:
        qg, qe = as_quaternions(gt_rotations), as_quaternions(est_rotations)
    pg, pe = np.asarray(gt_positions, float), np.asarray(est_positions, float)
    d = np.empty(qg.shape)

    def per_pose(lo: int, hi: int) -> None:
        d[lo:hi] = quat_multiply(qg[lo:hi], quat_conjugate(qe[lo:hi]))

    blockwise(per_pose, len(d))
    trans, rot = np.empty(len(i)), np.empty(len(i))

    def rows(lo: int, hi: int) -> None:
        a, b = i[lo:hi], j[lo:hi]
        take = np.take  # gathers: faster than fancy indexing, and without the GIL
        di = take(d, a, axis=0)
        err_t = quat_rotate(di, take(pe, b, axis=0) - take(pe, a, axis=0)) - (take(pg, b, axis=0) - take(pg, a, axis=0))
        trans[lo:hi] = np.sqrt(np.einsum("ij,ij->i", err_t, err_t))
        rot[lo:hi] = quat_angle_deg(quat_conj_multiply(take(d, b, axis=0), di))

    blockwise(rows, len(i))
    return trans, rot
