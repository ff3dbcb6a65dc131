"""``history`` never passes over tonight's night (exit 0 on yesterday's verdict): a result folder
given among the runs (``res/<algorithm>/*.txt``, which history does not evaluate) is refused, exit
2, saying what history reads and how to make a run of it; a path that is no run but newer than the
newest run read is refused too, except history's own outputs; damaged older nights are still passed
over with a warning."""

from __future__ import annotations

import os
import shutil
from functools import partial

import pytest
from helpers import run_cli
from helpers import table_nights as nights

from lorisnb.errors import ValidationError
from lorisnb.tools.decisions.history import load_runs

run = partial(run_cli, joined=True)

ODOM = ("cafe-1-1-odom.txt", "cafe-1-2-odom.txt", "home-1-1-odom.txt")  # as conftest.ODOM


@pytest.fixture(scope="module")
def table(odom_sequences):
    return odom_sequences.copy()


def results(folder, icra20, files=ODOM):
    (folder / "odom").mkdir(parents=True)
    for f in files:
        shutil.copy(icra20 / "per-seq" / "odom" / f, folder / "odom" / f)
    return folder


def test_a_result_folder_given_to_history_is_refused_not_passed_over(tmp_path, table, icra20, capsys):
    one, two = nights(tmp_path / "n", table, table)
    tonight = results(tmp_path / "tonight", icra20, ODOM[:2])  # lost home-1: never judged before
    rc, out, err = run(capsys, "history", one, two, tonight)
    assert rc == 2, err  # it was 0: "tonight passed over, no run", 2.csv judged as the newest
    assert "passed over" not in err and "newest run" not in out
    assert f"error: {tonight}: a result folder (2 result file(s), such as odom/" in err
    assert f"lorisnb evaluate {tonight} --csv" in err and "lorisnb report --results" in err
    assert "lorisnb diff" in err
    # wherever it is given, and in Python
    rc, _, err = run(capsys, "history", tonight, one, two)
    assert rc == 2 and "a result folder" in err
    with pytest.raises(ValidationError, match="a result folder"):
        load_runs([one, two, tonight], [])
    # a result file given alone is one too
    rc, _, err = run(capsys, "history", one, two, tonight / "odom" / ODOM[0])
    assert rc == 2 and "a result file, not a run" in err


def test_a_path_newer_than_the_newest_run_that_is_no_run_is_refused(tmp_path, table, capsys):
    one, two = nights(tmp_path / "n", table, table)
    empty = tmp_path / "n" / "tonight"  # tonight's night in a form history does not read
    empty.mkdir()
    (empty / "log.txt").write_text("crashed\n")
    os.utime(empty, (1.7e9 + 5000, 1.7e9 + 5000))
    rc, out, err = run(capsys, "history", one, two, empty)
    assert rc == 2, err
    assert f"{empty}: not a report run and not a CSV/Parquet table; it is newer than the newest run read" in err
    # older than the newest run: passed over with the warning, as documented
    os.utime(empty, (1.7e9, 1.7e9))
    rc, out, err = run(capsys, "history", one, two, empty)
    assert rc == 0 and f"warning: {empty} passed over, no run" in err


def test_historys_own_outputs_newer_than_the_night_are_still_passed_over(tmp_path, table, capsys):
    one, two = nights(tmp_path / "n", table, table)
    h, figs = tmp_path / "n" / "h.csv", tmp_path / "n" / "figs"
    rc, _, err = run(capsys, "history", one, two, "--csv", h, "--out", figs)
    assert rc == 0, err
    for p in (h, figs):  # a second history the same night: its own outputs are newer than the night
        os.utime(p, (1.7e9 + 9000, 1.7e9 + 9000))
    rc, out, err = run(capsys, "history", one, two, h, figs)
    assert rc == 0, err
    assert f"warning: {h} passed over, no run" in err and f"warning: {figs} passed over, no run" in err
    assert "newest run 2.csv against 1.csv: ok" in out


def test_a_damaged_older_night_is_still_passed_over(tmp_path, table, capsys):
    bad = table.copy()
    bad["cr"] = bad["cr"].astype(object)
    bad.loc[0, "cr"] = "abc"
    one, two, three = nights(tmp_path / "n", table, bad, table)
    rc, _, err = run(capsys, "history", one, two, three)
    assert rc == 0 and f"warning: {two} passed over, a damaged run older than the newest" in err
