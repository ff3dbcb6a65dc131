"""The order of nightly runs and the runs that cannot be read, as ``history`` and ``diff --baseline
last-comparable`` choose by them: dates in a run's folder name (``2026-02-01/sequences.csv``) or
written compactly (``20260105.csv``) that contradict the files' modification times are warned of,
by both commands (history looked at the file name alone, and diff said nothing); a damaged or
foreign older run is passed over, named, and the newest night judged (history exited 2 for it,
hiding the newest night's regression); a damaged newest night is still exit 2."""

from __future__ import annotations

import os
from datetime import date, time
from functools import partial

import pytest
from helpers import run_cli

import lorisnb as ln
from lorisnb.io.writers import write_csv
from lorisnb.tools.decisions.history import load_runs, name_dates
from lorisnb.tools.decisions.runs import load_run

run = partial(run_cli, joined=True)


@pytest.fixture(scope="module")
def table(odom_sequences):
    return odom_sequences.copy()  # three odom files, as a results folder's evaluation names them


def nights(folder, table, names, newest_first=True):
    """Tables at ``names`` (relative paths) under ``folder``, the later the name the older the file
    (a copy or a download) unless ``newest_first`` is False; the last one lost home-1."""
    paths = []
    for k, name in enumerate(names):
        f = folder / name
        f.parent.mkdir(parents=True, exist_ok=True)
        write_csv(table if k < len(names) - 1 else table[table["scene"] != "home"], f)
        t = 1.7e9 - 1000 * k if newest_first else 1.7e9 + 1000 * k
        os.utime(f, (t, t))
        paths.append(f)
    return paths


def test_dates_in_folder_names_and_compact_dates_are_read(tmp_path, table):
    folders = nights(tmp_path / "a", table, [f"2026-02-0{k}/sequences.csv" for k in (1, 2, 3)])
    assert name_dates([load_run(p) for p in folders]) == [(date(2026, 2, k), None) for k in (1, 2, 3)]
    compact = nights(tmp_path / "b", table, ["20260105.csv", "20260106T0300.csv", "nightly_2026-01-07T04:30.csv"])
    assert name_dates([load_run(p) for p in compact]) == [
        (date(2026, 1, 5), None), (date(2026, 1, 6), time(3, 0)), (date(2026, 1, 7), time(4, 30))]  # fmt: skip
    # 8 digits that form no date, a day-first date, and two different days in one name: no date
    other = nights(tmp_path / "c", table, ["12345678.csv", "05-01-2026.csv", "2026-01-05_vs_2026-01-04.csv"])
    assert name_dates([load_run(p) for p in other]) == [None, None, None]


@pytest.mark.parametrize(
    "names",
    [
        [f"2026-02-0{k}/sequences.csv" for k in (1, 2, 3)],  # the guide's own example: the date in the folder
        [f"2026010{k}.csv" for k in (1, 2, 3)],  # compact ISO 8601
    ],
)
def test_history_warns_of_names_against_modification_times(tmp_path, table, capsys, names):
    paths = nights(tmp_path / "nightly", table, names)
    rc, out, err = run(capsys, "history", *paths, "--metric", "cr")
    assert "warning: runs ordered by modification time contradict the dates in their names" in err, err
    first, second = names[2], names[1]
    assert f"{first} (named 2026-0" in err and f"is ordered before {second}" in err, err
    assert f"so {names[0]} is taken as the newest run" in err, err  # by time: the oldest name is the newest run
    for k, p in enumerate(paths):  # times in the names' order: nothing to warn of
        os.utime(p, (1.7e9 + 1000 * k, 1.7e9 + 1000 * k))
    rc, out, err = run(capsys, "history", *paths, "--metric", "cr")
    assert "contradict" not in err and rc == 1, err


def test_diff_last_comparable_warns_as_history_does(tmp_path, table, capsys):
    folder = tmp_path / "nightly"
    nights(folder, table, ["2026-01-04.csv", "2026-01-05.csv"])  # 2026-01-05 copied: older than 2026-01-04
    cand = tmp_path / "cand.csv"
    write_csv(table[table["scene"] != "home"], cand)
    rc, out, err = run(capsys, "diff", "--baseline", "last-comparable", folder, cand)
    assert "baseline: " in err and "2026-01-04.csv (the newest" in err, err
    assert ("warning: runs ordered by modification time contradict the dates in their names: 2026-01-05.csv "
            "(named 2026-01-05) is ordered before 2026-01-04.csv (named 2026-01-04), so 2026-01-04.csv is taken as "
            "the baseline") in err, err  # fmt: skip


def test_a_damaged_or_foreign_older_run_is_passed_over_and_the_newest_judged(tmp_path, table, capsys):
    folder = tmp_path / "nightly"
    paths = nights(folder, table, [f"2026-03-0{k}.csv" for k in (1, 2, 3, 4)], newest_first=False)
    text = paths[1].read_text().splitlines()
    head = text[0].split(",")
    row = text[2].split(",")
    row[head.index("cr")] = "nan"  # a damaged older night (line 3)
    paths[1].write_text("\n".join([*text[:2], ",".join(row), *text[3:]]) + "\n")
    os.utime(paths[1], (1.7e9 + 1000, 1.7e9 + 1000))
    rc, out, err = run(capsys, "history", *paths, "--metric", "cr")
    assert rc == 1, err  # was 2: "line 3: column cr: nan", hiding the newest night's lost home-1
    assert f"warning: {paths[1]} passed over, a damaged run older than the newest: {paths[1]}, line 3: column cr" in err
    assert "newest run 2026-03-04.csv against 2026-03-03.csv: regression" in out, out
    # history's own table kept in the folder, newer than every night: no run, passed over
    rc, _, err = run(capsys, "history", *paths[2:], "--metric", "cr", "--csv", folder / "h.csv")
    assert rc == 1 and (folder / "h.csv").is_file(), err
    rc, out, err = run(capsys, "history", *sorted(folder.iterdir()), "--metric", "cr")
    assert rc == 1 and f"warning: {folder / 'h.csv'} passed over, no run (not a per-sequence table" in err, err
    assert "newest run 2026-03-04.csv against 2026-03-03.csv: regression" in out, out
    # a damaged newest night: nothing to judge, exit 2 naming it
    paths[3].write_text(paths[1].read_text())
    os.utime(paths[3], (1.7e9 + 9000, 1.7e9 + 9000))
    rc, out, err = run(capsys, "history", *paths, "--metric", "cr")
    assert rc == 2 and f"{paths[3]}, line 3: column cr" in err, err
    # in Python, without a list to say it in, any run that cannot be read is the error, as before
    with pytest.raises(ln.errors.ParseError):
        load_runs(paths[:2])
