"""Is a ranking real? Repeated trials, confidence intervals, pairwise tests and robust ranking.

Everything works on per-sequence tables (:func:`lorisnb.core.lifelong.scoring.score`, or a sweep), one row
per algorithm, scene, sequence and trial. Scene values follow the paper: CR is correct time over
ground-truth time, so a scene's CR is the mean of its sequences' CR weighted by their durations;
CR-T is weighted by tracked time, C-ATE by correct poses, CS-R is a plain mean.

Uncertainty (:func:`confidence_intervals`): a percentile bootstrap, seeded. With one trial per
sequence, ``scipy.stats.bootstrap`` over the sequences; with several trials, two levels (the
sequences are redrawn, then the trials within each drawn sequence); with a single sequence and
several trials, over the trials. What this assumes: sequences (and trials) are exchangeable
draws from the conditions the benchmark stands for, and a scene's value is the weighted mean above.
With few sequences the interval is wide, as it should be.

Pairwise comparison (:func:`pairwise`): one test for every pair, the stratified permutation test
of :mod:`lorisnb.core.stats.permutation` on the sequences both algorithms have: within each sequence the
trials of A and B are relabelled, the statistic is the difference of the scene values. With one
trial each it is the paired permutation test over sequences (exact: all 2^n sign flips); with
trials it uses the run-to-run spread of every sequence. Ties need no correction. Holm's correction
over every pair of every scene of the comparison: one family, as the verdict of ``diff``
(:mod:`lorisnb.core.stats.regression`), so a comparison of systems that do not differ claims a
difference anywhere in at most ``alpha`` of the cases (measured by ``make calibrate``). The
smallest p-value the design can give (``min_p``) is stated: n paired sequences cannot go below
2 / 2^n (0.0625 for OpenLORIS' five corridor or home sequences), 3 vs 3 trials of one sequence not
below 0.1. The ranking (:mod:`lorisnb.core.stats.ranking`), the summary of
``compare`` and the bold marks of :mod:`lorisnb.tools.report.tables` all read this one test.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterable, Sequence
from itertools import combinations

import numpy as np
import pandas as pd

from lorisnb.core.lifelong.aggregate import scene_mean
from lorisnb.core.spec import validate
from lorisnb.errors import ValidationError

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


def thresholded(table: pd.DataFrame) -> np.ndarray:
    """Which rows' rates were scored at a finite threshold (``eps`` or ``phi``; rows without those
    columns count as such): at eps = phi = inf a pose is correct whenever it is matched, so CR is the
    share of time with output, which a system that never loses track repeats exactly from run to run
    (honest reruns of one, its ATE varying 11-14 %, were called copies of one run)."""
    finite = np.zeros(len(table), bool)
    for c in ("eps", "phi"):
        if c not in table.columns:
            return np.ones(len(table), bool)
        finite |= np.isfinite(pd.to_numeric(table[c], errors="coerce").to_numpy(float))
    return finite


def trial_spread(table: pd.DataFrame, by: Sequence[str] = ("algorithm",)) -> pd.DataFrame:
    """What varies between trials, per group of ``by`` (columns of the table) with two or more
    trials of a sequence: the median over its sequences of the standard deviation between trials
    of CR (``cr_spread``) and of the log of ATE RMSE (``ate_spread``, about a relative spread),
    ``cr_ties``: the share of its sequences with a CR strictly between 0 and 1, scored at a finite
    threshold (:func:`thresholded`), whose trials all have the very same CR, and ``copies``: both spreads below a quarter of what real reruns show
    (:data:`~lorisnb.core.stats.tolerances.RERUN_SPREAD`), or the CR the same in every trial of most
    such sequences. Such trials are copies of one run (byte-identical, near-identical, or one run's
    tracking with its positions changed: CR is a continuous share of time that real reruns never
    repeat to the last digit, unless it is 0 or 1), not reruns: one run's evidence, however many
    there are. ``compare`` claims no significance for them, and ``diff``'s verdict counts them as
    one run."""
    from lorisnb.core.stats.tolerances import RERUN_SPREAD

    t = with_trials(table)
    keys = ["suite", "algorithm", "scene", "seq"]
    cols = ["cr_spread", "ate_spread", "cr_ties", "copies"]
    if t.empty:
        return pd.DataFrame(columns=[*by, *cols])
    cr = pd.to_numeric(t["cr"], errors="coerce") if "cr" in t else pd.Series(np.nan, t.index)
    ate = pd.to_numeric(t["ate_rmse"], errors="coerce") if "ate_rmse" in t else pd.Series(np.nan, t.index)
    per = pd.DataFrame(
        {"cr": cr, "ate": np.log(ate.where(ate > 0)), "trial": t["trial"], "thresholded": thresholded(t)}
    ).groupby([t[k] for k in keys], sort=False, dropna=False)
    seqs = pd.DataFrame({
        "n": per["trial"].nunique(), "cr": per["cr"].std(), "ate": per["ate"].std(),
        "inside": (per["cr"].min() > 0) & (per["cr"].max() < 1) & per["thresholded"].all(),
        "tied": per["cr"].max() == per["cr"].min(),
    }).reset_index()  # fmt: skip
    rows = []
    for name, g in seqs.groupby(list(by), sort=True, dropna=False):
        if g["n"].max() < 2:
            continue
        cr_s, ate_s = float(g["cr"].median()), float(g["ate"].median())
        inside = g[(g["n"] >= 2) & g["inside"]]
        ties = float(inside["tied"].mean()) if len(inside) else np.nan
        copies = (cr_s < RERUN_SPREAD["rate"] / 4 and ate_s < RERUN_SPREAD["log"] / 4) or bool(ties > 0.5)
        rows.append(dict(zip(by, name if isinstance(name, tuple) else (name,), strict=True), cr_spread=cr_s,
                         ate_spread=ate_s, cr_ties=ties, copies=bool(copies)))  # fmt: skip
    return pd.DataFrame(rows, columns=[*by, *cols])


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
        parts[m] = scene_mean(num.to_numpy(), den.to_numpy())
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
        v = g[metric].to_numpy(float)  # its value is the plain mean of the trials, as with several sequences
        return v[:, None], np.full(len(v), float(g["_w"].mean())), np.ones(len(v), int), "trials"
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
    """The scene value of sequences' values ``v`` and weights ``w`` (the table completed with the
    missing sequences as failed runs): :func:`lorisnb.core.lifelong.aggregate.scene_mean`."""
    with np.errstate(invalid="ignore", over="ignore"):
        return scene_mean(np.sum(v * w, axis=axis), np.sum(w, axis=axis))


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
    seed = validate.seed(seed)
    rows = []
    for key, g in t.groupby(GROUP, sort=False, observed=True):
        for m in metrics:
            rng = np.random.default_rng(seed)  # each interval its own draws: the same data, the same interval
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


def scene_means(table: pd.DataFrame, metric: str) -> pd.DataFrame:
    """Per suite, scene and algorithm: ``value``, the weighted mean over its sequences of each
    sequence's mean over trials (the value :func:`confidence_intervals` and the ranking report)."""
    t = with_trials(table)
    rows = []
    for key, g in t.groupby(GROUP, sort=False, observed=True):
        values, w, _, _ = _units(g, metric)
        seq_means = np.nanmean(values, axis=1) if len(values) else np.zeros(0)
        value = float(_weighted_mean(seq_means, w)) if len(w) and w.sum() > 0 else np.nan
        rows.append(dict(zip(GROUP, key, strict=True), value=value))
    out = pd.DataFrame(rows, columns=GROUP + ["value"])
    return out[["suite", "scene", "algorithm", "value"]]


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


def _sequence_trials(g: pd.DataFrame, metric: str) -> dict[str, tuple[dict[object, np.ndarray], dict[object, float]]]:
    """Per algorithm: (sequence -> the trials' values, sequence -> its weight), finite values only."""
    w_col = _metric(metric)
    out = {}
    for alg, d in g.groupby("algorithm", sort=True, observed=True):
        v = d[metric].to_numpy(float)
        w = np.ones(len(d)) if w_col is None else d[w_col].to_numpy(float)
        ok = np.isfinite(v) & np.isfinite(w) & ((w > 0) if metric == "c_ate_rmse" else True)
        d = d.assign(_v=v, _w=w)[ok]
        out[str(alg)] = (
            {s: x["_v"].to_numpy(float) for s, x in d.groupby("seq", sort=True)},
            {s: float(x["_w"].mean()) for s, x in d.groupby("seq", sort=True)},
        )
    return out


def _cliffs_delta(a: list[np.ndarray], b: list[np.ndarray]) -> float:
    """Cliff's delta within sequences: P(a > b) - P(a < b) over the pairs of trials of each sequence
    (each sequence counts equally); from -1 (B always higher) to 1 (A always higher)."""
    d = [np.mean(np.sign(x[:, None] - y[None, :])) for x, y in zip(a, b, strict=True) if len(x) and len(y)]
    return float(np.mean(d)) if d else np.nan


#: A sampled permutation test draws at least this many relabellings per Holm level it may have to
#: reach (pairs / alpha): its p-value's floor, 1 / (draws + 1), is then a twentieth of alpha / pairs.
RESAMPLES_PER_LEVEL = 20
#: Relabellings a sampled test draws at most (as many as an exact one enumerates at most): beyond
#: about 500 pairs at alpha 0.05 the floor says so (``min_p``, ``reachable``).
MAX_RESAMPLES = 200_000


def pairwise(
    table: pd.DataFrame,
    metric: str = "cr",
    alpha: float = 0.05,
    n_resamples: int = 2000,
    seed: int = 0,
    higher_is_better: bool | None = None,
    intervals: bool = True,
) -> pd.DataFrame:
    """Every pair of algorithms in each scene, on the sequences both have: one stratified
    permutation test (:func:`lorisnb.core.stats.permutation.permutation_test`: trials relabelled within
    each sequence; with one trial each, the paired test over sequences), exact when the
    relabellings are few, else sampled: at least ``n_resamples`` relabellings and
    :data:`RESAMPLES_PER_LEVEL` x pairs / alpha (at most :data:`MAX_RESAMPLES`), the same for every
    pair (the number depends on the design only).

    Columns: the scene values (``value_a``, ``value_b``: weighted means over the common sequences
    of each sequence's mean over trials), ``difference`` (A - B, the test statistic, in the
    metric's unit), ``cliffs_delta`` (effect size, -1..1), ``p`` (two-sided), ``min_p`` (the
    smallest p the test can give: the design's, or a sampled test's 1 / (draws + 1) where larger), ``exact``, ``p_holm`` (Holm over every pair of every scene),
    ``significant`` (p_holm <= alpha), ``better`` (the significantly better algorithm, or ""),
    ``reachable`` (whether min_p, Holm-corrected as if it were the comparison's smallest p, can
    reach alpha), ``difference_low``, ``difference_high`` (with ``intervals``: the interval of the
    difference that inverts the same test at the level Holm decided it at, ``interval_level``; it
    holds 0 exactly when the pair is not significant) and ``p_a_better`` (bootstrap probability
    that A is better, descriptive)."""
    from lorisnb.core.stats.permutation import difference_interval, holm_levels, permutation_test

    better_high = (metric != "c_ate_rmse") if higher_is_better is None else higher_is_better
    t = with_trials(table)
    _need(t, ["algorithm", "scene", "seq", metric] + ([_metric(metric) or metric]))
    seed = validate.seed(seed)
    alpha = validate.probability("alpha", alpha)
    rng = np.random.default_rng(seed)
    rows: list[dict] = []
    tested: list[tuple] = []
    scenes_trials = [(key, _sequence_trials(g, metric))
                     for key, g in t.groupby(["suite", "scene"], sort=False, observed=True)]  # fmt: skip
    # a sampled test's p cannot go below 1 / (resamples + 1): enough of them that Holm's smallest level over the
    # family (alpha / pairs) is within reach (2,000 for any family held p_holm above 0.05 past 100 pairs)
    family = sum(len(per) * (len(per) - 1) // 2 for _, per in scenes_trials)
    resamples = min(max(n_resamples, 2000, math.ceil(RESAMPLES_PER_LEVEL * family / alpha)), MAX_RESAMPLES)
    for (suite, scene), per in scenes_trials:
        scene_rows, samples = [], []
        for a, b in combinations(sorted(per), 2):
            (va, wa), (vb, wb) = per[a], per[b]
            common = sorted(set(va) & set(vb), key=str)
            xa, xb = [va[s] for s in common], [vb[s] for s in common]
            w = np.array([(wa[s] + wb[s]) / 2 for s in common])
            res = permutation_test(xa, xb, w, n_resamples=resamples, rng=rng)
            samples.append((xa, xb, w))
            ma = np.array([x.mean() for x in xa])
            mb = np.array([x.mean() for x in xb])
            mean_a = float(_weighted_mean(ma, np.array([wa[s] for s in common]))) if common else np.nan
            mean_b = float(_weighted_mean(mb, np.array([wb[s] for s in common]))) if common else np.nan
            p_better = np.nan
            if len(common) >= 2:
                idx = rng.integers(0, len(common), size=(n_resamples, len(common)))
                diff = _weighted_mean(ma[idx], w[idx]) - _weighted_mean(mb[idx], w[idx])
                diff = diff if better_high else -diff
                p_better = float(np.mean(diff > 0) + 0.5 * np.mean(diff == 0))
            trials = max([len(x) for x in xa + xb], default=0)
            scene_rows.append(
                dict(suite=suite, scene=scene, metric=metric, a=a, b=b, sequences=len(common),
                     trials_a=max([len(x) for x in xa], default=0), trials_b=max([len(x) for x in xb], default=0),
                     value_a=mean_a, value_b=mean_b, difference=res.statistic, cliffs_delta=_cliffs_delta(xa, xb),
                     test=("paired permutation over sequences" if trials <= 1 else
                           "permutation of trials within sequences"),
                     relabellings=res.relabellings, exact=res.exact, p=res.pvalue,
                     min_p=res.min_p if res.exact else max(res.min_p, 1 / (resamples + 1)),
                     p_a_better=p_better)
            )  # fmt: skip
        rows += scene_rows
        tested += samples
    # one family: every pair of every scene of the call (the whole comparison), as diff's verdict
    adj = holm(np.array([r["p"] for r in rows]))
    levels = holm_levels(np.array([r["p"] for r in rows]), alpha)
    scenes = len({(r["suite"], r["scene"]) for r in rows})
    for r, pa, level, (xa, xb, w) in zip(rows, adj, levels, tested, strict=True):
        sig = bool(np.isfinite(pa) and pa <= alpha)
        low, high = (difference_interval(xa, xb, w, level, n_resamples=1000, seed=seed, iterations=20, rejected=sig)
                     if intervals and np.isfinite(level) else (np.nan, np.nan))  # fmt: skip
        r.update(difference_low=low, difference_high=high, interval_level=1 - level)
        a_wins = (r["difference"] > 0) == better_high
        r.update(p_holm=pa, significant=sig, better=(r["a"] if a_wins else r["b"]) if sig else "",
                 reachable=bool(np.isfinite(r["min_p"]) and r["min_p"] * len(rows) <= alpha),
                 correction=f"Holm over {len(rows)} pair(s) of {scenes} scene(s), alpha {alpha}")  # fmt: skip
    cols = ["suite", "scene", "metric", "a", "b", "sequences", "trials_a", "trials_b", "value_a", "value_b",
            "difference", "difference_low", "difference_high", "interval_level", "cliffs_delta", "test", "relabellings",
            "exact", "p", "min_p", "p_holm", "significant", "better", "reachable", "p_a_better", "correction"]  # fmt: skip
    return pd.DataFrame(rows, columns=cols)
