"""The challenge server under load on loopback (bounded: 50 uploads, 15 minutes at most): 50 teams
upload real icra20 cafe results at the same moment; every upload is accepted, stored and scored
exactly once, the same files get the same scores, and the leaderboard page answers throughout.
The figures are ``make bench``'s (benchmarks/challenge_load.py)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

pytest.importorskip("fastapi")
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from challenge_load import describe, run_load  # noqa: E402

pytestmark = pytest.mark.slow


def test_fifty_concurrent_submissions(tmp_path, data):
    f = run_load(tmp_path, data, n=50, workers=2, timeout=900)
    print(describe(f))
    assert f["accepted"] == f["stored"] == 50  # none refused, none lost
    assert f["scored"] == 50 and f["queue"]["failed"] == 0
    assert f["once"] == f["ledger_rows"] == 50  # each scored exactly once
    assert f["same_scores"]  # the same files, the same numbers, whichever scorer took them
    assert f["page_loads"] > 10 and f["page_max"] < 10.0  # the page answered throughout
