"""Is a ranking real? Repeated trials, confidence intervals, pairwise tests and robust ranking.

Everything works on per-sequence tables (:func:`lorisnb.core.scoring.score`, or a sweep), one row
per algorithm, scene, sequence and trial. Scene values follow the paper: CR is correct time over
ground-truth time, so a scene's CR is the mean of its sequences' CR weighted by their durations;
CR-T is weighted by tracked time, C-ATE by correct poses, CS-R is a plain mean.

Uncertainty (:func:`confidence_intervals`): a percentile bootstrap, seeded. With one trial per
sequence, ``scipy.stats.bootstrap`` over the sequences; with several trials, two levels (the
sequences are redrawn, then the trials within each drawn sequence); with a single sequence and
several trials, over the trials. What this assumes: sequences (and trials) are exchangeable
draws from the conditions the benchmark stands for, and a scene's value is the weighted mean above.
With few sequences the interval is wide, as it should be.

Pairwise comparison (:func:`pairwise`): on the sequences both algorithms have, the bootstrap
probability that A's scene value exceeds B's (sequences resampled in pairs), and a Wilcoxon
signed-rank test of the per-sequence differences (``scipy.stats.wilcoxon``, two-sided), with
Holm's correction over the pairs of a scene. It assumes pairs are independent across sequences
and differences symmetric about their median under the null. With n sequences its smallest
possible p-value is 2 / 2^n (0.0625 for OpenLORIS' five corridor or home sequences), so a scene
with five sequences or fewer can never show a significant difference: ``min_p`` says so. With
three or more trials of each algorithm, ``trials_p`` adds a Mann-Whitney U test of the per-trial
scene values (run-to-run spread; trials assumed independent), also Holm-corrected.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable, Sequence
from itertools import combinations

import numpy as np
import pandas as pd

from ..errors import ValidationError

#: Scene metrics and the per-sequence weight of each (None: a plain mean).
WEIGHTS: dict[str, str | None] = {"cr": "gt_duration", "cr_t": "track_time", "c_ate_rmse": "c_matched", "cs_r": None}
GROUP = ["suite", "algorithm", "scene"]


def _need(table: pd.DataFrame, columns: Iterable[str]) -> None:
    missing = [c for c in columns if c not in table.columns]
    if missing:
        raise ValidationError(f"the table lacks column(s) {', '.join(missing)}; expected a per-sequence table (score)")


def _metric(metric: str) -> str | None:
    if metric not in WEIGHTS:
        raise ValidationError(f"metric={metric}: expected one of {', '.join(WEIGHTS)}")
    return WEIGHTS[metric]


def with_trials(table: pd.DataFrame) -> pd.DataFrame:
    """The table with a ``trial`` column (0 where it has none) and a ``suite`` column."""
    out = table.copy()
    if "trial" not in out.columns:
        out["trial"] = 0
    if "suite" not in out.columns:
        out["suite"] = ""
    return out


def trial_summary(
    table: pd.DataFrame, metrics: Sequence[str] = ("cr", "cr_t", "cs_r", "c_ate_rmse"), level: str = "scene"
) -> pd.DataFrame:
    """Each metric summarized over trials: mean, median, std (ddof 1), min, max, the number of
    trials, and the share of trials that failed (CR = 0, or nothing matched). ``level="scene"``:
    per algorithm and scene, of the scene value of each trial; ``level="sequence"``: per
    algorithm, scene and sequence, of the sequence's values."""
    t = with_trials(table)
    _need(t, ["algorithm", "scene", "seq", "matched", *(_metric(m) or m for m in metrics), *metrics])
    if level == "scene":
        per_trial, group = scene_values(t, metrics, by=GROUP + ["trial"]), GROUP
    elif level == "sequence":
        per_trial, group = t, GROUP + ["seq"]
    else:
        raise ValidationError(f"level={level}: expected 'scene' or 'sequence'")
    rows = []
    for key, g in per_trial.groupby(group, sort=False, observed=True):
        row = dict(zip(group, key, strict=True), trials=len(g))
        row["failed_share"] = float(((g["cr"] <= 0) | (g["matched"] == 0)).mean()) if "cr" in g else np.nan
        for m in metrics:
            v = g[m].to_numpy(float)
            row.update(
                {
                    f"{m}_mean": np.nanmean(v) if np.isfinite(v).any() else np.nan,
                    f"{m}_median": np.nanmedian(v) if np.isfinite(v).any() else np.nan,
                    f"{m}_std": np.nanstd(v, ddof=1) if np.isfinite(v).sum() > 1 else np.nan,
                    f"{m}_min": np.nanmin(v) if np.isfinite(v).any() else np.nan,
                    f"{m}_max": np.nanmax(v) if np.isfinite(v).any() else np.nan,
                }
            )
        rows.append(row)
    return pd.DataFrame(rows)


def scene_values(table: pd.DataFrame, metrics: Sequence[str], by: Sequence[str]) -> pd.DataFrame:
    """Weighted scene values of ``metrics`` (see the module docstring) per group ``by``, with the
    number of sequences and matched poses."""
    t = with_trials(table)
    parts = {}
    for m in metrics:
        w = _metric(m)
        v = t[m].to_numpy(float)
        wt = np.ones(len(t)) if w is None else t[w].to_numpy(float)
        ok = np.isfinite(v) & (wt > 0) if m == "c_ate_rmse" else np.isfinite(v)
        num = pd.Series(np.where(ok, v * wt, 0.0)).groupby([t[c].to_numpy() for c in by]).sum()
        den = pd.Series(np.where(ok, wt, 0.0)).groupby([t[c].to_numpy() for c in by]).sum()
        parts[m] = (num / den.where(den > 0)).to_numpy()
        index = num.index
    out = pd.DataFrame(parts, index=index).reset_index()
    out.columns = list(by) + list(metrics)
    counts = t.groupby(list(by), sort=False, observed=True).agg(
        sequences=("seq", "nunique"), matched=("matched", "sum")
    )
    return out.merge(counts.reset_index(), on=list(by))


def _units(g: pd.DataFrame, metric: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, str]:
    """Resampling units of one algorithm and scene: (values (S, K) with NaN padding, weights (S,),
    trial counts (S,), 'sequences', 'sequences x trials' or 'trials')."""
    w = _metric(metric)
    g = g.assign(_w=1.0 if w is None else g[w].astype(float))
    g = g[np.isfinite(g[metric].astype(float)) & np.isfinite(g["_w"])]
    if metric == "c_ate_rmse":
        g = g[g["_w"] > 0]
    if g.empty:
        return np.zeros((0, 1)), np.zeros(0), np.zeros(0, int), "sequences"
    if g["seq"].nunique() < 2 and g["trial"].nunique() >= 2:  # one sequence, several runs
        v = g[metric].to_numpy(float)
        return v[:, None], g["_w"].to_numpy(float), np.ones(len(v), int), "trials"
    per = [(d[metric].to_numpy(float), float(d["_w"].mean())) for _, d in g.groupby("seq", sort=True)]
    k = max(len(v) for v, _ in per)
    values = np.full((len(per), k), np.nan)
    for i, (v, _) in enumerate(per):
        values[i, : len(v)] = v
    counts = np.array([len(v) for v, _ in per])
    unit = "sequences x trials" if k > 1 else "sequences"
    return values, np.array([w for _, w in per]), counts, unit


def _nested_resample(values: np.ndarray, weights: np.ndarray, counts: np.ndarray, n: int, rng: np.random.Generator
                     ) -> np.ndarray:  # fmt: skip
    """Two-level bootstrap: n redraws of the sequences, and within each drawn sequence of its
    trials, all vectorized; returns the n weighted means."""
    S, K = values.shape
    seq = rng.integers(0, S, size=(n, S))
    trial = np.floor(rng.random((n, S, K)) * counts[seq][:, :, None]).astype(int)
    drawn = values[seq[:, :, None], trial]  # (n, S, K): trial k of each drawn sequence
    keep = np.arange(K)[None, None, :] < counts[seq][:, :, None]
    means = np.where(keep, drawn, 0.0).sum(axis=2) / counts[seq]
    return _weighted_mean(means, weights[seq])


def _weighted_mean(v: np.ndarray, w: np.ndarray, axis: int = -1) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.sum(v * w, axis=axis) / np.sum(w, axis=axis)


def confidence_intervals(
    table: pd.DataFrame,
    metrics: Sequence[str] = ("cr", "cr_t", "cs_r", "c_ate_rmse"),
    level: float = 0.95,
    n_resamples: int = 2000,
    seed: int = 0,
) -> pd.DataFrame:
    """Per algorithm, scene and metric: the scene value (the weighted mean over sequences of each
    sequence's mean over trials), and a bootstrap confidence interval (``low``, ``high``) at
    ``level``, with what was resampled (``sequences``, ``sequences x trials`` or ``trials``), how
    many units and the most trials of a sequence. NaN bounds with a single unit."""
    from scipy import stats  # here, not at the top: scipy.stats takes half a second to import

    if not 0 < level < 1:
        raise ValidationError(f"level={level}: expected a confidence level between 0 and 1")
    t = with_trials(table)
    rng = np.random.default_rng(seed)
    rows = []
    for key, g in t.groupby(GROUP, sort=False, observed=True):
        for m in metrics:
            values, w, counts, unit = _units(g, m)
            seq_means = np.nanmean(values, axis=1) if len(values) else np.zeros(0)
            value = float(_weighted_mean(seq_means, w)) if len(w) and w.sum() > 0 else np.nan
            low = high = np.nan
            if len(w) >= 2 and np.nanmax(values) > np.nanmin(values):
                if values.shape[1] == 1:  # one value per unit: scipy's bootstrap over the units
                    with warnings.catch_warnings():  # a handful of units: scipy warns, the interval is wide
                        warnings.simplefilter("ignore", stats.DegenerateDataWarning)
                        res = stats.bootstrap(
                            (values[:, 0], w), _weighted_mean, paired=True, vectorized=True,
                            n_resamples=n_resamples, confidence_level=level, method="percentile", random_state=rng,
                        )  # fmt: skip
                    low, high = float(res.confidence_interval.low), float(res.confidence_interval.high)
                else:  # several trials: sequences, then trials within each (two levels)
                    boot = _nested_resample(values, w, counts, n_resamples, rng)
                    low, high = (float(q) for q in np.nanquantile(boot, [(1 - level) / 2, (1 + level) / 2]))
            elif len(w) >= 2:
                low = high = value
            rows.append(
                dict(zip(GROUP, key, strict=True), metric=m, value=value, low=low, high=high, level=level,
                     unit=unit, units=len(w), trials=int(counts.max()) if len(counts) else 0)
            )  # fmt: skip
    return pd.DataFrame(rows)


def holm(p: np.ndarray) -> np.ndarray:
    """Holm's step-down correction of p-values (family-wise error rate)."""
    p = np.asarray(p, float)
    out = np.full(p.shape, np.nan)
    ok = np.flatnonzero(np.isfinite(p))
    if ok.size == 0:
        return out
    order = ok[np.argsort(p[ok])]
    m = order.size
    adj = np.minimum(1.0, np.maximum.accumulate((m - np.arange(m)) * p[order]))
    out[order] = adj
    return out


def pairwise(
    table: pd.DataFrame,
    metric: str = "cr",
    alpha: float = 0.05,
    n_resamples: int = 2000,
    seed: int = 0,
    higher_is_better: bool | None = None,
) -> pd.DataFrame:
    """Every pair of algorithms in each scene, on the sequences both have (trial means): the scene
    values, ``p_a_better`` (bootstrap probability that A is better), the Wilcoxon signed-rank
    p-value of the per-sequence differences, the Holm-corrected p-value over the scene's pairs,
    and whether the difference is significant at ``alpha`` after correction."""
    from scipy import stats  # here, not at the top: scipy.stats takes half a second to import

    better_high = (metric != "c_ate_rmse") if higher_is_better is None else higher_is_better
    w_col = _metric(metric)
    t = with_trials(table)
    rng = np.random.default_rng(seed)
    rows = []
    for (suite, scene), g in t.groupby(["suite", "scene"], sort=False, observed=True):
        means = g.groupby(["algorithm", "seq"]).agg(
            v=(metric, "mean"), w=(w_col, "mean") if w_col else (metric, "size")
        )
        if w_col is None:
            means["w"] = 1.0
        algs = sorted(means.index.get_level_values(0).unique())
        trial_values = scene_values(g, [metric], by=["algorithm", "trial"])
        per_trial = {k: d[metric].to_numpy(float) for k, d in trial_values.groupby("algorithm")}
        scene_rows = []
        for a, b in combinations(algs, 2):
            both = pd.merge(
                means.loc[a], means.loc[b], left_index=True, right_index=True, suffixes=("_a", "_b")
            ).dropna()
            n = len(both)
            va, vb = both["v_a"].to_numpy(), both["v_b"].to_numpy()
            wa, wb = both["w_a"].to_numpy(), both["w_b"].to_numpy()
            mean_a = float(_weighted_mean(va, wa)) if n else np.nan
            mean_b = float(_weighted_mean(vb, wb)) if n else np.nan
            p_better, p_w = np.nan, np.nan
            if n >= 2:
                idx = rng.integers(0, n, size=(n_resamples, n))
                diff = _weighted_mean(va[idx], wa[idx]) - _weighted_mean(vb[idx], wb[idx])
                diff = diff if better_high else -diff
                p_better = float(np.mean(diff > 0) + 0.5 * np.mean(diff == 0))
                d = va - vb
                if np.any(d != 0):
                    p_w = float(stats.wilcoxon(va, vb, zero_method="zsplit").pvalue)
                else:
                    p_w = 1.0
            ta, tb = per_trial.get(a, np.zeros(0)), per_trial.get(b, np.zeros(0))
            p_t = np.nan
            if len(ta) >= 3 and len(tb) >= 3:
                p_t = 1.0 if np.ptp(np.concatenate([ta, tb])) == 0 else float(stats.mannwhitneyu(ta, tb).pvalue)
            scene_rows.append(
                dict(suite=suite, scene=scene, metric=metric, a=a, b=b, sequences=n, value_a=mean_a, value_b=mean_b,
                     p_a_better=p_better, wilcoxon_p=p_w, min_p=2.0 / 2**n if n else np.nan, trials_a=len(ta),
                     trials_b=len(tb), trials_p=p_t)
            )  # fmt: skip
        if scene_rows:
            adj = holm(np.array([r["wilcoxon_p"] for r in scene_rows]))
            adj_t = holm(np.array([r["trials_p"] for r in scene_rows]))
            for r, pa, pt in zip(scene_rows, adj, adj_t, strict=True):
                r.update(p_holm=pa, significant=bool(pa <= alpha) if np.isfinite(pa) else False, trials_p_holm=pt,
                         significant_trials=bool(pt <= alpha) if np.isfinite(pt) else False,
                         correction=f"Holm over {len(scene_rows)} pair(s) of this scene, alpha {alpha}")  # fmt: skip
        rows += scene_rows
    cols = ["suite", "scene", "metric", "a", "b", "sequences", "value_a", "value_b", "p_a_better", "wilcoxon_p",
            "min_p", "p_holm", "significant", "trials_a", "trials_b", "trials_p", "trials_p_holm", "significant_trials",
            "correction"]  # fmt: skip
    return pd.DataFrame(rows, columns=cols)
