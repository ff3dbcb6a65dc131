"""Threshold sensitivity: every metric over grids of eps, phi, delta and tau, from per-pose errors
computed once (:func:`lorisnb.evaluation.compute_errors`).

Correctness over a grid of (eps, phi) is one broadcast comparison; correct time over a grid of
delta is one matrix product; nothing is re-read or re-aligned per setting. A row of
:func:`sweep` equals the row :func:`lorisnb.evaluation.score` gives for that setting (same
columns, same numbers).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Sequence

import numpy as np
import pandas as pd
from scipy import stats

from . import metrics
from .evaluation import (
    EXTRA_COLUMNS,
    SEQUENCE_COLUMNS,
    FileErrors,
    SequenceErrors,
    aggregate_scenes,
    scene_eps,
)
from .frames import PAPER_EPS, PAPER_PHI

#: Columns of the default (lean) sweep table: identity, thresholds, and the metrics that depend on
#: them, plus what scene aggregation needs. ``columns="all"`` gives every column of ``score``.
METRIC_COLUMNS = [
    "suite", "algorithm", "file", "scene", "seq", "eps", "eps_value", "phi", "delta", "tau", "matched",
    "c_matched", "correct_time", "track_time", "cr", "cr_t", "cs_r", "ate_rmse", "c_ate_rmse", "c_aoe_rmse",
]

#: How eps may be given relative to the size of each sequence's ground truth.
RELATIVE = (None, "extent", "length")


def _as_list(v) -> list:
    if isinstance(v, (str, float, int, np.floating, np.integer)):
        return [v]
    return list(v)


def sequence_size(e: SequenceErrors, relative_to: str) -> float:
    """Size of a sequence's ground truth (at the matched stamps), metres: ``extent`` is the
    diagonal of its bounding box, ``length`` the distance travelled."""
    p = e.gt_positions
    if len(p) < 2:
        return np.nan
    if relative_to == "extent":
        return float(np.linalg.norm(p.max(axis=0) - p.min(axis=0)))
    if relative_to == "length":
        return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())
    raise ValueError(f"relative_to must be one of {RELATIVE}, got {relative_to!r}")


def _eps_values(eps: list, scene: str, e: SequenceErrors, relative_to: str | None) -> np.ndarray:
    out = np.empty(len(eps))
    for i, v in enumerate(eps):  # over grid values, not poses
        if isinstance(v, str) and v == "paper":
            out[i] = PAPER_EPS[scene]
        elif relative_to is None:
            out[i] = scene_eps(v, scene)
        else:
            out[i] = float(v) * sequence_size(e, relative_to)
    return out


@dataclass
class _Grid:
    eps: list
    phi: np.ndarray
    delta: np.ndarray
    tau: np.ndarray

    @property
    def shape(self) -> tuple[int, int, int, int]:
        return len(self.eps), len(self.phi), len(self.delta), len(self.tau)


def _sequence_grid(f: FileErrors, e: SequenceErrors, g: _Grid, relative_to, rpe_delta, rpe_unit,
                   with_rpe: bool = True) -> dict:
    """All metrics of one sequence over the grid, as arrays of shape (E, P, D, T)."""
    E, P, D, T = g.shape
    shape = (E, P, D, T)
    eps = _eps_values(g.eps, f.scene, e, relative_to)
    out = {"eps": np.broadcast_to(eps[:, None, None, None], shape)}
    if e.matched == 0:
        z = np.zeros(shape)
        nan = np.full(shape, np.nan)
        out.update(ate_rmse=nan, aoe_rmse=nan, c_ate_rmse=nan, c_aoe_rmse=nan, c_matched=z, correct_time=z, cr=z,
                   cr_t=z, reloc_time=np.full(shape, np.inf), cs_r=z, t0=nan, track_time=z,
                   first_correct=np.zeros(shape, bool), rpe_trans_rmse=nan, rpe_rot_rmse=nan, c_rpe_trans_rmse=nan,
                   c_rpe_rot_rmse=nan, rpe_pairs=z, c_rpe_pairs=z)
        return out
    # correctness of every pose at every (eps, phi): (E, P, M)
    c = (e.ate[None, None, :] <= eps[:, None, None]) & (e.aoe[None, None, :] <= g.phi[None, :, None])
    cf = c.reshape(E * P, -1).astype(float)
    dt = metrics.valid_intervals(e.stamps, e.gt_end)
    held = np.minimum(dt[None, :], g.delta[:, None])             # (D, M)
    ct = (cf @ held.T).reshape(E, P, D)                         # correct time, Eq. 2 numerator
    n_c = cf.sum(axis=1).reshape(E, P)
    with np.errstate(invalid="ignore", divide="ignore"):
        c_ate = np.sqrt((cf @ (e.ate ** 2)).reshape(E, P) / n_c)
        c_aoe = np.sqrt((cf @ (e.aoe ** 2)).reshape(E, P) / n_c)
    c_ate[n_c == 0] = np.nan
    c_aoe[n_c == 0] = np.nan
    t0 = float(e.stamps[0])
    span = e.gt_end - e.gt_start
    track = e.gt_end - t0
    rt = metrics.relocalization_time(t0, e.gt_start)
    first = c[:, :, 0]
    csr = np.where(first[:, :, None], np.exp(-rt / g.tau)[None, None, :], 0.0)  # (E, P, T)
    bc = lambda a: np.broadcast_to(a, shape)  # noqa: E731
    out.update(
        ate_rmse=bc(float(metrics.rmse(e.ate))), aoe_rmse=bc(float(metrics.rmse(e.aoe))),
        c_ate_rmse=bc(c_ate[:, :, None, None]), c_aoe_rmse=bc(c_aoe[:, :, None, None]),
        c_matched=bc(n_c[:, :, None, None]), correct_time=bc(ct[:, :, :, None]),
        cr=bc((ct / span if span > 0 else ct * 0)[:, :, :, None]),
        cr_t=bc((ct / track if track > 0 else ct * 0)[:, :, :, None]),
        reloc_time=bc(rt), cs_r=bc(csr[:, :, None, :]), t0=bc(t0), track_time=bc(track),
        first_correct=bc(first[:, :, None, None]))
    # RPE: pairs fixed per sequence; C-RPE over pairs whose two poses are correct
    if not with_rpe:
        return out
    i, j, tr, rr = e.rpe(rpe_delta, rpe_unit)
    if len(i):
        both = (c[:, :, i] & c[:, :, j]).reshape(E * P, -1).astype(float)
        nb = both.sum(axis=1).reshape(E, P)
        with np.errstate(invalid="ignore", divide="ignore"):
            ctr = np.where(nb > 0, np.sqrt((both @ tr ** 2).reshape(E, P) / nb), np.nan)
            crr = np.where(nb > 0, np.sqrt((both @ rr ** 2).reshape(E, P) / nb), np.nan)
        out.update(rpe_trans_rmse=bc(float(metrics.rmse(tr))), rpe_rot_rmse=bc(float(metrics.rmse(rr))),
                   c_rpe_trans_rmse=bc(ctr[:, :, None, None]), c_rpe_rot_rmse=bc(crr[:, :, None, None]),
                   rpe_pairs=bc(float(len(i))), c_rpe_pairs=bc(nb[:, :, None, None]))
    else:
        nan = np.full(shape, np.nan)
        out.update(rpe_trans_rmse=nan, rpe_rot_rmse=nan, c_rpe_trans_rmse=nan, c_rpe_rot_rmse=nan,
                   rpe_pairs=np.zeros(shape), c_rpe_pairs=np.zeros(shape))
    return out


def sweep(errors: FileErrors | Iterable[FileErrors], eps: Sequence = (np.inf,), phi: Sequence = (np.inf,),
          delta: Sequence = (1.0,), tau: Sequence = (60.0,), relative_to: str | None = None,
          rpe_delta: float = 1.0, rpe_unit: str = "s", columns: str = "metrics") -> pd.DataFrame:
    """One row per sequence and per combination of thresholds. With ``columns="all"`` the columns
    are those of :func:`lorisnb.evaluation.score` (a row equals ``score`` at that setting, RPE
    included); the default ``"metrics"`` keeps :data:`METRIC_COLUMNS` (same values, less memory).

    Args:
        eps: ATE thresholds in metres; ``"paper"`` gives each scene the paper's 1/3/5 m. With
            ``relative_to`` the numbers are fractions of each sequence's ground-truth ``extent``
            (bounding-box diagonal) or ``length`` (distance travelled); ``eps_value`` keeps the
            value as given, ``eps`` the metres used.
        phi: AOE thresholds, degrees. delta: validity windows, seconds. tau: re-localization
            time factors, seconds.
    """
    files = [errors] if isinstance(errors, FileErrors) else list(errors)
    if relative_to not in RELATIVE:
        raise ValueError(f"relative_to must be one of {RELATIVE}, got {relative_to!r}")
    g = _Grid(_as_list(eps), np.asarray(_as_list(phi), float), np.asarray(_as_list(delta), float),
              np.asarray(_as_list(tau), float))
    E, P, D, T = g.shape
    n_set = E * P * D * T
    seq_meta, blocks = [], []
    for f in files:  # per sequence, never per pose
        for e in f.sequences:
            blocks.append(_sequence_grid(f, e, g, relative_to, rpe_delta, rpe_unit, columns == "all"))
            seq_meta.append(dict(algorithm=f.algorithm, file=f.file, scene=f.scene, seq=e.seq, frame=f.frame,
                                 poses=e.poses, matched=e.matched, suite=f.suite, mode=f.mode,
                                 aligned_on=f.aligned_on, scale=e.scale, gt_start=e.gt_start,
                                 gt_end=e.gt_end, gt_duration=e.gt_end - e.gt_start,
                                 official_interpolation=f.official_interpolation))
    cols = SEQUENCE_COLUMNS + EXTRA_COLUMNS + ["eps_value"] if columns == "all" else METRIC_COLUMNS
    if columns not in ("all", "metrics"):
        raise ValueError(f"columns must be 'all' or 'metrics', got {columns!r}")
    if not blocks:
        return pd.DataFrame(columns=cols)
    S = len(blocks)
    meta = pd.DataFrame(seq_meta)
    rep = np.repeat(np.arange(S), n_set)
    data = {}
    for k in [c for c in meta.columns if c in cols]:
        col = meta[k]
        data[k] = pd.Categorical(col.to_numpy()[rep]) if col.dtype == object else col.to_numpy()[rep]
    grid_idx = np.indices((E, P, D, T)).reshape(4, -1)
    data["phi"] = np.tile(g.phi[grid_idx[1]], S)
    data["delta"] = np.tile(g.delta[grid_idx[2]], S)
    data["tau"] = np.tile(g.tau[grid_idx[3]], S)
    labels = np.array([str(v) if isinstance(v, str) else float(v) for v in g.eps], dtype=object)
    data["eps_value"] = pd.Categorical(np.tile(labels[grid_idx[0]], S).astype(str)) if any(
        isinstance(v, str) for v in g.eps) else np.tile(labels[grid_idx[0]].astype(float), S)
    for k in [c for c in blocks[0] if c in cols]:
        dtype = bool if k == "first_correct" else int if k in ("c_matched", "rpe_pairs", "c_rpe_pairs") else float
        col = np.empty(S * n_set, dtype=dtype)
        view = col.reshape(S, E, P, D, T)
        for s_i, b in enumerate(blocks):  # per sequence: broadcast straight into the column
            view[s_i] = b[k]
        data[k] = col
    # columns in final order, no consolidation copy: the table is large for big grids
    return pd.DataFrame({k: data[k] for k in cols}, copy=False)


def sweep_scenes(table: pd.DataFrame, data_root=None) -> pd.DataFrame:
    """Scene aggregates (:func:`lorisnb.evaluation.aggregate_scenes`) of a sweep, per setting."""
    plain = table.astype({c: str for c in ("algorithm", "scene", "suite", "file") if c in table.columns})
    if "eps_value" in plain.columns:
        plain["eps_value"] = plain["eps_value"].astype(str)
    return aggregate_scenes(plain, data_root=data_root)


def eps_at_cr(errors: Iterable[FileErrors], target: float, phi: float = np.inf, delta: float = 1.0,
              durations: pd.DataFrame | None = None, data_root=None) -> pd.DataFrame:
    """The smallest eps (metres) at which each algorithm reaches scene CR >= ``target``, exactly.

    Scene CR grows with eps as a step function that steps at the poses' ATE values: sorting the
    poses of a scene by ATE and accumulating the time they hold gives the answer without a grid.
    NaN where even eps = infinity does not reach the target (not enough tracking time).
    """
    from .evaluation import scene_durations

    files = list(errors)
    if durations is None:
        durations = scene_durations(sorted({f.scene for f in files}), data_root)
    total = durations.groupby("scene")["gt_duration"].sum()
    parts: dict[tuple, list] = {}
    for f in files:
        for e in f.sequences:
            if e.matched == 0:
                continue
            held = np.minimum(metrics.valid_intervals(e.stamps, e.gt_end), delta)
            ok = e.aoe <= phi
            parts.setdefault((f.suite, f.algorithm, f.scene), []).append((e.ate[ok], held[ok]))
    rows = []
    for (suite, alg, scene), chunks in parts.items():
        ate = np.concatenate([a for a, _ in chunks])
        held = np.concatenate([h for _, h in chunks])
        order = np.argsort(ate, kind="stable")
        cr = np.cumsum(held[order]) / total[scene]
        k = np.searchsorted(cr, target - 1e-12)
        rows.append(dict(suite=suite, algorithm=alg, scene=scene, target_cr=target, phi=phi, delta=delta,
                         eps=float(ate[order][k]) if k < len(cr) else np.nan,
                         max_cr=float(cr[-1]) if len(cr) else 0.0))
    return pd.DataFrame(rows, columns=["suite", "algorithm", "scene", "target_cr", "phi", "delta", "eps", "max_cr"])


def rank_stability(scenes: pd.DataFrame, metric: str = "cr", reference: dict | None = None) -> pd.DataFrame:
    """How stable the ranking of algorithms is as eps changes, per scene (and suite, phi, delta, tau):
    Kendall's tau between the ranking at each eps and at the reference eps (default: the paper's
    eps for the scene), and the number of algorithm pairs whose order differs.

    ``scenes`` is a scene aggregate over several eps (:func:`sweep_scenes`).
    """
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
            rows.append(dict(zip(keys, key, strict=True), eps=float(e), reference_eps=float(ref_col),
                             kendall_tau=kt, swapped_pairs=flips, algorithms=int(ok.sum())))
    return pd.DataFrame(rows, columns=keys + ["eps", "reference_eps", "kendall_tau", "swapped_pairs", "algorithms"])


def rank_swaps(scenes: pd.DataFrame, metric: str = "cr") -> pd.DataFrame:
    """Where two algorithms swap rank as eps grows: one row per scene, pair and eps interval in
    which their order of ``metric`` reverses."""
    rows = []
    for (suite, scene, phi, delta, tau), grp in scenes.groupby(["suite", "scene", "phi", "delta", "tau"], sort=False,
                                                               observed=True):
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
                    rows.append(dict(suite=suite, scene=scene, phi=phi, delta=delta, tau=tau,
                                     leader_before=algs[a] if s[k0] > 0 else algs[b],
                                     leader_after=algs[a] if s[k1] > 0 else algs[b],
                                     eps_from=float(eps[k0]), eps_to=float(eps[k1])))
    return pd.DataFrame(rows, columns=["suite", "scene", "phi", "delta", "tau", "leader_before", "leader_after",
                                       "eps_from", "eps_to"])


PAPER_SETTING = dict(eps="paper", phi=PAPER_PHI, delta=1.0, tau=60.0)
