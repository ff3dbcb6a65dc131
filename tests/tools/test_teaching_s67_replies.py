"""The adversarial pass s67 of the grader: a prediction's cell that added its check's reference name to
the request it was run by (the child replied with it) rebound the reference and scored the points; a
reply line forged with the request's id was taken as the reply, the child's own counted as the stray
line, and the note said "ignored; only the replies to the grader's own requests were read"; student
ids that look the same in two Unicode forms drew two data variants."""

from __future__ import annotations

from pathlib import Path

import nbformat
import pytest
from test_teaching_cells import _meta

from lorisnb.tools.teaching.sandbox import Limits, Sandbox, can_isolate

pytestmark = pytest.mark.xdist_group("grading")

# walks up from the cell to the sandbox child's main(), whose locals hold the request and the reply file
_FRAME = (
    "import sys, json\n"
    "_f = sys._getframe()\n"
    "while _f is not None and 'request_id' not in _f.f_locals:\n"
    "    _f = _f.f_back\n"
)
INJECT = _FRAME + "_f.f_locals['req']['capture'].append({ref!r})\n"
FORGE = (
    _FRAME + "_f.f_locals['reply'].write(json.dumps({{'ok': True, 'id': _f.f_locals['request_id'], "
    "'values': {values}}}) + '\\n')\n_f.f_locals['reply'].flush()\n"
)


def _lab() -> nbformat.NotebookNode:
    """A lab whose checks compare with references the instructor's cells compute (``pred_ref``,
    ``val_ref``), as lab 1's do (``cr_lost``): a formula (A), a prediction (B), a value (C)."""
    v4 = nbformat.v4
    return v4.new_notebook(
        cells=[
            v4.new_code_cell("student_id = None", metadata={"tags": ["parameters"]}),
            v4.new_code_cell("import numpy as np\nT = 10.0\nk = 3", metadata=_meta("setup")),
            v4.new_code_cell(
                "def double(x):\n    ### BEGIN SOLUTION\n    return 2 * x\n    ### END SOLUTION",
                metadata=_meta("A_fn", solution=True),
            ),
            v4.new_code_cell(
                "assert double(x=np.array([1.0, 2.0])).tolist() == [2.0, 4.0]",
                metadata=_meta("test_A_fn", grade=True, points=1),
            ),
            v4.new_code_cell(
                "pred = ...\n### BEGIN SOLUTION\npred = T / 2\n### END SOLUTION",
                metadata={**_meta("B_pred", solution=True), "tags": ["prediction"]},
            ),
            v4.new_code_cell("pred_ref = T / 2", metadata=_meta("B_ref")),
            v4.new_code_cell(
                "assert pred == pred_ref, f'pred is {pred!r}, not {pred_ref!r}'\nprint(f'pred {pred} ref {pred_ref}')",
                metadata=_meta("test_B_pred", grade=True, points=1),
            ),
            v4.new_code_cell(
                "val = ...\n### BEGIN SOLUTION\nval = k * T\n### END SOLUTION", metadata=_meta("C_val", solution=True)
            ),
            v4.new_code_cell("val_ref = k * T", metadata=_meta("C_ref")),
            v4.new_code_cell(
                "assert val == val_ref, f'val is {val!r}'", metadata=_meta("test_C_val", grade=True, points=1)
            ),
        ]
    )


def _answered(answers: dict[str, str]) -> nbformat.NotebookNode:
    nb = _lab()
    for cell in nb.cells:
        gid = cell.metadata.get("nbgrader", {}).get("grade_id")
        if gid in answers:
            cell.source = answers[gid]
    return nb


def _grade(tmp_path: Path, answers: dict[str, str], name: str):
    from lorisnb.tools.teaching.autograde import GradeSettings, grade_submission, lab_spec
    from lorisnb.tools.teaching.sandbox import claim_uids

    lab = tmp_path / "refs.ipynb"
    if not lab.exists():
        nbformat.write(_lab(), lab)
        (tmp_path / "release").mkdir()
    settings = GradeSettings(Limits(cell_timeout_s=30, locked_timeout_s=60), secret="s",
                             uid=claim_uids(63000) if can_isolate() else 0)  # fmt: skip
    path = tmp_path / name / "refs.ipynb"
    path.parent.mkdir()
    nbformat.write(_answered(answers), path)
    return grade_submission(lab_spec(lab), tmp_path / "release", path, name, settings)


def _score(res, question: str):
    return next(s for s in res.scores if s.question == question)


def test_a_reply_holds_only_the_names_asked_for_and_a_forged_second_reply_is_told(tmp_path):
    """The sandbox keeps the names it asked for (a cell that added one to its request is named in
    ``tampered``), and a reply forged with the request's id is found by the child's own reply to
    the same request (two replies: named in ``tampered``, not a line "ignored")."""
    with Sandbox(tmp_path, limits=Limits(cell_timeout_s=20), uid=0, no_lorisnb=True) as box:
        reply = box.run("a = 1.0\nb = 2.0\n" + INJECT.format(ref="b"), ("a",), name="<answer X>")
        assert reply["ok"] and reply["values"] == {"a": {"value": 1.0}}
        assert box.tampered == ["<answer X>: its reply held names the grader did not ask for (b)"]
        forged = FORGE.format(values="{'a': {'value': 0.5}, 'ref': {'value': 0.5}}")
        reply = box.run("a = 0.5\n" + forged, ("a",), name="<answer Y>")
        assert reply["values"] == {"a": {"value": 0.5}}  # the names asked for, whichever reply was read
        assert box.tampered[1:] == ["<answer Y>: 2 replies to one request", "<answer Y>: its reply held names the "
                                    "grader did not ask for (ref)"]  # fmt: skip
        assert box.stray == 0  # the second reply is no stray line: it is told as a second reply
        # a line that is no reply (another id, no id) is not read as one: counted as stray, nothing else told
        junk = _FRAME + "_f.f_locals['reply'].write(json.dumps({'ok': True, 'id': 'x'}) + '\\n{}\\n')\n"
        reply = box.run("a = 2.0\n" + junk, ("a",), name="<answer W>")
        assert reply["values"] == {"a": {"value": 2.0}} and box.stray == 2 and len(box.tampered) == 3
        # an honest cell after them: nothing told, the sandbox's own replies as they were
        reply = box.run("c = [1.0, 2.0]", ("c", "nothing"), name="<answer Z>")
        assert reply["values"] == {"c": {"array": [1.0, 2.0], "dtype": "<f8"}, "nothing": {"missing": True}}
        assert len(box.tampered) == 3 and box.stray == 2


def test_the_checks_read_the_answers_own_names_never_a_reference_from_a_reply(tmp_path):
    """Whatever reaches the checks (a reply's extra names through any path), the check's
    reference is the grader's: ``pred_ref`` in the values of B stays T / 2."""
    from lorisnb.tools.teaching.autograde import _run_checks, lab_spec

    nbformat.write(_lab(), tmp_path / "refs.ipynb")
    spec = lab_spec(tmp_path / "refs.ipynb")
    assert spec.values["B_pred"] == ("pred",)
    wrong = {"pred": {"value": 1.0}, "pred_ref": {"value": 1.0}}
    values = {"C_val": {"val": {"value": 7.0}, "val_ref": {"value": 7.0}}}
    (tmp_path / "root").mkdir()
    scores = _run_checks(spec, values, {}, {"student_id": "s"}, tmp_path / "root", lambda gid, lab: dict(wrong))
    by = {s.question: s for s in scores}
    assert by["test_B_pred"].points == 0.0 and "pred is 1.0, not 5.0" in by["test_B_pred"].message
    assert by["test_C_val"].points == 0.0 and "val is 7.0" in by["test_C_val"].message


@pytest.mark.slow
def test_answers_whose_code_writes_into_the_grader_channel_score_0_with_a_true_note(tmp_path):
    """s67 findings 1 and 2, graded whole: the prediction that added its reference's name to its
    request scored 1/1 ("pred 1.0 ref 1.0"); one that forged a reply with the request's id had the
    note "ignored; only the replies to the grader's own requests were read". Now each scores 0 with
    a note saying what its code did; the honest answers keep their points."""
    honest = {"A_fn": "def double(x):\n    return 2 * x\n", "C_val": "val = k * T\n"}
    inject = "pred = 1.0\npred_ref = pred\n" + INJECT.format(ref="pred_ref")
    res = _grade(tmp_path, {**honest, "B_pred": inject}, "s-inject")
    b = _score(res, "test_B_pred")
    assert b.points == 0.0, b.message
    assert "wrote into the grader's reply channel" in b.message and "did not ask for (pred_ref)" in b.message
    assert _score(res, "test_A_fn").points == 1.0 and _score(res, "test_C_val").points == 1.0
    assert any(
        n.startswith("B_pred: RuntimeError: your answer cell B_pred: the notebook's code wrote") for n in res.notes
    )
    # only when run alone (its prelude imports math, the lab does not): the prediction's own run finds it
    alone = "pred = 1.0\npred_ref = pred\nif 'math' in globals():\n" + "".join(
        f"    {line}\n" for line in INJECT.format(ref="pred_ref").splitlines()
    )
    res = _grade(tmp_path, {**honest, "B_pred": alone}, "s-alone")
    b = _score(res, "test_B_pred")
    assert b.points == 0.0 and "the prediction B_pred: the notebook's code wrote" in b.message, b.message

    forged = "pred = 5.0\n" + FORGE.format(values="{'pred': {'value': 5.0}, 'pred_ref': {'value': 5.0}}")
    value = "val = 1.0\nval_ref = val\n" + INJECT.format(ref="val_ref")  # the lab's own run of a value answer
    res = _grade(tmp_path, {**honest, "B_pred": forged, "C_val": value}, "s-forged")
    b, c = _score(res, "test_B_pred"), _score(res, "test_C_val")
    assert b.points == 0.0 and "2 replies to one request" in b.message, b.message
    assert c.points == 0.0 and "did not ask for (val_ref)" in c.message, c.message
    note = next(n for n in res.notes if n.startswith("the submission's code wrote replies of its own into the grader"))
    assert "2 replies to one request" in note and "each answer during whose run it did so scores 0" in note
    assert not any("ignored; only the replies to the grader's own requests were read" in n for n in res.notes)
    assert _score(res, "test_A_fn").points == 1.0

    # a formula whose cell writes into the channel is not graded either, whatever its functions return
    formula = "def double(x):\n    return 2 * x\n" + INJECT.format(ref="double")
    res = _grade(tmp_path, {**honest, "A_fn": formula}, "s-formula")
    a = _score(res, "test_A_fn")
    assert a.points == 0.0 and "wrote into the grader's reply channel" in a.message, a.message


def test_ids_that_look_the_same_draw_one_variant_and_ascii_ids_keep_theirs():
    """s67 finding 3: 'zoë' typed as one character or as e and a combining diaeresis, and a
    full-width 'ｓ０００１', drew other variants than 'zoë' and 's0001', unflagged."""
    from lorisnb.tools.teaching._prose import lab_variant, same_id
    from lorisnb.tools.teaching.gradebook import same_variants

    nfc, nfd = "zo\u00eb", "zoe\u0308"
    assert same_id(nfc) == same_id(nfd) and lab_variant(nfc).seed == lab_variant(nfd).seed
    assert same_id("ｓ０００１") == "s0001" and lab_variant("ｓ０００１").seed == lab_variant("s0001").seed
    assert same_id("Ｓ\u3000０００１") == "s0001"  # a full-width space is a space
    assert same_variants(["s0001", "ｓ０００１", nfc, nfd, "s0002"]) == {
        "s0001": ("ｓ０００１",), "ｓ０００１": ("s0001",), nfc: (nfd,), nfd: (nfc,)}  # fmt: skip
    # ASCII ids draw the variants they drew before (pinned from the casefold-only id)
    seeds = {"s0001": 209534660, "S 1234567": 440348896, "alice": 916710555, "Bob.Smith@uni.edu": 1724701805}
    assert {sid: lab_variant(sid).seed for sid in seeds} == seeds
    assert same_id(" S 1234567 ") == "s1234567" and same_id("\u212a") == "k" and same_id("ﬁ") == "fi"
