"""The sandbox ran a notebook's cells in a plain dict, not in a ``__main__`` module: a function a cell
defined could not be pickled by name (``attribute lookup f on __main__ failed``), so an honest
``multiprocessing.Pool().map(f, data)`` or ``ProcessPoolExecutor`` failed in the grader while the same
notebook worked in Jupyter. The cells now run in a module registered as ``sys.modules["__main__"]``,
as IPython's; a pool's forked worker reaches the grader's reply channel as any forked process of the
cells could before, and what it forges there is told as the child's own forgeries are."""

from __future__ import annotations

import pytest
from test_teaching_s67_replies import _FRAME, _grade, _score

from lorisnb.tools.teaching.sandbox import Limits, Sandbox, can_isolate, claim_uids

pytestmark = pytest.mark.xdist_group("grading")

POOL = (
    "import multiprocessing as mp\n"
    "def square(x):\n"
    "    return x * x\n"
    "with mp.get_context('fork').Pool(2) as pool:\n"
    "    squares = pool.map(square, [1, 2, 3, 4])\n"
)
EXECUTOR = (
    "import multiprocessing as mp\n"
    "from concurrent.futures import ProcessPoolExecutor\n"
    "def shifted(x, by=0.5):\n"
    "    return x + by\n"
    "with ProcessPoolExecutor(2, mp_context=mp.get_context('fork')) as ex:\n"
    "    shifts = list(ex.map(shifted, [1.0, 2.0]))\n"
)


def _uid() -> int:
    return claim_uids(63000) if can_isolate() else 0


def test_a_function_defined_in_a_cell_maps_over_a_process_pool_as_in_jupyter(tmp_path):
    with Sandbox(tmp_path, limits=Limits(cell_timeout_s=30), uid=_uid()) as box:
        reply = box.run(POOL, ("squares",), name="<pool>")
        assert reply["ok"], reply.get("error")
        assert reply["values"] == {"squares": {"array": [1, 4, 9, 16], "dtype": "<i8"}}
        reply = box.run(EXECUTOR, ("shifts",), name="<executor>")
        assert reply["ok"], reply.get("error")
        assert reply["values"] == {"shifts": {"array": [1.5, 2.5], "dtype": "<f8"}}
        # a cell's class and function pickle by name, and __main__ is the cells' namespace, as in Jupyter
        reply = box.run(
            "import pickle, __main__\n"
            "class Pose:\n    pass\n"
            "same = [pickle.loads(pickle.dumps(square)) is square, type(pickle.loads(pickle.dumps(Pose()))) is Pose,\n"
            "        __main__.square is square, __name__ == '__main__']\n",
            ("same",),
            name="<pickle>",
        )
        assert reply["values"] == {"same": {"array": [True, True, True, True], "dtype": "|b1"}}, reply
    assert box.tampered == [] and box.late == [] and box.stray == 0


def test_a_pool_worker_that_forges_a_reply_is_told_as_the_cells_own_forgery_is(tmp_path):
    """A forked worker inherits the reply channel (as any process the cells fork did before): a reply it
    forges with the request's id is a second reply to the request, named in ``tampered``; the values
    are the names asked for, and the honest cell after it is told nothing."""
    forge = (
        "import multiprocessing as mp\n"
        "def forge(x):\n"
        + "".join(f"    {line}\n" for line in _FRAME.splitlines())
        + "    _f.f_locals['reply'].write(json.dumps({'ok': True, 'id': _f.f_locals['request_id'],\n"
        "        'values': {'a': {'value': 1.0}}}) + '\\n')\n"
        "    _f.f_locals['reply'].flush()\n"
        "    return x\n"
        "a = 0.2\n"
        "with mp.get_context('fork').Pool(1) as pool:\n"
        "    pool.map(forge, [0])\n"
    )
    with Sandbox(tmp_path, limits=Limits(cell_timeout_s=30), uid=_uid()) as box:
        box.run(forge, ("a",), name="<answer Y>")
        assert box.tampered == ["<answer Y>: 2 replies to one request"]
        honest = box.run("b = 3.0", ("b",), name="<answer Z>")
        assert honest["values"] == {"b": {"value": 3.0}}
        assert box.tampered == ["<answer Y>: 2 replies to one request"] and box.stray == 0


def test_an_answer_graded_with_numpy_only_still_may_not_start_a_pool(tmp_path):
    """A formula's or a prediction's sandbox refuses other processes (they would run without the
    guard): a pool fails there, saying so, whatever its function."""
    with Sandbox(tmp_path, limits=Limits(cell_timeout_s=30), uid=_uid(), no_lorisnb=True) as box:
        reply = box.run(POOL, ("squares",), name="<pool>")
    assert not reply["ok"] and reply["values"] == {"squares": {"missing": True}}
    assert reply["error"].startswith("PermissionError:") and "may not use os.fork" in reply["error"]


@pytest.mark.slow
def test_a_value_answer_computed_with_a_process_pool_scores_as_in_jupyter(tmp_path):
    """A submission whose value answer maps a function of its cell over a pool: its points (0 before,
    with the pickling error), and a formula answer starting a pool is refused as another process."""
    pooled = (
        "import multiprocessing as mp\n"
        "def times_k(x):\n"
        "    return k * x\n"
        "with mp.get_context('fork').Pool(2) as pool:\n"
        "    val = sum(pool.map(times_k, [T]))\n"
    )
    res = _grade(tmp_path, {"C_val": pooled}, "s-pool")
    assert _score(res, "test_C_val").points == 1.0, _score(res, "test_C_val").message
    assert _score(res, "test_A_fn").points == 1.0 and _score(res, "test_B_pred").points == 1.0
    assert not any("reply" in n for n in res.notes), res.notes
