"""Every warning issued while a command runs prints as one ``warning: ...`` line (docs/guide/errors.md):
the report's own LorisWarnings (a linked-folder loop, a file still showing an absolute path) printed
as Python's two lines, with a source line of lorisnb; control characters escaped, the command's
roots named ``{results}`` and ``{data}``."""

from __future__ import annotations

import os
import warnings

from test_portable_runs import fake_notebook, lab

import lorisnb.cli.commands as commands
from lorisnb.cli import main
from lorisnb.errors import LorisWarning


def shown(argv):
    """``main(argv)`` with LorisWarnings shown, as outside the tests (conftest quiets them)."""
    with warnings.catch_warnings():
        warnings.simplefilter("default", LorisWarning)
        return main(argv)


def test_a_linked_folder_loop_during_report_is_one_warning_line_naming_the_root(tmp_path, data, icra20,
                                                                                   monkeypatch, capsys):  # fmt: skip
    import lorisnb.tools.report.build as report

    here = lab(tmp_path / "lab", data, icra20)
    os.symlink(here / "res", here / "res" / "orb" / "loop")
    monkeypatch.setattr(report, "run_notebook", fake_notebook)
    rc = shown(["report", "--results", str(here / "res"), "--data", str(here / "data"), "--out", str(here / "r"),
               "--notebooks", "compare_algorithms", "--no-progress"])  # fmt: skip
    err = capsys.readouterr().err
    assert rc in (0, 1), err
    lines = [x for x in err.splitlines() if "lead back to a folder they are in" in x]
    assert lines and all(x.startswith("warning: ") for x in lines), err
    assert "{results}/orb/loop -> {results}" in lines[0] and str(here) not in err
    assert "warnings.warn" not in err and "LorisWarning" not in err  # no source line, no category


def test_every_warning_of_a_command_is_one_escaped_line(tmp_path, monkeypatch, capsys):
    res = tmp_path / "res"
    res.mkdir()

    def warns(args):
        warnings.warn(f"odd \x1b[2J name\nin {res.resolve()}/a\u202eb", LorisWarning, stacklevel=2)
        warnings.warn("a library's deprecation", FutureWarning, stacklevel=2)
        return 0

    monkeypatch.setattr(commands, "cmd_verify", warns)
    assert shown(["verify", str(tmp_path), "--results", str(res)]) == 0
    err = capsys.readouterr().err
    assert err.splitlines() == [
        "warning: odd \\x1b[2J name\\nin {results}/a\\u202eb",
        "warning: FutureWarning: a library's deprecation",
    ], err
