"""The files of a submission as the grader reads them (the adversarial pass grading4): the grader
often runs as root, so a notebook or ``timestamp.txt`` that is a symbolic link (to the instructor's
source notebook, the course's ``.grading-secret``, ``/etc/shadow``), or that sits in a linked folder,
is refused, never followed; what a submission's file holds is never quoted in the feedback, the
notes, ``grades.csv`` or the terminal; and the instructor's source notebook returned as a plain file
is flagged (its nbgrader markers), its points unchanged."""

from __future__ import annotations

import csv
import os

import pytest
from test_gradebook_times import TINY, grade_script, submit, tiny_course

from lorisnb.errors import ValidationError

pytestmark = pytest.mark.xdist_group("grading")

SHADOW = "root:$6$not-a-real-hash:20228:0:99999:7:::"  # what a system file a link names could hold


def test_read_submitted_refuses_links_folders_that_are_links_and_fifos(tmp_path):
    from lorisnb.tools.teaching.autograde import read_submitted

    below = tmp_path / "submitted"
    (below / "s1" / "lab").mkdir(parents=True)
    (below / "s1" / "lab" / "a.ipynb").write_text("{}")
    (tmp_path / "secret").write_text("hush")
    os.symlink(tmp_path / "secret", below / "s1" / "lab" / "link.ipynb")
    os.symlink(below / "s1", below / "s2")
    os.mkfifo(below / "s1" / "lab" / "fifo.ipynb")
    assert read_submitted(below / "s1" / "lab" / "a.ipynb", below) == b"{}"
    for path, why in [
        (below / "s1" / "lab" / "link.ipynb", "it is a symbolic link"),
        (below / "s2" / "lab" / "a.ipynb", f"the folder {below / 's2'} is a symbolic link"),
        (below / "s1" / "lab" / "fifo.ipynb", "not a regular file"),  # read, it would block the grader
    ]:
        with pytest.raises(ValidationError, match=why) as err:
            read_submitted(path, below)
        assert "hush" not in str(err.value)
    with pytest.raises(ValidationError, match="larger than 1 bytes"):
        read_submitted(below / "s1" / "lab" / "a.ipynb", below, limit=1)
    with pytest.raises(FileNotFoundError):
        read_submitted(below / "s1" / "lab" / "none.ipynb", below)


@pytest.mark.thorough
def test_links_are_refused_nothing_of_a_file_is_quoted_and_the_source_notebook_is_flagged(tmp_path, capsys):
    """grading4's fsym (the notebook a link to the instructor's source: 18/18), fstamp (timestamp.txt a
    link to .grading-secret: the secret printed in feedback.html, grades.csv and on stderr), fstamp2 (a
    plain timestamp.txt holding it: quoted the same way), fshadow (the notebook a link to /etc/shadow:
    its first line in the feedback) and fsrc1 (the source notebook as a plain file: 18/18, no note)."""
    grade = grade_script()
    course, source = tiny_course(tmp_path)
    secret_file = course / ".grading-secret"
    secret_file.write_text("c0ffee" * 5 + "42")
    secret = secret_file.read_text()
    shadow = tmp_path / "shadow"
    shadow.write_text(SHADOW + "\n")
    lab_nb = f"{TINY}.ipynb"
    submit(course, "honest", stamp="2026-12-01 20:00:00.000000 UTC")
    (course / "submitted" / "fsym" / TINY).mkdir(parents=True)
    os.symlink(source / TINY / lab_nb, course / "submitted" / "fsym" / TINY / lab_nb)
    (course / "submitted" / "fshadow" / TINY).mkdir(parents=True)
    os.symlink(shadow, course / "submitted" / "fshadow" / TINY / lab_nb)
    os.symlink(secret_file, submit(course, "fstamp") / "timestamp.txt")
    (submit(course, "fstamp2") / "timestamp.txt").write_text(secret)
    (submit(course, "fplain") / lab_nb).write_text(SHADOW)  # a plain file that is no notebook: not quoted either
    (course / "submitted" / "fsrc" / TINY).mkdir(parents=True)
    (course / "submitted" / "fsrc" / TINY / lab_nb).write_bytes((source / TINY / lab_nb).read_bytes())
    elsewhere = submit(course, "moved").parent  # a student's folder that is a link to another folder
    os.rename(elsewhere, tmp_path / "moved")
    os.symlink(tmp_path / "moved", elsewhere)

    rc = grade.main([str(course), "--source", str(source), "--timeout", "30", "--no-progress",
                     "--due", "2026-12-01T23:59+00:00"])  # fmt: skip
    out, err = capsys.readouterr()
    assert rc == 1  # the refused ones are not graded, and named
    rows = {r["student"]: r for r in csv.DictReader((course / "grades.csv").open(encoding="utf-8"))}
    scores = {s: r["score"] for s, r in rows.items()}
    assert scores == {"honest": "5", "fsym": "0", "fshadow": "0", "fstamp": "5", "fstamp2": "5", "fplain": "0",
                      "fsrc": "5", "moved": "0"}, scores  # fmt: skip
    for student in ("fsym", "fshadow"):
        page = (course / "graded" / student / TINY / "feedback.html").read_text()
        assert "it is a symbolic link: refused" in page, page
    assert "the folder" in rows["moved"]["notes"] or "symbolic link" in err
    assert "it is a symbolic link: refused" in rows["fstamp"]["notes"]
    assert "is not a time: not a date and time" in rows["fstamp2"]["notes"]
    assert "NotJSONError: not JSON" in (course / "graded" / "fplain" / TINY / "feedback.html").read_text()
    # the source notebook: flagged in its feedback, grades.csv and on stderr, its points unchanged
    assert "instructor's markers in this notebook (Q1_total: ### BEGIN SOLUTION" in rows["fsrc"]["notes"]
    assert "solutions leaked" in (course / "graded" / "fsrc" / TINY / "feedback.html").read_text()
    assert "1 submission(s) hold the instructor's nbgrader markers" in err and "(fsrc;" in err
    assert not any("markers" in rows[s]["notes"] for s in ("honest", "fstamp2"))
    # nothing of the secret or of the linked file anywhere the grader writes or prints
    written = [p for p in course.rglob("*") if p.is_file() and "submitted" not in p.parts and p != secret_file]
    written = [p for p in written if p.name != "timestamp.txt"]  # fstamp2's own file, copied where nbgrader reads it
    for text in [out, err, *(p.read_text(errors="replace") for p in written)]:
        assert secret not in text and "not-a-real-hash" not in text


@pytest.mark.thorough
def test_a_lab_folder_without_its_notebook_gets_a_row_and_a_reason(tmp_path, capsys):
    """A student's lab folder holding a zip of the notebook (or nothing) had no row in grades.csv and
    no word on the terminal: it is now a 0 saying what was found (names only, nothing read)."""
    grade = grade_script()
    course, source = tiny_course(tmp_path)
    submit(course, "honest")
    (course / "submitted" / "fzip" / TINY).mkdir(parents=True)
    (course / "submitted" / "fzip" / TINY / f"{TINY}.zip").write_bytes(b"PK\x03\x04" + SHADOW.encode())
    (course / "submitted" / "fempty" / TINY).mkdir(parents=True)
    rc = grade.main([str(course), "--source", str(source), "--timeout", "30", "--no-progress"])
    out, err = capsys.readouterr()
    assert rc == 1
    rows = {r["student"]: r for r in csv.DictReader((course / "grades.csv").open(encoding="utf-8"))}
    assert {s: r["score"] for s, r in rows.items()} == {"honest": "5", "fzip": "0", "fempty": "0"}
    page = (course / "graded" / "fzip" / TINY / "feedback.html").read_text()
    assert f"no notebook named {TINY}.ipynb in fzip/{TINY}/ (found: {TINY}.zip)" in page, page
    assert "(found: nothing)" in (course / "graded" / "fempty" / TINY / "feedback.html").read_text()
    assert "fzip" in out + err and "not-a-real-hash" not in out + err + page
