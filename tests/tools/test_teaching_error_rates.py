"""The measured error rates of lab 1's grader (lorisnb.tools.teaching.errorrates,
teaching/grading_error_rates.py; teaching/README.md, "How often a grade is wrong"): the corpus holds
every typical mistake that applies to each question, each wrong answer really is wrong (and each
right formula right) by lorisnb's own numbers, the intervals are Wilson's, a quick run of the
harness through the grader's sandboxes finds no grading error and names each mistake's hint, the
route of `make grade` agrees with it, and the docs quote one table whose rates and intervals
follow from its counts. The grading errors the harness found stay fixed."""

from __future__ import annotations

import ast
import inspect
import math
import re
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from helpers import temp_dir_left_as_found

import lorisnb as ln
from lorisnb.errors import AnswerError
from lorisnb.io.datasets.paths import sample_data
from lorisnb.tools import teaching as teach
from lorisnb.tools.teaching import _checks, _labs
from lorisnb.tools.teaching import errorrates as er
from lorisnb.tools.teaching.autograde import PRELUDE, RemoteFunction, lab_spec
from lorisnb.tools.teaching.sandbox import Sandbox, can_isolate, claim_uids

ROOT = Path(__file__).resolve().parents[2]
SOURCE = ROOT / "teaching" / "source"
SOURCE_NB = SOURCE / er.LAB / f"{er.LAB}.ipynb"
SPEC = lab_spec(SOURCE_NB)


# --- the intervals -----------------------------------------------------------------------------


@pytest.mark.parametrize(("k", "n"), [(0, 50), (3, 40), (20, 20), (1, 1), (7, 300)])
def test_the_intervals_are_wilsons_on_known_counts(k, n):
    """scipy's Wilson interval, as the regression gate's own formula (calibration.wilson) and the
    textbook's give it."""
    from lorisnb.tools.decisions.calibration import wilson as gate_wilson

    lo, hi = er.wilson(k, n)
    z, p = 1.959963984540054, k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    assert lo == pytest.approx(max(0.0, centre - half), abs=1e-9) and hi == pytest.approx(min(1.0, centre + half))
    assert (lo, hi) == pytest.approx(gate_wilson(k, n), abs=1e-6)
    assert lo <= p <= hi


def test_the_table_gives_rates_and_intervals_from_the_counts():
    row = er.Rates("test_A1_correctness", 40, 0, 50, 1, 3, 10, 9, 1, 2)
    text = er.table([row])
    assert "| A1_correctness | 40 | 0 | 0.0 % [0.0, 8.8] | 50 | 1 | 2.0 % [0.4, 10.5] | 3 | 9 of 10 | 1 | 2 |" in text
    assert math.isnan(er.wilson(0, 0)[0]) and "| 0 | 0 | - - |" in er.table([er.Rates("q", 0, 0, 0, 0, 0, 0, 0, 0, 0)])


# --- the corpus --------------------------------------------------------------------------------


def _strings(fn) -> set[str]:
    """The string constants in a function's source that name a mistake."""
    tree = ast.parse(inspect.getsource(fn).lstrip() if not isinstance(fn, str) else fn)
    return {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and n.value in teach.MISTAKES}


def _test_cell(answer: str) -> str:
    q = next(q for q in SPEC.questions if answer in q.answers)
    return next(c.source for c in SPEC.notebook.cells if c.get("metadata", {}).get("nbgrader", {}).get("grade_id")
                == q.grade_id)  # fmt: skip


def test_the_corpus_holds_every_mistake_each_question_can_name():
    """Every mistake of MISTAKES applies to some question; each question's wrong answers make every
    mistake its check can name (the names in its check's code and its test cell), and only those."""
    assert set().union(*er.APPLIES.values()) == set(teach.MISTAKES)
    assert set(er.APPLIES) == set(er.CORPUS) == {a for q in SPEC.questions for a in q.answers}
    can_name = {
        "A1_correctness": _strings(teach.check_correctness) | {"elementwise", "signature"},  # check_function's
        "B2_correct_rate": _strings(teach.check_correct_rate) | _strings(_checks._rate_variants)
        | {n for n, _ in _checks._NUMERATORS} | {"signature"},
        "C1_cs_r": _strings(teach.check_cs_r) | {"nan", "signature"},
        "D1_alignment": _strings(_labs.check_alignment_cr),
        "E1_threshold": _strings(_labs.check_eps_at_cr),
        "F_timeline": _strings(_labs.check_best_cr) | _strings(teach.check_value),
        "G1_difficulty": _strings(_labs.check_ate_percent),
    }  # fmt: skip
    for cell in ("B1_prediction", "B3_prediction", "C2_prediction"):
        can_name[cell] = _strings(_test_cell(cell)) | _strings(teach.check_value)
    can_name["C2_prediction"] -= {"fraction"}  # CS-R is 0 here: in percent it is 0 too, no hint can show
    for cell, answers in er.CORPUS.items():
        made = {a.mistake for a in answers if not a.right and a.mistake}
        assert made == set(er.APPLIES[cell]) == can_name[cell], cell
        assert all(a.mistake is None for a in answers if a.right)


def test_each_answer_reads_what_its_cell_may_and_leaves_the_labs_names_alone():
    corpus = [*er.instructor_solutions(SPEC), *(a for answers in er.CORPUS.values() for a in answers)]
    er.check_corpus(SPEC, corpus)  # no error
    names = [(a.cell, a.name) for a in corpus]
    assert len(names) == len(set(names)), "two answers of one cell share a name"
    clobbers = er.Answer("D1_alignment", "x", "life = 1\ncr_visit2_lifelong = cr_visit2_per_seq = 0.0\n", True)
    reads = er.Answer("B1_prediction", "y", "predicted_cr_lost = t_lost.loc[1, 'cr']\n", True)  # after the cell
    for bad in (clobbers, reads):
        with pytest.raises(ValueError, match=bad.name):
            er.check_corpus(SPEC, [bad])


@pytest.mark.parametrize("cell", ["A1_correctness", "B2_correct_rate", "C1_cs_r"])
def test_each_wrong_formula_differs_from_lorisnbs_and_each_right_one_agrees(cell):
    """Judged apart from the grader, by lorisnb's own formula on the check's visible cases and cases
    made as the hidden tests make them: the corpus's labels are right."""
    cases = er.formula_cases(cell)
    (name,) = SPEC.functions[cell]
    for a in [*er.CORPUS[cell], *(s for s in er.instructor_solutions(SPEC) if s.cell == cell)]:
        assert er.formula_differs(a, cases, name) != a.right, (cell, a.name)


def test_the_predictions_references_are_their_test_cells():
    for cell in SPEC.predictions:
        (value,) = SPEC.values[cell]
        assert re.sub(r"\s", "", er.REFERENCE[value]).replace("'", '"') in re.sub(r"\s", "", _test_cell(cell))


# --- the harness, quick, through the grader's sandboxes ------------------------------------------


@pytest.fixture(scope="module")
def measured():
    made: list[Path] = []  # the folders this process's harness makes (under pytest-xdist each worker runs
    # this fixture: a glob of the temporary folder saw the other worker's harness at work)

    class Recorded(tempfile.TemporaryDirectory):
        def __init__(self, *args, **kwargs) -> None:
            super().__init__(*args, **kwargs)
            made.append(Path(self.name))

    with temp_dir_left_as_found(), pytest.MonkeyPatch.context() as mp:
        mp.setattr(er.tempfile, "TemporaryDirectory", Recorded)
        m = er.measure(SOURCE_NB, 2)
    assert made and not [p for p in made if p.exists()]
    return m


@pytest.mark.slow
def test_a_quick_run_finds_no_grading_error_and_names_each_mistake(measured):
    rows = {r.question: r for r in er.rates(measured.verdicts)}
    assert len(rows) == len(SPEC.questions) + 1
    total = rows["all"]
    assert total.right >= 200 and total.wrong >= 200, total  # 2 students: about 116 and 123 answers each
    assert er.errors_found(measured.verdicts) == []
    assert total.false_fail == 0 and total.false_pass == 0
    assert total.hint_right == total.named > 100 and total.hint_other == 0
    # every mistake that applies was graded as a wrong answer, but E1's scan without the delta cap,
    # which finds the right eps on the sample data (teaching/README.md says so)
    graded = {(v.answer.cell, v.answer.mistake) for v in measured.verdicts if not v.answer.right and not v.coincide}
    missing = {(c, m) for c, ms in er.APPLIES.items() for m in ms} - graded
    assert missing == {("E1_threshold", "delta_cap")}, missing
    assert {v.answer.mistake for v in measured.verdicts if v.coincide and v.answer.mistake} == {"delta_cap"}


@pytest.mark.slow
def test_each_wrong_value_is_beyond_the_tolerance_and_each_edge_within(measured):
    """A wrong answer counted is wrong by more than its check's tolerance at that student's variant
    (the others coincide and are counted apart); an answer at the edge is within it."""
    right = measured.right  # each student's right values (the test cells' references)
    values = [v for v in measured.verdicts if not SPEC.functions.get(v.answer.cell)]
    assert {v.answer.kind for v in values} == {"written", "edge", "perturbed", "copied"}
    for v in values:
        want = right[v.student][v.answer.cell]
        close = [er._close(v.values[n], want[n], er.TOLERANCE[n]) for n in want]
        if v.answer.right and v.answer.kind == "edge":
            assert all(close), (v.answer.name, v.values, want)
        elif not v.answer.right:
            assert all(close) == v.coincide, (v.answer.name, v.values, want)
            assert v.coincide or v.answer.kind != "perturbed" or not all(close)


@pytest.mark.slow
def test_make_grades_route_agrees_with_the_measurement(measured):
    """Two generated submissions (one of right answers, one of wrong ones) graded by
    gradebook.grade_class in a temporary course: every question's points are what the measurement says."""
    with temp_dir_left_as_found():
        route = er.grade_route(SOURCE, measured, n=2, jobs=2, progress=False)
    assert len(route) == 2 * len(SPEC.questions)
    assert all(r.agrees and r.measured_passed is not None for r in route), er.route_summary(route)
    assert all(r.points > 0 for r in route if r.right) and not any(r.points > 0 for r in route if not r.right)


# --- the docs quote the harness's table --------------------------------------------------------

ROW = re.compile(
    r"^\| (\**[\w ]+\**) \| (\d+) \| (\d+) \| ([\d.]+ %) (\[[\d.]+, [\d.]+\]) \| (\d+) \| (\d+) \| ([\d.]+ %) "
    r"(\[[\d.]+, [\d.]+\]) \| (\d+) \| (\d+) of (\d+) \| (\d+) \| (\d+) \|$",
    re.M,
)


def _quoted(path: Path) -> list[tuple[str, ...]]:
    text = path.read_text()
    return ROW.findall(text.split("How often a grade is wrong", 1)[1])


def test_the_docs_quote_one_table_whose_rates_follow_from_its_counts():
    guide, readme = _quoted(ROOT / "docs" / "guide" / "teaching.md"), _quoted(ROOT / "teaching" / "README.md")
    assert guide == readme and len(guide) == len(SPEC.questions) + 1
    for name, right, ff, ff_rate, ff_ci, wrong, fp, fp_rate, fp_ci, coincide, hinted, named, other, unnamed in guide:
        r = er.Rates(name, int(right), int(ff), int(wrong), int(fp), int(coincide), int(named), int(hinted),
                     int(other), int(unnamed))  # fmt: skip
        assert (ff_rate, ff_ci) == (er._pct(r.false_fail, r.right), er._ci(r.fail_ci()))
        assert (fp_rate, fp_ci) == (er._pct(r.false_pass, r.wrong), er._ci(r.pass_ci()))
    for page in (ROOT / "docs" / "guide" / "teaching.md", ROOT / "teaching" / "README.md"):
        assert "python teaching/grading_error_rates.py" in page.read_text()


# --- the grading errors found, fixed -----------------------------------------------------------


def test_a1_answered_with_a_list_scores_in_the_sandbox_as_in_the_notebook(tmp_path):
    """One boolean per pose, as a list: ✓ in the learner's notebook, 0 points in `make grade` (the
    sandbox read the list back as "not a plain value": "returned shape ()")."""
    source = "def correctness(ate_m, aoe_deg, eps, phi):\n    return [a <= eps and o <= phi for a, o in zip(ate_m, aoe_deg)]\n"
    ns: dict = {}
    exec(PRELUDE + source, ns)  # noqa: S102
    assert teach.check_correctness(ns["correctness"])
    work = Path(tempfile.mkdtemp(prefix="lorisnb-errorrates-test-"))
    work.chmod(0o711)
    uid = claim_uids(62000, 2) if can_isolate() else 62000
    try:
        (work / "fn").mkdir()
        with Sandbox(work / "fn", uid=uid + 1, no_lorisnb=True) as box:
            assert box.run(PRELUDE + source).get("ok")
            assert teach.check_correctness(RemoteFunction(box, "correctness"))
    finally:
        import shutil

        shutil.rmtree(work)


def test_e1_answered_with_a_one_value_series_is_read_as_its_number():
    """`eps_at_cr(...)['eps']` (a one-row Series, read back as a one-value array): the check took it
    for NaN and said "degrees vs radians"."""
    from lorisnb.core.lifelong.sweep import eps_at_cr

    data = sample_data()
    ev = ln.evaluate(sorted((data.icra20 / "per-seq" / "orbslam2_t265").glob("cafe*.txt")), data_root=data)
    right = eps_at_cr(ev.errors, 0.3, ev.durations(), 30.0, 1.0)["eps"]
    for answer in (right, right.to_numpy(), pd.Series([float(right.iloc[0])])):
        assert teach.check_eps_at_cr(answer, ev.errors, ev.durations(), 0.3, 30.0, 1.0)
    with pytest.raises(AnswerError) as exc:
        teach.check_eps_at_cr(np.array([0.1, 0.2]), ev.errors, ev.durations(), 0.3, 30.0, 1.0)
    assert "expected one number" in str(exc.value) and "Hint" not in str(exc.value)


# --- forgeries ------------------------------------------------------------------------------------


def test_forged_answers_write_the_solutions_replies_over_wrong_values():
    """The forged cells hold wrong values (their own names) and carry the solution aside: a
    prediction, a formula (its function returns a wrong number) and a value answer."""
    for cell in er.FORGED_CELLS:
        src = er.forged_source(SPEC, cell, "sync")
        compile(src, cell, "exec")
        assert "_lx_forge(" in src and "exec(" in src
        for name in SPEC.values.get(cell, ()):
            assert f"{name} = -0.123" in src
        for name in SPEC.functions.get(cell, ()):
            assert f"def {name}(*args, **kwargs)" in src and "return 0.123" in src


@pytest.mark.slow
def test_forged_submissions_graded_whole_score_nothing_where_the_grader_can_see_it():
    """Two forged submissions graded by make grade's route (replies forged with the solution's
    values: a second reply; a reply and the grader's sync answered): each forged answer scores 0
    and its grade says the code wrote into the grader's channel; the summary counts them."""
    with temp_dir_left_as_found():
        forged = er.forgery_route(SOURCE, jobs=2, progress=False, techniques=("reply", "sync"))
    assert len(forged) == 2 * len(er.FORGED_CELLS)
    assert all(f.found for f in forged), [f for f in forged if not f.found]
    assert "findable forged answers that scored: 0 of 6 (6 told as forgeries)" in er.forgery_summary(forged)
