"""The nightly gate as a CI job runs it for months (``history`` over a folder of nightly runs,
``diff --baseline last-comparable``): the newest run is the one the exit status judges, so runs of
one time (a download or copy resets modification times) keep the order given (they were sorted by
name: ``night-10`` before ``night-9``, and a regression the night it landed read as an
improvement, exit 0); a newest run with no comparable baseline (another spec, lorisnb version or
ground truth, or the only run) is judged by nothing and exits 2, never 0; inputs a report run could
not score fail ``history`` as they fail ``diff`` of the same two runs (exit 1); a copy of tonight's
run kept with the earlier runs is never its own baseline."""

from __future__ import annotations

import json
import os

import numpy as np
import pandas as pd
import pytest
from helpers import run_cli as run

from lorisnb.io.writers import write_csv
from lorisnb.tools.decisions.diff import same_values
from lorisnb.tools.decisions.history import (
    drift,
    drift_gates,
    history_table,
    last_comparable,
    load_runs,
    natural,
    newest_verdict,
)
from lorisnb.tools.decisions.runs import DURATIONS, FIRST_TABLE, load_run
from lorisnb.tools.report.provenance import KEYS

LOST = "odom/home-1-1-odom.txt"


@pytest.fixture(scope="module")
def table(odom_sequences):
    return odom_sequences.copy()  # three odom files, as a results folder's evaluation names them


def night(folder, table, created, unscored=()):
    """A report run as lorisnb report writes it, made at ``created``, with ``unscored`` inputs in its
    ``findings/input_errors.csv``."""
    (folder / "findings").mkdir(parents=True)
    write_csv(table, folder / FIRST_TABLE)
    write_csv(table[["scene", "seq", "gt_duration"]], folder / DURATIONS)
    if unscored:
        rows = "".join(f"{f},failed,could not read\n" for f in unscored)
        (folder / "findings" / "input_errors.csv").write_text("file,status,error\n" + rows)
    values = {**json.loads(table["spec"].iloc[0]), "eps": "inf", "phi": "inf", "delta": 1.0, "tau": 60.0}
    meta = {k: None for k in KEYS} | {"command": ["lorisnb", "report"], "lorisnb_version": "0.3.0", "created": created,
                                      "inputs": {}, "notebooks": {},
                                      "spec": {"description": "d", "values": {**values, "source": "{results}"}}}  # fmt: skip
    (folder / "run.json").write_text(json.dumps(meta))
    return folder


def test_runs_of_one_time_keep_the_order_given(tmp_path, table, capsys):
    nights = tmp_path / "nightly"
    nights.mkdir()
    write_csv(table, nights / "night-9.csv")
    write_csv(table[table["scene"] != "home"], nights / "night-10.csv")  # tonight lost home-1
    for f in nights.iterdir():
        os.utime(f, (1.7e9, 1.7e9))  # a download: one modification time
    given = [nights / "night-9.csv", nights / "night-10.csv"]
    assert [r.name for r in load_runs(given)] == ["night-9.csv", "night-10.csv"]  # was night-10 first (by name)
    for order in (given, given[::-1], sorted(given)):  # as given, reversed, a shell's night-*.csv (night-10 first)
        rc, out, err = run(capsys, "history", *order, "--metric", "cr")
        assert rc == 1 and "newest run night-10.csv against night-9.csv: regression" in out, out
        assert "ordered after it by name, numbers as numbers" in err
    # a folder has no order given: by name, numbers as numbers (night-9 before night-10)
    assert sorted(["night-10.csv", "night-9.csv", "night-1.csv"], key=natural) == [
        "night-1.csv", "night-9.csv", "night-10.csv"]  # fmt: skip
    cand = tmp_path / "tonight.csv"
    write_csv(table, cand)
    rc, out, err = run(capsys, "diff", nights, cand, "--baseline", "last-comparable")
    assert "baseline: " in err and "night-10.csv" in err  # the newest of the folder: night-10, not night-9


def test_a_newest_run_without_baseline_is_never_a_pass(tmp_path, table, capsys):
    a = night(tmp_path / "a", table, "2026-11-01T02:00:00+00:00")
    b = night(tmp_path / "b", table, "2026-11-02T02:00:00+00:00")
    meta = json.loads((b / "run.json").read_text())
    meta["lorisnb_version"] = "0.4.0"  # tonight's lorisnb was upgraded: no earlier run is comparable
    (b / "run.json").write_text(json.dumps(meta))
    rc, out, _ = run(capsys, "history", a, b)
    assert rc == 2 and "newest run b: no earlier run is comparable with it: not with a (lorisnb_version" in out
    assert "nothing judged" in out
    rc, out, _ = run(capsys, "history", a)
    assert rc == 2 and "newest run a: the only run given; nothing judged" in out
    runs = load_runs([a, b])
    _, diffs = history_table(runs, ["cr"])
    assert newest_verdict(runs, diffs)[0] == 2 and newest_verdict(runs[:1], {})[0] == 2
    assert newest_verdict(load_runs([a, night(tmp_path / "c", table, "2026-11-03T02:00:00+00:00")]),
                          history_table(load_runs([a, tmp_path / "c"]), ["cr"])[1])[0] == 0  # fmt: skip


def test_inputs_not_scored_fail_history_as_they_fail_diff(tmp_path, table, capsys):
    kept = table[table["scene"] != "home"]  # home-1 failed to read, both nights: no row on either side
    a = night(tmp_path / "a", kept, "2026-11-01T02:00:00+00:00", [LOST])
    b = night(tmp_path / "b", kept, "2026-11-02T02:00:00+00:00", [LOST])
    rc, _, err = run(capsys, "diff", a, b)
    assert rc == 1
    rc, out, err = run(capsys, "history", a, b)  # was 0: "newest run b against a: ok", the failed input unsaid
    assert rc == 1 and "newest run b against a: incomplete (2 input(s) not scored" in out
    assert f"1 input(s) of b could not be evaluated or were not scored ({LOST})" in err
    runs = load_runs([a, b])
    rc, lines = newest_verdict(runs, history_table(runs, ["cr"])[1])
    assert rc == 1 and any(LOST in x for x in lines)
    # a sequence BASE scored and CAND could not: "failed", with the reason, as diff says it
    c = night(tmp_path / "c", kept, "2026-11-03T02:00:00+00:00", [LOST])
    h, diffs = history_table(load_runs([night(tmp_path / "d", table, "2026-10-31T02:00:00+00:00"), c]), ["cr"])
    seqs = diffs[1].sequences
    assert set(seqs.loc[seqs["scene"] == "home", "status"]) == {"failed"}


def test_a_copy_of_tonight_kept_with_the_earlier_runs_is_not_its_baseline(tmp_path, table, capsys):
    nights = tmp_path / "nightly"
    nights.mkdir()
    write_csv(table, nights / "2026-11-01.csv")
    os.utime(nights / "2026-11-01.csv", (1.7e9, 1.7e9))
    cand = tmp_path / "tonight.csv"
    write_csv(table[table["scene"] != "home"], cand)  # tonight lost home-1
    os.utime(cand, (1.7e9 + 100, 1.7e9 + 100))
    copy = nights / "2026-11-02.csv"
    copy.write_bytes(cand.read_bytes())  # archived before the gate ran (or a job run again): a newer copy
    rc, out, err = run(capsys, "diff", nights, cand, "--baseline", "last-comparable")
    assert rc == 1 and "2026-11-01.csv" in err and "passed over: 2026-11-02.csv" in err, err  # was 0 against itself
    base, fits = last_comparable(nights, load_run(cand))
    assert base.name == "2026-11-01.csv" and [r.name for r in fits] == ["2026-11-01.csv"]
    os.utime(copy, (1.7e9 + 100, 1.7e9 + 100))  # a copy keeping its time: made at CAND's time, passed over too
    rc, out, err = run(capsys, "diff", nights, cand, "--baseline", "last-comparable")
    assert rc == 1 and "passed over: 2026-11-02.csv" in err
    os.utime(copy, (1.7e9 + 50, 1.7e9 + 50))  # an earlier run with every value of CAND: compared, and said
    rc, out, err = run(capsys, "diff", nights, cand, "--baseline", "last-comparable")
    assert rc == 0 and "holds every value of CAND" in err
    assert same_values(load_run(copy).table, load_run(cand).table)
    assert not same_values(load_run(nights / "2026-11-01.csv").table, load_run(cand).table)
    rc, _, err = run(capsys, "diff", cand, cand)  # a run against itself, given so: no note
    assert rc == 0 and "holds every value" not in err


def test_every_output_of_diff_says_what_its_exit_status_says(tmp_path, table, capsys):
    """Inputs not scored and nothing regressed: diff exits 1, and its JSON, JUnit XML, Markdown,
    annotations and badge said "ok" (a green badge, no failed test case)."""
    import xml.etree.ElementTree as ET

    from lorisnb.tools.decisions.diff import badge, diff_tables, github_annotations, markdown, with_unscored

    kept = table[table["scene"] != "home"]
    a = night(tmp_path / "a", kept, "2026-11-01T02:00:00+00:00", [LOST])
    b = night(tmp_path / "b", kept, "2026-11-02T02:00:00+00:00", [LOST])
    o = tmp_path / "out"
    rc, out, err = run(capsys, "diff", a, b, "--json", o / "d.json", "--junit", o / "d.xml", "--markdown",
                       o / "d.md", "--badge", o / "d.svg", "--annotations")  # fmt: skip
    assert rc == 1 and "verdict: incomplete (2 input(s) not scored" in out
    v = json.loads((o / "d.json").read_text())
    assert v["verdict"] == "incomplete" and v["exit_status"] == 1 and v["unscored_inputs"]["cand"] == [LOST]
    suite = ET.parse(o / "d.xml").getroot().find("testsuite")
    assert suite.get("errors") == "2" and [e.get("type") for e in suite.iter("error")] == ["not scored"] * 2
    assert (o / "d.md").read_text().startswith("## ⚠️ lorisnb diff: incomplete") and LOST in (o / "d.md").read_text()
    assert ">incomplete (2 not scored)<" in (o / "d.svg").read_text() and "::error title=" in out
    # the same in Python; nothing lost: as before
    d = diff_tables(load_run(a).table, load_run(b).table)
    assert d.verdict["verdict"] == "ok" and with_unscored(d, [], []) is d and ">ok<" in badge(d)
    lost = with_unscored(d, [], [LOST])
    assert lost.verdict["verdict"] == "incomplete" and not lost.regressed
    assert any(LOST in x for x in github_annotations(lost)) and "⚠️" in markdown(lost, "a", "b")
    rc, out, _ = run(capsys, "diff", a, a, "--json", o / "same.json")  # a run against itself: its inputs still lost
    assert rc == 1 and json.loads((o / "same.json").read_text())["verdict"] == "incomplete"


def _trials(table, rng, drop=0.0):
    """Three reruns of ``table``: CR (and CR-T) and ATE each moved by rerun-sized noise, cafe-1's CR
    lowered by ``drop``."""
    parts = []
    for trial in (1, 2, 3):
        t = table.copy()
        cafe1 = ((t["scene"] == "cafe") & (t["seq"] == 1)).to_numpy()
        for c in ("cr", "cr_t"):
            t[c] = (t[c] + rng.normal(0, 0.02, len(t)) - drop * cafe1).clip(0, 1)
        for c in ("ate_rmse", "c_ate_rmse", "aoe_rmse", "c_aoe_rmse"):
            t[c] = t[c] * np.exp(rng.normal(0, 0.15, len(t)))
        t["correct_time"] = t["cr"] * t["gt_duration"]
        parts.append(t.assign(trial=trial))
    return pd.concat(parts, ignore_index=True)


def test_a_slow_drift_is_named_against_the_first_run_of_its_series(tmp_path, table, capsys):
    """Each night's CR of one sequence 0.03 below the night before, within rerun noise night to
    night (history said nothing): against the series' first run the newest run regressed, and
    history names the drift with the diff that gates on it, on every night from the fourth. The
    night's exit status stays the night's own: gating on a drift failed twice as many noise-only
    nights (one lucky first night fails the nights after it; docs/guide/history.md)."""
    rng = np.random.default_rng(0)
    nights = []
    for k in range(8):
        f = tmp_path / f"night-{k}.csv"
        write_csv(_trials(table, rng, 0.03 * k), f)
        os.utime(f, (1.7e9 + 100 * k, 1.7e9 + 100 * k))
        nights.append(f)
    runs = load_runs(nights)
    _, diffs = history_table(runs, ["cr"])
    assert not any(d.regressed for d in diffs.values())  # night to night: within noise
    first, since = drift(runs)
    assert first == 0 and since.regressed and drift_gates(since) == []
    rc, out, _ = run(capsys, "history", *nights, "--metric", "cr")
    assert rc == 0 and "newest run night-7.csv against night-6.csv: ok" in out
    assert (
        "against night-0.csv, the first run of its series: regression (1 sequence(s) regressed: odom cafe-1 cr" in out
    )
    assert "a drift of values, which does not fail the night by itself (the night passes: exit 0)" in out
    assert "lorisnb diff night-0.csv night-7.csv" in out
    assert run(capsys, "diff", nights[0], nights[-1])[0] == 1  # the gate it names fails
    assert drift(runs[:2]) is None  # the first run is the baseline: nothing more
    rc, out, _ = run(capsys, "history", *nights[5:], "--metric", "cr")  # a series started later
    assert rc == 0 and "the first run of its series: ok" in out


def test_a_sequence_lost_and_left_lost_fails_every_night(tmp_path, table, capsys):
    """A sequence lost on night 1 failed night 1 only: night 2, whose baseline (night 1) had lost it
    too, exited 0 with the sequence still missing. Against the series' first run it is missing."""
    nights = []
    for k, t in enumerate((table, table[table["scene"] != "home"], table[table["scene"] != "home"])):
        f = tmp_path / f"night-{k}.csv"
        write_csv(t, f)
        os.utime(f, (1.7e9 + 100 * k, 1.7e9 + 100 * k))
        nights.append(f)
    rc, out, _ = run(capsys, "history", *nights, "--metric", "cr")
    assert rc == 1 and "newest run night-2.csv against night-1.csv: ok" in out
    assert (
        "against night-0.csv, the first run of its series: regression (1 sequence(s) regressed: odom home-1 missing)"
        in out
    )


def test_a_sequence_added_later_and_lost_fails_every_night(tmp_path, table, capsys):
    """An algorithm added on night 1 and lost on night 3 failed night 3 only: night 4, whose baseline
    had lost it too and whose series' first run never had it, exited 0. Any sequence an earlier run of
    the series had is gated, named with the night it was last seen; the listing calls a value absent in
    both nights no change (it read "nan -> no value", a change)."""
    both = pd.concat([table, table.assign(algorithm="odom2")], ignore_index=True)
    nights = []
    for k, t in enumerate((table, both, both, table, table)):
        f = tmp_path / f"night-{k}.csv"
        write_csv(t, f)
        os.utime(f, (1.7e9 + 100 * k, 1.7e9 + 100 * k))
        nights.append(f)
    rc, out, _ = run(capsys, "history", *nights[:4], "--metric", "cr")
    assert rc == 1 and "newest run night-3.csv against night-2.csv: regression" in out
    rc, out, _ = run(capsys, "history", *nights, "--metric", "cr")
    assert rc == 1 and "newest run night-4.csv against night-3.csv: ok" in out
    assert "3 sequence(s) an earlier run of its series had are lost" in out
    assert "odom2 cafe-1 missing (last seen in night-2.csv)" in out and "odom2 home-1 missing" in out
    assert "change in night-4.csv" not in out and "nan -> no value" not in out
    assert "first change in night-3.csv against night-2.csv" in out
    runs = load_runs(nights)
    h, diffs = history_table(runs, ["cr"])
    assert newest_verdict(runs, diffs)[0] == 1
    back = tmp_path / "night-5.csv"  # back again: nothing lost
    write_csv(both, back)
    os.utime(back, (1.7e9 + 500, 1.7e9 + 500))
    rc, out, _ = run(capsys, "history", *nights, back, "--metric", "cr")
    assert rc == 0 and "are lost" not in out


def test_a_drift_of_single_runs_is_named_not_gated(tmp_path, table, capsys):
    """With one run a side too a drift is named, with how to gate on it, and the night's exit
    status is the night's own."""
    nights = []
    for k, drop in enumerate((0.0, 0.15, 0.3, 0.45, 0.6)):
        t = table.copy()
        cafe = (t["scene"] == "cafe").to_numpy()
        for c in ("cr", "cr_t"):
            t[c] = (t[c] - drop * cafe).clip(0, 1)
        t["correct_time"] = t["cr"] * t["gt_duration"]
        f = tmp_path / f"night-{k}.csv"
        write_csv(t, f)
        os.utime(f, (1.7e9 + 100 * k, 1.7e9 + 100 * k))
        nights.append(f)
    rc, out, _ = run(capsys, "history", *nights, "--metric", "cr")
    assert "newest run night-4.csv against night-3.csv: ok" in out
    assert "the first run of its series: regression" in out and "does not fail the night by itself" in out
    assert "lorisnb diff night-0.csv night-4.csv" in out and rc == 0


def test_a_table_without_a_version_is_comparable_with_report_runs(tmp_path, table, capsys):
    """``diff --baseline last-comparable nightly tonight.csv``: a table (``evaluate --csv``) says no
    lorisnb version, and history counted 0.3.0 -> None as a difference, so no night was ever
    comparable (exit 2), where diff of the same two judged them (exit 0)."""
    folder = tmp_path / "nightly"
    night(folder / "n1", table, "2026-11-01T02:00:00+00:00")
    night(folder / "n2", table, "2026-11-02T02:00:00+00:00")
    tonight = tmp_path / "tonight.csv"
    write_csv(table, tonight)
    rc, out, err = run(capsys, "diff", "--baseline", "last-comparable", folder, tonight)
    assert rc == 0, err
    # what was checked, not "same spec, lorisnb version and ground truth": a table records neither
    assert "checked: the spec and thresholds their tables record; not checked: lorisnb version and ground-truth" in err
    rc, _, err = run(capsys, "history", folder / "n1", folder / "n2", tonight)
    assert rc == 0, err


def test_tables_ordered_by_modification_time_against_the_dates_in_their_names(tmp_path, table, capsys):
    """Bare tables named with ISO dates whose modification times say another order (a copy or a
    download): history orders them by time as before, and warns naming the contradiction and the
    run taken as the newest (it said nothing, and judged 2026-01-01 as the newest night)."""
    nights = []
    for k in range(3):
        f = tmp_path / f"2026-01-0{k + 1}.csv"
        write_csv(table, f)
        os.utime(f, (1.7e9 - 100 * k, 1.7e9 - 100 * k))  # the later the date, the older the file
        nights.append(f)
    rc, out, err = run(capsys, "history", *nights, "--metric", "cr")
    assert "warning: runs ordered by modification time contradict the dates in their names" in err, err
    assert (
        "2026-01-03.csv (named 2026-01-03) is ordered before 2026-01-02.csv (named 2026-01-02) (2 such"
        in err.replace("\n", " ")
    )
    assert "so 2026-01-01.csv is taken as the newest run" in err.replace("\n", " ")
    for k, f in enumerate(nights):
        os.utime(f, (1.7e9 + 100 * k, 1.7e9 + 100 * k))
    rc, out, err = run(capsys, "history", *nights, "--metric", "cr")
    assert "contradict" not in err, err


def test_a_file_in_the_nightly_folder_that_is_no_run_is_passed_over_and_named(tmp_path, table, capsys):
    """``history --csv nightly/h.csv`` (or a damaged night) left in the folder the nightly runs are
    kept in made every later ``diff --baseline last-comparable`` and ``report --baseline`` refuse
    the folder (exit 2, every night after): it is passed over now, named with why."""
    folder = tmp_path / "nightly"
    night(folder / "n1", table, "2026-11-01T02:00:00+00:00")
    night(folder / "n2", table, "2026-11-02T02:00:00+00:00")
    rc, _, err = run(capsys, "history", folder / "n1", folder / "n2", "--csv", folder / "h.csv")
    assert rc == 0 and (folder / "h.csv").is_file(), err
    (folder / "broken.csv").write_text("algorithm,scene\nx\n")
    tonight = tmp_path / "tonight.csv"
    write_csv(table[table["scene"] != "home"], tonight)  # tonight lost home-1: judged against n2
    rc, out, err = run(capsys, "diff", "--baseline", "last-comparable", folder, tonight)
    assert rc == 1 and "baseline: " in err and "n2" in err, err
    assert "h.csv passed over, not read as an earlier run" in err and "lacks column(s)" in err
    assert "broken.csv passed over" in err and "line 2" in err
    for p in folder.glob("n*"):  # nothing but such files: refused, naming them
        import shutil

        shutil.rmtree(p)
    rc, _, err = run(capsys, "diff", "--baseline", "last-comparable", folder, tonight)
    assert rc == 2 and "holds no run folder" in err and "h.csv" in err and "broken.csv" in err, err


def test_a_drift_line_says_what_the_night_exits_with(tmp_path, table, capsys):
    """A drift named on a night that fails on its own verdict (a regression against its baseline):
    the drift's line said "named, not failing the night" while the night exited 1; it says the
    drift does not fail the night by itself and that the night exits 1 for its other findings, and
    both verdict lines name the sequence that regressed by the test (they named lost ones only)."""
    rng = np.random.default_rng(0)
    nights = []
    for k, drop in enumerate([0.0, 0.03, 0.06, 0.09, 0.5]):  # tonight cafe-1 falls by 0.41 more
        f = tmp_path / f"night-{k}.csv"
        write_csv(_trials(table, rng, drop), f)
        os.utime(f, (1.7e9 + 100 * k, 1.7e9 + 100 * k))
        nights.append(f)
    rc, out, _ = run(capsys, "history", *nights, "--metric", "cr")
    assert (
        rc == 1
        and "newest run night-4.csv against night-3.csv: regression (1 sequence(s) regressed: odom cafe-1 cr" in out
    )
    line = next(x for x in out.splitlines() if "the first run of its series" in x)
    assert line.startswith("newest run night-4.csv against night-0.csv, the first run of its series: regression "
                           "(1 sequence(s) regressed: odom cafe-1 cr"), line  # fmt: skip
    assert "does not fail the night by itself (the night exits 1 for its other findings here)" in line, line
    assert "not failing the night" not in out
