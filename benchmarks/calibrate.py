"""``make calibrate``: the measured error rates of ``lorisnb diff``'s verdict (the regression gate).

Reruns of the bundled real SLAM outputs under two noise models, nights of noise only and nights
with one change of known size, and the share of each the verdict calls a regression
(:mod:`lorisnb.tools.decisions.calibration`). Prints the noise models against the real rerun pairs
of the icra20 data, then the table of false-alarm rates and power by trial count. Targets: false
alarms at most 5 % at every trial count; power at least 90 % with 3 or more trials for CR -0.05
and ATE +50 % on one sequence. Then the same for ``lorisnb compare``: how often it calls one system
run twice significantly different (target at most 5 %), and how many real differences of scene CR
(0.05 or more) between two systems it finds. Last, ``lorisnb history``'s exit status on noise-only
series of nightly runs (its newest run against its baseline and against the series' first run).

    python benchmarks/calibrate.py [--pool 24] [--nights 200] [--power-nights 60] [--compare-nights 60]
                                   [--single-nights 40] [--history-series 2] [--history-nights 30] [--quick]
                                   [--designs 1v1 3v3 1v3 3v1 1v5 2v5 3v5] [--models real] [--diff-only]
                                   [--history-only]

``--designs`` measures the verdict at unequal trial counts (BASE's v CAND's; a CAND of fewer runs holds
them as near-identical copies, see ``calibration._night``); ``--diff-only`` prints the verdict's table alone,
``--history-only`` history's table alone (the rates docs/guide/history.md quotes: ``--models real --history-only
--pool 24 --history-series 2 --history-nights 60``).
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np
from tqdm import tqdm

from lorisnb.core.stats.power import detectable_change
from lorisnb.core.stats.regression import parse_tolerances
from lorisnb.core.stats.tolerances import RERUN_SPREAD, SINGLE_RUN_BAND
from lorisnb.errors import LorisWarning
from lorisnb.tools.decisions.calibration import (
    DESIGNS,
    MODELS,
    REAL_DIFFERENCE,
    THRESHOLDS,
    UNBOUNDED,
    calibrate,
    compare_rates,
    family_size,
    generator_pairs,
    history_rates,
    make_pool,
    pair_spread,
    real_pairs,
    single_run_bands,
    single_run_rates,
    stopped_early,
)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--pool", type=int, default=24, help="reruns of every sequence per noise model (default 24)")
    p.add_argument("--nights", type=int, default=200, help="noise-only nights per model and trial count")
    p.add_argument("--power-nights", type=int, default=60, help="nights per change, model and trial count")
    p.add_argument("--compare-nights", type=int, default=60, help="nights of compare per trial count (default 60)")
    p.add_argument("--trials", type=int, nargs="+", default=[1, 3, 5], help="trial counts (default 1 3 5)")
    p.add_argument("--designs", nargs="+", default=None,
                   help="designs BASEvCAND instead of --trials, e.g. 1v3 3v1 (default: --trials a side, then "
                   + " ".join(f"{b}v{c}" for b, c in DESIGNS if b != c) + ")")  # fmt: skip
    p.add_argument("--models", nargs="+", default=list(MODELS), choices=list(MODELS), help="noise models (default all)")
    p.add_argument("--diff-only", action="store_true", help="the verdict's table of lorisnb diff only")
    p.add_argument("--compare-only", action="store_true",
                   help="the table of lorisnb compare's error rates only (model real; needs --models real)")  # fmt: skip
    p.add_argument("--history-only", action="store_true",
                   help="the table of lorisnb history's noise-only nights only (model real; needs --models real)")  # fmt: skip
    p.add_argument("--single-nights", type=int, default=40,
                   help="nights of one run a side with whole-system changes, per model (default 40)")  # fmt: skip
    p.add_argument("--history-series", type=int, default=2, help="noise-only series of history per model (default 2)")
    p.add_argument("--history-nights", type=int, default=30,
                   help="runs in each series of history (default 30; docs/guide/history.md quotes 4 series of 20 with 3 trials, about 9 minutes)")  # fmt: skip
    p.add_argument("--thresholds", choices=["paper", "none"], default="paper",
                   help="the thresholds the nights are scored at: the paper's (eps per scene, phi 30 deg; default) "
                   "or none (eps = phi = inf, the default of evaluate, diff and compare)")  # fmt: skip
    p.add_argument("--quick", action="store_true",
                   help="a small run (pool 12, 40 nights, 12 per change, 10 compares, one history series of 12)")  # fmt: skip
    args = p.parse_args(argv)
    if args.quick:
        args.pool, args.nights, args.power_nights, args.compare_nights = 12, 40, 12, 10
        args.history_series, args.history_nights = 1, 12
        args.single_nights = 12
    warnings.simplefilter("ignore", LorisWarning)
    start = time.perf_counter()
    pools = {}
    at = THRESHOLDS if args.thresholds == "paper" else UNBOUNDED
    for name, noise in MODELS.items():
        if name not in args.models:
            continue
        pools[name] = make_pool(noise, args.pool, progress=lambda x, n=name: tqdm(x, desc=f"reruns ({n})"),
                                thresholds=at)  # fmt: skip
    print(f"nights scored at {'the paper' if at is THRESHOLDS else 'no'} thresholds: "
          + ", ".join(f"{k} {v}" for k, v in at.items()))  # fmt: skip
    if args.compare_only:
        if "real" not in pools:
            p.error("--compare-only measures the real noise model: give --models real (or leave --models out)")
        compare_table(pools["real"], args.trials, args.compare_nights)
        print(f"({time.perf_counter() - start:.0f} s)")
        return 0
    if args.history_only:
        if "real" not in pools:
            p.error("--history-only measures the real noise model: give --models real (or leave --models out)")
        history_rates_table(pools, [n for n in args.trials if n <= 3], args.history_series, args.history_nights)
        print(f"({time.perf_counter() - start:.0f} s)")
        return 0
    if not args.diff_only:  # the noise models against real reruns, and the single-run bands
        real = real_pairs()
        early = stopped_early()
        print(
            "\nHow two runs of one system on one recording differ (median, 90th percentile; |dCR| and |log ATE ratio|):"
        )
        rows = [("real pairs (icra20 per-seq vs lifelong)", pair_spread(real["cr_a"], real["cr_b"], real["ate_rmse_a"],
                                                                        real["ate_rmse_b"]))]  # fmt: skip
        rows += [(f"generator, model {name}", generator_pairs(pool)) for name, pool in pools.items()]
        print(f"  {'':44s} {'CR med':>7s} {'CR p90':>7s} {'CR>0.3':>7s} {'ATE med':>8s} {'ATE p90':>8s}")
        for label, s in rows:
            print(f"  {label:44s} {s['cr_median']:7.4f} {s['cr_p90']:7.4f} {s['cr_over_0_3']:7.2f} "
                  f"{s['ate_median']:8.3f} {s['ate_p90']:8.3f}")  # fmt: skip
        print("\nReal outputs that stop before 75 % of their recording (a trial stopped halfway looks like these):")
        for r in early.itertuples():
            print(f"  {r.mode:9s} {r.stopped} of {r.runs} runs ({100 * r.share:.0f} %)")
        bands = single_run_bands(pools["real"], nights=min(args.nights, 100))
        print("\nThe largest change of a noise-only single-run night (model real; CR units, or log ratio for errors):")
        print("  what sizes lorisnb.core.stats.tolerances.SINGLE_RUN_BAND: the 95th percentiles times one factor "
              f"({bands['factor'].iloc[0]:.2f}) so that 95 % of the nights stay within every band")  # fmt: skip
        for r in bands.itertuples():
            have = SINGLE_RUN_BAND[r.level].get(r.metric, float("nan"))
            print(f"  {r.level:8s} {r.metric:15s} median {r.median:6.3f}  95th percentile {r.p95:6.3f}  band {r.band:6.3f}"
                  f"  in use {have:.2f}")  # fmt: skip
    if args.designs is not None:
        designs = [_design(d) for d in args.designs]
    else:
        designs = [(n, n) for n in args.trials] + [d for d in DESIGNS if d[0] != d[1]]
    table = calibrate(pools, nights=args.nights, power_nights=args.power_nights, designs=designs,
                      progress=lambda x: tqdm(x, desc="nights", leave=False))  # fmt: skip
    print("\nThe verdict of lorisnb diff (default tolerances, alpha 0.05), share of nights [95 % interval];"
          "\n  design: BASE's trials v CAND's (a CAND of fewer runs holds them as near-identical copies):")  # fmt: skip
    checks = list(dict.fromkeys(table["check"]))
    print(f"  {'model':6s} {'design':>6s} " + " ".join(f"{c:>22s}" for c in checks))
    for (model, n), g in table.groupby(["model", "design"], sort=False):
        cells = []
        for c in checks:
            r = g[g["check"] == c]
            cells.append(f"{'-':>22s}" if r.empty else
                         f"{100 * r['rate'].iloc[0]:5.1f}% [{100 * r['low'].iloc[0]:4.1f},{100 * r['high'].iloc[0]:5.1f}] "
                         f"n{int(r['nights'].iloc[0]):<3d}")  # fmt: skip
        print(f"  {model:6s} {n:>6s} " + " ".join(cells))
    fa = table[table["check"] == "false alarm"]
    print(
        f"\nfalse alarms at most 5 % everywhere: {'met' if (fa['rate'] <= 0.05).all() else 'NOT MET'} "
        f"(largest {100 * fa['rate'].max():.1f} %)"
    )
    for c in ("cr -0.05", "ate x1.5"):
        pw = table[(table["check"] == c) & (table["trials"] >= 3)]
        if len(pw):
            print(f"power for {c} with 3+ trials at least 90 %: {'met' if (pw['rate'] >= 0.9).all() else 'NOT MET'} "
                  f"(smallest {100 * pw['rate'].min():.1f} %)")  # fmt: skip
    if args.diff_only:
        print(f"({time.perf_counter() - start:.0f} s)")
        return 0
    single_run_table(pools, args.single_nights)
    bound_table(pools["real"] if "real" in pools else next(iter(pools.values())), args.trials)
    compare_table(pools["real"] if "real" in pools else next(iter(pools.values())), args.trials, args.compare_nights)
    history_rates_table(pools, [n for n in args.trials if n <= 3], args.history_series, args.history_nights)
    print(f"({time.perf_counter() - start:.0f} s)")
    return 0


def _design(text: str) -> tuple[int, int]:
    """``"1v3"`` -> (1, 3)."""
    b, sep, c = text.lower().partition("v")
    if not sep or not b.isdigit() or not c.isdigit() or int(b) < 1 or int(c) < 1:
        raise SystemExit(f"--designs {text}: expected BASEvCAND trial counts, e.g. 1v3")
    return int(b), int(c)


def single_run_table(pools: dict, nights: int) -> None:
    """One run per side against whole systems changed (:func:`single_run_rates`): one system worse
    on every sequence, alone and beside another one better, and the same nights without a change."""
    print("\nOne run a side, whole systems changed (the system made worse named among the regressions):")
    for model, pool in pools.items():
        rates = single_run_rates(pool, nights, progress=lambda x: tqdm(x, desc="single runs", leave=False))
        for r in rates.itertuples():
            print(
                f"  {model:6s} {r.check:38s} {100 * r.rate:5.1f}% [{100 * r.low:4.1f},{100 * r.high:5.1f}] of {r.nights}"
            )


def bound_table(pool: object, trials: list[int]) -> None:
    """The smallest change on one sequence that any test could find with 90 % power, at the real
    rerun spread (RERUN_SPREAD) and the default tolerances: with one test alone, and with the
    family of comparisons one night's verdict holds (Bonferroni; Holm is no better for one change)."""
    tol = parse_tolerances()
    cr_tol, ate_tol = tol["cr"].scaled("cr", 1.0), tol["ate_rmse"].scaled("ate_rmse", 1.0)
    print(
        "\nThe smallest change any test could find with 90 % power (oracle z-test knowing the real rerun spread, "
        f"{RERUN_SPREAD['rate']} CR and {RERUN_SPREAD['log']} log ATE per run; default tolerances):"
    )
    print(
        f"  {'trials':>6s} {'tests':>6s} {'CR drop, 1 test':>16s} {'CR drop, family':>16s} "
        f"{'ATE factor, 1 test':>19s} {'ATE factor, family':>19s}"
    )
    for n in trials:
        m = family_size(pool, n)  # type: ignore[arg-type]
        cr1, crm = (detectable_change(RERUN_SPREAD["rate"], n, cr_tol, comparisons=k) for k in (1, max(m, 1)))
        a1, am = (np.exp(detectable_change(RERUN_SPREAD["log"], n, ate_tol, comparisons=k)) for k in (1, max(m, 1)))
        print(f"  {n:6d} {m:6d} {cr1:16.3f} {crm:16.3f} {a1:19.2f} {am:19.2f}")
    print("  (a single run per side has no family: its tests are not significance tests; its bands are above)")


def compare_table(pool: object, trials: list[int], nights: int) -> None:
    """``lorisnb compare``'s error rates (:func:`compare_rates`): every algorithm of the pool twice."""
    rates = compare_rates(pool, trials, nights, progress=lambda x: tqdm(x, desc="compares", leave=False))  # type: ignore[arg-type]
    print(
        "\nThe decision of lorisnb compare (CR, alpha 0.05), each algorithm of the pool run twice under two labels:"
        f"\n  false claim: one system's two runs called different anywhere; found: real differences of scene CR"
        f" >= {REAL_DIFFERENCE} between two systems called, the better one named right"
    )
    for n, g in rates.groupby("trials", sort=False):
        cells = []
        for r in g.itertuples():
            cells.append(f"{r.check} {100 * r.rate:5.1f}% [{100 * r.low:4.1f},{100 * r.high:5.1f}] of {r.nights}")
        print(f"  {n} trial(s): " + "; ".join(cells))
    fa = rates[rates["check"] == "false claim"]
    print(f"compare's false claims at most 5 %: {'met' if (fa['rate'] <= 0.05).all() else 'NOT MET'} "
          f"(largest {100 * fa['rate'].max():.1f} %)")  # fmt: skip


def history_rates_table(pools: dict, trials: list[int], series: int, nights: int) -> None:
    """``lorisnb history``'s failed noise-only nights (:func:`history_rates`), per model and trial count."""
    pool = pools["real"]  # each night judges the whole series before it: the real model only
    print(f"\nThe exit status of lorisnb history on noise-only series ({series} x {nights} nightly runs a trial count, "
          f"real noise model, a pool of {len(pool.tables)} reruns; the newest run against its baseline and against "
          "the series' first run):")  # fmt: skip
    for n in trials:  # one trial count at a time: each printed as it is measured
        rates = history_rates(pool, (n,), series, nights, progress=lambda x: tqdm(x, desc="series", leave=False))
        for r in rates.itertuples():
            print(f"  real   {r.trials} trial(s): nights failed {100 * r.rate:5.1f}% [{100 * r.low:4.1f},"
                  f"{100 * r.high:5.1f}] ({r.hits} of {r.nights}; by a lost sequence alone: {r.lost}); drift named on "
                  f"{r.drifts} night(s)", flush=True)  # fmt: skip


if __name__ == "__main__":
    raise SystemExit(main())
