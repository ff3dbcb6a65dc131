"""`lorisnb report`: a run folder with executed notebooks, HTML, CSV, figures and index.html;
one broken input shows as an error while the rest of the report is complete; a failing notebook
does not stop the others; an existing run is never replaced without --force."""

from __future__ import annotations

import json
import os
import re
import stat

import nbformat
import numpy as np
import pandas as pd
import pytest
from helpers import write

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import LorisError
from lorisnb.tools.report.build import run_report

pytestmark = pytest.mark.slow


@pytest.fixture
def tree(tmp_path, icra20):
    root = tmp_path / "in"
    src = icra20 / "per-seq" / "orbslam2_rgbd" / "cafe_1_1_orbslam2-original.txt"
    write(root, "orbslam2_rgbd/cafe_1_1.txt", src.read_bytes())
    write(root, "broken_slam/cafe-1-2.txt", "scene: cafe\nframe: d400_color\nseq: 2\n5 0 0 0 0 0 0 0\n")
    return root


def test_report_with_broken_input_and_failing_notebook(tmp_path, tree):
    failing = tmp_path / "failing.ipynb"
    nb = nbformat.v4.new_notebook()
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    params = nbformat.v4.new_code_cell("output_dir = None")
    params.metadata["tags"] = ["parameters"]
    nb.cells = [params, nbformat.v4.new_code_cell("raise RuntimeError('deliberate failure')")]
    nbformat.write(nb, failing)
    out = tmp_path / "run"
    run_dir, runs = run_report(
        out, {"results_dir": str(tree), "quick": False}, ["per_sequence_benchmark", str(failing)], progress=False
    )
    assert run_dir == out
    status = {r.name: r.status for r in runs}
    assert status == {"per_sequence_benchmark": "ok", "failing": "failed"}
    index = (out / "index.html").read_text()
    assert "deliberate failure" in index
    assert "cafe-1-2.txt" in index and "quaternion has zero norm" in index
    nbdir = out / "per_sequence_benchmark"
    for name in (
        "per_sequence_benchmark.ipynb",
        "per_sequence_benchmark.html",
        "sequences.csv",
        "scenes.csv",
        "timeline_per_sequence.png",
    ):
        assert (nbdir / name).exists(), name
        assert f"per_sequence_benchmark/{name}" in index or name.endswith("ipynb") or name.endswith("html")
    assert "sequences.csv" in index and "timeline_per_sequence.png" in index
    # an existing run is not replaced without force
    before = (out / "index.html").stat().st_mtime_ns
    with pytest.raises(LorisError, match="exists"):
        run_report(out, {}, ["per_sequence_benchmark"], progress=False)
    assert (out / "index.html").stat().st_mtime_ns == before
    assert not list(tmp_path.glob(".run.partial-*"))


def test_report_cli_parameters(tmp_path, tree, capfd):
    out = tmp_path / "cli-run"
    rc = main(
        [
            "report",
            "--out",
            str(out),
            "--notebooks",
            "per_sequence_benchmark",
            "-p",
            "results_dir",
            str(tree),
            "-p",
            "eps",
            "inf",
            "-p",
            "delta",
            "0.5",
            "--no-progress",
        ]
    )
    assert rc == 1  # the tree holds one broken input: the terminal says so, as index.html does
    captured = capfd.readouterr()  # the kernel's own output too (file descriptors, not sys.stderr)
    assert "per_sequence_benchmark       ok, 1 input file(s) failed or not scored" in captured.out
    assert "without encryption" not in captured.err and "KeyboardInterrupt" not in captured.err
    params = (out / "parameters.json").read_text()
    assert '"delta": 0.5' in params


def _first_table(html: str) -> str:
    start = html.index("<table")
    return html[start : html.index("</table>", start)]


def test_report_on_a_results_folder_with_trials(tmp_path, icra20, data, capfd):
    """A lab's own results (two algorithms, three trials each): the page opens with the
    leaderboards of the report's own evaluation, every default notebook about results runs (the
    per-sequence one used to fail on trials), no simulated section, figures stored once, offline
    pages, a world-readable folder, run.json with every input's checksum, and verify."""
    from report_fixtures import trial_results

    from lorisnb.tools.report.leaderboard import findings
    from lorisnb.tools.report.provenance import sha256

    results = trial_results(tmp_path / "mine", icra20)
    out = tmp_path / "run"
    old = os.umask(0o022)
    try:
        rc = main(["report", "--results", str(results), "--out", str(out), "-p", "quick", "true", "--no-progress"])
    finally:
        os.umask(old)
    assert rc == 0, capfd.readouterr()
    runs = json.loads((out / "run.json").read_text())
    assert runs["notebooks"] == {n: "ok" for n in ("per_sequence_benchmark", "lifelong_benchmark",
                                                   "threshold_sensitivity", "compare_algorithms")}  # fmt: skip
    assert stat.S_IMODE(out.stat().st_mode) == 0o755
    index = (out / "index.html").read_text()
    first = _first_table(index)
    assert "class='leaderboard'" in first and "<th>rank</th>" in first and "coverage (sequences)" in first
    assert index.index("What was found") < index.index("Why: the evidence") < index.index("<h2>Notebooks</h2>")
    assert "metrics_primer (about the bundled data" in index  # left out, and said so
    # the leaderboard is the statistics API's on the same table
    ev = ln.evaluate(results, scale="auto")
    expected = findings(ev.sequences(), ev.durations()).board  # at compare's defaults (eps = phi = inf)
    board = pd.read_csv(out / "findings" / "leaderboard.csv")
    assert len(board) == len(expected) == 4
    assert np.allclose(board["value"], expected["value"]) and (board["trials"] == 3).all()
    assert f"{expected['value'].iloc[0]:.3f}" in first
    # no simulated section on a lab's results; the robust ranking ran on the trials instead
    cmp = out / "compare_algorithms"
    assert not list(cmp.glob("simulated_*")) and len(pd.read_csv(cmp / "robust_first.csv"))
    # each figure once: one PNG, linked from the notebook page and from index.html, never embedded
    assert not list(out.rglob("*.svg")) and not list(out.rglob("*.pdf"))
    pngs = sorted(out.rglob("*.png"))
    assert len(pngs) >= 5 and (out / "per_sequence_benchmark" / "timeline_per_sequence.png") in pngs
    for p in pngs:
        assert index.count(f"<img src='{p.relative_to(out).as_posix()}'") == 1
    for page in out.glob("*/*.html"):
        text = page.read_text()
        assert "<script src" not in text and "cdn" not in text.lower() and "data:image/png" not in text, page
    page = (out / "per_sequence_benchmark" / "per_sequence_benchmark.html").read_text()
    assert 'src="timeline_per_sequence.png"' in page and '<details class="lorisnb-code">' in page
    single = (out / "report.html").read_text()
    assert single.count("data:image/png;base64,") == len(pngs) and not re.search(r"src='(?!data:)", single)
    # provenance: every result file and the ground truth, with their checksums; verify
    assert set(runs) >= {"command", "lorisnb_version", "commit", "spec", "data_root", "created", "inputs", "notebooks"}
    assert runs["command"][:2] == ["lorisnb", "report"] and runs["spec"]["values"]["eps"] == "inf"
    trial = results / "orb" / "cafe_1_trial2.txt"
    # (paths below named roots: the run names no absolute path of this machine, tests/tools/test_portable_runs.py)
    assert runs["inputs"]["{results}/orb/cafe_1_trial2.txt"] == sha256(trial)
    assert runs["inputs"]["{data}/openloris-scene/groundtruth/gt_cafe_1.txt"] == sha256(data.groundtruth("cafe"))
    assert len([k for k in runs["inputs"] if k.startswith("{results}/")]) == 18
    roots = ["--data", str(data.root), "--results", str(results)]
    assert main(["verify", str(out), *roots]) == 0
    trial.write_text(trial.read_text() + "\n")
    capfd.readouterr()
    assert main(["verify", str(out), *roots]) == 1
    assert "changed: {results}/orb/cafe_1_trial2.txt" in capfd.readouterr().out
    # the folders it read are listed again: a result file added since is an input of the same command
    assert runs["input_roots"][0] == "{results}"
    added = results / "orb" / "home_1_trial4.txt"
    added.write_text((results / "orb" / "home_1_trial1.txt").read_text())
    assert (
        main(["verify", str(out), *roots]) == 1 and "added: {results}/orb/home_1_trial4.txt" in capfd.readouterr().out
    )
    # diff of the run against itself: each sequence once, though four of the run's tables hold it
    per_sequence = pd.read_csv(out / "findings" / "sequences.csv")
    assert main(["diff", str(out), str(out), "--no-progress"]) == 0
    n = len(per_sequence.drop_duplicates(["algorithm", "scene", "seq"]))
    assert n == 6 and f"\n{n} sequence(s);" in capfd.readouterr().out


def test_report_notebooks_dir_runs_every_notebook(tmp_path, capfd):
    """--notebooks-dir: every notebook runs, shipped names first, then alphabetically; a broken
    one is a failed entry with its reason; the exit status is 1."""
    d = tmp_path / "nbs"
    d.mkdir()

    def nb(name, code, params=True, kernel=True):
        book = nbformat.v4.new_notebook()
        if kernel:
            book.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
        cell = nbformat.v4.new_code_cell("output_dir = None")
        if params:
            cell.metadata["tags"] = ["parameters"]
        book.cells = [cell, nbformat.v4.new_code_cell(code)]
        nbformat.write(book, d / f"{name}.ipynb")

    nb("zz_mine", "open('made.txt', 'w').write('yes')")
    nb("lifelong_benchmark", "print('a shipped name')")
    nb("boom", "raise ValueError('on purpose')")
    nb("no_params", "x = 1", params=False)
    nb("no_kernel", "x = 1", kernel=False)
    (d / "garbled.ipynb").write_text("{ nope")
    out = tmp_path / "run"
    rc = main(["report", "--notebooks-dir", str(d), "--out", str(out), "--no-progress"])
    assert rc == 1
    lines = [line.split()[0:2] for line in capfd.readouterr().out.splitlines() if line.strip() and " s" in line]
    assert lines == [["lifelong_benchmark", "ok"], ["boom", "failed"], ["garbled", "failed"],
                     ["no_kernel", "failed"], ["no_params", "failed"], ["zz_mine", "ok"]]  # fmt: skip
    assert (out / "zz_mine" / "made.txt").read_text() == "yes"
    index = (out / "index.html").read_text()
    for reason in ("ValueError: on purpose", "invalid JSON", "no kernelspec", "no cell tagged"):
        assert reason in index
