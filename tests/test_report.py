"""`lorisnb report`: a run folder with executed notebooks, HTML, CSV, figures and index.html;
one broken input shows as an error while the rest of the report is complete; a failing notebook
does not stop the others; an existing run is never replaced without --force."""

from __future__ import annotations

import nbformat
import pytest
from helpers import write

from lorisnb.cli import main
from lorisnb.errors import LorisError
from lorisnb.tools.report import run_report

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
    nb.cells = [nbformat.v4.new_code_cell("raise RuntimeError('deliberate failure')")]
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
    assert "per_sequence_benchmark       ok, 1 input file(s) failed" in captured.out
    assert "without encryption" not in captured.err and "KeyboardInterrupt" not in captured.err
    params = (out / "parameters.json").read_text()
    assert '"delta": 0.5' in params
