"""Runs that travel and are safe to receive: a report run written below named roots ({data},
{results}) holds no absolute path of the machine it was made on, is verified and rendered again
where it was moved to; verify reads nothing outside the run folder and the roots named on its
command line, whatever run.json says."""

from __future__ import annotations

import json
import os
import shutil
import warnings
from pathlib import Path

import pytest
from helpers import run_cli as run

from lorisnb.errors import LorisWarning, OutputError, ValidationError
from lorisnb.tools.report.portable import held_paths, make_portable, root_key, spellings, unreplaced
from lorisnb.tools.report.provenance import checksums, input_files, run_record, verify_run, write_run_json

ORB = "cafe_1_1_orbslam2-original.txt"
ODOM = "cafe-1-1-odom.txt"


def lab(where: Path, data, icra20) -> Path:
    """A lab folder: ``res/<alg>/*.txt`` (two real results) and ``data/`` (the real ground truth
    and extrinsics), as a user keeps them."""
    for alg, src, name in (("orb", "orbslam2_rgbd", ORB), ("odom", "odom", ODOM)):
        (where / "res" / alg).mkdir(parents=True)
        shutil.copy(icra20 / "per-seq" / src / name, where / "res" / alg / name)
    shutil.copytree(data.root / "openloris-scene", where / "data" / "openloris-scene")
    return where


@pytest.mark.slow
def test_a_run_moved_elsewhere_is_verified_and_rendered_there_and_names_no_path_of_the_first(
    tmp_path, data, icra20, capsys
):
    first = lab(tmp_path / "first-place", data, icra20)
    rc, out, err = run(capsys, "report", "--results", first / "res", "--data", first / "data", "--out",
                       first / "runs" / "r1", "--notebooks", "compare_algorithms", "evaluate_my_results", "--no-progress")  # fmt: skip
    assert rc == 0, out + err
    record = json.loads((first / "runs" / "r1" / "run.json").read_text())
    assert record["data_root"] == "{data}" and record["roots"] == {"data": None, "results": None}
    assert record["inputs"]["{results}/orb/" + ORB] and record["spec"]["values"]["source"] == "{results}"
    assert "{results}/odom" not in record["input_roots"] and "{results}" in record["input_roots"]
    second = tmp_path / "elsewhere" / "other-name"
    second.parent.mkdir()
    shutil.move(first, second)
    r1 = second / "runs" / "r1"
    rc, _, err = run(capsys, "verify", r1)  # the roots are not guessed from the file
    assert rc == 2 and "--data DIR" in err
    rc, _, err = run(capsys, "verify", r1, "--data", second / "data", "--results", second / "res")
    assert rc == 0 and "all 230 input file(s) unchanged" in err, err  # with the bundled results
    (second / "res" / "orb" / ORB).write_text((second / "res" / "orb" / ORB).read_text() + "\n")
    rc, out, _ = run(capsys, "verify", r1, "--data", second / "data", "--results", second / "res")
    assert rc == 1 and out.strip() == "changed: {results}/orb/" + ORB
    before = (r1 / "compare_algorithms" / "compare_algorithms.html").read_bytes()
    (r1 / "compare_algorithms" / "compare_algorithms.html").write_bytes(before + b"<p>my note</p>")
    rc, _, err = run(capsys, "render", r1)  # a page edited since the run: kept, not rendered over
    assert rc == 2 and "compare_algorithms.html" in err
    assert (r1 / "compare_algorithms" / "compare_algorithms.html").read_bytes().endswith(b"my note</p>")
    (r1 / "compare_algorithms" / "compare_algorithms.html").unlink()
    rc, out, _ = run(capsys, "render", r1)
    assert rc == 0 and "compare_algorithms.html" in out and "report.html" in out
    again = (r1 / "compare_algorithms" / "compare_algorithms.html").read_text()
    assert (
        "data root: {data}" in again
        and again.count("jp-OutputArea-output") == before.decode().count("jp-OutputArea-output") > 0
    )
    everything = [p for p in r1.rglob("*") if p.is_file()]
    assert len(everything) >= 8 and {".ipynb", ".png", ".csv", ".json", ".tex"} <= {p.suffix for p in everything}
    firsts = [tmp_path / "first-place", (tmp_path / "first-place").resolve()]
    assert held_paths(r1, firsts) == []
    for p in everything:  # every spelling of the first place, in every file, binary or not
        blob = p.read_bytes()
        for s in {x for f in firsts for x in spellings(f)} | {str(tmp_path)}:
            assert s.encode() not in blob, (p, s)
    assert b"{data}" in (r1 / "compare_algorithms" / "compare_algorithms.ipynb").read_bytes()


def fake_notebook(name, out_dir, params, **kw):
    """A notebook that prints its parameters (absolute paths) into its output and a PNG."""
    from lorisnb.tools.report.notebooks import NotebookRun

    folder = out_dir / name
    folder.mkdir()
    (folder / f"{name}.ipynb").write_text(json.dumps({"cells": [{"outputs": [{"text": f"data root: {params}"}]}]}))
    (folder / f"{name}.html").write_text(f"<pre>{params.get('results_dir')}</pre>")
    return NotebookRun(name)


@pytest.mark.thorough
def test_absolute_paths_only_when_asked_through_python(tmp_path, data, icra20, monkeypatch):
    import lorisnb.tools.report.build as report

    here = lab(tmp_path / "lab", data, icra20)
    monkeypatch.setattr(report, "run_notebook", fake_notebook)
    out, _ = report.run_report(here / "runs" / "p", {"data_root": str(here / "data")}, ["compare_algorithms"],
                               progress=False, results=here / "res")  # fmt: skip
    assert held_paths(out, [here]) == []
    assert "{results}" in (out / "compare_algorithms" / "compare_algorithms.html").read_text()
    out, _ = report.run_report(here / "runs" / "a", {"data_root": str(here / "data")}, ["compare_algorithms"],
                               progress=False, results=here / "res", absolute_paths=True)  # fmt: skip
    record = json.loads((out / "run.json").read_text())
    assert record["roots"] == {"data": str((here / "data").resolve()), "results": str((here / "res").resolve())}
    assert str((here / "res" / "orb" / ORB).resolve()) in record["inputs"]
    assert held_paths(out, [here])  # the pages say where, as asked
    assert verify_run(out, {"data": here / "data", "results": here / "res"}) == []


def test_absolute_paths_through_the_command_line(tmp_path, data, icra20, monkeypatch, capsys):
    import lorisnb.tools.report.build as report

    here = lab(tmp_path / "lab", data, icra20)
    monkeypatch.setattr(report, "run_notebook", fake_notebook)
    rc, _, err = run(capsys, "report", "--results", here / "res", "--data", here / "data", "--out", here / "r",
                     "--notebooks", "compare_algorithms", "--no-progress", "--absolute-paths")  # fmt: skip
    assert rc == 0, err
    assert str(here.resolve()) in (here / "r" / "run.json").read_text()
    rc, _, err = run(capsys, "verify", here / "r")  # absolute roots in run.json: not read without being named
    assert rc == 2 and "outside the run folder and the roots given here" in err
    rc, _, err = run(capsys, "verify", here / "r", "--data", here / "data", "--results", here / "res")
    assert rc == 0 and "all 7 input file(s) unchanged" in err


def received(tmp_path, record_changes, roots=("res",)):
    """A run folder as received: run.json written by lorisnb, then edited."""
    res = tmp_path / "res"
    (res / "orb").mkdir(parents=True)
    (res / "orb" / "a.txt").write_text("1 0 0 0 0 0 0 1\n")
    named = {"results": res}
    record = run_record(["lorisnb", "report"], {"description": "d", "values": {}}, None,
                        checksums(input_files([res]), named), {}, [res], named, absolute=False)  # fmt: skip
    record.update(record_changes)
    folder = tmp_path / "run"
    folder.mkdir()
    write_run_json(folder, record)
    as_written(folder)
    return folder, res


def as_written(folder: Path) -> None:
    """The run marker lorisnb writes beside run.json, listing the folder's files as they are now: a
    run.json of named roots without it is a damaged run (its marker removed), which verify names."""
    from lorisnb.tools.report.build import _files, _write_marker

    _write_marker(folder, _files(folder))


@pytest.mark.parametrize(
    "edit, message",
    [
        ({"input_roots": ["/etc"]}, "outside the run folder"),
        ({"input_roots": ["/"]}, "outside the run folder"),
        ({"input_roots": ["{results}/../../../../etc"]}, "leaves its root {results}"),
        ({"inputs": {"/etc/passwd": "0" * 64}}, "outside the run folder"),
        ({"inputs": {"{data}/passwd": "0" * 64}}, "--data DIR"),
        ({"inputs": {"{etc}/passwd": "0" * 64}}, "--root etc DIR"),
    ],
)
def test_verify_refuses_roots_from_run_json_outside_those_it_was_given(tmp_path, capsys, monkeypatch, edit, message):
    folder, res = received(tmp_path, edit)
    opened = []
    real = Path.rglob
    monkeypatch.setattr(Path, "rglob", lambda self, pat: opened.append(self) or real(self, pat))
    with pytest.raises(ValidationError, match=message.replace("{", r"\{").replace("}", r"\}")):
        verify_run(folder, {"results": res})
    assert opened == []  # refused before any folder was walked
    rc, out, err = run(capsys, "verify", folder, "--results", res)
    assert rc == 2 and message in err and out == "" and "root:x:" not in err


def test_a_link_inside_a_root_to_a_file_outside_is_listed_not_read(tmp_path, capsys):
    folder, res = received(tmp_path, {})
    secret = tmp_path / "secret.txt"
    secret.write_text("private")
    os.symlink(secret, res / "orb" / "b.txt")
    assert verify_run(folder, {"results": res}) == [("{results}/orb/b.txt", "outside")]
    rc, out, _ = run(capsys, "verify", folder, "--results", res)
    assert rc == 1 and "outside: {results}/orb/b.txt" in out and "private" not in out


def test_make_portable_replaces_each_spelling_at_path_ends_only(tmp_path):
    root = tmp_path / "a b&c"
    root.mkdir()
    page = tmp_path / "run" / "page.html"
    page.parent.mkdir()
    import html

    page.write_text(f"{root}/x {html.escape(str(root))}/y {json.dumps(str(root))} {root}2/z")
    assert make_portable(page.parent, [("results", root)]) == [page]
    assert page.read_text() == f'{{results}}/x {{results}}/y "{{results}}" {root}2/z'
    # after a terminal colour code (a traceback's file line), raw or escaped in a notebook's JSON: replaced, the code kept
    coloured = f"\x1b[32m{root}/a.py \x1b[1;31m{root}/b.py"
    page.write_text(coloured + " " + json.dumps(coloured) + f" m{root}/c")
    assert make_portable(page.parent, [("results", root)]) == [page]
    kept = "\x1b[32m{results}/a.py \x1b[1;31m{results}/b.py"
    assert page.read_text() == kept + " " + json.dumps(kept) + f" m{root}/c"
    # what it leaves (after a letter: perhaps inside other data) is listed, for the report to say
    assert unreplaced(page.parent, [("results", root)]) == [page]
    page.write_text(kept + f" {root}2/z")
    assert unreplaced(page.parent, [("results", root)]) == []
    (page.parent / "f.png").write_bytes(b"\x89PNG\r\n\x1a\n\xff" + str(root).encode())
    with pytest.raises(OutputError, match="f.png: a binary file"):
        make_portable(page.parent, [("results", root)])
    assert root_key(root / "q" / "r.txt", {"results": root, "data": tmp_path}) == "{results}/q/r.txt"


@pytest.mark.thorough
def test_a_run_against_a_baseline_names_the_baseline_folder_by_its_root(tmp_path, data, icra20, monkeypatch):
    import lorisnb.tools.report.build as report

    here = lab(tmp_path / "lab", data, icra20)
    monkeypatch.setattr(report, "run_notebook", fake_notebook)
    common = dict(progress=False, results=here / "res")
    report.run_report(here / "earlier" / "r0", {"data_root": str(here / "data")}, ["compare_algorithms"], **common)
    out, _ = report.run_report(here / "runs" / "r1", {"data_root": str(here / "data")}, ["compare_algorithms"],
                               baseline=here / "earlier", command=["lorisnb", "report", "--baseline",
                                                                  str(here / "earlier")], **common)  # fmt: skip
    assert held_paths(out, [here, here / "earlier"]) == []
    assert "{baseline}" in (out / "run.json").read_text()


@pytest.mark.thorough
def test_a_run_with_no_comparable_baseline_is_written_and_says_so(tmp_path, data, icra20, monkeypatch):
    """The first run after an upgrade or a spec change (no earlier run comparable with it) was thrown
    away with exit 2 after its notebooks ran, every night (no run of the new kind was ever kept); it is
    written, its front page saying that nothing was judged and a new series starts; the next is judged."""
    import json

    import lorisnb.tools.report.build as report

    here = lab(tmp_path / "lab", data, icra20)
    monkeypatch.setattr(report, "run_notebook", fake_notebook)
    common = dict(progress=False, results=here / "res")
    report.run_report(here / "nightly" / "r0", {"data_root": str(here / "data"), "eps": 1.0}, ["compare_algorithms"],
                      **common)  # fmt: skip
    params = {"data_root": str(here / "data"), "eps": 2.0}  # another spec: r0 is no baseline
    out, _ = report.run_report(here / "nightly" / "r1", params, ["compare_algorithms"], baseline=here / "nightly",
                               **common)  # fmt: skip
    since = json.loads((out / "findings" / "since_baseline.json").read_text())
    assert since["baseline"] is None and "is comparable with it" in since["no_baseline"]
    assert (
        "No baseline:" in (out / "index.html").read_text() and "a new series starts" in (out / "index.html").read_text()
    )
    out2, _ = report.run_report(here / "nightly" / "r2", params, ["compare_algorithms"], baseline=here / "nightly",
                                **common)  # fmt: skip
    assert json.loads((out2 / "findings" / "since_baseline.json").read_text())["baseline"] == "r1"


@pytest.mark.thorough
def test_report_gate_exits_as_diff_judges_the_run_against_its_baseline(tmp_path, data, icra20, monkeypatch, capsys):
    """``report --baseline DIR`` exits for its notebooks and inputs only (a front page showing a
    regression exited 0); ``--gate`` makes its exit status diff's: 2 with nothing judged (a new
    series), 0 unchanged, 1 when a sequence was lost since the baseline; refused without --baseline."""
    import lorisnb.tools.report.build as report

    here = lab(tmp_path / "lab", data, icra20)
    monkeypatch.setattr(report, "run_notebook", fake_notebook)
    night = ["report", "--results", here / "res", "--data", here / "data", "--notebooks", "compare_algorithms",
             "--no-progress", "--baseline", here / "nightly", "--gate", "--out"]  # fmt: skip
    rc, _, err = run(capsys, *night[:-4], "--out", here / "nightly" / "r1")  # the first night: no baseline yet
    assert rc == 0, err
    (here / "nightly" / "h.csv").write_text("run,metric\n")  # no run: passed over, named
    rc, _, err = run(capsys, *night, here / "nightly" / "r2")
    assert rc == 0 and "gate: ok since the baseline r1" in err, err
    assert "h.csv" in (here / "nightly" / "r2" / "index.html").read_text()
    rc, _, err = run(capsys, *night[:-1], "-p", "eps", "2", "--out", here / "nightly" / "r3")  # another spec
    assert rc == 2 and "nothing judged" in err, err
    # the run's own folder by its path, not the literal {run} of its portable files
    assert "{run}" not in err and f"in {here / 'nightly' / 'r3'}" in err, err
    (here / "res" / "odom" / ODOM).unlink()  # tonight odom lost its sequence
    rc, _, err = run(capsys, *night, here / "nightly" / "r4")
    assert rc == 1 and "gate: regression since the baseline r2" in err, err
    rc, _, err = run(capsys, *night[:-4], "--gate", "--out", here / "nightly" / "r5")
    assert rc == 2 and "--gate" in err and "give --baseline" in err and not (here / "nightly" / "r5").exists()


def papermill_notebook(name, out_dir, params, **kw):
    """A notebook as papermill writes one: its parameters cell (non-ASCII as ``\\xe9``), papermill's
    ``input_path`` (where lorisnb is installed), a warning naming a file of lorisnb, and its HTML page
    with the path cut into spans at the escape, as nbconvert's highlighter cuts it."""
    import nbformat
    from papermill.translators import PythonTranslator

    from lorisnb.tools.report.build import notebook_dir
    from lorisnb.tools.report.notebooks import NotebookRun

    folder = out_dir / name
    folder.mkdir()
    literal = PythonTranslator.translate_str(str(params["results_dir"]))
    nb = nbformat.v4.new_notebook()
    nb.metadata["papermill"] = {"input_path": str(notebook_dir() / f"{name}.ipynb")}
    cell = nbformat.v4.new_code_cell(f"results_dir = {literal}")
    import lorisnb

    warning = f"{Path(lorisnb.__file__).parent / 'tools' / 'figures' / 'plotting.py'}:237: UserWarning: Glyph 27"
    cell.outputs = [nbformat.v4.new_output("stream", name="stderr", text=warning)]
    nb.cells = [cell]
    nbformat.write(nb, folder / f"{name}.ipynb")
    head, _, tail = literal.partition("\\x")
    (folder / f"{name}.html").write_text(f'<span class="s2">{head}</span><span class="se">\\x{tail[:2]}</span>'
                                         f'<span class="s2">{tail[2:]}</span>')  # fmt: skip
    return NotebookRun(name)


def test_a_run_names_no_path_spelled_by_papermill_cut_by_a_highlighter_or_of_lorisnb_itself(
    tmp_path, data, icra20, monkeypatch
):
    """A results folder below ``café`` (papermill writes ``caf\\xe9``; the page's highlighter cuts it
    there), papermill's ``input_path``, a warning's file of lorisnb: none of their absolute paths
    remains in the run (the page is rendered again from its portable notebook)."""
    import sys

    import lorisnb
    import lorisnb.tools.report.build as report

    here = lab(tmp_path / "café lab", data, icra20)
    monkeypatch.setattr(report, "run_notebook", papermill_notebook)
    out, _ = report.run_report(here / "runs" / "p", {"data_root": str(here / "data")}, ["compare_algorithms"],
                               progress=False, results=here / "res")  # fmt: skip
    install = Path(lorisnb.__file__).resolve().parents[1]
    assert held_paths(out, [here, install, Path(sys.prefix)]) == []
    page = (out / "compare_algorithms" / "compare_algorithms.html").read_text()
    assert "{results}" in page and "caf" not in page  # rendered again from the notebook, not a fragment left
    nb = (out / "compare_algorithms" / "compare_algorithms.ipynb").read_text()
    assert "{lorisnb}/lorisnb/tools/figures/plotting.py" in nb and '"input_path": "{lorisnb}/' in nb
    for p in (x for x in out.rglob("*") if x.is_file()):
        assert b"caf\\xe9" not in p.read_bytes() and b"caf\\\\xe9" not in p.read_bytes(), p


def test_links_on_the_way_are_kept_in_run_json_and_the_run_verifies_where_it_was_made(
    tmp_path, data, icra20, monkeypatch, capsys
):
    """An algorithm folder linked into the results folder, and a data root whose ``openloris-scene`` is a
    link: run.json names their files where they were found ({results}/odom/..., {data}/openloris-scene/...),
    no path of the machine (it named them by the absolute paths the links lead to, which verify then
    refused on the machine that made the run). verify there lists what the links lead out to as
    'outside', unread, until the folders they lead to are named with --root, as for any link."""
    import lorisnb.tools.report.build as report

    here = lab(tmp_path / "lab", data, icra20)
    (here / "elsewhere").mkdir()
    shutil.move(here / "res" / "odom", here / "elsewhere" / "odom")
    (here / "res" / "odom").symlink_to(here / "elsewhere" / "odom", target_is_directory=True)
    (here / "data2").mkdir()
    (here / "data2" / "openloris-scene").symlink_to(here / "data" / "openloris-scene", target_is_directory=True)
    monkeypatch.setattr(report, "run_notebook", fake_notebook)
    rc, _, err = run(capsys, "report", "--results", here / "res", "--data", here / "data2", "--out", here / "r",
                     "--notebooks", "compare_algorithms", "--no-progress")  # fmt: skip
    assert rc == 0, err
    record = json.loads((here / "r" / "run.json").read_text())
    assert "{results}/odom/" + ODOM in record["inputs"] and "{results}/orb/" + ORB in record["inputs"]
    assert "{data}/openloris-scene/groundtruth/gt_cafe_1.txt" in record["inputs"]
    assert all(k.startswith("{") for k in [*record["inputs"], *record["input_roots"]]), record["input_roots"]
    assert held_paths(here / "r", [here]) == []
    rc, out, err = run(capsys, "verify", here / "r", "--data", here / "data", "--results", here / "res")
    assert rc == 1 and out.strip() == "outside: {results}/odom/" + ODOM and "--root NAME DIR" in err, out + err
    mine = ["--root", "odom", here / "elsewhere", "--root", "scene", here / "data" / "openloris-scene"]
    rc, out, err = run(capsys, "verify", here / "r", "--data", here / "data2", "--results", here / "res", *mine)
    assert rc == 0 and "all 7 input file(s) unchanged" in err, out + err
    (here / "elsewhere" / "odom" / ODOM).write_text("1 2 3\n")  # changed where the link leads: seen
    (here / "data" / "openloris-scene" / "groundtruth" / "gt_new.txt").write_text("1\n")
    rc, out, err = run(capsys, "verify", here / "r", "--data", here / "data2", "--results", here / "res", *mine)
    lines = out.split("\n")
    assert rc == 1 and "changed: {results}/odom/" + ODOM in lines, out
    assert "added: {data}/openloris-scene/groundtruth/gt_new.txt" in lines, out


def test_a_report_of_a_manifest_records_it_and_its_ground_truth_below_roots_of_their_own(tmp_path, data):
    """-p manifest /abs/lab.toml: the manifest and its sessions' ground truth are inputs, named below
    {manifest} and {sessions}, not by their absolute paths."""
    from lorisnb.tools.report.notebooks import input_roots
    from lorisnb.tools.report.portable import named_roots

    folder = tmp_path / "m"
    folder.mkdir()
    shutil.copy(data.root / "tum-rgbd" / "fr2_desk_groundtruth.txt", folder / "gt.txt")
    (folder / "lab.toml").write_text('[[session]]\nname = "desk"\ngroundtruth = "gt.txt"\n')
    params = {"manifest": str(folder / "lab.toml"), "path": str(tmp_path / "est")}
    (tmp_path / "est").mkdir()
    roots = input_roots(["evaluate_my_results"], params, None, None)
    assert folder / "lab.toml" in roots and folder / "gt.txt" in roots
    named = named_roots(params, None, None, None)
    keys = checksums(input_files(roots, resolve=False), named)
    assert set(keys) == {"{manifest}/lab.toml", "{manifest}/gt.txt"}
    assert named_roots({"manifest": "euroc-vicon-room1"}, None, None, None).get("manifest") is None


def test_a_run_verifies_against_a_copy_that_spells_its_names_in_another_unicode_form(
    tmp_path, data, icra20, monkeypatch, capsys
):
    """A results folder ``algé`` written in NFD (a Mac), copied by a tool that writes NFC: the same
    files, not one missing and one added with names that look alike."""
    import unicodedata

    import lorisnb.tools.report.build as report

    here = lab(tmp_path / "lab", data, icra20)
    nfd, nfc = (unicodedata.normalize(f, "algé") for f in ("NFD", "NFC"))
    shutil.move(here / "res" / "orb", here / "res" / nfd)
    monkeypatch.setattr(report, "run_notebook", fake_notebook)
    rc, _, err = run(capsys, "report", "--results", here / "res", "--data", here / "data", "--out", here / "r",
                     "--notebooks", "compare_algorithms", "--no-progress")  # fmt: skip
    assert rc == 0, err
    shutil.move(here / "res" / nfd, here / "res" / nfc)
    rc, out, err = run(capsys, "verify", here / "r", "--data", here / "data", "--results", here / "res")
    assert rc == 0 and "all 7 input file(s) unchanged" in err, out + err
    (here / "res" / nfc / ORB).write_text("1 2 3\n")
    rc, out, err = run(capsys, "verify", here / "r", "--data", here / "data", "--results", here / "res")
    assert rc == 1 and out.strip() == f"changed: {{results}}/{nfd}/{ORB}", out


def test_messages_name_what_the_user_gave_and_what_they_can_do(tmp_path, data, icra20, monkeypatch, capsys):
    """--out below a file names --out (not the temporary folder lorisnb would have written into);
    render of a run with an edited page says what render can do (it has no --out); verify without
    --data says it does not read LORISNB_DATA."""
    import lorisnb.tools.report.build as report

    here = lab(tmp_path / "lab", data, icra20)
    monkeypatch.setattr(report, "run_notebook", fake_notebook)
    (here / "afile").write_text("x")
    rc, _, err = run(capsys, "report", "--results", here / "res", "--data", here / "data", "--out",
                     here / "afile" / "r", "--notebooks", "compare_algorithms", "--no-progress")  # fmt: skip
    assert rc == 2 and f"--out {here / 'afile' / 'r'}: cannot write into" in err and ".partial" not in err, err
    rc, _, err = run(capsys, "report", "--results", here / "res", "--data", here / "data", "--out", here / "r",
                     "--notebooks", "compare_algorithms", "--no-progress")  # fmt: skip
    assert rc == 0, err
    page = here / "r" / "compare_algorithms" / "compare_algorithms.html"
    page.write_text(page.read_text() + "<p>mine</p>")
    rc, _, err = run(capsys, "render", here / "r")
    assert rc == 2 and "compare_algorithms.html" in err and "render a copy of the run" in err and "--out" not in err
    monkeypatch.setenv("LORISNB_DATA", str(here / "data"))
    rc, _, err = run(capsys, "verify", here / "r", "--results", here / "res")
    assert rc == 2 and "--data DIR" in err and "not from LORISNB_DATA" in err


def test_a_reports_input_errors_name_each_input_by_its_root_not_as_typed(tmp_path, monkeypatch, data):
    """``findings/input_errors.csv`` named an input as typed (``res/alg/x.txt``, relative to where
    the command ran): once the run is moved that names nothing. By its root's name, as run.json."""
    import lorisnb as ln
    from lorisnb.tools.report.build import _by_root

    monkeypatch.chdir(tmp_path)
    (tmp_path / "res" / "alg").mkdir(parents=True)
    (tmp_path / "res" / "alg" / "cafe_1_1.txt").write_text("scene: cafe\nseq: 1\n1 2\n")
    ev = ln.evaluate("res", data_root=data.root, jobs=1, progress=False)
    table = _by_root(ev.failures_table(), {"results": tmp_path / "res", "data": data.root})
    assert list(table["file"]) == ["{results}/alg/cafe_1_1.txt"]
    assert table["error"][0].startswith("{results}/alg/cafe_1_1.txt, line 3: ")


def test_verify_refuses_a_root_given_twice_with_two_folders(tmp_path, capsys):
    """``--root NAME DIR`` twice with two folders: the last won silently (exit 0 or 1 by the order);
    refused, as ``--data A --data B``. (A name of one's own is a folder a link may lead into.)"""
    folder, res = received(tmp_path, {})
    other = tmp_path / "other"
    other.mkdir()
    rc, _, err = run(capsys, "verify", folder, "--root", "results", res, "--root", "results", other)
    assert rc == 2 and "--root results given twice" in err
    rc, _, err = run(capsys, "verify", folder, "--root", "results", res, "--root", "results", res)  # the same twice
    assert rc == 0, err


def quoting_notebook(name, out_dir, params, **kw):
    """A notebook as papermill and nbconvert write one for a folder whose path holds quotes: the parameters
    cell (``"`` as ``\\"``), its JSON in the .ipynb, the page's highlighted code (``&`` escaped, ``'`` and
    ``"`` not: ``html.escape(quote=False)``), an output printing the path's ``repr``, JSON in the page."""
    import html

    import nbformat
    from papermill.translators import PythonTranslator

    from lorisnb.tools.report.notebooks import NotebookRun

    folder = out_dir / name
    folder.mkdir()
    path = str(params["results_dir"])
    literal = PythonTranslator.translate_str(path)
    nb = nbformat.v4.new_notebook()
    cell = nbformat.v4.new_code_cell(f"results_dir = {literal}")
    cell.outputs = [nbformat.v4.new_output("stream", name="stdout", text=repr([path]))]
    nb.cells = [cell]
    nbformat.write(nb, folder / f"{name}.ipynb")
    (folder / f"{name}.html").write_text(
        f"<pre>results_dir = {html.escape(literal, quote=False)}</pre><pre>{html.escape(repr([path]), quote=False)}"
        f"</pre><a title='{html.escape(path, quote=True)}'></a><script>{html.escape(json.dumps({'p': path}))}</script>"
        f"<pre>{path.replace('&', '&#38;').replace(chr(39), '&#39;').replace(chr(34), '&#34;')}</pre>"
    )
    return NotebookRun(name)


@pytest.mark.parametrize("odd", ["x&'", 'dq"x', "a<b>&c'd\"e\\f"])
def test_a_folder_whose_path_holds_quotes_and_ampersands_leaves_no_spelling_of_it(
    tmp_path, data, icra20, monkeypatch, odd
):
    """A folder ``/tmp/x&'/...``: nbconvert escapes ``&`` and leaves ``'``; papermill writes ``"`` as ``\\"``
    (``\\\\\\"`` in the notebook's JSON). Every spelling a run's files give the path is replaced, and
    unreplaced() lists a form no escaping it knows spells (so that the report warns)."""
    import warnings

    import lorisnb.tools.report.build as report
    from lorisnb.tools.report.portable import _pattern

    here = lab(tmp_path / odd, data, icra20)
    monkeypatch.setattr(report, "run_notebook", quoting_notebook)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no "still show an absolute path" warning
        out, _ = report.run_report(here / "runs" / "p", {"data_root": str(here / "data")}, ["compare_algorithms"],
                                   progress=False, results=here / "res")  # fmt: skip
    page = (out / "compare_algorithms" / "compare_algorithms.html").read_text()
    assert page.count("{results}") == 5, page
    assert held_paths(out, [here]) == [] and unreplaced(out, [("lab", here)]) == []
    for p in (x for x in out.rglob("*") if x.is_file()):
        assert str(tmp_path).encode() not in p.read_bytes(), p
    # an escaping no spelling knows (a made-up one): still listed, the path's plain parts around it
    strange = str(here).replace("&", "\\u0026").replace("'", "&apos;").replace('"', "&QUOT;").replace("<", "%3c")
    (out / "odd.txt").write_text(f"see {strange}/res")
    assert unreplaced(out, [("lab", here)]) == [out / "odd.txt"]
    pattern, _ = _pattern([("lab", here)])
    for s in spellings(here):  # each spelling listed is one make_portable replaces, whole
        m = pattern.match(s.encode())
        assert m and m.end() == len(s.encode()), s


def failing_link_notebook(name, out_dir, params, **kw):
    """A notebook that, as compare_algorithms does, writes its input errors: one about a file linked from
    outside the results folder, naming where it leads (JSON in the notebook, HTML in the page, CSV)."""
    import html

    from lorisnb.tools.report.notebooks import NotebookRun

    folder = out_dir / name
    folder.mkdir()
    target = (Path(str(params["results_dir"])) / "orb" / "cafe_1_2_bad.txt").resolve()
    error = f"x.txt, line 3: not a trajectory file as expected (a link to {target}, outside the results folder: its content is not shown)"  # fmt: skip
    (folder / f"{name}.ipynb").write_text(json.dumps({"cells": [{"outputs": [{"text": error}]}]}))
    (folder / f"{name}.html").write_text(f"<pre>{html.escape(error)}</pre>")
    (folder / "input_errors.csv").write_text(f'file,error\nx.txt,"{error}"\n')
    return NotebookRun(name)


def test_an_error_about_a_link_leading_out_of_the_results_folder_does_not_say_where_it_leads(
    tmp_path, data, icra20, monkeypatch
):
    """A file linked into --results from elsewhere that fails to parse: its error said ``(a link to
    /abs/elsewhere/bad.txt, outside the results folder ...)`` in index.html, report.html and the input
    errors' tables of the portable run, and no warning. It says ``a link leading outside``; had any page
    kept the path, the report would have warned."""
    import warnings

    import lorisnb.tools.report.build as report
    import lorisnb.tools.report.portable as portable

    here = lab(tmp_path / "lab", data, icra20)
    (here / "elsewhere").mkdir()
    bad = here / "elsewhere" / "bad.txt"
    bad.write_text("seq: 1\n1.0 0 0 0 0 0 0 1\nGARBAGE\n")
    (here / "res" / "orb" / "cafe_1_2_bad.txt").symlink_to(bad)
    monkeypatch.setattr(report, "run_notebook", failing_link_notebook)
    params = {"data_root": str(here / "data")}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out, _ = report.run_report(here / "runs" / "p", params, ["compare_algorithms"], progress=False,
                                   results=here / "res")  # fmt: skip
    errors = (out / "findings" / "input_errors.csv").read_text()
    assert "{results}/orb/cafe_1_2_bad.txt" in errors and "(a link leading outside the results folder" in errors
    for p in (x for x in out.rglob("*") if x.is_file()):
        assert str(here).encode() not in p.read_bytes(), p
    assert "a link leading outside" in (out / "index.html").read_text()
    monkeypatch.setattr(portable, "hide_link_targets", lambda data: data)  # as before: the path left in the pages
    with pytest.warns(UserWarning, match="still show an absolute path") as caught:
        report.run_report(here / "runs" / "q", params, ["compare_algorithms"], progress=False, results=here / "res")
    assert "index.html" in str(caught[0].message) and "input_errors.csv" in str(caught[0].message)


def test_results_given_as_a_link_holding_a_linked_algorithm_folder_records_it_where_it_is(
    tmp_path, data, icra20, monkeypatch, capsys
):
    """``--results reslink`` (a link to ``res``) holding ``algC``, a folder linked from elsewhere: run.json
    named algC's files by the absolute path the link leads to, and verify refused the run (exit 2) where it
    was made. They are ``{results}/odom/...``, listed by verify as ``outside`` (exit 1), as for any link."""
    import lorisnb.tools.report.build as report

    here = lab(tmp_path / "lab", data, icra20)
    (here / "elsewhere").mkdir()
    shutil.move(here / "res" / "odom", here / "elsewhere" / "odom")
    (here / "res" / "odom").symlink_to(here / "elsewhere" / "odom", target_is_directory=True)
    (here / "reslink").symlink_to("res", target_is_directory=True)
    monkeypatch.setattr(report, "run_notebook", fake_notebook)
    rc, _, err = run(capsys, "report", "--results", here / "reslink", "--data", here / "data", "--out", here / "r",
                     "--notebooks", "compare_algorithms", "--no-progress")  # fmt: skip
    assert rc == 0 and "still show an absolute path" not in err, err
    record = json.loads((here / "r" / "run.json").read_text())
    assert "{results}/odom/" + ODOM in record["inputs"] and "{results}/orb/" + ORB in record["inputs"]
    assert all(k.startswith("{") for k in [*record["inputs"], *record["input_roots"]]), record
    assert held_paths(here / "r", [here]) == []
    for results in ("reslink", "res"):
        rc, out, err = run(capsys, "verify", here / "r", "--data", here / "data", "--results", here / results)
        assert rc == 1 and out.strip() == "outside: {results}/odom/" + ODOM, out + err
    rc, out, err = run(capsys, "verify", here / "r", "--data", here / "data", "--results", here / "reslink",
                       "--root", "odom", here / "elsewhere")  # fmt: skip
    assert rc == 0 and "all 7 input file(s) unchanged" in err, out + err


@pytest.mark.parametrize("full_at", ["compare_algorithms.html", "report.html", ".lorisnb-run"])
def test_render_on_a_full_disk_leaves_the_run_as_it_was_names_the_page_and_renders_once_freed(
    tmp_path, data, icra20, monkeypatch, capsys, full_at
):
    """``lorisnb render`` on a full disk left report.html cut short, said "an output (the system named
    no file)", and refused the run afterwards (its marker listed the pages as they were). Every page is
    written whole or not at all, the error names it, and once space is freed render renders the run."""
    import errno

    import lorisnb.tools.report.build as report

    here = lab(tmp_path / "lab", data, icra20)
    monkeypatch.setattr(report, "run_notebook", papermill_notebook)
    rc, _, err = run(capsys, "report", "--results", here / "res", "--data", here / "data", "--out", here / "r",
                     "--notebooks", "compare_algorithms", "--no-progress")  # fmt: skip
    assert rc == 0, err
    r = here / "r"
    before = {p: p.read_bytes() for p in r.rglob("*") if p.is_file()}
    (r / "report.html").unlink()
    real_write = Path.write_text

    def full(self, text, *a, **kw):  # the disk fills while this file is written: half of it, then ENOSPC
        if full_at in self.name:
            real_write(self, text[: len(text) // 2], *a, **kw)
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real_write(self, text, *a, **kw)

    monkeypatch.setattr(Path, "write_text", full)
    rc, _, err = run(capsys, "render", r)
    shown = {"compare_algorithms.html": "compare_algorithms.html", "report.html": "report.html"}.get(full_at, full_at)
    assert rc == 2 and f"{shown}: No space left on device" in err and "the system named no file" not in err, err
    after = {p: p.read_bytes() for p in r.rglob("*") if p.is_file()}
    assert after == {p: b for p, b in before.items() if p.name != "report.html"}  # as it was: nothing cut, no temp
    monkeypatch.setattr(Path, "write_text", real_write)
    rc, out, err = run(capsys, "render", r)
    assert rc == 0 and "report.html" in out, err
    assert (r / "report.html").read_bytes() == before[r / "report.html"]
    rc, _, err = run(capsys, "render", r)  # and again: the marker lists what render wrote
    assert rc == 0, err


def test_a_relative_out_names_the_notebooks_output_path_by_the_runs_root(tmp_path, data, icra20, monkeypatch, capsys):
    """``--out place/r1`` (relative): papermill's ``output_path`` kept the temporary build folder's name
    (``place/.r1.partial-XXXX/...``); it is ``{run}/...`` as with an absolute --out."""
    import lorisnb.tools.report.build as report

    def with_output_path(name, out_dir, params, **kw):
        import nbformat

        from lorisnb.tools.report.notebooks import NotebookRun

        (out_dir / name).mkdir()
        nb = nbformat.v4.new_notebook()
        nb.metadata["papermill"] = {"output_path": str(out_dir / name / f"{name}.ipynb")}
        nbformat.write(nb, out_dir / name / f"{name}.ipynb")
        (out_dir / name / f"{name}.html").write_text("<p>page</p>")
        return NotebookRun(name)

    here = lab(tmp_path / "lab", data, icra20)
    monkeypatch.setattr(report, "run_notebook", with_output_path)
    monkeypatch.chdir(here)
    rc, _, err = run(capsys, "report", "--results", "res", "--data", "data", "--out", "place/r1", "--notebooks",
                     "compare_algorithms", "--no-progress")  # fmt: skip
    assert rc == 0, err
    nb = json.loads((here / "place" / "r1" / "compare_algorithms" / "compare_algorithms.ipynb").read_text())
    assert nb["metadata"]["papermill"]["output_path"] == "{run}/compare_algorithms/compare_algorithms.ipynb"
    for p in (x for x in (here / "place").rglob("*") if x.is_file()):
        assert b".partial-" not in p.read_bytes(), p


@pytest.mark.parametrize(
    "full_at",
    ["parameters.json", "run.json", "index.html", "report.html", "compare_algorithms/compare_algorithms.ipynb",
     "findings/sequences.csv", "findings/leaderboard.csv"],
)  # fmt: skip
def test_report_on_a_full_disk_names_the_file_it_could_not_write(tmp_path, data, icra20, monkeypatch, capsys, full_at):
    """``lorisnb report`` on a full disk said ``error: r: No space left on device`` (the run folder:
    write() names no file, and a file of the temporary folder was renamed to the run folder). Every
    write of the report names its file, where it goes in the run folder, as render names its page."""
    import errno

    import lorisnb.io.writers as writers
    import lorisnb.tools.report.build as report

    here = lab(tmp_path / "lab", data, icra20)
    monkeypatch.setattr(report, "run_notebook", fake_notebook)
    name = Path(full_at).name

    def enospc():
        return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))  # as write() raises it: no file named

    real_text, real_bytes = Path.write_text, Path.write_bytes

    def full_text(self, text, *a, **kw):
        if name in self.name and not name.endswith(".ipynb"):  # (the notebook, as it ran: its entry says so)
            raise enospc()
        return real_text(self, text, *a, **kw)

    def full_bytes(self, data, *a, **kw):
        if name in self.name:
            raise enospc()
        return real_bytes(self, data, *a, **kw)

    def full_open(file, *a, **kw):
        if name in os.fspath(file):
            raise enospc()
        return open(file, *a, **kw)

    monkeypatch.setattr(Path, "write_text", full_text)
    monkeypatch.setattr(Path, "write_bytes", full_bytes)
    monkeypatch.setattr(writers, "open", full_open, raising=False)
    rc, _, err = run(capsys, "report", "--results", here / "res", "--data", here / "data", "--out", here / "r",
                     "--notebooks", "compare_algorithms", "--no-progress")  # fmt: skip
    expected = str(here / "r" / Path(full_at))
    assert rc == 2 and f"error: {expected}: No space left on device" in err, err
    assert ".partial-" not in err and not (here / "r").exists()
    assert not [p for p in here.iterdir() if ".partial-" in p.name]  # nothing left behind


@pytest.mark.parametrize("printed", ["parent", "quote_plus", "quote"])
def test_a_page_showing_the_folder_above_a_root_or_a_root_url_quoted_is_warned_about(
    tmp_path, data, icra20, monkeypatch, capsys, printed
):
    """A notebook printing ``os.path.dirname(results_dir)`` (the author's folder above the root) or
    ``urllib.parse.quote_plus(results_dir)`` left the author's path in the run with no warning."""
    from urllib.parse import quote, quote_plus

    import lorisnb.tools.report.build as report
    from lorisnb.tools.report.notebooks import NotebookRun

    here = lab(tmp_path / "lab", data, icra20)
    show = {"parent": os.path.dirname, "quote_plus": quote_plus, "quote": lambda s: quote(s, safe="")}[printed]

    def leaks(name, out_dir, params, **kw):
        (out_dir / name).mkdir()
        text = show(str(params["results_dir"]))
        (out_dir / name / f"{name}.ipynb").write_text(json.dumps({"cells": [{"outputs": [{"text": text}]}]}))
        (out_dir / name / f"{name}.html").write_text(f"<pre>{text}</pre>")
        return NotebookRun(name)

    monkeypatch.setattr(report, "run_notebook", leaks)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        out, _ = report.run_report(here / "r", {"data_root": str(here / "data")}, ["compare_algorithms"],
                                   progress=False, results=here / "res")  # fmt: skip
    said = [str(w.message) for w in caught if "still show an absolute path" in str(w.message)]
    assert said and "compare_algorithms/compare_algorithms.html" in said[0], [str(w.message) for w in caught]
    monkeypatch.setattr(report, "run_notebook", fake_notebook)  # the roots themselves: replaced, nothing said
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        report.run_report(here / "r2", {"data_root": str(here / "data")}, ["compare_algorithms"], progress=False,
                          results=here / "res")  # fmt: skip
    assert not [w for w in caught if "still show an absolute path" in str(w.message)]


def test_control_and_bidi_characters_of_a_name_are_shown_escaped_on_the_pages_and_kept_in_the_tables(
    tmp_path, data, icra20, monkeypatch
):
    """An algorithm folder named with ESC, a right-to-left override and a CR: index.html and
    report.html held them raw (a cell shown reversed, text hidden). The pages show them escaped as
    the terminal does (``\\x1b``, ``\\u202e``, ``\\r``); the findings tables (data) keep the name as it is."""
    import lorisnb.tools.report.build as report

    here = lab(tmp_path / "lab", data, icra20)
    odd = "o\x1b[31mr\u202eb\rx"
    (here / "res" / "orb").rename(here / "res" / odd)
    monkeypatch.setattr(report, "run_notebook", fake_notebook)
    out, _ = report.run_report(here / "r", {"data_root": str(here / "data")}, ["compare_algorithms"],
                               progress=False, results=here / "res")  # fmt: skip
    for page in ("index.html", "report.html"):
        text = (out / page).read_text(encoding="utf-8")
        assert "\x1b" not in text and "\u202e" not in text and "\r" not in text, page
        assert "o\\x1b[31mr\\u202eb\\rx" in text, page
    import pandas as pd

    assert odd in set(pd.read_csv(out / "findings" / "sequences.csv")["algorithm"])


@pytest.mark.thorough
def test_verify_tells_a_baseline_changed_since_the_verdict(tmp_path, data, icra20, monkeypatch, capsys):
    """A run made against a baseline records the files its verdict read (the earlier run's run.json
    and tables) below ``{baseline}``; ``verify --root baseline DIR`` tells one edited since (the
    verdict may no longer hold), and without that root verify says they are not checked."""
    import lorisnb.tools.report.build as report

    here = lab(tmp_path / "lab", data, icra20)
    monkeypatch.setattr(report, "run_notebook", fake_notebook)
    night = ["report", "--results", here / "res", "--data", here / "data", "--notebooks", "compare_algorithms",
             "--no-progress", "--baseline", here / "nightly", "--out"]  # fmt: skip
    assert run(capsys, *night[:-3], "--out", here / "nightly" / "r1")[0] == 0  # the first night: no baseline yet
    rc, _, err = run(capsys, *night, here / "nightly" / "r2")
    assert rc == 0, err
    record = json.loads((here / "nightly" / "r2" / "run.json").read_text())
    base = record["baseline_inputs"]
    assert record["roots"]["baseline"] is None and record["roots"]["results"] is None
    assert {"{baseline}/r1/run.json", "{baseline}/r1/findings/sequences.csv"} <= set(base), base
    from lorisnb.tools.report.provenance import sha256

    assert base["{baseline}/r1/findings/sequences.csv"] == sha256(
        here / "nightly" / "r1" / "findings" / "sequences.csv"
    )
    roots = ["--data", here / "data", "--results", here / "res"]
    rc, _, err = run(capsys, "verify", here / "nightly" / "r2", *roots)
    n = len(record["inputs"])
    assert rc == 0 and f"{len(base)} file(s) of the earlier run" in err and "--root baseline DIR" in err, err
    assert f"all {n} input file(s) unchanged" in err
    rc, _, err = run(capsys, "verify", here / "nightly" / "r2", *roots, "--root", "baseline", here / "nightly")
    assert rc == 0 and f"all {n + len(base)} input file(s) unchanged" in err, err
    table = here / "nightly" / "r1" / "findings" / "sequences.csv"
    table.write_text(table.read_text().replace("orb", "orb2", 1))  # the baseline edited since the verdict
    rc, out, err = run(capsys, "verify", here / "nightly" / "r2", *roots, "--root", "baseline", here / "nightly")
    assert rc == 1 and "changed: {baseline}/r1/findings/sequences.csv" in out, out + err
    moved = tmp_path / "elsewhere"  # the folder of runs moved: verified there, the baseline found by its root
    shutil.move(here / "nightly", moved)
    rc, out, err = run(capsys, "verify", moved / "r2", *roots, "--root", "baseline", moved)
    assert rc == 1 and "changed: {baseline}/r1/findings/sequences.csv" in out and str(here) not in out + err
    (moved / "r1" / "run.json").unlink()
    rc, out, _ = run(capsys, "verify", moved / "r2", *roots, "--root", "baseline", moved)
    assert rc == 1 and "missing: {baseline}/r1/run.json" in out


@pytest.mark.thorough
def test_a_run_made_from_a_notebook_records_the_python_call_not_the_kernels_paths(tmp_path, data, icra20, monkeypatch):
    """``run_report`` called in a Jupyter kernel (no ``command`` given): run.json records ``python``
    and the launcher's name, not ``sys.argv``, which holds this machine's paths (the kernel's
    connection file): every run made from a notebook warned that it shows an absolute path."""
    import sys

    import lorisnb.tools.report.build as report

    here = lab(tmp_path / "lab", data, icra20)
    runtime = tmp_path / "home" / ".local" / "share" / "jupyter" / "runtime"
    argv = [str(tmp_path / "venv" / "ipykernel_launcher.py"), "-f", str(runtime / "kernel-1a2b.json")]
    monkeypatch.setattr(sys, "argv", argv)
    monkeypatch.setattr(report, "run_notebook", fake_notebook)
    with warnings.catch_warnings():
        warnings.simplefilter("error", LorisWarning)
        out, _ = report.run_report(here / "runs" / "k", {"data_root": str(here / "data")}, ["compare_algorithms"],
                                   progress=False, results=here / "res")  # fmt: skip
    assert json.loads((out / "run.json").read_text())["command"] == ["python", "ipykernel_launcher.py"]
    assert held_paths(out, [tmp_path]) == []
    monkeypatch.setattr(sys, "argv", ["-c"])
    assert report.python_call() == ["python"]
