"""Every message line the command line prints (error:, warning:, note:, not scored:) shows control
characters escaped, as the tables do: a file name or a line quoted from a file, received from
someone else, can neither move the cursor, clear the screen nor start a line that looks like
lorisnb's own. Python keeps the text as it is (exceptions carry the real name)."""

from __future__ import annotations

import json
import shutil

import pytest
from test_portable_runs import received

from lorisnb.cli import main
from lorisnb.cli.text import say
from lorisnb.errors import ValidationError
from lorisnb.tools.report.provenance import verify_run, write_run_json

ORB = "cafe_1_1_orbslam2-original.txt"


def test_say_escapes_what_the_terminal_would_act_on(capsys):
    say("error: a\x1b[2Jb\nc\u202ed\te")
    assert capsys.readouterr().err == "error: a\\x1b[2Jb\\nc\\u202ed\\te\n"


def test_a_failed_file_and_the_line_it_quotes_are_escaped(tmp_path, data, icra20, capsys):
    alg = tmp_path / "res" / "alg\x1b[31m"
    alg.mkdir(parents=True)
    shutil.copy(icra20 / "per-seq" / "orbslam2_rgbd" / ORB, alg / ORB)
    (alg / "cafe_1_2_bad\x1b[32m.txt").write_text("garbage\x1b[2J line\n")
    rc = main(["evaluate", str(tmp_path / "res"), "--data", str(data.root), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 1 and "\x1b" not in err
    line = next(x for x in err.splitlines() if x.startswith("error:"))
    assert "alg\\x1b[31m/cafe_1_2_bad\\x1b[32m.txt" in line and "garbage\\x1b[2J line" in line


@pytest.mark.parametrize("key", ["/etc/\x1b[2J\x1b[31mevil", "{re\x1b[31msults}/x", "/tmp/a\nerror: all is well"])
def test_a_refused_key_of_a_received_run_json_is_escaped(tmp_path, capsys, key):
    folder, res = received(tmp_path, {})
    record = json.loads((folder / "run.json").read_text())
    record["inputs"][key] = "0" * 64
    write_run_json(folder, record)
    if "{" not in key:
        with pytest.raises(ValidationError) as exc:
            verify_run(folder, {"results": res})
        assert key in str(exc.value)  # Python: the name as it is
    rc = main(["verify", str(folder), "--results", str(res)])
    out, err = capsys.readouterr()
    assert rc in (1, 2) and "\x1b" not in out + err
    lines = (out + err).splitlines()
    assert all(x.startswith(("error:", "missing:", "1 of")) for x in lines) and len(lines) <= 2, out + err
    assert not any(x.startswith("error: all is well") for x in lines)  # no line of its own making


def test_a_received_run_jsons_version_is_escaped_in_diffs_refusal(tmp_path, data, icra20, capsys):
    import lorisnb as ln
    from lorisnb.tools.decisions.runs import FIRST_TABLE

    res = tmp_path / "res" / "orb"
    res.mkdir(parents=True)
    shutil.copy(icra20 / "per-seq" / "orbslam2_rgbd" / ORB, res / ORB)
    table = ln.evaluate(res.parent, data_root=data, progress=False).sequences()
    for name, version in (("a", "0.3.0"), ("b", "9\x1b[2J")):
        run = tmp_path / name
        (run / "findings").mkdir(parents=True)
        table.to_csv(run / FIRST_TABLE, index=False)
        meta = {"command": [], "lorisnb_version": version, "commit": None, "spec": {"values": {}}, "data_root": None,
                "created": None, "inputs": {}, "notebooks": {}}  # fmt: skip
        (run / "run.json").write_text(json.dumps(meta))
    rc = main(["diff", str(tmp_path / "a"), str(tmp_path / "b")])
    err = capsys.readouterr().err
    # runs of two versions are not comparable (exit 2, as history says): the version is named, escaped
    assert rc == 2 and "lorisnb_version 0.3.0 -> 9\\x1b[2J" in err and "\x1b" not in err


@pytest.mark.parametrize(
    "args", [["report", "--label", "v1\x1b[31m"], ["evaluate", "x", "--eps", "1\x1b[2J"], ["ev\x1b"]]
)
def test_a_usage_error_quoting_the_value_given_is_escaped(capsys, args):
    with pytest.raises(SystemExit) as exc:
        main(args)
    err = capsys.readouterr().err
    assert exc.value.code == 2 and "\\x1b" in err and "\x1b" not in err


def test_a_wide_name_keeps_the_tables_columns_aligned(tmp_path, data, icra20, capsys):
    """An algorithm named in Chinese (two terminal columns a character) or with a combining accent
    (none for the accent) lines up with the others: every row of the printed table is as wide
    on the screen as its header."""
    from lorisnb.cli.text import display_width

    for name in ("视觉里程计", "orbslam2", "q\u0307-slam"):
        (tmp_path / "res" / name).mkdir(parents=True)
        shutil.copy(icra20 / "per-seq" / "orbslam2_rgbd" / ORB, tmp_path / "res" / name / ORB)
    assert display_width("视觉") == 4 and display_width("e\u0301") == 1 and display_width("\u200bx") == 1
    rc = main(["evaluate", str(tmp_path / "res"), "--data", str(data.root), "--no-progress"])
    out = capsys.readouterr().out
    assert rc == 0
    head = next(k for k, line in enumerate(out.splitlines()) if "algorithm" in line)
    table = out.splitlines()[head : head + 4]
    assert any("视觉里程计" in line for line in table) and any("\u0307" in line for line in table)
    assert len({display_width(line.rstrip()) for line in table}) == 1, table
