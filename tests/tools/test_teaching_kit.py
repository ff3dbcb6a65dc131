"""The teaching kit (teaching/): the labs' sources are nbgrader-ready and stored clean; `make student`
releases them without a trace of a solution, `make grade` grades the submissions (the
solutions score full marks with the hidden tests; the typical mistakes get their hints in the
feedback), and `make book` builds the offline book with no script from the network. The make test
runs on a copy of the checkout's files (as a fresh clone would have them), outside the checkout."""

from __future__ import annotations

import csv
import importlib.util
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from datetime import date
from pathlib import Path

import nbformat
import pytest
from test_teaching_lab import solution_expressions, solution_leaks

ROOT = Path(__file__).resolve().parents[2]
SOURCE = ROOT / "teaching" / "source"
LABS = sorted(p.name for p in SOURCE.iterdir() if p.is_dir())
LAB1 = "lab1_lifelong_metrics"


def _teaching_module(name: str):
    """A script of teaching/ (they import each other, so teaching/ goes on sys.path)."""
    if str(ROOT / "teaching") not in sys.path:
        sys.path.insert(0, str(ROOT / "teaching"))
    spec = importlib.util.spec_from_file_location(f"teaching_{name}", ROOT / "teaching" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _nbgrader(cell) -> dict:
    return cell.get("metadata", {}).get("nbgrader", {})


@pytest.mark.parametrize("lab", LABS)
def test_lab_sources_are_clean_and_nbgrader_ready(lab):
    nb = nbformat.read(SOURCE / lab / f"{lab}.ipynb", as_version=4)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert all(not c.outputs and c.execution_count is None for c in code)
    assert sum("parameters" in c.metadata.get("tags", []) for c in code) == 1
    ids = [_nbgrader(c)["grade_id"] for c in nb.cells if _nbgrader(c)]
    assert len(ids) == len(set(ids)), "grade ids are unique"
    answers = [c for c in code if _nbgrader(c).get("solution")]
    tests = [c for c in code if _nbgrader(c).get("grade")]
    assert len(answers) >= 8 and len(tests) >= 8
    for c in answers:
        assert "### BEGIN SOLUTION" in c.source and "### END SOLUTION" in c.source, _nbgrader(c)["grade_id"]
        # a student may rewrite the whole answer cell: it defines nothing the later cells need
        outside = re.sub(r"### BEGIN SOLUTION.*?### END SOLUTION", "", c.source, flags=re.S)
        for line in outside.splitlines():
            assert " = " not in line or line.rstrip().endswith("= ..."), f"{_nbgrader(c)['grade_id']}: {line}"
    for c in tests:
        assert _nbgrader(c)["points"] > 0 and "teach.check_" in c.source, _nbgrader(c)["grade_id"]
    # the write-it-yourself exercises have hidden tests on real sequences
    hidden = [c for c in tests if "### BEGIN HIDDEN TESTS" in c.source]
    assert {"test_A1_correctness", "test_B2_correct_rate", "test_C1_cs_r"} <= {_nbgrader(c)["grade_id"] for c in hidden}
    # the equations are typeset with the paper's numbers
    text = "\n".join(c.source for c in nb.cells if c.cell_type == "markdown")
    for k in (1, 2, 3, 4):
        assert f"\\tag{{{k}}}" in text


def test_book_notebook_has_exercises_and_dropdown_solutions_without_hidden_tests():
    book = _teaching_module("book")
    nb = book.book_notebook(SOURCE / LABS[0] / f"{LABS[0]}.ipynb")
    text = "\n".join(c.source for c in nb.cells)
    n_answers = sum(
        1
        for c in nbformat.read(SOURCE / LABS[0] / f"{LABS[0]}.ipynb", as_version=4).cells
        if _nbgrader(c).get("solution")
    )
    assert text.count("{exercise-start}") == text.count("{exercise-end}") == n_answers
    assert text.count("{solution-start}") == text.count("{solution-end}") == n_answers
    assert ":class: dropdown" in text
    assert "HIDDEN TESTS" not in text and "BEGIN SOLUTION" not in text and "_fe = simulated_errors" not in text
    assert not any(_nbgrader(c) for c in nb.cells)
    # the gated blocks follow each other, never nested: exercise (its question inside), then its solution
    gates = re.findall(r"\{(exercise|solution)-(start|end)\}", text)
    assert gates == [("exercise", "start"), ("exercise", "end"), ("solution", "start"), ("solution", "end")] * n_answers
    for k, c in enumerate(nb.cells):
        if "{exercise-start}" in c.source:
            question = nb.cells[k + 1]
            assert (
                "**Exercise" in question.source
                or "**Question" in question.source
                or ("question" in question.metadata.get("tags", []))
            ), question.source
    # no exercise block opens before a section heading and closes after it
    for c in nb.cells:
        if c.cell_type == "markdown" and c.source.startswith("**"):
            assert not re.search(r"^#+ ", c.source, re.M)


def _run_part_f(answer: str) -> str:
    """Part F of lab 1 as the grader runs it, on the sample data: the parameters, the timeline's cell
    (its figure not drawn), ``answer`` as the answer cell, then the test cell; what the checks print."""
    import contextlib
    import io
    from types import SimpleNamespace

    import lorisnb as ln
    from lorisnb.tools import teaching as teach

    cells = {
        _nbgrader(c).get("grade_id"): c for c in nbformat.read(SOURCE / LAB1 / f"{LAB1}.ipynb", as_version=4).cells
    }
    params = next(c.source for c in cells.values() if "parameters" in c.metadata.get("tags", []))
    out = SimpleNamespace(figure=lambda *a, **k: None)
    scope = {"ln": ln, "teach": teach, "out": out, "plot_timeline": lambda *a, **k: None}
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        exec(params, scope)  # noqa: S102 (the lab's own cells)
        scope["data"] = teach.lab_data(scope["data_root"])
        scope["timeline_eps"] = 1.0  # one variant's (tests/tools/test_teaching_variants.py runs each)
        for source in (cells["locked_cell_38"].source, answer, cells["test_F_timeline"].source):
            exec(source, scope)  # noqa: S102
    return buf.getvalue()


def test_part_f_demo_mistake_cr_t_for_cr_fails_with_its_hint():
    """F2's CR-T-for-CR confusion fails on the lab's own data with its hint (on cafe the best
    algorithm by CR is also the best by CR-T: the name alone passed by luck, so F2 asks its CR too);
    the instructor's solution passes."""
    from lorisnb.errors import AnswerError

    demo = _teaching_module("demo_submissions")
    solution = demo.solutions(SOURCE / LAB1 / f"{LAB1}.ipynb")["F_timeline"]
    printed = _run_part_f(solution)
    assert "✓ algorithm with the highest scene CR" in printed and "✓ CR of vins_mono_color_imu_with_loop" in printed
    with pytest.raises(AnswerError, match=r"you answered 0\.89.*\nHint \(cr vs crt\)") as exc:
        _run_part_f(demo.MISTAKES["F_timeline"])
    assert "you answered 0.89, too high" in str(exc.value) and "0.837" not in str(exc.value)  # CR not given


def _copy_checkout(dest: Path) -> None:
    """The checkout's files as a fresh clone has them (tracked and new, not ignored)."""
    files = subprocess.run(
        ["git", "ls-files", "-co", "--exclude-standard"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.splitlines()
    for f in files:
        if (ROOT / f).is_file():
            (dest / f).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / f, dest / f)


def _tree(folder: Path) -> list[str]:
    """Every path under ``folder``, not following links (the copy's .venv links to the checkout's),
    but Python's bytecode caches (``__pycache__``: git ignores them; written or not as the
    environment's PYTHONDONTWRITEBYTECODE says)."""
    return sorted(
        os.path.relpath(os.path.join(d, n), folder)
        for d, dirs, files in os.walk(folder)
        for n in dirs + files
        if "__pycache__" not in Path(d, n).relative_to(folder).parts
    )


@pytest.fixture
def open_tmp_path():
    """A temporary folder other users may enter (pytest's tmp_path is closed to them), removed after."""
    d = Path(tempfile.mkdtemp(prefix="lorisnb-kit-", dir="/tmp" if os.name == "posix" else None))
    d.chmod(0o755)
    yield d
    shutil.rmtree(d, ignore_errors=True)


@pytest.mark.slow
@pytest.mark.xdist_group("grading")  # one grader at a time (tests/tools/test_teaching_sandbox.py)
def test_make_student_grade_book_and_slides_on_a_fresh_copy(open_tmp_path, teaching_python):
    """As a fresh clone runs them: the Makefile's own (relative) VENV and TEACH, here links to the
    checkout's environments (a clone creates them: ``teaching_python``), and the course and builds
    given as relative paths. The clone lies where others may enter (the sandbox's own user imports
    its lorisnb; pytest's tmp_path is closed to other users)."""
    tmp_path = open_tmp_path
    copy = tmp_path / "lorisnb"
    _copy_checkout(copy)
    for env_dir in (".venv", ".venv-teach"):
        (copy / env_dir).symlink_to(ROOT / env_dir, target_is_directory=True)
    before = _tree(copy)
    env = {k: v for k, v in os.environ.items() if k not in ("LORISNB_DATA", "PYTHONPATH", "VIRTUAL_ENV")}
    env["TMPDIR"] = str(tmp_path / "tmp")  # where the notebooks' temporary folders would be left
    (tmp_path / "tmp").mkdir()
    course, out = tmp_path / "course", tmp_path / "site"  # an instructor's folders, outside the checkout
    args = ["-o", ".venv/.installed-stamp", "-o", ".venv-teach/.installed-stamp", "COURSE=../course",
            "BOOK_OUT=../site/book", "SLIDES_OUT=../site/slides"]  # fmt: skip
    r = subprocess.run(
        ["make", "-C", str(copy), *args, "student", "grade", "book", "slides"],
        env=env,
        capture_output=True,
        text=True,
        timeout=1800,
    )
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    assert "not found" not in r.stderr, r.stderr[-3000:]  # e.g. "/bin/sh: .venv/bin/python: not found"
    # nothing written into the checkout: the course and the builds are where the instructor said
    assert _tree(copy) == before
    assert not list((tmp_path / "tmp").glob("lorisnb-*")), "the builds leave no temporary folder behind"
    teaching = course
    offline = _teaching_module("offline")
    for lab in LABS:
        # student version: every answer cell is a stub, no solution (in any spelling) and no hidden test left
        source = nbformat.read(SOURCE / lab / f"{lab}.ipynb", as_version=4)
        release = nbformat.read(teaching / "release" / lab / f"{lab}.ipynb", as_version=4)
        text = "\n".join(c.source for c in release.cells)
        assert "BEGIN SOLUTION" not in text and "HIDDEN TESTS" not in text
        assert solution_leaks(release, solution_expressions(source)) == []
        for c in source.cells:
            m = re.search(r"### BEGIN SOLUTION\n(.*?)### END SOLUTION", c.source, re.S)
            if m:
                for line in m.group(1).strip().splitlines():
                    if len(line.strip()) >= 12 and not line.strip().startswith("#"):
                        assert line.strip() not in text, f"solution line left in the student version: {line}"
        stubs = sum(c.source.count("raise NotImplementedError()") for c in release.cells if c.cell_type == "code")
        assert stubs == sum(1 for c in source.cells if _nbgrader(c).get("solution"))
        # grades (the sandboxed grader): the instructor's solutions score full marks (hidden tests included);
        # the mistakes do not, and their feedback names the hints; the demo students are kept apart
        demo = {r["student"]: r for r in csv.DictReader((teaching / "grades-demo.csv").open()) if r["lab"] == lab}
        assert float(demo["demo-correct"]["score"]) == float(demo["demo-correct"]["max_score"]) >= 15
        assert 0 < float(demo["demo-mistakes"]["score"]) < float(demo["demo-mistakes"]["max_score"])
        assert not list(csv.DictReader((teaching / "grades.csv").open()))
        feedback = (teaching / "graded" / "demo-mistakes" / lab / "feedback.html").read_text()
        hints = set(re.findall(r"Hint \(([a-z ]+)\)", re.sub(r"<[^>]+>", "", feedback)))
        assert {"delta cap", "cr vs crt", "degrees radians", "first pose", "alignment", "phi ignored"} <= hints, hints
        if lab == LAB1:  # F2's CR-T for CR gets its own hint, not only B2's formula
            scores = json.loads((teaching / "graded" / "demo-mistakes" / lab / "result.json").read_text())["scores"]
            f = next(s for s in scores if s["question"] == "test_F_timeline")
            assert f["points"] == 0 and "Hint (cr vs crt)" in f["message"], f
        assert (teaching / "graded" / "demo-correct" / lab / "feedback.html").exists()
    assert offline.remote_references(offline.built_files(teaching / "graded")) == []
    # the book: every page, exercises with dropdown solutions, executed checks, local MathJax only
    slides = out / "slides"
    out = out / "book"
    assert (out / "index.html").exists() and (out / "metrics_primer.html").exists()
    page = (out / f"{LABS[0]}.html").read_text()
    assert "exercise" in page and "dropdown" in page and "✓ correct_rate matches lorisnb" in page
    assert "_static/mathjax/tex-chtml.js" in page and (out / "_static" / "mathjax" / "tex-chtml.js").is_file()
    assert "THEBE_JS_URL" not in page and re.search(r"instructor\S{1,8}s copy", (out / "intro.html").read_text())
    assert offline.remote_references(offline.built_files(out)) == []
    assert list((out / "_images").glob("*.png")), "figures of the executed notebooks"
    # the slides: one per notebook, reveal.js and MathJax beside them, nothing from the network (fonts included)
    assert "F1 and F2" in page  # the exercises are titled as in the lab (F's is two questions), not numbered 1-10
    assert "\\tag{1}" in page and "\\cr" in page  # Eq. (1) with no \\ row break: Sphinx does not wrap it in split
    assert re.search(r"&#169; Copyright \d{4}|© Copyright \d{4}", page) and str(date.today().year) in page
    for lab in LABS:  # the deck to project during the lab: no solution, no check's answer
        html = (slides / f"{lab}.projector.slides.html").read_text()
        assert "YOUR CODE HERE" in html and "eps_at_cr(ev_orb.errors" not in html
        assert "computed by lorisnb:" not in html and "matches lorisnb on" not in html and "<img" in html
    for name in ("metrics_primer", *LABS):
        html = (slides / f"{name}.slides.html").read_text()
        assert 'src="reveal.js/dist/reveal.js"' in html and 'src="mathjax/tex-chtml.js"' in html
        assert "reveal.js/dist/theme/white.css" in html and "<section" in html
    assert (slides / "reveal.js" / "dist" / "reveal.js").is_file() and (slides / "mathjax" / "tex-chtml.js").is_file()
    assert offline.remote_references(offline.built_files(slides)) == []


@pytest.mark.slow
@pytest.mark.xdist_group("grading")  # one grader at a time (tests/tools/test_teaching_sandbox.py)
def test_what_make_grade_writes_in_a_clone_is_ignored_by_git(open_tmp_path, teaching_python):
    """`make student grade` in a clone (the default course folder, teaching/) writes the course's
    secret, the students' grades, feedback and exports: git ignores every one (they showed as
    untracked, so `git add -A` would have committed the secret and the grades)."""
    copy = open_tmp_path / "lorisnb"
    _copy_checkout(copy)
    git = ["git", "-C", str(copy), "-c", "user.name=kit", "-c", "user.email=kit@example.org"]
    for cmd in (["init", "-q"], ["add", "-A"], ["commit", "-qm", "a clone"]):
        subprocess.run([*git, *cmd], check=True, capture_output=True)
    for env_dir in (".venv", ".venv-teach"):  # links to the checkout's environments (not the clone's files)
        (copy / env_dir).symlink_to(ROOT / env_dir, target_is_directory=True)
    before = set(_tree(copy))
    env = {k: v for k, v in os.environ.items() if k not in ("LORISNB_DATA", "PYTHONPATH", "VIRTUAL_ENV")}
    r = subprocess.run(
        ["make", "-C", str(copy), "-o", ".venv/.installed-stamp", "-o", ".venv-teach/.installed-stamp",
         "student", "grade"],
        env=env, capture_output=True, text=True, timeout=1800,
    )  # fmt: skip
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    written = sorted(p for p in set(_tree(copy)) - before if not p.startswith(".git/"))  # files and folders
    made = {".grading-secret", "grades.csv", "grades-demo.csv", "gradebook.db", "graded/demo-correct", "exports",
            "release", "submitted/demo-correct"}  # fmt: skip
    assert {f"teaching/{p}" for p in made} <= set(written), written
    ignored = subprocess.run([*git, "check-ignore", "--stdin"], input="\n".join(written), capture_output=True,
                             text=True).stdout.splitlines()  # fmt: skip
    assert sorted(set(written) - set(ignored)) == []
    status = subprocess.run([*git, "status", "--porcelain", "--untracked-files=all"], capture_output=True,
                            text=True, check=True).stdout.splitlines()  # fmt: skip
    assert [line for line in status if line[3:] not in (".venv", ".venv-teach")] == []


def test_sample_data_is_small_and_a_verbatim_subset_of_the_data(data):
    """The teaching data shipped in the package: every file under 512 KiB, about 1.8 MB in all,
    each a byte-for-byte copy of the file of the same path in the full data (teaching/make_sample_data.py)."""
    from lorisnb.io.datasets.paths import sample_data

    root = sample_data().root
    files = [p for p in root.rglob("*") if p.is_file() and p != root / "README.md"]  # that one is the sample's own
    assert 20 <= len(files) and all(p.stat().st_size < 512 * 1024 for p in files)
    assert 1.0e6 < sum(p.stat().st_size for p in files) < 2.0e6
    for p in files:
        assert p.read_bytes() == (data.root / p.relative_to(root)).read_bytes(), p
    assert sample_data().scenes_with_groundtruth() == ["cafe"]
