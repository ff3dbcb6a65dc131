"""What ``lorisnb compare`` computes and writes: coverage made explicit, intervals, one permutation
test for the pairs, the ranking and the bold marks from that test, and the tables."""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from lorisnb.core.lifelong.coverage import complete, coverage_notes
from lorisnb.core.metrics.openloris import RATES
from lorisnb.core.spec import validate
from lorisnb.core.stats import inference as stats
from lorisnb.core.stats import ranking
from lorisnb.core.stats.power import runs_for_power
from lorisnb.core.stats.tolerances import RERUN_SPREAD
from lorisnb.core.stats.trials import check_duplicates
from lorisnb.errors import ValidationError
from lorisnb.io.writers import write_csv
from lorisnb.tools.decisions.escape import clean
from lorisnb.tools.report.tables import interval, write_comparison


@dataclass
class Comparison:
    """``algorithms``: one row per suite, scene and algorithm (value, interval, coverage, rank,
    p-value and effect against the scene's top algorithm); ``pairs``: the pairwise test;
    ``significant``: its significant rows; ``ci``: intervals of every metric; ``coverage``;
    ``power`` (with a power delta) and ``power_note``, why it sizes no pair; ``header``,
    ``summary``: what the command prints (names in them escaped,
    :func:`~lorisnb.tools.decisions.escape.clean`); ``notes``: warnings (missing sequences)."""

    algorithms: pd.DataFrame
    pairs: pd.DataFrame
    significant: pd.DataFrame
    ci: pd.DataFrame
    coverage: pd.DataFrame
    power: pd.DataFrame | None
    header: str
    summary: str
    notes: list[str]
    #: why ``power`` sizes no pair, where it sizes none ("" otherwise, or without a power delta)
    power_note: str = ""
    #: the trials some algorithm lacks (a whole trial, or a trial of a sequence), each counted as a
    #: failed run: ``"B mix trial 3"``; ``compare`` exits 1 when any (:attr:`~lorisnb.tools.decisions.comparison.Comparison.exit_status`)
    lacking: tuple[str, ...] = ()

    @property
    def exit_status(self) -> int:
        """1 when a trial is missing (counted as a failed run, :attr:`lacking`), else 0: a crashed
        trial changes the scores, as a missing sequence of a declared session does."""
        return 1 if self.lacking else 0


def check_table_duplicates(table: pd.DataFrame) -> None:
    """Several files for one sequence and trial in a per-sequence table are an error (see
    :func:`lorisnb.core.stats.trials.check_duplicates`)."""
    t = stats.with_trials(table)
    if "file" not in t.columns or t.empty:
        return
    keys = [
        (str(f), (su, a, sc, int(tr)), tuple(g["seq"]))
        for (f, su, a, sc, tr), g in t.groupby(["file", "suite", "algorithm", "scene", "trial"], sort=False)
    ]
    check_duplicates(keys)


def _bound(v: float) -> str:
    return "n/a" if not np.isfinite(v) and not np.isinf(v) else ("-inf" if v == -np.inf else "inf" if v == np.inf
                                                                  else _signed(v))  # fmt: skip


def _signed(v: float) -> str:
    """``v`` to three decimals with its sign, ``+0.000`` for what rounds to zero (not ``-0.000``)."""
    return f"{round(float(v), 3) + 0.0:+.3f}"


def _versus_top(rank: pd.DataFrame, pairs: pd.DataFrame) -> pd.DataFrame:
    """Each algorithm against the top-ranked algorithm of its scene (best value among rank 1)."""
    out = []
    for (suite, scene), r in rank.groupby(["suite", "scene"], sort=False):
        top = r.iloc[0]["algorithm"]  # ranking sorts by rank, then value
        p = pairs[(pairs["suite"] == suite) & (pairs["scene"] == scene)]
        for alg in r["algorithm"]:
            row = dict(suite=suite, scene=scene, algorithm=alg, top=top, difference_vs_top=np.nan,
                       difference_low_vs_top=np.nan, difference_high_vs_top=np.nan, cliffs_delta_vs_top=np.nan,
                       p_vs_top=np.nan, p_holm_vs_top=np.nan, min_p_vs_top=np.nan)  # fmt: skip
            hit = p[((p["a"] == alg) & (p["b"] == top)) | ((p["a"] == top) & (p["b"] == alg))]
            if alg != top and len(hit):
                h = hit.iloc[0]
                sign = 1.0 if h["a"] == alg else -1.0
                low, high = (h["difference_low"], h["difference_high"])
                row.update(difference_vs_top=sign * h["difference"], cliffs_delta_vs_top=sign * h["cliffs_delta"],
                           difference_low_vs_top=low if sign > 0 else -high,
                           difference_high_vs_top=high if sign > 0 else -low,
                           p_vs_top=h["p"], p_holm_vs_top=h["p_holm"], min_p_vs_top=h["min_p"])  # fmt: skip
            out.append(row)
    return pd.DataFrame(out)


def trial_spread(table: pd.DataFrame) -> tuple[pd.DataFrame, set[str]]:
    """What varies between trials: per algorithm with trials, the median over its sequences of the
    standard deviation of CR between trials and of the log of ATE RMSE (about a relative spread),
    and the algorithms whose trials are **near-identical copies**: both spreads below a quarter of
    real rerun spreads, or a CR strictly between 0 and 1 repeated to the last digit by every trial
    of most sequences (:func:`lorisnb.core.stats.inference.trial_spread`, as ``diff``'s verdict)."""
    spread = stats.trial_spread(table)
    copies = set(spread.loc[spread["copies"].astype(bool), "algorithm"])
    return spread.drop(columns=["copies"]).reset_index(drop=True), copies


#: Two trials' rows of a sequence whose every judged value is within a trace of noise of each other
#: (:func:`near_copies`): rates within this much (a handful of poses of a sequence flipping at the
#: threshold: one pose at 30 Hz in 100 s moves CR by 3e-4) ...
NEAR_RATE = 1e-3
#: ... and errors within this relative difference; real reruns differ by a median 0.017 in CR and
#: 18 % in ATE (:data:`~lorisnb.core.stats.tolerances.RERUN_SPREAD`), so two reruns rarely agree
#: within both on every value of a sequence.
NEAR_ERROR = 0.01


def near_copies(table: pd.DataFrame) -> np.ndarray:
    """Which rows of a per-sequence table repeat an earlier trial's row of the same sequence within a
    trace of noise: the same number of matched poses (noise added to a copy's positions keeps its
    stamps; a rerun's dropouts and start differ), and every judged value
    (:data:`~lorisnb.core.stats.regression.METRICS`) of a row with output, rates within
    :data:`NEAR_RATE`, errors within :data:`NEAR_ERROR` relative (NaN as NaN). Copies of a rerun
    whose errors moved by 0.2 % and CR by up to 1e-3 (a script adding noise) beside one real rerun
    made two labels of one system differ in 14 of 20 of a helper's nights; the every-value rule
    within 1e-4 (:func:`~lorisnb.core.stats.regression.repeated_trials`) let them pass. (Without the
    matched poses, an odometry's reruns, whose ATE varies little, were taken for copies now and then.)"""
    from lorisnb.core.stats.regression import KEYS, METRICS

    t = stats.with_trials(table)
    rates = [c for c in METRICS if c in t.columns and c in RATES]
    errors = [c for c in METRICS if c in t.columns and c not in RATES]
    r = np.column_stack([pd.to_numeric(t[c], errors="coerce").to_numpy(float) for c in rates]) if rates else None
    with np.errstate(divide="ignore", invalid="ignore"):
        e = (np.column_stack([np.log(pd.to_numeric(t[c], errors="coerce").to_numpy(float)) for c in errors])
             if errors else None)  # fmt: skip
    matched = pd.to_numeric(t["matched"], errors="coerce").to_numpy(float) if "matched" in t else None
    out = matched > 0 if matched is not None else np.ones(len(t), bool)
    near = np.zeros(len(t), bool)
    for idx in t.groupby(KEYS, sort=False, observed=True, dropna=False).indices.values():
        idx = idx[out[idx]]  # a handful of trials a sequence: every pair of them at once
        if len(idx) < 2:
            continue
        same = np.tri(len(idx), k=-1, dtype=bool)  # an earlier row only
        if matched is not None:  # the same poses matched: noise added to a copy keeps them, a rerun's differ
            same &= matched[idx][:, None] == matched[idx][None, :]
        for values, tol in ((r, NEAR_RATE), (e, NEAR_ERROR)):
            if values is not None:
                v = values[idx]
                with np.errstate(invalid="ignore"):
                    close = (np.abs(v[:, None, :] - v[None, :, :]) <= tol) | (
                        np.isnan(v[:, None, :]) & np.isnan(v[None, :, :])
                    )
                    close |= v[:, None, :] == v[None, :, :]  # the same infinite value
                same &= close.all(axis=2)
        near[idx] = same.any(axis=1)
    return near


def _tested_values(full: pd.DataFrame, metric: str) -> tuple[np.ndarray, np.ndarray]:
    """The tested metric's values of ``full`` (the log for C-ATE, whose spread is relative) and
    which of them can tell a copy by their spread: a rate strictly between 0 and 1 scored at a
    finite threshold (reruns tie at 0 and 1, and at eps = phi = inf CR is the share of time with
    output, which a system that never loses track repeats: :func:`~lorisnb.core.stats.inference.thresholded`),
    an error above 0."""
    v = pd.to_numeric(full[metric], errors="coerce").to_numpy(float)
    if metric in RATES:
        return v, (v > 0) & (v < 1) & stats.thresholded(full)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.log(v), np.isfinite(v) & (v > 0)


def _without_repeated_trials(table: pd.DataFrame, full: pd.DataFrame) -> tuple[pd.DataFrame, dict]:
    """``full`` without the rows of a trial that repeat another trial's row of the same sequence,
    every value within 1e-4 (:func:`lorisnb.core.stats.regression.repeated_trials`, as ``diff``
    counts them) or within a trace of noise (:func:`near_copies`). Returns the table and, per
    algorithm, (rows dropped, rows); an algorithm whose trials are all near-identical copies of one
    run (:func:`trial_spread` of ``table``) keeps them: none of its pairs is tested."""
    from lorisnb.core.stats.regression import repeated_trials

    t = stats.with_trials(full)
    rep = repeated_trials(t) | near_copies(t)
    rep &= ~full["algorithm"].isin(trial_spread(table)[1]).to_numpy()
    if not rep.any():
        return full, {}
    total = full["algorithm"].value_counts()
    counted = {a: (int(n), int(total[a])) for a, n in full.loc[rep, "algorithm"].value_counts().sort_index().items()}
    return full[~rep], counted


def prepared_table(
    table: pd.DataFrame, durations: pd.DataFrame, lost: Iterable[tuple[str, str, int]] = ()
) -> tuple[pd.DataFrame, pd.DataFrame, dict[str, tuple[int, int]]]:
    """What ``compare`` tests, from a per-sequence table and the scenes' durations: every expected
    sequence and trial (missing ones as failed runs, :func:`~lorisnb.core.lifelong.coverage.complete`
    with ``peers``: an algorithm with fewer trials than another of its scene lacks some), the
    trials that repeat another's counted once (:func:`_without_repeated_trials`, whatever
    metric is tested); with the coverage and the counts of repeated rows. ``lost``: runs known to
    have left no output (:func:`~lorisnb.core.lifelong.coverage.complete`). ``compare_table`` and
    ``make calibrate`` both use it."""
    full, cover = complete(
        table, durations, peers=True, lost=lost
    )  # the trials of the comparison's algorithms expected
    full, counted = _without_repeated_trials(table, full)
    return full, cover, counted


def metric_copies(full: pd.DataFrame, metric: str) -> dict[str, float]:
    """The algorithms whose distinct trials (``full`` without repeated rows) vary in the tested
    ``metric`` by less than a quarter of what real reruns show (:data:`RERUN_SPREAD`: CR 0.017, the
    log of an error 0.19), median over the sequences with two or more trials and a value that can
    tell a copy (:func:`_tested_values`), with that spread. The test sees only that metric: a
    realistic ATE spread beside a CR no rerun repeats (four copies of one run, positions scaled, one
    pose dropped from one: CR spread 0.0002) licensed a CR test at p 0.0005."""
    t = stats.with_trials(full)
    values, telling = _tested_values(t, metric)
    t = t.assign(_v=values)[telling]
    if t.empty:
        return {}
    per = t.groupby(["suite", "algorithm", "scene", "seq"], sort=False, observed=True)["_v"]
    seqs = pd.DataFrame({"n": per.size(), "sd": per.std()}).reset_index()
    seqs = seqs[seqs["n"] >= 2]
    quarter = RERUN_SPREAD["rate" if metric in RATES else "log"] / 4
    spread = seqs.groupby("algorithm", sort=True)["sd"].median()
    return {str(a): float(v) for a, v in spread.items() if v < quarter}


#: The ``test`` of a pair one of whose algorithms' trials are copies of one run: none is made.
COPIES_TEST = "none: trials are copies of one run"


def decide(table: pd.DataFrame, full: pd.DataFrame, metric: str, alpha: float, seed: int, intervals: bool = True
           ) -> tuple[pd.DataFrame, pd.DataFrame, set[str]]:  # fmt: skip
    """The decision of ``compare``: the pairwise test on ``full`` (the table with missing sequences
    as failed runs, :func:`lorisnb.core.lifelong.coverage.complete`), no significance for the pairs
    of an algorithm whose trials are near-identical copies (:func:`trial_spread` of ``table``).
    Returns the pairs, the trial spread and those algorithms. ``intervals=False`` skips the test
    intervals (the decision is the same): what ``make calibrate`` measures."""
    pairs = stats.pairwise(full, metric, alpha=alpha, seed=seed, intervals=intervals)
    spread, copies = trial_spread(table)
    copies |= set(metric_copies(full, metric))
    if copies:  # pseudo-replicates: their test would claim a significance that reruns would not show, so no
        # test is reported for their pairs (no p-value; an interval of the difference that excludes nothing), and
        # the CSV, the terminal's intervals and the ranks say the same
        mask = pairs["a"].isin(copies) | pairs["b"].isin(copies)
        pairs.loc[mask, "significant"] = False
        pairs.loc[mask, "better"] = ""
        pairs.loc[mask, ["p", "p_holm", "p_a_better"]] = np.nan
        pairs.loc[mask, "difference_low"] = -np.inf
        pairs.loc[mask, "difference_high"] = np.inf
        pairs.loc[mask, "test"] = COPIES_TEST
        # no test was made: nothing it could reach (the design's floor and relabellings were of a test of copies)
        pairs["exact"] = pairs["exact"].astype(object)
        pairs.loc[mask, "reachable"] = False
        pairs.loc[mask, ["min_p", "relabellings", "exact", "interval_level"]] = np.nan
    return pairs, spread, copies


def compare_table(
    table: pd.DataFrame,
    durations: pd.DataFrame,
    metric: str = "cr",
    level: float = 0.95,
    alpha: float = 0.05,
    seed: int = 0,
    power_delta: float | None = None,
    lost: Iterable[tuple[str, str, int]] = (),
) -> Comparison:
    """Everything ``compare`` shows, from a per-sequence table and the ground-truth durations of its
    scenes (the sequences every algorithm is expected to have). ``lost``: (suite, algorithm, trial)
    of runs that left no output, each a failed run of every sequence: the ``trials`` of the
    evaluation's failures (an empty trial folder), ``[t for f in ev.failures for t in f.trials]``."""
    for name, value in (("table", table), ("durations", durations)):
        if not isinstance(value, pd.DataFrame):
            raise ValidationError(f"{name}: expected a DataFrame (Evaluation.sequences() / .durations()), got "
                                  f"{type(value).__name__}")  # fmt: skip
    metric = validate.choice("metric", metric, tuple(stats.WEIGHTS))  # CR as the command line reads it
    if table.empty:
        raise ValidationError("table: no sequence to compare (nothing was scored)")
    from lorisnb.tools.decisions.diff import check_numbers  # diff builds on this module

    table = table.copy()
    check_numbers(table)  # a table edited by hand is refused, naming the row, as diff refuses it
    if power_delta is not None:  # a difference the metric can show: a rate moves by 1 at most
        power_delta = validate.positive("power delta", power_delta, "the metric's unit")
        if metric in RATES and power_delta > 1:
            raise ValidationError(f"power delta={power_delta:g}: {metric} is a rate between 0 and 1, so a difference "
                                  "above 1 cannot happen; expected a difference in (0, 1]")  # fmt: skip
    check_table_duplicates(table)
    full, cover, counted_once = prepared_table(table, durations, lost)
    notes = coverage_notes(cover)
    if counted_once:
        notes.append("trials that repeat another trial's every value, within 1e-4 or a trace of noise (copies, not "
                     "reruns), counted once, rows of each sequence: " + "; ".join(
            f"{a}: {n} of {t}" for a, (n, t) in counted_once.items()) + " (a copied trial tested as a rerun made a "
            "significance no rerun would show)")  # fmt: skip
    ci = stats.confidence_intervals(full, level=level, seed=seed)
    pairs, spread, copies = decide(table, full, metric, alpha, seed)
    if copies:
        tested = metric_copies(full, metric)
        unit = "the log of " if metric not in RATES else ""
        why_copies = {r.algorithm: f"{r.algorithm}: CR varies by {r.cr_spread:.2g}, ATE by {100 * r.ate_spread:.2g} %"
                + (f", CR the same to the last digit in {100 * r.cr_ties:.0f} % of the sequences where it is neither 0 "
                   "nor 1 (which reruns never repeat)" if r.cr_ties > 0.5 else "")
                for r in spread.itertuples()}  # fmt: skip
        why_copies.update({a: f"{a}: {unit}{metric}, the metric tested, varies by {v:.2g} between its distinct trials"
                     for a, v in tested.items() if a not in trial_spread(table)[1]})  # fmt: skip
        notes += [f"the trials of {', '.join(sorted(copies))} are near-identical: " + "; ".join(
            why_copies[a] for a in sorted(copies) if a in why_copies)
            + f" between trials (median over sequences), where real reruns of the icra20 systems vary by "
            f"{RERUN_SPREAD['rate']:g} and {100 * RERUN_SPREAD['log']:.0f} %: they look like copies of one run, "
            "not reruns, so no significance is claimed for their pairs; run the system again for each trial"]  # fmt: skip
    rank = ranking.ranking(full, metric, alpha=alpha, seed=seed, pairs=pairs)
    keys = ["suite", "scene", "algorithm"]
    c = ci[ci["metric"] == metric].drop(columns=["metric"])
    algs = rank.merge(c.drop(columns=["value"]), on=keys, how="left").merge(cover, on=keys, how="left")
    algs = algs.merge(_versus_top(rank, pairs), on=keys, how="left")
    algs["value [CI]"] = [
        interval(v, lo, hi, 3) for v, lo, hi in zip(algs["value"], algs["low"], algs["high"], strict=True)
    ]
    algs["covered"] = [f"{s}/{e}" for s, e in zip(algs["sequences"], algs["expected"], strict=True)]
    algs["vs top [test interval]"] = [
        "" if not np.isfinite(d) else f"{_signed(d)} [{_bound(lo)}, {_bound(hi)}]"
        for d, lo, hi in zip(
            algs["difference_vs_top"], algs["difference_low_vs_top"], algs["difference_high_vs_top"], strict=True
        )
    ]
    algs = algs.rename(columns={"sequences": "sequences_with_output", "expected": "scene_sequences"})
    trials = _trials_said(full, copies)
    units = _units_said(ci[ci["metric"] == metric])
    header = (
        f"{metric} per algorithm and scene, {level:.0%} bootstrap intervals over {units} ({trials}); "
        f"missing sequences count as failed runs; rank = 1 + algorithms significantly better by a permutation "
        f"test (exact where the relabellings are few; Holm over every pair of every scene, alpha {alpha}); 'vs top': the difference to "
        "the scene's first algorithm, with the interval that inverts the same test (it holds 0 exactly when the "
        "test does not separate the two):"
    )
    if len(spread):
        header += "\nwhat varies between trials (median over sequences of the trials' spread): " + "; ".join(
            f"{clean(r.algorithm)} CR {r.cr_spread:.2g}, ATE {100 * r.ate_spread:.2g} %" for r in spread.itertuples()
        ) + f" (real reruns: CR {RERUN_SPREAD['rate']:g}, ATE {100 * RERUN_SPREAD['log']:.0f} %)"  # fmt: skip
    sig = pairs[pairs["significant"].astype(bool)]  # a mask also when empty (object dtype)
    summary = f"{len(sig)} of {len(pairs)} pairs differ significantly (the test behind the ranks and bold marks)"
    summary += ":" if len(sig) else "."
    unreached = [(clean(scene), *_unreachable(g, full, metric, alpha, len(pairs)))
            for scene, g in pairs.groupby("scene", sort=False) if not g["reachable"].astype(bool).any()]  # fmt: skip
    if unreached:
        summary += (
            f"\nno pair can reach alpha {alpha} in "
            + "; ".join(f"{scene} ({why})" for scene, why, _ in unreached)
            + (": run more trials (--power DELTA says how many)" if any(more for *_, more in unreached) else "")
        )
    power, power_note = None, ""
    if power_delta is not None:  # copies' spread is no rerun's: sized from it, a pair looked cheap to tell apart
        copied = pairs["test"].eq(COPIES_TEST).to_numpy(bool)
        differ = pairs["significant"].astype(bool).to_numpy()
        power = runs_for_power(full, pairs[~differ & ~copied], power_delta, alpha,
                               comparisons=max(len(pairs), 1))  # fmt: skip
        said = "copies of one run, whose spread says nothing of a rerun's; run the system again per trial"
        if copied.any():
            notes.append(f"--power: no number of runs for the pairs of {', '.join(sorted(copies))}: their trials are "
                         f"{said}")  # fmt: skip
        why = ([f"{int(differ.sum())} of {len(pairs)} pair(s) differ already"] if differ.any() else []) + (
            [f"{int(copied.sum())} of {len(pairs)} pair(s) not sized: the trials of {', '.join(sorted(copies))} are "
             f"{said}"] if copied.any() else [])  # fmt: skip
        power_note = (f"--power {power_delta:g}: no pair sized: " + ("; ".join(why) if why else
                      "no scene has two algorithms with a value to compare")) if power.empty else ""  # fmt: skip
    lacking = tuple(f"{r.algorithm}{f' ({r.suite})' if r.suite else ''} {r.scene} trial(s) "
                    + ", ".join(dict.fromkeys(x for x in [*str(r.lost_trials).split(", "),
                                              *(t for q in str(r.missing_trials).split("; ") if ": " in q
                                                for t in q.split(": ", 1)[1].split(", "))] if x))
                    for r in cover.itertuples() if r.lost_trials or r.missing_trials)  # fmt: skip
    return Comparison(algs, pairs, sig, ci, cover, power, header, summary, notes, power_note, lacking)


def _unreachable(g: pd.DataFrame, full: pd.DataFrame, metric: str, alpha: float, m: int) -> tuple[str, bool]:
    """Why no pair of a scene (its rows of the pairs, ``g``) can reach ``alpha``, from the facts of
    the pair closest to it (the smallest ``min_p``): how many sequences both algorithms have a value
    of ``metric`` on, how many of them differ (a sequence whose every trial of both has the same
    value, a tie, cannot move the permutation test), the smallest p the test can give with that and
    Holm's ``m`` pairs; and whether more runs could help (some sequence differs, the trials are no
    copies). "Every pair's results are the same" was said where one of two sequences tied and the
    other differed (the smallest p was 1: one differing sequence of one run each)."""
    nothing = f"no two algorithms both have a value of {metric} there: nothing to test", False
    if not (g["sequences"] > 0).any():
        return nothing
    if g["test"].eq(COPIES_TEST).all():
        return "the trials are copies of one run: no pair is tested; run the system again per trial", False
    g = g[~g["test"].eq(COPIES_TEST)]
    if not np.isfinite(g["min_p"]).any():
        return nothing
    best = g.assign(_p=g["min_p"].fillna(np.inf)).sort_values(["_p", "sequences"], ascending=[True, False]).iloc[0]
    scene = full[(full["scene"].astype(str) == str(best["scene"])) & (full["suite"] == best["suite"])]
    per = stats._sequence_trials(stats.with_trials(scene), metric)
    (va, wa), (vb, wb) = per.get(str(best["a"]), ({}, {})), per.get(str(best["b"]), ({}, {}))
    common = [q for q in va if q in vb and np.isfinite((wa[q] + wb[q]) / 2) and (wa[q] + wb[q]) > 0]
    differ = sum(bool(np.ptp(np.concatenate([va[q], vb[q]])) > 0) for q in common)
    n, min_p, pair = len(common), float(best["min_p"]), f"{clean(best['a'])} vs {clean(best['b'])}"
    runs = f"{int(best['trials_a'])} vs {int(best['trials_b'])} trial(s) a sequence"
    if differ == 0:
        return (
            "every pair's results are the same on every sequence: no test can separate them"
            + (f" ({n} sequence(s) where two algorithms both have a value of {metric})" if n > 1 else "")
        ), False
    if n == 1 and min_p >= 1:
        return f"only 1 sequence where two algorithms both have a value of {metric}: a test needs two or more", False
    ties = f", {n - differ} of them the same for both (a tie cannot move the test)" if differ < n else ""
    holm = f" x {m} pair(s) by Holm = {min(1.0, min_p * m):.4g}" if m > 1 else ""
    return (
        f"smallest possible p {min_p:.4g}{holm}, above alpha {alpha}: {pair} differ on {differ} of the {n} "
        f"sequence(s) where both have a value of {metric}{ties}, with {runs}"
    ), True


def _units_said(ci: pd.DataFrame) -> str:
    """What the bootstrap intervals resample, for the header: the unit most scenes have, then the
    scenes whose unit differs (one sequence with output: its trials alone); ``sequences x trials,
    trials`` was said where one scene had a single sequence."""
    per = ci.drop_duplicates(["suite", "scene"])
    if per.empty:
        return "sequences"
    common = per["unit"].value_counts().index[0]
    other = per[per["unit"] != common]
    return common + "".join(f" ({u} in {', '.join(clean(s) for s in g['scene'])})"
                            for u, g in other.groupby("unit", sort=True))  # fmt: skip


def _trials_said(full: pd.DataFrame, copies: set[str]) -> str:
    """How many runs a sequence has, for the header: trials per sequence, and, for the algorithms
    whose trials are copies of one run (:func:`trial_spread`), their files and the one distinct run
    they are counted as (``4 trial(s) per sequence`` was said of four copies of one run)."""
    per_seq = stats.with_trials(full).groupby(["algorithm", "scene", "seq"])["trial"].nunique()
    copied = per_seq.index.get_level_values("algorithm").isin(sorted(copies))

    def span(n: pd.Series, what: str) -> str:
        lo, hi = int(n.min()), int(n.max())
        return f"{lo} {what}" if lo == hi else f"{lo} to {hi} {what}"

    said = [span(per_seq[~copied], "trial(s) per sequence")] if (~copied).any() else []
    if copied.any():
        said.append(f"{', '.join(clean(a) for a in sorted(copies))}: {span(per_seq[copied], 'file(s)')} per sequence, "
                    "1 distinct run (the trials are copies of one run, counted as one)")  # fmt: skip
    return "; ".join(said)


def _with_power(pairs: pd.DataFrame, power: pd.DataFrame) -> pd.DataFrame:
    """The pairs CSV's rows with ``--power``'s columns: ``needed`` a whole number where the pair is
    sized, empty where it is not, and ``needed_note`` saying why not (the spread is unknown: -1 in
    Python, which read as "minus one run"; the pair differs already; its trials are copies)."""
    out = pairs.join(power[["unit", "have", "needed", "needed_note"]])
    out["needed"] = out["needed"].where(out["needed"].ge(0)).astype("Int64")
    unsized = out["needed_note"].isna()
    out.loc[unsized & out["significant"].astype(bool), "needed_note"] = "differs already"
    out.loc[unsized & out["test"].eq(COPIES_TEST), "needed_note"] = (
        "not sized: the trials are copies of one run, whose spread says nothing of a rerun's"
    )
    out["needed_note"] = out["needed_note"].fillna("")
    return out


def write_outputs(
    res: Comparison,
    metric: str,
    csv: str | os.PathLike[str] | None,
    pairs_csv: str | os.PathLike[str] | None,
    latex: str | os.PathLike[str] | None,
    markdown: str | os.PathLike[str] | None,
    force: bool,
    alpha: float,
) -> list[Path]:
    """The tables asked for: per algorithm (value, interval, coverage, rank, p and effect against
    the top), per pair (the test), LaTeX and Markdown (bold from the ranking)."""
    written = []
    if csv:
        written.append(
            write_csv(res.algorithms.drop(columns=["value [CI]", "covered", "vs top [test interval]"]), csv, force)
        )
    if pairs_csv:
        pairs = res.pairs if res.power is None else _with_power(res.pairs, res.power)
        written.append(write_csv(pairs, pairs_csv, force))
    rank = res.algorithms[["suite", "scene", "metric", "algorithm", "rank"]]
    for out in (latex, markdown):
        if out:
            written.append(write_comparison(res.ci, metric, out, force, ranks=rank, alpha=alpha))
    return written
