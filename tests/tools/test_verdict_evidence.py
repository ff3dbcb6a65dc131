"""What counts as evidence in ``lorisnb diff``'s verdict (issue 44, checked on nights it never saw):
copies of one run are one run, trial numbers are labels (not pairings between the runs), a base
that matched a handful of poses, none correct, has no tracking to lose, and a table edited by hand
is refused in Python as on the command line. Real data: the bundled icra20 results, evaluated, and
trials made from them with a rerun-sized spread."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from helpers import longest_tracked, rerun_trials

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.stats.regression import changes
from lorisnb.tools.decisions.diff import diff_tables

ALG = "orbslam2_rgbd"


@pytest.fixture(scope="module")
def table(paper_sequences):
    return paper_sequences.copy()


def _copies(table: pd.DataFrame, n: int = 3) -> pd.DataFrame:
    return pd.concat([table.assign(trial=k) for k in range(1, n + 1)], ignore_index=True)


def _lower_cr(t: pd.DataFrame, where: tuple[str, int], by: float) -> pd.DataFrame:
    t = t.copy()
    here = (t["algorithm"] == ALG) & (t["scene"] == where[0]) & (t["seq"] == where[1])
    t.loc[here, "cr"] = t.loc[here, "cr"] - by
    return t


def _row(seqs: pd.DataFrame, where: tuple[str, int], metric: str) -> pd.Series:
    r = seqs[(seqs["algorithm"] == ALG) & (seqs["scene"] == where[0]) & (seqs["seq"] == where[1])]
    return r[r["metric"] == metric].iloc[0]


def test_copies_of_one_run_are_one_run_not_significance(table):
    """One run copied into three trials a side (byte-identical, or with a trace of noise) is one run's
    evidence: a CR drop of 0.1 on one sequence, which a single run per side cannot tell from rerun
    noise, is judged by the single-run rule and named as copies, not called significant by a t-test
    on copies (it was: Holm-adjusted p 1e-4 over 302 tests); real reruns with the same drop on every
    trial still regress."""
    where = longest_tracked(table, ALG)
    cand = _lower_cr(table, where, 0.1)
    single = _row(changes(table, cand)[0], where, "cr")
    assert single["status"] == "ok" and "single run per side" in single["decided_by"]
    seqs, scenes = changes(_copies(table), _copies(cand))
    row = _row(seqs, where, "cr")
    assert row["status"] == "ok", row["decided_by"]
    assert "single run per side" in row["decided_by"] and "near-identical copies of one run" in row["decided_by"]
    assert "BASE's trials are" in row["decided_by"] and "CAND's trials are" in row["decided_by"]
    assert not set(seqs["status"]) & {"regression", "missing", "failed"}
    assert not set(scenes["status"]) & {"regression", "missing"}
    rng = np.random.default_rng(0)  # near-identical: CR +-1e-4, ATE +-0.5 %
    near = [_copies(t).assign(cr=lambda x: np.clip(x["cr"] + rng.normal(0, 1e-4, len(x)), 0, 1),
                              ate_rmse=lambda x: x["ate_rmse"] * np.exp(rng.normal(0, 0.005, len(x))))
            for t in (table, cand)]  # fmt: skip
    row = _row(changes(*near)[0], where, "cr")
    assert row["status"] == "ok" and "near-identical copies of one run" in row["decided_by"]
    base, reruns = rerun_trials(table, range(1, 6), 1), rerun_trials(table, range(1, 6), 2)
    row = _row(changes(base, _lower_cr(reruns, where, 0.3))[0], where, "cr")
    assert row["status"] == "regression" and "copies" not in row["decided_by"]


def test_one_runs_tracking_with_its_positions_changed_is_one_run_too(table):
    """Three "trials" that are one run with its positions scaled (x1.0, x1.12, x0.9): ATE varies by half,
    but CR, a share of time, is the same to the last digit wherever it is neither 0 nor 1, which reruns
    never repeat. They are copies: the verdict judges them as one run a side (a t-test on them called a
    CR-T drop of 0.065 significant), and compare claims no significance for them."""
    from lorisnb.core.stats.inference import trial_spread
    from lorisnb.tools.decisions.comparison import compare_table

    def scaled(t: pd.DataFrame) -> pd.DataFrame:
        return pd.concat([t.assign(trial=k, ate_rmse=t["ate_rmse"] * f, c_ate_rmse=t["c_ate_rmse"] * f)
                          for k, f in enumerate((1.0, 1.12, 0.9), start=1)], ignore_index=True)  # fmt: skip

    where = longest_tracked(table, ALG)
    base, cand = scaled(table), scaled(_lower_cr(table, where, 0.1))
    spread = trial_spread(base).set_index("algorithm")
    assert spread.loc[ALG, "ate_spread"] > 0.05 and spread.loc[ALG, "cr_ties"] == 1.0 and spread.loc[ALG, "copies"]
    row = _row(changes(base, cand)[0], where, "cr")
    assert row["status"] == "ok" and "the same to the last digit" in row["decided_by"], row["decided_by"]
    real = rerun_trials(table, range(1, 4), 3)  # reruns: CR varies, no ties
    assert not trial_spread(real).set_index("algorithm").loc[ALG, "copies"]
    mine = base[base["algorithm"] == ALG]
    two = pd.concat([mine, mine.assign(algorithm="other", cr=mine["cr"] * 0.97)], ignore_index=True)
    durations = table[["scene", "seq", "gt_duration"]].drop_duplicates()
    res = compare_table(two, durations, "cr")
    assert any("near-identical" in n and "last digit" in n for n in res.notes), res.notes
    assert not res.pairs["significant"].any()
    # and nothing else claims it: no p-value, an interval of the difference that holds 0, in the pairs and vs top
    assert res.pairs["p_holm"].isna().all() and res.pairs["p"].isna().all()
    assert (res.pairs["difference_low"] == -np.inf).all() and (res.pairs["difference_high"] == np.inf).all()
    second = res.algorithms[res.algorithms["algorithm"] != res.algorithms["top"]]
    assert len(second)
    sized = compare_table(two, durations, "cr", power_delta=0.05)  # copies' zero spread sized nothing right
    assert sized.power is not None and len(sized.power) == 0
    assert any(n.startswith("--power: no number of runs for the pairs of") for n in sized.notes), sized.notes
    assert second["p_holm_vs_top"].isna().all() and second["vs top [test interval]"].str.endswith("[-inf, inf]").all()


def test_a_trial_that_repeats_another_counts_once(table):
    """Four reruns and a fifth trial that is a byte-identical copy of the fourth: 5 vs 4 independent
    runs, and the verdict says so at the sequence and the scene level. The copy is no run: against
    a base of 5 reruns it is a missing trial (a crashed trial filled in with another's output
    regresses as the crash would), named; where the base holds no more independent runs, or the
    candidate holds enough besides the copy, nothing is missing."""
    base = rerun_trials(table, range(1, 6), 3)
    cand = rerun_trials(table, range(1, 5), 4)
    cand = pd.concat([cand, cand[cand["trial"] == 4].assign(trial=5)], ignore_index=True)
    seqs, scenes = changes(base, cand)
    judged = seqs[(seqs["status"] == "ok") & seqs["decided_by"].str.startswith("t-test")]
    assert len(judged) and judged["decided_by"].str.contains("5 vs 5 trials, tested on 5 vs 4 values").all()
    assert judged["decided_by"].str.contains("1 of CAND's trials repeat another's every value: counted once").all()
    scene = scenes[scenes["decided_by"].str.startswith("t-test")]
    assert len(scene) and scene["decided_by"].str.contains("5 vs 5 trials, tested on 5 vs 4 values").all()
    lost = seqs[seqs["metric"] == "trial"]
    with_output = table["matched"].to_numpy() > 0  # a trial without output repeats nothing
    assert (
        len(lost) == with_output.sum()
        and (lost["status"] == "missing").all()
        and (lost["cand"] == "trial 5 a copy").all()
    )
    assert lost["decided_by"].str.contains("trial 5 repeats trial 4.s every value").all()
    assert diff_tables(base, cand).regressed
    assert not set(seqs.loc[seqs["metric"] != "trial", "status"]) & {"regression", "missing", "failed"}
    other = rerun_trials(table, range(1, 5), 5)  # both sides 4 runs and a copy
    other = pd.concat([other, other[other["trial"] == 2].assign(trial=5)], ignore_index=True)
    assert not (changes(cand, other)[0]["metric"] == "trial").any()
    five = rerun_trials(table, range(1, 6), 6)  # 5 runs and a copy of its fourth: 5 independent besides the copy
    six = pd.concat([five, five[five["trial"] == 4].assign(trial=6)], ignore_index=True)
    seqs = changes(base, six)[0]
    assert not (seqs["metric"] == "trial").any()
    assert seqs["decided_by"].str.contains("1 of CAND's trials repeat another's every value").any()


def test_reruns_that_vary_little_are_no_missing_trials(table):
    """Reruns of a system that tracks nearly all of a sequence with a steady ATE vary by less than a
    quarter of the rerun spread now and then (a helper's noise-only nights: CR 0.0037, ATE 1.8 %):
    taken for near-identical copies, three such CAND trials were one run against BASE's three, and
    the night failed as "trial 2, 3 a copy", on noise alone. Only trials that repeat another's every
    value are no run; near-identical ones still count as one run in the values."""
    base = rerun_trials(table, (1, 2, 3), 11)
    rng = np.random.default_rng(12)
    parts = []
    for k in (1, 2, 3):  # reruns with a small spread: every value different
        t = table.assign(trial=k)
        t["cr"] = np.clip(t["cr"] + rng.normal(0, 0.002, len(t)), 0, 1)
        t["ate_rmse"] = t["ate_rmse"] * np.exp(rng.normal(0, 0.01, len(t)))
        parts.append(t)
    cand = pd.concat(parts, ignore_index=True)
    seqs, _ = changes(base, cand)
    assert not (seqs["metric"] == "trial").any()
    assert seqs["decided_by"].str.contains("near-identical copies of one run").any()  # one run in the values
    exact = _copies(table)  # byte-identical copies: still no runs, so missing trials against 3 reruns
    assert (changes(base, exact)[0]["cand"] == "trial 2, 3 a copy").any()


def test_compare_counts_a_copied_trial_once(table):
    """Two labels of one system, each with 4 trials of which 3 are byte-identical copies of one rerun
    (a script filling in crashed trials): the spread of the fourth kept them from the near-copy rule,
    and compare called pairs significant (a helper: 7 of 25 such nights) where the two reruns a side
    they are show nothing. A copied trial counts once, as diff counts it, and the note says so."""
    from lorisnb.tools.decisions.comparison import compare_table

    mine = table[table["algorithm"] == ALG]
    runs = rerun_trials(mine, range(1, 5), 21)
    one, other = runs[runs["trial"] == 1], runs[runs["trial"] == 3]
    a = pd.concat([one, one.assign(trial=2), one.assign(trial=4), other.assign(trial=3)], ignore_index=True)
    runs = rerun_trials(mine, range(1, 5), 22)
    one, other = runs[runs["trial"] == 2], runs[runs["trial"] == 4]
    b = pd.concat([one.assign(trial=1), one, one.assign(trial=3), other], ignore_index=True)
    two = pd.concat([a.assign(algorithm="A"), b.assign(algorithm="B")], ignore_index=True)
    durations = table[["scene", "seq", "gt_duration"]].drop_duplicates()
    res = compare_table(two, durations, "cr")
    seqs = len(mine)
    assert any(n.startswith("trials that repeat another trial's every value") and f"A: {2 * seqs} of {4 * seqs}" in n
               for n in res.notes), res.notes  # fmt: skip
    dedup = two.drop_duplicates(subset=["algorithm", "scene", "seq", "cr", "ate_rmse"])
    alone = compare_table(dedup, durations, "cr")
    assert res.pairs[["p", "p_holm", "significant"]].equals(alone.pairs[["p", "p_holm", "significant"]])
    assert "2 trial(s) per sequence" in res.header


def test_a_single_run_regression_cannot_widen_its_own_band(table):
    """One run a side: the rerun band was widened to 4x the 90th percentile of the diff's unsigned
    changes, so a regression of more than a tenth of the comparisons hid itself (every orbslam2 ATE
    x10: ok, exit 0), and an improvement of one system hid a regression of another (odom's ATE /10
    beside one orbslam2 sequence x8). Noise moves values both ways; the band now widens by the
    smaller of the two tails, which neither a regression nor an improvement alone can inflate."""
    base, cand = rerun_trials(table, (1,), 31), rerun_trials(table, (1,), 32)
    orb = cand["algorithm"] == ALG
    every = cand.assign(ate_rmse=np.where(orb, cand["ate_rmse"] * 10, cand["ate_rmse"]))
    d = diff_tables(base, every)
    rows = d.sequences[(d.sequences["metric"] == "ate_rmse") & (d.sequences["algorithm"] == ALG)]
    assert d.regressed and (rows["status"] == "regression").mean() > 0.8
    where = longest_tracked(table, ALG)
    one = orb & (cand["scene"] == where[0]) & (cand["seq"] == where[1])
    beside = cand.assign(ate_rmse=np.where(one, cand["ate_rmse"] * 8, np.where(orb, cand["ate_rmse"],
                                                                                cand["ate_rmse"] / 10)))  # fmt: skip
    row = _row(diff_tables(base, beside).sequences, where, "ate_rmse")
    assert row["status"] == "regression", row["decided_by"]
    assert "the largest change noise-only single runs show" in row["decided_by"]  # not widened by odom's gain


def test_a_copy_with_a_pose_edited_is_still_a_copy(table):
    """A copied file with one digit of one pose changed moves its ATE by about 1e-6 and nothing
    else: compared exactly, it passed as a rerun (compare called two labels of one system different
    in 6 of 25 of a helper's draws). Values within SAME_VALUE relative are the same value; real
    reruns (CR +-0.017, ATE +-19 %) never are."""
    from lorisnb.core.stats.regression import SAME_VALUE, repeated_trials

    runs = rerun_trials(table, range(1, 4), 41)
    edited = runs[runs["trial"] == 1].assign(trial=4)
    edited["ate_rmse"] = edited["ate_rmse"] * (1 + 1e-6)
    edited["c_ate_rmse"] = edited["c_ate_rmse"] * (1 - 1e-6)
    cand = pd.concat([runs, edited], ignore_index=True)
    t = cand.assign(suite="")
    copies = repeated_trials(t)
    with_output = t["matched"].to_numpy() > 0
    assert (copies == ((t["trial"] == 4).to_numpy() & with_output)).all()  # the edited copy only
    assert not repeated_trials(rerun_trials(table, range(1, 6), 42).assign(suite="")).any()  # reruns never
    far = edited.assign(ate_rmse=edited["ate_rmse"] * (1 + 10 * SAME_VALUE))
    assert not repeated_trials(pd.concat([runs, far], ignore_index=True).assign(suite="")).any()
    base = rerun_trials(table, range(1, 5), 43)  # four runs against three and an edited copy: a missing trial
    lost = changes(base, cand)[0]
    lost = lost[lost["metric"] == "trial"]
    assert len(lost) and (lost["cand"] == "trial 4 a copy").all()
    assert lost["decided_by"].str.contains("trial 4 repeats trial 1.s every value").all()


def test_trial_numbers_are_labels_not_pairings(table):
    """Three trials a side numbered 1-3 and 4-6 (or 0-2 and 1-3) lack nothing (every sequence was
    missing trials 1, 2 and 3); a candidate with more trials than the base is not compared with a
    base padded with failed runs (which hid a CR drop of 0.4); fewer trials than the base are still
    missing trials."""
    base = rerun_trials(table, (1, 2, 3), 5)
    for numbers in ((4, 5, 6), (1, 2, 3)):
        cand = rerun_trials(table, numbers, 6)
        d = diff_tables(base, cand)
        assert not d.regressed and d.verdict["counts"]["missing"] == 0, numbers
    zero = rerun_trials(table, (0, 1, 2), 7)
    assert not diff_tables(zero, rerun_trials(table, (1, 2, 3), 8)).regressed
    where = longest_tracked(table, ALG)
    more = _lower_cr(rerun_trials(table, range(1, 6), 9), where, 0.4)
    seqs, _ = changes(base, more)
    row = _row(seqs, where, "cr")
    assert row["status"] == "regression" and row["base"] > 0.6, (row["base"], row["decided_by"])
    assert not (seqs["metric"] == "trial").any()
    fewer = changes(rerun_trials(table, range(1, 6), 10), rerun_trials(table, (1, 2, 3), 11))[0]
    lost = fewer[fewer["metric"] == "trial"]
    assert len(lost) == table.shape[0] and (lost["cand"] == "missing trial 4, 5").all()


def test_a_base_with_a_handful_of_poses_none_correct_has_nothing_to_lose(table):
    """A sequence whose base matched 30 poses in every trial and whose candidate matched none is too
    little to judge, not a failed sequence, whether or not those poses were correct: at eps = inf
    every matched pose is correct, and a system that tracked 15 poses of home-2 (CR 0.028) and
    failed to initialise in the candidate failed the night. One whose base matched 50 poses or more
    in a trial still fails."""
    where = longest_tracked(table, ALG)
    here = (table["algorithm"] == ALG) & (table["scene"] == where[0]) & (table["seq"] == where[1])
    nothing = table.copy()
    cols = ["matched", "c_matched", "correct_time", "track_time", "cr", "cr_t", "cs_r", "rpe_pairs", "c_rpe_pairs"]
    nothing.loc[here, cols] = 0
    for c in ("ate_rmse", "aoe_rmse", "c_ate_rmse", "c_aoe_rmse", "rpe_trans_rmse", "rpe_rot_rmse"):
        nothing.loc[here, c] = np.nan
    handful = table.copy()
    handful.loc[here, ["matched", "c_matched", "correct_time", "cr", "cs_r"]] = [30, 0, 0.0, 0.0, 0.0]
    d = diff_tables(handful, nothing)
    row = _row(d.sequences, where, "sequence")
    assert row["status"] == "unjudged" and "matched at most 30 poses in a trial" in row["decided_by"], row
    assert not d.regressed
    correct = handful.copy()  # all of them correct, as at eps = inf
    correct.loc[here, ["c_matched", "cr"]] = [30, 0.028]
    d = diff_tables(correct, nothing)
    row = _row(d.sequences, where, "sequence")
    assert row["status"] == "unjudged" and "CR 0.028" in row["decided_by"] and not d.regressed, row
    trials = pd.concat([correct.assign(trial=1), correct.assign(trial=2)], ignore_index=True)
    trials.loc[(trials["trial"] == 2) & np.tile(here.to_numpy(), 2), "matched"] = 60  # one trial tracked 60
    lost = pd.concat([nothing.assign(trial=1), nothing.assign(trial=2)], ignore_index=True)
    assert _row(diff_tables(trials, lost).sequences, where, "sequence")["status"] == "failed"
    assert _row(diff_tables(table, nothing).sequences, where, "sequence")["status"] == "failed"


@pytest.mark.parametrize(
    ("column", "value", "said"),
    [("cr", np.nan, "column cr: nan is not a rate"), ("cr", "abc", "column cr: 'abc' is not a number"),
     ("ate_rmse", np.inf, "column ate_rmse: inf is not an RMSE"), ("c_ate_rmse", -1, "column c_ate_rmse: -1 is not an RMSE")],
)  # fmt: skip
def test_a_table_edited_by_hand_is_refused_in_python_as_on_the_command_line(table, tmp_path, capsys, column, value,
                                                                             said):  # fmt: skip
    """NaN in CR was "too little to judge" in Python (never a regression) and text a raw ValueError;
    both runs' numbers are now checked as ``lorisnb diff`` checks a table it reads, naming the row."""
    cand = table.astype(object).copy()
    cand.loc[cand.index[3], column] = value
    with pytest.raises(ln.ValidationError, match=f"CAND: row 3 .*{said}"):
        diff_tables(table, cand)
    table.to_csv(tmp_path / "base.csv", index=False)
    cand.to_csv(tmp_path / "cand.csv", index=False)
    assert main(["diff", str(tmp_path / "base.csv"), str(tmp_path / "cand.csv"), "--no-progress"]) == 2
    assert said.split(":")[0] in capsys.readouterr().err
