"""Received report runs (tester s71): every reader of run.json refuses one Python's parser cannot
read (an integer of 5,000 digits) with the package's error, exit 2, not a traceback and exit 1;
verify, render, diff and history check one record alike (a ``created`` that is no time, a spec
value no spec has); verify refuses a run folder holding links leading outside it, as render does;
an input that names a folder is a damaged run.json; the command line records each root by its name,
however it was typed."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest
from helpers import run_cli as run
from report_fixtures import fake_papermill_notebook as fake_notebook

from lorisnb.errors import ParseError, ValidationError
from lorisnb.tools.report.portable import command_by_root
from lorisnb.tools.report.provenance import load_json, read_run_json, verify_run

ORB = "cafe_1_1_orbslam2-original.txt"
SECRET = "TOPSECRET-CANARY"


def make_run(out: Path, data_root: str | Path, results: str | Path) -> Path:
    import lorisnb.tools.report.build as report

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(report, "run_notebook", fake_notebook)
        command = ["lorisnb", "report", "--results", str(results), "--data", str(data_root), "--out", str(out)]
        run_dir, _ = report.run_report(out, {"data_root": str(data_root)}, ["compare_algorithms"], progress=False,
                                       results=Path(results), command=command)  # fmt: skip
    return run_dir


@pytest.fixture(scope="module")
def made(tmp_path_factory, data, icra20):
    here = tmp_path_factory.mktemp("lab")
    (here / "res" / "orb").mkdir(parents=True)
    shutil.copy(icra20 / "per-seq" / "orbslam2_rgbd" / ORB, here / "res" / "orb" / ORB)
    return here, make_run(here / "runs" / "r1", data.root, here / "res")


def copy(src: Path, dst: Path) -> Path:
    shutil.copytree(src, dst, symlinks=True)
    return dst


def resign(run: Path) -> None:
    """The run's marker listing its files as they are now, as a run that wrote them would."""
    from lorisnb.tools.report.build import _files

    marker = json.loads((run / ".lorisnb-run").read_text())
    marker["files"] = _files(run)
    (run / ".lorisnb-run").write_text(json.dumps(marker))


def with_run_json(run: Path, text: str) -> None:
    (run / "run.json").write_text(text, encoding="utf-8")
    resign(run)


@pytest.mark.parametrize(
    ("edit", "said"),
    [
        (lambda t: t.replace('"dirty": false', '"dirty": ' + "9" * 5000),
         "not valid JSON (an integer of 5000 digits, more than can be read"),
        (lambda t: t.replace('"dirty": false', '"dirty": -' + "9" * 4301),
         "not valid JSON (an integer of 4301 digits, more than can be read"),
        (lambda t: t.replace('"inputs": {', '"inputs": {"x": [' + "1" * 5000 + "], ", 1),
         "not valid JSON (an integer of 5000 digits"),
        (lambda t: json.dumps({**json.loads(t), "created": "yesterday"}),
         '"created" is "yesterday"; expected an ISO 8601 time'),
        (lambda t: json.dumps({**(r := json.loads(t)), "spec": {**r["spec"], "values": {**r["spec"]["values"],
                                                                                           "delta": float("nan")}}}),
         '"spec" values: delta=nan'),
    ],
    ids=["huge-int", "huge-negative-int", "huge-int-nested", "created-no-time", "spec-nan"],
)  # fmt: skip
def test_one_damaged_run_json_is_refused_by_verify_render_diff_and_history_alike(
    made, data, tmp_path, capsys, edit, said
):
    here, out = made
    text = json.dumps({**json.loads((out / "run.json").read_text()), "dirty": False}, indent=2)  # as a clean checkout
    damaged = copy(out, tmp_path / "damaged")
    with_run_json(damaged, edit(text))
    with pytest.raises(ParseError, match=r"run\.json: "):
        read_run_json(damaged)
    for args in (("verify", damaged, "--data", data.root, "--results", here / "res"), ("render", damaged),
                 ("diff", out, damaged), ("diff", damaged, out), ("history", out, damaged)):  # fmt: skip
        rc, _, err = run(capsys, *args)
        assert rc == 2 and said in err and "Traceback" not in err and "set_int_max_str_digits" not in err, (args, err)


def test_load_json_names_what_python_cannot_read_and_reads_the_rest():
    assert load_json('{"a": ' + "9" * 4300 + "}", "f.json", "x")["a"] == int("9" * 4300)
    assert load_json('{"a": 1e99999, "b": -12}', "f.json", "x") == {"a": float("inf"), "b": -12}
    for text, why in (('{"a": ' + "9" * 4301 + "}", "an integer of 4301 digits"), ("[" * 100000, "nested too deeply"),
                      (b'{"a": "\xff"}', "can't decode byte 0xff"), ('{"a": 1, "a": 2}', 'the key "a" given twice')):  # fmt: skip
        with pytest.raises(ParseError, match="not valid JSON") as err:
            load_json(text, "f.json", "x")
        assert why in str(err.value)


def test_verify_refuses_a_run_folder_holding_links_leading_outside_it_as_render_does(made, data, tmp_path, capsys):
    here, out = made
    secret = tmp_path / "secret" / "s.txt"
    secret.parent.mkdir()
    secret.write_text(SECRET + "\n")
    elsewhere = tmp_path / "elsewhere"
    shutil.copytree(out / "compare_algorithms", elsewhere)
    cases = {
        "index": lambda r: ((r / "index.html").unlink(), (r / "index.html").symlink_to(secret)),
        "table": lambda r: ((r / "findings" / "leaderboard.csv").unlink(),
                            (r / "findings" / "leaderboard.csv").symlink_to(secret)),
        "notebook-folder": lambda r: (shutil.rmtree(r / "compare_algorithms"),
                                      (r / "compare_algorithms").symlink_to(elsewhere)),
    }  # fmt: skip
    for name, edit in cases.items():
        received = copy(out, tmp_path / name)
        edit(received)
        resign(received)  # the marker lists the link as it lists any file: it cannot tell
        with pytest.raises(ValidationError, match="leading outside"):
            verify_run(received, {"data": data.root, "results": here / "res"})
        rc, stdout, err = run(capsys, "verify", received, "--data", data.root, "--results", here / "res")
        link = {"index": "index.html", "table": "findings/leaderboard.csv", "notebook-folder": "compare_algorithms"}
        said = (f"{received / 'index.html'}: a link leading outside the run folder" if name == "index"
                else f"holds 1 link(s) leading outside it ({link[name]})")  # fmt: skip
        assert rc == 2 and said in err, (name, err)
        assert "unchanged" not in stdout + err and SECRET not in stdout + err and str(elsewhere) not in err
        rc, _, err = run(capsys, "render", received)
        assert rc == 2 and "leading outside" in err, (name, err)
    inside = copy(out, tmp_path / "inside")  # a link to a file of the run itself: no file elsewhere is read
    (inside / "findings" / "leaderboard.csv").unlink()
    (inside / "findings" / "leaderboard.csv").symlink_to("sequences.csv")
    resign(inside)
    assert verify_run(inside, {"data": data.root, "results": here / "res"}) == []


def test_an_input_naming_a_folder_or_nothing_is_a_damaged_run_json(made, data, tmp_path, capsys):
    here, out = made
    record = json.loads((out / "run.json").read_text())
    roots = ("--data", data.root, "--results", here / "res")
    for key, said in (("{results}/orb", 'the input "{results}/orb" is a folder here'),
                      ("{results}", 'the input "{results}" is a folder here'),
                      ("", '"inputs" holds ["", "000'),
                      ("{results}/orb/", '"inputs" holds ["{results}/orb/", "000')):  # fmt: skip
        damaged = copy(out, tmp_path / f"k{len(key)}")
        with_run_json(damaged, json.dumps({**record, "inputs": {**record["inputs"], key: "0" * 64}}))
        rc, stdout, err = run(capsys, "verify", damaged, *roots)
        assert rc == 2 and said in err and "not a regular file" not in stdout + err, (key, err)
        assert "expected the path of a file" in err or "each the path of a file (not empty, not ending in /" in err
    damaged = copy(out, tmp_path / "slash")  # a folder the run listed, outside: said to be one, not "a file"
    with_run_json(damaged, json.dumps({**record, "input_roots": [*record["input_roots"], "/"]}))
    rc, _, err = run(capsys, "verify", damaged, *roots)
    assert rc == 2 and "/: run.json names a folder (or file) the run listed outside the run folder" in err, err


def test_the_command_records_each_root_by_its_name_however_it_was_typed(tmp_path, monkeypatch, data, icra20):
    lab = tmp_path / "lab"
    (lab / "realres" / "orb").mkdir(parents=True)
    shutil.copy(icra20 / "per-seq" / "orbslam2_rgbd" / ORB, lab / "realres" / "orb" / ORB)
    (lab / "reslink").symlink_to("realres")
    (lab / "datalink").symlink_to(data.root)
    (lab / "work").mkdir()
    monkeypatch.chdir(lab / "work")
    out = make_run(Path("runs/r1"), "../datalink", "../reslink")
    record = json.loads((lab / "work" / out / "run.json").read_text())
    # the run folder, wherever it was asked for, is the run: {run} (runs/r1 meant nothing once moved)
    assert record["command"] == ["lorisnb", "report", "--results", "{results}", "--data", "{data}", "--out", "{run}"]
    assert "../" not in (lab / "work" / out / "run.json").read_text()
    assert verify_run(lab / "work" / out, {"data": data.root, "results": lab / "realres"}) == []
    named = {"data": Path(os.path.abspath("../datalink")).resolve(), "results": Path(os.path.abspath("../reslink"))}
    typed = ["lorisnb", "report", "--res=../reslink", "--dat", "../datalink/", "--notebooks", "../reslink",
             "-p", "groundtruth", "../datalink/openloris-scene", "-p", "algorithms", "../reslink", "--jobs", "1",
             "--ou=/home/alice/r2", "--", "--data", "../datalink"]  # fmt: skip
    assert command_by_root(typed, named) == [
        "lorisnb", "report", "--res={results}", "--dat", "{data}", "--notebooks", "../reslink",
        "-p", "groundtruth", "{data}/openloris-scene", "-p", "algorithms", "../reslink", "--jobs", "1",
        "--ou={run}", "--", "--data", "../datalink"]  # fmt: skip


def test_a_folder_the_run_read_that_is_gone_is_missing(made, tmp_path, capsys, data):
    """An ``input_roots`` entry whose folder is not here verified as unchanged (nothing below it was
    listed, so nothing was said); it is missing, exit 1."""
    here, run_dir = made
    mine = copy(run_dir, tmp_path / "r")
    record = json.loads((mine / "run.json").read_text())
    record["input_roots"] = [*record["input_roots"], "{results}/gone"]
    with_run_json(mine, json.dumps(record))
    rc, out, err = run(capsys, "verify", mine, "--results", here / "res", "--data", data.root)
    assert rc == 1 and "missing: {results}/gone" in out, (out, err)
    rc, out, err = run(capsys, "verify", run_dir, "--results", here / "res", "--data", data.root)
    assert rc == 0 and "missing" not in out, (out, err)
