"""What the notebooks' stored source must hold, read without running them (fast): the evaluation
spec of a notebook that evaluates the user's results comes from its parameters (``session.spec()``,
as the report's leaderboard builds its own), so ``lorisnb report -p scale off`` reaches it."""

from __future__ import annotations

import ast

import nbformat
import pytest

from lorisnb.tools.report.build import notebook_dir
from lorisnb.tools.report.notebooks import declared_parameters

NOTEBOOKS = sorted(notebook_dir().glob("*.ipynb"))


def _code(path) -> ast.Module:
    nb = nbformat.read(path, as_version=4)
    return ast.parse("\n".join(c.source for c in nb.cells if c.cell_type == "code" and not c.source.startswith("%")))


def _evaluate_calls(tree: ast.Module) -> list[ast.Call]:
    return [
        node
        for node in ast.walk(tree)
        if isinstance(node, ast.Call)
        and isinstance(node.func, ast.Attribute)
        and node.func.attr in ("evaluate", "evaluate_pairs", "evaluate_manifest")
    ]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_a_notebook_of_the_users_results_evaluates_with_the_sessions_spec(path):
    """A notebook that evaluates a ``results_dir`` declares the alignment (``scale``) and passes its
    evaluation the spec of its parameters, never a fixed ``scale=...``: compare_algorithms evaluated at
    ``scale="auto"`` while the report's leaderboard, given ``-p scale off``, was at SE(3)."""
    declared = declared_parameters(path)
    calls = _evaluate_calls(_code(path))
    if "results_dir" not in declared or not calls:
        pytest.skip("evaluates no results of the user's")
    assert {"scale", "official_interpolation"} <= set(declared), "the spec options it honours, declared"
    for call in calls:
        fixed = [k.arg for k in call.keywords if k.arg in ("scale", "official_interpolation", "eps", "phi")]
        assert not fixed, f"line {call.lineno}: {fixed} fixed in the call instead of the session's spec"
        assert call.args[1:] and ast.unparse(call.args[1]) == "spec", f"line {call.lineno}: no spec passed"
    assert "session.spec(" in ast.unparse(_code(path))


def _labels_of(tree: ast.Module, column: str) -> list[str]:
    """The labels given (``rename_axis(columns=...)``, ``title=``) to a table or figure of ``column``."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and column in {
            n.value for n in ast.walk(node) if isinstance(n, ast.Constant) and isinstance(n.value, str)
        }:
            found += [
                k.value.value
                for k in node.keywords
                if k.arg in ("columns", "title", "label") and isinstance(k.value, ast.Constant)
            ]
    return found


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_the_c_ate_rmse_is_never_labelled_ate_rmse(path):
    """``c_ate_rmse`` is over correct poses only: a table of it titled "ATE RMSE (m)"
    (per_sequence_benchmark's) says it is over all poses, which is false at any finite threshold."""
    labels = _labels_of(_code(path), "c_ate_rmse")
    assert all("C-ATE" in label for label in labels if "ATE" in label), labels
    nb = nbformat.read(path, as_version=4)
    for cell in nb.cells:
        if cell.cell_type == "markdown" and "bottom right" in cell.source:  # the timeline's per-scene numbers
            assert "C-ATE" in cell.source.split("bottom right", 1)[1][:40], cell.source


def test_the_timeline_says_what_its_numbers_are():
    import matplotlib

    matplotlib.use("Agg")
    from lorisnb.tools.figures.plotting import TIMELINE_XLABEL

    assert "C-ATE RMSE" in TIMELINE_XLABEL and "correct poses" in TIMELINE_XLABEL


def test_compare_algorithms_scores_as_compare_does():
    """compare_algorithms (a report's compare page) scored the evaluated sequences alone, so a sequence an
    algorithm lacked dropped out of its scene value: its intervals, test and ranking of the results are
    ``lorisnb compare``'s (:func:`lorisnb.tools.notebook.comparison.scene_comparison`), never the
    statistics called on the per-sequence table directly."""
    code = ast.unparse(_code(notebook_dir() / "compare_algorithms.ipynb"))
    assert "scene_comparison(table, ev.durations()" in code
    for call in ("confidence_intervals(table", "pairwise(table", "ranking(table"):
        assert call not in code, call
