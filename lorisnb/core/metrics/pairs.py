"""The pose pairs of a relative pose error, every rule: evo's (``evo_rpe --delta D --delta_unit
f|m|d|r [--all_pairs] [--pairs_from_reference]``, evo 1.38 ``evo.core.filters``) and lorisnb's
seconds (:func:`lorisnb.core.metrics.openloris.rpe_pairs`: the associated pose closest to ``t_i + delta``, as
TUM picks it, but over associated poses only). TUM's ``evaluate_rpe.py`` itself, which pairs every
estimate pose and composes its error in the other order, is :func:`tum_rpe`.

Units (:data:`RPE_UNITS`): ``frames``, ``m`` (path length), ``deg`` and ``rad`` (rotation), ``s``.
The path length and rotation are measured along the trajectory the pairs are taken from: evo's
default is the (aligned) estimate, ``pairs="reference"`` is evo's ``--pairs_from_reference``.

Consecutive pairs (evo's default): from the first pose, each pair ends at the first pose
``delta`` frames on, or whose accumulated path length (rotation angle, summed step by step) since
the pair's start reaches ``delta``; the next pair starts there. All pairs (``all_pairs=True``):
frames: every ``(i, i + delta)``; metres: for each start i the pose j > i whose path distance from
i is *closest* to ``delta``, kept if it differs from ``delta`` by at most ``tolerance * delta``
(evo's ``--delta_tol``, 0.1); angles: every j > i whose direct rotation angle from i lies within
``delta +- tolerance * delta`` (quadratic in the poses, as evo's).
"""

from __future__ import annotations

import numpy as np

from lorisnb.core.alignment.geometry import quat_normalize, quat_to_matrix
from lorisnb.core.conventions.evo_sync import accumulated_distances, rotation_angles
from lorisnb.core.metrics import openloris as metrics
from lorisnb.errors import ValidationError

RPE_UNITS = ("frames", "m", "deg", "rad", "s")
#: lorisnb's own rules (``all_pairs=None``): every start, along the reference (see :func:`rpe_indices`).
RPE_PAIRS = ("estimate", "reference")
RPE_TOLERANCE = 0.1  # evo's --delta_tol
_ALIASES = {"f": "frames", "d": "deg", "r": "rad"}


def rpe_indices(
    stamps: np.ndarray,
    gt_positions: np.ndarray,
    gt_quaternions: np.ndarray | None,
    est_positions: np.ndarray,
    est_quaternions: np.ndarray | None,
    delta: float,
    unit: str = "s",
    pairs: str = "reference",
    all_pairs: bool | None = None,
    tolerance: float = RPE_TOLERANCE,
) -> tuple[np.ndarray, np.ndarray]:
    """The RPE pairs of matched poses under every rule.

    ``all_pairs=None`` is lorisnb's own rule (its default, unchanged): every start pose, for ``s``
    the associated pose closest to ``t_i + delta`` (TUM's choice of j, not its tool: :func:`tum_rpe`), ``frames`` ``i + delta``, ``m`` the first pose at
    least ``delta`` metres further along the reference (:func:`lorisnb.core.metrics.openloris.rpe_pairs`);
    ``deg`` / ``rad`` take evo's all pairs. ``True`` / ``False`` are evo's all pairs (within
    ``tolerance``) / consecutive pairs (:func:`evo_rpe_pairs`; ``s``: lorisnb's seconds rule, with
    consecutive pairs chained). ``pairs``: measure ``m``/``deg``/``rad`` along the ``reference`` or
    the ``estimate`` (the aligned poses, as evo)."""
    unit = rpe_unit(unit)
    if pairs not in RPE_PAIRS:
        raise ValidationError(f"RPE pairs along {pairs!r}: expected one of {', '.join(RPE_PAIRS)}")
    if unit == "s":
        return metrics.rpe_pairs(stamps, gt_positions, delta, "s", all_pairs=all_pairs is not False)
    pos, quat = (gt_positions, gt_quaternions) if pairs == "reference" else (est_positions, est_quaternions)
    if all_pairs is None:
        if unit == "frames":
            return metrics.rpe_pairs(stamps, pos, delta, "f", all_pairs=True)
        if unit == "m":
            return metrics.rpe_pairs(stamps, pos, delta, "m", all_pairs=True)
        all_pairs = True
    return evo_rpe_pairs(pos, quat, delta, unit, all_pairs, tolerance)


def rpe_unit(unit: str) -> str:
    """A unit name of :data:`RPE_UNITS` (evo's letters ``f``, ``d``, ``r`` accepted)."""
    u = _ALIASES.get(unit, unit)
    if u not in RPE_UNITS:
        raise ValidationError(f"RPE unit {unit!r}: expected one of {', '.join(RPE_UNITS)}")
    return u


def _consecutive(steps: np.ndarray, delta: float) -> np.ndarray:
    """Start indices of evo's consecutive pairs: accumulate ``steps[k]`` (the increment from pose k
    to k + 1) from each start, reset when the sum reaches ``delta``. One loop step per pair; the
    sums are the same sequential float additions as evo's."""
    n = steps.size + 1
    ids = [0]
    k = 0
    while k < n - 1:  # one iteration per pair
        lo, block, found = k, 256, -1
        run = 0.0
        while lo < n - 1 and found < 0:
            hi = min(n - 1, lo + block)
            acc = np.cumsum(np.concatenate(([run], steps[lo:hi])))[1:]
            hit = np.flatnonzero(acc >= delta)
            if hit.size:
                found = lo + int(hit[0]) + 1
            else:
                run = float(acc[-1]) if acc.size else run
            lo, block = hi, block * 2
        if found < 0:
            break
        ids.append(found)
        k = found
    return np.asarray(ids, np.intp)


def evo_rpe_pairs(
    positions: np.ndarray,
    quaternions: np.ndarray | None,
    delta: float,
    unit: str = "frames",
    all_pairs: bool = False,
    tolerance: float = RPE_TOLERANCE,
) -> tuple[np.ndarray, np.ndarray]:
    """evo's pairs ``(i, j)`` (see the module docstring) over poses with ``positions`` (N, 3) metres
    and ``quaternions`` (N, 4) ``xyzw`` (needed for ``deg`` / ``rad``). An empty result is
    returned as empty arrays (evo raises)."""
    unit = rpe_unit(unit)
    p = np.asarray(positions, float)
    n = len(p)
    empty = np.zeros(0, np.intp)
    if delta < 0:
        raise ValidationError(f"RPE delta {delta}: expected a positive number")
    if n < 2:
        return empty, empty
    if unit == "frames":
        if float(delta) != int(delta):
            raise ValidationError(f"RPE delta {delta} frames: expected a whole number")
        step = int(delta)
        if step < 1:
            raise ValidationError(f"RPE delta {delta} frames: expected at least 1")
        if all_pairs:
            i = np.arange(max(n - step, 0))
            return i, i + step
        ids = np.arange(0, n, step) if step > 0 else np.zeros(0, np.intp)
        return ids[:-1], ids[1:]
    if unit == "m":
        if not all_pairs:
            steps = np.linalg.norm(p[1:] - p[:-1], axis=1)
            ids = _consecutive(steps, float(delta))
            return ids[:-1], ids[1:]
        return _path_all_pairs(accumulated_distances(p), float(delta), float(delta) * tolerance)
    if unit == "s":
        raise ValidationError("RPE in seconds: use lorisnb.core.metrics.openloris.rpe_pairs (evo has no seconds)")
    if quaternions is None:
        raise ValidationError(f"RPE delta in {unit} needs the orientations")
    q = quat_normalize(quaternions)
    bound = 180.0 if unit == "deg" else np.pi
    if not 0.0 <= delta <= bound:
        raise ValidationError(f"RPE delta angle {delta} {unit}: expected a value in [0, {bound:g}]")
    d_rad = np.deg2rad(delta) if unit == "deg" else float(delta)
    t_rad = np.deg2rad(delta * tolerance) if unit == "deg" else float(delta) * tolerance
    if not all_pairs:
        ids = _consecutive(rotation_angles(q[:-1], q[1:]), d_rad)
        return ids[:-1], ids[1:]
    return _angle_all_pairs(q, d_rad - t_rad, d_rad + t_rad)


def _path_all_pairs(dist: np.ndarray, delta: float, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """For each start i the j > i whose ``dist[j] - dist[i]`` is closest to ``delta`` (the first of
    equals, as ``argmin``), kept within ``tol``; candidates around the crossing only."""
    n = dist.size
    i = np.arange(n - 1)
    k = np.searchsorted(dist, dist[i] + delta, side="left")
    best_j = np.full(i.size, -1, np.intp)
    best_err = np.full(i.size, np.inf)
    for off in (-2, -1, 0, 1):  # four candidates around the crossing
        c = np.clip(k + off, i + 1, n - 1)
        c = np.maximum(np.searchsorted(dist, dist[c], side="left"), i + 1)  # first of equal distances
        err = np.abs((dist[c] - dist[i]) - delta)
        better = (err < best_err) | ((err == best_err) & (c < best_j))
        best_j = np.where(better, c, best_j)
        best_err = np.where(better, err, best_err)
    keep = best_err <= tol
    return i[keep], best_j[keep]


def _angle_all_pairs(q: np.ndarray, lower: float, upper: float) -> tuple[np.ndarray, np.ndarray]:
    """Every (i, j > i) whose direct rotation angle lies in ``[lower, upper]`` radians (quadratic in
    the poses, as evo's search; a block of starts against every pose at a time)."""
    n = len(q)
    out_i: list[np.ndarray] = []
    out_j: list[np.ndarray] = []
    block = max(1, 2**20 // max(n, 1))
    for lo in range(0, n - 1, block):  # blocks of starts, not poses
        hi = min(n - 1, lo + block)
        ang = rotation_angles(q[lo:hi, None, :], q[None, :, :])
        later = np.arange(n)[None, :] > np.arange(lo, hi)[:, None]
        a, b = np.nonzero(later & (lower <= ang) & (ang <= upper))
        out_i.append(a + lo)
        out_j.append(b)
    if not out_i:
        return np.zeros(0, np.intp), np.zeros(0, np.intp)
    return np.concatenate(out_i).astype(np.intp), np.concatenate(out_j).astype(np.intp)


#: The units of TUM's ``evaluate_rpe.py --delta_unit``.
TUM_RPE_UNITS = ("s", "m", "rad", "deg", "f")


def _tum_closest(values: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """TUM's ``find_closest_index`` for every target at once: the same binary search, so a tie
    between two stamps goes to the one the search visits first, as in the tool. ``values``
    increasing; one vector step per halving (about log2 N), not per target."""
    n = values.size
    t = np.asarray(targets, float)
    lo = np.zeros(t.size, np.intp)
    hi = np.full(t.size, n, np.intp)
    best = np.zeros(t.size, np.intp)
    diff = np.abs(values[0] - t)
    active = lo < hi
    while active.any():
        mid = (lo + hi) // 2
        v = values[np.minimum(mid, n - 1)]
        d = np.abs(v - t)
        better = active & (d < diff)
        best[better], diff[better] = mid[better], d[better]
        hit = active & (v == t)
        best[hit] = mid[hit]
        left = active & ~hit & (v > t)
        right = active & ~hit & ~(v > t)
        hi[left], lo[right] = mid[left], mid[right] + 1
        active = right | left
        active &= lo < hi
    return best


def tum_rpe(
    gt_stamps: np.ndarray,
    gt_positions: np.ndarray,
    gt_quaternions: np.ndarray,
    est_stamps: np.ndarray,
    est_positions: np.ndarray,
    est_quaternions: np.ndarray,
    delta: float = 1.0,
    unit: str = "s",
    offset: float = 0.0,
    scale: float = 1.0,
) -> dict[str, np.ndarray]:
    """The relative pose error exactly as TUM's ``evaluate_rpe.py --fixed_delta --max_pairs 0``
    computes it (its ``evaluate_trajectory``), which is not lorisnb's own RPE (:func:`rpe_indices`
    over associated poses, the paper's ``(Q_i^-1 Q_j)^-1 (P_i^-1 P_j)``):

    - pairs over *every* estimate pose (increasing, unique stamps: a TUM file read with the last
      pose of a repeated stamp, as its dict keeps): from each pose i, the pose j whose index value
      (unit ``s``: stamp; ``m``: path length of the estimate; ``rad``/``deg``: summed rotation
      angles of the estimate; ``f``: pose number) is closest to that of i plus ``delta``; a pair
      whose j is the last estimate pose is dropped, and j may equal i;
    - each estimate stamp + ``offset`` (s) takes the closest ground-truth stamp; a pair is skipped
      when either differs by more than twice the median ground-truth step;
    - the error is ``B_s A^-1`` with ``B = P_i^-1 P_j`` (its translation times ``scale``) and
      ``A = Q_i^-1 Q_j``: translation ``|s t_B - R_B R_A^T t_A|`` (m), angle of ``R_B R_A^T``.

    Positions in metres, quaternions ``xyzw``. Returns arrays ``est_i``, ``est_j``, ``gt_i``,
    ``gt_j`` (indices), ``trans`` (m) and ``rot`` (deg); raises ValidationError for an unknown unit
    or fewer than two estimate poses, and, as the tool, when fewer than two pairs remain."""
    if unit not in TUM_RPE_UNITS:
        raise ValidationError(f"TUM RPE unit {unit!r}: expected one of {', '.join(TUM_RPE_UNITS)}")
    tg, te = np.asarray(gt_stamps, float), np.asarray(est_stamps, float)
    if te.size < 2 or tg.size < 2:
        raise ValidationError("TUM's RPE needs at least two estimate and two ground-truth poses")
    r_e = quat_to_matrix(quat_normalize(est_quaternions))
    r_g = quat_to_matrix(quat_normalize(gt_quaternions))
    p_e, p_g = np.asarray(est_positions, float), np.asarray(gt_positions, float)
    n = te.size
    if unit == "s":
        index = te
    elif unit == "m":  # |translation of P_{k+1}^-1 P_k| = |p_k - p_{k+1}|, summed in order as the tool
        index = np.concatenate(([0.0], np.cumsum(np.linalg.norm(p_e[:-1] - p_e[1:], axis=1))))
    elif unit in ("rad", "deg"):
        rel = np.einsum("kji,kjl->kil", r_e[1:], r_e[:-1])  # R_{k+1}^T R_k
        ang = np.arccos(np.clip((np.trace(rel, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0))
        index = np.concatenate(([0.0], np.cumsum(ang * (180.0 / np.pi if unit == "deg" else 1.0))))
    else:
        index = np.arange(n, dtype=float)
    i = np.arange(n)
    j = _tum_closest(index, index + float(delta))
    i, j = i[j != n - 1], j[j != n - 1]
    gi, gj = _tum_closest(tg, te[i] + offset), _tum_closest(tg, te[j] + offset)
    limit = 2.0 * float(np.median(np.diff(tg)))
    ok = (np.abs(tg[gi] - (te[i] + offset)) <= limit) & (np.abs(tg[gj] - (te[j] + offset)) <= limit)
    i, j, gi, gj = i[ok], j[ok], gi[ok], gj[ok]
    if i.size < 2:
        raise ValidationError(
            f"TUM's RPE over {delta:g} {unit}: fewer than two pose pairs match the ground truth (the tool: "
            "'Couldn't find matching timestamp pairs'); is it the right ground truth, delta or offset?"
        )
    r_b = np.einsum("kji,kjl->kil", r_e[i], r_e[j])  # R_Ei^T R_Ej
    t_b = np.einsum("kji,kj->ki", r_e[i], p_e[j] - p_e[i])
    r_a = np.einsum("kji,kjl->kil", r_g[gi], r_g[gj])
    t_a = np.einsum("kji,kj->ki", r_g[gi], p_g[gj] - p_g[gi])
    r_err = np.einsum("kij,klj->kil", r_b, r_a)  # R_B R_A^T
    t_err = scale * t_b - np.einsum("kij,kj->ki", r_err, t_a)
    angle = np.arccos(np.clip((np.trace(r_err, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0))
    return dict(est_i=i, est_j=j, gt_i=gi, gt_j=gj, trans=np.linalg.norm(t_err, axis=1), rot=np.degrees(angle))
