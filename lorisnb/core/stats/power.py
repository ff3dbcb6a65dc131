"""How many runs would a comparison need? For each pair of algorithms of
:func:`lorisnb.core.stats.inference.pairwise`, the sequences (one trial each: the paired test) or the trials
per sequence (with trials: the stratified test) that would detect a difference ``delta`` of the
scene metric with probability ``power`` at ``alpha``, by
:func:`lorisnb.core.stats.permutation.units_for_power`. The spread is the one observed: of the
per-sequence differences, or of the trials within each sequence (pooled). A design too small to
ever reach ``alpha`` (:func:`lorisnb.core.stats.permutation.runs_needed`) is the floor."""

from __future__ import annotations

import numpy as np
import pandas as pd

from lorisnb.core.spec import validate
from lorisnb.core.stats.inference import WEIGHTS, with_trials
from lorisnb.core.stats.permutation import units_for_power
from lorisnb.errors import ValidationError


def _within_sd(g: pd.DataFrame, metric: str) -> float:
    """Pooled standard deviation of the trials within each sequence (NaN with single trials)."""
    parts = [d[metric].dropna().to_numpy(float) for _, d in g.groupby("seq")]
    dof = sum(len(x) - 1 for x in parts if len(x) > 1)
    if dof == 0:
        return np.nan
    return float(np.sqrt(sum(((x - x.mean()) ** 2).sum() for x in parts if len(x) > 1) / dof))


def _paired_unknown(values: int, common: int, metric: str) -> str:
    """Why one trial per sequence gives no spread of the differences (``values``: the sequences
    where both algorithms have a value of ``metric``, of the ``common`` ones both were run on)."""
    if values < 2:
        return (f"the spread is unknown, as {values} of {common} sequence(s) have a value of {metric} for both "
                f"algorithms{' (a failed or missing run has none)' if values < common else ''} and the spread of "
                "the differences needs two; evaluate more sequences")  # fmt: skip
    return f"the spread is unknown, as the differences of {metric} are not finite numbers"


def _trials_unknown(within: dict[str, float], common: int, metric: str) -> str:
    """Why trials give no spread: an algorithm with no sequence of two trials with a value of
    ``metric`` (``within``: each algorithm's pooled spread, NaN then)."""
    if common == 0:
        return "the spread is unknown, as no sequence has results of both algorithms"
    single = [a for a, s in within.items() if not np.isfinite(s)]
    if single:
        return (f"the spread is unknown, as {' and '.join(single)} {'has' if len(single) == 1 else 'have'} one trial "
                f"(with a value of {metric}) per sequence, which says nothing of how reruns vary; run "
                f"{'it' if len(single) == 1 else 'them'} at least twice per sequence")  # fmt: skip
    return f"the spread is unknown, as the values of {metric} or the sequences' weights are not finite numbers"


def runs_for_power(
    table: pd.DataFrame,
    pairs: pd.DataFrame,
    delta: float,
    alpha: float = 0.05,
    power: float = 0.8,
    comparisons: int = 1,
) -> pd.DataFrame:
    """``pairs`` with the columns ``delta``, ``power``, ``unit`` ("sequences" or "trials per
    sequence"), ``have`` (how many there are), ``needed`` (-1: the spread is unknown, so no number
    of runs can be named) and ``needed_note`` ("" where ``needed`` is a number, else why the spread
    is unknown and what would give one: fewer than two sequences where both algorithms have a value
    of the metric, an algorithm with one trial per sequence, ...; the command line prints it).
    ``comparisons``: the tests Holm's correction runs over (``compare``: every pair of every scene);
    each pair is sized at ``alpha / comparisons``, the level Holm holds its smallest p-value to, so
    the design it names can reach alpha after the correction (sized at ``alpha``, a pair was said
    to need the 2 trials a side it had, where no p-value of 2 could pass 0.05 over 60 pairs)."""
    if not (np.isfinite(delta) and delta > 0):
        raise ValidationError(f"power delta={delta}: expected a positive difference in the metric's unit")
    if not 0 < power < 1:
        raise ValidationError(f"power={power}: expected a probability between 0 and 1")
    alpha = validate.probability("alpha", alpha)
    if isinstance(comparisons, bool) or not isinstance(comparisons, (int, np.integer)) or comparisons < 1:
        raise ValidationError(f"comparisons={comparisons!r}: expected a whole number of tests, 1 or more")
    alpha = alpha / int(comparisons)
    t = with_trials(table)
    rows = []
    for r in pairs.itertuples():
        metric = r.metric
        w_col = WEIGHTS[metric]
        g = t[(t["suite"] == r.suite) & (t["scene"] == r.scene)]
        ga, gb = g[g["algorithm"] == r.a], g[g["algorithm"] == r.b]
        common = sorted(set(ga["seq"]) & set(gb["seq"]))
        if max(r.trials_a, r.trials_b) <= 1:
            ma = ga.groupby("seq")[metric].mean().reindex(common)
            mb = gb.groupby("seq")[metric].mean().reindex(common)
            d = (ma - mb).dropna().to_numpy(float)
            sd = float(np.std(d, ddof=1)) if len(d) > 1 else np.nan
            needed = units_for_power(sd, delta, alpha, power, groups=1)
            why = "" if needed >= 0 else _paired_unknown(len(d), len(common), metric)
            rows.append(dict(unit="sequences", have=len(common), needed=needed, needed_note=why))
        else:
            w = (np.ones(len(common)) if w_col is None else
                 g[g["seq"].isin(common)].groupby("seq")[w_col].mean().reindex(common).to_numpy(float))  # fmt: skip
            w = w / w.sum() if len(w) and w.sum() > 0 else w
            sa, sb = _within_sd(ga[ga["seq"].isin(common)], metric), _within_sd(gb[gb["seq"].isin(common)], metric)
            sd = float(np.sqrt(np.sum(w**2) * (sa**2 + sb**2) / 2)) if len(w) else np.nan
            both = g[g["algorithm"].isin([r.a, r.b]) & g["seq"].isin(common)]
            moving = int((both.groupby("seq")[metric].agg(np.ptp) > 0).sum())  # all-equal sequences cannot help
            needed = units_for_power(sd, delta, alpha, power, groups=2, strata=max(moving, 1))
            why = "" if needed >= 0 else _trials_unknown({r.a: sa, r.b: sb}, len(common), metric)
            rows.append(dict(unit="trials per sequence", have=min(r.trials_a, r.trials_b), needed=needed,
                             needed_note=why))  # fmt: skip
    extra = pd.DataFrame(rows, columns=["unit", "have", "needed", "needed_note"], index=pairs.index)
    return pairs.assign(delta=delta, power=power).join(extra)


def detectable_change(spread: float, trials: int, tolerance: float = 0.0, alpha: float = 0.05,
                      power: float = 0.9, comparisons: int = 1) -> float:  # fmt: skip
    """The smallest worsening (on the judged scale: CR units for a rate, the log of the ratio for an
    error) that *any* one-sided test at family-wise ``alpha`` over ``comparisons`` tests could find
    with probability ``power``, given ``trials`` runs per side whose rerun spread (standard deviation
    of one run about the system's mean) is ``spread`` and known exactly: the oracle z-test of
    ``d - tolerance`` with Bonferroni's level ``alpha / comparisons``,

        tolerance + (z(1 - alpha / comparisons) + z(power)) * spread * sqrt(2 / trials).

    A bound, not a rule: a test that must estimate the spread from the trials (a t-test) needs more.
    ``make calibrate`` prints it beside the measured power of ``lorisnb diff``."""
    from scipy import stats

    if not (np.isfinite(spread) and spread > 0):
        raise ValidationError(f"spread={spread}: expected a positive standard deviation")
    if int(trials) < 1:
        raise ValidationError(f"trials={trials}: expected at least one run per side")
    if int(comparisons) < 1:
        raise ValidationError(f"comparisons={comparisons}: expected at least one")
    if not 0 < power < 1:
        raise ValidationError(f"power={power}: expected a probability between 0 and 1")
    alpha = validate.probability("alpha", alpha)
    z = stats.norm.isf(alpha / int(comparisons)) + stats.norm.ppf(power)
    return float(tolerance + z * spread * np.sqrt(2.0 / int(trials)))
