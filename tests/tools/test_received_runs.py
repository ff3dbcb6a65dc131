"""A run folder received from someone else, or made from a results folder holding links: every
input keyed where it is (a link to a file elsewhere writes no absolute path into run.json); verify
lists a link leading outside the roots it was given as 'outside' (never reads it, never walks a
folder it leads to); render, diff and history read and write nothing through a link in the run
folder that leads outside it; run.json paths with a NUL byte are refused as a malformed run.json,
naming it."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest
from helpers import run_cli as run
from report_fixtures import fake_notebook
from test_portable_runs import as_written
from test_portable_runs import received as portable_run

from lorisnb.errors import LorisError, ParseError, ValidationError
from lorisnb.tools.decisions.runs import load_run
from lorisnb.tools.report.provenance import verify_run, write_run_json

ORB = "cafe_1_1_orbslam2-original.txt"
ODOM = "cafe-1-2-odom.txt"


@pytest.fixture(scope="module")
def made(tmp_path_factory, data, icra20):
    """A report run of a results folder whose odom file is a link to a file kept elsewhere."""
    import lorisnb.tools.report.build as report

    here = tmp_path_factory.mktemp("lab")
    (here / "res" / "orb").mkdir(parents=True)
    (here / "res" / "odom").mkdir()
    (here / "kept").mkdir()
    shutil.copy(icra20 / "per-seq" / "orbslam2_rgbd" / ORB, here / "res" / "orb" / ORB)
    shutil.copy(icra20 / "per-seq" / "odom" / ODOM, here / "kept" / ODOM)
    os.symlink(here / "kept" / ODOM, here / "res" / "odom" / ODOM)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(report, "run_notebook", fake_notebook)
        out, _ = report.run_report(here / "runs" / "r1", {"data_root": str(data.root)}, ["compare_algorithms"],
                                   progress=False, results=here / "res")  # fmt: skip
    return here, out


def test_a_linked_input_is_keyed_where_it_is_and_verified_only_where_its_folder_is_given(made, data, capsys):
    here, out = made
    text = (out / "run.json").read_text()
    record = json.loads(text)
    assert "{results}/odom/" + ODOM in record["inputs"] and "{results}/orb/" + ORB in record["inputs"]
    assert str(here) not in text and str(here.resolve()) not in text  # no absolute path of this machine
    roots = {"data": data.root, "results": here / "res"}
    assert verify_run(out, roots) == [("{results}/odom/" + ODOM, "outside")]  # leads out: not read
    assert verify_run(out, {**roots, "kept": here / "kept"}) == []
    rc, stdout, err = run(capsys, "verify", out, "--data", data.root, "--results", here / "res")
    assert rc == 1 and stdout.strip() == "outside: {results}/odom/" + ODOM and "--root NAME DIR" in err
    rc, _, err = run(capsys, "verify", out, "--data", data.root, "--results", here / "res", "--root", "kept",
                     here / "kept")  # fmt: skip
    assert rc == 0 and "unchanged" in err


def received(tmp_path, inputs_below_res, input_roots=("{results}",)):
    """A run folder as received (run.json of a results folder ``res``), its results folder here,
    with inputs and folders it read added to its run.json."""
    folder, res = portable_run(tmp_path, {})
    record = json.loads((folder / "run.json").read_text())
    record["inputs"].update({"{results}/" + k: "0" * 64 for k in inputs_below_res})
    record["input_roots"] = list(input_roots)
    write_run_json(folder, record)
    as_written(folder)
    return folder, res


def test_a_recorded_input_that_is_a_link_leading_out_here_is_listed_outside_not_refused(tmp_path, capsys):
    secret = tmp_path / "private" / "b.txt"
    secret.parent.mkdir()
    secret.write_text("private words")
    folder, res = received(tmp_path, ["orb/b.txt"])
    os.symlink(secret, res / "orb" / "b.txt")  # the receiver keeps that result elsewhere
    assert verify_run(folder, {"results": res}) == [("{results}/orb/b.txt", "outside")]
    rc, out, err = run(capsys, "verify", folder, "--results", res)
    assert rc == 1 and out == "outside: {results}/orb/b.txt\n" and "private" not in out + err
    assert verify_run(folder, {"results": res, "mine": secret.parent}) == [("{results}/orb/b.txt", "changed")]


def test_a_folder_it_read_that_leads_out_is_not_walked(tmp_path, capsys):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "names-of-private-files.txt").write_text("x")
    folder, res = received(tmp_path, [], input_roots=("{results}", "{results}/sub"))
    os.symlink(elsewhere, res / "sub")
    assert verify_run(folder, {"results": res}) == [("{results}/sub", "outside")]
    rc, out, _ = run(capsys, "verify", folder, "--results", res)
    assert rc == 1 and out == "outside: {results}/sub\n"  # its files are not listed


def test_a_folder_link_added_since_the_run_that_leads_out_is_listed_outside(tmp_path, capsys):
    """A folder of estimates linked into the results folder after the run, from outside the roots:
    listed 'outside' (exit 1) as a file link is, never walked; with its folder named, its files are
    'added'. A hidden one is passed over as hidden files are."""
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "names-of-private-files.txt").write_text("x")
    folder, res = received(tmp_path, [])
    assert verify_run(folder, {"results": res}) == []
    os.symlink(elsewhere, res / ".hidden")
    assert verify_run(folder, {"results": res}) == []
    os.symlink(elsewhere, res / "alg2")
    assert verify_run(folder, {"results": res}) == [("{results}/alg2", "outside")]
    rc, out, err = run(capsys, "verify", folder, "--results", res)
    assert rc == 1 and out == "outside: {results}/alg2\n" and "names-of-private" not in out + err
    assert verify_run(folder, {"results": res, "ext": elsewhere}) == [
        ("{results}/alg2/names-of-private-files.txt", "added")
    ]


@pytest.mark.parametrize("where", ["inputs", "input_roots", "data_root"])
def test_a_path_with_a_nul_byte_in_run_json_is_a_malformed_run_json(tmp_path, capsys, where):
    folder, res = received(tmp_path, [])
    record = json.loads((folder / "run.json").read_text())
    bad = "{results}/a\x00b"
    if where == "inputs":
        record["inputs"][bad] = "0" * 64
    elif where == "input_roots":
        record["input_roots"].append(bad)
    else:
        record["data_root"] = bad
    (folder / "run.json").write_text(json.dumps(record))
    with pytest.raises(ParseError, match=f'run.json: "{where}" (holds|is) .*a\\\\u0000b'):
        verify_run(folder, {"results": res})
    rc, out, err = run(capsys, "verify", folder, "--results", res)
    assert rc == 2 and "run.json" in err and where in err and "Traceback" not in err
    rc, _, err = run(capsys, "history", folder)
    assert rc == 2 and "run.json" in err


def copied(made, tmp_path) -> Path:
    run_dir = tmp_path / "received"
    shutil.copytree(made[1], run_dir, symlinks=True)
    return run_dir


def list_in_marker(run_dir: Path) -> None:
    """What a sender who made the links would do: the run marker lists them, as render checks."""
    from lorisnb.tools.report.build import RUN_MARKER, _files

    marker = json.loads((run_dir / RUN_MARKER).read_text())
    marker["files"] = _files(run_dir)
    (run_dir / RUN_MARKER).write_text(json.dumps(marker))


def test_render_writes_and_reads_nothing_through_a_link_leading_out(made, tmp_path, capsys):
    from lorisnb.tools.report.build import render_run

    run_dir = copied(made, tmp_path)
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    (run_dir / "report.html").unlink()
    os.symlink(victim, run_dir / "report.html")
    list_in_marker(run_dir)
    with pytest.raises(LorisError, match=r"1 link\(s\) leading outside it \(report.html\)"):
        render_run(run_dir)
    rc, out, err = run(capsys, "render", run_dir)
    assert rc == 2 and "leading outside" in err and out == ""
    assert victim.read_text() == "precious"


@pytest.mark.parametrize("which", ["findings/sequences.csv", "findings/durations.csv", "run.json"])
def test_diff_and_history_read_no_file_of_a_run_through_a_link_leading_out(made, tmp_path, capsys, which):
    run_dir = copied(made, tmp_path)
    secret = tmp_path / "secret.csv"
    secret.write_text(
        "algorithm,scene,seq,cr,eps,phi,delta,tau,gt_duration\nx,cafe,1,TOPSECRET,inf,inf,1,60,TOPSECRET\n"
    )
    (run_dir / which).unlink()
    os.symlink(secret, run_dir / which)
    with pytest.raises(ValidationError, match="a link leading outside the run folder"):
        load_run(run_dir)
    for command in (["diff", made[1], run_dir], ["history", made[1], run_dir]):
        rc, out, err = run(capsys, *command)
        assert rc == 2 and "a link leading outside the run folder" in err and "TOPSECRET" not in out + err


def test_a_results_or_data_root_given_as_a_file_is_refused(tmp_path, capsys):
    folder, res = received(tmp_path, [])
    a_file = res / "orb" / "a.txt"
    with pytest.raises(ValidationError, match="--results .*a.txt: a file; expected the folder of the run's results"):
        verify_run(folder, {"results": a_file})
    rc, out, err = run(capsys, "verify", folder, "--results", a_file)
    assert rc == 2 and out == "" and "a file; expected the folder" in err


def test_render_refuses_a_damaged_notebook_naming_it_before_writing_any_page(made, tmp_path, capsys):
    from lorisnb.tools.report.build import render_run

    run_dir = copied(made, tmp_path)
    page = run_dir / "compare_algorithms" / "compare_algorithms.html"
    page.unlink()
    assert page in render_run(run_dir)  # a page lost in a copy: rendered again
    notebook = run_dir / "compare_algorithms" / "compare_algorithms.ipynb"
    for damage in ('{"cells": "cut short', '{"cells": "x", "metadata": {}, "nbformat": 4, "nbformat_minor": 5}'):
        notebook.write_text(damage)
        list_in_marker(run_dir)
        before = {p: p.read_bytes() for p in run_dir.rglob("*.html")}
        with pytest.raises(ParseError, match="compare_algorithms.ipynb: not a notebook nbformat can read"):
            render_run(run_dir)
        rc, out, err = run(capsys, "render", run_dir)
        assert rc == 2 and "compare_algorithms.ipynb: not a notebook" in err and "Traceback" not in err
        assert {p: p.read_bytes() for p in run_dir.rglob("*.html")} == before  # no page written


def test_verify_names_the_run_own_files_edited_since(made, data, tmp_path, capsys):
    """verify checked the inputs only: a run whose leaderboard was edited (a CR raised), a figure
    replaced or a table added said 'all input file(s) unchanged', exit 0, while render refused it.
    The run's own files are checked against its marker too."""
    here, out = made
    copy = tmp_path / "run"
    shutil.copytree(out, copy, symlinks=True)
    roots = ["--data", data.root, "--results", here / "res", "--root", "kept", here / "kept"]
    rc, stdout, err = run(capsys, "verify", copy, *roots)
    assert rc == 0 and "edited" not in stdout, stdout + err
    board = copy / "findings" / "leaderboard.csv"
    board.write_text(board.read_text().replace("0.", "0.9", 1))
    (copy / "findings" / "extra.csv").write_text("a\n1\n")
    rc, stdout, err = run(capsys, "verify", copy, *roots)
    assert rc == 1 and stdout.split() == ["edited:", str(copy / "findings" / "extra.csv"), "edited:", str(board)]
    assert "2 file(s) of the run itself added, changed or removed" in err


def test_render_warns_of_a_figure_lost_in_a_copy(made, tmp_path, capsys):
    """A run copied without one of its figures rendered report.html (the one file to send) with a
    broken image and exit 0, without a word."""
    import warnings

    from lorisnb.errors import LorisWarning
    from lorisnb.tools.report.html import single_file

    _, out = made
    copy = tmp_path / "run"
    shutil.copytree(out, copy, symlinks=True)
    page = copy / "index.html"
    page.write_text(page.read_text().replace("</body>", "<img src='gone/figure.png'></body>"))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        single_file(page, tmp_path / "single.html")
    said = [str(w.message) for w in caught if issubclass(w.category, LorisWarning)]
    assert said == [f"{page}: 1 figure(s) it shows are not in the run folder (lost in a copy?), so not in the single "
                    "file made of it: gone/figure.png"], said  # fmt: skip


def test_render_advice_can_be_followed(made, tmp_path, capsys):
    """render's refusals advised what could not work: an edited index.html was to be 'moved out' (then
    the folder was no run at all), and a run whose marker lists no files (an earlier lorisnb) was to be
    'rendered from a copy' (which holds the same marker)."""
    _, out = made
    edited = tmp_path / "edited"
    shutil.copytree(out, edited, symlinks=True)
    (edited / "index.html").write_text((edited / "index.html").read_text() + "<p>mine</p>")
    rc, _, err = run(capsys, "render", edited)
    assert rc == 2 and "index.html is what render reads: put back the run's own" in err, err
    old = tmp_path / "old"
    shutil.copytree(out, old, symlinks=True)
    marker = json.loads((old / ".lorisnb-run").read_text())
    marker.pop("files")
    (old / ".lorisnb-run").write_text(json.dumps(marker))
    rc, _, err = run(capsys, "render", old)
    assert rc == 2 and "make the run again with lorisnb report" in err and "render a copy" not in err, err
