"""A scene value read back from a table ``lorisnb evaluate --csv`` wrote counts the scene's sequences
without a row as failed, as the evaluation of the results folder does: diff and history of the
tables and of the folders give the same scene CR (the table held only its sequences: 0.9996 against
0.6120 for the same results). Only where the table's ground-truth durations are the data root's."""

from __future__ import annotations

import shutil

import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.tools.decisions.diff import diff_tables
from lorisnb.tools.decisions.runs import load_run

ORB = "cafe_1_1_orbslam2-original.txt"


@pytest.fixture
def one_of_two(tmp_path, data, icra20, monkeypatch):
    """A results folder holding cafe's first sequence only (cafe has two), evaluated, and its CSV."""
    monkeypatch.setenv("LORISNB_DATA", str(data.root))
    (tmp_path / "res" / "orb").mkdir(parents=True)
    shutil.copy(icra20 / "per-seq" / "orbslam2_rgbd" / ORB, tmp_path / "res" / "orb" / ORB)
    ev = ln.evaluate(tmp_path / "res", progress=False, jobs=1)
    assert main(["evaluate", str(tmp_path / "res"), "--csv", str(tmp_path / "t.csv"), "--no-progress"]) == 0
    return ev, tmp_path / "t.csv"


def scene_cr(diff) -> float:
    s = diff.scenes
    return float(s.loc[(s["scene"] == "cafe") & (s["metric"] == "cr"), "base"].iloc[0])


def test_a_tables_scene_value_counts_the_sequences_it_lacks_as_the_folders_does(one_of_two):
    ev, csv = one_of_two
    folder = scene_cr(diff_tables(ev.sequences(), ev.sequences(), expected=ev.durations()))
    run = load_run(csv)
    assert run.expected is not None and sorted(run.expected["seq"]) == [1, 2] and run.notes == []
    table = scene_cr(diff_tables(run.table, run.table, expected=run.expected))
    alone = scene_cr(diff_tables(run.table, run.table))  # as before: the table's one sequence only
    cr1 = float(ev.sequences()["cr"].iloc[0])
    assert table == pytest.approx(folder, abs=1e-12) and folder < cr1 and alone == pytest.approx(cr1, abs=1e-12)


def test_a_table_whose_durations_are_not_the_data_roots_is_read_alone_with_a_note(one_of_two, tmp_path):
    _, csv = one_of_two
    t = pd.read_csv(csv)
    t["gt_duration"] = t["gt_duration"] + 1.0  # a pair's scene named cafe: another ground truth
    other = tmp_path / "pair.csv"
    t.to_csv(other, index=False)
    run = load_run(other)
    assert run.expected is None and "not those of the data root" in run.notes[0]


def test_without_the_ground_truth_a_table_is_read_alone_with_a_note(one_of_two, tmp_path, monkeypatch):
    _, csv = one_of_two
    empty = tmp_path / "nowhere"
    empty.mkdir()
    monkeypatch.setenv("LORISNB_DATA", str(empty))
    run = load_run(csv)
    assert run.expected is None and "set LORISNB_DATA" in run.notes[0]


def test_history_of_the_tables_writes_the_scene_cr_of_the_folders_evaluation(one_of_two, tmp_path, capsys):
    ev, csv = one_of_two
    shutil.copy(csv, tmp_path / "t2.csv")
    rc = main(["history", str(csv), str(tmp_path / "t2.csv"), "--csv", str(tmp_path / "h.csv")])
    capsys.readouterr()
    h = pd.read_csv(tmp_path / "h.csv")
    written = h.loc[(h["scene"] == "cafe") & (h["metric"] == "cr"), "value"].to_numpy()
    folder = scene_cr(diff_tables(ev.sequences(), ev.sequences(), expected=ev.durations()))
    assert rc == 0 and len(written) == 2 and written == pytest.approx([folder, folder], abs=1e-12)


def test_a_verdict_carried_by_scene_values_alone_says_so(one_of_two, tmp_path, capsys):
    """A scene's CR falls while its sequence stays within its own (wider) rerun band: the verdict
    line says no sequence regressed and how many scene values did, not '(0 sequence(s) regressed)'."""
    from lorisnb.core.stats.regression import regressed_phrase

    _, csv = one_of_two
    assert regressed_phrase({"verdict": "ok", "regressed_sequences": 0, "scene_counts": {}}) == ""
    v = {"verdict": "regression", "regressed_sequences": 0, "scene_counts": {"regression": 2}}
    assert regressed_phrase(v) == "no sequence regressed; 2 scene value(s) did"
    assert regressed_phrase({**v, "regressed_sequences": 3}) == "3 sequence(s) regressed"
    t = pd.read_csv(csv)
    worse = t.assign(cr=t["cr"] * 0.35, correct_time=t["correct_time"] * 0.35)
    worse.to_csv(tmp_path / "worse.csv", index=False)
    rc = main(["diff", str(csv), str(tmp_path / "worse.csv")])
    out = capsys.readouterr().out
    line = [x for x in out.splitlines() if x.startswith("verdict:")][0]
    assert rc == 1 and line.startswith("verdict: regression (no sequence regressed; "), out
    assert "scene value(s) did: " in line and " (scene) cr" in line, line  # which ones, not only how many


def test_history_says_when_two_runs_have_the_same_time(one_of_two, tmp_path, capsys):
    """Tables copied by a CI download share one modification time: their order is the order given,
    and the newest run's baseline (the exit status) hangs on it, so history says so."""
    import os

    _, csv = one_of_two
    for name in ("a", "b"):
        (tmp_path / name).mkdir()
        shutil.copy(csv, tmp_path / name / "s.csv")
        os.utime(tmp_path / name / "s.csv", (1767225600, 1767225600))
    rc = main(["history", str(tmp_path / "a" / "s.csv"), str(tmp_path / "b" / "s.csv")])
    err = capsys.readouterr().err
    assert rc == 0 and f"{tmp_path / 'b' / 's.csv'} has the same time as {tmp_path / 'a' / 's.csv'}" in err, err
    os.utime(tmp_path / "b" / "s.csv", (1767225700, 1767225700))
    rc = main(["history", str(tmp_path / "a" / "s.csv"), str(tmp_path / "b" / "s.csv")])
    assert rc == 0 and "same time" not in capsys.readouterr().err
