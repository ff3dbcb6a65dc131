"""evo's rules for matching an estimate with its reference in time, as ``evo_ape`` / ``evo_rpe``
apply them (evo 1.38, ``evo.core.sync``), on arrays: selectable as the associations
``evo-nearest`` and ``evo-interpolate`` (named so that they cannot be confused with lorisnb's
``nearest``, TUM's greedy one-to-one rule, nor with its ``interpolate``, the OpenLORIS bracket rule).

``evo-nearest`` (:func:`evo_associate`): evo starts from the trajectory with *fewer* poses (the
estimate when both have as many), and gives each of its stamps, independently, the nearest stamp of
the other within ``max_diff`` (``<=``, 0.01 s by default); one pose of the longer trajectory may
serve two. ``t_offset`` is added to the estimate's stamps for the matching only.
``evo-interpolate`` (:func:`evo_sync`): the same matched stamps of the shorter trajectory, at which
the longer one is interpolated (linear positions, slerp, clamped at its ends) instead of snapped.

Before the sync evo applies (in this order) :func:`evo_downsample` and :func:`evo_motion_filter` to
both trajectories, then ``--t_start/--t_end`` to the reference only (:func:`time_window`).
"""

from __future__ import annotations

import numpy as np

from lorisnb.core.alignment.geometry import quat_conj_multiply, quat_normalize
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.errors import ValidationError

EVO_MAX_DIFF = 0.01  # seconds: evo_ape's and evo_rpe's --t_max_diff
SYNC_METHODS = ("nearest", "interpolate")
_EPS = np.finfo(float).eps * 4.0  # evo.core.transformations._EPS


def evo_match_indices(
    stamps_1: np.ndarray, stamps_2: np.ndarray, max_diff: float = EVO_MAX_DIFF, offset_2: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """evo's ``matching_time_indices``: for each stamp of ``stamps_1`` the nearest stamp of
    ``stamps_2 + offset_2`` (seconds) if it lies within ``max_diff`` (``<=``). Ties go to the earlier
    stamp of ``stamps_2``. Returns the matched indices of both, in the order of ``stamps_1``.

    Linear time when ``stamps_2`` does not decrease (evo's binary search, reproduced with its exact
    comparisons); otherwise evo's linear search (the first of the closest stamps), here by sorting.
    """
    s1 = np.asarray(stamps_1, float).reshape(-1)
    s2 = np.asarray(stamps_2, float).reshape(-1) + offset_2
    empty = np.zeros(0, np.intp)
    if s1.size == 0 or s2.size == 0:
        return empty, empty
    if np.all(np.diff(s2) >= 0):
        inside = ~((s1 < s2[0] - max_diff) | (s1 > s2[-1] + max_diff))
        idx = np.minimum(np.searchsorted(s2, s1, side="right"), s2.size - 1)
        diff_ub = s2[idx] - s1
        diff_lb = np.where(idx > 0, s1 - s2[np.maximum(idx - 1, 0)], np.inf)
        up = (diff_ub <= max_diff) & (diff_ub < diff_lb)
        low = ~up & (diff_lb <= max_diff) & (diff_lb <= diff_ub)
        ok = inside & (up | low)
        best = np.where(up, idx, idx - 1)
        return np.flatnonzero(ok), best[ok].astype(np.intp)
    # evo's fallback: argmin of |stamps_2 - t| (the first index of the smallest difference)
    order = np.argsort(s2, kind="stable")
    values, first = np.unique(s2[order], return_index=True)
    first_index = order[first]  # the earliest file position of each distinct stamp
    k = np.searchsorted(values, s1, side="left")
    lo, hi = np.clip(k - 1, 0, values.size - 1), np.clip(k, 0, values.size - 1)
    d_lo, d_hi = np.abs(values[lo] - s1), np.abs(values[hi] - s1)
    i_lo, i_hi = first_index[lo], first_index[hi]
    take_lo = (d_lo < d_hi) | ((d_lo == d_hi) & (i_lo < i_hi))
    best = np.where(take_lo, i_lo, i_hi)
    diff = np.where(take_lo, d_lo, d_hi)
    ok = diff <= max_diff
    return np.flatnonzero(ok), best[ok].astype(np.intp)


def evo_associate(
    gt_stamps: np.ndarray, est_stamps: np.ndarray, max_diff: float = EVO_MAX_DIFF, t_offset: float = 0.0
) -> tuple[np.ndarray, np.ndarray, str]:
    """evo's nearest association (``sync.associate_trajectories``, reference first): indices
    ``(gt_index, est_index)`` of the matched poses in the order of the shorter trajectory, and which
    trajectory evo started from (``"gt"`` or ``"est"``; the estimate when both have as many poses).
    ``t_offset`` (seconds) is added to the estimate's stamps."""
    n_gt, n_est = len(gt_stamps), len(est_stamps)
    if n_est > n_gt:  # evo: the second (estimate) is longer, start from the reference
        gi, ej = evo_match_indices(gt_stamps, est_stamps, max_diff, t_offset)
        return gi, ej, "gt"
    ej, gi = evo_match_indices(est_stamps, gt_stamps, max_diff, -t_offset)
    return gi, ej, "est"


def evo_slerp(q0: np.ndarray, q1: np.ndarray, fraction: np.ndarray) -> np.ndarray:
    """evo's ``transformations.quaternion_slerp`` on (N, 4) quaternions (any component order,
    normalized first), fractions (N,): q0 at 0, q1 at 1, q0 when both are (nearly) the same
    rotation, along the shorter arc."""
    a = quat_normalize(q0)
    b = quat_normalize(q1)
    f = np.asarray(fraction, float).reshape(-1)
    d = np.einsum("ij,ij->i", a, b)
    same = np.abs(np.abs(d) - 1.0) < _EPS
    b = np.where((d < 0.0)[:, None], -b, b)
    d = np.abs(d)
    angle = np.arccos(np.clip(d, -1.0, 1.0))
    tiny = same | (np.abs(angle) < _EPS)
    with np.errstate(divide="ignore", invalid="ignore"):
        isin = 1.0 / np.sin(angle)
        out = a * (np.sin((1.0 - f) * angle) * isin)[:, None] + b * (np.sin(f * angle) * isin)[:, None]
    out = np.where(tiny[:, None], a, out)
    out = np.where((f == 1.0)[:, None], quat_normalize(q1), out)
    return np.where((f == 0.0)[:, None], a, out)


def evo_interpolate(traj: Trajectory, stamps: np.ndarray) -> Trajectory:
    """evo's ``PoseTrajectory3D.interpolate`` (no extrapolation): poses of ``traj`` at ``stamps``
    (seconds), positions linear and orientations by :func:`evo_slerp` between the poses around
    each stamp, clamped to the first or last pose outside ``traj``'s span."""
    t = np.asarray(stamps, float).reshape(-1)
    if len(traj) < 2:
        raise ValidationError("evo's interpolation needs a trajectory of at least two poses")
    g, p = traj.stamps, traj.positions
    idx = np.clip(np.searchsorted(g, t, side="left"), 1, len(g) - 1)
    t_prev, t_next = g[idx - 1], g[idx]
    dt = t_next - t_prev
    frac = (t - t_prev) / np.where(dt > 0.0, dt, 1.0)
    frac = np.clip(np.where(dt > 0.0, frac, 0.0), 0.0, 1.0)
    xyz = p[idx - 1] + frac[:, None] * (p[idx] - p[idx - 1])
    q = evo_slerp(traj.quaternions[idx - 1], traj.quaternions[idx], frac)
    return Trajectory.from_checked(t, xyz, q, None, dict(traj.meta))  # stamps of a checked trajectory


def evo_sync(
    gt: Trajectory,
    est: Trajectory,
    method: str = "nearest",
    max_diff: float = EVO_MAX_DIFF,
    t_offset: float = 0.0,
) -> tuple[Trajectory, Trajectory]:
    """evo's ``associate_trajectories`` on lorisnb trajectories: the synchronized copies
    ``(gt, est)``, pose k of one matched with pose k of the other (see the module docstring).
    ``method`` ``"nearest"`` or ``"interpolate"``. Each copy's ``meta["index"]`` holds the index of
    every kept pose in its source (-1 for an interpolated pose). No match gives two empty copies."""
    if method not in SYNC_METHODS:
        raise ValidationError(f"evo sync method {method!r}: expected one of {', '.join(SYNC_METHODS)}")
    gi, ej, short = evo_associate(gt.stamps, est.stamps, max_diff, t_offset)

    def pick(traj: Trajectory, index: np.ndarray) -> Trajectory:
        out = traj.subset(index)
        out.meta["index"] = index
        return out

    if method == "interpolate" and gi.size:
        if short == "gt":
            g = pick(gt, gi)
            e = evo_interpolate(est, g.stamps - t_offset)
            e.meta["index"] = np.full(gi.size, -1)
            return g, e
        e = pick(est, ej)
        g = evo_interpolate(gt, e.stamps + t_offset)
        g.meta["index"] = np.full(ej.size, -1)
        return g, e
    return pick(gt, gi), pick(est, ej)


def time_window(traj: Trajectory, t_start: float | None = None, t_end: float | None = None) -> Trajectory:
    """The poses with ``t_start <= stamp <= t_end`` (seconds; None: the trajectory's own first or
    last stamp), as evo's ``reduce_to_time_range`` (evo applies it to the reference only)."""
    if len(traj) == 0:
        return traj
    lo = float(traj.stamps[0]) if t_start is None else float(t_start)
    hi = float(traj.stamps[-1]) if t_end is None else float(t_end)
    if lo > hi:
        if t_start is not None and t_end is not None:
            raise ValidationError(f"t_start {lo:.17g} s is after t_end {hi:.17g} s; expected t_start <= t_end")
        first, last = float(traj.stamps[0]), float(traj.stamps[-1])
        given = f"t_start {lo:.17g} s is after" if t_end is None else f"t_end {hi:.17g} s is before"
        edge = f"last stamp {last:.17g} s" if t_end is None else f"first stamp {first:.17g} s"
        raise ValidationError(f"{given} the ground truth's {edge}: no ground-truth pose is left; give a "
                              f"{'t_start' if t_end is None else 't_end'} within its span {first:.17g}..{last:.17g} s "
                              "(stamps on the ground truth's clock)")  # fmt: skip
    return traj.subset((traj.stamps >= lo) & (traj.stamps <= hi))


def evo_downsample(n_poses: int, num: int) -> np.ndarray:
    """Indices evo's ``downsample(num)`` keeps of ``n_poses`` poses: all if there are no more than
    ``num``, else ``num`` evenly spaced ones (``linspace`` truncated to integers)."""
    if int(num) < 1:
        raise ValidationError(f"downsample to {num} poses: expected at least 1")
    if n_poses <= num:
        return np.arange(n_poses)
    return np.linspace(0, n_poses - 1, int(num), dtype=int)


def rotation_angles(q_from: np.ndarray, q_to: np.ndarray) -> np.ndarray:
    """Angle of the rotation from each of ``q_from`` to ``q_to`` (quaternions ``xyzw``), radians in
    [0, pi] (evo's ``so3_log_angle(relative_so3(...))``)."""
    d = quat_conj_multiply(quat_normalize(q_from), quat_normalize(q_to))
    xyz = d[..., :3]
    return 2.0 * np.arctan2(np.sqrt(np.einsum("...i,...i->...", xyz, xyz)), np.abs(d[..., 3]))


def accumulated_distances(positions: np.ndarray) -> np.ndarray:
    """evo's ``geometry.accumulated_distances``: path length from the first position to each, metres."""
    x = np.asarray(positions, float)
    return np.concatenate((np.array([0.0]), np.cumsum(np.linalg.norm(x[:-1] - x[1:], axis=1))))


def evo_motion_filter(positions: np.ndarray, quaternions: np.ndarray, distance: float, angle_deg: float) -> np.ndarray:
    """Indices evo's ``motion_filter(distance, angle, degrees=True)`` keeps: the first pose, then
    each pose that has travelled at least ``distance`` metres (along the path) or turned at least
    ``angle_deg`` degrees from the last kept one. The loop runs over kept poses, each step
    searching ahead in blocks."""
    p = np.asarray(positions, float)
    n = len(p)
    if n < 2:
        raise ValidationError("the motion filter needs at least two poses")
    if distance < 0 or angle_deg < 0:
        raise ValidationError("motion filter thresholds must be >= 0 (metres, degrees)")
    q = quat_normalize(quaternions)
    dist = accumulated_distances(p)
    angle = np.deg2rad(angle_deg)
    kept = [0]
    k, prev_dist = 0, 0.0
    while k < n - 1:  # one step per kept pose
        lo, block, found = k + 1, 256, -1
        while lo < n and found < 0:
            hi = min(n, lo + block)
            hit = (dist[lo:hi] - prev_dist >= distance) | (rotation_angles(q[k], q[lo:hi]) >= angle)
            if hit.any():
                found = lo + int(np.argmax(hit))
            lo, block = hi, block * 2
        if found < 0:
            break
        kept.append(found)
        k, prev_dist = found, float(dist[found])
    return np.asarray(kept, np.intp)
