"""Runs that travel and are safe to receive (issue 48, tester s68): verify compares the files
themselves (a twin of a recorded file, named the same in another Unicode spelling, is added); every
reader of a received run's JSON refuses one that is not the JSON lorisnb writes (nested too deeply,
a key twice, a checksum that is none, a value of the wrong type, a relative root) with the package's
error; two names shown side by side that differ only by their Unicode spelling are told apart; a
marker listing files outside the run is damaged, not "missing"; a FIFO among the inputs is "not a
regular file"; an --absolute-paths run records its final folder in papermill's metadata; verify's
--root names are checked."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from pathlib import Path

import pytest
from helpers import run_cli as run
from report_fixtures import fake_papermill_notebook as fake_notebook

from lorisnb.errors import ValidationError
from lorisnb.tools.report.provenance import verify_run

NOT_A_FILE = "not a regular file"

ORB = "cafe_1_1_orbslam2-original.txt"
ODOM = "cafe-1-1-odom.txt"
NFD = "alge\u0301"  # as a Mac writes the folder algé
NFC = "alg\u00e9"


def make_run(here: Path, data, icra20, **kw) -> Path:
    import lorisnb.tools.report.build as report

    for alg, src, name in (("orb", "orbslam2_rgbd", ORB), (NFD, "odom", ODOM)):
        (here / "res" / alg).mkdir(parents=True, exist_ok=True)
        shutil.copy(icra20 / "per-seq" / src / name, here / "res" / alg / name)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(report, "run_notebook", fake_notebook)
        out, _ = report.run_report(here / "runs" / "r1", {"data_root": str(data.root)}, ["compare_algorithms"],
                                   progress=False, results=here / "res", **kw)  # fmt: skip
    return out


@pytest.fixture(scope="module")
def made(tmp_path_factory, data, icra20):
    """A portable report run of a results folder holding an algorithm folder named in NFD."""
    here = tmp_path_factory.mktemp("lab")
    return here, make_run(here, data, icra20)


def copy(src: Path, dst: Path) -> Path:
    shutil.copytree(src, dst, symlinks=True)
    return dst


def with_run_json(run: Path, text: str) -> None:
    """run.json replaced by ``text``, its marker updated as if the run wrote it (render then reads it)."""
    (run / "run.json").write_text(text, encoding="utf-8")
    marker = json.loads((run / ".lorisnb-run").read_text())
    marker["files"]["run.json"] = hashlib.sha256(text.encode()).hexdigest()
    (run / ".lorisnb-run").write_text(json.dumps(marker))


def test_a_twin_named_in_the_other_unicode_spelling_is_added_and_a_respelled_copy_is_not(made, data, tmp_path):
    here, out = made
    record = json.loads((out / "run.json").read_text())
    assert f"{{results}}/{NFD}/{ODOM}" in record["inputs"]  # recorded as spelled (NFD)
    roots = {"data": data.root}
    twin = copy(here / "res", tmp_path / "twin")
    (twin / NFC).mkdir()
    shutil.copy(twin / "orb" / ORB, twin / NFC / ODOM)  # another file, its name NFC-equal to the recorded one
    assert verify_run(out, {**roots, "results": twin}) == [(f"{{results}}/{NFC}/{ODOM}", "added")]
    respelled = copy(here / "res", tmp_path / "respelled")  # the same files, the folder's name spelled in NFC
    os.rename(respelled / NFD, respelled / NFC)
    assert verify_run(out, {**roots, "results": respelled}) == []


def test_two_names_differing_only_by_their_unicode_spelling_are_told_apart(tmp_path):
    from lorisnb.core.stats import trials

    a, b = f"res/{NFD}/{ODOM}", f"res/{NFC}/{ODOM}"
    with pytest.raises(ValidationError) as err:
        trials.check_duplicates([(a, ("", NFC, "cafe", 0), (1,)), (b, ("", NFC, "cafe", 0), (1,))])
    message = str(err.value)
    assert f"res/alge\\u0301/{ODOM} (NFD) and res/alg\\xe9/{ODOM} (NFC) both hold" in message
    assert getattr(trials, "told_apart", lambda a, b: None)("orb/x.txt", "odom/x.txt") == (
        "orb/x.txt",
        "odom/x.txt",
    )  # names that differ: as they are


@pytest.mark.parametrize(
    ("text", "said"),
    [
        ("[" * 100000 + "]" * 100000, "not valid JSON (nested too deeply to be read)"),
        ("DUP", 'not valid JSON (the key "inputs" given twice in one object)'),
        ("ZZ", "expected an object path -> SHA-256 (64 hexadecimal digits"),
        ("DIRTY", '"dirty" is Infinity; expected true, false or null'),
        ("RELATIVE", "expected an absolute folder"),
    ],
    ids=["deep", "duplicate-key", "checksum", "dirty", "relative-root"],
)
def test_a_damaged_run_json_is_refused_by_every_reader_with_the_package_error(made, data, tmp_path, capsys, text, said):
    here, out = made
    damaged = copy(out, tmp_path / "damaged")
    record = json.loads((out / "run.json").read_text())
    key = f"{{results}}/orb/{ORB}"
    if text == "DUP":
        body = json.dumps(record)
        text = body[:-1] + ', "inputs": {}}'
    elif text == "ZZ":
        text = json.dumps({**record, "inputs": {**record["inputs"], key: "zz"}})
    elif text == "DIRTY":
        text = json.dumps({k: v for k, v in record.items() if k != "dirty"})[:-1] + ', "dirty": 1e99999}'
    elif text == "RELATIVE":
        text = json.dumps({**record, "roots": {**record["roots"], "data": "data"}})
    with_run_json(damaged, text)
    rc, _, err = run(capsys, "verify", damaged, "--data", data.root, "--results", here / "res")
    assert rc == 2 and "run.json: " in err and said in err and "Traceback" not in err, err
    if said.startswith("expected an object path"):  # a checksum is read against its file by verify only
        return
    for args in (("diff", out, damaged), ("history", out, damaged), ("render", damaged)):
        rc, _, err = run(capsys, *args)
        assert rc == 2 and said in err and "Traceback" not in err, (args, err)


def test_a_marker_listing_files_outside_the_run_is_a_damaged_marker(made, data, tmp_path, capsys):
    here, out = made
    for bad in ("/etc/passwd", "../../secret/s.txt"):
        damaged = copy(out, tmp_path / f"m{len(bad)}")
        marker = json.loads((damaged / ".lorisnb-run").read_text())
        marker["files"][bad] = "0" * 64
        (damaged / ".lorisnb-run").write_text(json.dumps(marker))
        rc, stdout, err = run(capsys, "verify", damaged, "--data", data.root, "--results", here / "res")
        assert rc == 2 and "an edited marker?" in err and repr(bad) in err and "missing" not in stdout, err
        rc, _, err = run(capsys, "render", damaged)
        assert rc == 2 and "an edited marker?" in err and "put them back" not in err, err


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_a_fifo_in_place_of_an_input_or_added_is_not_a_regular_file(made, data, tmp_path, capsys):
    here, out = made
    res = copy(here / "res", tmp_path / "fifo")
    (res / "orb" / ORB).unlink()
    os.mkfifo(res / "orb" / ORB)
    os.mkfifo(res / "orb" / "added.txt")
    problems = verify_run(out, {"data": data.root, "results": res})
    assert problems == [("{results}/orb/added.txt", NOT_A_FILE), (f"{{results}}/orb/{ORB}", NOT_A_FILE)]
    rc, stdout, err = run(capsys, "verify", out, "--data", data.root, "--results", res)
    assert rc == 1 and stdout.splitlines() == [f"not a regular file: {{results}}/orb/{x}" for x in ("added.txt", ORB)]
    assert "2 file(s) in the folders it read are not regular files" in err and "changed or missing" not in err


def test_an_absolute_paths_run_records_its_final_folder_in_papermills_metadata(tmp_path, data, icra20):
    out = make_run(tmp_path, data, icra20, absolute_paths=True)
    nb = out / "compare_algorithms" / "compare_algorithms.ipynb"
    meta = json.loads(nb.read_text())["metadata"]["papermill"]
    assert meta["output_path"] == str(out / "compare_algorithms" / "compare_algorithms.ipynb")
    assert ".partial-" not in nb.read_text()
    assert verify_run(out, {"data": data.root, "results": tmp_path / "res"}) == []  # the marker lists it as it is
    from lorisnb.tools.report.build import not_as_written

    assert not_as_written(out) == []


def test_verify_refuses_a_root_name_that_is_none_and_notes_one_the_run_does_not_use(made, data, capsys):
    here, out = made
    given = ["--data", data.root, "--results", here / "res"]
    for name in ("run", "", "x}/../{y", "1st"):
        rc, _, err = run(capsys, "verify", out, *given, "--root", name, here)
        assert rc == 2 and f"--root {name!r}" in err and "without braces" in err, (name, err)
    rc, _, err = run(capsys, "verify", out, *given, "--root", "elsewhere", here)
    assert rc == 0 and "note: --root elsewhere: the run names no root {elsewhere} (its roots: {data}, {results})" in err


def test_a_spec_cell_nested_too_deeply_is_refused_or_compared_as_text_not_a_traceback():
    import pandas as pd

    from lorisnb.errors import ParseError
    from lorisnb.tools.decisions import runs

    deep = "[" * 100000 + "]" * 100000  # a table's cell: no spec lorisnb writes (a damaged table), said briefly
    with pytest.raises(
        ParseError, match=r"column spec: '\[\[\[.*\(200000 characters\) is not the JSON of an evaluation"
    ):
        runs.check_values(pd.DataFrame({"spec": [deep]}), Path("x.csv"), "a table")
    assert runs._spec_keys([(deep,)], [("{}",)], "A", "B") is None
    assert runs._same_spec_text(deep, "{}") == (deep, "{}")


def test_a_notebook_marker_nested_past_the_stack_is_refused_not_a_traceback(tmp_path):
    """The notebooks' output marker read with json.loads: '[' * 100000 raised RecursionError; it is
    a marker that is not lorisnb's, refused with what to do, as any unreadable marker."""
    from lorisnb.errors import OutputError
    from lorisnb.tools.notebook.start import OUTPUTS_MARKER, Outputs

    out = tmp_path / "out"
    out.mkdir()
    (out / OUTPUTS_MARKER).write_text("[" * 100000 + "]" * 100000)
    with pytest.raises(OutputError, match="not a list of the files a notebook wrote"):
        Outputs(out, notebook="x").written()
