"""Notebook and report parameters, round 72: a grid's elements checked with the rule of the one value
(an eps mapping's scenes included) before anything runs, grid errors naming the grid, one rule for an
infinity papermill passes (one threshold or a grid's element), text with a comma for a list of names,
and notebooks without TeX."""

from __future__ import annotations

import json
import math
import re

import nbformat
import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.spec import validate
from lorisnb.errors import ValidationError
from lorisnb.tools.notebook.params import check_parameters, check_values
from lorisnb.tools.report import build as report
from lorisnb.tools.report.build import notebook_dir

#: compare_algorithms' first cells as a kernel's history holds them under papermill (declared, injected, setup)
DECLARED = ('# Parameters\neps = "paper"  # ATE\neps_grid = None  # grid\nscenes = None  # scenes\n'
            "results_dir = None  # results\nquick = False  # trim\n")  # fmt: skip
SETUP = 'session = ln.setup("compare_algorithms", data_root, output_dir, parameters=dict(quick=quick))'


class _Shell:
    def __init__(self, history: list[str], **namespace):
        self.user_ns = {"In": ["", *history], **namespace}


def _no_notebook(*args, **kwargs):
    raise AssertionError("a notebook was started")


@pytest.mark.parametrize("given", [["-p", "eps", '{"cafe": 1}'], ["-p", "eps_grid", '[{"cafe": 1}]'],
                                   ["-p", "eps_grid", '[1, {"cafe": 1, "home": 2}]']])  # fmt: skip
def test_an_eps_mapping_in_a_grid_is_refused_before_anything_runs_as_the_one_eps_is(
    tmp_path, data, monkeypatch, capsys, given
):
    """``-p eps_grid '[{"cafe":1}]'`` started compare_algorithms, which failed after its evaluation
    (exit 1, a run folder written), while ``-p eps '{"cafe":1}'`` was refused (exit 2)."""
    monkeypatch.setattr(report, "run_notebook", _no_notebook)
    out = tmp_path / "rg"
    rc = main(["report", "--data", str(data.root), "--no-progress", "--out", str(out), "--notebooks",
               "compare_algorithms", *given])  # fmt: skip
    err = capsys.readouterr().err
    assert rc == 2 and not out.exists() and not list(tmp_path.iterdir()), err
    name = given[1]
    assert f"{name}={{'cafe': 1.0" in err and "gives no threshold for scene 'corridor'" in err
    assert "which compare_algorithms scores" in err


def test_an_eps_mapping_covering_the_scenes_scored_passes(tmp_path, data):
    """quick on the bundled results scores home and corridor only: a mapping of those two is enough,
    for the one eps and a grid's element alike; the scenes filter counts too."""
    from lorisnb.tools.notebook.params import refuse_eps_without_scenes

    values = dict(quick=True, eps={"home": 1, "corridor": 2}, eps_grid=[1, {"home": 1, "corridor": 2}])
    refuse_eps_without_scenes(values, data, "compare_algorithms")
    refuse_eps_without_scenes(dict(eps_grid=[{"cafe": 1}], scenes=["cafe"]), data, "threshold_sensitivity")
    with pytest.raises(ValidationError, match=r"eps_grid=\{'cafe': 1.0\} \(an element of the grid\) gives no "
                                              r"threshold for scene 'home'"):  # fmt: skip
        refuse_eps_without_scenes(dict(quick=True, eps_grid=[{"cafe": 1}]), data, "threshold_sensitivity")
    with pytest.raises(ValidationError, match=r"eps=\{'home': 1.0\} gives no threshold for scene 'cafe'"):
        refuse_eps_without_scenes(dict(eps={"home": 1}, scene="cafe"), data, "metrics_primer")


def test_the_notebooks_first_cell_refuses_a_grid_mapping_without_a_scene(monkeypatch, tmp_path, data):
    """Under papermill the error came in the cell that sweeps, after the evaluation and after
    input_errors.csv was written; the first cell (setup) checks every element now."""
    import IPython

    namespace = dict(eps="paper", eps_grid=[{"cafe": 1}], scenes=None, results_dir=None, quick=True,
                     data_root=str(data.root), output_dir=None)  # fmt: skip
    history = [DECLARED, "# Parameters\neps_grid = [{'cafe': 1}]\n", SETUP]
    monkeypatch.setattr(IPython, "get_ipython", lambda: _Shell(history, **namespace))
    with pytest.raises(ValidationError, match=r"eps_grid=\{'cafe': 1.0\} \(an element of the grid\) gives no "
                                              "threshold for scene 'corridor'"):  # fmt: skip
        ln.setup("compare_algorithms", data.root, tmp_path / "out", parameters=dict(quick=True))
    assert not (tmp_path / "out").exists()
    namespace["eps_grid"] = [{"cafe": 1, "home": 1, "corridor": 1}]  # every scene quick scores: fine
    ln.setup("compare_algorithms", data.root, tmp_path / "out", parameters=dict(quick=True))


@pytest.mark.parametrize(
    ("values", "said"),
    [
        (dict(eps_grid=[1, -1]), r"eps_grid=-1: expected 'paper', 'relative:F', a number of metres >= 0"),
        (dict(eps_grid="1,-1"), r"eps_grid=-1: expected"),
        (dict(phi_grid=[]), r"phi_grid: an empty list"),
        (dict(relative_grid=[-0.1]), r"relative_grid=-0.1: expected a fraction of the ground truth's size"),
        (dict(delta_grid=[True]), r"delta_grid=True: expected a number"),
        (dict(tau_grid=[60, 60.0]), r"tau_grid=\[60, 60.0\]: 60 and 60.0 are the same value"),
        (dict(eps_grid=[{"Cafe": 1}]), r"eps_grid=\{'Cafe': 1\}: scene 'Cafe': OpenLORIS scene names are lower"),
    ],
)
def test_grid_errors_name_the_grid_not_the_one_value(tmp_path, monkeypatch, values, said):
    monkeypatch.chdir(tmp_path)
    declared = {n: {"default": None} for n in values}
    for check in (lambda: check_values(values), lambda: check_parameters(values, declared),
                  lambda: check_parameters(values, declared, by="threshold_sensitivity")):  # fmt: skip
        with pytest.raises(ValidationError, match=said):
            check()


def test_the_one_value_keeps_its_name_for_other_callers():
    with pytest.raises(ValidationError, match=r"^eps=-1: expected"):
        validate.threshold_list("eps", "1,-1")
    with pytest.raises(ValidationError, match=r"^phi: an empty list"):
        validate.threshold_list("phi", [])


def test_papermill_infinity_one_rule_for_thresholds_and_grids(tmp_path, monkeypatch):
    """papermill reads -p eps 1e400 as -p eps inf, YAML 1.0e400 as .inf: a notebook refuses an
    infinity passed as a number, one threshold or a grid's element alike, naming -p and -y; the
    word inf in a grid's text is unambiguous and taken; the report passes its checked inf on."""
    monkeypatch.chdir(tmp_path)  # no run folder of lorisnb report around
    declared = {n: {"default": None} for n in ("phi", "eps_grid", "phi_grid", "delta_grid", "tau_grid")}
    for values in (dict(eps_grid=[1.0, math.inf]), dict(tau_grid=math.inf), dict(phi_grid=(10.0, math.inf))):
        name = next(iter(values))
        with pytest.raises(ValidationError) as e:
            check_parameters(values, declared, ["threshold_sensitivity"], by="threshold_sensitivity")
        said = str(e.value)
        assert said.startswith(f"{name}=inf: papermill turned") and f"-p {name} or -y" in said
        assert f"papermill -p {name} 1,inf" in said and "1.0e400 as .inf" in said
        assert check_parameters(values, declared, ["threshold_sensitivity"])  # lorisnb report: its inf taken
    text = dict(eps_grid="1,inf")  # -p eps_grid 1,inf: text, the word inf
    assert check_parameters(text, declared, ["threshold_sensitivity"], by="threshold_sensitivity") == {
        "eps_grid": [1.0, math.inf]
    }
    with pytest.raises(ValidationError) as e:  # -y 'phi: .inf': the message names -y too
        check_parameters(dict(phi=math.inf), declared, ["threshold_sensitivity"], by="threshold_sensitivity")
    assert "-y 'phi: .inf'" in str(e.value) and "-p phi inf" in str(e.value)
    with pytest.raises(ValidationError) as e:  # -y 'eps: inf' is YAML text: named, not only -r
        check_values(dict(eps="inf"))
    assert "-y 'eps: inf'" in str(e.value) and "papermill's -r" in str(e.value)


def test_text_with_a_comma_for_a_list_of_names_gets_the_lists_form(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for name, text in (("scenes", "home,cafe"), ("algorithms", "dso, odom")):
        parts = [p.strip() for p in text.split(",")]
        with pytest.raises(ValidationError) as e:
            check_values({name: text})
        said = str(e.value)
        assert f"-y '{name}: [{', '.join(parts)}]'" in said and f"-p {name} '{json.dumps(parts)}'" in said
        assert check_values({name: parts}) is None  # the list itself is fine
    assert check_values({"eps_grid": "1,2"}) is None  # a grid's text is split at commas


#: TeX in a markdown cell: $...$, $$, or a TeX command
TEX = re.compile(r"\$[^$\n]+\$|\$\$|\\(?:frac|sum|mathrm|text|tag|begin|end|min|max|delta|tau|epsilon|phi|le|ge|"
                 r"dots|cdot|cr)\b")  # fmt: skip
CODE = re.compile(r"```.*?```|`[^`\n]*`", re.S)


def test_no_notebook_holds_tex():
    """The report's pages load no MathJax (offline): metrics_primer showed raw TeX ($$ \\frac ...)."""
    found = {}
    for path in sorted(notebook_dir().glob("*.ipynb")):
        nb = nbformat.read(path, as_version=4)
        for i, cell in enumerate(nb.cells):
            if cell.cell_type == "markdown":
                hit = TEX.search(CODE.sub("", cell.source))
                if hit:
                    found[f"{path.name} cell {i}"] = hit.group(0)
    assert not found, found
    primer = nbformat.read(notebook_dir() / "metrics_primer.ipynb", as_version=4)
    text = "".join(c.source for c in primer.cells if c.cell_type == "markdown")
    for number in ("(1)", "(2)", "(3)", "(4)"):  # the paper's equation numbers, kept
        assert number in text
    assert "Σ<sub>k=0</sub><sup>N</sup>" in text and "t<sub>min</sub>" in text
