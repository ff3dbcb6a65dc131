"""The seventh pass's evidence rules of ``lorisnb diff`` (issue s67): a side of one independent
value claims no significance whatever the other holds (1 BASE run against 3 CAND trials failed
12.5 % of noise-only nights by a t-test of CAND's spread alone), a CAND trial that is one of BASE's
own trial files is no run of CAND, and a scene's copies are told by the rule of a sequence's
(1e-4 relative), not by exact equality. Real data: the bundled icra20 results, evaluated."""

from __future__ import annotations

import json

import pandas as pd
import pytest
from helpers import longest_tracked, rerun_trials

from lorisnb.cli import main
from lorisnb.core.stats.regression import changes
from lorisnb.tools.decisions.diff import diff_tables

ALG = "orbslam2_rgbd"


@pytest.fixture(scope="module")
def table(paper_sequences):
    return paper_sequences.copy()


def _here(t: pd.DataFrame, where: tuple[str, int]) -> pd.Series:
    return (t["algorithm"] == ALG) & (t["scene"] == where[0]) & (t["seq"] == where[1])


def _row(seqs: pd.DataFrame, where: tuple[str, int], metric: str) -> pd.Series:
    return seqs[_here(seqs, where) & (seqs["metric"] == metric)].iloc[0]


def _diff_json(tmp_path, capsys, base: pd.DataFrame, cand: pd.DataFrame) -> tuple[int, dict]:
    b, c, out = tmp_path / "base.csv", tmp_path / "cand.csv", tmp_path / "v.json"
    base.to_csv(b, index=False)
    cand.to_csv(c, index=False)
    rc = main(["diff", str(b), str(c), "--no-progress", "--json", str(out)])
    capsys.readouterr()
    return rc, json.loads(out.read_text())


def test_one_base_run_against_tied_cand_trials_claims_no_significance(table, tmp_path, capsys):
    """BASE a single run, CAND three trials whose CR of a sequence is tied (a sequence whose reruns
    flip between two values: vins corridor-4, 0.74 against 0, 0, 0): the t-test took CAND's spread
    of 0 alone and called it a regression (p_adj 0.002). A side of one value is judged as single
    runs are, by the rerun band: no significance claimed; so is 3 BASE trials against CAND's three
    near-identical copies of one run (tested on 3 vs 1 values)."""
    where = longest_tracked(table, ALG)
    base = table.assign(trial=0)
    cand = rerun_trials(table, (1, 2, 3), 5)
    cand.loc[_here(cand, where), "cr"] = float(table.loc[_here(table, where), "cr"].iloc[0]) - 0.4  # tied
    seqs = changes(base, cand)[0]
    row = _row(seqs, where, "cr")
    assert row["status"] == "ok", row["decided_by"]
    assert row["decided_by"].startswith("a single run on one side (1 vs 3 trials): no significance claimed")
    assert not (seqs["decided_by"].str.startswith("t-test")).any()
    rc, v = _diff_json(tmp_path, capsys, base, cand)
    assert rc == 0 and v["verdict"] == "ok"
    # three reruns against three near-identical copies of one run: 3 vs 1 values, no t-test either
    copies = pd.concat([cand[cand["trial"] == 1].assign(trial=k, cr=lambda t, k=k: t["cr"] * (1 + 1e-4 * k))
                        for k in (1, 2, 3)], ignore_index=True)  # fmt: skip
    seqs = changes(rerun_trials(table, (1, 2, 3), 6), copies)[0]
    row = _row(seqs, where, "cr")
    assert "tested on 3 vs 1 values" in row["decided_by"] and row["decided_by"].startswith("a single run on one side")
    # two values a side or more: the t-test, as before
    two = changes(rerun_trials(table, (1, 2), 7), rerun_trials(table, (1, 2, 3), 8))[0]
    assert _row(two, where, "cr")["decided_by"].startswith("t-test of the change beyond the tolerance (2 vs 3 trials")


def test_a_cand_padded_with_base_trial_files_is_named_and_fails(table, tmp_path, capsys):
    """CAND's trial 4 a real regression (CR -0.3 on one sequence), its trials 5 and 6 BASE's own
    trials 1 and 2 (files copied over): copies were looked for within a side only, and the diff
    said ok. Each such trial is named ("CAND trial 5 repeats BASE trial 1's every value"), not
    counted as a CAND run, and CAND then holds fewer independent runs than BASE: a missing trial,
    as a copy within CAND is, at the command line too (exit 1)."""
    where = longest_tracked(table, ALG)
    base = rerun_trials(table, (1, 2, 3), 11)
    four = rerun_trials(table, (4,), 12)
    four.loc[_here(four, where), "cr"] -= 0.3
    cand = pd.concat([four, base[base["trial"] == 1].assign(trial=5), base[base["trial"] == 2].assign(trial=6)],
                     ignore_index=True)  # fmt: skip
    seqs, scenes = changes(base, cand)
    lost = seqs[seqs["metric"] == "trial"]
    with_output = int((table["matched"].to_numpy() > 0).sum())
    assert (
        len(lost) == with_output and (lost["status"] == "missing").all() and (lost["cand"] == "trial 5, 6 a copy").all()
    )
    assert lost["decided_by"].str.contains("CAND trial 5 repeats BASE trial 1's every value; CAND trial 6 repeats "
                                           "BASE trial 2's every value").all()  # fmt: skip
    cr = _row(seqs, where, "cr")
    assert "tested on 3 vs 1 values" in cr["decided_by"]
    assert "CAND trial 5 repeats BASE trial 1's every value: not counted" in cr["decided_by"]
    scene = scenes[(scenes["algorithm"] == ALG) & (scenes["scene"] == where[0]) & (scenes["metric"] == "cr")].iloc[0]
    assert "CAND trial 6 repeats BASE trial 2's every value: not counted" in scene["decided_by"]
    assert diff_tables(base, cand).regressed
    rc, v = _diff_json(tmp_path, capsys, base, cand)
    assert rc == 1 and v["verdict"] == "regression"
    # a run against itself is unchanged, no padding: nothing named missing
    same = changes(base, base.assign(trial=base["trial"] + 3))[0]
    assert not (same["metric"] == "trial").any() and not same["decided_by"].str.contains("repeats BASE").any()


def test_a_scene_counts_copies_by_the_rule_of_sequences(table):
    """BASE's trial 2 a copy of its trial 1 with every value moved by 1e-6 relative (a file
    rewritten with fewer digits): the sequences counted it once (1e-4 relative), the scene values
    twice (exact equality): "2 vs 3 values" beside "3 vs 3 trials". One rule at both levels now."""
    one = rerun_trials(table, (1,), 21)
    moved = one.assign(trial=2)
    for c in ("cr", "cr_t", "ate_rmse", "aoe_rmse", "c_ate_rmse", "c_aoe_rmse", "rpe_trans_rmse", "rpe_rot_rmse"):
        moved[c] = moved[c] * (1 + 1e-6)
    base = pd.concat([one, moved, rerun_trials(table, (3,), 22)], ignore_index=True)
    seqs, scenes = changes(base, rerun_trials(table, (1, 2, 3), 23))
    tested = scenes[scenes["decided_by"].str.startswith("t-test") & (scenes["algorithm"] == ALG)]  # odom: CR 0
    assert len(tested) and tested["decided_by"].str.contains("3 vs 3 trials, tested on 2 vs 3 values").all()
    assert tested["decided_by"].str.contains("1 of BASE's trials repeat another's every value: counted once").all()
    judged = seqs[seqs["decided_by"].str.startswith("t-test") & (seqs["cand"] > 0)]
    assert len(judged) and judged["decided_by"].str.contains("tested on 2 vs 3 values").all()
