"""A backslash in a name is escaped as ``\\\\`` by the one rule (:func:`clean`), as Python's repr and
``ls -b`` show it: a folder literally named ``orb\\x1b`` and one named ``orb`` + ESC never print the
same in a terminal table, Markdown, LaTeX or a workflow annotation."""

from __future__ import annotations

import shutil

from lorisnb.cli import main
from lorisnb.tools.decisions.escape import clean, code_span, markdown_cell, workflow_data
from lorisnb.tools.report.tables import latex_escape

ESC_NAME = "orb\x1b"  # orb + the ESC character
LITERAL = "orb\\x1b"  # orb, a backslash, x, 1, b
ORB = "cafe_1_1_orbslam2-original.txt"


def test_two_names_never_show_the_same():
    assert clean(ESC_NAME) == "orb\\x1b"
    assert clean(LITERAL) == "orb\\\\x1b"
    assert clean("a\\b\\") == "a\\\\b\\\\" and clean("plain name") == "plain name"
    for shown in (clean, markdown_cell, code_span, workflow_data, latex_escape):
        assert shown(ESC_NAME) != shown(LITERAL), shown.__name__
    assert markdown_cell(LITERAL) == "orb\\\\\\\\x1b"  # Markdown renders it orb\\x1b, as the terminal shows it
    assert latex_escape(LITERAL) == r"orb\textbackslash{}\textbackslash{}x1b"


def test_the_terminal_table_shows_the_two_folders_apart(tmp_path, icra20, data, capsys):
    for name in (ESC_NAME, LITERAL):
        (tmp_path / "res" / name).mkdir(parents=True)
        shutil.copy(icra20 / "per-seq" / "orbslam2_rgbd" / ORB, tmp_path / "res" / name / ORB)
    main(["evaluate", str(tmp_path / "res"), "--data", str(data.root), "--no-progress"])
    out = capsys.readouterr().out
    assert "\x1b" not in out
    rows = [line.split() for line in out.splitlines() if line.strip().startswith("orb")]
    names = {r[0] for r in rows}
    assert names == {"orb\\x1b", "orb\\\\x1b"}, rows
