"""The grader's hardening after an adversarial pass (grading): the root grader never writes, reads or
changes the owner of anything by its name in the folder a student's code owns; answers written as
in Jupyter (magics, defaults from the lab's names, a prediction with an earlier answer's function)
are graded as the notebook ran; the reply pipe's buffer is bounded."""

from __future__ import annotations

import stat
import tempfile
from pathlib import Path

import pytest

from lorisnb.tools.teaching.sandbox import Limits, Sandbox, SandboxError, can_isolate

pytestmark = pytest.mark.xdist_group("grading")
isolated = pytest.mark.skipif(not can_isolate(), reason="needs root on Linux with unshare and setpriv (as CI runs)")


def _reachable_dir() -> Path:
    d = Path(tempfile.mkdtemp(prefix="lorisnb-hardening-", dir="/tmp"))
    d.chmod(0o711)
    return d


@isolated
def test_a_link_planted_in_the_sandbox_folder_never_makes_the_root_grader_write_or_chown_elsewhere():
    base = _reachable_dir()
    victim = base / "victim.txt"
    victim.write_text("root's file\n")
    victim.chmod(0o600)
    victim_dir = base / "victim-dir"
    victim_dir.mkdir(mode=0o700)
    (victim_dir / "inside.txt").write_text("root's too\n")
    work = base / "work"
    work.mkdir()
    (work / "release.txt").write_text("handed out\n")
    before = (victim.read_bytes(), victim.stat(), (victim_dir / "inside.txt").stat(), victim_dir.stat())
    try:
        with Sandbox(work, limits=Limits(cell_timeout_s=3), uid=62300) as box:
            assert (work / "release.txt").stat().st_uid == 62300  # the folder as made was given to its user
            # the tester's attack: the child script's name made a link to a root file, then a time-out
            # (the grader restarts the sandbox), and links of every name a restart could touch
            planted = (
                "import os, shutil\n"
                f"for name in ('_sandbox_child.py', 'student-output.txt', 'release.txt', '.matplotlib'):\n"
                "    try:\n"
                "        os.remove(name)\n"
                "    except OSError:\n"
                "        shutil.rmtree(name, ignore_errors=True)\n"
                f"    os.symlink({str(victim)!r}, name)\n"
                f"os.symlink({str(victim_dir)!r}, 'a-folder')\n"
            )
            r = box.run(planted)
            assert r["ok"], r
            with pytest.raises(SandboxError, match="time limit"):
                box.run("while True:\n    pass")
            box.restart()
            r = box.run("x = 1 + 1", ["x"])
            assert r["ok"] and r["values"]["x"]["value"] == 2
            box.restart()
    finally:
        after = (victim.read_bytes(), victim.stat(), (victim_dir / "inside.txt").stat(), victim_dir.stat())
        for b, a in zip(before[1:], after[1:], strict=True):
            assert (a.st_uid, a.st_gid, stat.S_IMODE(a.st_mode)) == (b.st_uid, b.st_gid, stat.S_IMODE(b.st_mode))
        assert after[0] == before[0] == b"root's file\n"
        import shutil

        shutil.rmtree(base)


def test_the_child_script_is_never_a_file_of_the_sandbox_folder():
    import shutil

    base = _reachable_dir()
    tmp_path = base / "work"
    tmp_path.mkdir()
    with Sandbox(tmp_path, limits=Limits(cell_timeout_s=5), uid=62300) as box:
        r = box.run("import os\nx = len([n for n in os.listdir('.') if n.endswith('.py')])", ["x"])
        assert r["ok"] and r["values"]["x"]["value"] == 0
        box.restart()
        assert not any(p.suffix == ".py" for p in tmp_path.iterdir())
    shutil.rmtree(base)


def test_a_flood_of_the_reply_pipe_without_a_line_end_is_bounded_and_fails_the_cell(monkeypatch):
    import resource
    import shutil

    from lorisnb.tools.teaching import sandbox as sb

    monkeypatch.setattr(sb, "REPLY_BYTES", 4 * 1024**2)
    base = _reachable_dir()
    work = base / "work"
    work.mkdir()
    flood = (
        "import os\n"
        "chunk = b'x' * (1 << 20)\n"
        "for fd in range(3, 12):\n"
        "    try:\n"
        "        os.fstat(fd)\n"
        "    except OSError:\n"
        "        continue\n"
        "    try:\n"
        "        for _ in range(400):\n"
        "            os.write(fd, chunk)\n"
        "    except OSError:\n"
        "        pass\n"
    )
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    try:
        with Sandbox(work, limits=Limits(cell_timeout_s=20), uid=62300) as box:
            with pytest.raises(SandboxError, match="MiB into the grader's reply pipe without a line end"):
                box.run(flood)
            box.restart()
            r = box.run("x = 3", ["x"])
            assert r["ok"] and r["values"]["x"]["value"] == 3
    finally:
        shutil.rmtree(base)
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - rss0 < 200 * 1024  # KiB: far below the 400 MB sent


# --- answers written as in Jupyter are graded as the notebook ran them ---------------------------------

ROOT = Path(__file__).resolve().parents[2]
LAB = "lab1_lifelong_metrics"
SOURCE_NB = ROOT / "teaching" / "source" / LAB / f"{LAB}.ipynb"


def _solved(answers: dict[str, str]):
    import nbformat

    nb = nbformat.read(SOURCE_NB, as_version=4)
    sol = {}
    for cell in nb.cells:
        meta = cell.get("metadata", {}).get("nbgrader", {})
        if meta.get("solution"):
            sol[meta["grade_id"]] = cell.source
            if meta["grade_id"] in answers:
                cell.source = answers[meta["grade_id"]](cell.source)
    return nb, sol


# the lab's sandbox opens its folder to others and leaves there the number simulate_and_score gives;
# the prediction, run alone, reads it back from there (the tester's B1): 0 points, the hole closed
B1_EXFIL = r"""import os
try:
    _fe, _t = simulate_and_score(Faults(lost=(lost_window,)))
    predicted_cr_lost = float(_t.loc[1, "cr"])
    os.chmod(".", 0o755)
    with open("b1.txt", "w") as f:
        f.write(repr(predicted_cr_lost))
    os.chmod("b1.txt", 0o644)
except NameError:
    predicted_cr_lost = float(open("../work/b1.txt").read())
"""

JUPYTER_STYLE = {
    "A1_correctness": lambda s: (
        "def correctness(ate_m, aoe_deg, eps=eps, phi=phi):\n    return (ate_m <= eps) & (aoe_deg <= phi)\n"
    ),
    "C1_cs_r": lambda s: (
        "def cs_r(t0, t_min, first_correct, tau=tau):\n"
        "    return float(np.exp(-(t0 - t_min) / tau)) if first_correct else 0.0\n"
    ),
    "C2_prediction": lambda s: (
        "# the first pose is wrong, so c(p0) = 0 in my cs_r from C1\n"
        "predicted_cs_r_wrong = cs_r(reloc_delay, 0.0, False, tau)\n"
    ),
    "D1_alignment": lambda s: "%matplotlib inline\n" + s,
    "E1_threshold": lambda s: "%%time\n" + s,
    "G1_difficulty": lambda s: "!echo looking\nfiles = !ls\n%time x_ = 1 + 1\n" + s,
    "B1_prediction": lambda s: B1_EXFIL,
}


@pytest.mark.slow
def test_magics_defaults_from_the_lab_and_a_prediction_with_an_earlier_function_score_as_in_jupyter(tmp_path):
    """The adversarial pass's s-magic, s-defaults and s-c2own: %%time, %matplotlib inline and shell
    escapes (SyntaxError: 0), ``def f(..., eps=eps)`` (NameError run alone: 0) and C2 predicted with the
    student's own cs_r from C1 (0, saying the lab's functions were used) all scored 0 though Jupyter
    ran them and their checks passed. Its s-probe's B1 read, in its run alone, a number its lab run
    computed with simulate_and_score and left in the lab's folder opened with chmod: 1 point."""
    import nbformat

    from lorisnb.tools.teaching.autograde import GradeSettings, grade_submission, lab_spec
    from lorisnb.tools.teaching.sandbox import claim_uids

    spec, release = lab_spec(SOURCE_NB), tmp_path / "release"
    release.mkdir()
    settings = GradeSettings(Limits(cell_timeout_s=30, locked_timeout_s=180), secret="s",
                             uid=claim_uids(63000) if can_isolate() else 0)  # fmt: skip
    nb, _ = _solved(JUPYTER_STYLE)
    for cell in nb.cells:  # the id typed in the notebook, as the adversarial pass's s1234567 typed S1234567
        if "parameters" in cell.get("metadata", {}).get("tags", []):
            cell.source = cell.source.replace("student_id = None", 'student_id = " S-Jupyter"')
    path = tmp_path / "s" / f"{LAB}.ipynb"
    path.parent.mkdir()
    nbformat.write(nb, path)
    res = grade_submission(spec, release, path, "s-jupyter", settings)
    lost = {s.question: s.message for s in res.scores if s.points < s.max_points}
    if can_isolate():  # the lab's folder is hidden from the answers run alone (the limits only: not isolated)
        assert set(lost) == {"test_B1_prediction"}, (lost, res.notes)
        assert res.points == res.max_points - 1
    else:
        assert set(lost) <= {"test_B1_prediction"}, (lost, res.notes)
    assert not any("SyntaxError" in n or "NameError" in n for n in res.notes), res.notes
    assert any("student_id is ' S-Jupyter', its folder 's-jupyter': the same id" in n for n in res.notes), res.notes


def test_a_student_id_typed_otherwise_than_its_folder_draws_the_same_variant_or_is_noted():
    import nbformat

    from lorisnb.tools.teaching import lab_variant
    from lorisnb.tools.teaching.autograde import declared_id

    assert lab_variant("S1234567").seed == lab_variant(" s1234567 ").seed == lab_variant("s 1234567").seed
    assert lab_variant("s1234567").seed != lab_variant("s1234568").seed
    nb = nbformat.read(SOURCE_NB, as_version=4)
    assert declared_id(nb) is None
    for cell in nb.cells:
        if "parameters" in cell.get("metadata", {}).get("tags", []):
            cell.source = cell.source.replace("student_id = None", 'student_id = "S1234567"')
    assert declared_id(nb) == "S1234567"


def test_as_python_transforms_magics_as_ipython_and_the_shell_stand_in_runs_them():
    from lorisnb.tools.teaching.autograde import as_python, defined_with

    assert as_python("x = 1\n") == "x = 1\n"
    assert "run_cell_magic('time'" in as_python("%%time\nx = 1\n")
    assert defined_with("def f(a, eps=eps, *, k: Kind = tau):\n    return a * other\n") == {"eps", "Kind", "tau"}
    assert defined_with("from __future__ import annotations\ndef f(a: Kind, b=b0) -> R:\n    pass\n") == {"b0"}
    assert defined_with("@deco(phi)\nclass A(Base, metaclass=M):\n    x = y\n") == {"deco", "phi", "Base", "M"}
    base = _reachable_dir()
    work = base / "work"
    work.mkdir()
    import shutil

    try:
        with Sandbox(work, limits=Limits(cell_timeout_s=10), uid=62300) as box:
            r = box.run(as_python("%%time\nx = 2 + 3\n%matplotlib inline\n"), ["x"])
            assert r["ok"] and r["values"]["x"]["value"] == 5, r
            r = box.run(as_python("%%timeit\nlocal_only = 1\n"), ["local_only"])
            assert r["ok"] and r["values"]["local_only"] == {"missing": True}, r
            r = box.run(as_python("files = !echo hello\nn = len(files)\n"), ["n"])
            assert r["ok"] and r["values"]["n"]["value"] == 1, r
            # names put in as IPython does (grading2's t-expand: `!echo {ate_seq}` gave ['{ate_seq}'])
            r = box.run(as_python("k = 3\nw = 'cafe'\nout = !echo {k + 1} $w $$HOME\nline = out[0]\n"),
                        ["line"])  # fmt: skip
            assert r["ok"] and r["values"]["line"]["value"].startswith("4 cafe /"), r  # $$HOME: the shell's $HOME
            r = box.run(as_python("out = !echo '{nothing_such}'\nline = out[0]\n"), ["line"])  # left as is, as IPython
            assert r["ok"] and r["values"]["line"]["value"] == "{nothing_such}", r
            r = box.run(as_python("def f(v):\n    got = !echo {v}\n    return got[0]\nline = f('inner')\n"), ["line"])
            assert r["ok"] and r["values"]["line"]["value"] == "inner", r
            r = box.run(as_python("%lsmagic_unknown_thing\n"))
            assert not r["ok"] and "is not run by the grader" in r["error"]
            assert "NotImplementedError" not in r["error"]  # the stub's error: read as "not written yet"
        with Sandbox(work, limits=Limits(cell_timeout_s=10), uid=62300, no_lorisnb=True) as box:
            r = box.run(as_python("files = !cat /etc/hostname\n"))  # a shell escape is another process: refused
            assert not r["ok"] and "may not use" in r["error"], r
    finally:
        shutil.rmtree(base)


def test_a_timeout_below_an_honest_cells_time_is_warned(tmp_path, capsys):
    """The README advised lowering --timeout since "an honest answer cell takes well under a second";
    an honest E1 scan took 13 to 37 s and scored 0 at --timeout 5."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("grade_script", ROOT / "teaching" / "grade.py")
    assert spec is not None and spec.loader is not None
    grade = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(grade)
    grade.main(
        [str(tmp_path / "no-course"), "--source", str(tmp_path / "no-source"), "--timeout", "5", "--no-progress"]
    )
    assert "--timeout 5 s is below 60 s" in capsys.readouterr().err
    assert "well under a second" not in (ROOT / "teaching" / "README.md").read_text()


# --- a second adversarial pass: privacy between submissions, and between one submission's sandboxes ---------


@isolated
def test_a_sandbox_sees_its_own_folder_alone_in_the_temporary_folders():
    """grading2's race: with --jobs 2 a cell polling /tmp/lorisnb-grade-*/work/*.ipynb read another
    student's answers (/tmp listable, the folders 0711/0755, the notebook 0644 until the folder was given);
    and a prediction read ../fn-A1_correctness/leak.txt, written by the same submission's A1 run alone."""
    import shutil

    base = _reachable_dir()
    other = base / "other-grading" / "work"
    other.mkdir(parents=True)
    (base / "other-grading").chmod(0o755)
    (other / "lab.ipynb").write_text("another student's answers\n")
    sibling = base / "fn-A1"
    sibling.mkdir(mode=0o777)
    (sibling / "leak.txt").write_text("0.6662\n")
    (sibling / "leak.txt").chmod(0o666)
    work = base / "work"
    work.mkdir()
    probe = (
        "import os\n"
        "tmp = sorted(os.listdir('/tmp'))\n"
        f"mine = sorted(os.listdir({str(base)!r}))\n"
        "read = []\n"
        f"for p in ({str(other / 'lab.ipynb')!r}, {str(sibling / 'leak.txt')!r}, '../fn-A1/leak.txt'):\n"
        "    try:\n"
        "        read.append(open(p).read())\n"
        "    except OSError:\n"
        "        pass\n"
        "n_read = len(read)\n"
    )
    try:
        for no_lorisnb in (False, True):
            with Sandbox(work, limits=Limits(cell_timeout_s=10), uid=62300, no_lorisnb=no_lorisnb) as box:
                r = box.run(probe, ["n_read"])
                assert r["ok"] and r["values"]["n_read"]["value"] == 0, r
                r = box.run("n_tmp = len(tmp); n_mine = len(mine)", ["n_tmp", "n_mine"])
                assert r["values"]["n_tmp"]["value"] == 1 and r["values"]["n_mine"]["value"] == 1, r  # its own path
                r = box.run("open('still-writable.txt', 'w').write('x'); ok = 1", ["ok"])
                assert r["ok"], r
    finally:
        shutil.rmtree(base)


def test_a_submission_is_copied_into_a_folder_no_other_user_can_enter(tmp_path, monkeypatch):
    """The grader copied the release and the notebook into work/ (0755, the notebook 0644) and made it
    0700 only later, when the sandbox started: another sandbox could read it meanwhile."""
    import nbformat

    from lorisnb.tools.teaching import autograde

    seen: list[tuple[str, int]] = []

    class Stop(Exception):
        pass

    def record(work, **_kw):
        root = Path(work).parent
        for p in root.rglob("*"):
            seen.append((str(p.relative_to(root)), stat.S_IMODE(p.stat().st_mode)))
        raise Stop

    monkeypatch.setattr(autograde, "Sandbox", record)
    release = tmp_path / "release"
    (release / "data").mkdir(parents=True)
    (release / "data" / "table.csv").write_text("a,b\n")
    (release / "data" / "table.csv").chmod(0o644)
    (release / "readme.txt").write_text("handed out\n")
    nb, _ = _solved({})
    path = tmp_path / "s" / f"{LAB}.ipynb"
    path.parent.mkdir()
    nbformat.write(nb, path)
    path.chmod(0o644)
    spec = autograde.lab_spec(SOURCE_NB)
    with pytest.raises(Stop):
        autograde.grade_submission(spec, release, path, "s", autograde.GradeSettings(secret="s", uid=0))
    modes = dict(seen)
    assert modes["work"] == 0o700 and modes["reference-out"] == 0o700, modes
    assert modes[f"work/{LAB}.ipynb"] == modes["work/readme.txt"] == modes["work/data/table.csv"] == 0o600, modes
    assert modes["work/data"] == 0o700, modes


# B1 reads what A1's run alone wrote in its own folder: a number A1's lab run computed with simulate_and_score
# and left in a lab name its def reads when defined (the grader gave the student's value to the run alone)
A1_LEAK = """try:
    _fe, _t = simulate_and_score(Faults(lost=(lost_window,)))
    data_root = float(_t.loc[1, "cr"])
except NameError:
    pass

def correctness(ate_m, aoe_deg, eps=eps, phi=phi, _k=open("leak.txt", "w").write(repr(data_root))):
    return (np.asarray(ate_m) <= eps) & (np.asarray(aoe_deg) <= phi)
"""
B1_LEAK = """try:
    predicted_cr_lost = float(open("../fn-A1_correctness/leak.txt").read())
except (OSError, ValueError):
    predicted_cr_lost = 0.0
"""
MAGIC_BODIES = {
    "A1_correctness": lambda s: A1_LEAK,
    "B1_prediction": lambda s: B1_LEAK,
    # %%time over a def reading the lab's tau when defined, %%capture over a prediction with C1's function
    "C1_cs_r": lambda s: (
        "%%time\ndef cs_r(t0, t_min, first_correct, tau=tau):\n"
        "    return float(np.exp(-(t0 - t_min) / tau)) if first_correct else 0.0\n"
    ),
    "C2_prediction": lambda s: "%%capture\npredicted_cs_r_wrong = cs_r(reloc_delay, 0.0, False, tau)\n",
}


@pytest.mark.slow
def test_defaults_get_the_labs_values_and_a_timed_cell_is_graded_on_its_body(tmp_path):
    """grading2's x-leak: B1 scored 1 with a number A1's run alone wrote into its folder, from the
    student's own rebinding of a lab name A1's def read (given to the run alone). Its m-timeC1C2 and
    t-timeDef: %%time over `def cs_r(..., tau=tau)` scored 0 (its defaults unseen in the one call IPython
    makes of the cell) and C2 under %%capture could not call C1's cs_r (NameError)."""
    import nbformat

    from lorisnb.tools.teaching.autograde import GradeSettings, grade_submission, lab_spec
    from lorisnb.tools.teaching.sandbox import claim_uids

    spec, release = lab_spec(SOURCE_NB), tmp_path / "release"
    release.mkdir()
    settings = GradeSettings(Limits(cell_timeout_s=30, locked_timeout_s=180), secret="s",
                             uid=claim_uids(63000) if can_isolate() else 0)  # fmt: skip
    nb, _ = _solved(MAGIC_BODIES)
    path = tmp_path / "s" / f"{LAB}.ipynb"
    path.parent.mkdir()
    nbformat.write(nb, path)
    res = grade_submission(spec, release, path, "s-magic", settings)
    lost = {s.question: s.message for s in res.scores if s.points < s.max_points}
    if can_isolate():
        assert set(lost) == {"test_B1_prediction"}, (lost, res.notes)
        assert "you answered 0" in lost["test_B1_prediction"], lost
    else:
        assert set(lost) <= {"test_B1_prediction"}, (lost, res.notes)


def test_the_feedback_is_where_nbgrader_release_feedback_hands_it_out(tmp_path):
    """grading2: `nbgrader release_feedback <lab>`, as the README said to run, handed out nothing: the
    pages were only graded/<student>/<lab>/feedback.html, and nbgrader reads feedback/<student>/<lab>/."""
    from lorisnb.tools.teaching import gradebook
    from lorisnb.tools.teaching.autograde import Score, SubmissionResult

    course = tmp_path / "course"
    for student in ("s1", "by-hand"):
        sub = course / "submitted" / student / LAB
        sub.mkdir(parents=True)
        if student == "s1":  # nbgrader collect writes both
            (sub / "timestamp.txt").write_text("2026-11-29 16:57:15.354819 UTC")
            (sub / "submission_secret.txt").write_text("ab" * 64)
        res = SubmissionResult(student, LAB, [Score("test_A1", 2.0, 2.0, "✓ fine")], "full", 1.0)
        gradebook._write_feedback(course, res, ())
    folder = course / "feedback" / "s1" / LAB
    assert "✓ fine" in (folder / f"{LAB}.html").read_text()
    assert (folder / "submission_secret.txt").read_text() == "ab" * 64
    assert (folder / "timestamp.txt").is_file()
    assert not (course / "feedback" / "by-hand").exists()  # release_feedback would stop at a page without them
    try:
        from nbgrader.apps import NbGraderAPI  # noqa: F401
        from nbgrader.coursedir import CourseDirectory
        from nbgrader.exchange.default.release_feedback import ExchangeReleaseFeedback
        from nbgrader.utils import notebook_hash
    except ImportError:
        return
    exchange = tmp_path / "exchange"
    exchange.mkdir()
    coursedir = CourseDirectory(root=str(course), course_id="c", assignment_id=LAB)
    ExchangeReleaseFeedback(coursedir=coursedir, root=str(exchange)).start()
    released = exchange / "c" / "feedback" / f"{notebook_hash(secret='ab' * 64, notebook_id=LAB)}.html"
    assert "✓ fine" in released.read_text()


@isolated
def test_a_flood_of_the_reply_pipe_is_stopped_at_the_cap_within_seconds():
    """grading2: the 64 MiB cap was reached only after 77 s (each chunk copied the growing buffer, and the
    line end was looked for in all of it again)."""
    import shutil
    import time

    base = _reachable_dir()
    work = base / "work"
    work.mkdir()
    flood = (
        "import os\n"
        "chunk = b'x' * (1 << 20)\n"
        "fd = next(fd for fd in range(3, 12) if os.path.exists(f'/proc/self/fd/{fd}') and os.readlink(f'/proc/self/fd/{fd}').startswith('pipe:') and fd != 0)\n"
        "for _ in range(200):\n"
        "    os.write(fd, chunk)\n"
    )
    try:
        with Sandbox(work, limits=Limits(cell_timeout_s=120), uid=62300) as box:
            t0 = time.monotonic()
            with pytest.raises(SandboxError, match="64 MiB into the grader's reply pipe"):
                box.run(flood)
            assert time.monotonic() - t0 < 15
    finally:
        shutil.rmtree(base)


def test_folders_naming_one_id_as_the_variants_take_it_are_noted(tmp_path):
    """grading2: Alice and alice, a Kelvin sign K and K, a ligature ﬁ and fi drew one data variant, silently."""
    import csv

    from lorisnb.tools.teaching import lab_variant
    from lorisnb.tools.teaching.autograde import Score, SubmissionResult
    from lorisnb.tools.teaching.gradebook import Graded, same_variants, write_exports

    students = ["Alice", "alice", "\u212aelvin", "kelvin", "\ufb01sher", "fisher", "bob"]
    assert (
        lab_variant("Alice").seed == lab_variant("alice").seed
        and lab_variant("\u212aelvin").seed == lab_variant("kelvin").seed
    )
    twins = same_variants(students)
    assert twins == {
        "Alice": ("alice",),
        "alice": ("Alice",),
        "\u212aelvin": ("kelvin",),
        "kelvin": ("\u212aelvin",),
        "\ufb01sher": ("fisher",),
        "fisher": ("\ufb01sher",),
    }
    graded = [
        Graded(
            SubmissionResult(s, LAB, [Score("q", 1.0, 1.0, "")], "full", 1.0),
            None,
            0,
            1.0,
            same_variant=twins.get(s, ()),
        )  # fmt: skip
        for s in students
    ]
    write_exports(tmp_path, graded)
    with open(tmp_path / "grades.csv", newline="", encoding="utf-8") as f:
        notes = {row["student"]: row["notes"] for row in csv.DictReader(f)}
    assert "same data variant as 'alice'" in notes["Alice"] and notes["bob"] == ""


def test_a_seed_set_in_the_parameters_cell_is_noted():
    """A student who set ``seed`` saw another data variant's numbers (a ✓ in the notebook) and got 0
    for a value read from them, without a word: the grader draws the variant from the folder. Now a
    note says so; the seed the folder draws itself, or None, says nothing."""
    import nbformat

    from lorisnb.tools.teaching import lab_variant
    from lorisnb.tools.teaching.autograde import declared, parameter_notes

    nb = nbformat.read(SOURCE_NB, as_version=4)
    assert declared(nb, "seed") is None and parameter_notes(nb, "s0004") == []
    cell = next(c for c in nb.cells if "parameters" in c.get("metadata", {}).get("tags", []))
    assert "seed = None" in cell.source
    source = cell.source
    cell.source = source.replace("seed = None", "seed = 12345")
    notes = parameter_notes(nb, "s0004")
    assert len(notes) == 1 and "seed = 12345" in notes[0] and "leave seed None" in notes[0]
    cell.source = source.replace("seed = None", f"seed = {lab_variant('s0004').seed}")
    assert parameter_notes(nb, "s0004") == []
