"""The checks a student sees while working never print the number (or the choice) they check
against (the adversarial teaching pass: "you answered 0; lorisnb computes 0.6662" let 11 of lab 1's
18 points be typed in with no work). A wrong answer is told too high or too low, and by roughly how
much, with the hint of its mistake; a right one may show lorisnb's number."""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

import nbformat
import numpy as np
import pytest

from lorisnb.errors import AnswerError
from lorisnb.tools import teaching as teach

ROOT = Path(__file__).resolve().parents[2]
LAB = "lab1_lifelong_metrics"
NB = ROOT / "teaching" / "source" / LAB / f"{LAB}.ipynb"
HIDDEN = re.compile(r"^[ \t]*### BEGIN HIDDEN TESTS.*?### END HIDDEN TESTS[ \t]*\n?", re.S | re.M)

# the value questions: (answer cell, test cell, the answer's names, in the order the test checks them)
QUESTIONS = [
    ("B1_prediction", "test_B1_prediction", ["predicted_cr_lost"]),
    ("B3_prediction", "test_B3_prediction", ["predicted_cr_t_late"]),
    ("C2_prediction", "test_C2_prediction", ["predicted_cs_r_wrong"]),
    ("D1_alignment", "test_D1_alignment", ["cr_visit2_lifelong", "cr_visit2_per_seq"]),
    ("E1_threshold", "test_E1_threshold", ["eps_for_cr"]),
    ("F_timeline", "test_F_timeline", ["silent_in_visit2", "best_cr"]),
    ("G1_difficulty", "test_G1_difficulty", ["ate_percent_cafe"]),
]


def _gid(cell: nbformat.NotebookNode) -> str:
    return str(cell.metadata.get("nbgrader", {}).get("grade_id", ""))


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """Lab 1 run whole with the instructor's answers (hidden tests left out, its figures written in a
    temporary folder), as a student's kernel holds it: (its scope, its cells by grade_id)."""
    nb = nbformat.read(NB, as_version=4)
    cells = {_gid(c): c for c in nb.cells if c.cell_type == "code"}
    scope: dict = {}
    out = tmp_path_factory.mktemp("lab1")
    with contextlib.redirect_stdout(io.StringIO()):
        for c in nb.cells:
            if c.cell_type != "code":
                continue
            source = HIDDEN.sub("", c.source)
            if "parameters" in c.metadata.get("tags", []):
                source += f"\noutput_dir = {str(out)!r}\nstudent_id = 's1234567'\n"
            exec(source, scope)  # noqa: S102 (the lab's own cells)
    return scope, cells


def _message(scope: dict, cell: str) -> str:
    with contextlib.redirect_stdout(io.StringIO()), pytest.raises(AnswerError) as exc:
        exec(cell, scope)  # noqa: S102
    return str(exc.value)


def _tail(message: str) -> str:
    """What a failed check says after "you answered <the answer>,": the bands of ``how_far`` and the
    tolerance, which name no reference, taken out."""
    tail = message.split("you answered", 1)[1].split(",", 1)[1].split("\nHint", 1)[0]
    return re.sub(r"by between \S+ and \S+|\(tolerance [^)]*\)", "", tail)


def _printed(value: float) -> list[str]:
    return [f"{value:{f}}" for f in (".4g", ".3g", ".3f", ".2f")] + ([f"{100 * value:.1f}"] if abs(value) <= 1 else [])


@pytest.mark.thorough
@pytest.mark.parametrize(("answer_cell", "test_cell", "names"), QUESTIONS)
@pytest.mark.parametrize("wrong", ["low", "high"])
def test_a_wrong_value_is_told_too_high_or_too_low_never_the_reference(lab, answer_cell, test_cell, names, wrong):
    scope, cells = lab
    test = cells[test_cell].source
    refs = {n: scope[n] for n in names}  # the instructor's answers: what the checks compare with
    try:
        for n in names:
            ref = float(refs[n])
            bad = (ref - 0.5 - abs(ref)) if wrong == "low" else (ref + 0.5 + abs(ref))
            if isinstance(refs[n], (int, np.integer)):
                bad = int(round(bad))
            scope[n] = bad
            msg = _message(scope, test)
            assert f"too {wrong}" in msg, msg
            assert "computes" not in msg and "lorisnb gives" not in msg, msg
            tail = _tail(msg)
            for shown in _printed(ref):
                assert shown not in tail, (shown, msg)
            scope[n] = refs[n]  # right again: the next name of the cell is checked
    finally:
        scope.update(refs)


@pytest.mark.thorough
def test_a_wrong_best_algorithm_is_not_told_the_right_one(lab):
    scope, cells = lab
    best = scope["best_algorithm"]
    others = [a for a in scope["life_scenes"]["algorithm"] if a != best]
    try:
        for other in others:
            scope["best_algorithm"] = other
            msg = _message(scope, cells["test_F_timeline"].source)
            assert "which is not right" in msg and best not in msg, msg
    finally:
        scope["best_algorithm"] = best


def test_check_value_says_the_side_and_the_order_of_the_difference():
    for answer, side, band in [(0.0, "too low", "between 0.1 and 1"), (5.0, "too high", "between 1 and 10"),
                               (0.66, "too low", "just outside the tolerance"),
                               (0.6962, "too high", "between 0.01 and 0.1")]:  # fmt: skip
        with pytest.raises(AnswerError) as exc:
            teach.check_value("B1", answer, 0.6662, tol=0.005)
        msg = str(exc.value)
        assert side in msg and band in msg and "0.6662" not in msg and "0.666" not in msg, msg
    assert teach.check_value("B1", 0.667, 0.6662, tol=0.005)  # right: its line may show lorisnb's number


def test_a_formula_on_the_hidden_cases_is_not_given_their_values():
    """The grader's feedback shows the hidden tests' messages; with resubmissions, their values
    would let a formula return them case by case. The public hand-made cases still show lorisnb's."""
    import lorisnb as ln
    from lorisnb.core.simulate import Faults, simulated_errors
    from lorisnb.io.datasets.paths import sample_data

    gt = ln.load_groundtruth("cafe", sample_data())
    fe = simulated_errors(gt, Faults(position_noise_m=0.3, lost=((5.0, 9.0),), seed=3), seqs=[1])
    cases = teach.cases_from(fe, 0.5, 10.0, 0.3, 60.0)

    def nan_cs_r(t0, t_min, first_correct, tau):
        return float("nan")

    def half(stamps, correct, t_min, t_max, delta):
        return 0.5

    for check, fn, kind in [(teach.check_cs_r, nan_cs_r, "cs_r"), (teach.check_correct_rate, half, "correct_rate")]:
        with pytest.raises(AnswerError) as visible:
            check(fn)
        assert "lorisnb gives" in str(visible.value)
        with pytest.raises(AnswerError) as hidden:
            check(fn, cases[kind])
        assert "lorisnb gives" not in str(hidden.value), str(hidden.value)
    want = teach._checks._cr(**cases["correct_rate"][0])
    assert "you return 0.5, too " in str(hidden.value)
    assert not any(s in _tail(str(hidden.value).replace("you return", "you answered")) for s in _printed(want))
