"""`teaching/grade.py`'s exit status and the submissions it must name (the adversarial teaching
pass): every option refused before grading exits 2 (they exited 1, as "some submissions not graded"
does), with a message naming the option, and grades nothing; a notebook put straight in
``submitted/<student>/`` (no ``<lab>/`` folder) gets a row scoring 0 saying where it belongs, as a
lab folder without its notebook does (it was skipped without a word)."""

from __future__ import annotations

import csv

import pytest
from test_gradebook_times import TINY, grade_script, submit, tiny_course

pytestmark = pytest.mark.xdist_group("grading")


@pytest.mark.parametrize(
    ("options", "said"),
    [
        (["--due", "tomorrow"], "--due 'tomorrow' is not an ISO 8601 date"),
        (["--due", "2026-12-01T23:59"], "has no time zone"),
        (["--due", "2026-12-01T23:59+01:00", "--late-per-day", "1.5"], "within [0, 1]"),
        (["--due", "2026-12-01T23:59+01:00", "--late-max-days", "-1"], "must be >= 0"),
        (["--lab", "nosuchlab"], "--lab nosuchlab: no "),
        (["--roster", "nosuch.csv"], "--roster nosuch.csv: No such file"),
        (["--source", "nosuchfolder"], "--source nosuchfolder is not a folder"),
    ],
)
def test_a_refused_option_exits_2_naming_it_and_grades_nothing(tmp_path, capsys, monkeypatch, options, said):
    grade = grade_script()
    course, source = tiny_course(tmp_path)
    submit(course, "honest")
    monkeypatch.chdir(tmp_path)  # the relative names (nosuch.csv, nosuchfolder) are looked for here
    args = [str(course), "--source", str(source), "--no-progress", *options]
    rc = grade.main(args)
    err = capsys.readouterr().err
    assert rc == 2 and said in err, (rc, err)
    assert not (course / "graded").exists() and not (course / "grades.csv").exists()


def test_a_malformed_roster_and_a_missing_release_exit_2(tmp_path, capsys):
    grade = grade_script()
    course, source = tiny_course(tmp_path)
    submit(course, "honest")
    roster = tmp_path / "roster.csv"
    roster.write_text("who,what\nx,y\n")
    assert grade.main([str(course), "--source", str(source), "--no-progress", "--roster", str(roster)]) == 2
    assert str(roster) in capsys.readouterr().err
    (course / "release" / TINY / f"{TINY}.ipynb").unlink()
    (course / "release" / TINY).rmdir()
    assert grade.main([str(course), "--source", str(source), "--no-progress"]) == 2
    assert "run `make student` first" in capsys.readouterr().err
    assert not (course / "grades.csv").exists()


@pytest.mark.thorough
def test_a_notebook_outside_its_lab_folder_is_named_and_scores_0(tmp_path, capsys):
    grade = grade_script()
    course, source = tiny_course(tmp_path)
    submit(course, "honest")
    nb = submit(course, "m_nolabdir") / f"{TINY}.ipynb"
    nb.rename(nb.parents[1] / nb.name)  # submitted/m_nolabdir/tiny_lab.ipynb
    nb.parent.rmdir()
    other = submit(course, "m_renamed") / f"{TINY}.ipynb"  # another name, straight in the student's folder
    other.rename(other.parents[1] / "my lab.ipynb")
    other.parent.rmdir()
    (course / "submitted" / "m_nothing").mkdir()  # an empty student folder: nothing returned, no row
    rc = grade.main([str(course), "--source", str(source), "--timeout", "30", "--no-progress"])
    out, err = capsys.readouterr()
    assert rc == 1
    rows = {r["student"]: r for r in csv.DictReader((course / "grades.csv").open(encoding="utf-8"))}
    assert {s: r["score"] for s, r in rows.items()} == {"honest": "5", "m_nolabdir": "0", "m_renamed": "0"}, rows
    for student, name in (("m_nolabdir", f"{TINY}.ipynb"), ("m_renamed", "my lab.ipynb")):
        page = (course / "graded" / student / TINY / "feedback.html").read_text()
        assert f"{student}/{name}" in page and f"submitted/{student}/{TINY}/{TINY}.ipynb" in page, page
        assert student in err


def test_a_notebook_straight_in_submitted_is_named_and_exits_1(tmp_path, capsys):
    """A notebook put in ``submitted/`` itself, in no student's folder, has no student to be graded
    for: it was passed over without a word, exit 0; it is named now, exit 1."""
    import shutil

    grade = grade_script()
    course, source = tiny_course(tmp_path)
    (course / "submitted").mkdir(exist_ok=True)
    stray = course / "submitted" / f"{TINY}.ipynb"
    shutil.copy(course / "release" / TINY / f"{TINY}.ipynb", stray)
    (course / "submitted" / ".DS_Store").write_text("x")  # hidden: not a submission
    (course / "submitted" / "README.md").write_text("x")  # the course's (teaching/submitted/ holds one)
    rc = grade.main([str(course), "--source", str(source), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 1 and f"not graded: {stray}: a notebook straight in submitted/, in no student's folder" in err, err
    assert ".DS_Store" not in err and "README.md" not in err
