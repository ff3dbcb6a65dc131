"""The LMS exports of `make grade`, read back the way each LMS documents its import (issue 46: "exports
validated against the LMS layouts"), on a generated class of 30 whose roster holds the names that
break CSV files: commas, quotes, accents, other scripts, a section with a comma, a student without an
e-mail. Fast: the class's grades are generated, not graded.

- Canvas, "How do I import grades in the Gradebook?" (Canvas Instructor Guide): a CSV whose first
  columns are Student, ID, SIS User ID, SIS Login ID, Section, then one column per assignment; an
  optional "Points Possible" row; a student is found by ID, SIS User ID or SIS Login ID (one is enough).
- Moodle, "Import grades" (Moodle docs, Grades > Import > CSV file): a header row, a separator (comma)
  and an encoding (UTF-8, a byte-order mark trimmed) chosen on upload; one column is mapped to a user
  field to identify the user (here "Email address" to email) and each grade column to a grade item. A
  row whose identifier is blank is not refused: its grades go to the user of the row before (the
  importer keeps the last user found), so every identifier must be there. A grade over 100 (the default
  gradepointmax) stops the import.
- Gradescope, "Adding Students and Staff" (the roster: a header row, a unique e-mail per student, UTF-8
  for accented names) and its assignment score export (First Name, Last Name, SID, Email, Total Score,
  Max Points, Status, Submission Time, Lateness (H:M:S), then "k: question (p pts)" columns).
"""

from __future__ import annotations

import csv
import io
import re
from datetime import datetime, timedelta, timezone
from pathlib import Path

import numpy as np
import pytest

from lorisnb.tools.teaching.autograde import Score, SubmissionResult, lab_spec
from lorisnb.tools.teaching.gradebook import Graded, LatePolicy, read_roster, write_exports

ROOT = Path(__file__).resolve().parents[2]
LAB = "lab1_lifelong_metrics"
CANVAS_IDS = ("Student", "ID", "SIS User ID", "SIS Login ID", "Section")
GRADESCOPE_FIRST = ("First Name", "Last Name", "SID", "Email", "Total Score", "Max Points", "Status",
                    "Submission Time", "Lateness (H:M:S)")  # fmt: skip


def _csv_rows(path: Path, *, bom: bool) -> list[list[str]]:
    """The records of a CSV file as the LMSs read one: UTF-8 (with a byte-order mark only where the LMS
    trims it), RFC 4180 quoting, no blank line (a record of no field), one line ending after the last."""
    raw = path.read_bytes()
    assert bom or not raw.startswith(b"\xef\xbb\xbf"), f"{path.name}: a byte-order mark"
    text = raw.decode("utf-8-sig")  # not UTF-8: UnicodeDecodeError
    assert text.endswith("\n") and not text.endswith("\n\n") and not text.endswith("\r\n\r\n"), path.name
    rows = list(csv.reader(io.StringIO(text, newline=""), strict=True))
    assert rows and all(rows), f"{path.name}: a blank line"
    assert all(len(r) == len(rows[0]) for r in rows), f"{path.name}: rows of another width than the header"
    return rows


def _number(cell: str, top: float, where: str) -> float:
    assert re.fullmatch(r"-?\d+(\.\d+)?", cell), f"{where}: {cell!r} is not a plain number"
    v = float(cell)
    assert 0 <= v <= top, f"{where}: {v} outside 0..{top}"
    return v


def _unique_filled(rows: list[dict[str, str]], column: str, where: str) -> None:
    values = [r[column] for r in rows if r[column]]
    assert len(values) == len(set(values)), (
        f"{where}: {column} repeats {sorted(v for v in values if values.count(v) > 1)}"
    )


def read_canvas(path: Path) -> tuple[dict[str, float], list[dict[str, str]]]:
    """Canvas' gradebook import: (points possible per assignment, the students' rows)."""
    rows = _csv_rows(path, bom=True)
    header = rows[0]
    assert tuple(header[:5]) == CANVAS_IDS and len(header) > 5 and all(h.strip() for h in header[5:]), header
    body = rows[1:]
    possible: dict[str, float] = {}
    if body and body[0][0].strip() == "Points Possible":
        assert not any(body[0][1:5]), body[0]
        possible = {
            h: _number(v, float("inf"), "Points Possible") for h, v in zip(header[5:], body[0][5:], strict=True)
        }
        body = body[1:]
    students = [dict(zip(header, r, strict=True)) for r in body]
    for k, s in enumerate(students, 2):
        assert s["ID"] or s["SIS User ID"] or s["SIS Login ID"], f"canvas row {k}: no identifier"
        for h in header[5:]:
            if s[h]:
                _number(s[h], possible.get(h, float("inf")), f"canvas row {k}, {h}")
    for column in ("ID", "SIS User ID", "SIS Login ID"):
        _unique_filled(students, column, "canvas")
    return possible, students


def read_moodle(path: Path, grade: str, identifier: str = "Email address", top: float = 100.0) -> list[dict[str, str]]:
    """Moodle's CSV grade import, comma-separated UTF-8, users identified by ``identifier`` (mapped to
    their e-mail), ``grade`` mapped to the grade item."""
    rows = _csv_rows(path, bom=True)
    header = [h.strip() for h in rows[0]]
    assert all(header) and len(header) == len(set(header)), header  # Moodle maps each column once
    assert identifier in header and grade in header, header
    students = [dict(zip(header, r, strict=True)) for r in rows[1:]]
    for k, s in enumerate(students, 2):
        assert len(rows[k - 1]) > 1  # Moodle skips a line of one field
        assert s[identifier].strip(), f"moodle row {k}: blank {identifier}: its grade would go to the row before's user"
        _number(s[grade].strip(), min(top, 100.0), f"moodle row {k}")
    _unique_filled(students, identifier, "moodle")
    return students


def read_gradescope(path: Path) -> tuple[dict[str, float], list[dict[str, str]]]:
    """Gradescope's score layout, students matched by e-mail: (points per question, the rows)."""
    rows = _csv_rows(path, bom=False)
    header = rows[0]
    assert tuple(header[:9]) == GRADESCOPE_FIRST, header
    points = {}
    for k, h in enumerate(header[9:], 1):
        m = re.fullmatch(rf"{k}: (.+) \((\d+(?:\.\d+)?) pts\)", h)
        assert m, h
        points[h] = float(m.group(2))
    students = [dict(zip(header, r, strict=True)) for r in rows[1:]]
    for k, s in enumerate(students, 2):
        assert "@" in s["Email"], f"gradescope row {k}: e-mail {s['Email']!r}"
        top = _number(s["Max Points"], float("inf"), f"gradescope row {k}, Max Points")
        _number(s["Total Score"], top, f"gradescope row {k}, Total Score")
        assert re.fullmatch(r"\d+:\d\d:\d\d", s["Lateness (H:M:S)"]), s["Lateness (H:M:S)"]
        assert not s["Submission Time"] or datetime.fromisoformat(s["Submission Time"]).tzinfo
        for h, p in points.items():
            if s[h]:
                _number(s[h], p, f"gradescope row {k}, {h}")
    _unique_filled(students, "Email", "gradescope")
    _unique_filled(students, "SID", "gradescope")
    return points, students


# --- a class of 30 with a roster that breaks CSV files ----------------------------------------------

TRICKY = [  # (name, email, sis_id, login_id, section)
    ("Lovelace, Ada", "ada@uni.example", "1001", "", ""),  # "Last, First", as Canvas lists students
    ('Zoë "Zed" Quinn', "zoe@uni.example", "", "zquinn", ""),
    ("José María García-López", "jm.garcia@uni.example", "1003", "", "Lab A, Tuesday"),
    ("Łukasz Żółć", "lukasz@uni.example", "", "", ""),
    ("Nguyễn Văn An", "an.nguyen@uni.example", "1005", "", ""),
    ("李小龙", "xiaolong@uni.example", "", "", ""),
    ("O'Brien, Siobhán", "siobhan@uni.example", "1007", "", "Lab B"),
    ("Ingrid Bergström", "", "1008", "", ""),  # no e-mail on the roster
]


def _class(tmp_path: Path, n: int = 30) -> tuple[dict, list[Graded], LatePolicy]:
    roster_csv = tmp_path / "roster.csv"
    rng = np.random.default_rng(46)
    with roster_csv.open("w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(["id", "name", "email", "sis_id", "login_id", "section"])
        for k in range(1, n + 1):
            name, email, sis, login, section = (
                TRICKY[k - 1]
                if k <= len(TRICKY)
                else (
                    f"Student {k:02d}",
                    f"s{k:02d}@uni.example",
                    f"{1000 + k}",
                    "",
                    "Lab A, Tuesday" if k % 2 else "Lab B",
                )
            )
            w.writerow([f"s{k:02d}", f"  {name} " if k == 4 else name, email, sis, login, section])  # fmt: skip
    roster = read_roster(roster_csv)
    questions = [
        (q.grade_id, q.points) for q in lab_spec(ROOT / "teaching" / "source" / LAB / f"{LAB}.ipynb").questions
    ]
    policy = LatePolicy(datetime(2026, 12, 1, 23, 59, tzinfo=timezone.utc), per_day=0.1, max_days=3)
    graded = []
    for sid in [*roster, "s99", "demo-mistakes"]:  # one not on the roster, one demonstration student
        scores = [Score(q, float(p * rng.integers(0, 2)) if rng.random() < 0.4 else p, p, "✓") for q, p in questions]
        when = policy.due + timedelta(hours=float(rng.uniform(-72, 60)))
        factor, days = policy.factor(when)
        result = SubmissionResult(sid, LAB, scores, "full", 30.0)
        graded.append(Graded(result, when, days, factor, max(0.0, (when - policy.due).total_seconds())))
    return roster, graded, policy


@pytest.fixture
def exported(tmp_path):
    roster, graded, _ = _class(tmp_path)
    left_out = write_exports(tmp_path, graded, roster)
    return tmp_path / "exports", roster, {g.result.student: g for g in graded}, left_out


def _split_back(first: str, last: str, name: str) -> bool:
    """The First and Last columns hold the roster's name: "Last, First" split at its comma (as Canvas
    lists students), else the last word is the last name (a name of one word is all last name)."""
    if "," in name:
        before, _, after = name.partition(",")
        return (first, last) == (after.strip(), before.strip())
    return f"{first} {last}".strip() == name and bool(last) and not first.endswith(" ")


def test_canvas_export_imports_as_canvas_documents(exported):
    exports, roster, graded, _ = exported
    possible, students = read_canvas(exports / f"{LAB}-canvas.csv")
    assert possible == {LAB: 18.0}
    assert len(students) == 30  # everyone on the roster (the one without an e-mail has an SIS User ID)
    by_sis = {s["SIS User ID"]: s for s in students}
    for sid, who in roster.items():
        row = by_sis[who.sis_id or sid]
        assert row["Student"] == who.name and row["Section"] == who.section
        assert float(row[LAB]) == pytest.approx(graded[sid].score, abs=5e-5)


def test_moodle_export_imports_as_moodle_documents(exported):
    exports, roster, graded, left_out = exported
    students = read_moodle(exports / f"{LAB}-moodle.csv", LAB, top=18.0)
    by_email = {s["Email address"]: s for s in students}
    assert len(students) == 29 and "s08" in left_out.no_email  # no e-mail: left out, and named
    for sid, who in roster.items():
        if who.email:
            row = by_email[who.email]
            assert _split_back(row["First name"], row["Last name"], who.name), (row, who.name)
            assert float(row[LAB]) == pytest.approx(graded[sid].score, abs=5e-5)


def test_gradescope_export_imports_as_gradescope_documents(exported):
    exports, roster, graded, left_out = exported
    points, students = read_gradescope(exports / f"{LAB}-gradescope.csv")
    assert sum(points.values()) == 18.0 and len(students) == 29 and "s08" in left_out.no_email
    by_email = {s["Email"]: s for s in students}
    for sid, who in roster.items():
        if who.email:
            row = by_email[who.email]
            assert _split_back(row["First Name"], row["Last Name"], who.name), (row, who.name)
            assert float(row["Total Score"]) == pytest.approx(graded[sid].score, abs=5e-5)


def test_exports_name_whom_they_leave_out_and_keep_demo_students_apart(exported):
    exports, roster, _, left_out = exported
    assert left_out.not_on_roster == ["s99"] and left_out.no_email == ["s08"]
    for lms in ("canvas", "moodle", "gradescope"):
        text = (exports / f"{LAB}-{lms}.csv").read_text(encoding="utf-8")
        assert "demo-" not in text and "s99" not in text


@pytest.mark.parametrize(
    ("row", "match"),
    [
        ("s2,Bob,ada@uni.example,,,", "line 3.*e-mail 'ada@uni.example'.*line 2"),
        ("s2,Bob,bob@uni.example,1001,,", "line 3.*sis_id '1001'.*line 2"),
        ("s2,Bob,bob@uni.example,,ada,", "line 3.*login_id 'ada'.*line 2"),
    ],
)
def test_roster_refuses_an_identifier_two_students_share(tmp_path, row, match):
    """Moodle and Gradescope find a student by e-mail, Canvas by SIS User ID or SIS Login ID: two
    students with one of them would get each other's grades."""
    from lorisnb.errors import ValidationError

    f = tmp_path / "roster.csv"
    f.write_text(f"id,name,email,sis_id,login_id,section\ns1,Ada,ada@uni.example,1001,ada,\n{row}\n")
    with pytest.raises(ValidationError, match=match):
        read_roster(f)
