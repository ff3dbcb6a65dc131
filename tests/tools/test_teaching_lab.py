"""The labs' sources (teaching/source): what a student sees holds no solution, students and the
grader evaluate on the same data, and the prose around the questions stays true for other
parameters. Fast: the sources are read, not executed (the simulated scenarios run on the sample data)."""

from __future__ import annotations

import ast
import copy
import re
import textwrap
from pathlib import Path

import nbformat
import pytest

import lorisnb as ln
from lorisnb.core.simulate import Faults, simulated_errors
from lorisnb.io.datasets.paths import sample_data
from lorisnb.tools import teaching as teach

ROOT = Path(__file__).resolve().parents[2]
SOURCE = ROOT / "teaching" / "source"
LABS = sorted(p.name for p in SOURCE.iterdir() if p.is_dir())
SOLUTION = re.compile(r"^([ \t]*)### BEGIN SOLUTION[ \t]*\n(.*?)^[ \t]*### END SOLUTION[ \t]*\n?", re.S | re.M)
HIDDEN = re.compile(r"^[ \t]*### BEGIN HIDDEN TESTS.*?### END HIDDEN TESTS[ \t]*\n?", re.S | re.M)
FORMULAS = (ast.BinOp, ast.Compare, ast.BoolOp, ast.UnaryOp, ast.Call, ast.Subscript, ast.Attribute)


class _Numbers(ast.NodeTransformer):
    """20 and 20.0 are the same formula; 'a' and "a" already are (the AST has no quotes)."""

    def visit_Constant(self, node: ast.Constant) -> ast.Constant:
        if isinstance(node.value, int | float) and not isinstance(node.value, bool):
            return ast.Constant(float(node.value))
        return node


def _key(node: ast.AST) -> str:
    return ast.dump(_Numbers().visit(copy.deepcopy(node)))


def solution_expressions(nb: nbformat.NotebookNode, min_nodes: int = 8) -> dict[str, str]:
    """Every formula of the notebook's solution regions (not the tiny ones such as ``np.diff(x)``)."""
    out = {}
    for cell in nb.cells:
        for m in SOLUTION.finditer(cell.source) if cell.cell_type == "code" else ():
            for node in ast.walk(ast.parse(textwrap.dedent(m.group(2)))):
                if isinstance(node, FORMULAS) and sum(1 for _ in ast.walk(node)) >= min_nodes:
                    out[_key(node)] = ast.unparse(node)
    return out


def solution_leaks(visible: nbformat.NotebookNode, solutions: dict[str, str]) -> list[str]:
    """``cell k: formula`` for each solution formula (spelled in any way: quotes, 20 or 20.0, spaces)
    found in a code cell of ``visible``, outside its solution regions and hidden tests."""
    found = []
    for k, cell in enumerate(visible.cells):
        if cell.cell_type != "code":
            continue
        stub = SOLUTION.sub(lambda m: f"{m.group(1)}raise NotImplementedError()\n", HIDDEN.sub("", cell.source))
        tree = ast.parse(stub)  # as nbgrader releases it
        found += [
            f"cell {k}: {ast.unparse(n)}" for n in ast.walk(tree) if isinstance(n, ast.expr) and _key(n) in solutions
        ]
    return found


def _source(lab: str) -> nbformat.NotebookNode:
    return nbformat.read(SOURCE / lab / f"{lab}.ipynb", as_version=4)


def test_solution_leaks_finds_a_solution_written_differently_outside_its_region():
    nb = nbformat.v4.new_notebook()
    nb.cells = [
        nbformat.v4.new_code_cell(
            'x = ...\n### BEGIN SOLUTION\nx = 100 * orb1["ate_rmse"] / seq1.path_length\n### END SOLUTION'
        ),
        nbformat.v4.new_code_cell("print(f\"{100 * orb1['ate_rmse'] / seq1.path_length:.2f} %\")"),
        nbformat.v4.new_code_cell("y = 1 - (20.0 - min(delta, 20.0)) / T  # not a solution here"),
    ]
    assert solution_leaks(nb, solution_expressions(nb)) == [
        "cell 1: 100 * orb1['ate_rmse'] / seq1.path_length",
        "cell 1: 100 * orb1['ate_rmse']",
    ]


@pytest.mark.parametrize("lab", LABS)
def test_no_solution_appears_outside_its_region(lab):
    """What `make student` keeps of a lab (every cell but the solution regions and hidden tests)
    shows none of the solutions' formulas: not in an explanation cell, not in an f-string."""
    nb = _source(lab)
    assert solution_leaks(nb, solution_expressions(nb)) == []


@pytest.mark.parametrize("lab", LABS)
def test_a_lab_runs_on_the_sample_data_unless_its_parameters_name_a_folder(lab, data, monkeypatch, capsys):
    """The answers' reference numbers depend on the data: a student with the wheel (the sample data)
    and the grader with the full data found in ../shared/data or $LORISNB_DATA would disagree (F2's
    best algorithm differs). The lab's data is its data_root parameter, else the sample data."""
    setup = next(c.source for c in _source(lab).cells if "ln.setup(" in c.source)
    assert "teach.lab_data(data_root)" in setup and "sample=True" not in setup
    monkeypatch.setenv("LORISNB_DATA", str(data.root))
    assert ln.find_data().root == data.root  # what a notebook finding "its" data would use
    assert teach.lab_data().root == sample_data().root
    assert "every student and the grader evaluate on the same data" in capsys.readouterr().out
    assert teach.lab_data(str(data.root)).root == data.root  # the teacher's explicit choice, for all


@pytest.mark.parametrize(("eps", "phi"), [(1.0, 30.0), (5.0, 50.0), (0.2, 10.0), (3.0, 180.0)])
def test_question_c2_holds_for_any_thresholds(eps, phi):
    """Question C2 (a wrong re-localization) as the lab builds it: the jump scales with eps, so the
    instructor's answer (CS-R = 0) is right and the explanation does not contradict itself."""
    lab = _source("lab1_lifelong_metrics")
    question = next(c.source for c in lab.cells if "wrong_reloc_question" in c.source)
    scope = {"eps": eps, "phi": phi, "display": lambda *a: None, "Markdown": str, "teach": teach}
    exec(question, scope)  # noqa: S102 (the lab's own cell)
    offset, yaw = scope["reloc_offset_m"], scope["reloc_yaw_deg"]
    gt = ln.load_groundtruth("cafe", sample_data())
    faults = {
        1: Faults(position_noise_m=0.05, seed=0),
        2: Faults(wrong_reloc_at_s=0.0, wrong_reloc_offset_m=(offset, 0.0, 0.0), wrong_reloc_yaw_deg=yaw),
    }
    fe = simulated_errors(gt, faults, seqs=[1, 2])
    visit = ln.score(fe, eps, phi, 1.0, 60.0).set_index("seq").loc[2]
    assert visit["cs_r"] == 0.0 and not visit["first_correct"]
    text = teach.explain_wrong_reloc(visit, fe.sequences[1], eps, phi, 60.0)
    assert f"first pose is wrong (ATE {offset:.2f} m > eps = {eps:g} m" in text
    assert ("≤ phi" in text) == (yaw <= phi) and "CS-R = 0.000" in text
    assert f"{offset:g} m off" in teach.wrong_reloc_question(offset, yaw, eps, phi)


def test_explanations_quote_their_numbers():
    gap = teach.explain_gap(0.666, 0.0, (15.0, 35.0), 1.0, 57.0)
    assert "1 - (20 - 1) / 57.0 = 0.667" in gap
    assert "min(delta, 20 s) = 20 s" in teach.explain_gap(0.6, 0.0, (15.0, 35.0), 30.0, 57.0)
    g = teach.explain_ate_percent(0.473, 30.5, {"difficult": 0.758, "very difficult": 0.933}, 12.0)
    assert f"{100 * 0.473 / 30.5:.2f} %" in g and "0.76 % (difficult)" in g and "12 m path" in g
    lab = "\n".join(c.source for c in _source("lab1_lifelong_metrics").cells)
    assert "1 % of a 12 m path" not in lab and "eps_for_half" not in lab
