"""The conventions of the field, selectable: how estimate and ground-truth poses are matched in
time and how the estimate is aligned before errors are taken.

Association:
    ``interpolate`` (OpenLORIS, lorisnb's default): the ground truth interpolated at each estimate
    stamp inside a bracket of ``max_gap`` seconds (:func:`lorisnb.core.alignment.association.associate`).
    ``nearest`` (TUM RGB-D's ``associate.py``, also rpg_trajectory_evaluation's): candidate pairs
    whose stamps differ by less than ``max_diff`` seconds, accepted greedily in order of increasing
    difference, each stamp used at most once. ``t_offset`` (seconds) is added to every estimate
    stamp first (a known clock offset; TUM's ``--offset``).

Alignment (``gt = s R est + t``, fitted on the matched positions):
    ``se3`` (Horn/Umeyama, no scale), ``sim3`` (with scale), ``posyaw`` (4-DoF: translation and a
    rotation about gravity, z; the standard for visual-inertial systems, rpg's ``posyaw``),
    ``none``, ``scale`` (the Sim(3) scale alone, about the origin: evo's ``-s`` without ``-a``),
    ``origin`` (the first matched estimate pose onto the first ground-truth pose: evo's
    ``--align_origin``). ``align_frames=N`` fits on the first N matched poses only (evo's ``n_to_align``,
    rpg's ``align_num_frames``); with N = 1, ``se3`` and ``posyaw`` use the first pose's
    orientation as rpg does.
"""

from __future__ import annotations

import warnings

import numpy as np

from lorisnb.core.alignment.geometry import PositionPairs, Sim3, degenerate_alignment, quat_to_matrix, umeyama
from lorisnb.core.conventions.evo_options import origin_alignment, scale_alignment
from lorisnb.core.spec.evalspec import ASSOCIATIONS, MAX_DIFF, Conventions
from lorisnb.core.spec.validate import choice
from lorisnb.errors import EvaluationError, LorisWarning

#: The alignments :func:`fit_alignment` fits (the spec's ``auto`` is resolved per algorithm first).
ALIGNMENTS = ("se3", "sim3", "posyaw", "none", "scale", "origin")

__all__ = ["ALIGNMENTS", "ASSOCIATIONS", "MAX_DIFF", "Conventions", "associate_nearest", "fit_alignment"]


def associate_nearest(
    gt_stamps: np.ndarray, est_stamps: np.ndarray, max_diff: float = MAX_DIFF
) -> tuple[np.ndarray, np.ndarray]:
    """TUM's ``associate``: pairs ``(gt i, est j)`` with ``|t_gt - t_est| < max_diff``, accepted in
    order of increasing difference (ties: earlier ground-truth, then earlier estimate stamp), each
    stamp used once. Returns the matched indices in increasing estimate order.

    Linear memory, about linear time: in each round, every pair of stamps that are each other's
    best remaining partner (found by ``searchsorted`` among the nearest stamps on either side) is
    accepted; such a pair is the smallest candidate of both its stamps, so the greedy rule accepts
    it too (for a strict order of candidates this gives exactly the greedy matching). Stamps left
    without a candidate within ``max_diff`` are dropped. What the nearest neighbours cannot decide
    (differences that round to equal values on one side, stamps out of order or repeated) goes to
    the exact rule over every candidate (:func:`_greedy_candidates`). Rounds, not poses: a few
    suffice unless differences grow along a long chain of alternating stamps.
    """
    g = np.asarray(gt_stamps, float)
    e = np.asarray(est_stamps, float)
    if g.size == 0 or e.size == 0:
        return np.zeros(0, int), np.zeros(0, int)
    if not (np.all(g[1:] > g[:-1]) and np.all(e[1:] > e[:-1])):  # repeated or unsorted stamps (NaN too)
        return _greedy_candidates(g, e, np.arange(g.size), np.arange(e.size), max_diff)
    # differences below max_diff are exact (Sterbenz) when every stamp is at least max_diff from 0, one sign
    exact = bool(min(g[0], e[0]) >= max_diff or max(g[-1], e[-1]) <= -max_diff)
    gi_left, ej_left = np.arange(g.size), np.arange(e.size)
    g_left, e_left = g, e
    out_g, out_e = [], []
    while gi_left.size and ej_left.size:
        best_of_e = _nearest_best(g_left, e_left, max_diff, exact)
        best_of_g = _nearest_best(e_left, g_left, max_diff, exact)
        j = np.flatnonzero(best_of_e >= 0)
        i = best_of_e[j]
        win = best_of_g[i] == j
        if not win.any():  # only ties of rounded differences remain undecided: the exact rule
            mg, me = _greedy_candidates(g, e, gi_left, ej_left, max_diff)
            out_g.append(mg)
            out_e.append(me)
            break
        out_g.append(gi_left[i[win]])
        out_e.append(ej_left[j[win]])
        keep_e = best_of_e != -1  # stamps with a candidate left (-1: none within max_diff)
        keep_g = best_of_g != -1
        keep_e[j[win]] = False
        keep_g[i[win]] = False
        gi_left, ej_left, g_left, e_left = gi_left[keep_g], ej_left[keep_e], g_left[keep_g], e_left[keep_e]
    partner = np.full(e.size, -1, np.int64)  # in increasing estimate order without a sort
    for mg, me in zip(out_g, out_e, strict=True):
        partner[me] = mg
    me = np.flatnonzero(partner >= 0)
    return partner[me], me


def _nearest_best(a: np.ndarray, b: np.ndarray, max_diff: float, exact: bool) -> np.ndarray:
    """For each stamp of ``b`` (both strictly increasing), the index in ``a`` of its best candidate
    by (difference, stamp): the nearest stamp on the left if its difference is not larger than the
    right one's, else the nearest on the right; -1 if neither is within ``max_diff``, -2 if the
    best is not known: the left stamp's difference ties with the one before it (differences
    rounded to equal values, impossible when ``exact``: every difference below ``max_diff`` is then
    computed without rounding)."""
    n = a.size
    k = np.searchsorted(a, b, side="left")  # a[k - 1] < b <= a[k]; k increasing
    first, last = np.searchsorted(k, [1, n])  # k == 0 before first, k == n from last on
    d_left = b - a.take(k - 1, mode="clip")  # |a - b| as computed (fl(-x) = -fl(x))
    d_left[:first] = np.inf
    d_right = a.take(k, mode="clip") - b
    d_right[last:] = np.inf
    left = d_left <= d_right
    best = k - left
    d_best = np.minimum(d_left, d_right)
    best[~(d_best < max_diff)] = -1
    if not exact:
        d_far = b - a.take(k - 2, mode="clip")
        d_far[: np.searchsorted(k, 2)] = np.inf
        best[left & (d_best < max_diff) & (d_far == d_left)] = -2
    return best


def _greedy_candidates(
    g: np.ndarray, e: np.ndarray, g_idx: np.ndarray, e_idx: np.ndarray, max_diff: float
) -> tuple[np.ndarray, np.ndarray]:
    """The greedy rule over every candidate pair of the stamps ``g[g_idx]`` and ``e[e_idx]``
    (indices increasing): in each round every candidate that is the best remaining one of both its
    stamps is accepted, and candidates touching an accepted stamp are dropped. Returns indices
    into ``g`` and ``e``, in increasing estimate order."""
    gs, es = g[g_idx], e[e_idx]
    lo = np.searchsorted(gs, es - max_diff, side="left")
    hi = np.searchsorted(gs, es + max_diff, side="right")
    count = hi - lo
    ej = np.repeat(np.arange(es.size), count)
    gi = np.repeat(lo, count) + (np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count))
    diff = np.abs(gs[gi] - es[ej])
    ok = diff < max_diff
    gi, ej, diff = gi[ok], ej[ok], diff[ok]
    # a strict order of candidates: difference, then gt stamp, then estimate stamp (TUM sorts tuples)
    rank = np.empty(gi.size, np.int64)
    rank[np.lexsort((es[ej], gs[gi], diff))] = np.arange(gi.size)
    taken_g = np.zeros(gs.size, bool)
    taken_e = np.zeros(es.size, bool)
    out_g, out_e = [], []
    while gi.size:  # rounds, not poses: each round accepts at least the best candidate
        best_g = np.full(gs.size, np.iinfo(np.int64).max)
        best_e = np.full(es.size, np.iinfo(np.int64).max)
        np.minimum.at(best_g, gi, rank)
        np.minimum.at(best_e, ej, rank)
        win = (best_g[gi] == rank) & (best_e[ej] == rank)
        out_g.append(gi[win])
        out_e.append(ej[win])
        taken_g[gi[win]] = True
        taken_e[ej[win]] = True
        keep = ~taken_g[gi] & ~taken_e[ej]
        gi, ej, rank = gi[keep], ej[keep], rank[keep]
    mg = g_idx[np.concatenate(out_g)] if out_g else np.zeros(0, int)
    me = e_idx[np.concatenate(out_e)] if out_e else np.zeros(0, int)
    order = np.argsort(me, kind="stable")
    return mg[order], me[order]


def _best_yaw(c: np.ndarray) -> float:
    """The yaw maximizing ``trace(Rz(theta) C)`` (rpg's ``get_best_yaw``)."""
    return float(np.pi / 2 - np.arctan2(c[0, 0] + c[1, 1], c[0, 1] - c[1, 0]))


def _rot_z(theta: float) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def fit_alignment(
    est_positions: np.ndarray,
    gt_positions: np.ndarray,
    method: str = "se3",
    frames: int | None = None,
    est_quaternions: np.ndarray | None = None,
    gt_quaternions: np.ndarray | None = None,
    strict: bool = True,
    notes: list[str | None] | None = None,
    origin_blocks: tuple[np.ndarray, np.ndarray] | None = None,
    label: str | None = None,
    pairs: PositionPairs | None = None,
) -> Sim3:
    """The alignment ``gt = s R est + t`` of matched poses by ``method`` (see the module
    docstring), fitted on the first ``frames`` matched poses (None: all). Positions in metres;
    quaternions ``xyzw``, needed for ``frames=1`` with ``se3`` or ``posyaw``, and for ``origin``.

    Where no alignment can be determined (fewer than 3 positions, zero spread, all on one line;
    posyaw without horizontal spread) it raises EvaluationError saying what to do; ``strict=False``
    fits se3/sim3 on all poses all the same, as the official OpenLORIS tool does (the pipeline then
    says so: :func:`lorisnb.core.pipeline.plausibility.degenerate_fit`). posyaw on an estimate tilted
    against the ground truth, or an alignment on all of fewer than :data:`FEW_POSES` poses, is
    warned about (appended to ``notes`` when given, else a LorisWarning). ``origin_blocks``: the first
    matched estimate and ground-truth rotation blocks as written, for ``origin`` (evo composes them).
    ``label``: what the poses are (``FILE, seq N``), said first in every note, as the pipeline's
    other warnings say it. ``pairs``: the positions' :class:`~lorisnb.core.alignment.geometry.PositionPairs`
    where the caller made them for its checks (the pipeline's), for :func:`umeyama` (se3, sim3 on all poses)."""
    method = choice("align", method, ALIGNMENTS)
    p_e, p_g = np.asarray(est_positions, float), np.asarray(gt_positions, float)
    if method == "none" or len(p_e) == 0:
        return Sim3.identity()
    if method == "scale":
        return scale_alignment(p_e, p_g, frames)
    if method == "origin":
        if est_quaternions is None or gt_quaternions is None:
            raise EvaluationError("align='origin' needs the orientations")
        return origin_alignment(p_e[0], est_quaternions[0], p_g[0], gt_quaternions[0], *(origin_blocks or (None, None)))
    if frames is None and 3 <= len(p_e) < FEW_POSES:
        _say(
            f"the {method} alignment is fitted on all of only {len(p_e)} matched poses, so it absorbs most of their "
            "error (the ATE is small by construction); evaluate a longer estimate, or align on fewer poses "
            "(--align-frames N) and judge the rest",
            notes,
            label,
        )
    if frames is None and method in ("se3", "sim3"):  # all matched poses: Horn/Umeyama, as the official tool
        return umeyama(p_e, p_g, method == "sim3", strict=strict, pairs=pairs)
    n = len(p_e) if frames is None else min(int(frames), len(p_e))
    if frames is not None and int(frames) > len(p_e):  # evo slices silently, rpg asserts: said, not dropped
        _say(
            f"align_frames={int(frames)} (--align-frames) but only {len(p_e)} poses are matched: the {method} "
            f"alignment is fitted on all {len(p_e)} (rpg_trajectory_evaluation refuses a count above the matched "
            "poses); give --align-frames at most the matched count, or leave it out to align on all",
            notes,
            label,
        )
    if n == 1 and method in ("se3", "posyaw"):
        if est_quaternions is None or gt_quaternions is None:
            raise EvaluationError(f"align={method!r} on one pose needs the orientations")
        r_g = quat_to_matrix(np.asarray(gt_quaternions[0], float))
        r_e = quat_to_matrix(np.asarray(est_quaternions[0], float))
        rot = r_g @ r_e.T if method == "se3" else _rot_z(_best_yaw(r_e @ r_g.T))
        return Sim3(rot, p_g[0] - rot @ p_e[0], 1.0)
    if method == "sim3" and n < 2:
        raise EvaluationError("a Sim(3) alignment needs at least 2 matched poses")
    if method == "posyaw":
        mu_e, mu_g = p_e[:n].mean(axis=0), p_g[:n].mean(axis=0)
        c = (p_e[:n] - mu_e).T @ (p_g[:n] - mu_g)
        if not np.hypot(c[0, 0] + c[1, 1], c[0, 1] - c[1, 0]) > np.finfo(float).eps * max(1.0, np.abs(c).max()):
            raise EvaluationError(
                f"no posyaw alignment can be determined: the {n} matched positions have no horizontal spread "
                "(all on one vertical line or one point), so the yaw is arbitrary; align on more poses, on the "
                "first pose's orientation (--align-frames 1), or not at all (--align none)"
            )
        rot = _rot_z(_best_yaw(c))
        _say(_tilt_note(p_e[:n], p_g[:n], Sim3(rot, mu_g - rot @ mu_e, 1.0)), notes, label)
        return Sim3(rot, mu_g - rot @ mu_e, 1.0)
    return umeyama(p_e[:n], p_g[:n], method == "sim3", strict=True)


#: An alignment on all matched poses, fewer than this, is said to absorb their error.
FEW_POSES = 10
#: posyaw is questioned when the best full rotation between the positions tilts z by more than
#: this (degrees) and fits them at least this much better (ATE RMSE ratio).
TILT_DEGREES = 10.0
TILT_GAIN = 0.5


def _say(note: str | None, notes: list[str | None] | None, label: str | None = None) -> None:
    if note is None:
        return
    if label:
        note = f"{label}: {note}"
    if notes is not None:
        notes.append(note)
    else:
        warnings.warn(note, LorisWarning, stacklevel=3)


def _tilt_note(p_e: np.ndarray, p_g: np.ndarray, posyaw: Sim3) -> str | None:
    """The positions say the two world frames differ in roll/pitch: posyaw (a rotation about
    gravity only) then leaves a tilt in every error."""
    if degenerate_alignment(p_e, p_g) is not None:
        return None
    se3 = umeyama(p_e, p_g)
    tilt = float(np.degrees(np.arccos(np.clip(se3.rotation[2, 2], -1.0, 1.0))))
    rmse_yaw = float(np.sqrt(np.mean(np.sum((posyaw.apply(p_e) - p_g) ** 2, axis=1))))
    rmse_se3 = float(np.sqrt(np.mean(np.sum((se3.apply(p_e) - p_g) ** 2, axis=1))))
    if tilt > TILT_DEGREES and rmse_se3 < TILT_GAIN * rmse_yaw:
        return (
            f"align='posyaw' assumes both trajectories have z along gravity, but the best full rotation between "
            f"them tilts z by {tilt:.1f} deg (roll/pitch) and fits with ATE RMSE {rmse_se3:.3f} m against "
            f"{rmse_yaw:.3f} m for posyaw: is the estimate gravity-aligned (a visual-only system?)? "
            "Use --align se3 (or sim3)."
        )
    return None
