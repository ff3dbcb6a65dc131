"""rpg_trajectory_evaluation's relative error: over sub-trajectories of given lengths (metres
travelled along the ground truth, by default 10, 20, 30, 40 and 50 % of the total length), the
error of the estimate's relative motion, reported per metre travelled as rpg reports it
(translation in % of the length, rotation in degrees per metre).

The lengths (:func:`rpg_preset_lengths`) are fractions of the path length of the *whole* ground
truth as read (rpg's ``traj_length``, before association), truncated to centimetres, unless preset
distances are given (rpg's ``preset_boxplot_distances``); distances along the path are measured on
the matched ground truth.

For each start pose i, the end pose is the first j >= i whose distance from the start is closest
to ``d_i + L``, within ``0.2 L``. Like rpg, the pairs are then numbered in order of the starts that
found an end (rpg's ``compute_relative_error`` pairs the k-th found end with the k-th pose); the
two agree whenever the ends missing are all at the end of the trajectory, as they are unless the
ground truth jumps by more than 0.2 L. The rotation angle is ``arccos((trace R - 1) / 2)`` as rpg
computes it. The error is also split as rpg splits it (``rel_yaw``, ``rel_gravity``): the error
rotation expressed in the world frame, ``R_w = R_est,j R_E R_est,j^T``, as z-y-x Euler angles
(``euler_from_matrix(R_w, 'rzyx')``): ``yaw`` the absolute yaw, ``gravity`` the root of the
squared pitch and roll (the part gravity makes observable to a visual-inertial system), degrees.
rpg computes its relative errors on the estimate as read, not aligned (``Trajectory`` passes
``p_es, q_es``), so ``R_est,j`` is the estimate's own orientation and its world frame the
estimate's: :func:`relative_table` turns the aligned orientation back by the alignment's rotation
(``world_rotation``) where the errors keep it (a file of one sequence, or a lifelong file's one
alignment). Only the split depends on it (the length, translation and angle of the error do not).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from lorisnb.core.alignment.geometry import quat_conjugate, quat_multiply, quat_normalize, quat_rotate, quat_to_matrix
from lorisnb.core.lifelong.scoring import as_files
from lorisnb.core.pipeline.model import FileErrors, check_label
from lorisnb.core.spec import validate
from lorisnb.errors import LorisWarning, ValidationError

if TYPE_CHECKING:
    import pandas as pd

#: rpg's default sub-trajectory lengths, fractions of the total length
RPG_FRACTIONS = (0.1, 0.2, 0.3, 0.4, 0.5)


def distances(positions: np.ndarray) -> np.ndarray:
    """Distance travelled from the first position to each, metres."""
    steps = np.linalg.norm(np.diff(np.asarray(positions, float), axis=0), axis=1)
    return np.concatenate(([0.0], np.cumsum(steps)))


def rpg_preset_lengths(total: float, fractions: tuple[float, ...] = RPG_FRACTIONS) -> list[float]:
    """rpg's sub-trajectory lengths of a ground truth ``total`` metres long: each fraction of it,
    truncated to centimetres (rpg's ``compute_boxplot_distances``)."""
    return [math.trunc(f * float(total) * 100.0) / 100.0 for f in fractions]


def rpg_lengths(gt_positions: np.ndarray, fractions: tuple[float, ...] = RPG_FRACTIONS) -> list[float]:
    """:func:`rpg_preset_lengths` of the path length of ``gt_positions`` (pass the whole ground
    truth, as rpg does, for rpg's lengths)."""
    return rpg_preset_lengths(float(distances(gt_positions)[-1]) if len(gt_positions) else 0.0, fractions)


def rpg_pairs(dist: np.ndarray, length: float, max_dist_diff: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Start and end indices of the sub-trajectories of ``length`` metres (see the module docstring)."""
    if max_dist_diff is None:
        max_dist_diff = 0.2 * length
    n = dist.size
    target = dist + length
    k = np.searchsorted(dist, target, side="left")  # first with distance >= target
    before = np.clip(k - 1, 0, n - 1)
    before = np.searchsorted(dist, dist[before], side="left")  # earliest of equal distances
    before = np.maximum(before, np.arange(n))
    after = np.minimum(k, n - 1)
    err_b = np.abs(dist[before] - target)
    err_a = np.abs(dist[after] - target)
    best = np.where(err_b <= err_a, before, after)
    err = np.minimum(err_b, err_a)
    found = best[err < max_dist_diff]
    return np.arange(found.size), found


def rpg_relative_errors(
    gt_positions: np.ndarray,
    gt_quaternions: np.ndarray,
    est_positions: np.ndarray,
    est_quaternions: np.ndarray,
    lengths: list[float] | None = None,
    scale: float = 1.0,
    world_rotation: np.ndarray | None = None,
) -> pd.DataFrame:
    """rpg's relative errors of matched poses for each sub-trajectory length (metres; default
    :func:`rpg_lengths`), the estimate's relative translations multiplied by ``scale`` (the Sim(3)
    scale, as rpg does). One row per pair: ``length``, ``trans`` (m), ``trans_perc`` (% of the
    length), ``rot`` (deg), ``rot_deg_per_m``, ``yaw`` and ``gravity`` (deg). ``world_rotation``: the
    (3, 3) rotation the estimate's orientations were turned by (an alignment's), undone for the
    yaw / gravity split as rpg splits in the estimate's own frame (module docstring)."""
    import pandas as pd

    p_g, p_e = np.asarray(gt_positions, float), np.asarray(est_positions, float)
    q_g = quat_normalize(gt_quaternions)
    q_e = quat_normalize(est_quaternions)
    dist = distances(p_g)
    rows = []
    for length in rpg_lengths(p_g) if lengths is None else lengths:  # a handful of lengths
        i, j = rpg_pairs(dist, float(length))
        if i.size < 2:  # rpg: "Too few samples! Will not compute."
            continue
        inv_e, inv_g = quat_conjugate(q_e[i]), quat_conjugate(q_g[i])
        rel_e_t = scale * quat_rotate(inv_e, p_e[j] - p_e[i])
        rel_g_t = quat_rotate(inv_g, p_g[j] - p_g[i])
        rel_g_q = quat_multiply(inv_g, q_g[j])
        inv_rel_g = quat_conjugate(rel_g_q)
        err_t = quat_rotate(inv_rel_g, rel_e_t - rel_g_t)
        err_q = quat_multiply(inv_rel_g, quat_multiply(inv_e, q_e[j]))
        r_err = quat_to_matrix(err_q)
        trace = r_err.trace(axis1=1, axis2=2)
        rot = np.degrees(np.arccos(np.clip((trace - 1.0) / 2.0, -1.0, 1.0)))
        r_j = quat_to_matrix(q_e[j])
        if world_rotation is not None:  # the estimate's orientation as read: R_a^T R_j
            r_j = np.einsum("ki,nkj->nij", np.asarray(world_rotation, float), r_j)
        yaw, gravity = _yaw_gravity(np.einsum("nij,njk,nlk->nil", r_j, r_err, r_j))
        trans = np.linalg.norm(err_t, axis=1)
        rows.append(
            pd.DataFrame(
                dict(
                    length=float(length),
                    trans=trans,
                    trans_perc=trans / length * 100,
                    rot=rot,
                    rot_deg_per_m=rot / length,
                    yaw=yaw,
                    gravity=gravity,
                )
            )  # fmt: skip
        )
    cols = ["length", "trans", "trans_perc", "rot", "rot_deg_per_m", "yaw", "gravity"]
    return pd.concat(rows, ignore_index=True) if rows else pd.DataFrame(columns=cols)


def rpg_scale_errors(gt_positions: np.ndarray, est_positions: np.ndarray) -> np.ndarray:
    """rpg's scale error of each aligned pose (its ``compute_absolute_error``'s ``e_scale_perc``),
    percent: ``|(|p_est| / |p_gt|) - 1| x 100``. rpg means the ratio of distances travelled, but its
    ``np.diff(p, 0)`` is a difference of order 0, the positions themselves, so the ratio is that of the
    positions' distances from the world origin; reproduced as rpg computes it (a ground-truth position
    at the origin gives inf or NaN, as in rpg)."""
    g = np.sqrt(np.einsum("ij,ij->i", gt_positions, gt_positions))
    e = np.sqrt(np.einsum("ij,ij->i", est_positions, est_positions))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.abs((e / g - 1.0) * 100)


def rpg_absolute_table(errors: FileErrors | Iterable[FileErrors]) -> pd.DataFrame:
    """rpg's absolute errors of every sequence on the aligned poses: ``trans_rmse`` (m), ``rot_rmse``
    (deg) and its scale error (:func:`rpg_scale_errors`, percent): ``scale_perc_rmse``,
    ``scale_perc_mean``, ``scale_perc_median``."""
    import pandas as pd

    from lorisnb.core.metrics.relations import error_statistics

    rows = []
    for f in as_files(errors):
        for e in f.sequences:
            scale = error_statistics(rpg_scale_errors(e.gt_positions, e.est_positions))
            rows.append(dict(algorithm=f.algorithm, file=f.file, trial=f.trial, seq=e.seq, matched=e.matched,
                             trans_rmse=error_statistics(e.ate)["rmse"], rot_rmse=error_statistics(e.aoe)["rmse"],
                             scale_perc_rmse=scale["rmse"], scale_perc_mean=scale["mean"],
                             scale_perc_median=scale["median"]))  # fmt: skip
    cols = ["algorithm", "file", "trial", "seq", "matched", "trans_rmse", "rot_rmse", "scale_perc_rmse",
            "scale_perc_mean", "scale_perc_median"]  # fmt: skip
    return pd.DataFrame(rows, columns=cols)


def _alignment_rotation(f: FileErrors) -> np.ndarray | None:
    """The rotation of the alignment applied to every sequence of ``f`` (its one sequence's, or a
    lifelong file's), None where each sequence had its own (not kept: the aligned frame is used)."""
    if f.mode == "lifelong" or len(f.sequences) == 1:
        return np.asarray(f.alignment.rotation, float)
    return None


def _yaw_gravity(r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """rpg's split of (N, 3, 3) world-frame error rotations: ``|yaw|`` and ``sqrt(pitch^2 + roll^2)``,
    degrees, of ``euler_from_matrix(R, 'rzyx')`` (transformations.py; its branch for a pitch of
    +-90 deg, where yaw and roll are not separable, included)."""
    cy = np.hypot(r[:, 0, 0], r[:, 1, 0])
    regular = cy > np.finfo(float).eps * 4.0
    yaw = np.where(regular, np.arctan2(r[:, 1, 0], r[:, 0, 0]), 0.0)
    pitch = np.arctan2(-r[:, 2, 0], cy)
    roll = np.where(regular, np.arctan2(r[:, 2, 1], r[:, 2, 2]), np.arctan2(-r[:, 1, 2], r[:, 1, 1]))
    return np.degrees(np.abs(yaw)), np.degrees(np.sqrt(pitch**2 + roll**2))


def _positive_list(name: str, values: Any, most: float = math.inf) -> tuple[float, ...]:
    """A non-empty list of positive numbers (at most ``most``): ``fractions=2`` or ``lengths=[-1]``
    gave an empty table, ``fractions=0.1`` a TypeError."""
    if isinstance(values, str):  # a list only (the command line splits its own text)
        raise ValidationError(f"{name}={values!r}: expected a non-empty list of positive numbers")
    return validate.positive_list(name, values, "", most)


def relative_table(
    errors: FileErrors | Iterable[FileErrors],
    fractions: tuple[float, ...] = RPG_FRACTIONS,
    lengths: Sequence[float] | None = None,
) -> pd.DataFrame:
    """rpg's relative error of every sequence, per sub-trajectory length: samples, mean and RMSE of
    the translation error in % of the length, mean rotation error in degrees per metre. Computed on
    the aligned poses (a rigid alignment leaves relative motion unchanged, and a Sim(3)
    alignment's scale is rpg's ``scale``).

    Lengths: ``lengths`` (metres, rpg's preset distances; ``fraction`` is then NaN), else
    ``fractions`` of the whole ground truth's path length where the errors know it
    (``FileErrors.groundtruth_lengths``, as rpg), else of the matched ground truth's."""
    import pandas as pd

    fractions = _positive_list("fractions", fractions, most=1.0)
    lengths = None if lengths is None else _positive_list("lengths", lengths)
    rows = []
    missed: list[str] = []  # what rpg would not compute, said (rpg prints "Too few samples! Will not compute.")
    for f in as_files(errors):  # per file, sequence and length, never per pose
        for e in f.sequences:
            if e.matched < 2 or e.gt_quaternions is None or e.est_quaternions is None:
                why = "no orientation" if e.matched >= 2 else f"{e.matched} matched pose(s)"
                missed.append(f"{check_label(f.path, f.file)}, seq {e.seq} ({why})")
                continue
            if lengths is not None:
                use = [float(x) for x in lengths]
                fraction_of = dict.fromkeys(use, math.nan)
            else:
                total = f.groundtruth_lengths.get(e.seq)
                use = rpg_lengths(e.gt_positions, fractions) if total is None else rpg_preset_lengths(total, fractions)
                fraction_of = dict(zip(use, fractions, strict=True))
            rel = rpg_relative_errors(e.gt_positions, e.gt_quaternions, e.est_positions, e.est_quaternions,
                                      [x for x in use if x > 0], world_rotation=_alignment_rotation(f))  # fmt: skip
            done = set(rel["length"].tolist())
            short = [x for x in dict.fromkeys(use) if x not in done]
            if short:  # fewer than 2 sub-trajectories (or a length truncated to 0 cm of a path under 10 cm)
                missed.append(f"{check_label(f.path, f.file)}, seq {e.seq} at {', '.join(f'{x:g}' for x in short)} m")
            for length, g in rel.groupby("length", sort=False):
                rows.append(
                    dict(
                        algorithm=f.algorithm,
                        file=f.file,
                        suite=f.suite,
                        scene=f.scene,
                        trial=f.trial,
                        seq=e.seq,
                        fraction=fraction_of[float(length)],
                        length=length,
                        samples=len(g),
                        trans_perc_mean=g["trans_perc"].mean(),
                        trans_perc_rmse=float(np.sqrt(np.mean(g["trans_perc"] ** 2))),
                        rot_deg_per_m_mean=g["rot_deg_per_m"].mean(),
                        yaw_mean=g["yaw"].mean(),
                        gravity_mean=g["gravity"].mean(),
                    )  # fmt: skip
                )
    if missed:
        named = "; ".join(missed[:MISSED_NAMED]) + (
            f"; and {len(missed) - MISSED_NAMED:,} more" if len(missed) > MISSED_NAMED else ""
        )
        warnings.warn(f"rpg's relative error is not computed (no row) where a sub-trajectory length has fewer than 2 "
                      f"sub-trajectories, as rpg says 'Too few samples! Will not compute.': {named}",
                      LorisWarning, stacklevel=2)  # fmt: skip
    cols = ["algorithm", "file", "suite", "scene", "trial", "seq", "fraction", "length", "samples", "trans_perc_mean",
            "trans_perc_rmse", "rot_deg_per_m_mean", "yaw_mean", "gravity_mean"]  # fmt: skip
    return pd.DataFrame(rows, columns=cols)


#: Sequences (and their lengths) named in :func:`relative_table`'s note of lengths not computed.
MISSED_NAMED = 10
