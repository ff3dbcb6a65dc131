"""The adversarial pass s68 of ``lorisnb compare``: a copy is a copy of what the test sees. Copies of
one rerun with their errors scaled by 0.2 % (CR unchanged) beside one real rerun made two labels of
one system differ in 18 of 30 of a helper's nights (every-value rule: not copies; spread rule: lifted
by the real rerun); four copies of one run, positions scaled and one pose dropped from one, had a
realistic ATE spread and CR tested at p 0.0005; past 100 pairs no sampled test could reach alpha
(2,000 draws: p >= 0.0005, x pairs by Holm) while ``min_p`` and ``reachable`` said it could; a scene
of copies said nothing of why no pair was tested. Real data: the bundled icra20 results."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from helpers import rerun_trials

import lorisnb as ln
from lorisnb.core.stats.inference import MAX_RESAMPLES, RESAMPLES_PER_LEVEL, pairwise
from lorisnb.tools.decisions.comparison import COPIES_TEST, compare_table, prepared_table

ERRORS = ("ate_rmse", "aoe_rmse", "c_ate_rmse", "c_aoe_rmse")


@pytest.fixture(scope="module")
def run(icra20):
    """One real run of orbslam2_rgbd's per-seq results (CR at eps = phi = inf: its tracked share)."""
    ev = ln.evaluate([icra20 / "per-seq" / "orbslam2_rgbd"], progress=False)
    return ev.sequences(), ev.durations()


def _scaled(t: pd.DataFrame, factor: float) -> pd.DataFrame:
    """A copy of a run whose errors moved by ``factor`` (a trace of noise in its positions)."""
    return t.assign(**{c: t[c] * factor for c in ERRORS if c in t})


def _labelled(parts: list[pd.DataFrame], label: str) -> pd.DataFrame:
    return pd.concat([p.assign(trial=k + 1, algorithm=label) for k, p in enumerate(parts)], ignore_index=True)


def test_copies_of_a_rerun_beside_a_real_one_count_once_for_the_metric_tested(run):
    """Each label: two reruns and two copies of the second whose errors moved by 0.2 % and 0.3 %
    (CR the same): the copies' rows are counted once, so the test sees two trials a sequence, not
    four (every value differs beyond 1e-4, the CR does not)."""
    seqs, durations = run
    reruns = [rerun_trials(seqs, (1,), seed).drop(columns="trial") for seed in range(4)]
    x = _labelled([reruns[0], reruns[1], _scaled(reruns[1], 1.002), _scaled(reruns[1], 1.003)], "sys (1)")
    y = _labelled([reruns[2], reruns[3], _scaled(reruns[3], 1.002), _scaled(reruns[3], 1.003)], "sys (2)")
    table = pd.concat([x, y], ignore_index=True)
    full, _, counted = prepared_table(table, durations, "cr")
    inside = ((table["cr"] > 0) & (table["cr"] < 1)).groupby(table["algorithm"]).sum()
    assert counted == {a: (int(inside[a] / 4 * 2), len(x)) for a in ("sys (1)", "sys (2)")}
    tells = full[(full["cr"] > 0) & (full["cr"] < 1)]  # at 0 or 1 reruns tie: no copy is told there
    assert (tells.groupby(["algorithm", "scene", "seq"]).size() == 2).all()
    res = compare_table(table, durations)
    assert (res.pairs["trials_a"] >= 2).all()  # the test's trials: those left
    assert any("or its cr (copies, not reruns), counted once" in n for n in res.notes)
    # the every-value rule alone would have kept them: their errors differ by 0.2 %, beyond 1e-4
    every = prepared_table(table.assign(cr=table["cr"] + 1e-3 * table["trial"]), durations, "cr")[2]
    assert every == {}


def test_copies_with_a_realistic_ate_spread_and_a_cr_no_rerun_repeats_are_not_tested(run):
    """Four copies of one run per label, positions scaled by 1.0-1.3 (ATE spread about 11 %, a
    rerun's) and one pose dropped from the second (its CR 0.1 % lower): CR varies 90 times less than
    reruns do, so the trials are copies for the CR test: no p-value, nothing reachable, and the
    summary says why."""
    seqs, durations = run
    one = seqs.copy()
    parts = [_scaled(one, f) for f in (1.0, 1.1, 1.2, 1.3)]
    parts[1] = parts[1].assign(cr=parts[1]["cr"] * 0.999)
    table = pd.concat([_labelled(parts, "a"), _labelled([p.assign(cr=np.clip(p["cr"] * 0.9, 0, 1)) for p in parts],
                                                      "b")], ignore_index=True)  # fmt: skip
    res = compare_table(table, durations)
    assert (res.pairs["test"] == COPIES_TEST).all()
    assert not res.pairs["reachable"].any() and res.pairs["min_p"].isna().all() and res.pairs["p"].isna().all()
    assert res.pairs["relabellings"].isna().all() and not res.pairs["significant"].any()
    assert "the trials are copies of one run: no pair is tested" in res.summary
    assert "no two algorithms both have a value" not in res.summary
    note = next(n for n in res.notes if n.startswith("the trials of a, b are near-identical"))
    assert "cr, the metric tested, varies by" in note
    # real reruns of the same run (CR spread 0.017) are tested
    reruns = [rerun_trials(seqs, (1,), seed).drop(columns="trial") for seed in range(8)]
    real = pd.concat([_labelled(reruns[:4], "a"), _labelled(reruns[4:], "b")], ignore_index=True)
    assert not (compare_table(real, durations).pairs["test"] == COPIES_TEST).any()


def test_a_sampled_test_draws_enough_for_holm_over_many_pairs_and_says_its_floor():
    """15 algorithms (105 pairs), 4 trials of 4 sequences each (70^4 relabellings: sampled), one of
    them far below the others at a rerun's spread: its 14 pairs are significant (with 2,000 draws p
    could not go below 1/2001, p_holm 0.05 at best, and none was), and ``min_p`` is the sampled
    test's floor 1 / (draws + 1), which ``reachable`` follows."""
    rng = np.random.default_rng(1)
    rows = [dict(suite="", algorithm=f"alg{a:02d}", scene="home", seq=s, trial=t, gt_duration=100.0,
                 cr=float(np.clip((0.1 if a == 0 else 0.8) + rng.normal(0, 0.017), 0, 1)))
            for a in range(15) for s in range(1, 5) for t in range(1, 5)]  # fmt: skip
    pairs = pairwise(pd.DataFrame(rows), "cr", intervals=False)
    draws = min(max(2000, int(np.ceil(RESAMPLES_PER_LEVEL * 105 / 0.05))), MAX_RESAMPLES)
    assert len(pairs) == 105 and not pairs["exact"].any()
    assert (pairs["min_p"] == 1 / (draws + 1)).all() and pairs["reachable"].all()
    assert set(pairs.loc[pairs["significant"], "better"]) == {f"alg{a:02d}" for a in range(1, 15)}
    assert int(pairs["significant"].sum()) == 14
    assert (pairs.loc[pairs["significant"], "p_holm"] < 0.01).all()


def test_the_header_says_what_the_intervals_resample_of_the_metric_compared(run):
    """The header joined the units of every metric's intervals (``sequences x trials, trials``: a
    scene with one sequence holding C-ATE); it names the compared metric's unit and the scenes
    whose unit differs."""
    seqs, durations = run
    rng = np.random.default_rng(5)
    reruns = [rerun_trials(seqs, (1,), seed).drop(columns="trial") for seed in range(4)]
    reruns = [r.assign(c_ate_rmse=r["c_ate_rmse"] * np.exp(rng.normal(0, 0.19, len(r)))) for r in reruns]
    table = pd.concat([_labelled(reruns[:2], "a"), _labelled(reruns[2:], "b")], ignore_index=True)
    home = (table["scene"] == "home") & (table["seq"] != table.loc[table["scene"] == "home", "seq"].min())
    table.loc[home, ["c_ate_rmse", "c_aoe_rmse"]] = np.nan  # home: one sequence with a correct pose
    table.loc[home, "c_matched"] = 0
    cr = compare_table(table, durations).header
    assert "bootstrap intervals over sequences x trials (" in cr and ", trials" not in cr.split("(")[0]
    ate = compare_table(table, durations, metric="c_ate_rmse").header
    assert "bootstrap intervals over sequences x trials (trials in home) (" in ate, ate[:200]


@pytest.mark.parametrize(
    ("edit", "said"),
    [
        (lambda t: t.assign(cr=t["cr"].where(t.index != 0, 1.7)), "column cr: 1.7 is not a rate between 0 and 1"),
        (lambda t: t.assign(cr=t["cr"].where(t.index != 0, np.nan)), "column cr: nan is not a rate"),
        (
            lambda t: t.assign(cr=t["cr"].astype(object).where(t.index != 0, "high")),
            "column cr: 'high' is not a number",
        ),
        (lambda t: t.assign(trial=[1.5] + [1] * (len(t) - 1)), "column trial: 1.5 is not a trial number"),
    ],
)
def test_a_table_edited_by_hand_is_refused_by_compare_as_by_diff(run, edit, said):
    """``compare_table`` took a CR of 1.7 (the scene value moved 0.741 -> 0.841 with no word), NaN,
    text and a trial 1.5; it refuses them naming the row, as ``diff`` does (one check)."""
    from lorisnb.errors import ValidationError

    seqs, durations = run
    with pytest.raises(ValidationError, match="row 0 .*" + said.replace("(", r"\(")):
        compare_table(edit(seqs.copy()), durations)
    assert not compare_table(seqs.copy(), durations).algorithms.empty  # the table as evaluate made it
