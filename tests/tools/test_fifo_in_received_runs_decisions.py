"""A FIFO where a received run holds run.json or its own table, given to diff and history: run.json
a FIFO made diff take the run for a result folder, and a FIFO table was called "no such file";
both are refused naming the file, never opened, and an older night so damaged is passed over.
Each command runs in a process of its own with a time limit: a regression fails, never hangs."""

from __future__ import annotations

import os
import subprocess
import sys

from test_duplicate_rows_in_runs import lost_home, report_run, table  # noqa: F401 (a fixture)

from lorisnb.tools.decisions.runs import FIRST_TABLE


def lorisnb(*args) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "lorisnb.cli", *map(str, args), "--no-progress"],
                          capture_output=True, text=True, timeout=120)  # fmt: skip


def test_a_fifo_for_run_json_or_its_table_is_refused_and_an_older_one_passed_over(tmp_path, table):  # noqa: F811
    runs = tmp_path / "runs"
    good = report_run(runs / "r1", table, "2026-01-01T03:00:00+00:00")
    fifo_json = runs / "r2"
    fifo_json.mkdir()
    os.mkfifo(fifo_json / "run.json")
    fifo_table = report_run(tmp_path / "r3", table, "2026-01-03T03:00:00+00:00")
    (fifo_table / FIRST_TABLE).unlink()
    os.mkfifo(fifo_table / FIRST_TABLE)
    tonight = report_run(tmp_path / "r4", lost_home(table), "2026-01-04T03:00:00+00:00")

    got = lorisnb("diff", fifo_json, good)
    assert got.returncode == 2 and f"{fifo_json / 'run.json'}: not a regular file" in got.stderr, got.stderr
    got = lorisnb("diff", good, fifo_table)
    assert got.returncode == 2 and f"{fifo_table / FIRST_TABLE}: not a regular file" in got.stderr, got.stderr
    assert "no such file" not in got.stderr
    # the damaged older night among the earlier runs: passed over, tonight judged against r1
    got = lorisnb("diff", runs, tonight, "--baseline", "last-comparable")
    assert got.returncode == 1 and "home" in got.stdout + got.stderr, got.stdout + got.stderr
    assert "r2" in got.stderr and "not a regular file" in got.stderr, got.stderr
    assert (fifo_json / "run.json").is_fifo() and (fifo_table / FIRST_TABLE).is_fifo()  # left as they were
