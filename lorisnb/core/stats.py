"""Is a ranking real? Repeated trials, confidence intervals, pairwise tests and robust ranking.

Everything works on per-sequence tables (:func:`lorisnb.core.scoring.score`, or a sweep), one row
per algorithm, scene, sequence and trial. Scene values follow the paper: CR is correct time over
ground-truth time, so a scene's CR is the mean of its sequences' CR weighted by their durations;
CR-T is weighted by tracked time, C-ATE by correct poses, CS-R is a plain mean.

Uncertainty (:func:`confidence_intervals`): the resampled units are the sequences (each holding
the mean over its trials), with ``scipy.stats.bootstrap`` (percentile, seeded); with a single
sequence and several trials, the trials. What this assumes: sequences (and trials) are exchangeable
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
from scipy import stats

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


def trial_summary(table: pd.DataFrame, metrics: Sequence[str] = ("cr", "cr_t", "cs_r", "c_ate_rmse")) -> pd.DataFrame:
    """Per algorithm and scene, each metric's scene value in every trial, summarized over trials:
    mean, median, std (ddof 1), min, max, the number of trials, and the share of trials that
    failed (scene CR = 0, or no sequence matched)."""
    t = with_trials(table)
    _need(t, ["algorithm", "scene", "seq", "matched", *(_metric(m) or m for m in metrics), *metrics])
    per_trial = scene_values(t, metrics, by=GROUP + ["trial"])
    rows = []
    for key, g in per_trial.groupby(GROUP, sort=False, observed=True):
        row = dict(zip(GROUP, key, strict=True), trials=len(g))
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


def _units(g: pd.DataFrame, metric: str) -> tuple[np.ndarray, np.ndarray, str]:
    """Resampling units of one algorithm and scene: (values, weights, 'sequences' or 'trials')."""
    w = _metric(metric)
    g = g.assign(_w=1.0 if w is None else g[w].astype(float))
    if metric == "c_ate_rmse":
        g = g[np.isfinite(g[metric]) & (g["_w"] > 0)]
    if g["seq"].nunique() >= 2 or g["trial"].nunique() < 2:
        per = g.groupby("seq").agg(v=(metric, "mean"), w=("_w", "mean"))
        return per["v"].to_numpy(float), per["w"].to_numpy(float), "sequences"
    return g[metric].to_numpy(float), g["_w"].to_numpy(float), "trials"


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
    """Per algorithm, scene and metric: the scene value (mean over trials of the weighted mean over
    sequences), and a bootstrap confidence interval (``low``, ``high``) at ``level``, with the
    units resampled (``sequences`` or ``trials``) and how many. NaN bounds with a single unit."""
    if not 0 < level < 1:
        raise ValidationError(f"level={level}: expected a confidence level between 0 and 1")
    t = with_trials(table)
    rng = np.random.default_rng(seed)
    rows = []
    for key, g in t.groupby(GROUP, sort=False, observed=True):
        for m in metrics:
            v, w, unit = _units(g, m)
            ok = np.isfinite(v) & np.isfinite(w)
            v, w = v[ok], w[ok]
            value = float(_weighted_mean(v, w)) if len(v) and w.sum() > 0 else np.nan
            low = high = np.nan
            if len(v) >= 2 and np.ptp(v) > 0:
                with warnings.catch_warnings():  # a handful of units: scipy warns, the interval is wide
                    warnings.simplefilter("ignore", stats.DegenerateDataWarning)
                    res = stats.bootstrap(
                        (v, w), _weighted_mean, paired=True, vectorized=True, n_resamples=n_resamples,
                        confidence_level=level, method="percentile", random_state=rng,
                    )  # fmt: skip
                low, high = float(res.confidence_interval.low), float(res.confidence_interval.high)
            elif len(v) >= 2:
                low = high = value
            rows.append(
                dict(zip(GROUP, key, strict=True), metric=m, value=value, low=low, high=high, level=level,
                     unit=unit, units=len(v))
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


def ranking(table: pd.DataFrame, metric: str = "cr", alpha: float = 0.05, seed: int = 0) -> pd.DataFrame:
    """Algorithms of each scene ordered by ``metric``, with ``rank`` = 1 + the number of
    algorithms significantly better (by the sequence test or the trials test of :func:`pairwise`,
    each after Holm's correction), so algorithms the data cannot separate share a rank, and
    ``tied_with`` naming them."""
    better_high = metric != "c_ate_rmse"
    pairs = pairwise(table, metric, alpha=alpha, seed=seed)
    values = scene_values(with_trials(table), [metric], by=["suite", "algorithm", "scene", "trial"])
    mean = values.groupby(["suite", "scene", "algorithm"])[metric].mean()
    rows = []
    for (suite, scene), s in mean.groupby(level=[0, 1], sort=False):
        algs = list(s.index.get_level_values(2))
        p = pairs[(pairs["suite"] == suite) & (pairs["scene"] == scene)]
        for alg in algs:
            beaten = tied = 0
            names = []
            for _, r in p[(p["a"] == alg) | (p["b"] == alg)].iterrows():  # pairs of algorithms, a handful
                other = r["b"] if r["a"] == alg else r["a"]
                mine, theirs = (r["value_a"], r["value_b"]) if r["a"] == alg else (r["value_b"], r["value_a"])
                if not (r["significant"] or r["significant_trials"]):
                    tied += 1
                    names.append(other)
                elif (theirs > mine) == better_high:
                    beaten += 1
            rows.append(dict(suite=suite, scene=scene, metric=metric, algorithm=alg, value=float(s.loc[(suite, scene, alg)]),
                             rank=1 + beaten, tied_with=", ".join(sorted(names))))  # fmt: skip
    out = pd.DataFrame(rows)
    if out.empty:
        return out
    return out.sort_values(["suite", "scene", "rank", "value"], ascending=[True, True, True, not better_high])


def robust_ranking(sweep_table: pd.DataFrame, durations: pd.DataFrame, metric: str = "cr",
                   reference: tuple[float, float] | None = None) -> tuple[pd.DataFrame, pd.DataFrame]:  # fmt: skip
    """Rankings over a grid of thresholds and the trials together, from a sweep
    (:func:`lorisnb.core.sweep.sweep`, eps x phi) of several algorithms.

    Returns:
        first: per scene and algorithm, the share of (eps, phi, trial) cases in which it ranks
            first by the scene ``metric`` (algorithms tied at the top all count as first).
        region: per scene, eps and phi, whether the ranking by the mean over trials equals the
            ranking at ``reference`` (default: the paper's eps for the scene and phi 30 deg), and
            Kendall's tau between the two.
    """
    from .aggregate import aggregate_scenes
    from .frames import PAPER_EPS, PAPER_PHI

    t = with_trials(sweep_table)
    t = t.astype({c: str for c in ("algorithm", "scene", "suite", "file") if c in t.columns})
    if "eps_value" in t.columns:
        t["eps_value"] = t["eps_value"].astype(str)
    scenes = aggregate_scenes(t, durations)
    sign = -1.0 if metric == "c_ate_rmse" else 1.0
    keys = ["suite", "scene", "eps", "phi", "trial"]
    scenes["_score"] = sign * scenes[metric].fillna(-np.inf if sign > 0 else np.inf)
    top = scenes.groupby(keys, sort=False)["_score"].transform("max")
    best = scenes[np.isclose(scenes["_score"], top, rtol=0, atol=1e-12) | (scenes["_score"] == top)]
    cases = scenes.groupby(["suite", "scene"])[keys[2:]].apply(lambda d: len(d.drop_duplicates()))
    first = best.groupby(["suite", "scene", "algorithm"]).size().rename("firsts").reset_index()
    first["cases"] = first.set_index(["suite", "scene"]).index.map(cases).to_numpy()
    first["share_first"] = first["firsts"] / first["cases"]
    mean = scenes.groupby(["suite", "scene", "eps", "phi", "algorithm"])["_score"].mean().reset_index()
    rows = []
    for (suite, scene), g in mean.groupby(["suite", "scene"], sort=False):
        ref_eps, ref_phi = reference if reference is not None else (PAPER_EPS.get(scene, np.nan), PAPER_PHI)
        grid_eps = np.unique(g["eps"].to_numpy(float))
        grid_phi = np.unique(g["phi"].to_numpy(float))
        e0 = grid_eps[np.argmin(np.abs(grid_eps - ref_eps))]
        p0 = grid_phi[np.argmin(np.abs(grid_phi - ref_phi))]
        ref = g[(g["eps"] == e0) & (g["phi"] == p0)].set_index("algorithm")["_score"]
        ref_order = list(ref.sort_values(ascending=False).index)
        for (eps, phi), s in g.groupby(["eps", "phi"], sort=True):
            cur = s.set_index("algorithm")["_score"].reindex(ref.index)
            order = list(cur.sort_values(ascending=False).index)
            kt = stats.kendalltau(ref.to_numpy(), cur.to_numpy()).statistic if len(ref) > 1 else np.nan
            rows.append(dict(suite=suite, scene=scene, eps=float(eps), phi=float(phi), reference_eps=float(e0),
                             reference_phi=float(p0), same_ranking=order == ref_order, kendall_tau=kt))  # fmt: skip
    return first.sort_values(["suite", "scene", "share_first"], ascending=[True, True, False]), pd.DataFrame(rows)
