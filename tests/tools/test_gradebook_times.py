"""The submission times of the gradebook (``gradebook.submission_time``, ``grade_class``): nbgrader's
``timestamp.txt`` in any zone it writes, a time that cannot be read flags one student (the others
are graded and exported), and a submission without a time under a late policy is said, not silent.

Also :func:`tiny_course`, a small lab graded in seconds by the real grader (the copy check of
``test_teaching_sandbox.py`` uses it)."""

from __future__ import annotations

import csv
import importlib.util
import shutil
from datetime import datetime, timedelta, timezone
from pathlib import Path

import nbformat
import pytest
from nbformat.v4 import new_code_cell, new_notebook

from lorisnb.errors import ValidationError
from lorisnb.tools.teaching import gradebook

ROOT = Path(__file__).resolve().parents[2]
# as test_teaching_sandbox.py: sandboxes of one uid run one at a time (make test* use --dist loadgroup)
pytestmark = pytest.mark.xdist_group("grading")

TINY = "tiny_lab"
#: answer grade_id -> (the line the stub keeps, the solution, its check)
TINY_ANSWERS = {
    "Q1_total": ("total = ...", "total = sum(k * k for k in range(10)) + len('lifelong')", "assert total == 293"),
    "Q2_mean": ("mean = ...", "values = [2.0, 4.0, 9.0]\nmean = sum(values) / len(values)", "assert mean == 5.0"),
    "Q3_word": ("word = ...", "word = ''.join(sorted(set('openloris scene'))).strip()", "assert word == 'ceilnoprs'"),
    "Q4_flag": ("flag = ...", "flag = True", "assert flag is True"),
    "Q5_count": ("count = ...", "count = 3", "assert count == 3"),
}
STUB = "# YOUR CODE HERE\nraise NotImplementedError()"  # teaching/nbgrader_config.py's code stub


def _lab(solutions: bool) -> nbformat.NotebookNode:
    """The tiny lab as nbgrader lays it out: the instructor's (``solutions``) or the release."""
    params = new_code_cell("student_id = None  # as the lab hands it out: the grader passes the folder's")
    params.metadata["tags"] = ["parameters"]
    cells = [params]
    for gid, (keep, solution, check) in TINY_ANSWERS.items():
        body = f"### BEGIN SOLUTION\n{solution}\n### END SOLUTION" if solutions else STUB
        answer = new_code_cell(f"{keep}\n{body}")
        answer.metadata["nbgrader"] = {"schema_version": 3, "grade_id": gid, "solution": True, "grade": False,
                                       "locked": False}  # fmt: skip
        test = new_code_cell(check)
        test.metadata["nbgrader"] = {"schema_version": 3, "grade_id": f"test_{gid}", "solution": False,
                                     "grade": True, "locked": True, "points": 1}  # fmt: skip
        cells += [answer, test]
    return new_notebook(cells=cells)


def tiny_course(tmp_path: Path) -> tuple[Path, Path]:
    """(course, source) of the tiny lab: ``source/<lab>/<lab>.ipynb`` with solutions,
    ``course/release/<lab>/<lab>.ipynb`` with nbgrader's stubs, no submission yet."""
    course, source = tmp_path / "course", tmp_path / "source"
    (source / TINY).mkdir(parents=True)
    nbformat.write(_lab(True), source / TINY / f"{TINY}.ipynb")
    (course / "release" / TINY).mkdir(parents=True)
    nbformat.write(_lab(False), course / "release" / TINY / f"{TINY}.ipynb")
    return course, source


def submit(course: Path, student: str, answers: dict[str, str] | None = None, stamp: str | None = None) -> Path:
    """``student``'s notebook: the release with ``answers`` (grade_id -> the cell; default: every
    solution below the stub's first line, with a comment of the student's own) in its answer
    cells, and ``timestamp.txt`` if ``stamp``."""
    if answers is None:
        answers = {
            gid: f"{keep}\n# {student} worked this out\n{solution}\nchecked_{gid.lower()} = True"
            for gid, (keep, solution, _) in TINY_ANSWERS.items()
        }
    nb = nbformat.read(course / "release" / TINY / f"{TINY}.ipynb", as_version=4)
    for cell in nb.cells:
        gid = cell.get("metadata", {}).get("nbgrader", {}).get("grade_id")
        if gid in answers and cell.metadata["nbgrader"].get("solution"):
            cell.source = answers[gid]
    folder = course / "submitted" / student / TINY
    folder.mkdir(parents=True)
    nbformat.write(nb, folder / f"{TINY}.ipynb")
    if stamp is not None:
        (folder / "timestamp.txt").write_text(stamp + "\n")
    return folder


def grade_script():  # noqa: ANN201 (teaching/grade.py, as `make grade` runs it)
    spec = importlib.util.spec_from_file_location("teaching_grade", ROOT / "teaching" / "grade.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# --- nbgrader's timestamps --------------------------------------------------------------------------

INSTANT = datetime(2026, 12, 1, 22, 10, 0, 123456, tzinfo=timezone.utc)
SUMMER = datetime(2026, 7, 1, 21, 10, 0, 123456, tzinfo=timezone.utc)


def _nbgrader_stamp(instant: datetime, zone: str, fmt: str = "%Y-%m-%d %H:%M:%S.%f %Z") -> str:
    """What nbgrader writes (``Exchange.set_timestamp``): ``datetime.now(gettz(Exchange.timezone))``
    formatted with ``Exchange.timestamp_format`` (default ``%Y-%m-%d %H:%M:%S.%f %Z``)."""
    from dateutil.tz import gettz

    return instant.astimezone(gettz(zone)).strftime(fmt)


@pytest.mark.parametrize(
    ("instant", "zone", "fmt", "written"),
    [
        (INSTANT, "Europe/Berlin", None, "2026-12-01 23:10:00.123456 CET"),
        (SUMMER, "Europe/Berlin", None, "2026-07-01 23:10:00.123456 CEST"),
        (INSTANT, "UTC", None, "2026-12-01 22:10:00.123456 UTC"),
        (SUMMER, "America/Los_Angeles", None, "2026-07-01 14:10:00.123456 PDT"),
        (INSTANT, "Asia/Kolkata", None, "2026-12-02 03:40:00.123456 IST"),  # IST is also Israel's: +0200
        (INSTANT, "Asia/Dubai", None, "2026-12-02 02:10:00.123456 +04"),  # the tz database's numeric names
        (INSTANT, "Europe/Berlin", "%Y-%m-%d %H:%M:%S.%f %z", "2026-12-01 23:10:00.123456 +0100"),
        (INSTANT, "America/St_Johns", "%Y-%m-%d %H:%M:%S.%f %z", "2026-12-01 18:40:00.123456 -0330"),
        (INSTANT, "Europe/Berlin", "%Y-%m-%dT%H:%M:%S.%f%z", "2026-12-01T23:10:00.123456+0100"),
    ],
)
def test_nbgrader_timestamps_in_any_zone_are_read_as_the_instant_they_name(tmp_path, instant, zone, fmt, written):
    """A timestamp.txt in a non-UTC zone stopped grading ("'... CET' is not a time"); nbgrader's own
    parse_utc reads +0100 as 100 seconds and CEST, PDT (no tz file of that name) as UTC."""
    stamp = _nbgrader_stamp(instant, zone, *([fmt] if fmt else []))
    if zone == "Asia/Kolkata":  # IST: +0530 in Kolkata, +0200 in Jerusalem: the due date's offset tells
        assert stamp == written and gradebook.parse_time(stamp, timedelta(hours=5, minutes=30)) == instant
        return
    assert stamp == written
    (tmp_path / "timestamp.txt").write_text(stamp + "\n")
    assert gradebook.submission_time(tmp_path) == instant


@pytest.mark.parametrize(
    ("written", "meant"),
    [
        ("2026-12-01 23:10:00.123456 Europe/Berlin", INSTANT),
        ("2026-12-01 23:10:00.123456 UTC+01:00", INSTANT),  # Python's %Z of a zone that is only an offset
        ("2026-12-01 23:10:00.123456 +01:00", INSTANT),
        ("2026-12-01 22:10:00.123456", INSTANT),  # no zone: UTC, as nbgrader reads it
        ("2026-12-01T22:10:00.123456Z", INSTANT),
        ("Tue Dec  1 23:10:00.123456 CET 2026", INSTANT),  # another layout nbgrader's dateutil reads
    ],
)
def test_other_layouts_nbgrader_reads_are_read(tmp_path, written, meant):
    (tmp_path / "timestamp.txt").write_text(written)
    assert gradebook.submission_time(tmp_path) == meant


@pytest.mark.parametrize(
    ("written", "why"),
    [
        ("2026-12-01 23:10:00.123456 CST", "abbreviation means different offsets"),  # Chicago, Havana, Shanghai
        ("2026-12-01 23:10:00.123456 CEST", "no zone of the tz database"),  # a summer zone in December: none then
        ("2026-12-01 23:10:00.123456 XYZ", "no zone of the tz database"),
        ("1st of December, late evening", "not a date and time"),
        ("Dec 1 23:10 CET", "missing"),  # no year: not today's
        ("2026-12-01 23:10:00 +2500", "out of range"),
    ],
)
def test_a_time_that_cannot_be_read_is_refused_naming_the_file_and_what_was_expected(tmp_path, written, why):
    (tmp_path / "timestamp.txt").write_text(written)
    with pytest.raises(ValidationError, match=why) as err:
        gradebook.submission_time(tmp_path)
    assert str(tmp_path / "timestamp.txt") in str(err.value) and "expected a time as nbgrader writes it" in str(
        err.value
    )
    # what the file holds is never quoted (it is a student's: the feedback, grades.csv and the terminal show it)
    assert written not in str(err.value) and written.split()[-1] not in str(err.value).split(), err.value


def test_an_abbreviation_of_several_offsets_takes_the_due_dates_and_no_file_is_no_time(tmp_path):
    chicago = datetime(2026, 12, 2, 5, 10, tzinfo=timezone.utc)
    assert (
        gradebook.parse_time("2026-12-01 23:10:00 CST", timedelta(hours=-6)) == chicago
    )  # --due 2026-12-01T23:59-06:00
    assert gradebook.parse_time("2026-12-01 23:10:00 CST", timedelta(hours=8)) == chicago - timedelta(hours=14)
    with pytest.raises(ValueError, match="different offsets"):
        gradebook.parse_time("2026-12-01 23:10:00 CST", timedelta(hours=1))
    assert gradebook.submission_time(tmp_path) is None


# --- a class with such times -----------------------------------------------------------------------


@pytest.mark.thorough
def test_a_time_in_another_zone_or_unreadable_flags_that_student_and_grades_the_class(tmp_path, capsys):
    """One timestamp.txt in CET stopped `make grade` after grading everyone (exit 1, grades.csv not
    written, no exports), even without --due. Now every zone nbgrader writes is read; a time that
    cannot be read is that student's note (file, what was expected), the others graded and exported,
    with --due too (counted as on time, as a submission without a time); fixed, the note goes."""
    grade = grade_script()
    course, source = tiny_course(tmp_path)
    submit(course, "s-berlin", stamp="2026-12-01 23:10:00.123456 CET")  # on time
    submit(course, "s-offset", stamp="2026-12-01 23:30:00.000000 +0100")  # on time (read as +100 s: late)
    submit(course, "s-late", stamp="2026-12-02 10:00:00.000000 CET")  # a day late
    submit(course, "s-garbled", stamp="1st of December, late evening")
    submit(course, "s-none")  # put in submitted/ by hand: no timestamp.txt
    args = [str(course), "--source", str(source), "--timeout", "30", "--no-progress"]

    rc = grade.main(args)  # no late policy
    out, err = capsys.readouterr()
    assert rc == 0, err
    rows = {r["student"]: r for r in csv.DictReader((course / "grades.csv").open(encoding="utf-8"))}
    assert set(rows) == {"s-berlin", "s-offset", "s-late", "s-garbled", "s-none"}
    assert all(r["raw_score"] == r["score"] == "5" for r in rows.values()), rows
    assert rows["s-berlin"]["submitted"] == "2026-12-01T23:10:00.123456+01:00"
    assert (
        rows["s-garbled"]["submitted"] == ""
        and "submitted/s-garbled/tiny_lab/timestamp.txt" in rows["s-garbled"]["notes"]
    )
    assert "expected a time as nbgrader writes it" in rows["s-garbled"]["notes"]
    assert not any("timestamp" in rows[s]["notes"] for s in ("s-none", "s-berlin"))  # no late policy: nothing to apply
    assert "warning: s-garbled:" in err and "timestamp.txt" in err and "no timestamp.txt" not in err
    assert (course / "exports" / f"{TINY}-canvas.csv").is_file()
    feedback = (course / "graded" / "s-garbled" / TINY / "feedback.html").read_text()
    assert "timestamp.txt" in feedback and "expected a time" in feedback

    rc = grade.main([*args, "--due", "2026-12-01T23:59+01:00", "--late-per-day", "0.1"])
    out, err = capsys.readouterr()
    assert rc == 0, err
    rows = {r["student"]: r for r in csv.DictReader((course / "grades.csv").open(encoding="utf-8"))}
    days = {s: (r["days_late"], r["late_factor"], r["score"]) for s, r in rows.items()}
    assert days == {"s-berlin": ("0", "1", "5"), "s-offset": ("0", "1", "5"), "s-late": ("1", "0.9", "4.5"),
                    "s-garbled": ("0", "1", "5"), "s-none": ("0", "1", "5")}  # fmt: skip
    for student in ("s-none", "s-garbled"):  # counted as on time, as documented, and said
        assert (
            "late policy (due 2026-12-01T23:59:00+01:00) could not be applied: counted as on time"
            in rows[student]["notes"]
        )
        page = (course / "graded" / student / TINY / "feedback.html").read_text()
        assert "could not be applied" in page
    assert "no submitted/s-none/tiny_lab/timestamp.txt" in rows["s-none"]["notes"]
    assert not any("timestamp" in rows[s]["notes"] for s in ("s-berlin", "s-offset", "s-late"))
    assert "1 submission(s) have no timestamp.txt, so --due could not be applied" in err and "(s-none;" in err
    assert "warning: s-garbled:" in err

    (course / "submitted" / "s-garbled" / TINY / "timestamp.txt").write_text("2026-12-01 23:00:00.000000 CET\n")
    shutil.rmtree(course / "exports")
    assert grade.main(args) == 0  # fixed: the note goes, from the feedback too
    err = capsys.readouterr().err
    said = [line for line in err.splitlines() if "warning" in line and not line.startswith("warning: --timeout")]
    assert not [line for line in said if "warning: not root" not in line], err  # (isolation's warning off root)
    assert "timestamp" not in (course / "graded" / "s-garbled" / TINY / "feedback.html").read_text()
    assert (course / "exports" / f"{TINY}-canvas.csv").is_file()


@pytest.mark.thorough
def test_with_a_due_date_a_submission_without_a_time_is_counted_on_time_and_said(tmp_path, capsys):
    """With --due, a submission without timestamp.txt silently counted as on time (days_late 0,
    late_factor 1, no note), though LatePolicy says it "is named in the notes": it still counts as
    on time (the documented rule), and its note, its feedback and the command line say so."""
    grade = grade_script()
    course, source = tiny_course(tmp_path)
    submit(course, "s-late", stamp="2026-12-02 10:00:00.000000 UTC")
    submit(course, "s-none")
    submit(course, "s-ontime", stamp="2026-12-01 20:00:00.000000 UTC")
    rc = grade.main([str(course), "--source", str(source), "--timeout", "30", "--no-progress",
                     "--due", "2026-12-01T23:59+00:00", "--late-per-day", "0.25"])  # fmt: skip
    out, err = capsys.readouterr()
    assert rc == 0, err
    rows = {r["student"]: r for r in csv.DictReader((course / "grades.csv").open(encoding="utf-8"))}
    assert {s: (r["days_late"], r["late_factor"], r["score"]) for s, r in rows.items()} == {
        "s-late": ("1", "0.75", "3.75"), "s-none": ("0", "1", "5"), "s-ontime": ("0", "1", "5")}  # fmt: skip
    note = rows["s-none"]["notes"]
    assert note.startswith("no submitted/s-none/tiny_lab/timestamp.txt") and "time is unknown" in note, note
    assert "late policy (due 2026-12-01T23:59:00+00:00) could not be applied: counted as on time" in note
    assert "could not be applied" in (course / "graded" / "s-none" / TINY / "feedback.html").read_text()
    assert rows["s-late"]["notes"] == rows["s-ontime"]["notes"] == ""
    assert "warning: 1 submission(s) have no timestamp.txt, so --due could not be applied to them" in err, err


def test_grades_csv_notes_hold_the_graders_own_notes(tmp_path):
    """The grader's notes of a submission (a sandbox ended on purpose, a cell id carried twice, an
    output cut) reached only its feedback.html; grades.csv's notes column, the instructor's view,
    now holds them before the gradebook's own."""
    import csv

    from lorisnb.tools.teaching.autograde import Score, SubmissionResult
    from lorisnb.tools.teaching.gradebook import Graded, _write_grades

    result = SubmissionResult("s1", "lab", [Score("q1", 1.0, 2.0, "")], "limits only", 1.0,
                              notes=["Q2_mean: NotImplementedError: ", "G1_difficulty: the sandbox ended (os._exit)"])  # fmt: skip
    graded = Graded(result, None, 0, 1.0, notes=["no timestamp.txt"])
    _write_grades(tmp_path / "grades.csv", [graded], {})
    with open(tmp_path / "grades.csv", newline="", encoding="utf-8") as f:
        row = next(csv.DictReader(f))
    assert (
        row["notes"] == "G1_difficulty: the sandbox ended (os._exit) | no timestamp.txt"
    )  # an unanswered stub's left out
