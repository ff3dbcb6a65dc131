"""Scoring: every threshold-dependent metric of the paper, from per-pose errors.

One implementation: :func:`sequence_grid` scores a sequence over a grid of eps x phi x delta x tau
(Eq. 1-4 of the paper, C-ATE, C-AOE and C-RPE); :func:`score` is that kernel on a one-point grid,
and :func:`lorisnb.core.lifelong.sweep.sweep` is the same kernel on a larger grid. Units: metres, degrees,
seconds.
"""

from __future__ import annotations

from collections.abc import Iterable
from functools import partial
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from lorisnb.core.metrics import openloris as metrics
from lorisnb.core.metrics.relations import error_statistics, masked_statistics, masked_sum
from lorisnb.core.pipeline.model import (
    EXTRA_COLUMNS,
    POSE_COLUMNS,
    SEQUENCE_COLUMNS,
    STAT_COLUMNS,
    Eps,
    FileErrors,
    SequenceErrors,
    sequence_eps,
)
from lorisnb.core.spec.evo import check_evo, check_evo_together, tolerance_refusal
from lorisnb.core.spec.validate import eps_value, flag, known_keys, threshold
from lorisnb.core.trajectory.blocks import each
from lorisnb.errors import ValidationError

if TYPE_CHECKING:
    import pandas as pd

#: Metrics computed by :func:`sequence_grid`, with their dtype in tables.
GRID_METRICS: dict[str, type] = {
    "ate_rmse": float, "aoe_rmse": float, "c_ate_rmse": float, "c_aoe_rmse": float, "c_matched": int,
    "correct_time": float, "cr": float, "cr_t": float, "reloc_time": float, "cs_r": float, "t0": float,
    "track_time": float, "first_correct": bool, "rpe_trans_rmse": float, "rpe_rot_rmse": float,
    "c_rpe_trans_rmse": float, "c_rpe_rot_rmse": float, "rpe_pairs": int, "c_rpe_pairs": int,
}  # fmt: skip
GRID_METRICS.update(dict.fromkeys(STAT_COLUMNS, float))
RPE_METRICS = ("rpe_trans_rmse", "rpe_rot_rmse", "c_rpe_trans_rmse", "c_rpe_rot_rmse", "rpe_pairs", "c_rpe_pairs")


def as_files(errors: FileErrors | Iterable[FileErrors]) -> list[FileErrors]:
    """One FileErrors or several, as a list; anything else is an error that says what is expected."""
    files = [errors] if isinstance(errors, FileErrors) else None
    if files is None:
        if isinstance(errors, (str, bytes)) or not isinstance(errors, Iterable):
            raise ValidationError(
                f"expected evaluated errors (FileErrors, or lorisnb.evaluate(...).errors), got {type(errors).__name__}"
                " (to score a file, evaluate it first: lorisnb.evaluate(path).sequences(...))"
            )
        files = list(errors)
        bad = [type(f).__name__ for f in files if not isinstance(f, FileErrors)]
        if bad:
            raise ValidationError(f"expected FileErrors items, got {bad[0]}")
    return files


def sequence_meta(f: FileErrors, e: SequenceErrors) -> dict[str, Any]:
    """The threshold-free columns of a sequence's row."""
    return dict(
        algorithm=f.algorithm, file=f.file, scene=f.scene, seq=e.seq, frame=f.frame, poses=e.poses,
        matched=e.matched, suite=f.suite, mode=f.mode, aligned_on=f.aligned_on, scale=e.scale,
        gt_start=e.gt_start, gt_end=e.gt_end, gt_duration=e.gt_end - e.gt_start,
        official_interpolation=f.official_interpolation, trial=f.trial, rotation_lever=e.rotation_lever,
    )  # fmt: skip


#: Grid rows, poses and value columns of each matrix product of :func:`row_sums`: every product
#: has this shape (zeros padded; a sequence's last poses a shorter block, the same for every grid),
#: so each row is summed by the same kernel in the same order. Small, so that one setting's products
#: cost a few multiply-adds per pose and a few MB, not the grid's work.
ROW_BLOCK, POSE_BLOCK, COLUMN_BLOCK = 8, 1 << 14, 8


def row_sums(selected: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Sums of each column of ``values`` (M, k) over the entries each row of ``selected`` (R, M;
    boolean, or 0 and 1) selects: (R, k), by BLAS's matrix product on blocks of exactly
    :data:`ROW_BLOCK` rows, :data:`POSE_BLOCK` poses (the last block of a sequence shorter) and a
    multiple of :data:`COLUMN_BLOCK` columns (zeros padded), each row's block sums added in pose
    order. Every row is then summed by the same kernels in the same order, whatever the grid it
    belongs to: a threshold setting alone (:func:`score`) equals its point in any sweep to the last
    bit, a larger threshold never gives a smaller sum, and BLAS's threads (which split rows and
    columns, never the sum over poses) change nothing. (Products of other shapes summed a one-row
    grid in another order than a large one: sweeps and scores differed in the last digits.)"""
    sel = np.asarray(selected)  # booleans are cast into each block: no float copy of the whole grid
    R, M = sel.shape
    vals = np.asarray(values, float).reshape(M, -1)
    k = vals.shape[1]
    cols = -(-max(k, 1) // COLUMN_BLOCK) * COLUMN_BLOCK
    out = np.zeros((R, k))
    width = min(POSE_BLOCK, M)
    padded, block = np.zeros((width, cols)), np.zeros((ROW_BLOCK, width))  # reused: one allocation
    for p0 in range(0, M, POSE_BLOCK):  # blocks of poses and of grid rows: each holds many
        m = min(POSE_BLOCK, M - p0)
        if m < width:  # a sequence's last, shorter block of poses: arrays of its own shape
            padded, block = np.zeros((m, cols)), np.zeros((ROW_BLOCK, m))
        padded[:, :k] = vals[p0 : p0 + m]
        for lo in range(0, R, ROW_BLOCK):
            n = min(ROW_BLOCK, R - lo)
            if n < ROW_BLOCK:
                block[n:] = 0.0
            block[:n] = sel[lo : lo + n, p0 : p0 + m] > 0
            out[lo : lo + n] += (block @ padded)[:n, :k]
    return out


def selected_squares(selected: np.ndarray, *values: np.ndarray) -> np.ndarray:
    """Sums of ``v**2`` over the entries each row of ``selected`` (R, M; 0 or 1) selects, for each
    of ``values`` ((M,) each): (R, len(values)), by :func:`row_sums`, except that a value whose
    square is not finite (an ATE past 1e154 m: a diverged pose) counts only in the rows that
    select it: in a product its 0 weight would make every row NaN (0 * inf)."""
    with np.errstate(over="ignore", invalid="ignore"):
        sq = np.column_stack([np.asarray(v, float) ** 2 for v in values])
    bad = ~np.isfinite(sq)
    if not bad.any():
        return row_sums(selected, sq)
    total = row_sums(selected, np.where(bad, 0.0, sq))
    with np.errstate(invalid="ignore"):
        for k in range(sq.shape[1]):
            rows = bad[:, k]
            total[:, k] += masked_sum(np.asarray(selected)[:, rows] > 0, sq[rows, k])
    return total


def sequence_grid(
    e: SequenceErrors,
    eps: ArrayLike,
    phi: ArrayLike,
    delta: ArrayLike,
    tau: ArrayLike,
    *,
    rpe_delta: float = 1.0,
    rpe_unit: str = "s",
    with_rpe: bool = True,
    with_stats: bool = False,
    rpe_pairs: str = "reference",
    rpe_all_pairs: bool | None = None,
    rpe_tolerance: float = 0.1,
) -> dict[str, np.ndarray]:
    """Every metric of one sequence over a grid, as arrays of shape (E, P, D, T).

    Args:
        e: per-pose errors of the sequence.
        eps: (E,) ATE thresholds in metres (already resolved for this sequence's scene).
        phi: (P,) AOE thresholds, degrees. delta: (D,) validity windows, seconds (Eq. 2).
        tau: (T,) re-localization time factors, seconds (Eq. 4).
        rpe_delta, rpe_unit, rpe_pairs, rpe_all_pairs, rpe_tolerance: the RPE pairs (see
            :func:`lorisnb.core.metrics.pairs.rpe_indices`).
        with_rpe: also the RPE columns (their pairs are computed once per sequence and kept).
        with_stats: also :data:`~lorisnb.core.pipeline.model.STAT_COLUMNS` (needs ``with_rpe``): evo's
            statistics of ATE, AOE and RPE, and of the same over correct poses (pairs) only.

    A sequence with no matched pose has CR = CR-T = CS-R = 0, no ATE (NaN), 0 correct poses and
    an infinite re-localization time. One with no RPE pair (shorter than the RPE step) has 0 pairs
    and NaN RPE statistics, its other metrics as usual (the evaluation warns, naming it).
    """
    eps_a, phi_a, delta_a, tau_a = (np.asarray(v, float).reshape(-1) for v in (eps, phi, delta, tau))
    shape = (len(eps_a), len(phi_a), len(delta_a), len(tau_a))
    E, P, D, T = shape

    one = shape == (1, 1, 1, 1)  # one setting (score): each metric one value

    def bc(a: Any) -> np.ndarray:  # for one setting a reshape, a third of a broadcast view's cost:
        # score over the icra20 tree 0.38-0.67 -> 0.33-0.46 s of CPU (side by side, 2 shared cores);
        # the array's own method: np.reshape's dispatch took 1.7 us of a float's 2 (69 a sequence)
        return np.asarray(a).reshape(shape) if one else np.broadcast_to(a, shape)

    nan, zero = bc(np.nan), bc(0.0)
    if e.matched == 0:
        out = dict(
            ate_rmse=nan, aoe_rmse=nan, c_ate_rmse=nan, c_aoe_rmse=nan, c_matched=zero, correct_time=zero, cr=zero,
            cr_t=zero, reloc_time=bc(np.inf), cs_r=zero, t0=nan, track_time=zero, first_correct=bc(False),
        )  # fmt: skip
        if with_rpe:
            out.update(dict.fromkeys(RPE_METRICS[:4], nan), rpe_pairs=zero, c_rpe_pairs=zero)
        if with_stats:
            out.update(dict.fromkeys(STAT_COLUMNS, nan))
        return out
    # correctness of every pose at every (eps, phi), Eq. (1): (E, P, M)
    c = (e.ate[None, None, :] <= eps_a[:, None, None]) & (e.aoe[None, None, :] <= phi_a[None, :, None])
    cf = c.reshape(E * P, -1)
    held = np.minimum(metrics.valid_intervals(e.stamps, e.gt_end, e.gt_start)[None, :], delta_a[:, None])  # (D, M)
    ct = row_sums(cf, held.T).reshape(E, P, D)  # correct time, numerator of Eq. (2) and (3)
    n_c = cf.sum(axis=1).reshape(E, P).astype(float)
    sums = selected_squares(cf, e.ate, e.aoe)
    with np.errstate(invalid="ignore", divide="ignore"):
        c_ate = np.where(n_c > 0, np.sqrt(sums[:, 0].reshape(E, P) / n_c), np.nan)
        c_aoe = np.where(n_c > 0, np.sqrt(sums[:, 1].reshape(E, P) / n_c), np.nan)
    t0 = float(e.stamps[0])
    track = e.gt_end - max(t0, e.gt_start)  # tracked time inside the span, as the correct time
    rt = metrics.relocalization_time(t0, e.gt_start)
    first = c[:, :, 0]
    csr = metrics.relocalization_score(t0, e.gt_start, first[:, :, None], tau_a[None, None, :])  # Eq. (4), (E, P, T)
    out = dict(
        ate_rmse=bc(float(metrics.rmse(e.ate))), aoe_rmse=bc(float(metrics.rmse(e.aoe))),
        c_ate_rmse=bc(c_ate[:, :, None, None]), c_aoe_rmse=bc(c_aoe[:, :, None, None]),
        c_matched=bc(n_c[:, :, None, None]), correct_time=bc(ct[:, :, :, None]),
        cr=bc(metrics.correct_rate(ct, e.gt_start, e.gt_end)[:, :, :, None]),
        cr_t=bc(metrics.correct_rate_tracking(ct, max(t0, e.gt_start), e.gt_end)[:, :, :, None]),
        reloc_time=bc(rt), cs_r=bc(csr[:, :, None, :]), t0=bc(t0), track_time=bc(track),
        first_correct=bc(first[:, :, None, None]),
    )  # fmt: skip
    if not with_rpe:
        return out
    # RPE: pairs fixed per sequence; C-RPE over the pairs whose two poses are correct
    i, j, tr, rr = e.rpe(rpe_delta, rpe_unit, rpe_pairs, rpe_all_pairs, rpe_tolerance)
    pairs_c = c[:, :, i] & c[:, :, j]  # (E, P, pairs): the pairs whose two poses are correct
    if with_stats:
        out.update(_statistics(e, c, tr, rr, pairs_c, bc))
    if len(i) == 0:
        out.update(dict.fromkeys(RPE_METRICS[:4], nan), rpe_pairs=zero, c_rpe_pairs=zero)
        return out
    both = pairs_c.reshape(E * P, -1)
    nb = both.sum(axis=1).reshape(E, P).astype(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        sums = selected_squares(both, tr, rr)
        ctr = np.where(nb > 0, np.sqrt(sums[:, 0].reshape(E, P) / nb), np.nan)
        crr = np.where(nb > 0, np.sqrt(sums[:, 1].reshape(E, P) / nb), np.nan)
    out.update(
        rpe_trans_rmse=bc(float(metrics.rmse(tr))), rpe_rot_rmse=bc(float(metrics.rmse(rr))),
        c_rpe_trans_rmse=bc(ctr[:, :, None, None]), c_rpe_rot_rmse=bc(crr[:, :, None, None]),
        rpe_pairs=bc(float(len(i))), c_rpe_pairs=bc(nb[:, :, None, None]),
    )  # fmt: skip
    return out


def _statistics(
    e: SequenceErrors, c: np.ndarray, tr: np.ndarray, rr: np.ndarray, pairs_c: np.ndarray, bc: Any
) -> dict[str, np.ndarray]:
    """:data:`~lorisnb.core.pipeline.model.STAT_COLUMNS` of a sequence with matched poses, given
    the correctness of its poses ``c`` (E, P, M), its RPE errors and the correctness of their
    pairs (E, P, pairs), each shaped by ``bc`` (:func:`sequence_grid`'s)."""
    out: dict[str, np.ndarray] = {}
    named = {"ate": (e.ate, c), "aoe": (e.aoe, c), "rpe_trans": (tr, pairs_c), "rpe_rot": (rr, pairs_c)}
    # the whole arrays' statistics side by side (a median each); the masked ones after, in order
    whole = dict(
        zip(named, each(*(partial(error_statistics, v) for v, _ in named.values()), rows=e.matched), strict=True)
    )
    for name, stats in whole.items():
        out.update({f"{name}_{k}": bc(v) for k, v in stats.items() if k != "rmse"})
    for name, (values, m) in named.items():
        ms = masked_statistics(values, m, whole[name])
        out.update({f"c_{name}_{k}": bc(v[:, :, None, None]) for k, v in ms.items()})
    return out


def rpe_setting(rpe_delta: Any, rpe_unit: Any) -> tuple[float, str]:
    """Validated RPE step by the spec's own rules (:func:`lorisnb.core.spec.evo.check_evo`): a
    positive delta in ``s`` (seconds), ``f`` or ``frames`` (whole), ``m`` (metres), ``deg``/``d`` or
    ``rad``/``r`` (rotation, at most half a turn)."""
    unit = check_evo("rpe_unit", rpe_unit, "rpe_unit")
    delta = float(check_evo("rpe_delta", rpe_delta, "rpe_delta"))
    check_evo_together({"rpe_delta": delta, "rpe_unit": unit}, str)
    return delta, unit


def rpe_options(
    rpe_pairs: Any, rpe_all_pairs: Any, rpe_tolerance: Any, rpe_unit: str | None = None
) -> tuple[str, bool | None, float]:
    """Validated RPE pair options, by the spec's own rules: along ``reference`` or ``estimate``;
    all pairs True / False (evo's rules) or None (lorisnb's); a positive relative tolerance, other
    than the default only where the pairs use it (:func:`lorisnb.core.spec.evo.tolerance_refusal`,
    the rule of :func:`lorisnb.core.spec.evo.evo_refusals`: evo's all pairs in m, deg or rad; ``rpe_unit``
    None: a unit not told, so evo's all pairs asked for)."""
    pairs = check_evo("rpe_pairs", rpe_pairs, "rpe_pairs")
    all_pairs = check_evo("rpe_all_pairs", rpe_all_pairs, "rpe_all_pairs")
    tol = float(check_evo("rpe_tolerance", rpe_tolerance, "rpe_tolerance"))
    unit = "m" if rpe_unit is None else check_evo("rpe_unit", rpe_unit, "rpe_unit")
    why = tolerance_refusal(unit, all_pairs)
    if tol != RPE_DEFAULTS["rpe_tolerance"] and why:
        raise ValidationError(why)
    return pairs, all_pairs, tol


#: The RPE settings of :func:`score` and their defaults (lorisnb's own rule over 1 s).
RPE_DEFAULTS: dict[str, Any] = dict(
    rpe_delta=1.0, rpe_unit="s", rpe_pairs="reference", rpe_all_pairs=None, rpe_tolerance=0.1
)


class _OfSpec:
    """The default of a threshold or RPE setting of :func:`score`, :func:`~lorisnb.core.lifelong.sweep.sweep`
    and the other tables of errors: the errors' own spec's (:func:`thresholds_of`, :func:`rpe_of`)."""

    def __repr__(self) -> str:
        return "<the errors' spec>"


OF_SPEC: Any = _OfSpec()

#: The thresholds of :func:`score` and their defaults where the errors record none (errors from
#: :func:`~lorisnb.core.pipeline.sessions.compute_errors`): every pose correct, the paper's 1 s and 60 s.
THRESHOLD_DEFAULTS: dict[str, Any] = dict(eps=np.inf, phi=np.inf, delta=1.0, tau=60.0)

#: Every setting :func:`score` and :func:`score_rows` take, in the order their messages list them.
SETTINGS = (*THRESHOLD_DEFAULTS, *RPE_DEFAULTS, "stats")


def recorded_thresholds(f: FileErrors) -> dict[str, Any]:
    """The thresholds of the spec ``f`` was evaluated under (``eps``, ``phi``, ``delta``, ``tau``), as
    the evaluation that holds it records them (:class:`~lorisnb.tools.evaluation.result.Evaluation`:
    the defaults of its tables); empty when not known."""
    return dict(getattr(f, "thresholds", None) or {})


def _of_spec(
    files: list[FileErrors], given: dict[str, Any], defaults: dict[str, Any], record: Any, what: str
) -> dict[str, Any]:
    """The settings to score ``files`` with: those ``given`` (not :data:`OF_SPEC`), the rest those
    each file records (``record(f)``; files recording different values need them given), else
    ``defaults``."""
    given = {k: v for k, v in given.items() if v is not OF_SPEC}
    if set(defaults) <= set(given):  # all given: nothing read from the files
        return dict(given)
    seen: list[dict[str, Any]] = []
    for f in files:  # once per file; one record in practice (values compared by ==: a scene mapping too)
        r = {k: v for k, v in record(f).items() if k in defaults}
        if r and r not in seen:
            seen.append(r)
    differ = sorted(k for k in defaults if k not in given and any(r.get(k) != seen[0].get(k) for r in seen[1:]))
    if differ:
        raise ValidationError(f"{', '.join(differ)}: the errors were computed under different {what}; give "
                              f"{'it' if len(differ) == 1 else 'them'} to score all the files alike")  # fmt: skip
    return defaults | (seen[0] if seen else {}) | given


def thresholds_of(files: list[FileErrors], given: dict[str, Any]) -> dict[str, Any]:
    """The thresholds to score ``files`` at: those ``given`` (not :data:`OF_SPEC`), the rest those of
    the spec the errors were evaluated under (:func:`recorded_thresholds`: ``ln.evaluate(path,
    eps=0.3).errors`` are scored at 0.3 m, as that evaluation's tables are; files of different
    thresholds need them given), else :data:`THRESHOLD_DEFAULTS`. Not validated here."""
    return _of_spec(files, given, THRESHOLD_DEFAULTS, recorded_thresholds, "thresholds")


def rpe_of(files: list[FileErrors], given: dict[str, Any]) -> dict[str, Any]:
    """The RPE settings to score ``files`` with: those ``given`` (not :data:`OF_SPEC`), the rest
    from the spec the errors were computed under (:attr:`FileErrors.rpe`; files of different
    settings need them given), else :data:`RPE_DEFAULTS`. A key of ``given`` that names no
    setting (a typo of any setting the call takes, the thresholds' too: ``ev.sequences(epss=1)``)
    is refused by :func:`~lorisnb.core.spec.validate.known_keys`."""
    known_keys(given, SETTINGS, "a setting of the scores")
    return _of_spec(files, given, RPE_DEFAULTS, lambda f: f.rpe, "RPE settings")


def refuse_unknown(other: dict[str, Any], entry: Any, what: str) -> None:
    """Refuse keywords ``entry`` (a function taking ``**other``) does not take, as
    :func:`~lorisnb.core.spec.validate.known_keys` refuses them everywhere: naming its parameters."""
    if other:
        import inspect

        named = (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
        params = inspect.signature(entry).parameters.values()
        known_keys(other, [p.name for p in params if p.kind in named and p.name != "errors"], what)


def score_rows(
    errors: FileErrors | Iterable[FileErrors], eps: Eps = OF_SPEC, phi: float = OF_SPEC, delta: float = OF_SPEC,
    tau: float = OF_SPEC, stats: bool = True, **rpe: Any,
) -> list[dict[str, Any]]:  # fmt: skip
    """One row per sequence (a dict of :func:`score`'s columns): every metric of the paper at one
    threshold setting, without pandas (the command line prints these rows as they are). The
    arguments are :func:`score`'s (the RPE settings by name; another keyword is refused)."""
    stats = flag("stats", stats)
    files = as_files(errors)
    r = rpe_of(files, rpe)
    t = thresholds_of(files, dict(eps=eps, phi=phi, delta=delta, tau=tau))
    eps_v = eps_value(t["eps"])
    phi_v, delta_v, tau_v = threshold("phi", t["phi"]), threshold("delta", t["delta"]), threshold("tau", t["tau"])
    rpe_d, rpe_u = rpe_setting(r["rpe_delta"], r["rpe_unit"])
    rpe_p, rpe_a, rpe_t = rpe_options(r["rpe_pairs"], r["rpe_all_pairs"], r["rpe_tolerance"], rpe_u)
    rows = []
    for f in files:  # one iteration per file and sequence, never per pose
        for e in f.sequences:
            e_scene = sequence_eps(eps_v, f.scene, e)
            row = sequence_meta(f, e) | dict(eps=e_scene, phi=phi_v, delta=delta_v, tau=tau_v)
            row.update(sequence_scores(e, e_scene, phi_v, delta_v, tau_v, (rpe_d, rpe_u, rpe_p, rpe_a, rpe_t), stats))
            rows.append(row)
    return rows


#: Settings whose scores a sequence keeps (:func:`sequence_scores`), the latest ones.
KEPT_SETTINGS = 4
_STATS = frozenset(STAT_COLUMNS)
_RPE = frozenset(RPE_METRICS)


def sequence_scores(
    e: SequenceErrors, eps: float, phi: float, delta: float, tau: float, rpe: tuple[Any, ...], stats: bool
) -> dict[str, Any]:
    """Every metric of one sequence at one validated setting (:func:`sequence_grid` on a one-point
    grid, as Python numbers; ``rpe``: delta, unit, pairs, all pairs, tolerance), kept on the
    sequence for the latest :data:`KEPT_SETTINGS` settings, as its RPE pairs are: scores without
    the statistics are those with them less the statistics, and those with them are those without
    plus the statistics, computed alone (each column is computed apart from the others: the same
    values to the last bit). An evaluation's workers score its spec's setting without the
    statistics where they computed the errors (about a quarter of the work of all the columns), so
    ``lorisnb evaluate``'s printed table is read, and a table with every column
    (``Evaluation.sequences``, a CSV) computes only the statistics, in the process that collects
    the files. The errors are results: a changed copy (``dataclasses.replace``) keeps none of it."""
    key = (float(eps), float(phi), float(delta), float(tau), *rpe, bool(stats))
    kept = e._scores.get(key)
    if kept is None and not stats:  # the scores with the statistics hold those without, to the last bit (score)
        full = e._scores.get((*key[:-1], True))
        if full is not None:
            return {k: v for k, v in full.items() if k not in _STATS}
    lean = e._scores.get((*key[:-1], False)) if kept is None and stats else None
    if lean is not None and not e.matched:  # no pose matched: no statistic (sequence_grid's order: last)
        kept = lean | {k: GRID_METRICS[k](np.nan) for k in STAT_COLUMNS}
    elif lean is not None:  # those without the statistics are kept: only the statistics are computed
        c = ((e.ate <= eps) & (e.aoe <= phi))[None, None, :]  # Eq. (1), as sequence_grid's (1, 1, M)
        i, j, tr, rr = e.rpe(*rpe)
        one = _statistics(e, c, tr, rr, c[:, :, i] & c[:, :, j], lambda a: np.reshape(a, (1, 1, 1, 1)))
        stat = {k: GRID_METRICS[k](v.reshape(-1)[0]) for k, v in one.items()}
        kept = {k: v for k, v in lean.items() if k not in _RPE} | stat | {k: v for k, v in lean.items() if k in _RPE}
    elif kept is None:
        grid = sequence_grid(
            e, [eps], [phi], [delta], [tau], rpe_delta=rpe[0], rpe_unit=rpe[1], with_stats=stats, rpe_pairs=rpe[2],
            rpe_all_pairs=rpe[3], rpe_tolerance=rpe[4],
        )  # fmt: skip
        kept = {k: GRID_METRICS[k](v.reshape(-1)[0]) for k, v in grid.items()}
    if key not in e._scores:
        while len(e._scores) >= KEPT_SETTINGS:
            del e._scores[next(iter(e._scores))]
        e._scores[key] = kept
    return dict(kept)


def score(
    errors: FileErrors | Iterable[FileErrors],
    eps: Eps = OF_SPEC,
    phi: float = OF_SPEC,
    delta: float = OF_SPEC,
    tau: float = OF_SPEC,
    rpe_delta: float = OF_SPEC,
    rpe_unit: str = OF_SPEC,
    rpe_pairs: str = OF_SPEC,
    rpe_all_pairs: bool | None = OF_SPEC,
    rpe_tolerance: float = OF_SPEC,
    stats: bool = True,
    **other: Any,
) -> pd.DataFrame:
    """One row per sequence: every metric of the paper at one threshold setting.

    Each threshold not given is that of the spec the errors were evaluated under
    (:func:`thresholds_of`: ``ln.score(ln.evaluate(path, eps=0.3).errors)`` is at 0.3 m, as that
    evaluation's ``sequences()``), else (errors from ``compute_errors``) the default below.
    A keyword that names no setting (``epsilon=``) is refused (ValidationError), naming them.

    Args:
        eps: ATE threshold, metres (number, ``"paper"`` or scene -> metres). Default infinity.
        phi: AOE threshold, degrees. Default infinity.
        delta: validity window of a pose, seconds (Eq. 2). Default 1 s.
        tau: re-localization time factor, seconds (Eq. 4). Default 60 s.
        rpe_delta, rpe_unit, rpe_pairs, rpe_all_pairs, rpe_tolerance: the RPE pairs (see
            :func:`lorisnb.core.metrics.pairs.rpe_indices`); each not given is that of the spec the errors
            were computed under (:func:`rpe_of`; lorisnb's own rule over 1 s when not known).
        stats: also the error statistics (:data:`~lorisnb.core.pipeline.model.STAT_COLUMNS`); False
            leaves them out, for a table that shows only the paper's metrics: the other columns are
            the same values to the last bit, in about a quarter of the time (their medians and
            masked sums are most of a setting's work: icra20's market scene 0.15 -> 0.04 s of CPU,
            the whole tree 0.56 -> 0.16 s, measured side by side).

    Columns: :data:`~lorisnb.core.pipeline.model.SEQUENCE_COLUMNS`, then
    :data:`~lorisnb.core.pipeline.model.EXTRA_COLUMNS` and :data:`~lorisnb.core.pipeline.model.STAT_COLUMNS`: the
    rows of :func:`score_rows`, each :func:`sequence_grid` on a one-point grid.
    """
    import pandas as pd

    rows = score_rows(
        errors, eps, phi, delta, tau, rpe_delta=rpe_delta, rpe_unit=rpe_unit, rpe_pairs=rpe_pairs,
        rpe_all_pairs=rpe_all_pairs, rpe_tolerance=rpe_tolerance, stats=stats, **other,
    )  # fmt: skip
    return pd.DataFrame(rows, columns=SEQUENCE_COLUMNS + EXTRA_COLUMNS + (STAT_COLUMNS if stats else []))


def pose_table(
    errors: FileErrors | Iterable[FileErrors], eps: Eps = OF_SPEC, phi: float = OF_SPEC, **other: Any
) -> pd.DataFrame:
    """One row per matched pose: algorithm, file, suite, scene, seq, stamp (s), t_rel (s from the
    ground truth's start), ate (m), aoe (deg), correct (Eq. 1); ``eps`` and ``phi`` not given are
    the errors' spec's, as :func:`score`'s."""
    import pandas as pd

    refuse_unknown(other, pose_table, "a setting of the pose table")
    files = as_files(errors)
    t = thresholds_of(files, dict(eps=eps, phi=phi))
    eps_v, phi_v = eps_value(t["eps"]), threshold("phi", t["phi"])
    parts = []
    for f in files:
        for e in f.sequences:
            if e.matched == 0:
                continue
            e_scene = sequence_eps(eps_v, f.scene, e)
            parts.append(
                pd.DataFrame(
                    {
                        "algorithm": f.algorithm, "file": f.file, "suite": f.suite, "scene": f.scene, "seq": e.seq,
                        "stamp": e.stamps, "t_rel": e.stamps - e.gt_start, "ate": e.ate, "aoe": e.aoe,
                        "correct": metrics.correctness(e.ate, e.aoe, e_scene, phi_v),
                    }
                )
            )  # fmt: skip
    return pd.concat(parts, ignore_index=True) if parts else pd.DataFrame(columns=POSE_COLUMNS)
