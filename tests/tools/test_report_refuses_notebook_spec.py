"""``lorisnb report`` checks each notebook's evaluation spec before the run folder exists, built as
the notebook builds it (:func:`lorisnb.tools.notebook.params.evaluation_spec`) for the inputs it
scores: ``-p conventions tum -p official_interpolation true`` on a pair ran ``evaluate_my_results``,
which failed minutes later (exit 1, a run folder left behind), where docs/guide/errors.md promises a
usage error with nothing run (adversarial finding 5)."""

from __future__ import annotations

import pytest

from lorisnb.cli import main
from lorisnb.errors import ValidationError
from lorisnb.tools.report.notebooks import refuse_inapplicable_specs

TUM = "tum-rgbd"


def test_a_parameter_the_notebook_would_refuse_is_a_usage_error_and_nothing_runs(data, tmp_path, capsys):
    est, gt = data.root / TUM / "fr2_desk_ORB.txt", data.root / TUM / "fr2_desk_groundtruth.txt"
    out = tmp_path / "rep"
    rc = main(["report", "--out", str(out), "--notebooks", "evaluate_my_results", "-p", "path", str(est),
               "-p", "groundtruth", str(gt), "-p", "conventions", "tum", "-p", "official_interpolation", "true",
               "--no-progress"])  # fmt: skip
    err = capsys.readouterr().err
    assert rc == 2, err
    assert "evaluate_my_results (scoring the pair path, groundtruth) would refuse its parameters: " in err
    assert "official_interpolation: the official tool's slips are those of interpolation" in err
    assert not out.exists() and list(tmp_path.iterdir()) == []  # no run folder, no partial one


def test_the_same_parameters_a_notebook_can_take_pass(data):
    """The control, with the notebooks' own spec: interpolation (lorisnb's default) takes the slips on a
    pair, on OpenLORIS files every notebook takes them; a nearest association on OpenLORIS files too."""
    est, gt = data.root / TUM / "fr2_desk_ORB.txt", data.root / TUM / "fr2_desk_groundtruth.txt"
    names = ["evaluate_my_results", "per_sequence_benchmark", "lifelong_benchmark", "compare_algorithms"]
    refuse_inapplicable_specs(names, None, {"path": str(est), "groundtruth": str(gt), "official_interpolation": True})
    refuse_inapplicable_specs(names, None, {"official_interpolation": True, "scale": True})
    refuse_inapplicable_specs(["evaluate_my_results"], None, {"conventions": "tum"})
    with pytest.raises(ValidationError, match="official_interpolation: the official tool's slips"):
        refuse_inapplicable_specs(["evaluate_my_results"], None, {"conventions": "tum", "official_interpolation": True})
