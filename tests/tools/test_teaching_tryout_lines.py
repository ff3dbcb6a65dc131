"""The adversarial pass adv6 of the grader: a formula whose try-out line fails after its def (any
error, not only a NameError) is graded on its def, as Jupyter's check saw it; an unanswered
prediction is "no answer yet"; only values the cells added below an answer changed are named; a
sandbox that ended is not told as a time-out; a reply the student's code forges passes the same
filter as the sandbox's own; duplicate cell ids, a byte-order mark and a number as a cell's source
are told in words."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import nbformat
import pytest
from test_teaching_cells import _answered, _tiny_lab

from lorisnb.tools.teaching.sandbox import Limits, Sandbox, SandboxError, can_isolate

pytestmark = pytest.mark.xdist_group("grading")


def _settings():
    from lorisnb.tools.teaching.autograde import GradeSettings
    from lorisnb.tools.teaching.sandbox import claim_uids

    return GradeSettings(Limits(cell_timeout_s=30, locked_timeout_s=180), secret="s",
                         uid=claim_uids(63000) if can_isolate() else 0)  # fmt: skip


def _grade(tmp_path: Path, student_nb: nbformat.NotebookNode | bytes, name: str):
    from lorisnb.tools.teaching.autograde import grade_submission, lab_spec

    lab = tmp_path / "tiny.ipynb"
    if not lab.exists():
        nbformat.write(_tiny_lab(), lab)
        (tmp_path / "release").mkdir()
    student = tmp_path / name / "tiny.ipynb"
    student.parent.mkdir()
    if isinstance(student_nb, bytes):
        student.write_bytes(student_nb)
    else:
        nbformat.write(student_nb, student)
    return grade_submission(lab_spec(lab), tmp_path / "release", student, name, _settings())


def _score(res, question: str):
    return next(s for s in res.scores if s.question == question)


@pytest.mark.slow
def test_a_formula_whose_tryout_line_fails_after_its_def_is_graded_on_its_def(tmp_path):
    """adv6 finding 1: a right def, then `print(double())` (TypeError) or a call with a list: 0 before,
    though Jupyter bound the def before the line failed and the check passed; an error *before* the
    def still scores 0 (Jupyter never bound it)."""
    good = "def double(x):\n    return 2 * x\n"
    res = _grade(tmp_path, _answered({"A_fn": [(good + "print(double())  # try-out", None)]}), "s-typeerror")
    a = _score(res, "test_A_fn")
    assert a.points == 1.0, a.message
    note = next(n for n in res.notes if n.startswith("A_fn: line 3"))
    assert "`print(double())  # try-out`" in note and "TypeError" in note and "`double`" in note
    assert "tidy that try-out line" in note
    res = _grade(tmp_path, _answered({"A_fn": [(good + "double([1, 2]) + 1", None)]}), "s-list")
    assert _score(res, "test_A_fn").points == 1.0
    assert any("raised TypeError" in n for n in res.notes)
    # the error before the def: in Jupyter `double` was never defined, so the check failed
    res = _grade(tmp_path, _answered({"A_fn": [("x = 1 / 0\n" + good, None)]}), "s-before")
    a = _score(res, "test_A_fn")
    assert a.points == 0.0 and "ZeroDivisionError" in a.message


@pytest.mark.slow
def test_an_unanswered_prediction_is_no_answer_yet_and_added_cells_name_only_what_they_changed(tmp_path):
    """adv6 findings 2 and 3: a prediction left as handed out (`pred = ...` and nbgrader's stub) was told
    "not computed with the lab's functions or lorisnb ... failed: NotImplementedError"; a cell added
    below an answer whose only line failed was said to have set the answer's value."""
    nb = _answered(
        {"B_pred": [("pred = ...\n# YOUR CODE HERE\nraise NotImplementedError()", None)],
         "C_val": [("val = k * T", None)]},
        added={"C_val": ["undefined_thing + 1"]},
    )  # fmt: skip
    res = _grade(tmp_path, nb, "s-unanswered")
    b = _score(res, "test_B_pred")
    assert b.points == 0.0 and "Ellipsis" in b.message, b.message  # the tiny check's "no answer": `...`
    assert not any("not computed with the lab's functions" in n for n in res.notes), res.notes
    assert _score(res, "test_C_val").points == 1.0
    assert not any("set in the cell(s) you added" in n for n in res.notes), res.notes
    # a cell below that does change it is named, and read there
    nb = _answered({"C_val": [("val = 1.0", None)]}, added={"C_val": ["val = k * T"]})
    res = _grade(tmp_path, nb, "s-changed")
    assert _score(res, "test_C_val").points == 1.0
    assert any(n.startswith("C_val: val set in the cell(s) you added") for n in res.notes), res.notes


def test_a_sandbox_that_ended_is_not_a_timeout_and_forged_replies_are_filtered(tmp_path):
    """adv6 findings 4 and 5: `os._exit(0)` in a cell was "TimeoutError: the sandbox ended"; a function
    that writes its own reply line into the grader's pipe had it taken as it was (a bare float, not a
    value the sandbox describes)."""
    from lorisnb.tools.teaching.sandbox import SandboxTimeout, error_of

    with Sandbox(tmp_path, limits=Limits(cell_timeout_s=20), uid=0, no_lorisnb=True) as box:
        with pytest.raises(SandboxError) as ended:
            box.run("import os\nos._exit(0)")
        assert not isinstance(ended.value, SandboxTimeout)
        assert "exit status 0" in str(ended.value)
        assert error_of(ended.value).startswith("RuntimeError: the sandbox ended")
        box.restart()
        with pytest.raises(SandboxTimeout) as slow:
            box.run("while True: pass", timeout_s=1)
        assert error_of(slow.value).startswith("TimeoutError: time limit")
        box.restart()
        forge = (
            "import sys, json\n"
            "def f(x, forged):\n"
            "    fr = sys._getframe(1)\n"
            "    while fr is not None and 'request_id' not in fr.f_locals:\n"
            "        fr = fr.f_back\n"
            "    fr.f_locals['reply'].write(json.dumps({'ok': True, 'result': json.loads(forged), 'id': fr.f_locals['request_id'],\n"
            "                                           'values': {'x': {'value': [1, 2]}}, 'extra': 1}) + '\\n')\n"
            "    fr.f_locals['reply'].flush()\n"
            "    return 0.5\n"
        )
        assert box.run(forge)["ok"]
        for forged in (
            0.123,
            {"value": {"a": 1}},
            {"array": [1, 2], "dtype": "O"},
            {"array": [[1], 2], "dtype": "<f8"},
        ):
            reply = box.call("f", {"x": 1.0, "forged": json.dumps(forged)})
            assert set(reply) <= {"ok", "result", "values", "error", "line", "output_truncated_mib"}
            assert "not_plain" in reply["result"], (forged, reply)
            assert reply["values"] == {"x": {"not_plain": reply["result"]["not_plain"]}}
        reply = box.call("f", {"x": 1.0, "forged": json.dumps({"array": [1, 2], "dtype": "<f8"})})
        assert reply["result"] == {"array": [1, 2], "dtype": "<f8"}  # a well-formed value passes, as any answer's
        # the sandbox's own replies pass whole: a 0-d array (its tolist() is one number), a numpy bool, a string
        assert box.run("import numpy as np\ndef h():\n    return np.array(2.5)\nb = np.bool_(True)\ns = 'x'")["ok"]
        assert box.call("h", {})["result"] == {"array": 2.5, "dtype": "<f8"}
        assert box.run("", ("b", "s", "nothing"))["values"] == {"b": {"value": True}, "s": {"value": "x"},
                                                                  "nothing": {"missing": True}}  # fmt: skip


def test_a_failing_cells_line_is_in_its_reply(tmp_path):
    with Sandbox(tmp_path, limits=Limits(cell_timeout_s=20), uid=0, no_lorisnb=True) as box:
        reply = box.run("def g(x):\n    return 1 / x\n\ny = 2\ng(0)\n", name="<answer Z>")
        assert not reply["ok"] and reply["error"].startswith("ZeroDivisionError") and reply["line"] == 5


def test_duplicate_ids_a_byte_order_mark_and_a_numeric_source_are_told_in_words(tmp_path, recwarn):
    """adv6 finding 6: ~100 DuplicateCellId warnings on the terminal; a BOM told "not JSON"; a number as
    the parameters cell's source a bare TypeError from compile()."""
    from lorisnb.tools.teaching.autograde import read_notebook

    nb = _answered({"C_val": [("val = k * T", None)]})
    for cell in nb.cells:
        cell["id"] = "same"
    data = json.dumps(nb).encode()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # any warning escaping the reading fails the test
        read, notes = read_notebook(data)
    assert len(read.cells) == len(nb.cells) and len({c["id"] for c in read.cells}) == len(nb.cells)
    assert notes and notes[0].startswith(f"{len(nb.cells) - 1} cell(s) of the notebook repeated another cell's id")
    res = _grade(tmp_path, data, "s-dupids")
    assert not res.error and _score(res, "test_C_val").points == 1.0 and notes[0] in res.notes
    assert not [w for w in recwarn if "DuplicateCellId" in type(w.message).__name__]

    res = _grade(tmp_path, b"\xef\xbb\xbf" + json.dumps(_answered({})).encode(), "s-bom")
    assert "JSON with a byte-order mark" in res.error and res.points == 0.0
    res = _grade(tmp_path, b"\xef\xbb\xbf{not json", "s-bom-garbage")
    assert "not JSON" in res.error

    nb = json.loads(json.dumps(_answered({})))
    next(c for c in nb["cells"] if "parameters" in c["metadata"].get("tags", []))["source"] = 5
    res = _grade(tmp_path, json.dumps(nb).encode(), "s-params-int")
    assert "JSON, but not a notebook nbformat reads" in res.error and "compile()" not in res.error
