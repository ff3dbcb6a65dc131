"""The grading sandbox and the tamper-proof grader (issue 46): adversarial submissions get the score
an honest grader gives, a class is graded within minutes, and nothing outside each submission's
output folder changes."""

from __future__ import annotations

import csv
import hashlib
import os
import shutil
import tempfile
import time
import uuid
from datetime import datetime, timedelta, timezone
from pathlib import Path

import nbformat
import numpy as np
import pytest

from lorisnb.errors import ValidationError
from lorisnb.tools.teaching.autograde import GradeSettings, Score, SubmissionResult, lab_spec
from lorisnb.tools.teaching.gradebook import LatePolicy, grade_class, read_roster, write_exports
from lorisnb.tools.teaching.sandbox import Limits, NotPlain, Sandbox, SandboxError, can_isolate, claim_uids, decode

ROOT = Path(__file__).resolve().parents[2]
LAB = "lab1_lifelong_metrics"
SOURCE_NB = ROOT / "teaching" / "source" / LAB / f"{LAB}.ipynb"
# the sandboxes of this module and the kit's grading test run one at a time (make test* use pytest-xdist
# with --dist loadgroup): side by side, two sandboxes of one uid disturbed each other's answers
pytestmark = pytest.mark.xdist_group("grading")

isolated = pytest.mark.skipif(not can_isolate(), reason="needs root on Linux with unshare and setpriv (as CI runs)")


@isolated
@pytest.mark.thorough
def test_sandbox_has_no_network_no_writes_outside_its_folder_and_limits(tmp_path):
    secret = tmp_path / "instructor"
    secret.mkdir()
    (secret / "solutions.txt").write_text("the answers")
    work = Path(tempfile.mkdtemp(prefix="lorisnb-sandbox-test-"))  # its user must reach it (tmp_path is 0700)
    outside = Path("/tmp") / f"lorisnb-pwned-{uuid.uuid4().hex}"
    with Sandbox(work, limits=Limits(cell_timeout_s=3), hidden=[secret], no_lorisnb=True) as box:
        assert box.isolation == "full"
        r = box.run("import os\nx = os.getuid()", ["x"])
        assert r["ok"] and r["values"]["x"]["value"] not in (0, os.getuid())
        r = box.run(f"x = open({str(secret / 'solutions.txt')!r}).read()", ["x"])
        assert not r["ok"] and ("Permission" in r["error"] or "No such file" in r["error"])  # hidden, or in /tmp
        r = box.run(f"open({str(outside)!r}, 'w').write('x')")
        assert not r["ok"] and "Read-only" in r["error"]
        r = box.run("import socket\nsocket.create_connection(('1.1.1.1', 80), timeout=2)")
        assert not r["ok"] and "may not use socket" in r["error"]  # the guard of a no-lorisnb sandbox
        r = box.run("import lorisnb")
        assert not r["ok"] and "lorisnb" in r["error"]
        r = box.run("x = bytearray(8 * 1024**3)", ["x"])
        assert not r["ok"] and "MemoryError" in r["error"]
        r = box.run("open('mine.txt', 'w').write('ok')\nclass Lazy:\n    pass\nx = Lazy()", ["x"])
        assert r["ok"] and isinstance(decode(r["values"]["x"]), NotPlain)
        t0 = time.monotonic()
        with pytest.raises(SandboxError, match="time limit"):
            box.run("while True:\n    pass")
        assert time.monotonic() - t0 < 10
    assert (work / "mine.txt").read_text() == "ok" and not outside.exists()
    with Sandbox(work, limits=Limits(cell_timeout_s=3)) as box:  # no guard (the lab's sandbox): no network either
        r = box.run("import socket\nsocket.create_connection(('1.1.1.1', 80), timeout=2)")
        assert not r["ok"] and "unreachable" in r["error"].lower()
    shutil.rmtree(work)
    assert (secret / "solutions.txt").read_text() == "the answers"


# --- adversarial submissions ---------------------------------------------------------------------

CHEATS = {
    # overwritten checks (every name a check could be reached by), and a wrong formula: 0 / 2
    "A1_correctness": (
        "from lorisnb.tools import teaching as teach\n"
        "import lorisnb.tools.teaching._checks as _c\n"
        "import lorisnb.tools.teaching._grading as _g\n"
        "_g.check_function = lambda *a, **k: True\n"
        "_c.check_value = lambda *a, **k: True\n"
        "class _Pass:\n"
        "    def __getattr__(self, name):\n"
        "        return lambda *a, **k: True\n"
        "teach = _Pass()\n"
        "def correctness(ate_m, aoe_deg, eps, phi):\n"
        "    return ate_m <= eps\n"
    ),
    # a prediction that fills itself in from the check's frame when it is compared: 0 / 1
    "B1_prediction": (
        "import sys\n"
        "class _Lazy:\n"
        "    def _v(self):\n"
        "        f = sys._getframe(1)\n"
        "        while f is not None:\n"
        "            if 'expected' in f.f_locals:\n"
        "                return float(f.f_locals['expected'])\n"
        "            f = f.f_back\n"
        "        return 0.5\n"
        "    def __float__(self):\n"
        "        return self._v()\n"
        "    def __array__(self, *a, **k):\n"
        "        import numpy\n"
        "        return numpy.array(self._v())\n"
        "predicted_cr_lost = _Lazy()\n"
    ),
    # lorisnb's own formula copied at run time with inspect.getsource: 0 / 3
    "B2_correct_rate": (
        "import inspect\n"
        "from lorisnb.core.metrics import openloris as _m\n"
        "_ns = {}\n"
        "exec(inspect.getsource(_m), _ns)\n"
        "def correct_rate(stamps, correct, t_min, t_max, delta):\n"
        "    return float(_ns['correct_rate'](_ns['correct_time'](stamps, correct, t_max, delta, t_min), t_min, t_max))\n"
    ),
    # an endless loop (the right formula after it never counts): 0 / 2
    "C1_cs_r": (
        "while True:\n"
        "    pass\n"
        "def cs_r(t0, t_min, first_correct, tau):\n"
        "    return float(np.exp(-(t0 - t_min) / tau)) if first_correct else 0.0\n"
    ),
    # what the edited (locked) scenario below gives, not the lab's: 0 / 1
    "C2_prediction": "predicted_cs_r_wrong = 0.6\n",
}


def _reads_and_writes(course: Path, source: Path) -> str:
    """D1's answer: read the solutions through ../ and absolute paths, write outside its folder; the
    answer is the solution's only if a read succeeded (honest: 0 / 2)."""
    targets = [str(source / LAB / f"{LAB}.ipynb"), str(ROOT / "teaching" / "source" / LAB / f"{LAB}.ipynb"),
               f"../../../source/{LAB}/{LAB}.ipynb", f"../source/{LAB}/{LAB}.ipynb", f"../../source/{LAB}/{LAB}.ipynb"]  # fmt: skip
    writes = [str(course / "pwned.txt"), str(source / "pwned.txt"), str(ROOT / "pwned.txt"), "../pwned.txt",
              "../../pwned.txt", "/tmp/lorisnb-pwned.txt", str(course / "graded" / "pwned.txt")]  # fmt: skip
    return (
        "import json, re\n"
        "cr_visit2_lifelong = cr_visit2_per_seq = 0.5\n"
        f"for _p in {targets!r}:\n"
        "    try:\n"
        "        _nb = json.load(open(_p))\n"
        "    except OSError:\n"
        "        continue\n"
        "    for _c in _nb['cells']:\n"
        "        _s = ''.join(_c['source'])\n"
        "        if 'cr_visit2_lifelong = lifelong' in _s:\n"
        "            exec(re.search(r'### BEGIN SOLUTION\\n(.*)### END SOLUTION', _s, re.S).group(1))\n"
        f"for _p in {writes!r}:\n"
        "    try:\n"
        "        open(_p, 'w').write('pwned')\n"
        "    except OSError:\n"
        "        pass\n"
    )


def _cheater(course: Path, source: Path) -> nbformat.NotebookNode:
    nb = nbformat.read(SOURCE_NB, as_version=4)
    for cell in nb.cells:
        meta = cell.get("metadata", {}).get("nbgrader", {})
        gid = meta.get("grade_id")
        if gid in CHEATS:
            cell.source = CHEATS[gid]
        elif gid == "D1_alignment":
            cell.source = _reads_and_writes(course, source)
        elif "parameters" in cell.metadata.get("tags", []):
            cell.source += "\neps = 100.0  # every pose correct\n"
        elif "wrong_reloc = {" in cell.source:  # a locked cell: the wrong re-localization edited away
            cell.source = cell.source.replace("wrong_reloc_at_s=0.0", "init_delay_s=30.0")
        elif meta.get("grade") and gid in ("test_C2_prediction", "test_B1_prediction"):
            cell.source = "pass"  # a locked check cell emptied
    return nb


# honest points per question: B3, E1, F, G1 answered right; every other one cheats or fails
CHEATER_POINTS = {
    "test_A1_correctness": 0, "test_B1_prediction": 0, "test_B2_correct_rate": 0, "test_B3_prediction": 1,
    "test_C1_cs_r": 0, "test_C2_prediction": 0, "test_D1_alignment": 0, "test_E1_threshold": 2,
    "test_F_timeline": 2, "test_G1_difficulty": 2,
}  # fmt: skip


def _snapshot(*folders: Path, skip: Path | None = None) -> dict[str, str]:
    out = {}
    for folder in folders:
        for p in sorted(folder.rglob("*")):
            if p.is_file() and not (skip and p.is_relative_to(skip)):
                out[str(p)] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


@pytest.mark.slow
@isolated
def test_adversarial_submissions_get_the_honest_score_and_change_nothing(tmp_path, monkeypatch):
    # as `python teaching/grade.py` runs: teaching/ (the labs' solutions) first on sys.path
    monkeypatch.syspath_prepend(str(ROOT / "teaching"))
    course, source = tmp_path / "course", tmp_path / "source"
    shutil.copytree(SOURCE_NB.parent, source / LAB)
    (course / "release" / LAB).mkdir(parents=True)
    (course / "release" / LAB / "README.txt").write_text("handed out with the lab\n")
    correct = course / "submitted" / "demo-correct" / LAB / f"{LAB}.ipynb"
    cheat = course / "submitted" / "s-cheater" / LAB / f"{LAB}.ipynb"
    for nb_path, nb in ((correct, nbformat.read(SOURCE_NB, as_version=4)), (cheat, _cheater(course, source))):
        nb_path.parent.mkdir(parents=True)
        nbformat.write(nb, nb_path)
    (cheat.parent / "timestamp.txt").write_text("2026-12-02 10:00:00.000000 UTC\n")
    before = _snapshot(course, source)
    t0 = time.monotonic()
    limits = Limits(cell_timeout_s=5, locked_timeout_s=180)
    due = {LAB: LatePolicy(datetime(2026, 12, 1, 23, 59, tzinfo=timezone.utc), per_day=0.25)}
    graded = grade_class(course, source, settings=GradeSettings(limits), jobs=2, late=due, progress=False)
    seconds = time.monotonic() - t0
    assert seconds < 240, f"two submissions took {seconds:.0f} s"
    by = {g.result.student: g for g in graded}
    assert by["demo-correct"].result.points == by["demo-correct"].result.max_points == 18
    cheater = by["s-cheater"].result
    assert cheater.isolation == "full"
    assert {s.question: s.points for s in cheater.scores} == CHEATER_POINTS, [
        (s.question, s.message) for s in cheater.scores
    ]
    msg = {s.question: s.message for s in cheater.scores}
    assert "not a plain value" in msg["test_B1_prediction"]
    assert "time limit" in msg["test_C1_cs_r"]
    # lorisnb imported by a formula answer: refused by the sandbox's guard, its points with it
    assert "tried to use lorisnb (import lorisnb" in msg["test_A1_correctness"]
    assert "tried to use lorisnb (import lorisnb" in msg["test_B2_correct_rate"]
    assert by["s-cheater"].days_late == 1 and by["s-cheater"].score == pytest.approx(7 * 0.75)
    # nothing changed outside the submissions' output folders (graded/) and the grader's exports
    write_exports(course, graded)
    after = _snapshot(course, source)
    changed = {p for p in set(before) | set(after) if before.get(p) != after.get(p)}
    allowed = {course / n for n in ("grades.csv", "grades-demo.csv", ".grading-secret")}
    assert {p for p in changed if not Path(p).is_relative_to(course / "graded")
            and not Path(p).is_relative_to(course / "exports") and Path(p) not in allowed} == set()  # fmt: skip
    assert not list(course.rglob("pwned*")) and not Path("/tmp/lorisnb-pwned.txt").exists()
    assert not (ROOT / "pwned.txt").exists() and not (ROOT / "teaching" / "pwned.txt").exists()
    # a second run regrades nothing (nothing changed)
    t0 = time.monotonic()
    again = grade_class(course, source, settings=GradeSettings(limits), jobs=2, late=due, progress=False)
    assert time.monotonic() - t0 < 5 and [g.result.scores for g in again] == [g.result.scores for g in graded]


# --- the gradebook: roster, late policy, LMS layouts ---------------------------------------------


def _result(student: str, points: list[float]) -> SubmissionResult:
    scores = [Score(f"test_Q{k}", p, 2.0, "✓" if p else "✗") for k, p in enumerate(points, 1)]
    return SubmissionResult(student, LAB, scores, "full", 1.0)


def test_exports_follow_the_lms_layouts_with_roster_names_and_late_policy(tmp_path):
    from lorisnb.tools.teaching.gradebook import Graded

    roster_csv = tmp_path / "roster.csv"
    roster_csv.write_text(
        "id,name,email,sis_id\ns1,Ada Lovelace,ada@uni.example,1001\ns2,Alan Turing,alan@uni.example,1002\n"
    )
    roster = read_roster(roster_csv)
    policy = LatePolicy(datetime(2026, 12, 1, 12, 0, tzinfo=timezone.utc), per_day=0.1, max_days=2)
    on_time = policy.due - timedelta(hours=1)
    assert policy.factor(on_time) == (1.0, 0)
    assert policy.factor(policy.due + timedelta(hours=1)) == (0.9, 1)
    assert policy.factor(policy.due + timedelta(days=2, hours=1)) == (0.0, 3)
    graded = [
        Graded(_result("s1", [2, 2, 0]), on_time, 0, 1.0),
        Graded(_result("s2", [2, 2, 2]), policy.due + timedelta(hours=25), 2, 0.8, 25 * 3600.0),
        Graded(_result("demo-correct", [2, 2, 2]), None, 0, 1.0),
        Graded(_result("s9", [2, 0, 0]), None, 0, 1.0),
    ]
    left_out = write_exports(tmp_path, graded, roster)
    assert left_out.not_on_roster == ["s9"] and left_out.no_email == []

    def rows(name: str) -> list[list[str]]:
        return list(csv.reader((tmp_path / name).open(encoding="utf-8")))

    grades = rows("grades.csv")
    assert grades[0][:7] == ["student", "name", "email", "lab", "test_Q1", "test_Q2", "test_Q3"]
    assert grades[1][:8] == ["s1", "Ada Lovelace", "ada@uni.example", LAB, "2", "2", "0", "4"]
    assert [r[0] for r in rows("grades-demo.csv")[1:]] == ["demo-correct"]
    canvas = rows(f"exports/{LAB}-canvas.csv")  # Canvas gradebook import: these five columns, then the assignment
    assert canvas[0] == ["Student", "ID", "SIS User ID", "SIS Login ID", "Section", LAB]
    assert canvas[1][0].strip() == "Points Possible" and canvas[1][-1] == "6"
    assert canvas[2:] == [["Ada Lovelace", "", "1001", "ada@uni.example", "", "4"],
                          ["Alan Turing", "", "1002", "alan@uni.example", "", "4.8"]]  # fmt: skip
    moodle = rows(f"exports/{LAB}-moodle.csv")
    assert moodle[0] == ["First name", "Last name", "ID number", "Email address", LAB, f"{LAB} feedback"]
    assert moodle[2][:5] == ["Alan", "Turing", "1002", "alan@uni.example", "4.8"] and "2 day(s) late" in moodle[2][5]
    gs = rows(f"exports/{LAB}-gradescope.csv")
    assert gs[0][:9] == ["First Name", "Last Name", "SID", "Email", "Total Score", "Max Points", "Status",
                         "Submission Time", "Lateness (H:M:S)"]  # fmt: skip
    assert gs[0][9] == "1: test_Q1 (2 pts)" and gs[2][8] == "25:00:00" and gs[2][4] == "4.8"
    assert all("demo-" not in "".join(r) and "s9" not in r for f in ("canvas", "moodle", "gradescope")
               for r in rows(f"exports/{LAB}-{f}.csv"))  # fmt: skip


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("id,name\ns1,Ada\n", "missing"),
        ("id,name,email,phone\ns1,Ada,a@b.c,1\n", "unknown"),
        ("id,name,email\ns1,Ada,a@b.c\ns1,Bob,b@b.c\n", "line 3.*twice"),
        ("id,name,email\ns 1,Ada,a@b.c\n", "line 2.*student id"),
        ("id,name,email\ns1,Ada,not-an-email\n", "line 2.*e-mail"),
    ],
)
def test_roster_errors_name_the_line(tmp_path, text, match):
    f = tmp_path / "roster.csv"
    f.write_text(text)
    with pytest.raises(ValidationError, match=match):
        read_roster(f)


def test_late_policy_and_limits_are_validated():
    with pytest.raises(ValidationError, match="time zone"):
        LatePolicy(datetime(2026, 12, 1))
    with pytest.raises(ValidationError, match="within"):
        LatePolicy(datetime(2026, 12, 1, tzinfo=timezone.utc), per_day=10)
    with pytest.raises(ValueError, match="cell_timeout_s"):
        Limits(cell_timeout_s=0)


def test_lab_spec_maps_each_check_to_its_answers():
    spec = lab_spec(SOURCE_NB)
    q = {x.grade_id: x for x in spec.questions}
    assert spec.max_points == 18
    assert q["test_D1_alignment"].names == ("cr_visit2_lifelong", "cr_visit2_per_seq")
    assert spec.functions["B2_correct_rate"] == ("correct_rate",) and spec.values["B2_correct_rate"] == ()
    assert q["test_F_timeline"].answers == ("F_timeline",)


def test_student_variants_differ_between_students_and_repeat_for_one():
    from lorisnb.tools.teaching import lab_variant

    a, b = lab_variant("s1001"), lab_variant("s1002")
    assert a == lab_variant("s1001") and (a.seed, a.lost_window, a.late_start) != (b.seed, b.lost_window, b.late_start)
    seeds = {lab_variant(f"s{k}").lost_window for k in range(30)}
    assert len(seeds) >= 20  # a class of 30 gets many different B1 questions
    assert lab_variant(None, seed=5).seed == 5
    assert np.all([10 <= lab_variant(f"x{k}").lost_window[0] <= 20 for k in range(10)])


def test_answers_are_read_back_as_plain_values_only():
    """What the sandbox reads back after an answer cell: numbers, strings, numpy and pandas numbers;
    an object of the student's (a lazy prediction, a float subclass) only by its type."""
    import pandas as pd

    from lorisnb.tools.teaching._sandbox_child import _plain

    class Sneaky(float):
        pass

    assert _plain(0.25) == {"value": 0.25} and _plain("vins") == {"value": "vins"}
    assert _plain(np.float64(0.5)) == {"value": 0.5} and _plain(np.bool_(True)) == {"value": True}
    assert _plain(pd.Series([0.627], name="eps")) == {"array": [0.627], "dtype": "<f8"}
    assert _plain(...) == {"missing": True}
    assert "not_plain" in _plain(Sneaky(0.5)) and "not_plain" in _plain(object())
    # a list or tuple of numbers (A1's one boolean per pose, as the lab allows) is their array, numpy's str_ a
    # string (both were "not a plain value": the list scored 0 for A1 in `make grade`, ✓ in the notebook);
    # a list holding an object of the student's is not plain
    assert _plain([True, np.bool_(False)]) == {"array": [True, False], "dtype": "|b1"}
    assert _plain((0.5, 1)) == {"array": [0.5, 1.0], "dtype": "<f8"} and _plain(np.str_("vins")) == {"value": "vins"}
    assert "not_plain" in _plain([Sneaky(0.5)]) and "not_plain" in _plain([0.5, "x"]) and "not_plain" in _plain([[0.5]])
    assert isinstance(decode(_plain(Sneaky(0.5))), NotPlain) and decode(_plain(np.float64(2.0))) == 2.0


def test_a_captured_cell_binds_its_output_as_ipython_does(capsys):
    """``%%capture cap`` in an answer cell runs the cell, shows nothing and binds ``cap`` (IPython's
    ``CapturedIO``: ``cap.stdout``), as Jupyter does, also when the cell fails; a later cell that
    reads ``cap.stdout`` is graded on it (it raised NameError: ``cap`` was never bound)."""
    from lorisnb.tools.teaching._sandbox_child import Shell
    from lorisnb.tools.teaching.autograde import as_python

    ns: dict = {}
    shell = Shell(ns)
    ns["get_ipython"] = lambda: shell
    exec(as_python("%%capture cap\nprint('CR 0.625')\nx = 3\n"), ns)  # noqa: S102 (the test's own cell)
    assert ns["x"] == 3 and ns["cap"].stdout == "CR 0.625\n" and str(ns["cap"]) == "CR 0.625\n"
    assert capsys.readouterr().out == ""  # kept, not shown
    exec(as_python("%%capture --no-stderr out\nimport sys\nprint('kept')\nsys.stderr.write('shown')\n"), ns)  # noqa: S102
    assert ns["out"].stdout == "kept\n" and capsys.readouterr().err == "shown"
    with pytest.raises(ZeroDivisionError):
        exec(as_python("%%capture failed\nprint('before')\n1 / 0\n"), ns)  # noqa: S102
    assert ns["failed"].stdout == "before\n"
    exec(as_python("%%capture\nprint('quiet')\ny = 4\n"), ns)  # noqa: S102 (no name: nothing bound)
    assert ns["y"] == 4 and capsys.readouterr().out == ""


@pytest.fixture
def open_base():
    """A folder under /tmp that other users may enter (pytest's tmp_path is closed to them)."""
    import shutil
    import tempfile

    d = Path(tempfile.mkdtemp(prefix="lorisnb-open-", dir="/tmp" if os.name == "posix" else None))
    d.chmod(0o755)
    yield d
    for q in d.rglob("*"):
        if q.is_dir():
            q.chmod(0o755)
    shutil.rmtree(d, ignore_errors=True)


def test_folders_closed_to_others_are_named(open_base):
    """What the sandbox's user could not pass on the way to a path (lorisnb in a checkout inside a
    folder closed to others made every answer score 0, silently)."""
    from lorisnb.tools.teaching.sandbox import closed_to_others

    closed, open_ = open_base / "closed", open_base / "open"
    (closed / "lorisnb").mkdir(parents=True)
    open_.mkdir()
    closed.chmod(0o700)
    open_.chmod(0o755)
    assert closed_to_others([closed / "lorisnb", open_]) == [closed.resolve()]
    assert closed_to_others([open_]) == []


@isolated
def test_grading_refuses_when_the_sandbox_cannot_read_lorisnb(open_base):
    from lorisnb.errors import ValidationError
    from lorisnb.tools.teaching import autograde

    closed = open_base / "closed"
    (closed / "lorisnb").mkdir(parents=True)
    closed.chmod(0o700)
    with pytest.raises(ValidationError, match=f"cannot read {closed.resolve()} "):
        autograde._check_reachable(closed, GradeSettings())
    autograde._check_reachable(Path(autograde.__file__).resolve().parents[3], GradeSettings())  # lorisnb's own: fine


def test_a_script_folder_on_sys_path_does_not_open_the_checkout(monkeypatch):
    """``python teaching/grade.py`` puts teaching/ first on sys.path (so did a kit test, once, before
    the adversarial test in one process): the sandbox must still hide teaching/ (the labs' solutions),
    tests/ and the git database; only lorisnb and its Python environment stay readable."""
    import sys

    import lorisnb
    from lorisnb.tools.teaching import autograde

    pkg = Path(lorisnb.__file__).resolve().parent
    if not (pkg.parent / "pyproject.toml").is_file():
        pytest.skip("lorisnb is installed, not run from a checkout: no checkout folder to hide")
    monkeypatch.setattr(sys, "path", [str(pkg.parent / "teaching"), str(pkg.parent / "tests"), *sys.path])
    py_path, hidden = autograde._package_paths()
    assert py_path == pkg.parent
    for name in ("teaching", "tests", ".git"):
        if (pkg.parent / name).is_dir():
            assert (pkg.parent / name).resolve() in hidden, name
    assert not any(pkg.is_relative_to(h) or Path(sys.prefix).resolve().is_relative_to(h) for h in hidden)


def test_the_git_database_of_a_course_kept_in_its_own_repository_is_hidden(tmp_path):
    """A course (and its labs' sources) in a repository of its own, not the checkout lorisnb runs
    from: the sandbox hid the course and source folders but not that repository's ``.git``, whose
    history holds the solutions (``git show HEAD:source/...`` from a sandbox printed them). A
    worktree's ``.git`` file leads to the main repository's database."""
    from lorisnb.tools.teaching import autograde, gradebook

    repo = tmp_path / "course-repo"
    (repo / ".git").mkdir(parents=True)
    (repo / "course").mkdir()
    (repo / "labs" / "source").mkdir(parents=True)
    assert autograde.git_databases([repo / "course", repo / "labs" / "source"]) == [(repo / ".git").resolve()]
    tree = tmp_path / "tree"
    (repo / ".git" / "worktrees" / "tree").mkdir(parents=True)
    (tree / "source").mkdir(parents=True)
    (tree / ".git").write_text("gitdir: ../course-repo/.git/worktrees/tree\n")  # relative, as git writes some
    assert autograde.git_databases([tree / "source"]) == [(repo / ".git").resolve()]

    hidden = gradebook.grading_settings(
        repo / "course", repo / "labs" / "source", autograde.GradeSettings(), "s"
    ).hidden
    assert (repo / ".git").resolve() in hidden and repo / "course" in hidden


@pytest.mark.thorough
def test_concurrent_graders_get_sandbox_users_of_their_own():
    """Each grading process holds its pair of sandbox user ids until it ends (a lock per id): two
    workers of one class, or two graders started side by side, never share one (the old rule, the
    pid modulo 1000, gave two workers the same user now and then). Ids of existing accounts are
    skipped."""
    import pwd
    import subprocess
    import sys

    from lorisnb.tools.teaching.sandbox import claim_uids

    base = 64000 + 2 * (os.getpid() % 500) * 8  # apart from other runs of this test
    code = "import sys; from lorisnb.tools.teaching.sandbox import claim_uids as c; print(c(%d), flush=True); sys.stdin.read()"
    procs = [subprocess.Popen([sys.executable, "-c", code % base], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                              text=True) for _ in range(3)]  # fmt: skip
    try:
        firsts = [int(p.stdout.readline()) for p in procs]
    finally:
        for p in procs:
            p.communicate("", timeout=60)
    assert len(set(firsts)) == 3 and all(f % 2 == base % 2 and base <= f < base + 4000 for f in firsts), firsts
    mine = claim_uids(base)
    assert claim_uids(base) == mine  # the same pair for every call of one process
    assert pwd.getpwuid(0) and claim_uids(0, 2, span=4000) != 0  # root's id is never a sandbox's


# --- a slow submission, an unreadable one, and the notes a submission earns (issue 46's review) ---


def _solutions() -> dict[str, str]:
    nb = nbformat.read(SOURCE_NB, as_version=4)
    return {c.metadata["nbgrader"]["grade_id"]: c.source for c in nb.cells if c.get("metadata", {}).get("nbgrader", {}).get("solution")}  # fmt: skip


def _submission(answers: dict[str, str]) -> nbformat.NotebookNode:
    nb = nbformat.read(SOURCE_NB, as_version=4)
    for cell in nb.cells:
        gid = cell.get("metadata", {}).get("nbgrader", {}).get("grade_id")
        if gid in answers and cell.metadata["nbgrader"].get("solution"):
            cell.source = answers[gid]
    return nb


def _slow(limit: float) -> dict[str, str]:
    """Every answer right, but each cell and each call of B2's function sleeping 0.9 x the per-cell
    limit, and three endless loops (C1, D1, F): A1, B1 and B3, answered before the budget runs out,
    still score."""
    sol, nap = _solutions(), f"import time\ntime.sleep({0.9 * limit})\n"
    loop = "while True:\n    pass\n"
    b2 = (nap + sol["B2_correct_rate"] + "\n_honest = correct_rate\n"
          "def correct_rate(stamps, correct, t_min, t_max, delta):\n"
          f"    time.sleep({0.9 * limit})\n"
          "    return _honest(stamps=stamps, correct=correct, t_min=t_min, t_max=t_max, delta=delta)\n")  # fmt: skip
    slow = {g: nap + s for g, s in sol.items() if g not in ("A1_correctness", "B1_prediction")}
    return {**sol, **slow, "B2_correct_rate": b2, "C1_cs_r": loop, "D1_alignment": loop, "F_timeline": loop}


@pytest.mark.slow
def test_a_slow_submission_stops_at_its_budget_and_keeps_the_points_it_earned(tmp_path):
    """Issue 46's review: a submission whose cells and calls each sleep 0.9 x the limit, plus endless
    loops, took ~51 s per second of limit (every time-out replayed every earlier cell, every check
    call got the full limit): now its code runs for at most the budget, and the honest answers
    before that still score, with a note."""
    from lorisnb.tools.teaching.autograde import grade_submission

    spec, release = lab_spec(SOURCE_NB), tmp_path / "release"
    release.mkdir()
    limits = Limits(cell_timeout_s=3, locked_timeout_s=180, budget_s=30)
    settings = GradeSettings(limits, secret="s", uid=claim_uids(62000) if can_isolate() else 0)
    honest, slow = tmp_path / "honest" / f"{LAB}.ipynb", tmp_path / "slow" / f"{LAB}.ipynb"
    for path, nb in ((honest, nbformat.read(SOURCE_NB, as_version=4)), (slow, _submission(_slow(3)))):
        path.parent.mkdir()
        nbformat.write(nb, path)
    t0 = time.monotonic()
    base = grade_submission(spec, release, honest, "s-honest", settings)
    honest_s = time.monotonic() - t0
    assert base.points == 18 and not any("budget" in n for n in base.notes), base.notes
    t0 = time.monotonic()
    res = grade_submission(spec, release, slow, "s-slow", settings)
    seconds = time.monotonic() - t0
    assert seconds < honest_s + limits.submission_s + 10, f"{seconds:.0f} s (honest: {honest_s:.0f} s)"
    pts = {s.question: s.points for s in res.scores}
    assert pts["test_A1_correctness"] == 2 and pts["test_B1_prediction"] == 1 and pts["test_B3_prediction"] == 1, res
    assert pts["test_B2_correct_rate"] == 0 and pts["test_C1_cs_r"] == 0 and pts["test_F_timeline"] == 0
    assert any(n.startswith("time budget:") and "30 s" in n for n in res.notes), res.notes
    msg = {s.question: s.message for s in res.scores}
    assert "time" in msg["test_B2_correct_rate"].lower() and "budget" in msg["test_G1_difficulty"], msg


def test_limits_take_a_budget():
    assert Limits(cell_timeout_s=60).submission_s == 300 and Limits(budget_s=7).submission_s == 7
    assert Limits(cell_timeout_s=5).submission_s == 120  # the lab's own cells need their time too
    with pytest.raises(ValueError, match="budget_s"):
        Limits(budget_s=0)


@pytest.mark.slow
def test_each_submission_is_graded_on_its_own_with_notes(tmp_path, capsys):
    """A truncated notebook scores 0, named, and the others are graded (it stopped the whole run,
    naming no one); a notebook without the answer cells' metadata, a 5 MB answer, and a submission
    writing fake replies into the grader's pipe each get a note, and the feedback stays small."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("teaching_grade", ROOT / "teaching" / "grade.py")
    grade = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(grade)
    course, source = tmp_path / "course", tmp_path / "source"
    shutil.copytree(SOURCE_NB.parent, source / LAB)
    (course / "release" / LAB).mkdir(parents=True)
    sol = _solutions()
    fake = (
        "import json, os\n"
        "_fake = json.dumps({'ok': True, 'values': {'predicted_cr_lost': {'value': 0.123}}}) + '\\n'\n"
        "for _fd in range(3, 64):\n"
        "    try:\n"
        "        if os.readlink(f'/proc/self/fd/{_fd}').startswith('pipe:'):\n"
        "            os.write(_fd, _fake.encode())\n"
        "    except OSError:\n"
        "        pass\n"
    )
    stripped = nbformat.read(SOURCE_NB, as_version=4)
    for cell in stripped.cells:
        cell.metadata.pop("nbgrader", None)
    subs = {
        "s-bad": None,
        "s-stripped": stripped,
        "s-long": _submission({"F_timeline": sol["F_timeline"] + "\nbest_algorithm = 'x' * 5_000_000\n"}),
        "s-tamper": _submission({"B1_prediction": fake + sol["B1_prediction"]}),
    }
    for student, nb in subs.items():
        path = course / "submitted" / student / LAB / f"{LAB}.ipynb"
        path.parent.mkdir(parents=True)
        if nb is None:
            text = nbformat.writes(nbformat.read(SOURCE_NB, as_version=4))
            path.write_text(text[: len(text) // 2])  # cut off mid-way, as a failed upload
        else:
            nbformat.write(nb, path)
    rc = grade.main([str(course), "--source", str(source), "--timeout", "10", "--no-progress"])
    out, err = capsys.readouterr()
    assert rc == 1 and "s-bad" in err and "JSON" in err, err
    rows = {r["student"]: r for r in csv.DictReader((course / "grades.csv").open())}
    assert set(rows) == set(subs) and rows["s-bad"]["raw_score"] == "0"
    assert float(rows["s-tamper"]["raw_score"]) == 18, rows["s-tamper"]
    results = {s: SubmissionResult.from_json((course / "graded" / s / LAB / "result.json").read_text()) for s in subs}
    assert "s-bad/" in results["s-bad"].notes[0] and results["s-bad"].error
    assert any("none of the lab's answer cells" in n for n in results["s-stripped"].notes), results["s-stripped"].notes
    assert any("did not ask for" in n for n in results["s-tamper"].notes), results["s-tamper"].notes
    assert not any("did not ask for" in n for s in ("s-long", "s-stripped") for n in results[s].notes)
    for name in ("result.json", "feedback.html"):
        size = (course / "graded" / "s-long" / LAB / name).stat().st_size
        assert size < 100_000, f"{name}: {size} bytes"
    assert "characters left out" in (course / "graded" / "s-long" / LAB / "result.json").read_text()


@pytest.mark.slow
def test_a_copied_cell_a_try_out_line_and_a_helper_of_an_earlier_cell_are_graded_as_the_notebook_ran(tmp_path):
    """What an honest notebook does and its own checks accept: a copied answer cell (it keeps its
    grade id) with the corrected function in the last copy, a try-out line reading the lab's
    numbers (``eps``) below a formula, a formula calling a helper the student wrote in an earlier
    answer cell. Each scored 0 (the first copy graded; the cell run alone failed on ``eps`` or the
    helper): all are right, with a note where the grade reads the notebook otherwise than as run."""
    from lorisnb.tools.teaching.autograde import grade_submission

    spec, release = lab_spec(SOURCE_NB), tmp_path / "release"
    release.mkdir()
    settings = GradeSettings(Limits(cell_timeout_s=10, locked_timeout_s=180), secret="s",
                             uid=claim_uids(63000) if can_isolate() else 0)  # fmt: skip
    sol = _solutions()
    nb = _submission({
        "A1_correctness": sol["A1_correctness"].replace("<= phi", "<= np.radians(phi)"),  # the first attempt
        "C1_cs_r": sol["C1_cs_r"] + "\nprint(cs_r(3.0, 0.0, True, tau))  # trying it out\n",
    })  # fmt: skip
    a1 = next(i for i, c in enumerate(nb.cells) if c.get("metadata", {}).get("nbgrader", {}).get("grade_id")
              == "A1_correctness")  # fmt: skip
    copy = nbformat.from_dict(dict(nb.cells[a1], id="copied-a1"))  # Jupyter gives a copy a cell id of its own
    copy.source = sol["A1_correctness"] + "\n\ndef held_time(stamps, t_max, delta):\n" \
        "    return np.minimum(np.diff(np.append(stamps, t_max)), delta)\n"  # fmt: skip
    nb.cells.insert(a1 + 1, copy)  # the corrected copy, below the first attempt
    b2 = next(c for c in nb.cells if c.get("metadata", {}).get("nbgrader", {}).get("grade_id") == "B2_correct_rate")
    b2.source = ("def correct_rate(stamps, correct, t_min, t_max, delta):\n"
                 "    return float(np.sum(held_time(stamps, t_max, delta) * np.asarray(correct)) / (t_max - t_min))\n")  # fmt: skip
    path = tmp_path / "s" / f"{LAB}.ipynb"
    path.parent.mkdir()
    nbformat.write(nb, path)
    res = grade_submission(spec, release, path, "s-honest", settings)
    assert res.points == res.max_points == 18, [(s.question, s.message) for s in res.scores if s.points < s.max_points]
    assert any(n.startswith("A1_correctness: 2 cells carry this answer's id") for n in res.notes), res.notes
    assert any(n.startswith("C1_cs_r: a line outside its functions needs the lab's numbers (NameError: name 'tau'")
               for n in res.notes), res.notes  # fmt: skip


# --- copied notebooks: identical answer cells are flagged, no points changed ---------------------------


def _as_submitted(source: str) -> str:
    """An instructor's answer cell as a student returns it: the release's lines and the solution, no
    nbgrader delimiters."""
    return "\n".join(line for line in source.splitlines() if line.strip() not in ("### BEGIN SOLUTION", "### END SOLUTION"))  # fmt: skip


def test_identical_answer_cells_flag_a_copy_not_the_stub_nor_short_answers_many_write_alike(tmp_path):
    """A byte-for-byte copy of another student's notebook got full marks and no flag. On lab 1's
    answer cells: a copy (trailing spaces added) is flagged on every answer with 40+ characters of
    its own, naming both; the stubs handed out, the one-liners many write alike (B3's 1.0, A1's
    comparison) and two identical answers only are not."""
    from lorisnb.tools.teaching import gradebook

    spec = lab_spec(SOURCE_NB)
    stubs = gradebook.answer_stubs(spec, tmp_path)  # no release notebook here: nbgrader's stubs, derived
    assert stubs["B3_prediction"] == ["predicted_cr_t_late = ...\n# YOUR CODE HERE\nraise NotImplementedError()"]
    # a student's own working: the instructor's answer and a line of their own (the instructor's alone is what
    # the exercise leads to, and is not counted)
    own = {gid: _as_submitted(src) + "\n_worked = 'my own check'\n" for gid, src in _solutions().items()}
    short = {
        "A1_correctness": "def correctness(ate_m, aoe_deg, eps, phi):\n    return (ate_m <= eps) & (aoe_deg <= phi)\n",
        "B1_prediction": "predicted_cr_lost = 1 - 19 / T\n",
        "B3_prediction": "predicted_cr_t_late = 1.0\n",
        "C2_prediction": "predicted_cs_r_wrong = 0.0\n",
        "C1_cs_r": "def cs_r(t0, t_min, first_correct, tau):\n    return np.exp((t_min - t0) / tau)\n",
    }
    answers = {
        "s-ann": own,
        "s-ben": {gid: "\n".join(line + "   " for line in src.splitlines()) + "\n\n" for gid, src in own.items()},
        "s-cat": {gid: s[0] for gid, s in stubs.items()},  # returned unanswered
        "s-dan": {gid: s[0] for gid, s in stubs.items()},
        "s-eve": short,
        "s-fay": dict(short),
        "s-gus": {"B2_correct_rate": own["B2_correct_rate"], "D1_alignment": own["D1_alignment"]},
        # the instructor's answers, reformatted and commented (two who read the book): the exercise's formulation
        "s-hal": {gid: "# mine\n" + _as_submitted(src).replace(" = ", "=") for gid, src in _solutions().items()},
        "s-ian": {gid: _as_submitted(src) + "\n\n" for gid, src in _solutions().items()},
        # long one-line answers the exercise dictates (the adversarial pass's alice and bob)
        "s-jo": {
            "A1_correctness": "def correctness(ate_m, aoe_deg, eps, phi):\n    return np.logical_and(ate_m <= eps, aoe_deg <= phi)\n",
            "C1_cs_r": "def cs_r(t0, t_min, first_correct, tau):\n    return np.exp(-(t0 - t_min) / tau) * first_correct\n",
            "G1_difficulty": 'ate_percent_cafe = 100 * orb_seq["ate_rmse"] / gt_seq.path_length\n',
        },
    }
    answers["s-kim"] = dict(answers["s-jo"], B3_prediction="predicted_cr_t_late = 1")
    found = gradebook.identical_answers(answers, stubs, gradebook.canonical_answers(spec))
    copied = ("A1_correctness", "B1_prediction", "B2_correct_rate", "B3_prediction", "C1_cs_r", "C2_prediction",
              "D1_alignment", "E1_threshold", "F_timeline", "G1_difficulty")  # fmt: skip
    assert found == {"s-ann": {"s-ben": copied}, "s-ben": {"s-ann": copied}}
    # an answer four students share is the exercise's, not a copy
    common = {s: dict(own) for s in ("s-w", "s-x", "s-y", "s-z")}
    assert gradebook.identical_answers(common, stubs, gradebook.canonical_answers(spec)) == {}
    assert set(gradebook.identical_answers(dict(list(common.items())[:3]), stubs)) == {"s-w", "s-x", "s-y"}


@pytest.mark.thorough
def test_a_copied_notebook_is_flagged_on_both_students_and_keeps_its_points(tmp_path, capsys):
    """`make grade` on a class where s-ben returned s-ann's notebook byte for byte: both keep their
    points, both are noted (grades.csv), naming the other and the answer cells, and the command line
    says so; students returning the stubs, or the same short answers, are not flagged; the student's
    feedback page does not name the other student (an instructor decides, and tells)."""
    from test_gradebook_times import TINY, grade_script, submit, tiny_course

    grade = grade_script()
    course, source = tiny_course(tmp_path)
    ann = submit(course, "s-ann")
    (course / "submitted" / "s-ben" / TINY).mkdir(parents=True)
    shutil.copyfile(ann / f"{TINY}.ipynb", course / "submitted" / "s-ben" / TINY / f"{TINY}.ipynb")
    submit(course, "s-cat", answers={})  # the release, unanswered
    submit(course, "s-dan", answers={})
    short = {"Q1_total": "total = 293", "Q2_mean": "mean = 5.0", "Q3_word": "word = 'ceilnoprs'",
             "Q4_flag": "flag = True", "Q5_count": "count = 3"}  # fmt: skip
    submit(course, "s-eve", answers=short)
    submit(course, "s-fay", answers=short)
    rc = grade.main([str(course), "--source", str(source), "--timeout", "30", "--no-progress"])
    out, err = capsys.readouterr()
    assert rc == 0, err
    rows = {r["student"]: r for r in csv.DictReader((course / "grades.csv").open(encoding="utf-8"))}
    assert {s: r["score"] for s, r in rows.items()} == {"s-ann": "5", "s-ben": "5", "s-cat": "0", "s-dan": "0",
                                                        "s-eve": "5", "s-fay": "5"}  # fmt: skip
    for student, other in (("s-ann", "s-ben"), ("s-ben", "s-ann")):
        note = rows[student]["notes"]
        assert note.startswith("possible copy:") and f"{other}'s Q1_total, Q2_mean, Q3_word" in note, note
        assert "no points changed" in note
        assert other not in (course / "graded" / student / TINY / "feedback.html").read_text()
    assert all(rows[s]["notes"] == "" for s in ("s-cat", "s-dan", "s-eve", "s-fay")), rows
    assert "1 pair(s) of submissions with identical answer cells" in err
    assert "s-ann and s-ben (tiny_lab: Q1_total, Q2_mean, Q3_word, Q4_flag, Q5_count)" in err


def test_a_needed_path_through_a_link_in_a_temporary_folder_is_kept_in_that_folder(tmp_path):
    """A clone in /tmp whose .venv links to a checkout's: the interpreter is started by the path
    through the link, which lay in a temporary folder the sandbox emptied; the child could not start
    and every answer of the kit's demo scored 0 (a fresh clone's make grade: 0 / 18). The folder is
    emptied all the same, the path through the link bound back in it (until the adversarial teaching
    pass the whole folder was left open: tests/tools/test_teaching_sandbox_tmp_env.py)."""
    from lorisnb.tools.teaching.sandbox import kept_paths, private_folders

    tmp, real = tmp_path / "tmp", tmp_path / "checkout" / ".venv" / "bin"
    real.mkdir(parents=True)
    (tmp / "clone").mkdir(parents=True)
    (tmp / "clone" / ".venv").symlink_to(real.parent, target_is_directory=True)
    work = tmp / "grade" / "work"
    work.mkdir(parents=True)
    python = tmp / "clone" / ".venv" / "bin" / "python"
    assert private_folders(work, [tmp], [real], tmp=False) == [tmp.resolve()]  # only the resolved path: emptied
    assert private_folders(work, [tmp], [python.parent], tmp=False) == [tmp.resolve()]
    assert kept_paths([tmp.resolve()], [python.parent]) == [python.parent]  # the path the child starts by: kept
