"""The adversarial pass s68 of the grader: code that forged its request's reply and then answered the
grader's own check of the channel (the ``sync`` request, read from the request pipe) scored full
marks: the child's own reply came after the forged sync answer, was counted as a stray line at the
next request, and the note said "the values graded are those the sandbox replied". A reply to a
request whose reply was read already is now found wherever it comes (at a later request, when the
sandbox is closed, after a check's last call of a function) and the answer whose request it was
scores 0 with a note saying so."""

from __future__ import annotations

import pytest
from test_teaching_s67_replies import _FRAME, _grade, _score

from lorisnb.tools.teaching.sandbox import Limits, Sandbox

pytestmark = pytest.mark.xdist_group("grading")

# the forged reply, then the grader's sync read from the request pipe and answered, as the s68 tester's cell did
FORGE_AND_SYNC = (
    _FRAME + "_L = _f.f_locals\n"
    "_L['reply'].write(json.dumps({{'ok': True, 'id': _L['request_id'], {body}}}) + '\\n'); _L['reply'].flush()\n"
    "_sync = json.loads(_L['requests'].readline())\n"
    "_L['reply'].write(json.dumps({{'ok': True, 'id': _sync['id']}}) + '\\n'); _L['reply'].flush()\n"
)


def test_a_reply_forged_with_the_grader_sync_answered_is_found_later_under_its_request(tmp_path):
    """The forged reply is read (the code wrote it first), but the child's own reply to the same
    request comes later: at the next request it is put in ``late`` under the forging request's name
    (not counted as a stray line, not blamed on the request then pending); at the last request it is
    found when the sandbox is closed."""
    with Sandbox(tmp_path, limits=Limits(cell_timeout_s=20), uid=0, no_lorisnb=True) as box:
        forged = FORGE_AND_SYNC.format(body="'values': {'a': {'value': 1.0}}")
        reply = box.run("a = 0.2\n" + forged, ("a",), name="<answer Y>")
        assert reply["values"] == {"a": {"value": 1.0}}  # what the code forged: the sandbox cannot tell yet
        assert box.tampered == [] and box.late == []
        honest = box.run("b = 3.0", ("b",), name="<answer Z>")
        assert honest["values"] == {"b": {"value": 3.0}}
        assert [name for name, _ in box.late] == ["<answer Y>"] and box.stray == 0 and box.tampered == []
        assert "a second reply to one request" in box.late[0][1]
        box.run("c = 0.2\n" + forged, ("c",), name="<answer W>")  # the last request: nothing follows it
        assert len(box.late) == 1
    assert [name for name, _ in box.late] == ["<answer Y>", "<answer W>"]  # found when the sandbox was closed

    with Sandbox(tmp_path, limits=Limits(cell_timeout_s=20), uid=0, no_lorisnb=True) as box:
        for k in range(3):  # honest requests: nothing late, nothing stray, whatever follows
            assert box.run(f"v = {k}", ("v",), name=f"<answer {k}>")["values"] == {"v": {"value": k}}
    assert box.late == [] and box.stray == 0 and box.tampered == []


@pytest.mark.slow
def test_answers_that_forge_a_reply_and_the_grader_sync_score_0_with_a_true_note(tmp_path):
    """The s68 tester's submissions, graded whole: a prediction (B3 there) whose cell holds 0.2 and
    forged the reply holding the right number, a formula (C1 there) that returns a wrong number
    and forged each call's reply with the right one, and a value answer doing the same in the lab's
    run, all scored full marks. Now each scores 0 naming what its code did; the honest answers keep
    their points, and the stray-line note no longer says the values graded are the sandbox's."""
    honest = {"A_fn": "def double(x):\n    return 2 * x\n", "B_pred": "pred = T / 2\n", "C_val": "val = k * T\n"}
    res = _grade(tmp_path, honest, "s-honest")
    assert [s.points for s in res.scores] == [1.0, 1.0, 1.0], [s.message for s in res.scores]
    assert not any("second reply" in n for n in res.notes)

    pred = "pred = 0.2\n" + FORGE_AND_SYNC.format(body="'values': {'pred': {'value': 5.0}}")
    val = "val = 0.0\n" + FORGE_AND_SYNC.format(body="'values': {'val': {'value': 30.0}}")
    formula = (  # the check calls it once: the forged result is right, what it returns is not
        "import sys, json\n"
        "def double(x):\n"
        + "".join(
            f"    {line}\n"
            for line in FORGE_AND_SYNC.format(body="'result': {'array': (2 * x).tolist(), 'dtype': '<f8'}").splitlines()
        )  # fmt: skip
        + "    return 0 * x\n"
    )
    res = _grade(tmp_path, {"A_fn": formula, "B_pred": pred, "C_val": val}, "s-forged")
    for question in ("test_A_fn", "test_B_pred", "test_C_val"):
        s = _score(res, question)
        assert s.points == 0.0 and "a second reply to one request" in s.message, (question, s.message)
        assert "wrote into the grader's reply channel" in s.message
    assert not any("the values graded are those the sandbox replied" in n for n in res.notes)
    assert any(n.startswith("the submission's code wrote replies of its own") for n in res.notes)


def test_code_that_forges_and_ends_the_sandbox_before_its_own_reply_is_found(tmp_path):
    """The s68 re-test: a prediction that forged its reply, answered the sync and ended the
    process (``os._exit``) before the child's own reply scored 1/1 with no note (its sandbox was
    closed without a look). The loop never ends by itself, so a process that ended after the
    reply was read puts that request in ``late``."""
    with Sandbox(tmp_path, limits=Limits(cell_timeout_s=20), uid=0, no_lorisnb=True) as box:
        box.run("a = 1.0", ("a",), name="<answer X>")
        forged = FORGE_AND_SYNC.format(body="'values': {'p': {'value': 1.0}}") + "import os\nos._exit(0)\n"
        box.run("p = 0.2\n" + forged, ("p",), name="<answer P>")
    assert [name for name, _ in box.late] == ["<answer P>"], box.late
    assert "ended on its own after its reply was read" in box.late[0][1]
