"""One exact test for every comparison of two groups of runs: a stratified permutation test.

The data are, for each stratum s (a sequence), the values of group A (``a[s]``, one per trial)
and of group B (``b[s]``). The statistic is the weighted mean over strata of the difference of
the group means, ``T = sum_s w_s (mean a_s - mean b_s) / sum_s w_s`` (the weights are the
sequences' scene weights, so T is the difference of scene values). Under the null hypothesis the
values within a stratum are exchangeable between A and B; the p-value is the share of the
relabellings within every stratum whose |T| reaches the observed |T| (two-sided).

- With one trial each, a stratum holds one pair and a relabelling is a sign flip: the paired
  (Fisher-Pitman) permutation test over sequences, 2^n relabellings for n sequences.
- With one sequence and m vs n trials: the two-sample permutation test, C(m+n, m) relabellings.
- Ties need no correction: tied values permute like any others.

When the relabellings number at most :data:`EXACT_LIMIT` every one is enumerated (the exact test);
beyond, ``n_resamples`` random relabellings, p = (1 + hits) / (1 + n_resamples). The smallest
p-value the design can give (:func:`min_p`) is stated with every test: 3 vs 3 trials have 20
relabellings and cannot go below 0.1, five paired sequences not below 2/32 = 0.0625.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from itertools import combinations

import numpy as np

from lorisnb.core.spec import validate

#: Enumerate every relabelling up to this many (the exact test); sample beyond.
EXACT_LIMIT = 200_000


@dataclass(frozen=True)
class PermutationResult:
    """``statistic``: T (A minus B); ``pvalue``: two-sided; ``min_p``: the smallest p-value these
    data can give (exact test: the share of relabellings reaching the largest |T|; sampled: the
    design's bound over the strata whose values are not all equal); ``relabellings``: how many
    there are (strata whose values are all equal left out: they cannot move T); ``exact``: all
    were enumerated."""

    statistic: float
    pvalue: float
    min_p: float
    relabellings: float
    exact: bool


def relabellings(sizes: Sequence[tuple[int, int]]) -> float:
    """Number of relabellings of strata with (m_s, n_s) values: prod C(m_s + n_s, m_s)."""
    return float(math.prod(math.comb(m + n, m) for m, n in sizes))


def min_p(sizes: Sequence[tuple[int, int]]) -> float:
    """Smallest two-sided p-value the design can give: 2 / relabellings when every stratum is
    balanced (m_s = n_s: each relabelling has a mirror with -T), else 1 / relabellings."""
    total = relabellings(sizes)
    if total <= 1:
        return 1.0
    balanced = all(m == n for m, n in sizes)
    return min(1.0, (2.0 if balanced else 1.0) / total)


@lru_cache(maxsize=64)
def _picks(n: int, m: int) -> np.ndarray:
    """Every choice of m of n positions, one per row (made once per design)."""
    return np.array(list(combinations(range(n), m)), dtype=np.int32).reshape(-1, m)


def _stratum_contributions(a: np.ndarray, b: np.ndarray, weight: float) -> np.ndarray:
    """Every relabelling of one stratum: weight * (mean of A's values - mean of B's)."""
    pooled = np.concatenate([a, b])
    m, total = len(a), pooled.sum()
    sum_a = pooled[_picks(len(pooled), m)].sum(axis=1)
    return weight * (sum_a / m - (total - sum_a) / len(b))


def permutation_test(
    a: Sequence[np.ndarray],
    b: Sequence[np.ndarray],
    weights: Sequence[float] | np.ndarray | None = None,
    n_resamples: int = 20_000,
    rng: np.random.Generator | None = None,
) -> PermutationResult:
    """Stratified two-sided permutation test of A against B (see the module docstring).

    Args:
        a, b: per stratum, the values of A and of B (1-D arrays; strata with an empty side are
            left out).
        weights: per stratum (default equal); normalized to sum 1.
        n_resamples: random relabellings when there are more than :data:`EXACT_LIMIT`.
        rng: for the random relabellings.
    """
    w = np.ones(len(a)) if weights is None else np.asarray(weights, float)
    keep = [k for k in range(len(a)) if len(a[k]) and len(b[k]) and np.isfinite(w[k]) and w[k] > 0]
    if not keep:
        return PermutationResult(np.nan, np.nan, np.nan, 0.0, True)
    xa = [np.asarray(a[k], float) for k in keep]
    xb = [np.asarray(b[k], float) for k in keep]
    wk = w[keep] / w[keep].sum()
    sizes = [(len(x), len(y)) for x, y in zip(xa, xb, strict=True)]
    observed = float(sum(wi * (x.mean() - y.mean()) for wi, x, y in zip(wk, xa, xb, strict=True)))
    # a stratum whose values are all equal adds 0 under every relabelling: it leaves the distribution
    moving = [k for k in range(len(xa)) if np.ptp(np.concatenate([xa[k], xb[k]])) > 0]
    xa, xb, wk = [xa[k] for k in moving], [xb[k] for k in moving], wk[moving]
    sizes = [sizes[k] for k in moving]
    total = relabellings(sizes)
    floor = min_p(sizes)
    tol = 1e-12 * max(1.0, abs(observed))
    if total <= EXACT_LIMIT:
        dist = np.zeros(1)
        for x, y, wi in zip(xa, xb, wk, strict=True):  # strata: a handful; the relabellings are arrays
            dist = (dist[:, None] + _stratum_contributions(x, y, wi)[None, :]).ravel()
        top = np.abs(dist).max()
        floor = float(np.mean(np.abs(dist) >= top - 1e-12 * max(1.0, top)))  # exact: from the data
        p = float(np.mean(np.abs(dist) >= abs(observed) - tol))
        return PermutationResult(observed, p, floor, total, True)
    rng = rng if rng is not None else np.random.default_rng(0)
    stat = np.zeros(n_resamples)
    for x, y, wi in zip(xa, xb, wk, strict=True):
        pooled = np.concatenate([x, y])
        perm = rng.permuted(np.broadcast_to(pooled, (n_resamples, len(pooled))), axis=1)
        stat += wi * (perm[:, : len(x)].mean(axis=1) - perm[:, len(x) :].mean(axis=1))
    hits = int(np.sum(np.abs(stat) >= abs(observed) - tol))
    return PermutationResult(observed, (1 + hits) / (1 + n_resamples), floor, total, False)


def holm_levels(p: np.ndarray, alpha: float) -> np.ndarray:
    """The level at which Holm's procedure (at family level ``alpha``) decides each p-value:
    alpha / (m - j) for the j-th smallest while all before it are rejected, and, for the first not
    rejected and all after it, the level of that first step. Equal p-values share the level of the
    first of them (Holm rejects them together), so a pair's level does not depend on the order the
    pairs are listed in. A test inverted at these levels
    (:func:`lorisnb.core.stats.permutation.difference_interval`) agrees with Holm's decisions."""
    p = np.asarray(p, float)
    out = np.full(p.shape, np.nan)
    ok = np.flatnonzero(np.isfinite(p))
    order = ok[np.argsort(p[ok], kind="stable")]
    m, stop, level = order.size, None, np.nan
    for j, i in enumerate(order):
        if j == 0 or p[i] != p[order[j - 1]]:  # a tie keeps the level of its first p-value
            level = alpha / (m - j)
        if stop is None and p[i] > level:
            stop = level
        out[i] = level if stop is None else stop
    return out


def runs_needed(alpha: float, paired: bool, strata: int = 1) -> int:
    """The fewest units that can reach ``alpha`` at all: paired sequences n with 2 / 2^n <= alpha,
    or trials per group m (m vs m in each of ``strata`` sequences) with min_p <= alpha."""
    alpha = validate.probability("alpha", alpha)  # alpha 0 is never reached, 1 always
    n = 1
    while (2.0 / 2**n if paired else min_p([(n, n)] * strata)) > alpha:
        n += 1
    return n


def units_for_power(
    sd: float, delta: float, alpha: float = 0.05, power: float = 0.8, groups: int = 1, strata: int = 1
) -> int:
    """Units needed to detect a difference ``delta`` with probability ``power`` at ``alpha``
    (two-sided), by the normal approximation the permutation test approaches:
    n = groups * (z_(1-alpha/2) + z_power)^2 sd^2 / delta^2, with ``groups`` = 1 for paired
    differences of spread ``sd`` (n sequences) and 2 for two independent groups of spread ``sd``
    each (n trials per group and sequence, over ``strata`` sequences: pass the effective spread);
    never fewer than :func:`runs_needed`. NaN spread or zero delta: -1 (cannot say)."""
    from scipy.stats import norm  # here, not at the top: scipy.stats takes half a second to import

    alpha, power = validate.probability("alpha", alpha), validate.probability("power", power)
    if not (np.isfinite(sd) and np.isfinite(delta)) or delta == 0:
        return -1
    z = norm.ppf(1 - alpha / 2) + norm.ppf(power)
    n = math.ceil(groups * (z * sd / abs(delta)) ** 2)
    return max(n, runs_needed(alpha, paired=groups == 1, strata=strata))


def difference_interval(
    a: Sequence[np.ndarray],
    b: Sequence[np.ndarray],
    weights: Sequence[float] | np.ndarray | None,
    alpha: float,
    n_resamples: int = 2000,
    seed: int = 0,
    iterations: int = 30,
    rejected: bool | None = None,
) -> tuple[float, float]:
    """The interval of the difference T (A minus B) that inverts :func:`permutation_test`: the shifts
    d for which the test of A - d against B does not reject at ``alpha`` (p > alpha), found outward
    from T by doubling and bisection. Infinite bounds where no shift can be rejected (the design
    cannot reach ``alpha``). Sampled tests reuse one seed for every shift. ``rejected``: the
    decision of the test on the data as reported elsewhere (it may have used other random
    relabellings); the interval is then made to contain 0 exactly when it was not rejected, so the
    two always agree."""
    seed = validate.seed(seed)
    if not a or not any(len(x) for x in a):
        return np.nan, np.nan
    # the shift moves T by d through the strata that vary (all-equal ones stay out of the test, as in it)
    w = np.ones(len(a)) if weights is None else np.asarray(weights, float)
    used = np.array([bool(len(x) and len(y) and np.isfinite(wi) and wi > 0) for x, y, wi in zip(a, b, w, strict=True)])
    moving = used & np.array(
        [bool(len(x) and len(y) and np.ptp(np.concatenate([x, y])) > 0) for x, y in zip(a, b, strict=True)]
    )
    share = float(w[moving].sum() / w[used].sum()) if used.any() else 0.0
    if share <= 0:
        return -np.inf, np.inf  # nothing varies: no shift can be rejected

    def p_at(d: float) -> float:
        shifted = [np.asarray(x, float) - (d / share if moving[k] else 0.0) for k, x in enumerate(a)]
        return permutation_test(shifted, b, weights, n_resamples, np.random.default_rng(seed)).pvalue

    centre = permutation_test(a, b, weights, n_resamples, np.random.default_rng(seed)).statistic
    if not np.isfinite(centre):
        return np.nan, np.nan
    values = np.concatenate([np.asarray(x, float) for x in list(a) + list(b) if len(x)])
    span = max(float(np.ptp(values)), abs(centre), 1e-9)
    bounds = []
    for sign in (-1.0, 1.0):
        inside, step = 0.0, span
        while step <= 64 * span and p_at(centre + sign * step) > alpha:  # still accepted: look further out
            inside, step = step, 2 * step
        if step > 64 * span:
            bounds.append(sign * np.inf)
            continue
        lo, hi = inside, step  # accepted at lo, rejected at hi
        for _ in range(iterations):
            mid = (lo + hi) / 2
            lo, hi = (mid, hi) if p_at(centre + sign * mid) > alpha else (lo, mid)
        bounds.append(centre + sign * lo)
    low, high = float(bounds[0]), float(bounds[1])
    if rejected is None:
        rejected = p_at(0.0) <= alpha
    if not rejected:  # 0 is an accepted shift: the interval holds it
        low, high = min(low, 0.0), max(high, 0.0)
    elif low <= 0.0 <= high:  # rejected: the interval stops short of 0 on its side
        low, high = (float(np.nextafter(0.0, 1.0)), high) if centre > 0 else (low, float(np.nextafter(0.0, -1.0)))
    return low, high
