"""The spec's notes on the options (``lifelong`` or ``per-seq`` on a pair, whose one sequence makes
them agree) reach Python as the command line prints them: a LorisWarning and ``ev.warnings`` (the
notebooks and ``lorisnb report`` get them through the Python API); Python said nothing."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

import lorisnb as ln
from lorisnb.errors import LorisWarning


@pytest.fixture
def est(tmp_path, data) -> Path:
    path = tmp_path / "orb.txt"
    shutil.copy(data.tum / "fr2_desk_ORB.txt", path)
    return path


@pytest.mark.parametrize("option", [{"lifelong": True}, {"mode": "per-seq"}])
def test_the_specs_notes_reach_python(tmp_path, data, est, option):
    """The command line printed 'mode lifelong: a pair has one sequence'; Python said nothing."""
    mode = "lifelong" if option.get("lifelong") else option["mode"]
    note = f"mode {mode}: a pair has one sequence, so per-seq and lifelong agree"
    with pytest.warns(LorisWarning) as caught:
        ev = ln.evaluate_pairs(est, data.tum / "fr2_desk_groundtruth.txt", **option)
    assert note in [str(w.message) for w in caught] and ev.warnings[0] == note and ev.notes == [note]


def test_a_notebook_shows_the_specs_notes(tmp_path, data, est, capsys):
    """A notebook silences LorisWarnings (ln.setup) and showed only each file's notes: the spec's
    went nowhere with ``lorisnb report -p lifelong true`` on a pair."""
    from lorisnb.tools.notebook.start import Outputs, show_inputs

    with pytest.warns(LorisWarning):
        ev = ln.evaluate_pairs(est, data.tum / "fr2_desk_groundtruth.txt", lifelong=True)
    show_inputs(ev, Outputs(tmp_path / "out", notebook="evaluate_my_results"))
    assert "note: mode lifelong: a pair has one sequence, so per-seq and lifelong agree" in capsys.readouterr().out
