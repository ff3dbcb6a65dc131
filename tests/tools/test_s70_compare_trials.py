"""A whole missing trial is a failed run in ``compare``, and the reason no pair can reach alpha is
told from the facts (s70). B's trial 3 with one sequence missing scored 0.757 with a warning; with
both missing (an empty ``trial3/``) it vanished and B scored 0.826, ranked first, exit 0: the
expected trials were B's own rows. And two algorithms tied on one of two sequences were said to
have "the same results on every sequence", where one sequence of one run each gives p 1 at best.
Real data: the bundled icra20 results, evaluated and varied as reruns."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.core.lifelong.coverage import complete
from lorisnb.tools.decisions.comparison import compare_table


@pytest.fixture(scope="module")
def runs(icra20):
    """odom and orbslam2_rgbd on home, three reruns (trials 1 to 3) each, values varied as reruns."""
    ev = ln.evaluate([icra20 / "per-seq" / "odom", icra20 / "per-seq" / "orbslam2_rgbd"], progress=False)
    table = ev.sequences(eps="paper", phi=30)
    table = table[table["scene"] == "home"]
    rng = np.random.default_rng(70)
    parts = []
    for k in (1, 2, 3):
        t = table.assign(trial=k)
        t["cr"] = np.clip(t["cr"] + rng.normal(0, 0.02, len(t)), 0, 1)
        t["ate_rmse"] = t["ate_rmse"] * np.exp(rng.normal(0, 0.2, len(t)))
        parts.append(t)
    return pd.concat(parts, ignore_index=True), ev.durations()


def _value(res, alg: str) -> float:
    return float(res.algorithms.set_index("algorithm").loc[alg, "value"])


def test_a_whole_missing_trial_is_a_failed_run_of_every_sequence(runs):
    table, durations = runs
    orb = table["algorithm"] == "orbslam2_rgbd"
    full = compare_table(table, durations)
    one_seq = compare_table(table[~(orb & (table["trial"] == 3) & (table["seq"] == 1))], durations)
    whole = compare_table(table[~(orb & (table["trial"] == 3))], durations)
    # a lost sequence of trial 3 lowers the score; losing every sequence of it lowers it further
    assert _value(one_seq, "orbslam2_rgbd") < _value(full, "orbslam2_rgbd")
    assert _value(whole, "orbslam2_rgbd") < _value(one_seq, "orbslam2_rgbd")
    mean3 = table[orb & (table["trial"] != 3)].groupby("seq")["cr"].mean() * 2 / 3  # trial 3: CR 0
    w = durations.set_index(["scene", "seq"]).loc["home", "gt_duration"]
    assert _value(whole, "orbslam2_rgbd") == pytest.approx(float((mean3 * w).sum() / w.sum()), abs=1e-9)
    assert full.lacking == () and full.exit_status == 0
    assert whole.lacking == ("orbslam2_rgbd home trial(s) 3",) and whole.exit_status == 1
    assert one_seq.lacking == ("orbslam2_rgbd home trial(s) 3",) and one_seq.exit_status == 1
    said = [n for n in whole.notes if "no output at all of trial(s) 3 in home" in n]
    assert len(said) == 1 and said[0].startswith("orbslam2_rgbd has") and "3, as odom has in this scene" in said[0]
    row = whole.coverage.set_index("algorithm").loc["orbslam2_rgbd"]
    assert row["lost_trials"] == "3" and row["missing_trials"] == ""


def test_trial_numbers_are_labels_and_a_single_run_is_no_crash(runs):
    """0 to 2 against 1 to 3 lacks nothing; a single unnumbered run beside reruns gets no failed
    trials; within one algorithm, a trial another scene has is expected in every scene."""
    table, durations = runs
    orb = table["algorithm"] == "orbslam2_rgbd"
    # one algorithm alone (no peers): its trial 3 of another scene is expected here too
    two = pd.concat([table[orb], table[orb & (table["trial"] != 3)].assign(scene="other")], ignore_index=True)
    exp = pd.concat([durations, durations[durations["scene"] == "home"].assign(scene="other")], ignore_index=True)
    full, cover = complete(two, exp)
    assert len(full[(full["scene"] == "other") & (full["trial"] == 3)]) == (durations["scene"] == "home").sum()
    assert cover.set_index("scene").loc["other", "lost_trials"] == "3"
    shifted = table.assign(trial=np.where(orb, table["trial"] - 1, table["trial"]))
    assert compare_table(shifted, durations).lacking == ()
    single = table[~orb | (table["trial"] == 1)].assign(trial=lambda t: np.where(t["algorithm"] == "odom",
                                                                                 t["trial"], 0))  # fmt: skip
    res = compare_table(single, durations)
    assert res.lacking == () and _value(res, "orbslam2_rgbd") == pytest.approx(
        float(compare_table(table[orb & (table["trial"] == 1)].assign(trial=0), durations).algorithms["value"].iloc[0])
    )


def _one_run(runs, seqs, tie):
    table, durations = runs
    t = table[(table["trial"] == 1) & table["seq"].isin(seqs)].drop(columns=["trial"])
    odom = t[t["algorithm"] == "odom"].set_index("seq")
    for q in tie:  # orbslam2_rgbd made to repeat odom's values on these sequences
        at = (t["algorithm"] == "orbslam2_rgbd") & (t["seq"] == q)
        for c in ("cr", "cr_t", "cs_r", "ate_rmse", "matched", "c_matched", "correct_time", "track_time", "poses"):
            if c in t.columns:
                t.loc[at, c] = odom.loc[q, c]
    return compare_table(t, durations[durations["seq"].isin(seqs)])


@pytest.mark.parametrize(
    ("seqs", "tie", "said"),
    [
        (
            [1, 2],
            [1],
            "smallest possible p 1, above alpha 0.05: odom vs orbslam2_rgbd differ on 1 of the 2 sequence(s)",
        ),
        ([1, 2, 3], [1], "smallest possible p 0.5, above alpha 0.05: odom vs orbslam2_rgbd differ on 2 of the 3"),
        ([1, 2, 3], [1, 2], "smallest possible p 1, above alpha 0.05: odom vs orbslam2_rgbd differ on 1 of the 3"),
        ([1, 2, 3, 4], [], "smallest possible p 0.125, above alpha 0.05: odom vs orbslam2_rgbd differ on 4 of the 4"),
    ],
)
def test_why_no_pair_can_reach_alpha_is_told_from_the_facts(runs, seqs, tie, said):
    res = _one_run(runs, seqs, tie)
    assert f"no pair can reach alpha 0.05 in home ({said}" in res.summary, res.summary
    assert "the same on every sequence" not in res.summary
    if tie:
        assert f"{len(tie)} of them the same for both (a tie cannot move the test)" in res.summary
    assert res.summary.endswith(": run more trials (--power DELTA says how many)")


def test_identical_results_are_still_said_to_be_identical(runs):
    res = _one_run(runs, [1, 2, 3], [1, 2, 3])
    assert "every pair's results are the same on every sequence: no test can separate them (3 sequence(s)" in (
        res.summary
    )
    assert "run more trials" not in res.summary


def test_the_command_line_exits_1_for_a_trial_an_algorithm_lacks(icra20, tmp_path, capsys):
    """``lorisnb compare`` on folders of trials: an algorithm whose trial 3 folder is empty (a crashed
    run) is scored with that trial failed, said, and the command exits 1 (it exited 0)."""
    import shutil

    from lorisnb.cli import main

    homes = sorted((icra20 / "per-seq" / "odom").glob("home*.txt"))
    assert homes
    for alg in ("odom", "orbslam2_rgbd"):
        for k in (1, 2, 3):
            folder = tmp_path / "res" / alg / f"trial{k}"
            folder.mkdir(parents=True)
            if alg == "orbslam2_rgbd" and k == 3:
                continue  # the crashed run: its folder, no file
            for f in sorted((icra20 / "per-seq" / alg).glob("home*.txt")):
                shutil.copy(f, folder / f.name)
    rc = main(["compare", str(tmp_path / "res"), "--no-progress", "--jobs", "1"])
    err = capsys.readouterr().err
    assert rc == 1, err
    assert "orbslam2_rgbd has no output at all of trial(s) 3 in home" in err
    for f in sorted((icra20 / "per-seq" / "orbslam2_rgbd").glob("home*.txt")):  # the trial rerun: complete
        shutil.copy(f, tmp_path / "res" / "orbslam2_rgbd" / "trial3" / f.name)
    assert main(["compare", str(tmp_path / "res"), "--no-progress", "--jobs", "1"]) == 0, capsys.readouterr().err
