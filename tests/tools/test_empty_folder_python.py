"""An evaluation that evaluated nothing says so in Python, as ``lorisnb evaluate`` does: an empty
folder once gave an empty Evaluation without a word (no failure, no warning) while the command
line printed "not scored: nothing was evaluated: no input file was found" and exited 1."""

from __future__ import annotations

import warnings

import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import FailedInputsWarning


def test_an_empty_folder_is_said_in_python(tmp_path, data):
    empty = tmp_path / "results"
    empty.mkdir()
    with pytest.warns(FailedInputsWarning) as caught:
        ev = ln.evaluate(empty, data_root=data.root, jobs=1)
    said = [str(w.message) for w in caught if issubclass(w.category, FailedInputsWarning)]
    assert len(said) == 1
    assert said[0].startswith(f"nothing was evaluated: no input file was found in {empty}")
    assert "exit_status() is 1" in said[0] and "<algorithm>/*.txt" in said[0]
    assert ev.exit_status() == 1 and len(ev.sequences()) == 0
    assert [f.error for f in ev.unscored] == ["nothing was evaluated: no input file was found"]


def test_every_input_skipped_is_said_in_python(icra20, data):
    office = sorted((icra20 / "per-seq" / "dso").glob("office-*.txt"))[:1]
    assert office  # the office ground truth was never published: the file is skipped
    with pytest.warns(FailedInputsWarning, match=r"nothing was evaluated: every input was skipped: .*office"):
        ev = ln.evaluate(office, data_root=data.root, jobs=1)
    assert ev.exit_status() == 1 and len(ev.skipped) == 1


def test_pairs_in_an_empty_folder_are_said(tmp_path, data):
    empty = tmp_path / "estimates"
    empty.mkdir()
    gt = data.tum / "fr2_desk_groundtruth.txt"
    with pytest.warns(FailedInputsWarning, match="nothing was evaluated: no input file was found"):
        ev = ln.evaluate_pairs(empty, gt, jobs=1)
    assert ev.exit_status() == 1


def test_an_evaluation_with_a_result_says_nothing_of_the_kind(icra20, data):
    one = sorted((icra20 / "per-seq" / "dso").glob("cafe-1-1*.txt"))[:1]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ev = ln.evaluate(one, data_root=data.root, jobs=1)
    assert not [w for w in caught if issubclass(w.category, FailedInputsWarning)]
    assert ev.exit_status() == 0 and len(ev.sequences()) == 1


def test_the_command_line_says_it_once_as_before(tmp_path, data, capsys):
    empty = tmp_path / "results"
    empty.mkdir()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        status = main(["evaluate", str(empty), "--data", str(data.root), "--no-progress"])
    err = capsys.readouterr().err
    assert status == 1
    assert err.count("nothing was evaluated") == 1, err
    assert "not scored: nothing was evaluated: no input file was found" in err
    assert not [w for w in caught if issubclass(w.category, FailedInputsWarning)]  # an error: line, not a warning
