"""Did a candidate run regress against a base run? The verdict of ``lorisnb diff``, ``history``
and the report's "since the baseline": one decision rule for every sequence, scene and metric.

Both runs are per-sequence tables (:func:`lorisnb.core.lifelong.scoring.score`, with trials or not).
A sequence is matched by (suite, algorithm, scene, seq). Every comparison of a diff is one test of
one **family**, and the family-wise error rate is held at ``alpha`` (Holm's step-down correction
over all of them): a noise-only diff ends in "regression" in at most ``alpha`` of the cases,
however many sequences, scenes and metrics it holds. The harness that measures this on reruns
made from the bundled real outputs is ``make calibrate`` (``benchmarks/calibrate.py``).

**What is compared.** Per sequence every metric of :data:`METRICS`; per scene the scene values of
:data:`lorisnb.core.stats.inference.WEIGHTS` (CR by duration, ...), computed for each trial over
all the scene's sequences (a sequence or trial the run lacks counts as a failed run). Rates (CR,
CR-T, CS-R) are compared as they are; errors (ATE, AOE, RPE: :data:`LOG_METRICS`) on a log scale,
as relative changes, because their rerun spread grows with their size.

**The rule.** ``d`` is how much worse the candidate is (mean over trials; + is worse) and ``tol``
the metric's tolerance (:data:`~lorisnb.core.stats.tolerances.DEFAULT_TOLERANCES`). The test asks
whether the change is *beyond the tolerance*: ``z = (d - tol) / se``, one-sided.

- **With trials** (at least two independent values on each side): ``se`` from the trials' own spread,
  moderated *upwards* across the diff's comparisons of the same metric and level (the
  empirical-Bayes variance of Smyth 2004, limma's ``squeezeVar``, taken only where it is larger than
  the comparison's own: a sequence whose reruns flip keeps its large spread), never below a quarter
  of :data:`~lorisnb.core.stats.tolerances.RERUN_SPREAD`; a t distribution with the pooled degrees
  of freedom gives p. Tied trial values (all CR 1.0) are tested like any others, never p = 1.
- **One run on a side** (one independent value of BASE or of CAND, whatever the other holds: a
  single value has no spread, and the other side's alone, tied perhaps, decided a t-test; 1 BASE run
  against 3 CAND trials failed 10 of 80 noise-only nights so, ``make calibrate`` measures every
  design): no significance can be claimed. The change must go beyond the tolerance
  plus a rerun band, :data:`~lorisnb.core.stats.tolerances.SINGLE_RUN_BAND` (the largest change
  noise-only single-run diffs of reruns show, measured by ``make calibrate``), widened where the
  changes of the comparison's own system (suite and algorithm) are larger, by the smaller of their
  two tails (:func:`_single_bands`; another system's changes never widen it); the output says so.

A comparison with trials is a regression when its Holm-adjusted p (over every comparison with
trials of the diff) is at most ``alpha`` (so ``d > tol``); an improvement likewise in the other
direction (a separate family). An algorithm with both is a
**trade-off** (:func:`verdict`).

**Copies of one run are one run.** Trials of an algorithm whose CR and ATE vary between them (median
over its sequences) by less than a quarter of what real reruns show (:func:`trial_copies`, the
pseudo-replicates of ``compare``) are counted as one run, their mean; a trial that repeats every
value of another trial of the sequence (or of the scene) counts once. Three copies a side are thus
judged as a single run per side, no significance claimed; ``decided_by`` says so. The copies are
the trials with output: a failed run (no pose matched, or a missing trial) counts as a run of its
own. ``decided_by`` counts trials as ``trials_base`` and ``trials_cand`` do (every trial, failed ones
too), then how many values the test took where fewer, and why.

**Coverage and failures** (no test needed; always a regression): a sequence the base has and the
candidate lacks (``missing``), scores with nothing matched (``failed``; unless its base matched
fewer than :data:`MIN_MATCHED` poses in every trial: too little to judge, as every comparison of so
few poses; at eps = inf every matched pose is correct, so the old exemption, "none of them
correct", never applied there), or holds fewer trials than the candidate's other sequences or than the base
(``missing trial``: the trial counts as a failed run in every value, and is named), or holds
more trials with no pose matched (a file written without a pose, :func:`_failed_trials`) and
missing than the base holds failed runs there, most of its trials (``trial 2, 3 no pose matched``),
or holds
fewer independent runs than the base because a trial is a copy of another (``trial 3 a copy``:
a crashed trial filled in with another's output). Trial numbers
are labels, not pairings: the candidate's trials 4 to 6 against the base's 1 to 3 lack nothing, and
trials the candidate holds beyond the base's are no failed runs of the base; an unnumbered run
(trial 0) is one trial, so against the base's 1 to 3 it lacks 2 and 3; trials numbered from 0
(``run_0/``: a sequence holds trial 0 beside others) count trial 0 as one of them. A candidate's new
sequence is listed, not judged.

**Too little to judge** (``unjudged``, never a regression): a sequence whose base matched fewer
than :data:`MIN_MATCHED` poses, or whose matched positions hold the alignment's rotation by a
lever under :data:`~lorisnb.core.stats.tolerances.MIN_LEVER` (column ``rotation_lever``: a tiny or
near-straight piece, where 5 mm of position noise turns the fit by more than a degree and can
move a 15-pose sequence's AOE by 10 degrees), for every metric; its error metrics (ATE, AOE, RPE,
C-*) also when the candidate's are short or ill-held likewise, or for C-* metrics fewer than
:data:`MIN_MATCHED` correct poses.
Its rates are still judged when only the candidate is short: a sequence that stopped tracking
regressed. CS-R where the trials (of both runs) disagree on whether the first pose is correct: CS-R
is 0 when it is not (Eq. 4 as the official tool computes it), a yes/no outcome of a few runs.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from scipy import special, stats

from lorisnb.core.lifelong.aggregate import has_output
from lorisnb.core.lifelong.coverage import FAILED_RUN, complete, expected_from
from lorisnb.core.spec import validate
from lorisnb.core.stats.inference import WEIGHTS, holm, scene_values, trial_spread, with_trials
from lorisnb.core.stats.tolerances import DEFAULT_TOLERANCES, MIN_LEVER, MIN_MATCHED, RERUN_SPREAD, SINGLE_RUN_BAND
from lorisnb.errors import ValidationError

#: Metrics compared, each with +1 when larger is better and -1 when smaller is better.
METRICS: dict[str, int] = {
    "cr": 1, "cr_t": 1, "cs_r": 1, "ate_rmse": -1, "aoe_rmse": -1, "c_ate_rmse": -1, "c_aoe_rmse": -1,
    "rpe_trans_rmse": -1, "rpe_rot_rmse": -1,
}  # fmt: skip
#: Metrics judged on a log scale (relative changes): the errors. The others are rates in [0, 1].
LOG_METRICS = frozenset(m for m, s in METRICS.items() if s < 0)
KEYS = ["suite", "algorithm", "scene", "seq"]
#: Statuses that fail a diff.
BAD = ("regression", "missing", "failed")
#: Columns of the change tables.
SEQUENCE_COLUMNS = KEYS + ["metric", "base", "cand", "worse_by", "tolerance", "trials_base", "trials_cand", "p_adj",
                           "status", "decided_by"]  # fmt: skip
SCENE_COLUMNS = SEQUENCE_COLUMNS


@dataclass(frozen=True)
class Tolerance:
    """How much worse a metric may get: ``amount`` in the metric's unit, or, when ``relative``, as
    a share of the base value."""

    amount: float
    relative: bool

    def of(self, base: float) -> float:
        return self.amount * abs(base) if self.relative else self.amount

    def __str__(self) -> str:
        return f"{100 * self.amount:g}%" if self.relative else f"{self.amount:g}"

    def scaled(self, metric: str, base: float) -> float:
        """The tolerance on the scale the metric is judged on: the amount for a rate, the log of
        the allowed ratio for an error (``10%`` -> log 1.1; an absolute amount relative to ``base``)."""
        if metric not in LOG_METRICS:
            return self.of(base)
        if self.relative:
            return float(np.log1p(self.amount))
        return float(np.log1p(self.amount / base)) if base > 0 and np.isfinite(base) else np.inf


def parse_tolerances(spec: str | Mapping[str, str | float] | None = None) -> dict[str, Tolerance]:
    """The defaults, updated by ``spec``: ``"cr=0.02,ate_rmse=0.05"`` or a mapping; a value is a
    non-negative number in the metric's unit or a percentage of the base value (``"5%"``). Metrics
    are named in any case (``CR=0.1`` is ``cr=0.1``, as ``history --metric CR`` and every word of the
    command line: docs/guide/errors.md); ``CR`` was refused, "not a compared metric"."""

    def metric(name: object) -> object:
        key = name.strip().lower() if isinstance(name, str) else name
        return key if key in METRICS else name

    items: dict[str, str | float] = dict(DEFAULT_TOLERANCES)
    if isinstance(spec, str):
        parts = [p.strip() for p in spec.split(",")]
        if any(parts) and not all(parts):  # as every comma list: an empty item is refused, not dropped
            raise ValidationError(f"tolerance {spec!r}: an empty item between commas; expected METRIC=VALUE,...")
        given: set[str] = set()
        for part in filter(None, parts):
            name, sep, text = part.partition("=")
            if not sep:
                raise ValidationError(f"tolerance {part!r}: expected METRIC=VALUE, e.g. cr=0.02 or ate_rmse=5%")
            key = str(metric(name.strip()))
            if key in given:  # the last would silently replace the first
                raise ValidationError(f"tolerance {spec!r}: {key} given twice; expected each metric once (in any case)")
            given.add(key)
            items[key] = text.strip()
    elif spec is not None:
        if not isinstance(spec, Mapping):
            raise ValidationError(f"tolerance: expected 'metric=value,...' or a mapping, got {type(spec).__name__}")
        lowered: dict[object, str | float] = {}
        for name, amount in spec.items():
            mkey = metric(name)
            if mkey in lowered:
                raise ValidationError(f"tolerance {mkey}: given twice; expected each metric once (in any case)")
            lowered[mkey] = amount
        items.update(lowered)  # type: ignore[arg-type]
    out = {}
    for name, value in items.items():
        if name not in METRICS:
            raise ValidationError(f"tolerance {name}: not a compared metric; expected one of {', '.join(METRICS)}")
        text = str(value).strip()
        m = re.fullmatch(r"([0-9.eE+-]+)\s*(%?)", text)
        try:
            amount = float(m.group(1)) if m else float("nan")
        except ValueError:
            amount = float("nan")
        if not np.isfinite(amount) or amount < 0 or isinstance(value, bool):
            raise ValidationError(
                f"tolerance {name}={value}: expected a non-negative number in the metric's unit or a percentage (5%)"
            )
        relative = bool(m and m.group(2))
        if name not in LOG_METRICS and (amount >= 100 if relative else amount >= 1):
            raise ValidationError(
                f"tolerance {name}={value}: {name} is a rate between 0 and 1, so no drop would ever exceed it (no "
                "regression could be found); expected less than 1 (or 100%), e.g. cr=0.02"
            )
        out[name] = Tolerance(amount / 100 if relative else amount, relative)
    return out


# --- the statistics -------------------------------------------------------------------------------


@dataclass
class _Comparison:
    """One comparison waiting for the family's decision: its row, and the values of each side on
    the judged scale (log for errors), signed so that larger ``d`` is worse."""

    row: dict
    base: np.ndarray
    cand: np.ndarray
    sign: int
    tol: float
    floor: float
    note: str = ""

    @property
    def d(self) -> float:
        return self.sign * (float(self.base.mean()) - float(self.cand.mean()))

    @property
    def counted(self) -> str:
        """The trials of each side (the row's ``trials_base`` and ``trials_cand``: every trial, a
        failed one too) and, where the test took fewer values (a failed run without an error to
        take, copies of one run counted once), how many: one count in every column and sentence."""
        nb, nc, tb, tc = len(self.base), len(self.cand), self.row["trials_base"], self.row["trials_cand"]
        return f"{tb} vs {tc} trials" + (f", tested on {nb} vs {nc} values" if (nb, nc) != (tb, tc) else "")


def _trigamma_inverse(x: float) -> float:
    """y with trigamma(y) = x (x > 0), by Newton's method as in limma's ``trigammaInverse``."""
    if x > 1e7:
        return 1.0 / np.sqrt(x)
    if x < 1e-6:
        return 1.0 / x
    y = 0.5 + 1.0 / x
    for _ in range(50):
        tri = float(special.polygamma(1, y))
        step = tri * (1 - tri / x) / float(special.polygamma(2, y))
        y += step
        if -step / y < 1e-8:
            break
    return y


def variance_prior(s2: np.ndarray, df: np.ndarray) -> tuple[float, float]:
    """(s0^2, d0): the scaled inverse chi-square prior of the comparisons' variances, fitted by
    moments of log s^2 (Smyth 2004, limma's ``fitFDist``). Variances of 0 (tied trials) and
    comparisons without degrees of freedom are left out of the fit. (nan, 0) when fewer than three
    remain: no prior, each comparison on its own."""
    s2, df = np.asarray(s2, float), np.asarray(df, float)
    ok = (df > 0) & np.isfinite(s2) & (s2 > 0)
    if ok.sum() < 3:
        return np.nan, 0.0
    z = np.log(s2[ok])
    e = z - special.digamma(df[ok] / 2) + np.log(df[ok] / 2)
    emean = float(e.mean())
    evar = float(np.var(e, ddof=1) - np.mean(special.polygamma(1, df[ok] / 2)))
    if evar > 0:
        d0 = 2 * _trigamma_inverse(evar)
        s0 = float(np.exp(emean + special.digamma(d0 / 2) - np.log(d0 / 2)))
    else:  # the variances differ no more than chance: one common spread
        d0, s0 = np.inf, float(np.exp(emean))
    return s0, float(min(d0, 1e6))


def _family_p(comps: list[_Comparison], levels: list[str]) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """p-values (worse, better) of comparisons with trials, before the family's correction: the
    change beyond the tolerance over its standard error, whose variance is the comparison's own
    trial variance moderated upwards towards the spread of its metric and level across the diff
    (Smyth 2004, limma's ``squeezeVar``, taken only where it is larger than the comparison's own;
    never below a quarter of the rerun variance), with a t distribution of the pooled degrees of
    freedom."""
    p_w, p_b = np.full(len(comps), np.nan), np.full(len(comps), np.nan)
    how = [""] * len(comps)
    groups: dict[tuple[str, str], list[int]] = {}
    for i, (c, level) in enumerate(zip(comps, levels, strict=True)):
        groups.setdefault((c.row["metric"], level), []).append(i)
    for idx in groups.values():
        cs = [comps[i] for i in idx]
        nb = np.array([len(c.base) for c in cs], float)
        nc = np.array([len(c.cand) for c in cs], float)
        df = nb + nc - 2
        ss = np.array(
            [float(((c.base - c.base.mean()) ** 2).sum() + ((c.cand - c.cand.mean()) ** 2).sum()) for c in cs]
        )
        with np.errstate(invalid="ignore", divide="ignore"):
            s2 = np.where(df > 0, ss / np.maximum(df, 1), np.nan)
        s0, d0 = variance_prior(s2, df)
        floor = cs[0].floor
        if not np.isfinite(s0):  # too few spreads to pool: the rerun variance as a prior of 4 degrees of freedom
            s0, d0 = floor**2, 4.0
        post = s0 if not np.isfinite(d0) else (d0 * s0 + df * np.nan_to_num(s2)) / (d0 + df)
        # pulled up towards the diff's spread, never down: a sequence whose reruns flip between tracking
        # and not (its own spread far above the others') keeps its own spread
        post = np.maximum(np.maximum(post, np.nan_to_num(s2)), (floor / 2) ** 2)
        se = np.sqrt(post * (1 / nb + 1 / nc))
        dof = np.minimum(df + d0, 1e6)
        d = np.array([c.d for c in cs])
        tol = np.array([c.tol for c in cs])
        p_w[idx] = stats.t.sf((d - tol) / se, dof)
        p_b[idx] = stats.t.sf((-d - tol) / se, dof)
        for k, i in enumerate(idx):
            how[i] = f"{cs[k].counted}, spread pooled over {len(cs)} comparisons (prior df {min(d0, 999):.3g})"
    return p_w, p_b, how


#: How far a single-run band widens with a system's own changes: this many times the smaller of the
#: 90th percentiles of its changes for the worse and for the better (:func:`_single_bands`). 5 x 1.28
#: sigma (the 90th percentile of one signed tail of normal noise) is about the 4 x 1.64 sigma of the
#: 90th percentile of unsigned changes that it replaced.
WIDEN = 5.0
#: The fewest changes of one system, metric and level whose tails widen its band (:func:`_single_bands`).
MIN_WIDEN = 10


def _widened(ds: np.ndarray) -> float:
    """:data:`WIDEN` times the smaller of the 90th percentiles of ``ds`` for the worse and for the
    better (0 where fewer than :data:`MIN_WIDEN` are finite)."""
    ds = ds[np.isfinite(ds)]
    if ds.size < MIN_WIDEN:
        return 0.0
    return WIDEN * max(0.0, min(float(np.quantile(ds, 0.9)), float(np.quantile(-ds, 0.9))))


def _single_bands(comps: list[_Comparison], levels: list[str]) -> list[float]:
    """The band a change of a single run per side must exceed beyond its tolerance (on the judged
    scale): :data:`~lorisnb.core.stats.tolerances.SINGLE_RUN_BAND` of its level and metric, widened
    where the changes of **its own system** (suite and algorithm) are larger, a noisier system than
    the calibration's: to :data:`WIDEN` times the smaller of the 90th percentiles of that system's
    changes of the metric for the worse and for the better, at the sequence level (at least
    :data:`MIN_WIDEN` of them), and the scene band by the same factor over its calibrated band (a
    system holds a handful of scenes), or by the scenes' own tails where it holds
    :data:`MIN_WIDEN` of them. Rerun noise moves values both ways alike; a regression moves them
    one way, so it widens only its own tail, and an improvement only the other. Estimated over all
    the diff's systems together, the tails were set by real changes: one system better and another
    worse (orbslam2's ATE x10 and infinitam's halved, orbslam2's CR -0.3 and infinitam's +0.3) each
    filled a tail, and the band swallowed both (exit 0). Another system's changes now never widen a
    system's band; a system that got better on some sequences and worse on others by more than a
    tenth of them each is judged as a noisy one (no regression claimed within its changes)."""
    groups: dict[tuple, list[int]] = {}
    for i, (c, level) in enumerate(zip(comps, levels, strict=True)):
        groups.setdefault((c.row["suite"], c.row["algorithm"], c.row["metric"], level), []).append(i)
    factor: dict[tuple, float] = {}  # per system and metric: its sequence band's widening
    for (suite, alg, metric, level), idx in groups.items():
        if level == "sequence":
            base = SINGLE_RUN_BAND[level][metric]
            wide = _widened(np.asarray([comps[i].d for i in idx], float))
            factor[(suite, alg, metric)] = max(1.0, wide / base) if base > 0 else 1.0
    bands = [0.0] * len(comps)
    for (suite, alg, metric, level), idx in groups.items():
        base = SINGLE_RUN_BAND[level][metric]
        band = max(base * factor.get((suite, alg, metric), 1.0), _widened(np.asarray([comps[i].d for i in idx], float)))
        for i in idx:
            bands[i] = band
    return bands


def _transform(metric: str, x: np.ndarray) -> np.ndarray:
    """Values on the scale a metric is judged on: the log of an error (positive values only), a rate as it is."""
    x = np.asarray(x, float)
    if metric in LOG_METRICS:
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.log(np.where(x > 0, x, np.nan))
    return x


class _Comparisons:
    """Every comparison of one diff, in order, with the families the tests are pooled in."""

    def __init__(self, tolerances: Mapping[str, Tolerance]) -> None:
        self.tols = tolerances
        self.rows: dict[str, list[dict]] = {"sequence": [], "scene": []}
        self.waiting: list[_Comparison] = []

    def coverage(self, level: str, label: dict, metric: str, base: str, cand: str, status: str, why: str) -> None:
        """A comparison decided by coverage alone (a sequence or trial missing, failed or new)."""
        self.rows[level].append(dict(label, metric=metric, base=base, cand=cand, status=status, decided_by=why))

    def add(self, level: str, label: dict, metric: str, xb: np.ndarray, xc: np.ndarray, unjudged: str | None,
            independent: tuple[np.ndarray, np.ndarray] | None = None, note: str = "") -> None:  # fmt: skip
        """One metric of one sequence or scene: the values of its trials on each side (NaN where
        undefined); tested later, with its family, unless decided here. ``independent``: the values
        that are independent runs (copies of one run counted once, :func:`_Side.independent`), which
        the test uses; ``note`` says why they are fewer."""
        tol = self.tols[metric]
        fb, fc = xb[np.isfinite(xb)], xc[np.isfinite(xc)]
        vb = float(fb.mean()) if fb.size else np.nan
        vc = float(fc.mean()) if fc.size else np.nan
        sign = METRICS[metric]
        row = dict(label, metric=metric, base=vb, cand=vc, tolerance=str(tol), trials_base=len(xb),
                   trials_cand=len(xc), p_adj=np.nan, status="ok", decided_by="")  # fmt: skip
        row["worse_by"] = sign * (vb - vc) if np.isfinite(vb) and np.isfinite(vc) else np.nan
        self.rows[level].append(row)
        if unjudged:
            row.update(status="unjudged", decided_by=f"too little to judge: {unjudged}")
            return
        if not np.isfinite(vb):
            row["decided_by"] = "undefined in the base: nothing to compare"
            return
        if not np.isfinite(vc):  # no correct pose left: the rates say how much worse
            row.update(status="unjudged", decided_by="too little to judge: undefined in the candidate (no pose to "
                       "take it over); its rates are judged")  # fmt: skip
            return
        if independent is not None:
            fb, fc = (x[np.isfinite(x)] for x in independent)
        lacking = [f"{k} of {name}'s trials have no {metric} (no pose to take it over)" for name, x in
                   (("BASE", xb), ("CAND", xc)) if (k := int((~np.isfinite(_transform(metric, x))).sum()))]  # fmt: skip
        note = "; ".join(x for x in (note, *lacking) if x)
        gb, gc = _transform(metric, fb), _transform(metric, fc)
        gb, gc = gb[np.isfinite(gb)], gc[np.isfinite(gc)]
        if not gb.size or not gc.size:
            row.update(status="unjudged", decided_by="too little to judge: an error of 0 on one side")
            return
        floor = RERUN_SPREAD["log" if metric in LOG_METRICS else "rate"]
        self.waiting.append(_Comparison(row, gb, gc, sign, tol.scaled(metric, vb), floor, note))

    def judge(self, alpha: float) -> tuple[pd.DataFrame, pd.DataFrame]:
        """Decide every waiting comparison as one family (see the module docstring) and return
        the two tables."""
        # a side of one value has no spread of its own: the other side's alone (tied, perhaps: a
        # sequence whose reruns flip between two values) decided the test, and 1 BASE run against 3
        # CAND trials failed 12.5 % of noise-only nights; such a comparison is judged as single runs
        trials = [c for c in self.waiting if min(len(c.base), len(c.cand)) >= 2]
        single = [c for c in self.waiting if min(len(c.base), len(c.cand)) < 2]
        levels = ["scene" if c.row["seq"] is None else "sequence" for c in single]
        if trials:
            levels_t = ["scene" if c.row["seq"] is None else "sequence" for c in trials]
            p_w, p_b, how = _family_p(trials, levels_t)
            adj_w, adj_b = holm(p_w), holm(p_b)
            for c, pw, pb, h in zip(trials, adj_w, adj_b, how, strict=True):
                self._decide(c, pw, pb, alpha, f"t-test of the change beyond the tolerance ({h}); Holm over the "
                             f"diff's {len(trials)} tests, family-wise alpha {alpha:g}")  # fmt: skip
        if single:
            for c, band, level in zip(single, _single_bands(single, levels), levels, strict=True):
                shown = f"{band:.3g}" if c.floor == RERUN_SPREAD["rate"] else f"x{np.exp(band):.3g}"
                up, down = c.d - c.tol > band, -c.d - c.tol > band
                what = ("the largest change noise-only single runs show" if band <= SINGLE_RUN_BAND[level][c.row["metric"]]
                        else f"{c.row['algorithm']}'s own noise in this diff, the smaller of its changes for the "
                        "worse and for the better, wider than the largest change noise-only single runs show")  # fmt: skip
                runs = ("single run per side" if (len(c.base), len(c.cand)) == (1, 1) else "a single run on one side") + (
                    "" if (c.row["trials_base"], c.row["trials_cand"]) == (1, 1) else f" ({c.counted})")  # fmt: skip
                c.row.update(status="regression" if up else ("improvement" if down else "ok"),
                             decided_by=f"{runs}: no significance claimed; judged by the tolerance "
                             f"widened by the rerun band ({shown}: {what})")  # fmt: skip
        for c in self.waiting:
            if c.note:
                c.row["decided_by"] += f"; {c.note}"
        seqs = pd.DataFrame(self.rows["sequence"], columns=SEQUENCE_COLUMNS)
        scenes = pd.DataFrame(self.rows["scene"], columns=SCENE_COLUMNS)
        parts = []
        if trials:
            parts.append(f"{len(trials)} comparison(s) with trials by t-tests of the change beyond the tolerance, "
                         f"spreads pooled per metric, Holm over all of them (family-wise alpha {alpha:g})")  # fmt: skip
        if single:
            parts.append(f"{len(single)} comparison(s) of one run per side (or on one side) by the tolerance widened by the rerun "
                         "band (no significance claimed)")  # fmt: skip
        parts.append("a missing or failed sequence or trial always regresses; too little to judge never does")
        seqs.attrs["rule"] = scenes.attrs["rule"] = "; ".join(parts)
        return seqs, scenes

    @staticmethod
    def _decide(c: _Comparison, p_worse: float, p_better: float, alpha: float, how: str) -> None:
        worse, better = p_worse <= alpha, p_better <= alpha
        c.row.update(p_adj=float(p_worse if worse or not better else p_better), decided_by=how,
                     status="regression" if worse else ("improvement" if better else "ok"))  # fmt: skip


def _labels(t: pd.DataFrame) -> dict[tuple, set]:
    """Each (suite, algorithm)'s trial labels in one run's table. Trial 0 is ambiguous in a table: a
    file without a trial token (the unnumbered run) or a real label (``trial0/``, ``run_0/``, which
    the default tokens read). It is a label of its own where some sequence holds trial 0 together
    with another trial (trials numbered from 0, or an unnumbered file beside numbered ones: a run of
    its own either way). Else, where numbered trials exist, it is the unnumbered stand-in: a sequence holding only it holds one of the run's trials (:func:`_padded`),
    whatever the others' numbers. Trial 0 was dropped wherever numbered trials existed: a 0-based run
    whose trial 2 was lost everywhere had its trial 0 relabelled as trial 2, and nothing was missing."""
    out = {}
    for k, g in t.groupby(["suite", "algorithm"], sort=False, observed=True):
        trials = set(g["trial"])
        numbered = trials - {0}
        per_seq = g.groupby(KEYS[2:], sort=False, observed=True, dropna=False)["trial"]
        zero_based = bool(numbered) and bool(per_seq.agg(lambda x: (x == 0).any() and (x != 0).any()).any())
        out[k] = trials if zero_based or not numbered else numbered
    return out


def _trial_sets(b: pd.DataFrame, c: pd.DataFrame) -> tuple[dict[tuple, list], dict[tuple, list]]:
    """The trials expected of every sequence of each (suite, algorithm), for BASE and for CAND. A run
    is expected to hold, for every sequence, each trial it holds for any of them (one a sequence
    lacks is a failed run of it); CAND is also expected to hold as many trials as BASE (where it
    holds fewer, the base's trial numbers it lacks are failed runs). Trial numbers are labels, not
    pairings: CAND's trials 4 to 6 against BASE's 1 to 3 lack nothing, and trials CAND holds beyond
    BASE's are no failed runs of BASE. An unnumbered trial (trial 0: files without a trial token) is
    one trial like any other: CAND's single unnumbered run against BASE's trials 1 to 3 lacks two of
    them (named 2, 3, as a CAND of run_1/ would), BASE's single run against CAND's three lacks
    nothing; where a run numbers some sequences' trials and not others', a sequence's trial 0 stands
    for one of the numbered trials (:func:`_padded`); where a sequence holds trial 0 beside another,
    0 is a label like any other (trials numbered from 0, :func:`_labels`). Each side is read from its
    own table: BASE's 0-based trials 0 to 2 against CAND's 1 and 2 lack trial 0."""
    tb, tc = _labels(b), _labels(c)
    eb, ec = {}, {}
    for k in dict.fromkeys([*tb, *tc]):
        x, y = tb.get(k, set()), tc.get(k, set())
        short = len(x) - len(y) if x and y else 0
        eb[k] = sorted(x)
        ec[k] = sorted(y | set(sorted(x - y)[-short:] if short > 0 else []))
    return eb, ec


def _padded(t: pd.DataFrame, trials: Mapping[tuple, list]) -> tuple[pd.DataFrame, dict[tuple, list]]:
    """The table with each sequence's missing trials added as failed runs (paper: missing output
    scores 0), and which trials each sequence lacked. A sequence's trial outside the expected ones
    (an unnumbered trial 0 in a run that numbers its other sequences' trials) is one of them: it
    takes the first label the sequence lacks, and only the rest are missing."""
    added, lacking = [], {}
    t = t.copy()
    trial_col = t["trial"].to_numpy().copy()
    relabelled = False
    for key, rows in t.groupby(KEYS, sort=False, observed=True, dropna=False).indices.items():
        expected = trials.get((key[0], key[1]), [])
        have = set(trial_col[rows])
        absent = [k for k in expected if k not in have]
        extra = [i for i in rows if trial_col[i] not in expected]
        for i, k in zip(extra, list(absent), strict=False):  # an unnumbered trial stands for a lacking one
            trial_col[i] = k
            absent.remove(k)
            relabelled = True
        if not absent:
            continue
        lacking[key] = absent
        template = t.iloc[rows[0]].to_dict()
        for k in absent:
            row = {c: template[c] for c in ("suite", "algorithm", "scene", "seq", "gt_duration", "eps", "phi",
                                             "delta", "tau", "frame", "mode") if c in t.columns}  # fmt: skip
            row.update({c: v for c, v in FAILED_RUN.items() if c in t.columns}, trial=k, file="")
            added.append(row)
    if relabelled:
        t["trial"] = trial_col
    if added:
        extra_rows = pd.DataFrame(added).reindex(columns=t.columns)
        t = pd.concat([t, extra_rows.astype({c: float for c in FAILED_RUN if c in extra_rows.columns})],
                      ignore_index=True)  # fmt: skip
    return t, lacking


def _unjudged(metric: str, matched: tuple[float, float], correct: tuple[float, float], fragile: bool = False,
              lever: tuple[float, float] = (np.inf, np.inf)) -> str | None:  # fmt: skip
    """Why a sequence's metric is too little to judge (None: it is judged), from the mean matched
    and correct poses of (base, candidate), whether the trials of both runs disagree on whether
    the first pose is correct (``fragile``, for CS-R) and the smallest rotation lever of each side
    (metres; infinite where the table has none); see the module docstring."""
    nb, nc = matched
    if nb < MIN_MATCHED:
        return f"the base matched {nb:.0f} poses (fewer than {MIN_MATCHED}: its alignment is unstable)"
    if lever[0] < MIN_LEVER:
        return (f"the base's matched positions hold its alignment by a lever of {lever[0]:.3g} m (under {MIN_LEVER} m: "
                f"5 mm of position noise turns the fit by {np.degrees(0.005 / max(lever[0], 1e-9)):.2g} deg)")  # fmt: skip
    if metric in LOG_METRICS and nc < MIN_MATCHED:
        return f"the candidate matched {nc:.0f} poses (fewer than {MIN_MATCHED}); its rates are judged"
    if metric in LOG_METRICS and lever[1] < MIN_LEVER:
        return (f"the candidate's matched positions hold its alignment by a lever of {lever[1]:.3g} m (under "
                f"{MIN_LEVER} m); its rates are judged")  # fmt: skip
    if metric.startswith("c_") and min(correct) < MIN_MATCHED:
        return f"{min(correct):.0f} correct poses on one side (fewer than {MIN_MATCHED})"
    if metric == "cs_r" and fragile:
        return ("its trials disagree on whether the first pose is correct, on which CS-R hinges (0 when it is "
                "not): a yes/no outcome of a few runs; CR judges the tracking")  # fmt: skip
    return None


#: Relative difference under which two trials' values are the same value (:func:`repeated_trials`):
#: a copy with one digit of one pose changed moves an ATE by about 1e-6; real reruns differ by a
#: median 18 % in ATE and 0.016 in CR (:data:`~lorisnb.core.stats.tolerances.RERUN_SPREAD`).
SAME_VALUE = 1e-4


def repeated_trials(table: pd.DataFrame) -> np.ndarray:
    """Which rows of a per-sequence table (with ``suite`` and ``trial`` columns) are trials with
    output whose every judged value (:data:`METRICS` and ``matched``) repeats an earlier trial's of
    the same sequence, within :data:`SAME_VALUE` relative: copies of it (a file copied into another
    trial's folder, or copied with a pose edited), no run. ``diff`` counts such a trial once and as a
    missing trial; ``compare`` counts it once. Compared exactly (``duplicated``), a copy with one
    digit of one pose changed passed as a rerun, and ``compare`` called two labels of one system
    different in 6 of 25 of a helper's draws."""
    return repeated_of(table) >= 0


def repeated_of(table: pd.DataFrame) -> np.ndarray:
    """For each row, the position of the earlier row of its sequence whose trial it repeats
    (:func:`repeated_trials`), else -1."""
    cols = [
        pd.to_numeric(table[c], errors="coerce").to_numpy(float) for c in (*METRICS, "matched") if c in table.columns
    ]
    values = np.column_stack(cols) if cols else np.zeros((len(table), 0))
    out = table["matched"].to_numpy(float) > 0 if "matched" in table.columns else np.ones(len(table), bool)
    of = np.full(len(table), -1)
    groups = table.groupby(KEYS, sort=False, observed=True, dropna=False).indices if len(table) else {}
    for idx in groups.values():  # a handful of trials a sequence: every pair of them at once
        if len(idx) < 2:
            continue
        first = same_values(values[idx])
        of[idx] = np.where((first >= 0) & out[idx], idx[np.maximum(first, 0)], -1)
    return of


def same_values(rows: np.ndarray, others: np.ndarray | None = None) -> np.ndarray:
    """The one rule of copies (:data:`SAME_VALUE`), for a sequence's trials and a scene's alike: for
    each row of ``rows`` (trials x values), the position of the earlier row whose every value it
    repeats within :data:`SAME_VALUE` relative (NaN as NaN), else -1; with ``others`` (the other
    side's trials), the position of the first row of ``others`` it repeats instead."""
    rows = np.asarray(rows, float)
    ref = rows if others is None else np.asarray(others, float)
    if not len(rows) or not len(ref):
        return np.full(len(rows), -1)
    with np.errstate(invalid="ignore"):
        same = np.isclose(rows[:, None, :], ref[None, :, :], rtol=SAME_VALUE, atol=0.0, equal_nan=True).all(axis=2)
    if others is None:
        same &= np.tri(len(rows), k=-1, dtype=bool)  # an earlier trial only
    return np.where(same.any(axis=1), same.argmax(axis=1), -1)


class _Side:
    """One run's per-sequence table as arrays: the rows of each sequence, and its columns."""

    def __init__(self, table: pd.DataFrame, name: str, one_run: Mapping[tuple, str] | None = None) -> None:
        self.table, self.name = table, name
        self.rows = {k: v for k, v in table.groupby(KEYS, sort=False, observed=True, dropna=False).indices.items()}
        self.cols = {c: pd.to_numeric(table[c], errors="coerce").to_numpy(float)
                     for c in (*METRICS, "matched", "c_matched", "first_correct", "rotation_lever")
                     if c in table.columns}  # fmt: skip
        self.trials = table["trial"].to_numpy()
        #: (suite, algorithm) whose trials are near-identical copies of one run, with what varies
        self.one_run = dict(one_run or {})
        self.copy_of = repeated_of(table) if len(table) else None  # the row each copy repeats, else -1
        self.copy = self.copy_of >= 0 if self.copy_of is not None else None
        #: rows repeating a trial of the other side (``repeats_of``), with that side's trial
        self.from_other: dict[int, Any] = {}
        self.other = ""

    def repeats_of(self, other: _Side) -> None:
        """Mark this side's trials that repeat every value of a trial of ``other`` (the same
        sequence; the rule of copies within a side, :func:`same_values`) as copies: a CAND padded with
        BASE's own trial files holds no run in them (its regression hid behind them: "ok"). Where
        every trial with output of a sequence repeats the other side's, the sequence is unchanged
        (one run kept on both sides, which ``diff`` names), no padding: left as it is."""
        if self.copy is None or other.copy is None:
            return
        cols = [c for c in (*METRICS, "matched") if c in self.cols and c in other.cols]
        mine = np.column_stack([self.cols[c] for c in cols]) if cols else np.zeros((len(self.table), 0))
        theirs = np.column_stack([other.cols[c] for c in cols]) if cols else np.zeros((len(other.table), 0))
        self.other = other.name
        judged = np.array([c in METRICS for c in cols], bool)  # a copy repeats three values or more, not a CR alone
        for key, rows in self.rows.items():
            orows = other.rows.get(key)
            if orows is None or not cols:
                continue
            src = same_values(mine[rows], theirs[orows])
            if (src >= 0).any():  # the other side's trial of the same number kept is that trial unchanged, no padding
                src = np.where(other.trials[orows[np.maximum(src, 0)]] != self.trials[rows], src, -1)
            out = self.output(rows) & (np.isfinite(mine[rows][:, judged]).sum(axis=1) >= 3)
            cross = (src >= 0) & out & ~self.copy[rows]
            if not cross.any() or not (out & ~self.copy[rows] & ~cross).any():
                continue
            for i in np.flatnonzero(cross):
                self.from_other[int(rows[i])] = other.trials[orows[src[i]]]
            self.copy[rows[cross]] = True

    def borrowed_scenes(self) -> dict[tuple, dict[Any, Any]]:
        """Per (suite, algorithm, scene), the trials that repeat the other side's in every sequence
        of the scene where they have output (``repeats_of``), each with the other side's trial:
        their scene values are the other side's, no run of this side."""
        per: dict[tuple, dict[Any, list]] = {}
        for key, rows in self.rows.items():
            for r, ok in zip(rows, self.output(rows), strict=True):
                if ok:
                    per.setdefault(tuple(key[:3]), {}).setdefault(self.trials[r], []).append(
                        self.from_other.get(int(r))
                    )
        out: dict[tuple, dict[Any, Any]] = {}
        for scene, trials in per.items():
            for trial, src in trials.items():
                if all(x is not None for x in src) and len(set(map(str, src))) == 1:
                    out.setdefault(scene, {})[trial] = src[0]
        return out

    def _repeats(self, row: int) -> str:
        """What a copy's row repeats, in words: "trial 2 repeats trial 1's every value", or for a
        trial of the other side's "CAND trial 5 repeats BASE trial 1's every value"."""
        if row in self.from_other:
            return (
                f"{self.name} trial {self.trials[row]} repeats {self.other} trial {self.from_other[row]}'s every value"
            )
        assert self.copy_of is not None
        return f"trial {self.trials[row]} repeats trial {self.trials[self.copy_of[row]]}'s every value"

    def independent(self, key: tuple, rows: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, str]:
        """The values of a sequence's trials that are independent runs, and why they are fewer:
        copies of a trial (every value the same) counted once; all of them as one run (their mean)
        where the algorithm's trials are near-identical copies (:func:`trial_copies`)."""
        if key[:2] in self.one_run:  # the copies are its trials with output; a failed run is a run of its own
            failed = ~self.output(rows)
            f = values[~failed & np.isfinite(values)]
            one = np.array([f.mean() if f.size else np.nan])
            if not failed.any():
                return one, f"{self.name}'s trials {self.one_run[key[:2]]}"
            return np.concatenate([one, values[failed]]), (
                f"{self.name}'s {int((~failed).sum())} trial(s) with output {self.one_run[key[:2]]}; its "
                f"{int(failed.sum())} failed run(s) (no pose matched) count each"
            )
        if self.copy is None or not self.copy[rows].any():
            return values, ""
        cross = np.array([int(r) in self.from_other for r in rows], bool)
        n = int((self.copy[rows] & ~cross).sum())
        notes = [f"{n} of {self.name}'s trials repeat another's every value: counted once"] if n else []
        notes += [f"{self._repeats(int(r))}: not counted" for r in rows[cross]]
        return values[~self.copy[rows]], "; ".join(notes)

    def output(self, rows: np.ndarray) -> np.ndarray:
        """Which of the rows have output (:func:`~lorisnb.core.lifelong.aggregate.has_output`; all
        of them in a table without ``matched``)."""
        m = self.cols.get("matched")
        return has_output(m[rows]) if m is not None else np.ones(len(rows), bool)

    def without_output(self, rows: np.ndarray, lacking: Sequence[Any]) -> list:
        """The trials of a sequence present in the run (not added for a missing trial) that matched no
        pose: failed runs (:func:`_failed_trials`)."""
        present = ~np.isin(self.trials[rows], list(lacking))
        return [t.item() if hasattr(t, "item") else t for t in self.trials[rows][present & ~self.output(rows)]]

    def runs(self, key: tuple, rows: np.ndarray, lacking: Sequence[Any]) -> int:
        """How many runs a sequence's trials are for the missing-trial rule: the trials present, less
        those that repeat another trial's every value (:meth:`independent`). Trials that are only
        near-identical (:func:`trial_copies`, a rule of spreads) are counted here as they are: real
        reruns of a system that tracks nearly all of a sequence with a steady ATE fall under its
        thresholds now and then (about 1 % of 3-trial draws of one icra20 system under a helper's
        noise model), and a night whose BASE fell just above them failed as missing trials, on
        noise alone. Their values still count as one run (:meth:`independent`)."""
        present = len(rows) - len(lacking)
        return present - (int(self.copy[rows].sum()) if self.copy is not None else 0)

    def copied_runs(self, key: tuple, rows: np.ndarray, lacking: Sequence[Any], other: int) -> tuple[str, str]:
        """The trials of a sequence that are copies, named ("3", "2, 3"), and how, where this side
        holds fewer independent runs (:meth:`runs`) than ``other`` (the other side's, less its
        trials named missing already); empty otherwise."""
        short = other - self.runs(key, rows, lacking)
        if short <= 0 or self.copy is None:
            return "", ""
        present = ~np.isin(self.trials[rows], list(lacking))
        assert self.copy_of is not None
        picked = [i for i in np.flatnonzero(self.copy[rows] & present)][-short:]  # each with the trial it repeats
        trials = self.trials[rows][picked]
        how = "; ".join(self._repeats(int(rows[i])) for i in picked)
        names = ", ".join(str(t) for t in trials[-short:])
        return (names, how) if names else ("", "")

    def mean(self, key: tuple, column: str) -> float:
        v = self.cols.get(column)
        return float(v[self.rows[key]].mean()) if v is not None else np.inf

    def least(self, key: tuple, column: str) -> float:
        """The smallest finite value of ``column`` over the sequence's trials (inf: none)."""
        v = self.cols.get(column)
        x = v[self.rows[key]] if v is not None else np.zeros(0)
        x = x[np.isfinite(x)]
        return float(x.min()) if x.size else np.inf


def _flips(sb: _Side, sc: _Side, key: tuple, rb: np.ndarray, rc: np.ndarray) -> bool:
    """Whether the trials of a sequence, over both runs, disagree on whether its first pose is
    correct, on which CS-R (Eq. 4) hinges (0 when it is not): a binary outcome of a few trials,
    which no test can call significant."""
    vb, vc = sb.cols.get("first_correct"), sc.cols.get("first_correct")
    if vb is None or vc is None:
        return False
    x = np.concatenate([vb[rb], vc[rc]])
    x = x[np.isfinite(x)]
    return bool(x.size and (x > 0).any() and (x <= 0).any())


def _failed_trials(comp: _Comparisons, label: dict, sb: _Side, sc: _Side, key: tuple, rows: tuple[np.ndarray, np.ndarray],
                   lacking: tuple[Sequence[Any], Sequence[Any]], fresh: int) -> None:  # fmt: skip
    """The failed-trial rule: a trial present in the candidate with no pose matched to the ground
    truth (:func:`~lorisnb.core.lifelong.aggregate.has_output`: a run that crashed after writing
    its header, or whose poses all fall outside the ground truth) is a failed run, as a trial never
    written is. Where the candidate holds more failed runs of a sequence (trials without output and
    trials missing) than the base does, and they are most of its trials (2 of 3, 3 of 5), a
    regression (``failed``) naming its trials without output; the trials it lacks and the base has
    (``fresh``) are named missing already. One failed run more than the base's, of three or five, is
    no evidence: reruns of a system that never initialise are the heavy tail of rerun noise (the
    calibration's heavy model: about 1 % of reruns of a sequence produce no pose; counting every
    excess failed run failed 85 % of its noise-only nights with 3 trials, 92.5 % with 5, against
    5 % and 0 % without it, as with the majority rule; the rule alone fired on none of 200 such
    nights). Not where the base matched fewer than :data:`MIN_MATCHED` poses in every trial (a
    tracking of a few seconds that reruns start or not: too little to judge, as the whole
    sequence's failure). A t-test of the
    values missed it: a CAND with 2 of 3 trials failed (CR 0.87 -> 0.28) passed on their spread."""
    (rb, rc), (lack_b, lack_c) = rows, lacking
    if "matched" not in sb.cols or "matched" not in sc.cols:
        return
    most = sb.cols["matched"][rb]
    if not np.isfinite(most).any() or float(np.nanmax(most)) < MIN_MATCHED:
        return
    zb, zc = sb.without_output(rb, lack_b), sc.without_output(rc, lack_c)
    failed_b, failed_c = len(lack_b) + len(zb), len(lack_c) - fresh + len(zc)
    if failed_c <= failed_b or 2 * (len(lack_c) + len(zc)) <= len(rc):
        return  # as many as BASE's, or half of CAND's trials or fewer: within rerun noise (see below)
    names = ", ".join(str(t) for t in zc)
    base = (f"none of its {len(rb)} trial(s)" if not failed_b else
            f"{failed_b} of its {len(rb)} trial(s) ({', '.join(str(t) for t in [*lack_b, *zb])})")  # fmt: skip
    comp.coverage("sequence", label, "trial", "matched", f"trial {names} no pose matched", "failed",
                  f"coverage: CAND's trial {names} matched no pose of the ground truth (a run that produced nothing "
                  f"for the sequence: a failed run, as a missing trial); BASE failed in {base}, CAND in "
                  f"{failed_c + fresh} of its {len(rc)}: more failed runs than the base")  # fmt: skip


def changes(
    base: pd.DataFrame, cand: pd.DataFrame, tolerances: Mapping[str, Tolerance] | None = None, alpha: float = 0.05,
    expected: pd.DataFrame | None = None,
) -> tuple[pd.DataFrame, pd.DataFrame]:  # fmt: skip
    """The changes from ``base`` to ``cand`` per sequence and per scene, every metric, decided by
    the one rule of the module docstring: (sequences, scenes), each one row per comparison with
    ``base``, ``cand`` (means over trials), ``worse_by``, ``tolerance``, ``trials_base``,
    ``trials_cand``, ``p_adj`` (the family-wise adjusted p; empty for single runs), ``status`` (``ok``,
    ``improvement``, ``regression``, ``missing``, ``failed``, ``new``, ``unjudged``) and
    ``decided_by``. ``expected``: every ground-truth sequence of the scenes (``scene``, ``seq``,
    ``gt_duration``, as :func:`lorisnb.core.lifelong.aggregate.durations_table`), when known: a
    sequence no row of a run holds then counts as failed in its scene value; else the base's."""
    tols = parse_tolerances() if tolerances is None else dict(tolerances)
    alpha = validate.probability("alpha", alpha)
    b, c = with_trials(base), with_trials(cand)
    one_b, one_c = trial_copies(b), trial_copies(c)
    trials_b, trials_c = _trial_sets(b, c)
    b, lack_b = _padded(b, trials_b)
    c, lack_c = _padded(c, trials_c)
    comp = _Comparisons(tols)
    sb, sc = _Side(b, "BASE", one_b), _Side(c, "CAND", one_c)
    sc.repeats_of(sb)  # CAND's trials that are BASE's own files: no runs of CAND
    for key in list(sb.rows) + [k for k in sc.rows if k not in sb.rows]:
        label = dict(zip(KEYS, key, strict=True))
        rb, rc = sb.rows.get(key), sc.rows.get(key)
        if rb is None:
            comp.coverage("sequence", label, "sequence", "absent", "present", "new", "coverage: new in the candidate")
            continue
        if rc is None or len(lack_c.get(key, [])) == len(rc):
            comp.coverage("sequence", label, "sequence", "present", "missing", "missing",
                          "coverage: in the base, not in the candidate")  # fmt: skip
            continue
        fresh = [k for k in lack_c.get(key, []) if k not in lack_b.get(key, [])]
        if fresh:
            names = ", ".join(str(k) for k in fresh)
            comp.coverage("sequence", label, "trial", "present", f"missing trial {names}", "missing",
                          f"coverage: trial {names} missing in the candidate (the base has it): a failed run")  # fmt: skip
        copied, how = sc.copied_runs(key, rc, lack_c.get(key, []), sb.runs(key, rb, lack_b.get(key, [])) - len(fresh))
        if copied:  # a run that crashed, its file filled in with another trial's: no run, so a missing one
            comp.coverage("sequence", label, "trial", "present", f"trial {copied} a copy", "missing",
                          f"coverage: CAND's trial {copied} is a copy, not a run ({how}), so CAND holds fewer "
                          "independent runs than BASE (a crashed trial filled in with another's output?): counted "
                          "once in the values, and as a missing trial")  # fmt: skip
        matched = (sb.mean(key, "matched"), sc.mean(key, "matched"))
        if "matched" in sc.cols and not (sc.cols["matched"][rc] > 0).any() and (sb.cols["matched"][rb] > 0).any():
            most = float(np.nanmax(sb.cols["matched"][rb]))
            if most >= MIN_MATCHED:
                comp.coverage("sequence", label, "sequence", "matched", "nothing matched", "failed",
                              "coverage: no pose of the candidate matched the ground truth")  # fmt: skip
            else:  # a handful of poses: as every other comparison of so few, too little to judge
                comp.coverage("sequence", label, "sequence", f"matched {most:.0f}", "nothing matched",
                              "unjudged", f"too little to judge: the base matched at most {most:.0f} poses in a "
                              f"trial (fewer than {MIN_MATCHED}), its CR {sb.mean(key, 'cr'):.3g}: a tracking of "
                              "a few seconds that reruns start or not")  # fmt: skip
        else:
            _failed_trials(comp, label, sb, sc, key, (rb, rc), (lack_b.get(key, []), lack_c.get(key, [])), len(fresh))
        correct = (sb.mean(key, "c_matched"), sc.mean(key, "c_matched"))
        lever = (sb.least(key, "rotation_lever"), sc.least(key, "rotation_lever"))
        for metric in METRICS:
            if metric in sb.cols and metric in sc.cols:
                (ib, nb), (ic, nc) = (
                    side.independent(key, r, side.cols[metric][r]) for side, r in ((sb, rb), (sc, rc))
                )
                comp.add("sequence", label, metric, sb.cols[metric][rb], sc.cols[metric][rc],
                         _unjudged(metric, matched, correct, _flips(sb, sc, key, rb, rc), lever), (ib, ic),
                         "; ".join(x for x in (nb, nc) if x))  # fmt: skip
    fragile = {k[:3] for k in sb.rows if k in sc.rows and _flips(sb, sc, k, sb.rows[k], sc.rows[k])}
    _scenes(comp, b, c, expected, fragile, (one_b, one_c), sc.borrowed_scenes())
    _scene_coverage(comp)
    return comp.judge(alpha)


def _scene_coverage(comp: _Comparisons) -> None:
    """A sequence or trial missing or failed in the candidate fails its scene too, with a row that
    names it (a scene value over a failed run can still look unchanged)."""
    lost: dict[tuple, list[str]] = {}
    for r in comp.rows["sequence"]:
        if r["status"] in ("missing", "failed"):
            what = f"{r['scene']}-{r['seq']}: {r['cand']}"
            lost.setdefault((r["suite"], r["algorithm"], r["scene"]), []).append(what)
    for (suite, alg, scene), whats in lost.items():
        label = dict(suite=suite, algorithm=alg, scene=scene, seq=None)
        comp.coverage("scene", label, "coverage", "complete", "; ".join(whats), "missing",
                      "coverage: a sequence or trial of the scene is missing or failed in the candidate")  # fmt: skip


def _scenes(comp: _Comparisons, b: pd.DataFrame, c: pd.DataFrame, expected: pd.DataFrame | None,
            fragile: set[tuple] | None = None, one_run: tuple[Mapping, Mapping] = ({}, {}),
            borrowed: Mapping[tuple, Mapping[Any, Any]] | None = None) -> None:  # fmt: skip
    """The scene values of each trial on both sides (over the base's sequences; a sequence or trial
    a run lacks is a failed run), added to ``comp``; copies of one run counted once
    (:func:`_independent_trials`)."""
    expected = expected_from(b, *([] if expected is None else [expected]))
    scenes = list(dict.fromkeys(zip(b["suite"], b["algorithm"], b["scene"], strict=True)))
    kept = set(scenes)
    c = c[np.array([k in kept for k in zip(c["suite"], c["algorithm"], c["scene"], strict=True)], bool)]
    c = c[c.set_index(KEYS).index.isin(b.set_index(KEYS).index)]  # the base's sequences only
    lost = kept - set(zip(c["suite"], c["algorithm"], c["scene"], strict=True))
    if lost:  # a scene without any output in the candidate: all its sequences failed
        gone = b[np.array([k in lost for k in zip(b["suite"], b["algorithm"], b["scene"], strict=True)], bool)]
        c = pd.concat([c, _failed_copy(gone)], ignore_index=True)
    metrics = [m for m in WEIGHTS if m in b.columns and m in c.columns and (WEIGHTS[m] or m) in b.columns]
    if not metrics or expected.empty:
        return
    by = ["suite", "algorithm", "scene", "trial"]
    fb, fc = complete(b, expected)[0], complete(c, expected)[0]
    vb, vc = scene_values(fb, metrics, by), scene_values(fc, metrics, by)
    counts = [_counts(f, by[:3]) for f in (fb, fc)]
    failed = [_trials_with_a_failed_run(f) for f in (fb, fc)]
    gb = {k: g for k, g in vb.groupby(by[:3], sort=False)}
    gc = {k: g for k, g in vc.groupby(by[:3], sort=False)}
    for key in scenes:
        if key not in gb:
            continue
        label = dict(suite=key[0], algorithm=key[1], scene=key[2], seq=None)
        matched = tuple(float(n["matched"].get(key, 0.0)) for n in counts)
        correct = tuple(float(n["c_matched"].get(key, 0.0)) for n in counts)
        ib, nb = _independent_trials(gb[key], metrics, one_run[0].get(key[:2]), "BASE", failed[0].get(key, set()))
        ic, nc = (_independent_trials(gc[key], metrics, one_run[1].get(key[:2]), "CAND", failed[1].get(key, set()),
                                      (borrowed or {}).get(key))
                  if key in gc else ({}, ""))  # fmt: skip
        note = "; ".join(x for x in (nb, nc) if x)
        for metric in metrics:
            xc = gc[key][metric].to_numpy(float) if key in gc else np.full(1, np.nan)
            why = _unjudged(metric, (matched[0], matched[1]), (correct[0], correct[1]), key in (fragile or set()))
            comp.add("scene", label, metric, gb[key][metric].to_numpy(float), xc, why,
                     (ib[metric], ic.get(metric, xc)), note)  # fmt: skip


def _trials_with_a_failed_run(full: pd.DataFrame) -> dict[tuple, set]:
    """Per (suite, algorithm, scene) of a run's completed table, its trials holding a failed run of
    a sequence (no pose matched: missing, or written without output) that another of its trials
    tracked: such a trial's scene values are no copy of the others' (:func:`_independent_trials`)."""
    if "matched" not in full.columns or full.empty:
        return {}
    out: dict[tuple, set] = {}
    ok = has_output(pd.to_numeric(full["matched"], errors="coerce").to_numpy(float))
    trial = full["trial"].to_numpy()
    for key, rows in full.groupby(KEYS, sort=False, observed=True, dropna=False).indices.items():
        if ok[rows].any() and not ok[rows].all():
            out.setdefault(tuple(key[:3]), set()).update(trial[rows][~ok[rows]].tolist())
    return out


def _independent_trials(values: pd.DataFrame, metrics: Sequence[str], one_run: str | None, name: str,
                        failed: set | frozenset = frozenset(), borrowed: Mapping[Any, Any] | None = None,
                        other: str = "BASE") -> tuple[dict[str, np.ndarray], str]:  # fmt: skip
    """A scene's values of each trial (one row per trial) that are independent runs, per metric, and
    why they are fewer: a trial whose scene values all repeat another's (and are not all 0: a
    scene without output) is a copy of it, counted once (within :data:`SAME_VALUE` relative, the
    rule of a sequence's copies, :func:`same_values`); a trial of ``borrowed`` (trial -> the trial
    of the other side, named ``other``, it repeats in every sequence of the scene,
    :meth:`_Side.repeats_of`) is no run of this side, not counted; where the algorithm's trials are
    near-identical copies (``one_run`` says what varies), all of them are one run (their mean),
    but for the trials holding a failed run (``failed``: a sequence without output that another
    trial tracked), each a run of its own."""
    x = values[list(metrics)].apply(pd.to_numeric, errors="coerce")
    if one_run is not None:
        bad = values["trial"].isin(list(failed)).to_numpy() if failed else np.zeros(len(x), bool)
        one = {m: np.array([np.nanmean(x[m][~bad]) if x[m][~bad].notna().any() else np.nan]) for m in metrics}
        if not bad.any():
            return one, f"{name}'s trials {one_run}"
        return {m: np.concatenate([one[m], x[m].to_numpy(float)[bad]]) for m in metrics}, (
            f"{name}'s {int((~bad).sum())} trial(s) without a failed run {one_run}; its {int(bad.sum())} trial(s) "
            "holding a failed run (a sequence with no pose matched) count each"
        )
    has = x.fillna(0).ne(0).any(axis=1).to_numpy()
    copy = (same_values(x.to_numpy(float)) >= 0) & has  # the rule of a sequence's copies (:func:`repeated_of`)
    notes = [f"{int(copy.sum())} of {name}'s trials repeat another's every value: counted once"] if copy.any() else []
    if borrowed:  # a trial that is the other side's in every sequence of the scene: no run of this side
        trial = values["trial"].to_numpy()
        cross = np.isin(trial, list(borrowed)) & ~copy
        notes += [f"{name} trial {trial[i]} repeats {other} trial {borrowed[trial[i]]}'s every value: not counted"
                  for i in np.flatnonzero(cross)]  # fmt: skip
        copy = copy | cross
    return {m: x[m].to_numpy(float)[~copy] for m in metrics}, "; ".join(notes)


#: The fewest sequences with a CR strictly between 0 and 1 whose ties make an algorithm's trials
#: copies of one run (:func:`trial_copies`): one tied sequence (a synthetic drop of every trial's CR
#: by 0.4 where every other CR is 1.0) is no pattern of copies.
MIN_TIED = 3


def trial_copies(table: pd.DataFrame) -> dict[tuple, str]:
    """The (suite, algorithm) of a per-sequence table whose trials are near-identical copies of one
    run, not reruns (:func:`lorisnb.core.stats.inference.trial_spread`: CR and ATE vary between its
    trials by less than a quarter of what real reruns show), each with what varies, in words. The
    verdict counts such trials as one run: copies are no independent evidence, so no significance
    can be claimed from them."""
    spread = trial_spread(table, by=("suite", "algorithm"))
    if len(spread):  # copies by ties alone (CR repeated to the last digit) take three such sequences, not one
        t = with_trials(table)
        cr = pd.to_numeric(t["cr"], errors="coerce") if "cr" in t else pd.Series(np.nan, t.index)
        g = cr.groupby([t[k] for k in KEYS], sort=False, dropna=False)
        inside = ((g.min() > 0) & (g.max() < 1) & (g.count() >= 2)).groupby(level=[0, 1], sort=False).sum()
        by_spread = (spread["cr_spread"] < RERUN_SPREAD["rate"] / 4) & (spread["ate_spread"] < RERUN_SPREAD["log"] / 4)
        few = [inside.get((r.suite, r.algorithm), 0) < MIN_TIED for r in spread.itertuples()]
        spread = spread.assign(copies=spread["copies"].astype(bool) & (by_spread | ~np.array(few, bool)))
    return {(r.suite, r.algorithm): (f"are near-identical copies of one run (CR varies by {r.cr_spread:.2g}, ATE "
                                     f"by {100 * r.ate_spread:.2g} % between them; real reruns {RERUN_SPREAD['rate']:g} "
                                     f"and {100 * RERUN_SPREAD['log']:.0f} %"
                                     + (f"; CR the same to the last digit in {100 * r.cr_ties:.0f} % of the sequences "
                                        "where it is neither 0 nor 1, which reruns never repeat" if r.cr_ties > 0.5
                                        else "") + "): counted as one run")
            for r in spread[spread["copies"].astype(bool)].itertuples()}  # fmt: skip


def _counts(table: pd.DataFrame, by: list[str]) -> pd.DataFrame:
    """Matched and correct poses of each scene, summed over its sequences and averaged over trials."""
    cols = [c for c in ("matched", "c_matched") if c in table.columns]
    per = table.groupby([*by, "trial"], sort=False)[cols].sum().groupby(level=list(range(len(by)))).mean()
    for c in ("matched", "c_matched"):
        if c not in per.columns:
            per[c] = np.inf
    return per


def sequence_changes(
    base: pd.DataFrame, cand: pd.DataFrame, tolerances: Mapping[str, Tolerance] | None = None, alpha: float = 0.05,
    expected: pd.DataFrame | None = None,
) -> pd.DataFrame:  # fmt: skip
    """The per-sequence table of :func:`changes` (the same family: the scenes are tested too)."""
    return changes(base, cand, tolerances, alpha, expected)[0]


def scene_changes(
    base: pd.DataFrame, cand: pd.DataFrame, tolerances: Mapping[str, Tolerance] | None = None, alpha: float = 0.05,
    expected: pd.DataFrame | None = None,
) -> pd.DataFrame:  # fmt: skip
    """The per-scene table of :func:`changes` (the same family: the sequences are tested too)."""
    return changes(base, cand, tolerances, alpha, expected)[1]


def _failed_copy(rows: pd.DataFrame) -> pd.DataFrame:
    """The base's rows as failed runs (a candidate without any output for them)."""
    out = rows.copy()
    for col, v in FAILED_RUN.items():
        if col in out.columns:
            out[col] = v
    for col in ("c_ate_rmse", "ate_rmse", "aoe_rmse", "c_aoe_rmse", "rpe_trans_rmse", "rpe_rot_rmse"):
        if col in out.columns:
            out[col] = np.nan
    return out


def verdict(sequences: pd.DataFrame, scenes: pd.DataFrame) -> dict:
    """The machine-readable verdict: ``verdict`` ("ok" or "regression"); ``regressions`` and
    ``improvements`` (objects with algorithm, scene, seq (null for a scene value), metric, base,
    cand, suite, level, status, worse_by, tolerance, p_adj, decided_by); ``tradeoffs`` (per
    suite and algorithm with both: what got worse and what got better); ``unjudged`` (too little
    to judge, with the reason); ``counts`` of each status over the per-sequence comparisons."""

    def entry(level: str, r: dict) -> dict:
        return dict(algorithm=r["algorithm"], scene=r["scene"], seq=_plain(r["seq"]), metric=r["metric"],
                    base=_plain(r["base"]), cand=_plain(r["cand"]), suite=r["suite"], level=level,
                    status=r["status"], worse_by=_plain(r.get("worse_by")), tolerance=_plain(r.get("tolerance")),
                    p_adj=_plain(r.get("p_adj")), decided_by=r.get("decided_by"))  # fmt: skip

    regs, better, unjudged = [], [], []
    for level, t in (("sequence", sequences), ("scene", scenes)):
        for r in t.to_dict("records"):
            if r["status"] in BAD:
                regs.append(entry(level, r))
            elif r["status"] == "improvement":
                better.append(entry(level, r))
            elif r["status"] == "unjudged":
                unjudged.append(entry(level, r))
    trade = []
    for suite, alg in dict.fromkeys((r["suite"], r["algorithm"]) for r in regs + better):
        w = [r for r in regs if (r["suite"], r["algorithm"]) == (suite, alg)]
        g = [r for r in better if (r["suite"], r["algorithm"]) == (suite, alg)]
        if w and g:
            trade.append(dict(suite=suite, algorithm=alg, worse=sorted({_what(r) for r in w}),
                              better=sorted({_what(r) for r in g})))  # fmt: skip
    counts = {s: int((sequences["status"] == s).sum()) for s in ("ok", "improvement", "regression", "missing",
                                                                   "failed", "new", "unjudged")}  # fmt: skip
    scene_counts = {s: int((scenes["status"] == s).sum()) for s in ("ok", "improvement", "regression")}
    n_seq = sequences[KEYS].drop_duplicates().shape[0] if len(sequences) else 0
    return dict(verdict="regression" if regs else "ok", rule=sequences.attrs.get("rule", ""), regressions=regs,
                improvements=better, tradeoffs=trade,
                unjudged=unjudged, sequences=n_seq, counts=counts, scene_counts=scene_counts,
                regressed_sequences=len({(r["suite"], r["algorithm"], r["scene"], r["seq"]) for r in regs
                                         if r["level"] == "sequence"}))  # fmt: skip


def unjudged_reasons(unjudged: Sequence[Mapping[str, Any]]) -> dict[str, int]:
    """Why the comparisons of a verdict's ``unjudged`` were too little to judge, each reason (in
    words, as the summary line of ``lorisnb diff`` gives it) with its count, the most frequent first.
    The line said "fewer than 50 matched or correct poses" of them all, also of those held back by a
    rotation lever under :data:`~lorisnb.core.stats.tolerances.MIN_LEVER`."""
    rules = (
        ("lever of", f"a rotation lever under {MIN_LEVER:g} m"),
        ("correct poses on one side", f"fewer than {MIN_MATCHED} correct poses"),
        ("matched", f"fewer than {MIN_MATCHED} matched poses"),
        ("whether the first pose is correct", "CS-R: the trials disagree on whether the first pose is correct"),
        ("undefined in the candidate", "undefined in the candidate (no pose to take it over)"),
        ("an error of 0", "an error of 0 on one side"),
    )
    out: dict[str, int] = {}
    for r in unjudged:
        text = str(r.get("decided_by") or "")
        why = next((name for key, name in rules if key in text), None)
        if why is None:  # a reason of its own: its words, up to the first note
            why = text.removeprefix("too little to judge: ").split(";")[0].strip() or "no reason given"
        out[why] = out.get(why, 0) + 1
    return dict(sorted(out.items(), key=lambda kv: -kv[1]))


def unjudged_line(unjudged: Sequence[Mapping[str, Any]]) -> str:
    """``"55 comparison(s) too little to judge (27 a rotation lever under 0.29 m; 18 fewer than 50
    matched poses; ...)"``: the one summary of a verdict's ``unjudged`` (:func:`unjudged_reasons`), as
    the terminal and the Markdown summary of ``lorisnb diff`` give it."""
    reasons = unjudged_reasons(unjudged)
    return (
        f"{len(unjudged)} comparison(s) too little to judge (" + "; ".join(f"{n} {w}" for w, n in reasons.items()) + ")"
    )


#: How many regressed sequences (or scene values) the verdict's line names before "and N more".
NAMED = 3


def regressed_phrase(verdict: Mapping[str, Any]) -> str:
    """What regressed, for the verdict's line: ``"2 sequence(s) regressed: odom home-2 failed;
    orb cafe-1 cr, cr_t"``, each sequence named with its metrics (lost or failed ones first, as
    ``missing``, ``failed`` or the trial lost), the first :data:`NAMED` and ``"and N more"``; where
    only scene values did (a scene's CR falls while each sequence stays within its wider rerun band),
    ``"no sequence regressed; 2 scene value(s) did: orb home (scene) cr; ..."``; "" for a verdict of
    ok. (The line named lost sequences only: a sequence that regressed by the t-test, the usual
    nightly regression, was a count.)"""
    if verdict["verdict"] == "ok":
        return ""
    regs = list(verdict.get("regressions", []))
    n = int(verdict["regressed_sequences"])
    seqs = [r for r in regs if r.get("seq") is not None]
    if n and seqs:
        return f"{n} sequence(s) regressed: {_named(seqs)}"
    if n:
        return f"{n} sequence(s) regressed"
    scenes = [r for r in regs if r.get("seq") is None]
    k = int(verdict["scene_counts"].get("regression", 0))
    return f"no sequence regressed; {k} scene value(s) did" + (f": {_named(scenes)}" if scenes else "")


def _named(regs: Sequence[Mapping[str, Any]]) -> str:
    """The first :data:`NAMED` of the regressed sequences (or scene values) of ``regs``, each with
    what regressed in it (its metrics; ``missing``, ``failed`` or the trial lost first), then
    ``and N more``."""
    lost = ("missing", "failed")
    what: dict[tuple, list[str]] = {}
    for r in sorted(regs, key=lambda r: r.get("status") not in lost):  # lost ones first, stable
        key = (r.get("suite") or "", r["algorithm"], r["scene"], r.get("seq"))
        word = (
            (str(r["cand"]) if r.get("metric") == "trial" else r["status"]) if r.get("status") in lost else r["metric"]
        )
        if word not in what.setdefault(key, []):
            what[key].append(word)
    shown = [f"{alg}{f' ({suite})' if suite else ''} {scene}" + (f"-{seq}" if seq is not None else " (scene)")
             + f" {', '.join(words)}" for (suite, alg, scene, seq), words in list(what.items())[:NAMED]]  # fmt: skip
    more = len(what) - len(shown)
    return "; ".join(shown) + (f"; and {more} more" if more > 0 else "")


def _what(r: dict) -> str:
    where = f"{r['scene']}-{r['seq']}" if r["seq"] is not None else f"{r['scene']} (scene)"
    return f"{r['metric']} {where}"


def _plain(v: object) -> object:
    """JSON-friendly: NaN and infinity as None, numpy numbers as Python numbers."""
    if v is None or isinstance(v, str):
        return v
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    try:
        f = float(v)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return str(v)
    return f if np.isfinite(f) else None
