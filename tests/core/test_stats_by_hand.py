"""The comparison statistics checked by hand on small inputs: every p-value below was computed by
enumerating all relabellings (sign flips, or choices of which trials are A's) in a separate script,
and agrees with scipy.stats.permutation_test where scipy has the same test; the refusals and fixes
of the statistics probe."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.core.stats import inference as stats
from lorisnb.core.stats import power
from lorisnb.core.stats.permutation import (
    difference_interval,
    holm_levels,
    permutation_test,
    runs_needed,
    units_for_power,
)


def _one(values: list[float]) -> list[np.ndarray]:
    return [np.array([v]) for v in values]


def _table(
    values: dict[str, list[list[float]]], track_time: dict[str, list[list[float]]] | None = None
) -> pd.DataFrame:
    """A per-sequence table: per algorithm, per sequence, the trials' values (the same value for
    every metric), durations 100 s each."""
    rows = []
    for alg, seqs in values.items():
        for s, trials in enumerate(seqs):
            for k, x in enumerate(trials):
                tt = track_time[alg][s][k] if track_time else 50.0
                rows.append(dict(algorithm=alg, scene="s", seq=s + 1, trial=k + 1 if len(trials) > 1 else 0, cr=x,
                                 cr_t=x, cs_r=x, c_ate_rmse=x, gt_duration=100.0, track_time=tt, c_matched=10,
                                 matched=100))  # fmt: skip
    return pd.DataFrame(rows)


def test_paired_test_enumerates_every_sign_flip():
    # A always better on 6 sequences: only the observed flips and their mirror reach |T|: 2/64
    r = permutation_test(_one([1, 2, 3, 4, 5, 6]), _one([0] * 6))
    assert (r.pvalue, r.min_p, r.relabellings, r.exact) == (2 / 64, 2 / 64, 64.0, True)
    # five sequences cannot go below 2/32 (the README's 0.0625)
    assert permutation_test(_one([1, 2, 3, 4, 5]), _one([0] * 5)).pvalue == 0.0625
    # a zero difference leaves the test (16 flips); |T| >= 1.4 in 6 of 16 flips (enumerated): 0.375;
    # the largest |T| (all of one sign) in 2 of 16: min_p 0.125
    r = permutation_test(_one([1, -2, 3, 0, 5]), _one([0] * 5))
    assert (r.pvalue, r.min_p, r.relabellings) == (0.375, 0.125, 16.0)
    # weights 1:2:5 on differences 0.4, 0.2, 0.6: T = 0.475; 2 of 8 flips reach it
    r = permutation_test(_one([0.9, 0.8, 0.7]), _one([0.5, 0.6, 0.1]), [1, 2, 5])
    assert r.statistic == pytest.approx(0.475) and r.pvalue == 0.25
    # identical algorithms: nothing moves, p = 1
    r = permutation_test(_one([0.5, 0.6, 0.7]), _one([0.5, 0.6, 0.7]))
    assert (r.statistic, r.pvalue, r.min_p, r.relabellings) == (0.0, 1.0, 1.0, 1.0)


def test_trials_of_unequal_counts_enumerate_every_relabelling():
    # 4 vs 4 trials of one sequence, separated: 2 / C(8, 4) = 2/70 (the README's 0.029)
    r = permutation_test([np.array([1.0, 2, 3, 4])], [np.array([5.0, 6, 7, 8])])
    assert r.pvalue == pytest.approx(2 / 70) and r.relabellings == 70
    # 2 vs 4 trials: C(6, 2) = 15 relabellings, {1,2} and its mirror {5,6} reach |T| = 3: 2/15
    r = permutation_test([np.array([1.0, 2])], [np.array([3.0, 4, 5, 6])])
    assert r.pvalue == pytest.approx(2 / 15) and r.relabellings == 15
    # 3 vs 2 and 1 vs 4 trials, equal weights: C(5,3) * C(5,1) = 50 relabellings, only the observed
    # one reaches |T| = 0.11 (the next largest is 0.089): 1/50
    r = permutation_test([np.array([0.6, 0.7, 0.65]), np.array([0.8])],
                         [np.array([0.5, 0.55]), np.array([0.7, 0.72, 0.71, 0.69])])  # fmt: skip
    assert r.statistic == pytest.approx(0.11) and r.pvalue == pytest.approx(1 / 50) and r.relabellings == 50
    # weights 2:1, 3 vs 3 and 2 vs 3 trials: 20 * 10 = 200 relabellings, 24 reach |T| = 0.8: 0.12
    r = permutation_test([np.array([1.0, 2, 3]), np.array([0.5, 0.7])],
                         [np.array([2.0, 3, 4]), np.array([0.9, 1.0, 1.1])], [2, 1])  # fmt: skip
    assert r.statistic == pytest.approx(-0.8) and r.pvalue == pytest.approx(0.12) and r.min_p == pytest.approx(0.005)
    assert runs_needed(0.05, paired=True) == 6 and runs_needed(0.05, paired=False) == 4
    assert runs_needed(0.05, paired=False, strata=2) == 3  # 2 / C(6,3)^2 = 0.005; 2 / C(4,2)^2 = 0.056


def test_difference_interval_is_the_set_of_accepted_shifts():
    # 6 paired differences 0.5, 0.5, 0.5, 0.5, 0.45, 0.39: a shift c is rejected (p = 2/64) only when
    # every d - c has one sign, so the accepted shifts are [min d, max d]
    a, b = _one([0.6, 0.7, 0.8, 0.9, 0.95, 0.99]), _one([0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    low, high = difference_interval(a, b, None, 0.05)
    assert low == pytest.approx(0.39, abs=1e-6) and high == pytest.approx(0.5, abs=1e-6)


def test_holm_and_its_levels():
    # Holm by hand: sorted 0.005*4, 0.01*3, 0.03*2, 0.04*1, running maximum
    p = np.array([0.01, 0.04, 0.03, 0.005])
    assert stats.holm(p) == pytest.approx([0.03, 0.06, 0.06, 0.02])
    assert holm_levels(p, 0.05) == pytest.approx([0.05 / 3, 0.025, 0.025, 0.0125])


def test_equal_p_values_share_their_holm_level():
    """Three pairs with p = 0.0625 at alpha 0.2 were decided at 0.2/3, 0.1 and 0.2 by the order the
    pairs happened to be listed in, so the same evidence gave a 93 %, a 90 % and an 80 % interval;
    Holm rejects equal p-values together, at the first one's level."""
    assert holm_levels(np.array([0.0625, 0.0625, 0.0625]), 0.2) == pytest.approx([0.2 / 3] * 3)
    assert holm_levels(np.array([0.02, 0.02]), 0.05) == pytest.approx([0.025, 0.025])  # both rejected (Holm 0.04)
    t = _table({"A": [[0.6], [0.7], [0.8], [0.9], [0.95], [0.99]], "B": [[0.1], [0.2], [0.3], [0.4], [0.5], [0.6]],
                "C": [[0.35], [0.45], [0.55], [0.65], [0.72], [0.79]]})  # fmt: skip
    pw = stats.pairwise(t, alpha=0.2)  # every pair: p = 2/64, Holm 3/32 <= 0.2, all at level 0.2/3
    assert pw["p"].tolist() == [2 / 64] * 3 and pw["significant"].all()
    assert pw["interval_level"].tolist() == pytest.approx([1 - 0.2 / 3] * 3)


def test_one_holm_family_over_every_scene_of_a_comparison():
    """Two scenes, one pair each, A better on all six sequences of both: p = 2/64 in each. Holm per
    scene called both pairs significant at 0.05, so a comparison of several scenes claimed a
    difference somewhere more often than alpha; over one family, 2 * 2/64 = 0.0625 > 0.05."""
    one = _table({"A": [[0.6], [0.7], [0.8], [0.9], [0.95], [0.99]], "B": [[0.1], [0.2], [0.3], [0.4], [0.5], [0.6]]})
    t = pd.concat([one, one.assign(scene="t")], ignore_index=True)
    pw = stats.pairwise(t)
    assert pw["p"].tolist() == [2 / 64] * 2
    assert pw["p_holm"].tolist() == pytest.approx([0.0625] * 2) and not pw["significant"].any()
    assert not pw["reachable"].any() and set(pw["correction"]) == {"Holm over 2 pair(s) of 2 scene(s), alpha 0.05"}
    assert stats.pairwise(t, alpha=0.1)["significant"].all()  # 0.0625 <= 0.1


@pytest.mark.parametrize("alpha", [1.5, 1.0, 0.0, -0.1, float("nan")])
def test_alpha_outside_0_1_is_refused(alpha):
    """pairwise(alpha=1.5) called two identical algorithms significantly different (p_holm 1 <=
    1.5) and runs_for_power(alpha=0) failed with 'cannot convert float NaN to integer'."""
    t = _table({"A": [[0.5], [0.6], [0.7]], "B": [[0.5], [0.6], [0.7]]})
    with pytest.raises(ln.ValidationError, match="alpha"):
        stats.pairwise(t, alpha=alpha)
    pairs = stats.pairwise(t)
    with pytest.raises(ln.ValidationError, match="alpha"):
        power.runs_for_power(t, pairs, 0.1, alpha=alpha)
    with pytest.raises(ln.ValidationError, match="alpha"):
        units_for_power(0.1, 0.05, alpha=alpha)
    with pytest.raises(ln.ValidationError, match="alpha"):
        runs_needed(alpha, paired=True)


def test_power_sizes_each_pair_at_holms_level():
    """compare --power sized each pair at alpha itself, while Holm holds the smallest p-value of m
    pairs to alpha / m: 6 algorithms x 2 trials of 3 sequences (15 pairs), the line above said no
    pair could reach 0.05 and the power table said the 2 trials a side sufficed. Sized at alpha / m,
    the design named reaches alpha after the correction: its smallest p passes alpha / m."""
    rng = np.random.default_rng(5)
    algs = {a: [list(0.5 + 0.02 * k + rng.normal(0, 0.01, 2)) for _ in range(3)] for k, a in enumerate("ABCDEF")}
    t = _table(algs)
    pairs = stats.pairwise(t)
    m = len(pairs)
    alone = power.runs_for_power(t, pairs, 0.3, alpha=0.05)
    held = power.runs_for_power(t, pairs, 0.3, alpha=0.05, comparisons=m)
    assert (alone["needed"] == 2).all() and (held["needed"] == runs_needed(0.05 / m, paired=False, strata=3)).all()
    assert (held["needed"] > alone["needed"]).all()
    assert runs_needed(0.05 / m, paired=False, strata=3) > 2  # 2 a side over 3 sequences: p >= (1/3)^3 > 0.05/15
    with pytest.raises(ln.ValidationError, match="comparisons"):
        power.runs_for_power(t, pairs, 0.3, comparisons=0)


def test_identical_algorithms_are_never_separated():
    t = _table({"A": [[0.5], [0.6], [0.7], [0.8], [0.9], [0.95]], "B": [[0.5], [0.6], [0.7], [0.8], [0.9], [0.95]]})
    r = stats.pairwise(t).iloc[0]
    assert (r["difference"], r["p"], r["p_holm"], r["significant"], r["better"]) == (0.0, 1.0, 1.0, False, "")


def test_one_sequence_with_trials_is_the_plain_mean_of_its_trials():
    """One sequence, two trials of CR-T 0.2 and 0.8 tracked 10 s and 90 s: the scene value is the
    sequence's mean over trials, 0.5, as pairwise, trial_summary and several sequences have it; the
    interval and the ranking reported the track-time weighted 0.2*0.1 + 0.8*0.9 = 0.74."""
    t = _table({"A": [[0.2, 0.8]], "B": [[0.5, 0.5]]}, track_time={"A": [[10.0, 90.0]], "B": [[50.0, 50.0]]})
    ci = stats.confidence_intervals(t, ["cr_t"]).set_index("algorithm")
    assert ci.loc["A", "value"] == pytest.approx(0.5) and ci.loc["A", "unit"] == "trials"
    assert stats.scene_means(t, "cr_t").set_index("algorithm").loc["A", "value"] == pytest.approx(0.5)
    assert stats.pairwise(t, "cr_t").iloc[0]["value_a"] == pytest.approx(0.5)


def test_bootstrap_interval_is_scipys():
    # five sequences of durations 10..50 s, one trial: scipy.stats.bootstrap (percentile, paired over
    # (value, weight), 2000 resamples, seed 3) of the weighted mean gives [0.74, 0.9095238...]
    t = _table({"A": [[0.6], [0.7], [0.8], [0.9], [0.95]]})
    t["gt_duration"] = [10.0, 20.0, 30.0, 40.0, 50.0]
    ci = stats.confidence_intervals(t, ["cr"], level=0.9, seed=3).iloc[0]
    assert ci["value"] == pytest.approx(0.85) and ci["low"] == pytest.approx(0.74)
    assert ci["high"] == pytest.approx(0.9095238095238095)


def test_an_interval_does_not_depend_on_the_other_algorithms():
    """Two algorithms with the same values got different intervals (one random stream ran through
    every algorithm in turn), and adding an algorithm changed the others' intervals at one seed;
    each interval now draws from its own stream of the seed."""
    same = [[0.6], [0.7], [0.8], [0.9], [0.95]]
    t = _table({"A": same, "B": same, "C": [[0.1], [0.5], [0.2], [0.4], [0.3]]})
    ci = stats.confidence_intervals(t, ["cs_r", "cr"], seed=5)
    ci = ci[ci["metric"] == "cr"].set_index("algorithm")
    alone = stats.confidence_intervals(t[t["algorithm"] == "B"], ["cr"], seed=5).iloc[0]
    assert ci.loc["A", "low"] == ci.loc["B", "low"] == alone["low"]
    assert ci.loc["A", "high"] == ci.loc["B", "high"] == alone["high"]
