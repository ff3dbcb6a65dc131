"""Threshold sensitivity: every metric over grids of eps, phi, delta and tau, from per-pose errors
computed once (:func:`lorisnb.core.pipeline.sessions.compute_errors`).

The metrics come from the one scoring kernel, :func:`lorisnb.core.lifelong.scoring.sequence_grid`, on the
whole grid at once; nothing is re-read or re-aligned per setting, and a row of :func:`sweep`
equals the row :func:`lorisnb.core.lifelong.scoring.score` gives for that setting (same columns, same
numbers).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np
import pandas as pd

from lorisnb.core.lifelong.aggregate import aggregate_scenes
from lorisnb.core.lifelong.scoring import (
    GRID_METRICS,
    OF_SPEC,
    as_files,
    refuse_unknown,
    rpe_of,
    rpe_options,
    rpe_setting,
    sequence_grid,
    sequence_meta,
    thresholds_of,
)
from lorisnb.core.metrics import openloris as metrics
from lorisnb.core.metrics.relation_table import RELATION_COLUMNS, repeated_relation_columns
from lorisnb.core.pipeline.model import (
    EXTRA_COLUMNS,
    SEQUENCE_COLUMNS,
    STAT_COLUMNS,
    FileErrors,
    SequenceErrors,
    sequence_eps,
    sequence_size,
)  # fmt: skip
from lorisnb.core.spec import validate
from lorisnb.core.spec.validate import choice, fraction, threshold, threshold_list
from lorisnb.core.trajectory.frames import PAPER_EPS
from lorisnb.core.trajectory.poses import RELATIVE
from lorisnb.errors import EvaluationError, ValidationError

#: Columns of the default (lean) sweep table: identity, thresholds, and the metrics that depend on
#: them, plus what scene aggregation needs. ``columns="all"`` gives every column of ``score``.
METRIC_COLUMNS = [
    "suite", "algorithm", "trial", "file", "scene", "seq", "eps", "eps_value", "phi", "delta", "tau", "matched",
    "c_matched", "correct_time", "track_time", "cr", "cr_t", "cs_r", "ate_rmse", "c_ate_rmse", "c_aoe_rmse",
]  # fmt: skip

#: Memory a sweep may use by default (table plus working arrays), bytes.
MAX_SWEEP_BYTES = 4 * 2**30

#: Working memory of one call of the scoring kernel in a sweep, bytes (its (eps, phi, pose)
#: arrays, 9 bytes an entry): a sequence's grid is scored in chunks of eps (and phi) values of
#: about this size, the same chunks whatever else is swept, so a fine grid needs no more.
CHUNK_BYTES = 2**28


def _chunks(E: int, P: int, poses: int) -> list[tuple[int, int, int, int]]:
    """Index ranges ``(eps from, eps to, phi from, phi to)`` covering an E x P grid, each needing
    at most :data:`CHUNK_BYTES` for ``poses`` matched poses (one point at least)."""
    per = max(poses, 1) * 9.0
    cp = P if P * per <= CHUNK_BYTES else max(1, int(CHUNK_BYTES // per))
    ce = max(1, int(CHUNK_BYTES // (cp * per)))
    return [(a, min(a + ce, E), b, min(b + cp, P)) for a in range(0, E, ce) for b in range(0, P, cp)]


def sweep_bytes(files: list[FileErrors], shape: tuple[int, int, int, int], columns: str = "metrics") -> float:
    """Memory a sweep of ``files`` over an eps x phi x delta x tau grid of ``shape`` needs, bytes:
    its tidy table (rows x columns x 8) plus the working arrays of one chunk of the grid
    (:data:`CHUNK_BYTES`, or less for a small grid)."""
    E, P, D, T = shape
    n_seq = sum(len(f.sequences) for f in files)
    longest = max((e.matched for f in files for e in f.sequences), default=0)
    ncol = len(SEQUENCE_COLUMNS + EXTRA_COLUMNS + STAT_COLUMNS) + 1 if columns == "all" else len(METRIC_COLUMNS)
    return n_seq * E * P * D * T * ncol * 8.0 + min(E * P * longest * 9.0, max(CHUNK_BYTES, longest * 9.0))


def check_sweep_size(
    files: list[FileErrors],
    shape: tuple[int, int, int, int],
    columns: str,
    max_bytes: float = MAX_SWEEP_BYTES,
    streamed: bool = False,
) -> None:
    """Refuse a sweep that would need more than ``max_bytes`` (:func:`sweep_bytes`), saying how much
    it would need and how to stream it instead; ``streamed``: ``files`` are one group of a sweep
    already streamed one group at a time (:func:`lorisnb.tools.evaluation.streaming.sweep_to_parquet`,
    :func:`~lorisnb.tools.evaluation.streaming.sweep_to_csv`), which fewer files or streaming cannot help."""
    need = sweep_bytes(files, shape, columns)
    if need > max_bytes:
        E, P, D, T = shape
        n_seq = sum(len(f.sequences) for f in files)
        longest = max((e.matched for f in files for e in f.sequences), default=0)
        ncol = len(SEQUENCE_COLUMNS + EXTRA_COLUMNS + STAT_COLUMNS) + 1 if columns == "all" else len(METRIC_COLUMNS)
        raise ValidationError(
            f"this sweep would need about {need / 2**30:.1f} GiB ({n_seq * E * P * D * T:,} rows of {ncol} columns; "
            f"{E} eps x {P} phi x {D} delta x {T} tau over {n_seq} sequences, up to {longest:,} poses each), "
            f"more than the {max_bytes / 2**30:.1f} GiB allowed (max_bytes); "
            + (
                f"streamed, each group of files (one algorithm, scene and trial: {files[0].algorithm} "
                f"{files[0].scene}, trial {files[0].trial}) must fit: use fewer thresholds"
                if streamed
                else "use fewer thresholds or files, or stream the table to Parquet (command line: --parquet DIR; "
                "Python: lorisnb.tools.sweep_to_parquet)"
            )
        )


def grid_values(name: str, values: Any) -> list[Any]:
    """A validated threshold grid: :func:`lorisnb.core.spec.validate.threshold_list`, the single
    evaluation's rules (a 0-d numpy array, ``arr.max()`` of an array, is one value)."""
    return threshold_list(name, values)


def scene_totals(durations: pd.DataFrame, scenes: Iterable[str]) -> pd.Series:
    """Ground-truth time of each scene (the denominator of scene CR, Eq. 2), seconds; a scene of
    the inputs without durations is refused as :func:`lorisnb.core.lifelong.aggregate.aggregate_scenes`
    refuses it (its rates would be NaN or a KeyError)."""
    total = durations.groupby("scene")["gt_duration"].sum()
    missing = sorted(set(scenes) - set(total.index))
    if missing:
        raise EvaluationError(f"no ground-truth durations for scene(s) {', '.join(missing)}; pass their durations")
    return total


def _eps_label(v: Any) -> Any:
    """An eps grid value as the ``eps_value`` column shows it: metres as a number, a word as
    given, a scene mapping as ``scene:metres`` pairs."""
    if isinstance(v, Mapping):
        return ",".join(f"{k}:{x:g}" for k, x in v.items())
    return v if isinstance(v, str) else float(v)


def _eps_values(eps: list[Any], scene: str, e: SequenceErrors, relative_to: str | None) -> np.ndarray:
    """The eps of each grid value for one sequence, metres."""
    size = sequence_size(e, relative_to) if relative_to is not None else np.nan
    return np.array(
        [
            sequence_eps(v, scene, e) if relative_to is None else float(v) * size
            for v in eps  # over grid values, not poses
        ]
    )


def sweep(
    errors: FileErrors | Iterable[FileErrors],
    eps: Any = OF_SPEC,
    phi: Any = OF_SPEC,
    delta: Any = OF_SPEC,
    tau: Any = OF_SPEC,
    relative_to: str | None = None,
    rpe_delta: float = OF_SPEC,
    rpe_unit: str = OF_SPEC,
    columns: str = "metrics",
    max_bytes: float = MAX_SWEEP_BYTES,
    rpe_pairs: str = OF_SPEC,
    rpe_all_pairs: bool | None = OF_SPEC,
    rpe_tolerance: float = OF_SPEC,
    relation: str | None = None,
    change_unit: str | None = None,
    **other: Any,
) -> pd.DataFrame:
    """One row per sequence and per combination of thresholds. With ``columns="all"`` the columns
    are those of :func:`lorisnb.core.lifelong.scoring.score` (a row equals ``score`` at that setting, RPE
    included); the default ``"metrics"`` keeps :data:`METRIC_COLUMNS` (same values, less memory).

    Args:
        eps: ATE thresholds in metres; ``"paper"`` gives each scene the paper's 1/3/5 m. With
            ``relative_to`` the numbers are fractions of each sequence's ground-truth ``extent``
            (bounding-box diagonal) or ``length`` (distance travelled); ``eps_value`` keeps the
            value as given, ``eps`` the metres used.
        phi: AOE thresholds, degrees. delta: validity windows, seconds. tau: re-localization
            time factors, seconds. Each a value or a list (validated like the command line's).
            Each not given is the one value of the spec the errors were evaluated under, as
            :func:`~lorisnb.core.lifelong.scoring.score`'s (:func:`~lorisnb.core.lifelong.scoring.thresholds_of`;
            eps infinity with ``relative_to``); a keyword that names no setting is refused.
        max_bytes: refuse (with the size it would need) a sweep whose table or working arrays
            would take more memory than this.
        rpe_delta, rpe_unit, rpe_pairs, rpe_all_pairs, rpe_tolerance: as :func:`~lorisnb.core.lifelong.scoring.score`'s
            (not given: the errors' own spec's).
        relation: evo's pose relation (``evaluate --relation``): its ``ape_*``/``rpe_*`` columns last,
            in ``change_unit`` (evo's ``--change_unit``; None: the relation's own).
    """
    refuse_unknown(other, sweep, "a setting of the sweep")
    files = as_files(errors)
    if relative_to is not None:
        relative_to = choice("relative_to", relative_to, RELATIVE)
        eps = (np.inf,) if eps is OF_SPEC else eps  # the spec's metres are no fraction: every pose correct
    t = thresholds_of(files, dict(eps=eps, phi=phi, delta=delta, tau=tau))
    eps, phi, delta, tau = ((t[k],) if v is OF_SPEC else v for k, v in (("eps", eps), ("phi", phi), ("delta", delta),
                                                                        ("tau", tau)))  # fmt: skip
    columns = choice("columns", columns, ("all", "metrics"))
    max_bytes = validate.positive("max_bytes", max_bytes, "bytes")
    eps_l = grid_values("eps", eps)
    if relative_to is not None and any(isinstance(v, (str, Mapping)) for v in eps_l):
        raise ValidationError("eps: with relative_to, eps values are fractions (numbers), not 'paper' or a mapping")
    if relative_to is not None:
        eps_l = [fraction("eps", v) if np.isfinite(v) else v for v in eps_l]  # inf: every pose correct
        if not any(np.isfinite(v) for v in eps_l):  # nothing is a fraction of anything: relative_to changes nothing
            raise ValidationError(f"relative_to={relative_to}: no eps value to read as a fraction of each sequence's "
                                  f"{relative_to} (eps is inf: every pose correct); give eps fractions (--eps 0.05,0.1) "
                                  "or leave relative_to out")  # fmt: skip
    phi_a = np.array(grid_values("phi", phi))
    delta_a = np.array(grid_values("delta", delta))
    tau_a = np.array(grid_values("tau", tau))
    r = rpe_of(files, dict(rpe_delta=rpe_delta, rpe_unit=rpe_unit, rpe_pairs=rpe_pairs, rpe_all_pairs=rpe_all_pairs,
                           rpe_tolerance=rpe_tolerance))  # fmt: skip
    rpe_d, rpe_u = rpe_setting(r["rpe_delta"], r["rpe_unit"])
    rpe_p, rpe_a, rpe_t = rpe_options(r["rpe_pairs"], r["rpe_all_pairs"], r["rpe_tolerance"], rpe_u)
    given = dict(rpe_delta=rpe_delta, rpe_unit=rpe_unit, rpe_pairs=rpe_pairs, rpe_all_pairs=rpe_all_pairs,
                 rpe_tolerance=rpe_tolerance)  # fmt: skip
    unused = [k for k, v in given.items() if v is not OF_SPEC]
    if columns == "metrics" and relation is None and unused:  # checked above, and still of no use: refused
        raise ValidationError(f"{unused[0]}: the RPE is in the table of columns='all' (or of relation=); the "
                              "default columns='metrics' holds the thresholds' metrics only")  # fmt: skip
    E, P, D, T = len(eps_l), len(phi_a), len(delta_a), len(tau_a)
    n_set = E * P * D * T
    check_sweep_size(files, (E, P, D, T), columns, max_bytes)
    with_rpe = columns == "all"
    cols = SEQUENCE_COLUMNS + EXTRA_COLUMNS + STAT_COLUMNS + ["eps_value"] if columns == "all" else METRIC_COLUMNS
    pairs = [(f, e) for f in files for e in f.sequences]
    if not pairs:
        return pd.DataFrame(columns=cols)
    S = len(pairs)
    data: dict[str, Any] = {}
    views: dict[str, np.ndarray] = {}
    for s_i, (f, e) in enumerate(pairs):  # per sequence and chunk of the grid, never per pose
        eps_m = _eps_values(eps_l, f.scene, e, relative_to)
        for a, b, p0, p1 in _chunks(E, P, e.matched):
            block = sequence_grid(
                e, eps_m[a:b], phi_a[p0:p1], delta_a, tau_a, rpe_delta=rpe_d, rpe_unit=rpe_u, with_rpe=with_rpe,
                with_stats=with_rpe, rpe_pairs=rpe_p, rpe_all_pairs=rpe_a, rpe_tolerance=rpe_t,
            )  # fmt: skip
            block["eps"] = eps_m[a:b, None, None, None]
            for k in (k for k in block if k in cols):
                if k not in views:
                    data[k] = np.empty(S * n_set, dtype=GRID_METRICS.get(k, float))
                    views[k] = data[k].reshape(S, E, P, D, T)
                views[k][s_i, a:b, p0:p1] = block[k]  # broadcast straight into the column
    meta = pd.DataFrame([sequence_meta(f, e) for f, e in pairs])
    rep = np.repeat(np.arange(S), n_set)
    for k in [c for c in meta.columns if c in cols]:
        col = meta[k]
        if col.dtype == object or isinstance(col.dtype, pd.StringDtype):
            codes, uniques = pd.factorize(col, sort=True)  # one code per sequence, repeated: no strings copied
            data[k] = pd.Categorical.from_codes(codes[rep], categories=uniques)
        else:
            data[k] = col.to_numpy()[rep]
    grid_idx = np.indices((E, P, D, T)).reshape(4, -1)
    data["phi"] = np.tile(phi_a[grid_idx[1]], S)
    data["delta"] = np.tile(delta_a[grid_idx[2]], S)
    data["tau"] = np.tile(tau_a[grid_idx[3]], S)
    labels = np.array([_eps_label(v) for v in eps_l], dtype=object)
    if any(isinstance(v, str) for v in labels):
        data["eps_value"] = pd.Categorical(np.tile(labels[grid_idx[0]], S).astype(str))
    else:
        data["eps_value"] = np.tile(labels[grid_idx[0]].astype(float), S)
    if relation is not None:  # threshold-free, per sequence, as evaluate's
        data |= repeated_relation_columns(files, relation, n_set, change_unit, rpe_delta=rpe_d, rpe_unit=rpe_u, rpe_pairs=rpe_p,
                                          rpe_all_pairs=rpe_a, rpe_tolerance=rpe_t)  # fmt: skip
        cols = cols + RELATION_COLUMNS
    # columns in final order, no consolidation copy: the table is large for big grids
    return pd.DataFrame({k: data[k] for k in cols}, copy=False)


def sweep_groups(errors: FileErrors | Iterable[FileErrors]) -> list[list[FileErrors]]:
    """Files grouped by suite, algorithm, scene and trial, in order of first appearance: the
    sequences that scene aggregation (:func:`sweep_scenes`) combines, so that a sweep can be
    computed, aggregated and written one group at a time."""
    groups: dict[tuple[str, str, str, int], list[FileErrors]] = {}
    for f in as_files(errors):
        groups.setdefault((f.suite, f.algorithm, f.scene, f.trial), []).append(f)
    return list(groups.values())


def sweep_scenes(table: pd.DataFrame, durations: pd.DataFrame) -> pd.DataFrame:
    """Scene aggregates (:func:`lorisnb.core.lifelong.aggregate.aggregate_scenes`) of a sweep, per setting;
    ``durations`` as for that function (``Evaluation.durations()``)."""
    plain = table.astype({c: str for c in ("algorithm", "scene", "suite", "file") if c in table.columns})
    if "eps_value" in plain.columns:
        plain["eps_value"] = plain["eps_value"].astype(str)
    return aggregate_scenes(plain, durations)


def _target_cr(target: Any) -> float:
    """A correct rate to reach: a number above 0 and at most 1."""
    try:
        v = validate.positive("target", target, "")
    except ValidationError:
        v = np.nan
    if not 0 < v <= 1:
        order = " (the target comes second: eps_at_cr(errors, target, durations))" if hasattr(target, "shape") else ""
        raise ValidationError(f"target={validate.shown(target)}: expected a correct rate above 0 and at most 1 (0.5 "
                              f"for 50 %){order}")  # fmt: skip
    return v


def eps_at_cr(
    errors: Iterable[FileErrors], target: float, durations: pd.DataFrame, phi: float = OF_SPEC,
    delta: float = OF_SPEC, **other: Any,
) -> pd.DataFrame:  # fmt: skip
    """The smallest eps (metres) at which each algorithm reaches scene CR >= ``target`` (a rate
    above 0, at most 1), exactly, per suite, algorithm, scene and trial (each trial is one run,
    scored alone, as :func:`sweep_scenes` does).

    Scene CR grows with eps as a step function that steps at the poses' ATE values: sorting the
    poses of a scene by ATE and accumulating the time they hold gives the answer without a grid.
    NaN where even eps = infinity does not reach the target (not enough tracking time; ``max_cr``
    says how much there is, 0 for a run without a matched pose).
    ``durations``: the ground-truth durations (``Evaluation.durations()``). ``phi`` and ``delta``
    not given are the errors' spec's, as :func:`~lorisnb.core.lifelong.scoring.score`'s.
    """
    refuse_unknown(other, eps_at_cr, "a setting of eps_at_cr")
    files = as_files(errors)
    target = _target_cr(target)
    t = thresholds_of(files, dict(phi=phi, delta=delta))
    phi, delta = threshold("phi", t["phi"]), threshold("delta", t["delta"])
    total = scene_totals(durations, (f.scene for f in files))
    parts: dict[tuple[str, str, str, int], list[tuple[np.ndarray, np.ndarray]]] = {}
    for f in files:
        chunks = parts.setdefault((f.suite, f.algorithm, f.scene, f.trial), [])  # listed even if never matched
        for e in f.sequences:
            if e.matched == 0:
                continue
            held = np.minimum(metrics.valid_intervals(e.stamps, e.gt_end, e.gt_start), delta)
            ok = e.aoe <= phi
            chunks.append((e.ate[ok], held[ok]))
    rows = []
    for (suite, alg, scene, trial), chunks in parts.items():
        ate = np.concatenate([a for a, _ in chunks] or [np.zeros(0)])
        held = np.concatenate([h for _, h in chunks] or [np.zeros(0)])
        order = np.argsort(ate, kind="stable")
        cr = np.cumsum(held[order]) / total[scene]
        k = np.searchsorted(cr, target - 1e-12)
        eps = float(ate[order][k]) if k < len(cr) else np.nan
        max_cr = float(cr[-1]) if len(cr) else 0.0
        rows.append(dict(suite=suite, algorithm=alg, scene=scene, trial=trial, target_cr=target, phi=phi,
                         delta=delta, eps=eps, max_cr=max_cr))  # fmt: skip
    columns = ["suite", "algorithm", "scene", "trial", "target_cr", "phi", "delta", "eps", "max_cr"]
    return pd.DataFrame(rows, columns=columns)


def _scene_rows(scenes: pd.DataFrame, metric: str, name: str) -> None:
    """Refuse what ``name`` cannot rank: rows per sequence (a sweep's own table: ranked, they gave
    plausible numbers of the sequences averaged), a ``metric`` that is no numeric column, scene
    rows without one eps in metres (a relative sweep's: each sequence had its own)."""
    if "seq" in scenes.columns or "sequences" not in scenes.columns:
        raise ValidationError(f"{name}: expected scene rows (sweep_scenes(table, durations)), not one row per sequence")
    if metric not in scenes.columns or not pd.api.types.is_numeric_dtype(scenes[metric]):
        raise ValidationError(f"{name}: metric={metric!r} is no numeric column of the scene rows; expected one of "
                              f"{', '.join(c for c in ('cr', 'cr_t', 'cs_r', 'c_ate_rmse') if c in scenes.columns)}")  # fmt: skip
    if "eps" in scenes.columns and scenes["eps"].isna().any():
        raise ValidationError(
            f"{name}: ranks algorithms along eps in metres, but some scene rows have none (a sweep of "
            "relative eps gives each sequence its own); sweep absolute eps (metres) for this"
        )


def rank_stability(
    scenes: pd.DataFrame, metric: str = "cr", reference: Mapping[str, float] | None = None
) -> pd.DataFrame:
    """How stable the ranking of algorithms is as eps changes, per scene (and suite, phi, delta, tau):
    Kendall's tau between the ranking at each eps and at the reference eps (default: the paper's
    eps for the scene), and the number of algorithm pairs whose order differs.

    ``scenes`` is a scene aggregate over several eps (:func:`sweep_scenes`).
    """
    from scipy import stats  # here, not at the top: scipy.stats takes half a second to import

    _scene_rows(scenes, metric, "rank_stability")
    keys = ["suite", "scene", "phi", "delta", "tau"]
    rows = []
    for key, grp in scenes.groupby(keys, sort=False, observed=True):
        scene = key[1]
        ref_eps = (reference or {}).get(scene, PAPER_EPS.get(scene))
        wide = grp.pivot_table(index="algorithm", columns="eps", values=metric, observed=True)
        if wide.shape[0] < 2:
            continue
        cols = np.asarray(wide.columns, float)
        ref_col = wide.columns[int(np.argmin(np.abs(cols - ref_eps)))]
        ref = wide[ref_col].to_numpy()
        for e in wide.columns:
            cur = wide[e].to_numpy()
            ok = np.isfinite(cur) & np.isfinite(ref)
            kt = stats.kendalltau(ref[ok], cur[ok]).statistic if ok.sum() > 1 else np.nan
            a, b = np.triu_indices(int(ok.sum()), 1)
            flips = int(np.sum(np.sign(ref[ok][a] - ref[ok][b]) * np.sign(cur[ok][a] - cur[ok][b]) < 0))
            rows.append(
                dict(
                    zip(keys, key, strict=True),
                    eps=float(e),
                    reference_eps=float(ref_col),
                    kendall_tau=kt,
                    swapped_pairs=flips,
                    algorithms=int(ok.sum()),
                )
            )
    return pd.DataFrame(rows, columns=keys + ["eps", "reference_eps", "kendall_tau", "swapped_pairs", "algorithms"])


def rank_swaps(scenes: pd.DataFrame, metric: str = "cr") -> pd.DataFrame:
    """Where two algorithms swap rank as eps grows: one row per scene, pair and eps interval in
    which their order of ``metric`` reverses."""
    _scene_rows(scenes, metric, "rank_swaps")
    rows = []
    for (suite, scene, phi, delta, tau), grp in scenes.groupby(
        ["suite", "scene", "phi", "delta", "tau"], sort=False, observed=True
    ):
        wide = grp.pivot_table(index="eps", columns="algorithm", values=metric, observed=True).sort_index()
        algs = list(wide.columns)
        eps = wide.index.to_numpy(float)
        v = wide.to_numpy()
        for a in range(len(algs)):
            for b in range(a + 1, len(algs)):  # pairs of algorithms, a handful
                s = np.sign(v[:, a] - v[:, b])
                nz = np.flatnonzero(s != 0)
                flips = nz[1:][s[nz[1:]] != s[nz[:-1]]]
                prev = nz[:-1][s[nz[1:]] != s[nz[:-1]]]
                for k0, k1 in zip(prev, flips, strict=True):
                    rows.append(
                        dict(
                            suite=suite,
                            scene=scene,
                            phi=phi,
                            delta=delta,
                            tau=tau,
                            leader_before=algs[a] if s[k0] > 0 else algs[b],
                            leader_after=algs[a] if s[k1] > 0 else algs[b],
                            eps_from=float(eps[k0]),
                            eps_to=float(eps[k1]),
                        )
                    )
    return pd.DataFrame(
        rows, columns=["suite", "scene", "phi", "delta", "tau", "leader_before", "leader_after", "eps_from", "eps_to"]
    )
