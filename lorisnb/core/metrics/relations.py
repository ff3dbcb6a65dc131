"""Pose relations and error statistics as evo defines them (evo 1.38, ``evo.core.metrics``), on
quaternion arrays, vectorized.

Relations (``evo_ape/evo_rpe -r``): for APE the error pose is ``E = P^-1 Q`` (estimate P, reference
Q; Kümmerle et al.), for RPE ``E = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j)`` (TUM RGB-D). ``trans_part``:
``|t_E|`` metres; ``rot_part``: ``|R_E - I|_F`` (no unit; ``2 sqrt(2) sin(theta / 2)`` for a
rotation by theta); ``full``: ``|E - I|_F`` = ``sqrt(rot_part^2 + trans_part^2)``; ``angle_deg``
and ``angle_rad``: theta; ``point_distance``: for APE the distance of the positions (as
``trans_part``), for RPE ``| |q_j - q_i| - |p_j - p_i| |`` metres. ``point_distance_error_ratio``
(RPE only, as ``evo_rpe -r``; evo_ape has no such relation, so its APE values are none): that
difference in percent of the reference's distance ``|q_j - q_i|``, pairs with a zero reference
distance left out (evo warns "Ignoring N zero divisions").

Units (:func:`change_unit`, evo's ``--change_unit``): a relation in metres can be given in mm, cm,
m or km, one in degrees or radians in the other; the others (``rot_part``, ``full``, the ratio)
have none to change, as evo refuses them.

Statistics (:func:`error_statistics`): rmse, mean, median, std (population, ddof 0), min, max and
sse (sum of squares), evo's ``get_all_statistics``.
"""

from __future__ import annotations

import math

import numpy as np

from lorisnb.core.alignment.geometry import (
    as_quaternions,
    quat_conj_multiply,
    quat_conjugate,
    quat_multiply,
    quat_rotate,
)
from lorisnb.errors import ValidationError

RELATIONS = ("trans_part", "angle_deg", "angle_rad", "rot_part", "full", "point_distance", "point_distance_error_ratio")
#: Unit of each relation's values (evo's).
RELATION_UNITS = {
    "trans_part": "m", "angle_deg": "deg", "angle_rad": "rad", "rot_part": "", "full": "", "point_distance": "m",
    "point_distance_error_ratio": "%",
}  # fmt: skip
#: evo's ``--change_unit`` units: metres per length unit, and the angle units.
LENGTH_UNITS = {"mm": 1e-3, "cm": 1e-2, "m": 1.0, "km": 1e3}
ANGLE_UNITS = ("deg", "rad")
UNITS = (*LENGTH_UNITS, *ANGLE_UNITS)


def unit_refusal(relation: str | None, unit: str) -> str | None:
    """Why ``unit`` cannot be the unit of ``relation``'s values (evo's ``change_unit`` rules), or None."""
    if relation is None:
        return "evo's --change_unit changes the unit of the pose relation's columns: give a relation (--relation)"
    have = RELATION_UNITS[check_relation(relation)]
    if have in ("", "%"):
        return f"relation {relation} has {'no unit' if not have else 'percent'}: evo does not convert it"
    if (have in LENGTH_UNITS) != (unit in LENGTH_UNITS):
        return (
            f"relation {relation} is in {have}: cannot convert it to {unit} (evo: lengths to lengths, angles to angles)"
        )
    return None


def change_unit(values: np.ndarray, relation: str, unit: str | None) -> np.ndarray:
    """``values`` of ``relation`` in ``unit`` (evo's ``Metric.change_unit``; None: unchanged). A
    ValidationError where the unit cannot apply (:func:`unit_refusal`)."""
    if unit is None or unit == RELATION_UNITS[relation]:
        return values
    why = unit_refusal(relation, unit)
    if why is not None:
        raise ValidationError(why)
    have = RELATION_UNITS[relation]
    if have in LENGTH_UNITS:
        return values * (LENGTH_UNITS[have] / LENGTH_UNITS[unit])
    return np.rad2deg(values) if unit == "deg" else np.deg2rad(values)


STATISTICS = ("rmse", "mean", "median", "std", "min", "max", "sse")


def check_relation(relation: str) -> str:
    """``relation`` if it is one of :data:`RELATIONS`, else a ValidationError naming them."""
    if relation not in RELATIONS:
        raise ValidationError(f"pose relation {relation!r}: expected one of {', '.join(RELATIONS)}")
    return relation


def _half_sine(q: np.ndarray) -> np.ndarray:
    """``|sin(theta / 2)|`` of unit quaternions ``xyzw``: the length of their vector part."""
    xyz = q[..., :3]
    return np.sqrt(np.einsum("...i,...i->...", xyz, xyz))


def _angle(q: np.ndarray) -> np.ndarray:
    """Rotation angle of unit quaternions, radians in [0, pi]."""
    return 2.0 * np.arctan2(_half_sine(q), np.abs(q[..., 3]))


def _from_parts(relation: str, trans: np.ndarray, q_err: np.ndarray) -> np.ndarray:
    if relation == "trans_part":
        return trans
    if relation == "angle_rad":
        return _angle(q_err)
    if relation == "angle_deg":
        return np.rad2deg(_angle(q_err))
    rot = 2.0 * math.sqrt(2.0) * _half_sine(q_err)
    if relation == "rot_part":
        return rot
    return np.sqrt(rot * rot + trans * trans)  # full


def ape_relation(
    gt_positions: np.ndarray, gt_quaternions: np.ndarray, est_positions: np.ndarray, est_quaternions: np.ndarray,
    relation: str = "trans_part",
) -> np.ndarray:  # fmt: skip
    """Absolute pose error of each matched pose by ``relation`` (see the module docstring).
    Positions (N, 3) metres; quaternions (N, 4) ``xyzw`` (normalized here)."""
    relation = check_relation(relation)
    if relation == "point_distance_error_ratio":  # evo_rpe's only: no APE value
        return np.zeros(0)
    d = np.asarray(est_positions, float) - np.asarray(gt_positions, float)
    trans = np.sqrt(np.einsum("ij,ij->i", d, d))
    if relation in ("trans_part", "point_distance"):
        return trans
    q_err = quat_conj_multiply(as_quaternions(est_quaternions), as_quaternions(gt_quaternions))
    return _from_parts(relation, trans, q_err)


def rpe_relation(
    gt_positions: np.ndarray, gt_quaternions: np.ndarray, est_positions: np.ndarray, est_quaternions: np.ndarray,
    i: np.ndarray, j: np.ndarray, relation: str = "trans_part",
) -> np.ndarray:  # fmt: skip
    """Relative pose error of pairs (i, j) by ``relation`` (see the module docstring)."""
    relation = check_relation(relation)
    i, j = np.asarray(i, np.intp), np.asarray(j, np.intp)
    pg, pe = np.asarray(gt_positions, float), np.asarray(est_positions, float)
    if relation in ("point_distance", "point_distance_error_ratio"):
        dg, de = pg[j] - pg[i], pe[j] - pe[i]
        ref = np.sqrt(np.einsum("ij,ij->i", dg, dg))
        diff = np.abs(ref - np.sqrt(np.einsum("ij,ij->i", de, de)))
        if relation == "point_distance":
            return diff
        nz = ref != 0
        return diff[nz] / ref[nz] * 100
    qg, qe = as_quaternions(gt_quaternions), as_quaternions(est_quaternions)
    rel_g = quat_conj_multiply(qg[i], qg[j])  # Q_i^-1 Q_j
    rel_e = quat_conj_multiply(qe[i], qe[j])  # P_i^-1 P_j
    t_g = quat_rotate(quat_conjugate(qg[i]), pg[j] - pg[i])
    t_e = quat_rotate(quat_conjugate(qe[i]), pe[j] - pe[i])
    err_t = quat_rotate(quat_conjugate(rel_g), t_e - t_g)  # E = rel_g^-1 rel_e
    trans = np.sqrt(np.einsum("ij,ij->i", err_t, err_t))
    if relation == "trans_part":
        return trans
    return _from_parts(relation, trans, quat_multiply(quat_conjugate(rel_g), rel_e))


def error_statistics(values: np.ndarray, mask: np.ndarray | None = None) -> dict[str, float]:
    """evo's statistics of an error array (of its entries where ``mask`` is true): rmse, mean,
    median, std (ddof 0), min, max, sse; NaN for each when there is no value."""
    v = np.asarray(values, float).reshape(-1)
    if mask is not None:
        v = v[np.asarray(mask, bool).reshape(-1)]
    if v.size == 0:
        return dict.fromkeys(STATISTICS, math.nan)
    n = v.size
    with np.errstate(over="ignore", invalid="ignore"):  # a diverged pose (1e160 m): inf / NaN, no warning
        # numpy's own sums and divisions, as np.mean, np.std (ddof 0) and np.sum compute them (the same
        # numbers to the bit, tested), each sum once: the functions' dispatch was most of the time
        sq = np.power(v, 2)
        sse = float(np.add.reduce(sq))
        mean = float(np.add.reduce(v)) / n
        dev = v - mean
        np.multiply(dev, dev, out=dev)
        return dict(
            rmse=math.sqrt(sse / n), mean=mean, median=median_of(v), std=math.sqrt(float(np.add.reduce(dev)) / n),
            min=float(v.min()), max=float(v.max()), sse=sse,
        )  # fmt: skip


def median_of(v: np.ndarray) -> float:
    """``float(np.median(v))`` of a non-empty float array (M,), to the bit (a NaN in it: NaN; the mean
    of the two middle values for an even M, summed onto 0.0 as ``np.mean`` sums), by the same
    ``np.partition`` call: np.median's dispatch was 60 % of its 28 us on an icra20 sequence, four
    medians a sequence."""
    n = v.size
    h = n // 2
    part = np.partition(v, [h - 1, h, -1] if n % 2 == 0 else [h, -1])  # np.median's own kth (-1: a NaN last)
    if math.isnan(part[-1]):
        return math.nan
    return 0.0 + float(part[h]) if n % 2 else (0.0 + float(part[h - 1]) + float(part[h])) / 2


def masked_statistics(
    values: np.ndarray, mask: np.ndarray, whole: dict[str, float] | None = None
) -> dict[str, np.ndarray]:
    """:func:`error_statistics` (without rmse) of ``values`` (M,) over each row of a boolean
    ``mask`` (..., M) (a threshold grid's correct poses): arrays shaped ``mask.shape[:-1]``, NaN
    where a row selects nothing. Rows are done in chunks of about 2**22 values (bounded memory
    whatever the grid); each row's numbers are the same whatever the chunk. ``whole``:
    :func:`error_statistics` of ``values`` if already computed (a row selecting every value has
    those numbers)."""
    v = np.asarray(values, float)
    m = np.asarray(mask, bool)
    shape = m.shape[:-1]
    rows = m.reshape(math.prod(shape), v.size)  # not reshape(-1, 0): no value (e.g. no RPE pair) is a NaN row
    out = {k: np.full(rows.shape[0], np.nan) for k in ("mean", "median", "std", "min", "max", "sse")}
    full = rows.all(axis=1) if v.size else np.zeros(rows.shape[0], bool)
    if full.any():  # every value selected (no threshold): the same numbers as error_statistics, to the bit (tested)
        whole = whole if whole is not None else error_statistics(v)
        for k, a in out.items():
            a[full] = whole[k]
        if full.all():  # one setting without thresholds (the default): nothing more to compute
            return {k: a.reshape(shape) for k, a in out.items()}
        rows = rows[~full]
    part = {k: np.full(rows.shape[0], np.nan) for k in out}
    step = max(1, (1 << 22) // max(v.size, 1))
    for lo in range(0, rows.shape[0], step):  # chunks of grid rows, not poses
        _masked_rows(v, np.ascontiguousarray(rows[lo : lo + step]), {k: a[lo : lo + step] for k, a in part.items()})
    for k, a in out.items():
        a[~full] = part[k]
    return {k: a.reshape(shape) for k, a in out.items()}


def masked_sum(mask: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The sum of ``x`` (broadcast to ``mask``'s (R, M)) over the entries each row of the boolean
    ``mask`` selects: (R,). Each row is numpy's pairwise sum of its M entries in order (those not
    selected as 0), so a row's sum is the same to the last bit whatever the other rows are (a
    threshold setting alone, in a sweep's grid or a chunk of it), on any BLAS and thread count;
    an entry that is not finite (a diverged pose's square) counts only in the rows selecting it."""
    return np.ascontiguousarray(np.where(mask, x, 0.0)).sum(axis=1)


def _masked_rows(v: np.ndarray, rows: np.ndarray, out: dict[str, np.ndarray]) -> None:
    """The statistics of ``v`` over each row of ``rows`` (R, M), written into ``out``'s (R,) views."""

    def row_sums(x: np.ndarray) -> np.ndarray:
        return masked_sum(rows, x)

    n = rows.sum(axis=1)
    some = n > 0
    if not v.size or not some.any():
        return
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = row_sums(np.broadcast_to(v, rows.shape)) / n
        dev = v[None, :] - mean[:, None]
        out["mean"][some] = mean[some]
        out["std"][some] = np.sqrt(row_sums(dev * dev) / n)[some]
        out["sse"][some] = row_sums(np.broadcast_to(v * v, rows.shape))[some]
        out["min"][some] = np.where(rows, v, np.inf).min(axis=1)[some]
        out["max"][some] = np.where(rows, v, -np.inf).max(axis=1)[some]
        out["median"][some] = _masked_medians(v, rows)[some]


def _masked_medians(v: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """The median of ``v`` over each row of the boolean ``rows`` (R, M), NaN values left out and
    NaN where a row selects none: ``np.nanmedian(np.where(rows, v, nan), axis=1)`` to the bit
    (the middle value, or the mean of the two middle values), without its loop over rows. ``v`` is
    sorted once; in each row the k-th selected value in that order is found from the row's running
    count of selected values."""
    if not v.size:
        return np.full(rows.shape[0], np.nan)
    order = np.argsort(v, kind="stable")
    keep = ~np.isnan(v[order])
    ranked = rows[:, order] & keep  # (R, M): selected values, in increasing order of value
    R, M = ranked.shape
    flat = np.cumsum(ranked.reshape(-1), dtype=np.int64)  # running count over the rows end to end
    ends = flat[M - 1 :: M]
    starts = np.concatenate(([0], ends[:-1]))
    n = ends - starts
    lo_k, hi_k = (n + 1) // 2, n // 2 + 1  # 1-based ranks of the two middle values (equal for odd n)
    first = np.arange(R, dtype=np.int64) * M
    lo = np.minimum(np.searchsorted(flat, starts + np.maximum(lo_k, 1)) - first, M - 1)  # where the count reaches k
    hi = np.minimum(np.searchsorted(flat, starts + np.maximum(hi_k, 1)) - first, M - 1)  # (no value: NaN below)
    vs = v[order]
    with np.errstate(invalid="ignore"):  # -inf and inf in the middle: NaN, as numpy's
        med = np.where(n % 2 == 1, vs[lo], (vs[lo] + vs[hi]) / 2)
    return np.where(n > 0, med, np.nan)
