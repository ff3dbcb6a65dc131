"""``history`` says of its newest night what ``diff`` says of the same two tables: a night holding
every value of its baseline (a CI job that re-uploaded the previous night's table after its own run
crashed) is the same run kept twice, no comparison; it was judged "ok" with no word, exit 0. The
exit status stays the comparison's (diff's rule: ok, exit 0). Real data: the bundled icra20
results, evaluated and perturbed as reruns."""

from __future__ import annotations

import os
import shutil
from datetime import datetime, timedelta, timezone
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.tools.decisions.diff import diff_tables, keyed, same_run_note
from lorisnb.tools.decisions.history import drift, newest_verdict
from lorisnb.tools.decisions.runs import Run

T0 = 1767236400  # 2026-01-01T03:00:00Z


@pytest.fixture(scope="module")
def nights(icra20):
    """Two noise-only nights of three trials of the odom and orbslam2_rgbd per-seq results."""
    table = ln.evaluate([icra20 / "per-seq" / "odom", icra20 / "per-seq" / "orbslam2_rgbd"]).sequences(
        eps="paper", phi=30
    )
    rng = np.random.default_rng(5)
    out = []
    for _ in range(2):
        parts = []
        for k in range(1, 4):
            t = table.assign(trial=k)
            t["cr"] = np.clip(t["cr"] + rng.normal(0, 0.01, len(t)), 0, 1)
            t["ate_rmse"] = t["ate_rmse"] * np.exp(rng.normal(0, 0.05, len(t)))
            parts.append(t)
        out.append(pd.concat(parts, ignore_index=True))
    return out


def _write(folder: Path, tables: list[pd.DataFrame]) -> list[Path]:
    paths = []
    for k, t in enumerate(tables):
        p = folder / f"2026-01-0{k + 1}.csv"
        t.to_csv(p, index=False)
        os.utime(p, (T0 + 86400 * k, T0 + 86400 * k))
        paths.append(p)
    return paths


def test_history_notes_a_night_that_is_its_baseline_copied(nights, tmp_path, capsys):
    a, b = _write(tmp_path, nights)
    copy = tmp_path / "2026-01-03.csv"
    shutil.copyfile(b, copy)
    os.utime(copy, (T0 + 2 * 86400, T0 + 2 * 86400))
    rc = main(["history", str(a), str(b), str(copy), "--metric", "cr"])
    out = capsys.readouterr().out
    assert rc == 0, out  # diff's rule for the same two tables: ok, exit 0, with the note
    assert "newest run 2026-01-03.csv against 2026-01-02.csv: ok" in out
    assert "note: 2026-01-02.csv holds every value of 2026-01-03.csv, to the last digit: the same run kept twice" in out
    assert "is no baseline" in out
    rc = main(["history", str(a), str(b), "--metric", "cr"])  # a night of its own: no note
    assert rc == 0 and "holds every value" not in capsys.readouterr().out


def test_the_note_is_one_function_and_names_a_copy_of_the_first_run(nights):
    """In Python: :func:`same_run_note` is the words; ``newest_verdict`` says them of the newest run
    against its baseline and against its series' first run."""
    a, b = nights
    assert same_run_note(a, b, "A", "B") is None
    note = same_run_note(a, a.copy(), "A", "B")
    assert note is not None and note.startswith("A holds every value of B, to the last digit")
    start = datetime(2026, 1, 1, 3, tzinfo=timezone.utc)
    runs = [Run(Path(f"n{k}.csv"), "table", t, created=start + timedelta(days=k), created_from="test")
            for k, t in enumerate([a, b, a.copy()])]  # fmt: skip
    names = [r.name for r in runs]
    d = diff_tables(keyed(b, names[1]), keyed(a, names[2]), names=(names[1], names[2]))
    rc, lines = newest_verdict(runs, {2: d}, names, drift(runs))
    notes = [x for x in lines if x.startswith("note: ")]
    assert notes == [f"note: {same_run_note(a, a, 'n0.csv', 'n2.csv')}"], lines
    assert rc == 0
