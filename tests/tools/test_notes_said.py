"""The notes about inputs as a user reads them: each names the input it is about the way the
table does (two algorithms' ``cafe1.txt`` are two inputs, two notes), and a note that many inputs
share is said in full for a few of them and then counted, not printed once per file, while every
note stays in ``Evaluation.warnings``. Real data: the ICRA 2020 ORB-SLAM2 result of cafe 1-1."""

from __future__ import annotations

import warnings

import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import LorisWarning
from lorisnb.tools.evaluation.result import SAME_NOTE_IN_FULL, SAME_NOTE_NAMED, said_notes

ORB = "per-seq/orbslam2_rgbd/cafe_1_1_orbslam2-original.txt"
SWAPPED = "the quaternions look like 'qw qx qy qz'"
NO_PAIR = "no RPE pair over 1 s"


def _header_and_poses(icra20):
    lines = (icra20 / ORB).read_text().splitlines()
    head = next(i for i, line in enumerate(lines) if line.strip() and ":" not in line)
    return lines[:head], lines[head:]


def _swapped(icra20, folder, algorithms):
    """The real file with each quaternion written real part first, as ``cafe1.txt`` of each algorithm."""
    head, poses = _header_and_poses(icra20)
    moved = [" ".join([*t[:4], t[7], *t[4:7]]) if len(t := p.split()) == 8 else p for p in poses]
    for a in algorithms:
        (folder / a).mkdir(parents=True)
        (folder / a / "cafe1.txt").write_text("\n".join([*head, *moved]) + "\n")


def _short(icra20, folder, n):
    """``n`` algorithms, each the real file's first 12 to 26 poses (each its own count and span in
    its note): shorter than the RPE step."""
    head, lines = _header_and_poses(icra20)
    for k in range(n):
        (folder / f"config_{k:02d}").mkdir(parents=True)
        (folder / f"config_{k:02d}" / "cafe1.txt").write_text("\n".join([*head, *lines[: 12 + k % 15]]) + "\n")


def test_a_note_names_the_input_as_the_table_does(icra20, data, tmp_path, capsys):
    """Two algorithm folders holding the same file name, both with the quaternions in the other
    order: the command line says it twice, once for each (the note named only ``cafe1.txt``, and
    the two identical texts were said once: which algorithm was left to guess); a file given
    alone is named by its path as given."""
    _swapped(icra20, tmp_path / "res", ["algA", "algB"])
    assert main(["evaluate", str(tmp_path / "res"), "--data", str(data.root), "--no-progress", "--jobs", "1"]) == 0
    said = [line for line in capsys.readouterr().err.splitlines() if SWAPPED in line]
    assert [line.split(", seq 1:")[0] for line in said] == ["warning: algA/cafe1.txt", "warning: algB/cafe1.txt"]
    alone = tmp_path / "res" / "algB" / "cafe1.txt"
    assert main(["evaluate", str(alone), "--data", str(data.root), "--no-progress"]) == 0
    assert f"warning: {alone}, seq 1: {SWAPPED}" in capsys.readouterr().err


@pytest.mark.parametrize("n", [SAME_NOTE_IN_FULL + 1, SAME_NOTE_IN_FULL + SAME_NOTE_NAMED + 2])
def test_a_note_many_inputs_share_is_counted(icra20, data, tmp_path, capsys, n):
    """``n`` short files of different lengths, each with no RPE pair (its own pose count and span in
    its note): up to one more than SAME_NOTE_IN_FULL are said in full; more, and the first
    SAME_NOTE_IN_FULL are said in full, then one line counts the rest
    and names the first SAME_NOTE_NAMED of them (the command line and Python's warnings alike);
    Evaluation.warnings keeps every one."""
    _short(icra20, tmp_path / "res", n)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        ev = ln.evaluate(tmp_path / "res", data_root=data.root, progress=False, jobs=1)
    every = [w for w in ev.warnings if NO_PAIR in w]
    assert len(every) == n and len(set(every)) == n
    issued = [str(w.message) for w in caught if issubclass(w.category, LorisWarning)]
    assert issued == said_notes(ev.errors)
    full = [w for w in issued if NO_PAIR in w and not w.startswith("a note like")]
    if n <= SAME_NOTE_IN_FULL + 1:
        assert full == every and not any("more input(s)" in w for w in issued)
    else:
        assert full == every[:SAME_NOTE_IN_FULL]
        last = issued[issued.index(full[-1]) + 1]
        rest = [f"config_{k:02d}/cafe1.txt" for k in range(SAME_NOTE_IN_FULL, n)]
        assert "('no RPE pair over 1 s (its " in last  # which note it counts (two kinds' lines were one text)
        assert f", numbers aside) {len(rest)} more time(s), about {len(rest)} input(s): " in last
        assert all(r in last for r in rest[:SAME_NOTE_NAMED]) and rest[SAME_NOTE_NAMED] not in last
        assert last.count("config_") == SAME_NOTE_NAMED and ", ..." in last
    assert main(["evaluate", str(tmp_path / "res"), "--data", str(data.root), "--no-progress", "--jobs", "1"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert [line for line in err if line.startswith("warning:")] == [f"warning: {w}" for w in issued]


def test_a_challenge_note_names_the_uploaded_file_only(icra20, data, tmp_path):
    """The challenge scores an upload's files given alone, from a folder of the server's: its note
    names the file as the team uploaded it, never the server's folder or path."""
    from lorisnb.core.spec.evalspec import make_spec
    from lorisnb.tools.challenge.scoring import score_folder

    _swapped(icra20, tmp_path / "submission", ["files"])
    notes = score_folder(tmp_path / "submission" / "files", data, make_spec())["notes"]
    said = [n for n in notes if SWAPPED in n["text"]]
    assert [n["text"].split(", seq 1:")[0] for n in said] == ["cafe1.txt"] and said[0]["sequences"] == [("cafe", 1)]
    assert str(tmp_path) not in str(notes) and "(files)" not in str(notes)
