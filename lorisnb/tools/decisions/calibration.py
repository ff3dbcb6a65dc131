"""The measured error rates of the regression gate (``lorisnb diff``): reruns made from the bundled
real SLAM outputs, nights of noise only and nights with a change of known size, and the share of
each that the verdict calls a regression. ``make calibrate`` prints the table
(``benchmarks/calibrate.py``); docs/guide/regression-gating.md quotes it.

- **Reruns** (:mod:`lorisnb.core.stats.reruns`): every sequence of the chosen algorithms'
  ``per-seq`` results rerun ``pool`` times under a noise model, each rerun evaluated by the real
  pipeline and scored at the paper's thresholds. A **night** draws ``2 n`` distinct reruns of every
  sequence: ``n`` trials for BASE, ``n`` for CAND.
- **False alarms**: the share of noise-only nights whose verdict is "regression" (anything at
  all); the target is at most 5 % at every trial count.
- **Power** per change: the share of nights whose verdict names the changed sequence (or its
  scene). The changes (:data:`CHANGES`), on one target sequence of an algorithm at a time: its CR
  lowered by 0.05, 0.15 or 0.3 (output removed over that share of its duration where it was
  correct), its ATE multiplied by 1.5, 2 or 3 (every aligned position's error scaled), one of its
  trials missing, one stopped at half time.
- **The noise model checked against real reruns**: the icra20 ``lifelong`` runs start each scene
  with its first sequence, which the ``per-seq`` runs also ran on its own: 20 pairs of real runs of
  one system on one recording. :func:`real_pairs` gives their differences, :func:`pair_spread`
  the same statistics of two reruns of the generator, side by side in the printed table.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from lorisnb.core.lifelong.aggregate import durations_table
from lorisnb.core.lifelong.scoring import score
from lorisnb.core.pipeline.model import ResultFile
from lorisnb.core.pipeline.sessions import compute_errors
from lorisnb.core.spec.validate import finite
from lorisnb.core.stats.inference import scene_means, with_trials
from lorisnb.core.stats.regression import parse_tolerances
from lorisnb.core.stats.reruns import RerunNoise, rerun
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.errors import ValidationError
from lorisnb.io.datasets.paths import find_data, load_groundtruth
from lorisnb.io.readers.openloris import read_openloris
from lorisnb.tools.decisions.comparison import decide, prepared_table
from lorisnb.tools.decisions.diff import diff_tables, keyed
from lorisnb.tools.decisions.runs import Run

#: Algorithms of ``icra20_results/per-seq`` the nights are made of (good, medium and poor trackers).
ALGORITHMS = ("vins_mono_color_imu_with_loop", "orbslam2_rgbd", "infinitam_aligned_depth")
#: Noise models: "real" has the median spread of the 20 real rerun pairs (its sizes chosen so that
#: :func:`pair_spread` matches :func:`real_pairs`' medians); "heavy" adds a 10 % chance per run of
#: losing track for good, the tail the real pairs show (2 of 20 differ in CR by more than 0.3).
MODELS: dict[str, RerunNoise] = {
    "real": RerunNoise(),
    "heavy": RerunNoise(lost_rest=0.1),
}
#: The changes injected on one target sequence: CR lowered by a share of its duration, ATE
#: multiplied, a trial missing, a trial stopped at half time.
CR_DROPS = (0.05, 0.15, 0.3)
ATE_FACTORS = (1.5, 2.0, 3.0)
CHANGES = (*(f"cr -{x:g}" for x in CR_DROPS), *(f"ate x{x:g}" for x in ATE_FACTORS), "missing trial", "truncated trial")
#: The paper's thresholds (eps per scene, phi 30 degrees), at which the nights are scored unless
#: :func:`make_pool` is given others (``diff``'s and ``compare``'s default, eps = phi = inf:
#: :data:`UNBOUNDED`).
THRESHOLDS: dict[str, Any] = {"eps": "paper", "phi": 30.0}
#: No thresholds (eps = phi = inf, every matched pose correct: CR is the share of time with output),
#: the default of ``lorisnb evaluate``, ``diff`` and ``compare``.
UNBOUNDED: dict[str, Any] = {"eps": float("inf"), "phi": float("inf")}


@dataclass
class Pool:
    """Reruns of every sequence: ``tables[k]`` is rerun k's per-sequence table (all algorithms),
    ``changed[(change, target)][k]`` the target's rows of rerun k under a change."""

    tables: list[pd.DataFrame]
    changed: dict[tuple[str, tuple], list[pd.DataFrame]]
    expected: pd.DataFrame
    targets: dict[str, list[tuple]]


def _files(root: Path, algorithms: Sequence[str]) -> list[tuple[str, ResultFile]]:
    out = []
    for alg in algorithms:
        for path in sorted((root / "per-seq" / alg).glob("*.txt")):
            out.append((alg, read_openloris(path, warn=False)))
    return out


def _table(alg: str, rf: ResultFile, gt: ResultFile, trial: int,
           thresholds: Mapping[str, Any] | None = None) -> pd.DataFrame:  # fmt: skip
    """One rerun's rows scored at ``thresholds`` (default :data:`THRESHOLDS`, the paper's)."""
    fe = compute_errors(rf, gt, algorithm=alg, file=rf.path.name, trial=trial, checks=False)
    return score([fe], **(THRESHOLDS if thresholds is None else thresholds))


def _cr_change(traj: Trajectory, gt_span: tuple[float, float], drop: float) -> Trajectory:
    """The estimate without output over ``drop`` of the ground truth's duration, in the middle of
    its own span (where the targets track correctly): CR lower by about ``drop``."""
    span = gt_span[1] - gt_span[0]
    mid = 0.5 * (float(traj.stamps[0]) + float(traj.stamps[-1]))
    keep = np.abs(traj.stamps - mid) >= 0.5 * drop * span
    return Trajectory.from_checked(traj.stamps[keep], traj.positions[keep], traj.quaternions[keep], None, traj.meta)


def _ate_change(alg: str, rf: ResultFile, gt: ResultFile, seq: int, factor: float) -> Trajectory:
    """The estimate whose every aligned position is ``factor`` times as far from the ground truth
    (ATE times ``factor``), orientations unchanged, in the ground truth's frame (the alignment is
    then near identity)."""
    e = next(s for s in compute_errors(rf, gt, algorithm=alg, checks=False).sequences if s.seq == seq)
    pos = e.gt_positions + factor * (e.est_positions - e.gt_positions)
    return Trajectory.from_checked(np.array(e.stamps), pos, np.array(e.est_quaternions), None, {})


def _targets(base: pd.DataFrame) -> dict[str, list[tuple]]:
    """One target sequence per algorithm and change: the longest well-tracked one (CR at least
    0.8 for the CR changes, at least 300 matched poses)."""
    out: dict[str, list[tuple]] = {c: [] for c in CHANGES}
    for alg, g in base.groupby("algorithm", sort=False):
        g = g[g["matched"] >= 300].sort_values("gt_duration", ascending=False)
        good = g[g["cr"] >= 0.8]
        for change in CHANGES:
            pick = good if change.startswith("cr") else g
            if len(pick):
                r = pick.iloc[0]
                out[change].append((alg, r["file"], r["scene"], int(r["seq"])))
    return out


def make_pool(noise: RerunNoise, size: int, algorithms: Sequence[str] = ALGORITHMS, data_root: str | None = None,
              seed: int = 0, progress: Callable[[Iterable], Iterable] = lambda x: x,
              thresholds: Mapping[str, Any] | None = None) -> Pool:  # fmt: skip
    """``size`` reruns of every sequence of ``algorithms`` (and of each change's targets) under
    ``noise``, each scored at ``thresholds`` (eps, phi; default :data:`THRESHOLDS`, the paper's)."""
    at = dict(THRESHOLDS if thresholds is None else thresholds)
    data = find_data(data_root)
    have = set(data.scenes_with_groundtruth())
    files = [(a, rf) for a, rf in _files(data.icra20, algorithms) if rf.scene in have]  # office: no public ground truth
    gts = {s: load_groundtruth(s, data) for s in sorted({rf.scene for _, rf in files})}
    base = pd.concat([_table(a, rf, gts[rf.scene], 0, at) for a, rf in files], ignore_index=True)
    targets = _targets(base)
    by_file = {(a, rf.path.name): rf for a, rf in files}
    changed_files: dict[tuple[str, tuple], ResultFile] = {}
    for change, tlist in targets.items():
        for t in tlist:
            alg, name, scene, seq = t
            rf, gt = by_file[(alg, name)], gts[scene]
            if change.startswith("cr -"):
                g = gt.sequences[seq]
                new = _cr_change(rf.sequences[seq], (float(g.stamps[0]), float(g.stamps[-1])), float(change[4:]))
            elif change.startswith("ate x"):
                new = _ate_change(alg, rf, gt, seq, float(change[5:]))
            else:
                continue
            changed_files[(change, t)] = replace(rf, sequences={seq: new})
    tables: list[pd.DataFrame] = []
    changed: dict[tuple[str, tuple], list[pd.DataFrame]] = {k: [] for k in changed_files}
    rng = np.random.default_rng(seed)
    error = {(r["algorithm"], r["file"], int(r["seq"])): float(r["ate_rmse"]) for _, r in base.iterrows()}

    def again(alg: str, rf: ResultFile, s: int) -> ResultFile:
        return replace(rf, sequences={q: rerun(tr, noise, s + q, _finite(error.get((alg, rf.path.name, q))))
                                      for q, tr in rf.sequences.items()})  # fmt: skip

    for k in progress(range(size)):
        seeds = rng.integers(2**31, size=len(files) + len(changed_files))
        parts = []
        for (alg, rf), s in zip(files, seeds, strict=False):
            parts.append(_table(alg, again(alg, rf, int(s)), gts[rf.scene], k + 1, at))
        tables.append(pd.concat(parts, ignore_index=True))
        for (key, rf), s in zip(changed_files.items(), seeds[len(files) :], strict=True):
            changed[key].append(_table(key[1][0], again(key[1][0], rf, int(s)), gts[key[1][2]], k + 1, at))
    return Pool(tables, changed, durations_table(gts), targets)


def _finite(v: float | None) -> float | None:
    return v if v is not None and np.isfinite(v) and v > 0 else None


def _night(pool: Pool, n: int, rng: np.random.Generator, change: str | None = None, target: tuple | None = None,
           cand: int | None = None) -> tuple[pd.DataFrame, pd.DataFrame]:  # fmt: skip
    """BASE and CAND of one night: ``n`` distinct reruns for BASE (trials 1..n; one unnumbered trial
    when ``n`` is 1), ``cand`` (default ``n``) for CAND, CAND's target changed. A CAND of fewer
    reruns than BASE holds them as BASE's count of trials, the last rerun repeated as near-identical
    copies (values moved by 0.1 % relative, below what reruns vary, above the 1e-4 of an exact
    copy): CAND's trials counted as fewer runs (:func:`~lorisnb.core.stats.regression.trial_copies`),
    where fewer trials would be a missing trial, a regression by rule."""
    m = n if cand is None else cand
    picks = rng.choice(len(pool.tables), size=n + m, replace=False)

    def side(ks: np.ndarray, changed: bool, count: int) -> pd.DataFrame:
        numbered = count > 1
        parts = []
        for trial in range(1, count + 1):
            k = ks[min(trial, len(ks)) - 1]
            t = pool.tables[k].assign(trial=trial if numbered else 0)
            if changed and target is not None:
                alg, name, scene, seq = target
                here = (t["algorithm"] == alg) & (t["scene"] == scene) & (t["seq"] == seq)
                if change is not None and (change, target) in pool.changed:
                    new = pool.changed[(change, target)][k].assign(trial=trial if numbered else 0)
                    t = pd.concat([t[~here], new], ignore_index=True)
                elif change == "missing trial" and trial == max(1, count // 2 + 1):
                    t = t[~here]
                elif change == "truncated trial" and trial == max(1, count // 2 + 1):
                    t = _truncated(t, here)
            if trial > len(ks):  # a near-identical copy of the side's last rerun
                t = _near_copy(t, rng)
            parts.append(t)
        return pd.concat(parts, ignore_index=True)

    return side(picks[:n], False, n), side(picks[n:], True, max(m, n))


def _near_copy(t: pd.DataFrame, rng: np.random.Generator) -> pd.DataFrame:
    """A rerun's table with its judged values moved by about 0.1 % relative (rates kept in [0, 1])."""
    t = t.copy()
    for c in ("cr", "cr_t", "cs_r", "ate_rmse", "aoe_rmse", "c_ate_rmse", "c_aoe_rmse", "rpe_trans_rmse",
              "rpe_rot_rmse"):  # fmt: skip
        if c in t.columns:
            x = pd.to_numeric(t[c], errors="coerce").to_numpy(float)
            x = x * (1 + 1e-3 * rng.standard_normal(len(x)))
            t[c] = np.clip(x, 0, 1) if c in ("cr", "cr_t", "cs_r") else x
    return t


def _truncated(t: pd.DataFrame, here: pd.Series) -> pd.DataFrame:
    """A trial that stopped at half time: its correct and tracked time halved, as its CR and CR-T."""
    t = t.copy()
    for c in ("cr", "correct_time", "track_time", "matched", "c_matched"):
        if c in t.columns:
            t[c] = t[c].astype(float)
            t.loc[here, c] = t.loc[here, c] * 0.5
    return t


def _names(verdict: Mapping, target: tuple) -> bool:
    alg, _, scene, seq = target
    return any(
        r["algorithm"] == alg and r["scene"] == scene and r["seq"] in (seq, None) for r in verdict["regressions"]
    )


#: The designs (BASE's trials, CAND's trials) ``make calibrate`` measures beside equal counts: a
#: single BASE run against CAND's trials and the reverse (CAND's trials near-identical copies of one
#: run), and unequal counts of reruns.
DESIGNS = ((1, 1), (3, 3), (1, 3), (3, 1), (1, 5), (2, 5), (3, 5))


def calibrate(pools: Mapping[str, Pool], trials: Sequence[int] = (1, 3, 5), nights: int = 200,
              power_nights: int = 60, seed: int = 1, progress: Callable[[Iterable], Iterable] = lambda x: x,
              designs: Sequence[tuple[int, int]] | None = None) -> pd.DataFrame:  # fmt: skip
    """One row per noise model, design and check: ``nights``, ``hits`` and ``rate`` (false alarms:
    any regression on a noise-only night; power: the change named), with a 95 % Wilson interval.
    The designs are ``designs`` ((BASE's trials, CAND's trials), :func:`_night`), else each of
    ``trials`` a side; a row's ``base`` and ``cand`` are its counts, ``design`` says them ("1v3")
    and ``trials`` is the smaller."""
    tol = parse_tolerances()
    rng = np.random.default_rng(seed)
    rows = []
    pairs = list(designs) if designs is not None else [(n, n) for n in trials]
    for model, pool in pools.items():
        for nb, nc in pairs:
            if nb + max(nb, nc) > len(pool.tables) or nb + nc > len(pool.tables):
                continue
            jobs: list[tuple[str, tuple | None, int]] = [("false alarm", None, nights)]
            for change, tlist in pool.targets.items():
                jobs += [(change, t, max(1, power_nights // max(1, len(tlist)))) for t in tlist]
            hits: dict[str, list[int]] = {}
            for what, target, count in progress(jobs):
                for _ in range(count):
                    b, c = _night(pool, nb, rng, None if target is None else what, target, cand=nc)
                    d = diff_tables(b, c, tol, expected=pool.expected)
                    hit = d.regressed if target is None else _names(d.verdict, target)
                    hits.setdefault(what, []).append(int(hit))
            for what, h in hits.items():
                lo, hi = wilson(sum(h), len(h))
                rows.append(dict(model=model, design=f"{nb}v{nc}", base=nb, cand=nc, trials=min(nb, nc), check=what,
                                 nights=len(h), hits=sum(h), rate=sum(h) / len(h), low=lo, high=hi))  # fmt: skip
    return pd.DataFrame(rows)


#: The smallest difference of scene CR between two systems counted as a real one when measuring
#: how many of them ``compare`` finds (:func:`compare_rates`).
REAL_DIFFERENCE = 0.05


def compare_rates(pool: Pool, trials: Sequence[int] = (1, 3, 5), nights: int = 100, seed: int = 4,
                  alpha: float = 0.05, progress: Callable[[Iterable], Iterable] = lambda x: x) -> pd.DataFrame:  # fmt: skip
    """The measured error rates of ``lorisnb compare``'s decision
    (:func:`~lorisnb.tools.decisions.comparison.decide`, metric CR, the command's defaults). A night compares every algorithm of the pool **twice**,
    under two labels with ``n`` distinct reruns each: the same system, so calling the two labels
    different is a false claim. One row per trial count and check, as :func:`calibrate`:

    - ``false claim``: the share of nights in which any pair of one system's two labels is called
      significantly different, in any scene (the family the comparison's Holm correction holds at
      ``alpha``);
    - ``real difference found``: of the pairs of two different systems whose scene CR differs by at
      least :data:`REAL_DIFFERENCE` over the whole pool (their true difference), the share called
      significantly different with the better one named right."""
    truth_table = pd.concat([t.assign(trial=k + 1) for k, t in enumerate(pool.tables)], ignore_index=True)
    truth = scene_means(with_trials(truth_table), "cr").set_index(["scene", "algorithm"])["value"]
    rng = np.random.default_rng(seed)
    rows = []
    for n in trials:
        if 2 * n > len(pool.tables):
            continue
        false, found, real = [], 0, 0
        for _ in progress(range(nights)):
            a, b = _night(pool, n, rng)
            table = pd.concat([a.assign(algorithm=a["algorithm"] + " (1)"), b.assign(algorithm=b["algorithm"] + " (2)")],
                              ignore_index=True)  # fmt: skip
            full, _, _ = prepared_table(table, pool.expected)  # as compare_table prepares it
            pairs, _, _ = decide(table, full, "cr", alpha, int(rng.integers(2**31)), intervals=False)
            system_a, system_b = pairs["a"].str[:-4], pairs["b"].str[:-4]
            same = (system_a == system_b).to_numpy()
            sig = pairs["significant"].astype(bool).to_numpy()
            false.append(int((sig & same).any()))
            for r, sa, sb, sg in zip(pairs.itertuples(), system_a, system_b, sig, strict=True):
                if sa == sb:
                    continue
                d = truth[(r.scene, sa)] - truth[(r.scene, sb)]
                if abs(d) >= REAL_DIFFERENCE:
                    real += 1
                    found += int(sg and r.better == (r.a if d > 0 else r.b))
        lo, hi = wilson(sum(false), len(false))
        rows.append(dict(trials=n, check="false claim", nights=len(false), hits=sum(false),
                         rate=sum(false) / len(false), low=lo, high=hi))  # fmt: skip
        lo, hi = wilson(found, real)
        rows.append(dict(trials=n, check="real difference found", nights=real, hits=found,
                         rate=found / real if real else np.nan, low=lo, high=hi))  # fmt: skip
    return pd.DataFrame(rows)


def family_size(pool: Pool, trials: int, seed: int = 3) -> int:
    """How many comparisons one night's verdict tests (those with a p value: the family over which
    Holm holds the false-alarm rate), for :func:`lorisnb.core.stats.power.detectable_change`."""
    b, c = _night(pool, trials, np.random.default_rng(seed))
    d = diff_tables(b, c, expected=pool.expected)
    return int(sum(t["p_adj"].notna().sum() for t in (d.sequences, d.scenes)))


def single_run_bands(pool: Pool, nights: int = 100, seed: int = 2) -> pd.DataFrame:
    """What sizes :data:`~lorisnb.core.stats.tolerances.SINGLE_RUN_BAND`: over noise-only nights of
    one run per side, the largest change of each metric at each level in a night (on the judged
    scale: CR units, or the log of the ratio for the errors), its median and 95th percentile, and
    the band to use: the 95th percentiles scaled by one common factor so that in 95 % of the nights
    no metric at any level goes beyond its band (one night, one verdict over all of them)."""
    from lorisnb.core.stats.regression import LOG_METRICS

    rng = np.random.default_rng(seed)
    nightly: list[dict[tuple[str, str], float]] = []
    for _ in range(nights):
        b, c = _night(pool, 1, rng)
        d = diff_tables(b, c, expected=pool.expected)
        night: dict[tuple[str, str], float] = {}
        for level, t in (("sequence", d.sequences), ("scene", d.scenes)):
            t = t[t["status"].isin(["ok", "regression", "improvement"])]
            for metric, g in t.groupby("metric", sort=False):
                x, y = g["base"].astype(float).to_numpy(), g["cand"].astype(float).to_numpy()
                with np.errstate(divide="ignore", invalid="ignore"):
                    w = np.abs(np.log(y / x)) if metric in LOG_METRICS else np.abs(y - x)
                if np.isfinite(w).any():
                    night[(level, str(metric))] = float(np.nanmax(w))
        nightly.append(night)
    keys = sorted({k for n in nightly for k in n})
    p95 = {k: float(np.quantile([n[k] for n in nightly if k in n], 0.95)) for k in keys}
    ratio = [max((n[k] / p95[k] for k in n if p95[k] > 0), default=0.0) for n in nightly]
    factor = float(np.quantile(ratio, 0.95))
    return pd.DataFrame([dict(level=k[0], metric=k[1], median=float(np.median([n[k] for n in nightly if k in n])),
                              p95=p95[k], band=factor * p95[k], factor=factor) for k in keys])  # fmt: skip


def _series(pool: Pool, n: int, nights: int, rng: np.random.Generator) -> list[pd.DataFrame]:
    """A noise-only series of nightly runs: ``n`` reruns of every sequence a night (trials 1..n, 0
    for one), none shared with a night it is judged against: the night before (its baseline) and
    the series' first night (``history``'s drift check). A real night reruns the system; a rerun of
    the pool drawn again is a file copied from that night, which the cross-side copy rule rightly
    counts as no run, a missing trial (it failed 2 of 11 noise-only nights of a 24-rerun pool when
    only the night before was avoided). Needs a pool of at least ``3 n`` reruns."""
    if 3 * n > len(pool.tables) and nights > 2:
        raise ValidationError(f"a history series of {n} trial(s) a night draws from {len(pool.tables)} rerun(s): "
                              f"expected a pool of at least {3 * n} (a night shares no rerun with the first night "
                              "nor the night before); give a larger pool or fewer trials")  # fmt: skip
    out, first, last = [], np.zeros(0, int), np.zeros(0, int)
    for _ in range(nights):
        free = np.setdiff1d(np.arange(len(pool.tables)), np.concatenate([first, last]))
        last = rng.choice(free, size=n, replace=False)
        first = last if not first.size else first
        out.append(pd.concat([pool.tables[k].assign(trial=t if n > 1 else 0) for t, k in enumerate(last, start=1)],
                             ignore_index=True))  # fmt: skip
    return out


def history_rates(pool: Pool, trials: Sequence[int] = (1, 3), series: int = 2, nights: int = 60, seed: int = 6,
                  progress: Callable[[Iterable], Iterable] = lambda x: x) -> pd.DataFrame:  # fmt: skip
    """How often ``lorisnb history`` fails a noise-only night (exit 1): ``series`` series of
    ``nights`` runs each (:func:`_series`), every night from the second judged as ``history`` judges
    its newest run (:func:`~lorisnb.tools.decisions.history.newest_verdict`: against its baseline by
    ``diff``'s rule, and against the first run of its series, :func:`~lorisnb.tools.decisions.history.drift`).
    One row per trial count: ``nights`` judged, ``hits`` (exit 1) and ``rate`` with a 95 % Wilson
    interval, ``lost`` (nights failed by a sequence lost since the first run alone) and ``drifts``
    (nights whose drift was named, not gated)."""
    from datetime import datetime, timedelta, timezone

    from lorisnb.tools.decisions.history import drift, drift_gates, newest_verdict

    tol = parse_tolerances()
    rng = np.random.default_rng(seed)
    start = datetime(2026, 1, 1, 2, tzinfo=timezone.utc)
    rows = []
    for n in trials:
        if 3 * n > len(pool.tables):  # a night shares no rerun with the first night nor the night before
            continue
        hits = lost = drifts = judged = 0
        for _ in progress(range(series)):
            runs = [Run(Path(f"night-{k}.csv"), "table", t, created=start + timedelta(days=k), created_from="test",
                        expected=pool.expected) for k, t in enumerate(_series(pool, n, nights, rng))]  # fmt: skip
            names = [r.name for r in runs]
            for k in range(1, len(runs)):
                d = diff_tables(keyed(runs[k - 1].table, names[k - 1]), keyed(runs[k].table, names[k]), tol,
                                names=(names[k - 1], names[k]), expected=pool.expected)  # fmt: skip
                since = drift(runs[: k + 1], tol)
                rc, _ = newest_verdict(runs[: k + 1], {k: d}, names[: k + 1], since)
                judged += 1
                hits += rc == 1
                gated = since is not None and bool(drift_gates(since[1]))
                lost += rc == 1 and not d.regressed and gated
                drifts += since is not None and since[1].regressed and not gated
        lo, hi = wilson(hits, judged)
        rows.append(dict(trials=n, series=series, nights=judged, hits=hits, rate=hits / max(judged, 1), low=lo,
                         high=hi, lost=lost, drifts=drifts))  # fmt: skip
    return pd.DataFrame(rows)


def wilson(k: int, n: int, z: float = 1.959964) -> tuple[float, float]:
    """The 95 % Wilson score interval of a share k / n."""
    if n == 0:
        return np.nan, np.nan
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return float(max(0.0, centre - half)), float(min(1.0, centre + half))


def real_pairs(data_root: str | None = None) -> pd.DataFrame:
    """The 20 pairs of real runs of one system on one recording in the icra20 results (the first
    sequence of each scene, run on its own in ``per-seq`` and first in ``lifelong``): CR and ATE
    RMSE of both at the paper's thresholds."""
    from lorisnb.tools.evaluation.runner import evaluate

    root = find_data(data_root).icra20
    per = evaluate(root / "per-seq", data_root=data_root, progress=False).sequences(**THRESHOLDS)
    life = evaluate(root / "lifelong", data_root=data_root, progress=False).sequences(**THRESHOLDS)
    keys = ["algorithm", "scene", "seq"]
    both = per[keys + ["cr", "ate_rmse"]].merge(life[life["seq"] == 1][keys + ["cr", "ate_rmse"]], on=keys,
                                               suffixes=("_a", "_b"))  # fmt: skip
    return both


def pair_spread(a_cr: np.ndarray, b_cr: np.ndarray, a_ate: np.ndarray, b_ate: np.ndarray) -> dict[str, float]:
    """How two runs of one system differ: the median and 90th percentile of |difference of CR| and
    of |log ratio of ATE|, and the share of pairs whose CR differs by more than 0.3."""
    dcr = np.abs(np.asarray(a_cr, float) - np.asarray(b_cr, float))
    with np.errstate(divide="ignore", invalid="ignore"):
        rat = np.abs(np.log(np.asarray(a_ate, float) / np.asarray(b_ate, float)))
    rat = rat[np.isfinite(rat)]
    return dict(cr_median=float(np.median(dcr)), cr_p90=float(np.quantile(dcr, 0.9)),
                cr_over_0_3=float(np.mean(dcr > 0.3)), ate_median=float(np.median(rat)),
                ate_p90=float(np.quantile(rat, 0.9)))  # fmt: skip


def generator_pairs(pool: Pool) -> dict[str, float]:
    """:func:`pair_spread` of two reruns of every sequence (rerun 1 against rerun 2, 3 against 4, ...)."""
    a, b = pool.tables[0::2], pool.tables[1::2]
    keys = ["algorithm", "scene", "seq"]
    merged = pd.concat([x[keys + ["cr", "ate_rmse"]].merge(y[keys + ["cr", "ate_rmse"]], on=keys, suffixes=("_a", "_b"))
                        for x, y in zip(a, b, strict=False)], ignore_index=True)  # fmt: skip
    return pair_spread(merged["cr_a"], merged["cr_b"], merged["ate_rmse_a"], merged["ate_rmse_b"])


def stopped_early(data_root: str | None = None, before: float = 0.75) -> pd.DataFrame:
    """How often a real SLAM output stops before its recording ends: per icra20 mode (``per-seq``,
    ``lifelong``), the runs (one algorithm on one sequence with ground truth and any output) and the
    share whose last pose comes before ``before`` of the ground truth's span. A trial that stopped
    halfway looks exactly like these (a system that lost track for good), so the gate cannot tell
    a crash from a loss of tracking by where the output ends; CR judges both."""
    if not 0 < finite("before", before, "a share of the recording") <= 1:
        raise ValidationError(f"before={before!r}: expected a share of the recording, more than 0 and at most 1")
    data = find_data(data_root)
    have = set(data.scenes_with_groundtruth())
    gts = {s: load_groundtruth(s, data) for s in sorted(have)}
    rows = []
    for mode in ("per-seq", "lifelong"):
        ends = []
        for path in sorted((data.icra20 / mode).rglob("*.txt")):
            rf = read_openloris(path, warn=False)
            if rf.scene not in have:
                continue
            for q, traj in rf.sequences.items():
                g = gts[rf.scene].sequences.get(q)
                if g is None or len(traj) == 0:
                    continue
                g0, g1 = float(g.stamps[0]), float(g.stamps[-1])
                ends.append((float(traj.stamps[-1]) - g0) / (g1 - g0))
        e = np.array(ends)
        rows.append(dict(mode=mode, runs=len(e), before=before, stopped=int(np.sum(e < before)),
                         share=float(np.mean(e < before)) if len(e) else np.nan))  # fmt: skip
    return pd.DataFrame(rows)


#: System-wide changes of one run per side (:func:`single_run_rates`): every sequence of a system
#: changed at once, alone or with another system changed the other way (one better, one worse), as
#: (name, {algorithm: (columns, how)}): ``how`` a factor for the errors, an amount added for rates.
SYSTEM_CHANGES: tuple[tuple[str, dict[str, tuple[tuple[str, ...], str, float]]], ...] = (
    ("orbslam2 ATE x10", {"orbslam2_rgbd": (("ate_rmse", "c_ate_rmse"), "x", 10.0)}),
    ("orbslam2 ATE x10, infinitam ATE /2", {"orbslam2_rgbd": (("ate_rmse", "c_ate_rmse"), "x", 10.0),
                                            "infinitam_aligned_depth": (("ate_rmse", "c_ate_rmse"), "x", 0.5)}),
    ("orbslam2 CR -0.3", {"orbslam2_rgbd": (("cr", "cr_t"), "+", -0.3)}),
    ("orbslam2 CR -0.3, infinitam CR +0.3", {"orbslam2_rgbd": (("cr", "cr_t"), "+", -0.3),
                                             "infinitam_aligned_depth": (("cr", "cr_t"), "+", 0.3)}),
)  # fmt: skip


def _system_changed(t: pd.DataFrame, change: Mapping[str, tuple[tuple[str, ...], str, float]]) -> pd.DataFrame:
    t = t.copy()
    for alg, (cols, how, amount) in change.items():
        here = t["algorithm"] == alg
        for c in cols:
            x = t.loc[here, c].astype(float)
            t.loc[here, c] = x * amount if how == "x" else (x + amount).clip(0.0, 1.0)
    return t


def single_run_rates(pool: Pool, nights: int = 100, seed: int = 7,
                     progress: Callable[[Iterable], Iterable] = lambda x: x) -> pd.DataFrame:  # fmt: skip
    """The verdict of one run per side on whole-system changes (:data:`SYSTEM_CHANGES`, a CAND
    table changed after scoring) and on the same nights without a change: one row per check with
    ``nights``, ``hits`` (a false alarm: any regression; a change: a regression of the system made
    worse) and ``rate`` with a 95 % Wilson interval. A system better on every sequence beside
    another worse on every sequence set the single-run band from this diff's own changes and hid
    both (:func:`lorisnb.core.stats.regression._single_bands`)."""
    tol = parse_tolerances()
    rng = np.random.default_rng(seed)
    hits: dict[str, list[int]] = {"false alarm": []}
    for _ in progress(range(nights)):
        b, c = _night(pool, 1, rng)
        hits["false alarm"].append(int(diff_tables(b, c, tol, expected=pool.expected).regressed))
        for name, change in SYSTEM_CHANGES:
            worse = [a for a, (_, how, amount) in change.items() if (how == "x") == (amount > 1)]
            v = diff_tables(b, _system_changed(c, change), tol, expected=pool.expected).verdict
            hits.setdefault(name, []).append(int(any(r["algorithm"] in worse for r in v["regressions"])))
    rows = []
    for what, h in hits.items():
        lo, hi = wilson(sum(h), len(h))
        rows.append(dict(check=what, nights=len(h), hits=sum(h), rate=sum(h) / len(h), low=lo, high=hi))
    return pd.DataFrame(rows)
