"""A table holding one sequence and trial in two rows is a damaged run when it is read
(:func:`lorisnb.tools.decisions.runs.load_run`), as NaN or a missing column are, so that "damaged"
means one thing for ``history``, ``diff --baseline last-comparable`` and ``report --baseline``: an
older night with a repeated row is passed over with a warning and the newest night judged (it was
found only when two runs were compared: history and diff exited 2, the newest night's lost
sequence never judged). The error names the file and the lines of the repeated rows, for a bare
table and for a report run's ``findings/sequences.csv`` (called "a report run without a
per-sequence CSV table"). A count, sequence or trial of inf, -inf or 1e400 is refused without
numpy's RuntimeWarning printed before the error."""

from __future__ import annotations

import json
import os
import warnings
from functools import partial

import pandas as pd
import pytest
from helpers import run_cli
from helpers import table_nights as nights

from lorisnb.errors import ParseError
from lorisnb.io.writers import write_csv
from lorisnb.tools.decisions.history import last_comparable, load_runs
from lorisnb.tools.decisions.runs import DURATIONS, FIRST_TABLE, load_run, read_table
from lorisnb.tools.report.baseline import since_baseline
from lorisnb.tools.report.provenance import KEYS

run = partial(run_cli, joined=True)


@pytest.fixture(scope="module")
def table(odom_sequences):
    return odom_sequences.copy()  # three odom files, as a results folder's evaluation names them


def repeated(table):
    """The table with its cafe-2 row (data row 1: line 3) written again at its end (line 5)."""
    assert list(table["seq"]) == [1, 2, 1] and list(table["scene"]) == ["cafe", "cafe", "home"]
    return pd.concat([table, table.iloc[[1]]], ignore_index=True)


def lost_home(table):
    return table[table["scene"] != "home"]


REPEATED = "odom cafe-2 (trial 0) has several rows (lines 3 and 5)"


def test_a_repeated_row_is_refused_when_the_table_is_read_naming_its_lines(tmp_path, table):
    good, bad = nights(tmp_path, table, repeated(table))
    assert len(load_run(good).table) == 3
    with pytest.raises(ParseError) as exc:
        load_run(bad)
    assert exc.value.path == str(bad) and exc.value.line == 5
    assert f"{bad}, line 5: {REPEATED}; a sweep of several settings" in str(exc.value)
    with pytest.raises(ParseError, match="lines 3 and 5"):
        read_table(bad)
    # the same row from two result files: both named, and how to tell their trials apart
    two = repeated(table)
    two.loc[3, "file"] = "odom2/cafe-1-2-odom.txt"
    write_csv(two, tmp_path / "two.csv")
    with pytest.raises(ParseError) as exc:
        load_run(tmp_path / "two.csv")
    assert ("odom cafe-2 (trial 0) (from the result files odom/cafe-1-2-odom.txt and odom2/cafe-1-2-odom.txt) has "
            "several rows (lines 3 and 5); two result files of one sequence and trial") in str(exc.value)  # fmt: skip
    assert "--trials-by" in str(exc.value)
    # a Parquet table: its rows, counted from 1
    pytest.importorskip("pyarrow")
    repeated(table).to_parquet(tmp_path / "bad.parquet", index=False)
    with pytest.raises(ParseError, match=r"odom cafe-2 \(trial 0\) has several rows \(rows 2 and 4 of the table"):
        load_run(tmp_path / "bad.parquet")


def test_history_passes_over_an_older_night_with_a_repeated_row(tmp_path, table, capsys):
    one, two, three = nights(tmp_path / "n", table, repeated(table), lost_home(table))
    rc, out, err = run(capsys, "history", one, two, three)
    assert rc == 1, err  # it exited 2, the error of 2.csv, the newest night's lost sequence unjudged
    assert f"warning: {two} passed over, a damaged run older than the newest: {two}, line 5: {REPEATED}" in err
    assert f"{three} is judged as the newest run" in err
    assert "newest run 3.csv against 1.csv: regression (1 sequence(s) regressed: odom home-1 missing)" in out
    passed: list[str] = []
    assert [r.path for r in load_runs([one, two, three], passed)] == [one, three]
    assert len(passed) == 1 and "lines 3 and 5" in passed[0]
    # the newest night damaged: still the error (exit 2), naming the file and the lines
    os.utime(two, (1.7e9 + 9000, 1.7e9 + 9000))
    rc, _, err = run(capsys, "history", one, two, three)
    assert rc == 2 and f"error: {two}, line 5: {REPEATED}" in err


def test_diff_last_comparable_passes_over_an_earlier_table_with_a_repeated_row(tmp_path, table, capsys):
    one, two = nights(tmp_path / "n", table, repeated(table))
    (cand,) = nights(tmp_path / "cand", table, table, lost_home(table))[2:]
    rc, out, err = run(capsys, "diff", tmp_path / "n", cand, "--baseline", "last-comparable", "--no-progress")
    assert rc == 1, err  # the damaged table was the baseline: exit 2, the regression never judged
    assert f"baseline: {one} (the newest of 1 earlier run(s) comparable with CAND" in err
    assert f"note: {tmp_path / 'n'}: 2.csv passed over, not read as an earlier run ({two}, line 5: {REPEATED}" in err
    assert "verdict: regression (1 sequence(s) regressed: odom home-1 missing)" in out
    base, fits = last_comparable(tmp_path / "n", load_run(cand))
    assert base.path == one and [r.path for r in fits] == [one]
    # CAND itself damaged: the error (exit 2)
    rc, _, err = run(capsys, "diff", tmp_path / "n", two, "--baseline", "last-comparable", "--no-progress")
    assert rc == 2 and f"error: {two}, line 5: {REPEATED}" in err


def report_run(folder, table, created):
    """A report run folder as lorisnb report writes it (findings and run.json), made at ``created``."""
    (folder / "findings").mkdir(parents=True)
    write_csv(table, folder / FIRST_TABLE)
    write_csv(table[["scene", "seq", "gt_duration"]].drop_duplicates(), folder / DURATIONS)
    values = {**json.loads(table["spec"].iloc[0]), "eps": "inf", "phi": "inf", "delta": 1.0, "tau": 60.0}
    meta = {k: None for k in KEYS} | {"command": ["lorisnb", "report"], "lorisnb_version": "0.3.0",
                                      "created": created, "inputs": {}, "notebooks": {},
                                      "spec": {"description": "d", "values": {**values, "source": "{results}"}}}  # fmt: skip
    (folder / "run.json").write_text(json.dumps(meta))
    return folder


def test_a_report_runs_table_with_a_repeated_row_is_named_and_passed_over(tmp_path, table, capsys):
    runs = tmp_path / "runs"
    good = report_run(runs / "r1", table, "2026-01-01T03:00:00+00:00")
    bad = report_run(runs / "r2", repeated(table), "2026-01-02T03:00:00+00:00")
    this = report_run(tmp_path / "r3", lost_home(table), "2026-01-03T03:00:00+00:00")
    own = bad / FIRST_TABLE
    with pytest.raises(ParseError) as exc:
        load_run(bad)
    assert exc.value.path == str(own) and exc.value.line == 5 and REPEATED in str(exc.value)
    rc, _, err = run(capsys, "diff", good, bad, "--no-progress")
    assert rc == 2 and f"error: {own}, line 5: {REPEATED}" in err
    assert "without a per-sequence CSV table" not in err  # the table is there
    # report --baseline's choice: the damaged night passed over, named, this run judged against r1
    out = since_baseline(this, runs)
    assert out["baseline"] == "r1" and out["verdict"]["verdict"] == "regression"
    assert {"run": "r2", "why": f"not read as a run: {own}, line 5: {REPEATED}"} in [
        {**p, "why": p["why"].split("; a sweep")[0]} for p in out["passed_over"]
    ]
    rc, out_text, err = run(capsys, "history", good, bad, this)
    assert rc == 1 and f"{bad} passed over, a damaged run older than the newest" in err
    assert "newest run r3 against r1: regression" in out_text


@pytest.mark.parametrize("column", ["matched", "seq", "trial"])
@pytest.mark.parametrize("value", ["inf", "-inf", "1e400"])
def test_an_infinite_count_is_refused_without_a_numpy_warning(tmp_path, table, capsys, column, value):
    t = table.assign(trial=0).astype({column: object})
    t.loc[1, column] = value
    good, bad = nights(tmp_path, table.assign(trial=0), t)
    words = {"matched": "a count", "seq": "a sequence number", "trial": "a trial number"}[column]
    shown = "-inf" if value == "-inf" else "inf"
    for args in (["diff", good, bad, "--no-progress"], ["history", good, bad]):
        rc, _, err = run(capsys, *args)
        assert rc == 2 and f"error: {bad}, line 3: column {column}: {shown} is not {words} (a whole number >= 0)" in err
        assert "RuntimeWarning" not in err and "warning" not in err
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no numpy warning from Python either: the error alone
        with pytest.raises(ParseError, match=f"column {column}: {shown} is not {words}"):
            load_run(bad)
