"""verify, render and the front page on what an adversarial tester found: a key whose path holds a
newline is one key ({results}/new\\nline/x.txt was "missing" on an untouched run); a file of the run
removed, or its marker removed, is damage verify names (exit 1), not "all unchanged" nor "a run of
an earlier lorisnb"; names on index.html show a newline or a tab escaped, as the terminal does; an
--out reached through a linked folder of the results is refused as one inside them is; the front
page says "this run" for the run (not "{run}") and counts a file the report and a notebook both
list once; --absolute-paths records the leaderboard's source where it is; render says what is
missing."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest
from helpers import run_cli as run

from lorisnb.errors import LorisError, OutputError
from lorisnb.tools.report.portable import split_key
from lorisnb.tools.report.provenance import verify_run

ORB = "cafe_1_1_orbslam2-original.txt"
ODOM = "cafe-1-2-odom.txt"
NEWLINE = "new\nline"
BAD = "home_1_3_orbslam2-original.txt"


def fake_notebook(name, out_dir, params, **kw):
    """A notebook of the report: its page, and the inputs it could not evaluate as a notebook lists
    them (the lorisnb evaluation of its ``results_dir``, each file by its absolute path)."""
    import nbformat

    import lorisnb as ln
    from lorisnb.tools.notebook.start import INPUT_ERRORS_CSV
    from lorisnb.tools.report.notebooks import NotebookRun

    (out_dir / name).mkdir()
    nbformat.write(nbformat.v4.new_notebook(cells=[nbformat.v4.new_markdown_cell("a page")]),
                   str(out_dir / name / f"{name}.ipynb"))  # fmt: skip
    (out_dir / name / f"{name}.html").write_text("<p>page</p>")
    if params.get("results_dir"):
        ev = ln.evaluate(params["results_dir"], data_root=params.get("data_root"))
        ev.failures_table().to_csv(out_dir / name / INPUT_ERRORS_CSV, index=False)
    return NotebookRun(name)


def lab(here: Path, icra20: Path) -> Path:
    """A results folder: ``orb`` (real), ``new\\nline`` (a real odom file below a name holding a
    newline), ``linked`` (a link to a folder kept elsewhere), ``bad`` (a file that does not read)."""
    res = here / "res"
    for alg, src, name in (("orb", "orbslam2_rgbd", ORB), (NEWLINE, "odom", ODOM)):
        (res / alg).mkdir(parents=True)
        shutil.copy(icra20 / "per-seq" / src / name, res / alg / name)
    (here / "kept" / "vins").mkdir(parents=True)
    shutil.copy(icra20 / "per-seq" / "odom" / "cafe-1-1-odom.txt", here / "kept" / "vins" / "cafe-1-1.txt")
    os.symlink(here / "kept" / "vins", res / "linked")
    (res / "bad").mkdir()
    (res / "bad" / BAD).write_text("garbage line\n")
    return res


@pytest.fixture(scope="module")
def made(tmp_path_factory, data, icra20):
    """A report run of :func:`lab` (its notebook :func:`fake_notebook`, the leaderboard the report's own)."""
    import lorisnb.tools.report.build as report

    here = tmp_path_factory.mktemp("lab")
    res = lab(here, icra20)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(report, "run_notebook", fake_notebook)
        out, _ = report.run_report(here / "runs" / "r1", {"data_root": str(data.root)}, ["per_sequence_benchmark"],
                                   progress=False, results=res)  # fmt: skip
    return here, out


def copied(made, tmp_path) -> Path:
    run_dir = tmp_path / "received"
    shutil.copytree(made[1], run_dir, symlinks=True)
    return run_dir


def roots(made, data) -> dict[str, Path]:
    here, _ = made
    return {"data": data.root, "results": here / "res", "kept": here / "kept"}


# 1. keys matched whole


def test_a_key_is_matched_whole_a_newline_in_it_or_after_it():
    assert split_key("{results}/new\nline/x.txt") == ("results", "new\nline/x.txt")
    assert split_key("{results}/alg/x.txt\n") == ("results", "alg/x.txt\n")  # not alg/x.txt
    assert split_key("{results}\n") is None and split_key("{results}") == ("results", "")
    assert split_key("/abs/{results}/x") is None


def test_verify_reads_an_input_below_a_folder_whose_name_holds_a_newline(made, data, capsys):
    here, out = made
    record = json.loads((out / "run.json").read_text())
    key = f"{{results}}/{NEWLINE}/{ODOM}"
    assert key in record["inputs"]
    assert verify_run(out, roots(made, data)) == []
    rc, stdout, err = run(capsys, "verify", out, "--data", data.root, "--results", here / "res", "--root", "kept",
                          here / "kept")  # fmt: skip
    assert rc == 0 and stdout == "" and "unchanged" in err, stdout + err


# 2, 3. files of the run removed; the marker removed


def verify_args(made, data, run_dir):
    here, _ = made
    return ["verify", run_dir, "--data", data.root, "--results", here / "res", "--root", "kept", here / "kept"]


@pytest.mark.parametrize(
    "gone",
    [["index.html"], ["report.html"], ["findings/leaderboard.csv", "findings/sequences.csv"],
     ["per_sequence_benchmark/per_sequence_benchmark.html"]],
)  # fmt: skip
def test_verify_names_the_files_of_the_run_that_are_gone(made, data, tmp_path, capsys, gone):
    run_dir = copied(made, tmp_path)
    for rel in gone:
        (run_dir / rel).unlink()
    rc, stdout, err = run(capsys, *verify_args(made, data, run_dir))
    assert rc == 1, stdout + err
    assert all(f"missing: {run_dir / rel}" in stdout for rel in gone) and "edited:" not in stdout
    assert "added, changed or removed" in err
    from lorisnb.tools.report.build import missing_run_files, not_as_written

    assert not_as_written(run_dir) == sorted(gone) and missing_run_files(run_dir) == sorted(gone)


def test_render_puts_back_a_page_that_is_gone_and_refuses_a_run_missing_another_file(made, tmp_path, capsys):
    from lorisnb.tools.report.build import not_as_written

    run_dir = copied(made, tmp_path)
    (run_dir / "report.html").unlink()
    rc, stdout, _ = run(capsys, "render", run_dir)
    assert rc == 0 and "report.html" in stdout and not_as_written(run_dir) == []
    (run_dir / "findings" / "leaderboard.csv").unlink()  # render would write a marker no longer listing it
    rc, _, err = run(capsys, "render", run_dir)
    assert rc == 2 and "findings/leaderboard.csv" in err and "gone" in err
    assert not_as_written(run_dir) == ["findings/leaderboard.csv"]


def test_a_marker_removed_is_damage_not_an_earlier_run(made, data, tmp_path, capsys):
    from lorisnb.tools.report.build import RUN_MARKER, not_as_written

    run_dir = copied(made, tmp_path)
    board = run_dir / "findings" / "leaderboard.csv"
    board.write_text(board.read_text().replace("orb", "orc"))  # a hand edit, the marker removed to hide it
    (run_dir / RUN_MARKER).unlink()
    assert not_as_written(run_dir) == [RUN_MARKER]
    rc, stdout, err = run(capsys, *verify_args(made, data, run_dir))
    assert rc == 1 and f"missing: {run_dir / RUN_MARKER}" in stdout and "earlier lorisnb" not in err, stdout + err
    rc, _, err = run(capsys, "render", run_dir)
    assert rc == 2 and f"{RUN_MARKER} marker is gone" in err and "no index.html" not in err


def test_a_marker_listing_nothing_beside_a_run_json_with_named_roots_is_damage(made, data, tmp_path, capsys):
    from lorisnb.tools.report.build import RUN_MARKER, not_as_written

    run_dir = copied(made, tmp_path)
    (run_dir / RUN_MARKER).write_text(json.dumps({"lorisnb": "0.3.0", "pid": 1}))  # its list of files taken out
    assert not_as_written(run_dir) == [RUN_MARKER]
    rc, stdout, _ = run(capsys, *verify_args(made, data, run_dir))
    assert rc == 1 and str(run_dir / RUN_MARKER) in stdout
    record = json.loads((run_dir / "run.json").read_text())  # a run.json of before named roots: an earlier run
    del record["roots"]
    (run_dir / "run.json").write_text(json.dumps(record))
    assert not_as_written(run_dir) is None


# 4. names on the front page


def test_the_front_page_shows_a_newline_in_a_name_escaped(made):
    _, out = made
    for page in ("index.html", "report.html"):
        text = (out / page).read_text()
        assert "<td>new\\nline</td>" in text, page
        assert "new\nline" not in text and "<td>new line</td>" not in text, page


def test_esc_escapes_every_control_character_and_esc_block_keeps_lines():
    from lorisnb.tools.report.index import esc

    assert esc("new\nline") == "new\\nline" and esc("a\tb") == "a\\tb" and esc("<a\x1b>") == "&lt;a\\x1b&gt;"
    from lorisnb.tools.report.index import esc_block

    assert esc_block("Traceback\n  line\tx") == "Traceback\n  line\tx"


# 5. --out through a linked folder of the results


@pytest.mark.parametrize("where", ["res/linked/rep", "kept/vins/rep"])
def test_out_through_a_linked_folder_of_the_results_is_refused(tmp_path, data, icra20, monkeypatch, where):
    import lorisnb.tools.report.build as report

    here = tmp_path
    lab(here, icra20)
    monkeypatch.setattr(report, "run_notebook", fake_notebook)
    before = sorted(p.name for p in (here / "kept" / "vins").iterdir())
    with pytest.raises(OutputError, match="the input .* of this report; choose another folder"):
        report.run_report(here / where, {"data_root": str(data.root)}, ["per_sequence_benchmark"], progress=False,
                          results=here / "res")  # fmt: skip
    assert sorted(p.name for p in (here / "kept" / "vins").iterdir()) == before


# 6. smaller


def test_the_failures_header_counts_a_file_the_report_and_a_notebook_list_once(made):
    _, out = made
    text = (out / "index.html").read_text()
    assert BAD in (out / "per_sequence_benchmark" / "input_errors.csv").read_text()
    assert BAD in (out / "findings" / "input_errors.csv").read_text()
    assert "could not be evaluated or scored (1)</h3>" in text
    assert text.count(f"<td>{{results}}/bad/{BAD}</td>") == 1


def test_no_baseline_says_this_run_not_a_literal_run_root(made, data, monkeypatch):
    import lorisnb.tools.report.build as report

    here, _ = made
    monkeypatch.setattr(report, "run_notebook", fake_notebook)
    out, _ = report.run_report(here / "runs" / "night", {"data_root": str(data.root), "eps": 3.0},
                               ["per_sequence_benchmark"], progress=False, results=here / "res",
                               baseline=here / "runs")  # fmt: skip
    try:
        text = (out / "index.html").read_text()
        assert "No baseline:" in text and "in this run" in text and "{run}" not in text
    finally:
        shutil.rmtree(out)


def test_absolute_paths_record_the_leaderboards_source_where_it_is(made, data, monkeypatch, tmp_path):
    import lorisnb.tools.report.build as report

    here, _ = made
    monkeypatch.setattr(report, "run_notebook", fake_notebook)
    monkeypatch.chdir(here)
    out, _ = report.run_report(tmp_path / "abs", {"data_root": str(data.root)}, ["per_sequence_benchmark"],
                               progress=False, results="res", absolute_paths=True)  # fmt: skip
    values = json.loads((out / "run.json").read_text())["spec"]["values"]
    assert values["source"] == str((here / "res").resolve())


def test_render_says_what_is_missing(made, tmp_path):
    from lorisnb.tools.report.build import RUN_MARKER, render_run

    run_dir = copied(made, tmp_path)
    (run_dir / "index.html").unlink()
    with pytest.raises(LorisError, match="its index.html is gone") as e:
        render_run(run_dir)
    assert RUN_MARKER not in str(e.value)
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(LorisError, match=f"no {RUN_MARKER} and no index.html"):
        render_run(empty)
