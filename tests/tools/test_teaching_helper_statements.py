"""Helper cells and unused imports of lorisnb, statement by statement (the adversarial pass grading2
on GRADER_VERSION 11): an import statement was one unit (``import lorisnb as ln, math`` kept whole:
refused; ``import lorisnb as ln, pandas as pd`` dropped whole: pd lost; ``import lorisnb as ln;
STRICT = False`` blanked as a line: STRICT lost), a function's own local ``ln`` counted as a use of
the import, and a helper cell's top-level constants, lambdas and aliases were left out of a formula
run alone (hconst, hlambda, halias), its NameError saying "define or import `_held`" though the
student had."""

from __future__ import annotations

from pathlib import Path

import nbformat
import pytest
from test_teaching_added_below import _settings
from test_teaching_hardening import _solved

from lorisnb.tools.teaching.autograde import definitions_only, earlier_functions, without_lorisnb

pytestmark = pytest.mark.xdist_group("grading")

LAB = "lab1_lifelong_metrics"
SOURCE_NB = Path(__file__).resolve().parents[2] / "teaching" / "source" / LAB / f"{LAB}.ipynb"


def test_only_the_unused_lorisnb_names_are_left_out_statement_by_statement():
    assert without_lorisnb("import lorisnb as ln, math\nx = math.pi\n") == "import math\nx = math.pi\n\n"
    assert without_lorisnb("import lorisnb as ln; STRICT = False\n") == "STRICT = False\n\n"
    local = "import lorisnb as ln\ndef f(x):\n    ln = -x\n    return ln\n"
    assert without_lorisnb(local) == "\n" + local.split("\n", 1)[1] + "\n"
    used = "import lorisnb as ln\ndef f(x):\n    return ln.score(x)\n"
    assert without_lorisnb(used) == used  # read as the module's: kept, the guard refuses it
    assert definitions_only("import lorisnb as ln, pandas as pd\n", lorisnb=False) == "import pandas as pd\n"
    helper = ("GAP_FLOOR = 0.0\n_held = lambda t, d=GAP_FLOOR: max(t, d)\ndef _impl(x):\n    return x\n"
              "_decay = _impl\nref = eps\nbest = _impl(2)\nINF = np.inf\n")  # fmt: skip
    kept = earlier_functions({"k": helper}, ["k"])
    assert "GAP_FLOOR = 0.0" in kept and "_held = lambda" in kept and "_decay = _impl" in kept and "INF" in kept
    assert "ref = eps" not in kept and "best =" not in kept  # a lab's value, a call's result: never


HELD_CR = ("def correct_rate(stamps, correct, t_min, t_max, delta):\n"
           "    return float(np.sum(_held(stamps, t_max, delta) * np.asarray(correct)) / (t_max - t_min))\n")  # fmt: skip
HELD = "np.minimum(np.diff(np.append(np.asarray(stamps, float), t_max)), delta)"


@pytest.mark.slow
def test_honest_helpers_and_imports_score_in_the_lab(tmp_path):
    from lorisnb.tools.teaching.autograde import grade_submission, lab_spec

    nb, _ = _solved({
        "A1_correctness": lambda s: "import lorisnb as ln; STRICT = False\n\ndef correctness(ate_m, aoe_deg, eps, phi):\n"
            "    a, o = np.asarray(ate_m), np.asarray(aoe_deg)\n"
            "    return ((a < eps) & (o < phi)) if STRICT else ((a <= eps) & (o <= phi))\n",
        "B2_correct_rate": lambda s: HELD_CR.replace("np.sum(", "pd.Series(") .replace("* np.asarray(correct))",
                                                                                      "* np.asarray(correct)).sum()"),
        "C1_cs_r": lambda s: "import lorisnb as ln, math\n\ndef cs_r(t0, t_min, first_correct, tau):\n"
            "    ln = -(t0 - t_min) / tau\n    return _decay(math.exp(ln)) if first_correct else 0.0\n",
    })  # fmt: skip
    added = {  # below each answer, up to its check
        "A1_correctness": "import lorisnb as ln, pandas as pd\n",
        "B2_correct_rate": f"GAP_FLOOR = 0.0\n_held = lambda stamps, t_max, delta, f=GAP_FLOOR: np.maximum({HELD}, f)\n",
        "C1_cs_r": "def _same(x):\n    return float(x)\n_decay = _same\n",
    }
    for gid, src in added.items():
        at = next(i for i, c in enumerate(nb.cells) if c.metadata.get("nbgrader", {}).get("grade_id") == gid)
        nb.cells.insert(at + 1, nbformat.v4.new_code_cell(src))
    release = tmp_path / "release"
    release.mkdir()
    path = tmp_path / "s" / f"{LAB}.ipynb"
    path.parent.mkdir()
    nbformat.write(nb, path)
    res = grade_submission(lab_spec(SOURCE_NB), release, path, "s-helpers", _settings())
    lost = {s.question: s.message for s in res.scores if s.points < s.max_points}
    assert lost == {}, (lost, res.notes)
    assert res.points == res.max_points

    # a helper's value read from the lab's variables is not given: the NameError says why, not "define it"
    nb.cells[at + 1].source = "_decay = float if T > 0 else None\n"  # C1's helper cell
    path.write_text(nbformat.writes(nb))
    res = grade_submission(lab_spec(SOURCE_NB), release, path, "s-helpers", _settings())
    lost = {s.question: s.message for s in res.scores if s.points < s.max_points}
    assert set(lost) == {"test_C1_cs_r"}, (lost, res.notes)
    assert "`_decay` is assigned in your added cell 1 after cell" in lost["test_C1_cs_r"], lost
    assert "define or import `_decay`" not in lost["test_C1_cs_r"]


@pytest.mark.slow
def test_a_helper_cell_that_uses_lorisnb_when_defined_is_named_not_the_answers_given_it(tmp_path):
    """A helper cell whose def-time default imports lorisnb (``m=__import__('lorisnb')``) was run with
    the other helpers as one block, and each answer given it was told "its code tried to use
    lorisnb": a prediction that reads only the lab's numbers among them. The refusal names that cell."""
    from lorisnb.tools.teaching.autograde import grade_submission, lab_spec

    nb, _ = _solved({})
    at = next(i for i, c in enumerate(nb.cells) if c.metadata.get("nbgrader", {}).get("grade_id") == "A1_correctness")
    nb.cells.insert(at + 1, nbformat.v4.new_code_cell("def _unit(x, m=__import__('lorisnb')):\n    return x\n"))
    release = tmp_path / "release"
    release.mkdir()
    path = tmp_path / "s" / f"{LAB}.ipynb"
    path.parent.mkdir()
    nbformat.write(nb, path)
    res = grade_submission(lab_spec(SOURCE_NB), release, path, "s-default", _settings())
    lost = {s.question: s.message for s in res.scores if s.points < s.max_points}
    assert {"test_A1_correctness", "test_B1_prediction", "test_B2_correct_rate"} <= set(lost), (lost, res.notes)
    for q, message in lost.items():
        assert "refused (0 points): your added cell 1 after cell" in message, (q, message)
        assert "its code tried to use lorisnb" not in message, (q, message)
    assert (
        "the prediction B1_prediction: refused (0 points): your added cell 1 after cell" in lost["test_B1_prediction"]
    )
