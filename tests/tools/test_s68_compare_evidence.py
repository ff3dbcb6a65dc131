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


def _near(t: pd.DataFrame, seed: int) -> pd.DataFrame:
    """A copy of a run passed through a script adding a trace of noise: errors moved by 0.1-0.5 %,
    rates strictly between 0 and 1 by up to 1e-3 (a few poses flipping at the threshold)."""
    rng = np.random.default_rng(seed)
    out = _scaled(t, float(rng.uniform(1.001, 1.005)))
    for c in ("cr", "cr_t", "cs_r"):
        inside = (out[c] > 0) & (out[c] < 1)
        out[c] = np.where(inside, np.clip(out[c] + rng.uniform(-1e-3, 1e-3, len(out)), 0, 1), out[c])
    return out


def test_copies_of_a_rerun_beside_a_real_one_count_once(run):
    """Each label: two reruns and two copies of the second passed through a trace of noise (errors
    0.1-0.5 %, CR up to 1e-3): the copies' rows are counted once, so the test sees two trials a
    sequence, not four (every value differs beyond 1e-4, none beyond a trace of noise; 14 of 20 of a
    helper's nights called one system different from itself so). Real reruns count in full."""
    seqs, durations = run
    reruns = [rerun_trials(seqs, (1,), seed).drop(columns="trial") for seed in range(4)]
    x = _labelled([reruns[0], reruns[1], _near(reruns[1], 1), _near(reruns[1], 2)], "sys (1)")
    y = _labelled([reruns[2], reruns[3], _near(reruns[3], 3), _near(reruns[3], 4)], "sys (2)")
    table = pd.concat([x, y], ignore_index=True)
    full, _, counted = prepared_table(table, durations)
    tracked = full[full["matched"] > 0]
    assert (tracked.groupby(["algorithm", "scene", "seq"])["trial"].nunique() == 2).all()
    with_output = int((seqs["matched"] > 0).sum())
    assert counted == {a: (2 * with_output, len(x)) for a in ("sys (1)", "sys (2)")}
    res = compare_table(table, durations)
    assert any("within 1e-4 or a trace of noise (copies, not reruns), counted once" in n for n in res.notes)
    honest = pd.concat([_labelled(reruns, "sys (1)"), _labelled([rerun_trials(seqs, (1,), 10 + k).drop(
        columns="trial") for k in range(4)], "sys (2)")], ignore_index=True)  # fmt: skip
    assert prepared_table(honest, durations)[2] == {}  # reruns: no row counted once


def test_copies_with_a_realistic_ate_spread_and_a_cr_no_rerun_repeats_are_not_tested(icra20):
    """At the paper's thresholds, four copies of one run per label, positions scaled by 1.0-1.3
    (ATE spread about 11 %, a rerun's) and one pose dropped from the second (its CR 0.1 % lower):
    CR varies 90 times less than reruns do, so the trials are copies for the CR test: no p-value,
    nothing reachable, and the summary says why."""
    ev = ln.evaluate([icra20 / "per-seq" / "orbslam2_rgbd"], progress=False)
    seqs, durations = ev.sequences(eps="paper", phi=30), ev.durations()
    parts = [_scaled(seqs, f) for f in (1.0, 1.1, 1.2, 1.3)]
    parts[1] = parts[1].assign(cr=parts[1]["cr"] * 0.999)
    table = pd.concat([_labelled(parts, "a"), _labelled([p.assign(cr=np.clip(p["cr"] * 0.9, 0, 1)) for p in parts],
                                                      "b")], ignore_index=True)  # fmt: skip
    res = compare_table(table, durations)
    assert (res.pairs["test"] == COPIES_TEST).all()
    assert not res.pairs["reachable"].any() and res.pairs["min_p"].isna().all() and res.pairs["p"].isna().all()
    assert res.pairs["relabellings"].isna().all() and not res.pairs["significant"].any()
    assert res.pairs["interval_level"].isna().all()
    assert "the trials are copies of one run: no pair is tested" in res.summary
    assert "no two algorithms both have a value" not in res.summary
    assert any(n.startswith("the trials of a, b are near-identical") for n in res.notes)
    # real reruns of the same run (CR spread 0.017) are tested
    reruns = [rerun_trials(seqs, (1,), seed).drop(columns="trial") for seed in range(8)]
    real = pd.concat([_labelled(reruns[:4], "a"), _labelled(reruns[4:], "b")], ignore_index=True)
    assert not (compare_table(real, durations).pairs["test"] == COPIES_TEST).any()


def test_honest_reruns_of_a_system_that_never_loses_track_are_no_copies_at_eps_inf(run):
    """At eps = phi = inf CR is the share of time with output: a system that never loses track
    repeats it exactly from run to run while its ATE varies (11-14 % in a helper's reruns). Such
    reruns were called copies of one run and a real difference (CR 0.95 against 0.27) went untested;
    they are tested."""
    seqs, durations = run
    rng = np.random.default_rng(3)
    good = [seqs.assign(ate_rmse=seqs["ate_rmse"] * np.exp(rng.normal(0, 0.12, len(seqs))),
                        c_ate_rmse=seqs["c_ate_rmse"] * np.exp(rng.normal(0, 0.12, len(seqs)))) for _ in range(4)]  # fmt: skip
    bad = [g.assign(cr=g["cr"] * 0.3, cr_t=g["cr_t"] * 0.3) for g in good]
    table = pd.concat([_labelled(good, "good"), _labelled(bad, "bad")], ignore_index=True)
    res = compare_table(table, durations)
    assert not (res.pairs["test"] == COPIES_TEST).any() and not any("near-identical" in n for n in res.notes)
    tested = res.pairs[res.pairs["reachable"].astype(bool)]
    assert len(tested) and (tested["significant"] & (tested["better"] == "good")).all()


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
