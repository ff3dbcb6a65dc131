"""The report's words match its numbers: an all-zero tie is 'no algorithm scored', a smallest
possible p above what the sequences allow is explained, thresholds are shown as values, the
per-sequence benchmark's thresholds are the ones it ran with, run.json says if the checkout had
uncommitted changes."""

from __future__ import annotations

import subprocess

import pandas as pd
import pytest

from lorisnb.tools.report.index import git_dirty, write_index
from lorisnb.tools.report.leaderboard import sentence
from lorisnb.tools.report.notebooks import NotebookRun, shown_default


def _board(values, n=5):
    return pd.DataFrame({
        "suite": "", "scene": "home", "metric": "cr", "algorithm": [f"alg{i}" for i in range(len(values))],
        "rank": 1, "value": values, "low": values, "high": values, "trials": 1, "sequences_covered": n,
        "sequences_total": n, "coverage": f"{n}/{n}",
    })  # fmt: skip


def test_an_all_zero_tie_says_no_algorithm_scored():
    text = sentence(_board([0.0, 0.0]), pd.DataFrame({"sequences": [5], "min_p": [1.0]}))
    assert "no algorithm scored" in text and "highest" not in text


def test_a_smallest_p_above_what_the_sequences_allow_is_explained():
    board = _board([0.4, 0.2])
    dropped = sentence(board, pd.DataFrame({"sequences": [5], "min_p": [0.5]}))  # 1 of 5 sequences differs
    assert "smallest possible p 0.5" in dropped and "drop out of the paired test" in dropped
    full = sentence(board, pd.DataFrame({"sequences": [5], "min_p": [0.0625]}))  # 2 / 2^5: all 5 count
    assert "smallest possible p 0.0625" in full and "drop out" not in full


@pytest.mark.parametrize(("source", "shown"), [('float("inf")', "inf"), ("'paper'", "paper"), ("30.0", "30.0")])
def test_thresholds_are_shown_as_values(source, shown):
    assert shown_default(source) == shown


def test_the_per_sequence_benchmark_thresholds_are_the_ones_it_ran_with(tmp_path):
    runs = [NotebookRun("per_sequence_benchmark", thresholds={"eps": "paper", "phi": "inf"})]
    page = write_index(tmp_path, runs, {}).read_text()
    assert "without any" not in page and "reproduces Fig. 2 at eps paper, phi inf" in page
    runs = [NotebookRun("per_sequence_benchmark", thresholds={"eps": "inf", "phi": "inf"})]
    assert "reproduces Fig. 2 without any" in write_index(tmp_path, runs, {}).read_text()


def test_git_dirty_says_whether_the_checkout_has_uncommitted_changes(tmp_path):
    git = ["git", "-C", str(tmp_path), "-c", "user.name=t", "-c", "user.email=t@t"]
    subprocess.run([*git, "init", "-q"], check=True)
    (tmp_path / "a.py").write_text("x = 1\n")
    subprocess.run([*git, "add", "a.py"], check=True)
    subprocess.run([*git, "commit", "-qm", "a"], check=True)
    assert git_dirty(tmp_path) is False
    (tmp_path / "a.py").write_text("x = 2\n")
    assert git_dirty(tmp_path) is True
    assert git_dirty(tmp_path / "nowhere") is None
