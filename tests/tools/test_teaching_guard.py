"""The grading sandbox's guard against lorisnb in answers graded with numpy only (an adversarial
pass: a formula answer that appended another copy of lorisnb to ``sys.path`` and imported it got
full points, no note; a prediction computed with the lab's own ``simulate_and_score`` got its
point). The guard refuses lorisnb from any copy on the machine, and what could reach past it, in
both isolation modes; a refused answer scores 0 with a note; a prediction is graded from a run of
its own with the lab's numbers only; honest answers score as before."""

from __future__ import annotations

import os
import shutil
import stat
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import nbformat
import pytest

import lorisnb
from lorisnb.tools.teaching import sandbox as sandbox_module
from lorisnb.tools.teaching.autograde import GradeSettings, grade_submission, lab_spec
from lorisnb.tools.teaching.sandbox import Limits, Sandbox, can_isolate, claim_uids

ROOT = Path(__file__).resolve().parents[2]
LAB = "lab1_lifelong_metrics"
SOURCE_NB = ROOT / "teaching" / "source" / LAB / f"{LAB}.ipynb"
pytestmark = pytest.mark.xdist_group("grading")  # sandboxes one at a time (see test_teaching_sandbox.py)


@pytest.fixture(scope="module")
def other_copy() -> Iterator[Path]:
    """A copy of the lorisnb package in a folder of its own that every user can read (as another
    environment's site-packages or a second checkout is), and a link to it by another name."""
    base = Path(tempfile.mkdtemp(prefix="other-copy-", dir="/tmp"))
    shutil.copytree(Path(lorisnb.__file__).parent, base / "lorisnb", ignore=shutil.ignore_patterns("__pycache__"))
    (base / "renamed").symlink_to(base / "lorisnb")
    for p in [base, *base.rglob("*")]:
        if not p.is_symlink():
            p.chmod(p.stat().st_mode | stat.S_IROTH | (stat.S_IXOTH if p.is_dir() else 0))
    yield base
    shutil.rmtree(base)


@pytest.fixture(params=["full", "limits"])
def isolation(request, monkeypatch) -> str:
    """Each guard test as root with full isolation (where it can) and with the limits only."""
    if request.param == "full" and not can_isolate():
        pytest.skip("needs root on Linux with unshare and setpriv (as CI runs)")
    if request.param == "limits":
        monkeypatch.setattr(sandbox_module, "can_isolate", lambda: False)
    return request.param


def _trick(path: Path) -> str:
    """The adversarial pass's lines: lorisnb's None entry dropped, another copy put on sys.path."""
    return (
        "import sys as _s\n"
        '_s.modules.pop("lorisnb", None)\n'
        f"_s.path.append({str(path)!r})\n"
        "from lorisnb.core.metrics import openloris as _O\n"
    )


def _refusals(copy: Path) -> dict[str, tuple[str, str | None]]:
    """Answer code -> (the error it gets, the finding reported: None for a refusal that is no use of lorisnb)."""
    src = copy / "lorisnb" / "core" / "metrics" / "openloris.py"
    return {
        _trick(copy): ("ImportError", "import lorisnb.core.metrics"),
        "import lorisnb": ("ImportError", "import lorisnb"),
        f"text = open({str(src)!r}).read()": ("PermissionError", f"open {src}"),
        f"text = open({str(copy / 'renamed' / 'core' / 'metrics' / 'openloris.py')!r}).read()": (
            "PermissionError",
            "open ",
        ),
        (
            "import importlib.util\n"
            f"spec = importlib.util.spec_from_file_location('m', {str(copy / 'renamed' / 'errors.py')!r})\n"
            "m = importlib.util.module_from_spec(spec)\n"
            "spec.loader.exec_module(m)\n"
        ): ("PermissionError", "open "),
        f"import os\nos.symlink({str(copy / 'lorisnb')!r}, 'mine')": ("PermissionError", "os.symlink"),
        "import subprocess\nsubprocess.run(['true'])": ("PermissionError", None),
        "import _posixsubprocess\n_posixsubprocess.fork_exec()": ("PermissionError", None),
        "import os\nos.fork()": ("PermissionError", None),
        "import ctypes\nctypes.CDLL(None)": ("PermissionError", None),
        "import gc\ngc.get_objects()": ("PermissionError", None),
        "import socket\nsocket.socket()": ("PermissionError", None),
    }


@pytest.mark.thorough
def test_the_guard_refuses_lorisnb_from_any_copy_and_what_reaches_past_it(other_copy, isolation):
    work = Path(tempfile.mkdtemp(prefix="lorisnb-guard-test-"))
    uid = claim_uids(62000) + 1 if can_isolate() else 0
    try:
        for code, (error, finding) in _refusals(other_copy).items():
            # the copy lies in /tmp, which the sandbox sees empty: shown to it, as a copy elsewhere would be
            with Sandbox(work, limits=Limits(cell_timeout_s=20), no_lorisnb=True, uid=uid, private_tmp=False) as box:
                assert box.isolation == isolation
                r = box.run(code)
                assert not r["ok"] and r["error"].startswith(error), (code, r)
                assert "graded with numpy only" in r["error"], r["error"]
                if finding is None:
                    assert box.findings == [], (code, box.findings)
                else:
                    assert box.findings and box.findings[0].startswith(finding), (code, box.findings)
                assert box.stray == 0
        # lorisnb imported inside the function, when the check calls it: refused then, and reported
        with Sandbox(work, limits=Limits(cell_timeout_s=20), no_lorisnb=True, uid=uid, private_tmp=False) as box:
            late = (
                "def cs_r(t0, t_min, first_correct, tau):\n"
                + "".join(f"    {line}\n" for line in _trick(other_copy).splitlines())
                + "    return 1.0\n"
            )
            assert box.run(late)["ok"] and box.findings == []
            r = box.call("cs_r", {"t0": 1.0, "t_min": 0.0, "first_correct": True, "tau": 60.0})
            assert not r["ok"] and "ImportError" in r["error"] and box.findings == ["import lorisnb.core.metrics"]
        # honest code (numpy, math, pandas, scipy) runs as before, with nothing found
        with Sandbox(work, limits=Limits(cell_timeout_s=60), no_lorisnb=True, uid=uid) as box:
            honest = (
                "import math\nimport numpy as np\nimport pandas as pd\nimport scipy.special\n"
                "def cs_r(t0, t_min, first_correct, tau):\n"
                "    return float(np.exp(-(t0 - t_min) / tau)) if first_correct else 0.0\n"
                "x = cs_r(30.0, 0.0, True, 60.0) + 0 * pd.Series([1.0]).sum() + 0 * math.pi\n"
            )
            r = box.run(honest, ["x"])
            assert r["ok"] and abs(r["values"]["x"]["value"] - 0.6065306597) < 1e-9, r
            assert box.findings == [] and box.stray == 0
    finally:
        shutil.rmtree(work, ignore_errors=True)


def test_the_lab_names_its_predictions_and_what_each_may_read():
    spec = lab_spec(SOURCE_NB)
    assert set(spec.predictions) == {"B1_prediction", "B3_prediction", "C2_prediction"}
    b1 = set(spec.predictions["B1_prediction"])
    assert {"T", "lost_window", "delta", "simulate_and_score", "Faults", "ln"} <= b1  # functions: named, never given
    assert not b1 & {"cr_lost", "t_lost", "fe_lost"}  # the lab computes those after the prediction
    assert "t_late" not in spec.predictions["B3_prediction"] and "t_wrong" not in spec.predictions["C2_prediction"]


def _cheater(copy: Path) -> nbformat.NotebookNode:
    """A1, B2, C1 with the adversarial pass's trick (another copy of lorisnb on sys.path); B1
    computed with the lab's own helper; B3 read from a number A1's cell computed in the lab; the
    rest answered honestly."""
    sol = {
        c.metadata["nbgrader"]["grade_id"]: c.source
        for c in nbformat.read(SOURCE_NB, as_version=4).cells
        if c.get("metadata", {}).get("nbgrader", {}).get("solution")
    }
    trick = _trick(copy)
    answers = {
        "A1_correctness": trick + "def correctness(ate_m, aoe_deg, eps, phi):\n"
        "    return _O.correctness(ate_m, aoe_deg, eps, phi)\n"
        "_crt = simulate_and_score(Faults(init_delay_s=late_start))[1].loc[1, 'cr_t']\n",
        "B1_prediction": "predicted_cr_lost = simulate_and_score(Faults(lost=(lost_window,)))[1].loc[1, 'cr']\n",
        "B2_correct_rate": trick + "def correct_rate(stamps, correct, t_min, t_max, delta):\n"
        "    return float(_O.correct_rate(_O.correct_time(stamps, correct, t_max, delta, t_min), t_min, t_max))\n",
        "B3_prediction": "predicted_cr_t_late = float(_crt)\n",
        "C1_cs_r": trick + "def cs_r(t0, t_min, first_correct, tau):\n"
        "    return float(_O.relocalization_score(t0, t_min, first_correct, tau))\n",
    }
    nb = nbformat.read(SOURCE_NB, as_version=4)
    for cell in nb.cells:
        gid = cell.get("metadata", {}).get("nbgrader", {}).get("grade_id")
        if cell.get("metadata", {}).get("nbgrader", {}).get("solution"):
            cell.source = answers.get(gid, sol[gid])
    return nb


@pytest.mark.slow
def test_lorisnb_from_another_copy_and_computed_predictions_score_0_with_notes(tmp_path, other_copy, isolation):
    spec, release = lab_spec(SOURCE_NB), tmp_path / "release"
    release.mkdir()
    settings = GradeSettings(Limits(cell_timeout_s=30, locked_timeout_s=180), secret="s",
                             uid=claim_uids(62000) if can_isolate() else 0)  # fmt: skip
    honest, cheat = tmp_path / "honest" / f"{LAB}.ipynb", tmp_path / "cheat" / f"{LAB}.ipynb"
    for path, nb in ((honest, nbformat.read(SOURCE_NB, as_version=4)), (cheat, _cheater(other_copy))):
        path.parent.mkdir()
        nbformat.write(nb, path)
    os.chmod(tmp_path, 0o755)
    t0 = time.monotonic()
    base = grade_submission(spec, release, honest, "s-honest", settings)
    assert base.isolation == isolation and base.points == base.max_points == 18, [
        (s.question, s.message) for s in base.scores if s.points < s.max_points
    ]
    # the instructor's notebook returned as is: its markers are noted (the solutions leaked), nothing else
    assert [n for n in base.notes if "instructor's markers" not in n] == [], base.notes
    res = grade_submission(spec, release, cheat, "s-cheat", settings)
    pts = {s.question: s.points for s in res.scores}
    msg = {s.question: s.message for s in res.scores}
    for q in ("test_A1_correctness", "test_B2_correct_rate", "test_C1_cs_r"):
        assert pts[q] == 0 and "refused (0 points)" in msg[q] and "import lorisnb" in msg[q], msg[q]
    assert pts["test_B1_prediction"] == 0, msg["test_B1_prediction"]
    assert (
        "reads lost_window; not the lab's functions and objects it reads: Faults, simulate_and_score"
        in msg["test_B1_prediction"]
        and "NameError" in msg["test_B1_prediction"]
    ), msg["test_B1_prediction"]
    assert pts["test_B3_prediction"] == 0 and "_crt" in msg["test_B3_prediction"], msg["test_B3_prediction"]
    assert pts["test_C2_prediction"] == 1 and res.points == 9, pts  # C2, D1, E1, F, G1: honest
    lorisnb_notes = [n for n in res.notes if "tried to use lorisnb" in n]
    assert [n.split(":")[0] for n in lorisnb_notes] == [
        "the answer cell A1_correctness",
        "the answer cell B2_correct_rate",
        "the answer cell C1_cs_r",
    ], res.notes
    assert any(n.startswith("B1_prediction: a prediction is worked out") for n in res.notes), res.notes
    assert time.monotonic() - t0 < 240
