"""Cells a student adds right below an answer cell, as the notebook's check sees them (the adversarial
pass grading4): a formula's helper defined below it (up to its check) is given to its run alone; a
value computed below it (before the lab's next cell) is read there, and a name left unset without
the placeholder is told so, not "no answer yet"; a formula's NameError run alone says what it has
there (the lab's ``import pandas as pd`` to put in the cell); an unused ``import lorisnb`` in a
formula costs nothing; a float32 result is named."""

from __future__ import annotations

import copy
from pathlib import Path

import nbformat
import numpy as np
import pytest
from test_teaching_cells import _answered, _meta, _tiny_lab

from lorisnb.errors import AnswerError
from lorisnb.tools.teaching.sandbox import Limits, can_isolate

pytestmark = pytest.mark.xdist_group("grading")

ROOT = Path(__file__).resolve().parents[2]
LAB = "lab1_lifelong_metrics"
SOURCE_NB = ROOT / "teaching" / "source" / LAB / f"{LAB}.ipynb"


def _settings():
    from lorisnb.tools.teaching.autograde import GradeSettings
    from lorisnb.tools.teaching.sandbox import claim_uids

    return GradeSettings(Limits(cell_timeout_s=30, locked_timeout_s=180), secret="s",
                         uid=claim_uids(63000) if can_isolate() else 0)  # fmt: skip


def _lab_with_a_reference() -> nbformat.NotebookNode:
    """The tiny lab with a cell of the lab's between the formula A and its check, setting ``ref``."""
    nb = _tiny_lab()
    at = next(i for i, c in enumerate(nb.cells) if c.metadata.get("nbgrader", {}).get("grade_id") == "A_fn")
    nb.cells.insert(at + 1, nbformat.v4.new_code_cell("ref = 2.0", metadata=_meta("lab_ref")))
    return nb


def _grade(tmp_path: Path, lab: nbformat.NotebookNode, student_nb: nbformat.NotebookNode, name: str):
    from lorisnb.tools.teaching.autograde import grade_submission, lab_spec

    path = tmp_path / "tiny.ipynb"
    if not path.exists():
        nbformat.write(lab, path)
        (tmp_path / "release").mkdir()
    student = tmp_path / name / "tiny.ipynb"
    student.parent.mkdir()
    nbformat.write(student_nb, student)
    return grade_submission(lab_spec(path), tmp_path / "release", student, name, _settings())


def _below(answers: dict, added: dict, lab: nbformat.NotebookNode) -> nbformat.NotebookNode:
    """``_answered`` on ``lab``: answers by grade_id, cells added after a cell (by grade_id)."""
    import test_teaching_cells

    made = test_teaching_cells._tiny_lab
    test_teaching_cells._tiny_lab = lambda: copy.deepcopy(lab)  # the cells laid out as in ``lab``
    try:
        return _answered(answers, added)
    finally:
        test_teaching_cells._tiny_lab = made


@pytest.mark.slow
def test_helpers_and_values_in_cells_added_below_an_answer_are_graded_as_the_notebook_saw_them(tmp_path):
    """grading4's hbelow/hbelowA (a helper defined in a cell added under the formula, above its check:
    0, NameError) and haddval (the value computed in a cell added under the answer: 0, "no answer
    yet (replace the `...` and the NotImplementedError placeholder)", though neither was there)."""
    lab = _lab_with_a_reference()
    honest = _below(
        {"A_fn": [("import lorisnb as ln  # unused\ndef double(x):\n    return _scale(x)", None)],
         "B_pred": [("def _half(t):\n    return t / 2", None)],
         "C_val": [("def _times(a, b):\n    return a * b", None)]},
        {"A_fn": ["def _scale(x, f=k - 1):\n    return f * x"],  # k: the lab's, before the answer (k - 1 = 2)
         "B_pred": ["pred = _half(T)"], "C_val": ["val = _times(k, T)"]},
        lab,
    )  # fmt: skip
    res = _grade(tmp_path, lab, honest, "s-below")
    lost = {s.question: s.message for s in res.scores if s.points < s.max_points}
    assert lost == {}, (lost, res.notes)
    assert any("C_val: val set in the cell(s) you added right below the answer cell" in n for n in res.notes)
    assert any("A_fn: its unused import of lorisnb is left out" in n for n in res.notes), res.notes

    # a helper below may read, when defined, the lab's values as they were at the answer, never one the lab
    # sets between the answer and its check (a reference value): ref is not given, the call fails saying so
    forger = _below({"A_fn": [("def double(x):\n    return _scale(x)", None)]},
                    {"lab_ref": ["def _scale(x, f=ref):\n    return f * x"]}, lab)  # fmt: skip
    res = _grade(tmp_path, lab, forger, "s-ref")
    lost = {s.question: s.message for s in res.scores if s.points < s.max_points}
    assert set(lost) == {"test_A_fn"}, (lost, res.notes)
    assert "NameError" in lost["test_A_fn"] and "_scale" in lost["test_A_fn"], lost
    assert any("cells you added below it" in n and "name 'ref' is not defined" in n for n in res.notes), res.notes

    # no value set, and no placeholder: said so, not "no answer yet"; the placeholder left: "no answer yet"
    unset = _below({"C_val": [("def _times(a, b):\n    return a * b", None)],
                    "B_pred": [("pred = ...\nraise NotImplementedError()", None)]},
                   {"test_C_val": ["val = _times(k, T)"]}, lab)  # fmt: skip
    res = _grade(tmp_path, lab, unset, "s-unset")
    lost = {s.question: s.message for s in res.scores if s.points < s.max_points}
    assert set(lost) == {"test_C_val", "test_B_pred"}, (lost, res.notes)
    assert "`val` is not set by your answer cell, nor by a cell you added right below it" in lost["test_C_val"]
    assert "no answer yet" not in lost["test_C_val"]


@pytest.mark.slow
def test_the_lab_graded_whole_with_helpers_and_values_below_and_a_missing_import_said(tmp_path):
    """Lab 1 on its sample data, as grading4's students wrote it: A1's helper and C1's helper (with the
    lab's tau read when defined) in cells added below them, E1's and G1's values computed in cells added
    below (E1's answer cell defines the function), an unused `import lorisnb as ln` in A1's cell; B2 uses
    the lab's `pd` without importing it: its NameError says to import it in the cell."""
    from test_teaching_hardening import _solved

    from lorisnb.tools.teaching.autograde import grade_submission, lab_spec

    nb, _ = _solved({
        "A1_correctness": lambda s: "import lorisnb as ln\n\ndef correctness(ate_m, aoe_deg, eps, phi):\n"
                                    "    return within(ate_m, eps) & within(aoe_deg, phi)\n",
        "B2_correct_rate": lambda s: (
            "def correct_rate(stamps, correct, t_min, t_max, delta):\n    s = pd.Series(np.asarray(stamps, float))\n"
            "    held = (s.shift(-1).fillna(t_max) - s).clip(upper=delta)\n"
            "    return float((held * np.asarray(correct)).sum() / (t_max - t_min))\n"),
        "C1_cs_r": lambda s: "def cs_r(t0, t_min, first_correct, tau):\n    return _decay(t0 - t_min, tau) if first_correct else 0.0\n",
        "E1_threshold": lambda s: "def smallest_eps(target):\n    from lorisnb.core.lifelong.sweep import eps_at_cr\n"
                                  "    return eps_at_cr(ev_orb.errors, target, ev_orb.durations(), phi, delta)['eps'].iloc[0]\n",
        "G1_difficulty": lambda s: "def pct(row, seq):\n    return 100 * row['ate_rmse'] / seq.path_length\n",
    })  # fmt: skip
    below = {
        "A1_correctness": "def within(x, limit):\n    return np.asarray(x) <= limit\n",
        "C1_cs_r": "import math\ndef _decay(dt, scale=tau):\n    return math.exp(-dt / scale)\n",
        "E1_threshold": "eps_for_cr = smallest_eps(target_cr)\nprint(eps_for_cr)",
        "G1_difficulty": "ate_percent_cafe = pct(orb_seq, gt_seq)",
    }
    for gid, src in below.items():
        at = next(i for i, c in enumerate(nb.cells) if c.metadata.get("nbgrader", {}).get("grade_id") == gid)
        nb.cells.insert(at + 1, nbformat.v4.new_code_cell(src))
    release = tmp_path / "release"
    release.mkdir()
    path = tmp_path / "s" / f"{LAB}.ipynb"
    path.parent.mkdir()
    nbformat.write(nb, path)
    res = grade_submission(lab_spec(SOURCE_NB), release, path, "s-below", _settings())
    lost = {s.question: s.message for s in res.scores if s.points < s.max_points}
    assert set(lost) == {"test_B2_correct_rate"}, (lost, res.notes)
    assert "NameError: name 'pd' is not defined" in lost["test_B2_correct_rate"]
    assert "put `import pandas as pd` in your answer cell" in lost["test_B2_correct_rate"], lost
    assert res.points == res.max_points - 3


def test_a_float32_result_is_told_as_float32_and_a_rounded_one_as_rounded():
    """grading4's hf32: B2 computed in float32 was refused with "they differ by 2.5e-08 ... rounded?"."""
    from lorisnb.tools.teaching import check_correct_rate

    def f32(stamps, correct, t_min, t_max, delta):
        s = np.asarray(stamps, np.float32)
        held = np.minimum(np.diff(np.append(s, t_max)), delta)
        return float(np.sum(held * np.asarray(correct)) / (t_max - t_min))

    def rounded(stamps, correct, t_min, t_max, delta):
        held = np.minimum(np.diff(np.append(np.asarray(stamps, float), t_max)), delta)
        return round(float(np.sum(held * np.asarray(correct)) / (t_max - t_min)), 6)

    def all_f32(stamps, correct, t_min, t_max, delta):  # float32 arithmetic throughout
        held = np.minimum(np.diff(np.append(np.asarray(stamps, np.float32), np.float32(t_max))), np.float32(delta))
        return np.sum(held * np.asarray(correct, np.float32)) / np.float32(t_max - t_min)

    for fn in (f32, all_f32):
        with pytest.raises(
            AnswerError, match=r"you return 0\.3650000\d+; lorisnb gives 0\.365 .*computed in float32\?"
        ):
            check_correct_rate(fn)
    with pytest.raises(AnswerError, match=r"rounded to 6 decimal\(s\)\?") as err:
        check_correct_rate(rounded)
    assert "float32" not in str(err.value)


@pytest.mark.parametrize("offset", [1e-7, -2e-7, 3e-8])
def test_a_small_offset_is_told_close_not_float32(offset):
    """adversarial teaching pass: cs_r + 1e-7 (3.8e-6 relative at most) was told "computed in
    float32? ... leave out np.float32", which it never used."""
    from lorisnb.tools.teaching import check_cs_r

    def shifted(t0, t_min, first_correct, tau):
        return float(np.exp(-(t0 - t_min) / tau)) * first_correct + offset

    with pytest.raises(AnswerError) as err:
        check_cs_r(shifted)
    assert "float32" not in str(err.value) and "close, but not the formula's value" in str(err.value)
