"""Answer cells as the notebook ran them (the adversarial pass grading3): every cell of an answer's id
(JupyterLab's split cell, a copied cell) runs, in execution order; cells the student added run in
their place; a prediction's set-up (earlier cells' functions and imports) is not timed as the
prediction; a failing display line after the value, Jupyter's ``display`` and ``_``, a failing
answer's real error, a flood of prints, and the copy detector's instructor-answer exemption."""

from __future__ import annotations

from pathlib import Path

import nbformat
import pytest

from lorisnb.tools.teaching.sandbox import Limits, Sandbox, can_isolate

pytestmark = pytest.mark.xdist_group("grading")

ROOT = Path(__file__).resolve().parents[2]
LAB = "lab1_lifelong_metrics"
SOURCE_NB = ROOT / "teaching" / "source" / LAB / f"{LAB}.ipynb"


def _meta(gid: str, *, solution: bool = False, grade: bool = False, points: float = 0) -> dict:
    nb = {"grade_id": gid, "solution": solution, "grade": grade, "locked": not solution, "schema_version": 3}
    if grade:
        nb["points"] = points
    return {"nbgrader": nb}


def _tiny_lab() -> nbformat.NotebookNode:
    """A lab of three questions: a formula (A), a prediction (B) and a value (C)."""
    v4 = nbformat.v4
    cells = [
        v4.new_markdown_cell("# tiny lab", metadata=_meta("intro")),
        v4.new_code_cell("student_id = None", metadata={"tags": ["parameters"]}),
        v4.new_code_cell(
            "import numpy as np\nfrom IPython.display import Markdown\nT = 10.0\nk = 3", metadata=_meta("setup")
        ),  # fmt: skip
        v4.new_code_cell(
            "def double(x):\n    ### BEGIN SOLUTION\n    return 2 * x\n    ### END SOLUTION",
            metadata=_meta("A_fn", solution=True),
        ),  # fmt: skip
        v4.new_code_cell(
            "assert double(x=np.array([1.0, 2.0])).tolist() == [2.0, 4.0]",
            metadata=_meta("test_A_fn", grade=True, points=1),
        ),  # fmt: skip
        v4.new_code_cell(
            "pred = ...\n### BEGIN SOLUTION\npred = T / 2\n### END SOLUTION",
            metadata={**_meta("B_pred", solution=True), "tags": ["prediction"]},
        ),  # fmt: skip
        v4.new_code_cell(
            "assert pred == 5.0, f'pred is {pred!r}'", metadata=_meta("test_B_pred", grade=True, points=1)
        ),
        v4.new_code_cell(
            "val = ...\n### BEGIN SOLUTION\nval = k * T\n### END SOLUTION", metadata=_meta("C_val", solution=True)
        ),  # fmt: skip
        v4.new_code_cell("assert val == 30.0, f'val is {val!r}'", metadata=_meta("test_C_val", grade=True, points=1)),
    ]
    return v4.new_notebook(cells=cells)


def _grade(tmp_path: Path, student_nb: nbformat.NotebookNode, name: str):
    from lorisnb.tools.teaching.autograde import GradeSettings, grade_submission, lab_spec
    from lorisnb.tools.teaching.sandbox import claim_uids

    lab = tmp_path / "tiny.ipynb"
    if not lab.exists():
        nbformat.write(_tiny_lab(), lab)
        (tmp_path / "release").mkdir()
    spec = lab_spec(lab)
    settings = GradeSettings(Limits(cell_timeout_s=30, locked_timeout_s=60), secret="s",
                             uid=claim_uids(63000) if can_isolate() else 0)  # fmt: skip
    path = tmp_path / name / "tiny.ipynb"
    path.parent.mkdir()
    nbformat.write(student_nb, path)
    return grade_submission(spec, tmp_path / "release", path, name, settings)


def _answered(answers: dict[str, list[tuple[str, int | None]]], added: dict[str, list[str]] | None = None):
    """The tiny lab as a student returns it: grade_id -> its cells (source, execution count), and the
    cells added after a cell of the lab (by its grade_id)."""
    nb = _tiny_lab()
    cells = []
    for cell in nb.cells:
        gid = cell.metadata.get("nbgrader", {}).get("grade_id")
        if gid in answers:
            for src, count in answers[gid]:
                c = nbformat.v4.new_code_cell(src, metadata=cell.metadata)
                c.execution_count = count
                cells.append(c)
        else:
            cells.append(cell)
        cells += [nbformat.v4.new_code_cell(src) for src in (added or {}).get(gid, [])]
    nb.cells = cells
    return nb


def test_the_cells_of_one_answer_id_run_in_execution_order_and_added_cells_have_their_place():
    from lorisnb.tools.teaching.autograde import added_cells, answer_cells, student_answers

    nb = _answered(
        {"A_fn": [("def _h(x):\n    return 2 * x", None), ("def double(x):\n    return _h(x)", None)],
         "C_val": [("val = k * T", 40), ("val = k + T  # abandoned", 38)]},
        added={"setup": ["kk = k"], "test_A_fn": ["import math"]},
    )  # fmt: skip
    cells = answer_cells(nb)
    assert cells["A_fn"] == ["def _h(x):\n    return 2 * x", "def double(x):\n    return _h(x)"]  # split: top first
    assert cells["C_val"] == ["val = k + T  # abandoned", "val = k * T"]  # the one run last (40) runs last
    assert student_answers(nb)["C_val"].endswith("val = k * T")
    # counts on some cells only: the notebook's order
    next(c for c in nb.cells if c.source == "val = k * T").execution_count = None
    assert answer_cells(nb)["C_val"] == ["val = k * T", "val = k + T  # abandoned"]
    # added cells: after the lab's cell above them (indices in the lab's notebook); the parameters cell is the lab's
    lab = _tiny_lab()
    assert added_cells(lab, nb) == {2: ["kk = k"], 4: ["import math"]}


@pytest.mark.slow
def test_split_copied_and_added_cells_and_a_prediction_after_slow_helpers_score_as_in_jupyter(tmp_path):
    """grading3's hsplit, hdup, hextra, hdisp and hpd: the top half of a split cell was lost, an abandoned
    copy below the cell run last was graded, an added cell's helper and import were dropped, and a
    prediction after an earlier answer's slow imports ran out of its own time limit (twice its lab time
    plus 2 s)."""
    nb = _answered(
        {
            # split in JupyterLab: the top half (a helper the bottom half calls) keeps the id
            # (its bottom half imports what takes 2.5 s in a fresh process, as scipy or pandas can)
            "A_fn": [("def _two():\n    return 2", None),
                     ("import time\ndef _pause(_w=time.sleep(2.5)):\n    return None\n"
                      "def double(x):\n    return _twice(x) * _two() / 2", None)],
            "B_pred": [("pred = T / 2", None)],
            "C_val": [("val = kk * T", 40), ("# first try\nval = kk + T", 38)],
        },
        added={"setup": ["def _twice(x):\n    return 2 * x\nkk = k"]},
    )  # fmt: skip
    res = _grade(tmp_path, nb, "s-jupyter")
    lost = {s.question: s.message for s in res.scores if s.points < s.max_points}
    assert lost == {}, (lost, res.notes)
    assert any("2 cells carry this answer's id" in n and "all of them run" in n for n in res.notes), res.notes
    assert any("code cell(s) you added" in n for n in res.notes), res.notes


@pytest.mark.slow
def test_an_answer_cell_that_fails_says_its_error_not_no_answer_yet(tmp_path):
    """grading3's hunder: D1 read Jupyter's ``_`` (NameError in the grader) and was told "no answer yet". Its
    hdisp: a prediction whose value came before a failing display(Markdown(...)) line scored 0."""
    nb = _answered({"C_val": [("val = undefined_here * T", None)],
                    "B_pred": [("pred = T / 2\ndisplay(Markdown(f'my prediction: {pred}'))", None)]})  # fmt: skip
    res = _grade(tmp_path, nb, "s-fails")
    lost = {s.question: s.message for s in res.scores if s.points < s.max_points}
    assert set(lost) == {"test_C_val"}, (lost, res.notes)
    assert "your answer cell failed: NameError" in lost["test_C_val"], lost
    assert any("B_pred: a line failed when the prediction ran alone" in n for n in res.notes), res.notes


def _predict_alone(tmp_path: Path, source: str) -> tuple[dict, list[str]]:
    """The tiny lab's prediction B_pred graded alone (numpy, math and the lab's T), as ``_predict`` does."""
    from lorisnb.tools.teaching.autograde import Budget, GradeSettings, _predict, lab_spec
    from lorisnb.tools.teaching.sandbox import claim_uids

    lab = tmp_path / "tiny.ipynb"
    nbformat.write(_tiny_lab(), lab)
    tmp_path.chmod(0o711)
    settings = GradeSettings(Limits(cell_timeout_s=20), uid=claim_uids(63100) if can_isolate() else 0)
    notes: list[str] = []
    boxes: list[Sandbox] = []
    got = _predict(lab_spec(lab), "B_pred", source, {"T": {"value": 10.0}}, tmp_path, [], settings, Budget(60), notes,
                   1.0, boxes)  # fmt: skip
    return got, notes


@pytest.mark.parametrize(
    ("source", "value"),
    [  # the notebook's value: the += and the if after the first assignment count, the display after them does not
        ("pred = T\npred -= T / 2\nif T > 0:\n    pred += 0.0\ndisplay(Markdown(f'{pred}'))", 5.0),
        ("pred = 5.0\npred += 0.5\ndisplay(Markdown(f'{pred}'))", 5.5),  # wrong in the notebook: wrong here
        ("pred = 1.0\nfor _d in [T / 2]:\n    pred = _d\nprint(lab_table)\npred = 7.0", 5.0),
    ],
)
def test_a_prediction_failing_alone_is_graded_on_what_it_computed_up_to_the_failing_line(tmp_path, source, value):
    """grading2's haug: a prediction failing alone (a display line) was graded on its imports, definitions
    and plain assignments only: the +=, if and for were dropped, so an honest ``x = ...; x += ...`` scored 0
    and a wrong ``x = 0.0; x += 0.5`` scored as 0.0."""
    got, notes = _predict_alone(tmp_path, source)
    assert got["pred"] == {"value": value}, (got, notes)
    assert any("B_pred: a line failed when the prediction ran alone (NameError" in n for n in notes), notes


def test_a_prediction_failing_before_its_value_is_bound_scores_0_with_its_error(tmp_path):
    (tmp_path / "a").mkdir()
    got, _ = _predict_alone(tmp_path / "a", "print(lab_table)\npred = T / 2")
    assert "NameError: name 'lab_table' is not defined" in got["pred"]["error"], got
    (tmp_path / "b").mkdir()
    got, _ = _predict_alone(tmp_path / "b", "pred = ...\nundefined()")
    assert "NameError: name 'undefined' is not defined" in got["pred"]["error"], got  # the stub's ... is no value


def test_an_added_cells_def_reads_the_labs_values_as_an_answer_cells_does(tmp_path):
    """grading2's hdefault: ``def within(a, b, e=eps, p=phi)`` in a cell the student added failed (NameError
    at def) in a formula answer's run alone: the lab's def-time values were given for answer cells only."""
    from lorisnb.tools.teaching.autograde import _added_key, _in_order, _lab_values, lab_spec

    lab = tmp_path / "tiny.ipynb"
    nbformat.write(_tiny_lab(), lab)
    spec = lab_spec(lab)
    answers = {"A_fn": "def double(x, n=k):\n    return _scale(x)", "C_val": "val = k * T"}
    added = {2: ["def _scale(x, f=k - 1, t=T):\n    return f * x"], 5: ["def _later(x=pred):\n    return x"]}
    order, code, at = _in_order(spec, answers, added)
    assert order == [_added_key(2, 0), "A_fn", "B_pred", _added_key(5, 0), "C_val"]
    clean = _lab_values(spec, code, {"student_id": "s"}, tmp_path, at)
    assert clean[_added_key(2, 0)] == {"k": {"value": 3}, "T": {"value": 10.0}}
    assert clean["A_fn"] == {"k": {"value": 3}}
    assert _added_key(5, 0) not in clean  # an answer's value (the instructor's pred) is never given


def test_split_halves_run_last_top_first_are_replayed_top_to_bottom_when_counts_fail(tmp_path):
    """grading2's hsplit_rerun and hdefault: a split cell whose top half was run again last counts bottom
    first (a count is only a cell's last run): replayed so it failed (NameError); and an added cell's
    helper reading the lab's numbers when defined failed the formula's run alone."""
    nb = _answered(
        {"A_fn": [("def double(x):\n    return _scale(x)", 3)],
         "B_pred": [("half = T / 2", 9), ("pred = half", 8)],
         "C_val": [("kk2 = k", 12), ("val = kk2 * T", 11)]},
        added={"setup": ["def _scale(x, f=k - 1):\n    return f * x"]},
    )  # fmt: skip
    res = _grade(tmp_path, nb, "s-rerun")
    lost = {s.question: s.message for s in res.scores if s.points < s.max_points}
    assert lost == {}, (lost, res.notes)
    assert any(n.startswith("C_val: its cells failed in the order of their execution counts (NameError") and
               "top to bottom" in n for n in res.notes), res.notes  # fmt: skip
    assert not any("delete the copies" in n or "extra ones" in n for n in res.notes), res.notes
    assert not any(n.startswith("C_val: NameError") for n in res.notes), res.notes


def _box(tmp_path: Path, **limits) -> Sandbox:
    tmp_path.chmod(0o755)
    return Sandbox(tmp_path, limits=Limits(cell_timeout_s=20, **limits), uid=62310)


def test_a_flood_of_prints_is_cut_at_the_file_limit_and_later_cells_run(tmp_path):
    """grading3's ahuge: 80 MiB printed hit the output file's size limit, the sandbox ended and every later
    cell failed ("the sandbox ended")."""
    with _box(tmp_path, file_bytes=2 * 1024**2) as box:
        r = box.run("import sys\nfor _i in range(3):\n    sys.stdout.write('x' * (1 << 20))\nx = 1", ["x"])
        assert r["ok"] and r["values"]["x"]["value"] == 1, r
        assert r["output_truncated_mib"] == 2.0
        r = box.run("print('more')\nimport os\nos.write(1, b'y' * (1 << 20))\nx = 2", ["x"])
        assert r["ok"] and r["values"]["x"]["value"] == 2 and "output_truncated_mib" not in r, r
    out = (tmp_path / "student-output.txt").read_bytes()
    assert len(out) <= 2 * 1024**2 and out.count(b"output truncated at 2 MiB") == 1


def test_display_and_the_last_value_underscore_are_there_as_in_jupyter(tmp_path):
    """grading3's hdisp and hunder: ``display`` (NameError) and ``_`` (the last cell's value) as Jupyter has them."""
    with _box(tmp_path) as box:
        assert box.run("t = {'cr': 0.5}\nt")["ok"]
        r = box.run("cr = _['cr']\ndisplay(cr, 'shown')", ["cr"])
        assert r["ok"] and r["values"]["cr"]["value"] == 0.5, r
        assert box.run("1 + 1;")["ok"]  # silenced: _ unchanged
        r = box.run("same = _['cr']", ["same"])
        assert r["ok"] and r["values"]["same"]["value"] == 0.5, r
        assert box.run("_ = 'mine'\n3")["ok"]  # the cell's own _ stays (a loop variable)
        r = box.run("mine = _", ["mine"])
        assert r["values"]["mine"]["value"] == "mine", r


def test_the_instructors_answer_without_its_placeholders_is_no_copy(tmp_path):
    """grading3: two honest students who returned the instructor's answers with the `x = ...` lines deleted
    were flagged as copying each other: the exemption compared the answer with the placeholders kept."""
    from lorisnb.tools.teaching import gradebook
    from lorisnb.tools.teaching.autograde import lab_spec

    spec = lab_spec(SOURCE_NB)
    stubs = gradebook.answer_stubs(spec, tmp_path)
    canonical = gradebook.canonical_answers(spec)
    cleaned = {}
    for gid, (text,) in canonical.items():
        cleaned[gid] = "\n".join(line for line in text.splitlines() if not line.rstrip().endswith("= ...")) + "\n"
    assert cleaned["D1_alignment"] != canonical["D1_alignment"][0]
    answers = {"s-a": dict(cleaned), "s-b": dict(cleaned)}
    assert gradebook.identical_answers(answers, stubs, canonical) == {}
    # and a real copy of the same students' own working is still found
    own = {gid: src + "_worked = 'my own check'\n" for gid, src in cleaned.items()}
    assert "s-b" in gradebook.identical_answers({"s-a": own, "s-b": dict(own)}, stubs, canonical)["s-a"]
