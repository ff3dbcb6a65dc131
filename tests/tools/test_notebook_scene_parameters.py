"""Every notebook parameter that names one scene (``scene``, ``sim_scene``: the notebook loads its
ground truth) is refused up front when the data root holds no ground truth for it (office), as a
``scenes`` filter of only such scenes is: by ``lorisnb report`` before any notebook starts, and by
the notebook's first cell (``ln.setup``) under papermill or in Jupyter, not minutes later."""

from __future__ import annotations

import pytest

import lorisnb as ln
from lorisnb.errors import ValidationError
from lorisnb.tools.notebook.params import _VALUES, SCENE_PARAMETERS, check_parameters


def test_every_parameter_naming_a_scene_is_checked_for_ground_truth():
    """A parameter checked as one of the scenes in ``_VALUES`` is one of ``SCENE_PARAMETERS``."""
    named = set()
    for name, check in _VALUES.items():
        try:
            check("nonesuch-scene")
        except ValidationError as exc:
            if "cafe" in str(exc) and "corridor" in str(exc):  # the list of scenes it must be one of
                named.add(name)
        except Exception:
            pass
    assert named == set(SCENE_PARAMETERS) == {"scene", "sim_scene"}


@pytest.mark.parametrize(("notebook", "name"), [("metrics_primer", "scene"), ("compare_algorithms", "sim_scene")])
def test_setup_refuses_a_scene_without_ground_truth(tmp_path, data, notebook, name):
    with pytest.raises(ValidationError, match=f"-p {name} office: the data root .* holds no ground truth for office"):
        ln.setup(notebook, data.root, tmp_path / "out", parameters={name: "office"})
    assert not (tmp_path / "out").exists()
    ln.setup(notebook, data.root, tmp_path / "out", parameters={name: "Corridor"})  # one with ground truth passes


def test_the_reports_parameter_check_refuses_a_scene_without_ground_truth(data):
    declared = {"sim_scene": {"default": "corridor"}, "scene": {"default": "cafe"}, "data_root": {"default": None}}
    for name in ("scene", "sim_scene"):
        with pytest.raises(ValidationError, match=f"-p {name} office: .*no ground truth for office"):
            check_parameters({name: "office", "data_root": str(data.root)}, declared)
    assert check_parameters({"sim_scene": "Market", "data_root": str(data.root)}, declared)["sim_scene"] == "market"


@pytest.mark.parametrize(("notebook", "name"), [("compare_algorithms", "sim_scene"), ("metrics_primer", "scene")])
def test_lorisnb_report_refuses_a_scene_without_ground_truth_before_any_notebook(
    tmp_path, data, monkeypatch, capsys, notebook, name
):
    from lorisnb.cli import main
    from lorisnb.tools.report import build as report

    started: list = []
    monkeypatch.setattr(report, "run_notebook", lambda nb, *a, **k: started.append(nb) or report.NotebookRun(nb))
    out = tmp_path / "run"
    args = ["report", "--out", str(out), "--data", str(data.root), "--no-progress", "--notebooks", notebook]
    assert main([*args, "-p", name, "office"]) == 2
    err = capsys.readouterr().err
    assert f"-p {name} office" in err and "no ground truth" in err
    assert not started and not out.exists()
