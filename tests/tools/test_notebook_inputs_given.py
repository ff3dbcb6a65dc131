"""A notebook's inputs are refused up front, by the one parameter check of the notebooks (papermill's
``-p``, a parameter cell edited in Jupyter) and of ``lorisnb report``, where they could only give empty
tables or be ignored: a ``results_dir`` without result files (papermill ran per_sequence_benchmark on
it to exit 0 with empty tables, while ``lorisnb report --results`` refused it), and a ground truth
without the estimate to score against it (``evaluate_my_results`` scored its bundled example instead),
or, for ``every_number``, either half of its pair without the other."""

from __future__ import annotations

import pytest

import lorisnb as ln
from lorisnb.errors import ValidationError
from lorisnb.tools.notebook.params import check_parameters

NOTEBOOKS_WITH_RESULTS = ["per_sequence_benchmark", "compare_algorithms", "lifelong_benchmark", "threshold_sensitivity"]


@pytest.mark.parametrize("notebook", NOTEBOOKS_WITH_RESULTS)
def test_an_empty_results_dir_is_refused_as_report_refuses_it(tmp_path, data, notebook):
    empty = tmp_path / "empty"
    (empty / "alg").mkdir(parents=True)
    (empty / "alg" / "README.txt").write_text("not a result")  # a document is no result file
    with pytest.raises(ValidationError, match=r"results_dir=.*empty: no result files in it; expected a folder"):
        ln.setup(notebook, data.root, tmp_path / "out", parameters={"results_dir": str(empty)})
    assert not (tmp_path / "out").exists()
    with pytest.raises(ValidationError, match="no result files in it"):
        check_parameters({"results_dir": str(empty)}, {"results_dir": {"default": None}}, [notebook], by=notebook)


def test_a_results_dir_with_result_files_passes(tmp_path, data, icra20):
    ln.setup("per_sequence_benchmark", data.root, tmp_path / "out",
             parameters={"results_dir": str(icra20 / "per-seq")})  # fmt: skip


def test_evaluate_my_results_refuses_a_groundtruth_without_path(tmp_path, data):
    gt = data.tum / "fr2_desk_groundtruth.txt"
    with pytest.raises(ValidationError, match="evaluate_my_results: groundtruth=.* without path; give both path"):
        ln.setup("evaluate_my_results", data.root, tmp_path / "out", parameters={"groundtruth": str(gt), "path": None})
    assert not (tmp_path / "out").exists()
    declared = {n: {"default": None} for n in ("path", "groundtruth")}
    with pytest.raises(ValidationError, match="give both path"):
        check_parameters({"groundtruth": str(gt)}, declared, ["evaluate_my_results"], by="evaluate_my_results")
    check_parameters({"path": str(gt)}, declared, ["evaluate_my_results"])  # OpenLORIS result files: no pair


@pytest.mark.parametrize("given", ["path", "groundtruth"])
def test_lorisnb_report_refuses_half_of_every_numbers_pair_before_any_notebook(
    tmp_path, data, monkeypatch, capsys, given
):
    from lorisnb.cli import main
    from lorisnb.tools.report import build as report

    started: list = []
    monkeypatch.setattr(report, "run_notebook", lambda nb, *a, **k: started.append(nb) or report.NotebookRun(nb))
    out = tmp_path / "run"
    args = ["report", "--out", str(out), "--data", str(data.root), "--no-progress", "--notebooks", "every_number"]
    assert main([*args, "-p", given, str(data.tum / "fr2_desk_ORB.txt")]) == 2
    err = capsys.readouterr().err
    assert "give both path and groundtruth (a pair), or neither" in err
    assert not started and not out.exists()
