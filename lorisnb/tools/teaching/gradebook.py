"""Grade a class and write grades an LMS takes (``teaching/README.md``, "Grading").

:func:`grade_class` grades every ``submitted/<student>/<lab>/<lab>.ipynb`` of a course folder with
:func:`~lorisnb.tools.teaching.autograde.grade_submission`, in parallel, regrading only what changed
(the digest of the submission, the lab, the release and the settings is kept in each result), and
writes, all in the course folder:

- ``graded/<student>/<lab>/result.json`` and ``feedback.html`` (each question: points, the checks' messages);
- ``feedback/<student>/<lab>/<lab>.html``: the same page where ``nbgrader release_feedback <lab>`` hands it out
  from, with the submission's ``timestamp.txt`` and ``submission_secret.txt`` (for each submission collected
  through nbgrader's exchange, which has them);
- ``grades.csv``: one row per student and lab, every question's points, the late penalty, the score;
- ``exports/<lab>-canvas.csv``, ``-moodle.csv``, ``-gradescope.csv``: the LMS' CSV layouts;
- ``grades-demo.csv``: the demonstration students (``demo-*``), never in the LMS exports.

Names and e-mails come from a roster CSV (``id,name,email``, optional ``sis_id``, ``login_id``,
``section``); a student missing from a given roster is graded but left out of the exports (and named).

The gradebook's own notes (:attr:`Graded.notes`, the ``notes`` column of ``grades.csv``): a
submission whose time is unknown (no ``timestamp.txt`` while a late policy is set, or one that
cannot be read: that student is named, everyone else is graded and exported), and submissions
whose answer cells are identical (:func:`identical_answers`: possible copies, no points changed).
"""

from __future__ import annotations

import ast
import csv
import functools
import html
import itertools
import math
import os
import re
import zoneinfo
from collections.abc import Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from datetime import datetime, timedelta, timezone, tzinfo
from pathlib import Path
from typing import Any

import nbformat

from lorisnb.errors import ValidationError
from lorisnb.tools.teaching.autograde import (
    SOURCE_MARKERS,
    GradeSettings,
    LabSpec,
    SubmissionResult,
    digest,
    git_databases,
    grade_submission,
    lab_spec,
    leaked_note,
    not_a_notebook,
    read_notebook,
    read_submitted,
    student_answers,
    unreadable,
)
from lorisnb.tools.teaching.sandbox import can_isolate, claim_uids

DEMO_PREFIX = "demo-"  # the students demo_submissions.py writes
ROSTER_COLUMNS = ("id", "name", "email")
ROSTER_OPTIONAL = ("sis_id", "login_id", "section")


@dataclass(frozen=True)
class Student:
    id: str
    name: str = ""
    email: str = ""
    sis_id: str = ""
    login_id: str = ""
    section: str = ""


def read_roster(path: Path) -> dict[str, Student]:
    """The roster CSV: a header with ``id,name,email`` (and optionally ``sis_id``, ``login_id``,
    ``section``), one row per student; refused with the line when a column or an id is wrong."""
    with open(path, newline="", encoding="utf-8-sig") as f:
        rows = list(csv.reader(f))
    if not rows:
        raise ValidationError(f"{path}: empty roster; expected a header line {','.join(ROSTER_COLUMNS)}")
    header = [h.strip().lower() for h in rows[0]]
    missing = [c for c in ROSTER_COLUMNS if c not in header]
    unknown = [h for h in header if h not in ROSTER_COLUMNS + ROSTER_OPTIONAL]
    if missing or unknown:
        raise ValidationError(
            f"{path}, line 1: roster header {rows[0]}: missing {missing or 'nothing'}, unknown {unknown or 'nothing'}; "
            f"expected {', '.join(ROSTER_COLUMNS)} and optionally {', '.join(ROSTER_OPTIONAL)}"
        )
    out: dict[str, Student] = {}
    seen: dict[tuple[str, str], int] = {}  # (column, value) -> the line that has it
    for line, row in enumerate(rows[1:], start=2):
        if not any(cell.strip() for cell in row):
            continue
        if len(row) != len(header):
            raise ValidationError(
                f"{path}, line {line}: {len(row)} fields, expected {len(header)} ({','.join(header)})"
            )
        rec = {h: v.strip() for h, v in zip(header, row, strict=True)}
        if not re.fullmatch(r"[A-Za-z0-9._@+-]+", rec["id"]):
            raise ValidationError(
                f"{path}, line {line}: student id {rec['id']!r} (expected letters, digits, . _ @ + -)"
            )
        if rec["id"] in out:
            raise ValidationError(f"{path}, line {line}: student id {rec['id']!r} appears twice")
        if rec["email"] and "@" not in rec["email"]:
            raise ValidationError(f"{path}, line {line}: e-mail {rec['email']!r} has no @")
        for column, what in (("email", "e-mail"), ("sis_id", "sis_id"), ("login_id", "login_id")):
            key = (column, rec.get(column, "").lower() if column == "email" else rec.get(column, ""))
            if key[1] and key in seen:  # the LMSs find a student by these: two would get each other's grades
                raise ValidationError(
                    f"{path}, line {line}: {what} {rec[column]!r} is also on line {seen[key]}; "
                    "each student needs their own (the LMS exports identify students by it)"
                )
            seen[key] = line
        out[rec["id"]] = Student(**rec)
    return out


@dataclass(frozen=True)
class LatePolicy:
    """Due date (aware datetime) and the penalty: ``per_day`` of the points per started day late
    (0.1: 10 %), nothing after ``max_days`` days (None: no limit). A submission without a time
    (no nbgrader ``timestamp.txt``, or one that cannot be read) counts as on time, and is named in
    the notes (:func:`grade_class`: the student's ``feedback.html`` and ``grades.csv``; ``make grade``
    says how many)."""

    due: datetime
    per_day: float = 0.0
    max_days: int | None = None

    def __post_init__(self) -> None:
        if self.due.tzinfo is None:
            raise ValidationError(
                f"due date {self.due.isoformat()} has no time zone (write e.g. 2026-12-01T23:59+01:00)"
            )
        if not 0 <= self.per_day <= 1:
            raise ValidationError(f"late penalty per day must be within [0, 1] (a fraction), got {self.per_day}")
        if self.max_days is not None and self.max_days < 0:
            raise ValidationError(f"late days allowed must be >= 0, got {self.max_days}")

    def days_late(self, submitted: datetime) -> int:
        late = (submitted - self.due).total_seconds()
        return max(0, math.ceil(late / 86400.0))

    def factor(self, submitted: datetime | None) -> tuple[float, int]:
        """(fraction of the points kept, whole days late) for a submission at ``submitted``."""
        if submitted is None:
            return 1.0, 0
        days = self.days_late(submitted)
        if self.max_days is not None and days > self.max_days:
            return 0.0, days
        return max(0.0, 1.0 - self.per_day * days), days


TIME_EXPECTED = (
    "a time as nbgrader writes it, e.g. 2026-12-01 23:59:00.000000 UTC, with a zone name (CET, CEST, "
    "Europe/Berlin) or an offset (+0100, +01:00)"
)
_OFFSET = re.compile(r"(?:UTC|GMT)?([+-])(\d{1,2})(?::?(\d{2}))?")
_NOT_ZONES = {"Factory", "localtime", "posixrules"}  # in the tz database's list, but no place's zone


class NotATime(ValueError):
    """A text that is no time (:func:`parse_time`): its message may quote the text; ``reason`` says
    why in words that quote nothing of it (what a submission's feedback shows)."""

    def __init__(self, message: str, reason: str) -> None:
        super().__init__(message)
        self.reason = reason


@functools.lru_cache(maxsize=1)
def _zone_keys() -> tuple[str, ...]:
    return tuple(sorted(zoneinfo.available_timezones() - _NOT_ZONES))


def _zone(name: str, local: datetime, course: timedelta | None = None) -> tzinfo:
    """The zone a timestamp names after its time, at that (local) time: UTC, an offset (``+0100``,
    ``+01:00``, ``+01``, ``UTC+01:00``), an abbreviation (``CET``, ``CEST``, ``PDT``: the offset
    every zone of the tz database that uses it at that time has) or a zone of the tz database
    (``Europe/Berlin``). An abbreviation zones use with different offsets (``CST``: -0600 in
    Chicago, +0800 in Shanghai) takes that of this machine's zone, if it is one of them (as nbgrader
    reads it), else ``course`` (the due date's offset), if it is one of them; else, or when no zone
    uses it then, it is refused."""
    if name.upper() in ("UTC", "GMT", "UT", "Z"):
        return timezone.utc
    m = _OFFSET.fullmatch(name)
    if m:
        hours, minutes = int(m.group(2)), int(m.group(3) or 0)
        if hours > 23 or minutes > 59:
            raise NotATime(f"offset {name} is out of range", "its offset is out of range")
        return timezone((-1 if m.group(1) == "-" else 1) * timedelta(hours=hours, minutes=minutes))
    if "/" not in name:
        offsets: dict[timedelta, list[str]] = {}
        for key in _zone_keys():
            at = local.replace(tzinfo=zoneinfo.ZoneInfo(key))
            if at.tzname() == name and (offset := at.utcoffset()) is not None:
                offsets.setdefault(offset, []).append(key)
        here = local.astimezone()  # this machine's zone
        if len(offsets) > 1 and here.tzname() == name and here.utcoffset() in offsets:
            offsets = {o: k for o, k in offsets.items() if o == here.utcoffset()}
        elif len(offsets) > 1 and course in offsets:
            offsets = {o: k for o, k in offsets.items() if o == course}
        if len(offsets) == 1:
            return timezone(next(iter(offsets)), name)
        if offsets:
            places = "; ".join(f"{datetime(2000, 1, 1, tzinfo=timezone(o)).strftime('%z')} in {', '.join(k[:2])}"
                               for o, k in sorted(offsets.items()))  # fmt: skip
            why = (
                "means different offsets, and neither this machine's zone nor the due date's offset is one of them "
                "(--due in the course's zone tells; nbgrader's Exchange.timestamp_format with %z writes the offset)"
            )
            raise NotATime(f"the zone {name} {why} ({places})", f"its zone abbreviation {why}")
    try:
        return zoneinfo.ZoneInfo(name)
    except (zoneinfo.ZoneInfoNotFoundError, ValueError, OSError):
        raise NotATime(
            f"no zone of the tz database is called {name} or uses it on {local:%Y-%m-%d}",
            "its zone is no zone of the tz database, nor an abbreviation one uses on that date",
        ) from None


def _dateutil(text: str, course: timedelta | None = None) -> datetime:
    """A date and time in another layout, as nbgrader reads it (dateutil: ``Exchange.timestamp_format``
    may be any layout dateutil reads), its zone placed by :func:`_zone`; every part of the date and
    time must be written (read with two other defaults, it must give the same)."""
    try:
        from dateutil import parser  # type: ignore[import-untyped]  # pandas' dependency, as nbgrader's
    except ImportError:
        raise NotATime("not an ISO 8601 date and time", "not an ISO 8601 date and time") from None
    try:
        local = parser.parse(text, ignoretz=True, default=datetime(2000, 1, 1))
        other = parser.parse(text, ignoretz=True, default=datetime(2001, 2, 2, 1, 1))
        if local != other:
            raise NotATime("a part of the date or time is missing", "a part of the date or time is missing")

        def zone(name: str | None, offset: int | None) -> tzinfo:
            return _zone(name, local, course) if name else timezone(timedelta(seconds=offset or 0))

        t = parser.parse(text, default=datetime(2000, 1, 1), tzinfos=zone)
    except (parser.ParserError, OverflowError):
        raise NotATime("not a date and time", "not a date and time") from None
    return t


_STAMP = re.compile(r"(\d{4}-\d{2}-\d{2})(?:[T ](\d{2}:\d{2}(?::\d{2}(?:[.,]\d{1,6})?)?))?(?:\s*(\S+))?")


def parse_time(text: str, course: timedelta | None = None) -> datetime:
    """A submission's time as nbgrader writes it in ``timestamp.txt`` (``Exchange.timestamp_format``,
    by default ``%Y-%m-%d %H:%M:%S.%f %Z`` in ``Exchange.timezone``): the date and time, then the
    zone (:func:`_zone`: ``UTC``, ``CET``, ``Europe/Berlin``, ``+0100``...; an ISO 8601 time with
    its offset too); without a zone it is UTC, as nbgrader reads it (``nbgrader.utils.parse_utc``,
    whose split of date, time and zone this follows; unlike it, ``+0100`` is an hour, not 100 s,
    and a zone it cannot place, such as ``CEST`` on a machine in another zone, is refused instead
    of read as UTC). ``course``: the course's offset (the due date's), which an abbreviation
    several offsets share (``CST``) may mean. Raises ValueError saying why."""
    text = text.strip()
    m = _STAMP.fullmatch(text)
    if m is None:
        t = _dateutil(text, course)
    else:
        t = datetime.fromisoformat(f"{m.group(1)} {m.group(2) or '00:00'}".replace(",", "."))
        if m.group(3):
            t = t.replace(tzinfo=_zone(m.group(3), t, course))
    return t if t.tzinfo else t.replace(tzinfo=timezone.utc)


#: a ``timestamp.txt`` longer than this is no time nbgrader writes (and is not read further)
STAMP_MAX_BYTES = 256


def _read_time(f: Path, course: timedelta | None = None, below: Path | None = None) -> datetime | None:
    """The time in ``f`` (None: no such file), read by :func:`.autograde.read_submitted` (a link
    refused; ``below``: the folder of the submissions, every folder under it checked too); ValueError
    saying what was expected, quoting nothing of what it holds (the file is a student's: what a
    link, or a copy, put there would be shown in the feedback, ``grades.csv`` and the terminal)."""
    try:
        data = read_submitted(f, below, limit=STAMP_MAX_BYTES)
    except FileNotFoundError:
        return None
    except ValidationError as exc:
        reason = str(exc).removeprefix(f"{f}: ")
        raise ValueError(f"not read: {reason}") from None
    except OSError as exc:
        raise ValueError(f"cannot be read ({os.strerror(exc.errno) if exc.errno else type(exc).__name__}); "
                         f"expected {TIME_EXPECTED}") from None  # fmt: skip
    try:
        return parse_time(data.decode("utf-8"), course)
    except (UnicodeDecodeError, ValueError) as exc:
        why = exc.reason if isinstance(exc, NotATime) else "not a date and time"
        raise ValueError(f"is not a time: {why} (what it holds is not quoted: no file of a submission is shown); "
                         f"expected {TIME_EXPECTED}") from None  # fmt: skip


def submission_time(folder: Path) -> datetime | None:
    """When a submission was made: nbgrader's ``timestamp.txt`` (``nbgrader collect``/``submit``),
    read by :func:`parse_time`; None without one; ValidationError naming the file when it is no
    time (:func:`grade_class` then notes it for that student and grades the others)."""
    f = folder / "timestamp.txt"
    try:
        return _read_time(f, below=folder)
    except ValueError as exc:
        raise ValidationError(f"{f}: {exc}") from None


@dataclass
class Graded:
    """A graded submission with what the gradebook adds: its time, lateness, final score, and its
    notes: ``notes`` on its time (also in its ``feedback.html``), ``time_error`` (its
    ``timestamp.txt`` is no time: why), ``no_time`` (a late policy was set and it has no time, or an
    unreadable one: counted as on time), ``identical`` (another student -> the answer cells both
    submitted identical, :func:`identical_answers`; in ``grades.csv``, not in the feedback),
    ``same_variant`` (the other submissions of the lab whose folder names the same id as the data
    variants take it, case, spaces and Unicode's compatibility forms aside: Alice and alice, a Kelvin
    sign K and K, a ﬁ ligature and fi; they got the same numbers; in ``grades.csv``, not in the feedback)."""

    result: SubmissionResult
    submitted: datetime | None
    days_late: int
    factor: float
    lateness_s: float = 0.0
    notes: list[str] = field(default_factory=list)
    time_error: str = ""
    no_time: bool = False
    identical: dict[str, tuple[str, ...]] = field(default_factory=dict)
    same_variant: tuple[str, ...] = ()

    @property
    def score(self) -> float:
        return round(self.result.points * self.factor, 4)

    @property
    def variant_notes(self) -> list[str]:
        if not self.same_variant:
            return []
        return [
            f"same data variant as {', '.join(repr(s) for s in self.same_variant)}: their folders name the same id once "
            "spaces and case are set aside (Unicode's case folding: a Kelvin sign is K, a ligature ﬁ is fi), as the "
            "variant's seed is drawn, so they got the same numbers: one student under two folders, or two students "
            "whose ids must differ by more (rename a folder and regrade)"
        ]

    @property
    def leak_notes(self) -> list[str]:
        """The submission holds nbgrader's instructor markers (the lab's solutions leaked): its note."""
        return [leaked_note(self.result.instructor_markers)] if self.result.instructor_markers else []

    @property
    def copy_notes(self) -> list[str]:
        if not self.identical:
            return []
        whose = "; ".join(f"{other}'s {', '.join(gids)}" for other, gids in sorted(self.identical.items()))
        return [
            f"possible copy: answer cells identical to {whose} (each not the handed-out stub, with at least "
            f"{COPY_MIN_CHARS} characters and {COPY_MIN_LINES} lines of code of its own, not the instructor's answer, "
            f"given by fewer than {COPY_COMMON} students; {COPY_MIN_ANSWERS} or more such cells flag a pair): no points "
            "changed, an instructor decides"
        ]


def same_variants(students: Sequence[str]) -> dict[str, tuple[str, ...]]:
    """student -> the other students (submission folders) whose id draws the same data variant
    (:func:`._prose.same_id`: spaces and case aside, Unicode's case folding), for those that have any."""
    from lorisnb.tools.teaching._prose import same_id

    by_id: dict[str, set[str]] = {}
    for s in students:
        by_id.setdefault(same_id(s), set()).add(s)
    return {s: tuple(sorted(by_id[same_id(s)] - {s})) for s in students if len(by_id[same_id(s)]) > 1}


# --- identical answers (possible copies) -----------------------------------------------------------

COPY_MIN_ANSWERS = 3  # identical answer cells that flag a pair of submissions
COPY_MIN_CHARS = 40  # characters other than spaces an answer needs in its own lines (not the stub's) to count
COPY_MIN_LINES = 2  # lines of code of its own (not the stub's, not blank, not a comment) an answer needs to count
COPY_COMMON = 4  # an answer this many students gave alike is what the exercise leads to: no sign of a copy
CODE_STUB = "# YOUR CODE HERE\nraise NotImplementedError()"  # nbgrader's (and teaching/nbgrader_config.py's)
_DELIMITERS = set(SOURCE_MARKERS[:2])  # nbgrader's solution delimiters, in a cell copied from the instructor's
_SOLUTION = re.compile(r"^([ \t]*)### BEGIN SOLUTION[ \t]*\n.*?^[ \t]*### END SOLUTION[ \t]*$", re.S | re.M)


def _normal(source: str) -> str:
    """An answer cell as compared: each line's trailing whitespace and the blank lines around it left out."""
    return "\n".join(line.rstrip() for line in source.splitlines()).strip("\n")


def answer_stubs(spec: LabSpec, release: Path) -> dict[str, list[str]]:
    """answer grade_id -> the stubs a student was handed out: the release notebook's answer cell
    (``release/<lab>/<lab>.ipynb``, when there) and the instructor's cell with its solution replaced
    by nbgrader's :data:`CODE_STUB`, as ``nbgrader generate_assignment`` does."""
    out: dict[str, list[str]] = {}
    for cell in spec.notebook.cells:
        meta = cell.get("metadata", {}).get("nbgrader", {})
        if cell.cell_type == "code" and meta.get("solution") and meta.get("grade_id") is not None:
            src = cell.source
            stub = (_SOLUTION.sub(lambda m: "\n".join(m.group(1) + line for line in CODE_STUB.splitlines()), src)
                    if _SOLUTION.search(src) else CODE_STUB)  # fmt: skip
            out[str(meta["grade_id"])] = [stub]
    handed_out = release / f"{spec.name}.ipynb"
    if handed_out.is_file():
        try:
            for gid, src in student_answers(nbformat.read(handed_out, as_version=4)).items():
                out.setdefault(gid, []).append(src)
        except Exception:  # noqa: BLE001 (a release notebook that does not read: the derived stubs stay)
            pass
    return out


def canonical_answers(spec: LabSpec) -> dict[str, list[str]]:
    """answer grade_id -> the instructor's answer, as a student would return it (nbgrader's solution
    delimiters left out): the formulation the exercise leads to."""
    out: dict[str, list[str]] = {}
    for cell in spec.notebook.cells:
        meta = cell.get("metadata", {}).get("nbgrader", {})
        if cell.cell_type == "code" and meta.get("solution") and meta.get("grade_id") is not None:
            text = "\n".join(line for line in cell.source.splitlines() if line.strip() not in _DELIMITERS)
            out[str(meta["grade_id"])] = [text]
    return out


def _code_key(source: str) -> str | None:
    """A cell's code without its layout and comments (its syntax tree), None when it does not parse."""
    try:
        return ast.dump(ast.parse(source))
    except (SyntaxError, ValueError):
        return None


def _without(source: str, lines: set[str]) -> str:
    """``source`` without the lines that are, stripped, one of ``lines`` (a stub's), as it is indented."""
    return "\n".join(line for line in source.splitlines() if line.strip() not in lines)


def _own_code(source: str, stub_lines: set[str]) -> tuple[str, ...]:
    """The lines of code of an answer that are not a stub's (nor blank, nor comments), spaces left
    out: what the detector counts as the answer's own, compared when its code does not parse alone
    (a function's body without the stub's ``def`` line)."""
    lines = (line.strip() for line in source.splitlines())
    return tuple(
        "".join(line.split()) for line in lines if line and line not in stub_lines and not line.startswith("#")
    )


def identical_answers(
    answers: Mapping[str, Mapping[str, str]],
    stubs: Mapping[str, Sequence[str]],
    canonical: Mapping[str, Sequence[str]] | None = None,
) -> dict[str, dict[str, tuple[str, ...]]]:
    """Possible copies: student -> another student -> the answer cells (grade ids, in ``stubs``'
    order) the two submitted identical, for pairs with at least :data:`COPY_MIN_ANSWERS` of them.
    ``answers``: student -> grade_id -> the answer cell. Cells are compared after each line's
    trailing whitespace is stripped; a cell counts only when it is not empty, not a stub handed out
    (``stubs``: grade_id -> its stubs), and its own lines (not blank, not lines of a stub, not
    nbgrader's solution delimiters) hold at least :data:`COPY_MIN_CHARS` characters other than
    spaces: a one-line answer many would write alike (``predicted_cs_r_wrong = 0.0``,
    ``return (ate_m <= eps) & (aoe_deg <= phi)``) never counts, nor does one of fewer than
    :data:`COPY_MIN_LINES` lines of code of its own (``return np.logical_and(ate_m <= eps, aoe_deg <= phi)``
    is long, and still what many write), one whose code (layout and comments aside) is the
    instructor's answer (``canonical``: grade_id -> its formulations, :func:`canonical_answers`: the
    exercise leads to it), or one :data:`COPY_COMMON` or more students gave alike. A cheap check of
    exact copies: a copy edited (renamed, reformatted, a comment added) is not found."""

    def stub_lines_of(gid: str) -> set[str]:
        return {line.strip() for s in stubs.get(gid, ()) for line in s.splitlines()} | _DELIMITERS

    # the instructor's answer as the detector reads an answer: whole, and without the stub's lines (the
    # `x = ...` placeholders an honest student deletes), its code (layout and comments aside) and its own lines
    canon: dict[str, set[Any]] = {}
    for gid, texts in (canonical or {}).items():
        keys: set[Any] = set()
        for t in texts:
            keys |= {k for k in (_code_key(t), _code_key(_without(t, stub_lines_of(gid)))) if k}
            keys.add(_own_code(t, stub_lines_of(gid)))
        canon[gid] = keys
    order = {gid: k for k, gid in enumerate(stubs)}
    same: dict[tuple[str, str], list[str]] = {}  # (grade_id, the answer) -> the students who gave it
    for student, cells in answers.items():
        for gid, source in cells.items():
            text = _normal(source)
            handed = stubs.get(gid, ())
            if not text or text in {_normal(s) for s in handed}:
                continue
            stub_lines = stub_lines_of(gid)
            mine = [line.strip() for line in text.splitlines() if line.strip() not in stub_lines]
            own = sum(len("".join(line.split())) for line in mine)
            code = sum(1 for line in mine if line and not line.startswith("#"))
            if own < COPY_MIN_CHARS or code < COPY_MIN_LINES:
                continue
            if canon.get(gid) and (
                _code_key(text) in canon[gid]
                or _code_key(_without(text, stub_lines)) in canon[gid]
                or _own_code(text, stub_lines) in canon[gid]
            ):
                continue
            same.setdefault((gid, text), []).append(student)
    pairs: dict[tuple[str, str], list[str]] = {}
    for (gid, _), who in same.items():
        if len(who) >= COPY_COMMON:
            continue
        for a, b in itertools.combinations(sorted(who), 2):
            pairs.setdefault((a, b), []).append(gid)
    out: dict[str, dict[str, tuple[str, ...]]] = {}
    for (a, b), gids in sorted(pairs.items()):
        if len(gids) >= COPY_MIN_ANSWERS:
            both = tuple(sorted(gids, key=lambda g: (order.get(g, len(order)), g)))
            out.setdefault(a, {})[b] = both
            out.setdefault(b, {})[a] = both
    return out


def _class_answers(course: Path, lab: str, results: Sequence[SubmissionResult]) -> dict[str, dict[str, str]]:
    """student -> their answer cells, for the graded submissions of ``lab`` (not the demonstration
    students, not a notebook that could not be read)."""
    out: dict[str, dict[str, str]] = {}
    for res in results:
        if res.lab != lab or res.error or res.student.startswith(DEMO_PREFIX):
            continue
        try:
            path = course / "submitted" / res.student / lab / f"{lab}.ipynb"
            nb, _ = read_notebook(read_submitted(path, course / "submitted"))
            out[res.student] = student_answers(nb)
        except Exception:  # noqa: BLE001 (changed since it was graded: compared next time)
            continue
    return out


def _release_bytes(release: Path) -> bytes:
    return b"".join(p.relative_to(release).as_posix().encode() + p.read_bytes()
                    for p in sorted(release.rglob("*")) if p.is_file())  # fmt: skip


def _grade_one(args: tuple[LabSpec, Path, Path, str, GradeSettings]) -> SubmissionResult:
    spec, release, notebook, student, settings = args
    # a pair of users per worker, held until it ends: concurrent sandboxes cannot read each other
    uid = claim_uids(settings.uid, 2) if settings.uid and can_isolate() else settings.uid
    return grade_submission(spec, release, notebook, student,
                            GradeSettings(settings.limits, settings.hidden, settings.secret, uid, settings.submitted))  # fmt: skip


def _secret(course: Path) -> str:
    """The course's secret (``.grading-secret``, made once, readable by its owner only)."""
    f = course / ".grading-secret"
    if not f.is_file():
        fd = os.open(f, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        with os.fdopen(fd, "w") as out:
            out.write(os.urandom(16).hex())
    return f.read_text().strip()


def grading_settings(course: Path, source: Path, settings: GradeSettings, secret: str) -> GradeSettings:
    """The settings every submission of ``course`` is graded with: ``settings`` with the course, the
    labs' ``source`` and the git database of any repository holding either
    (:func:`~lorisnb.tools.teaching.autograde.git_databases`) hidden from the sandbox, and the
    course's ``secret``."""
    hidden = (course, source, *git_databases([course, source]), *settings.hidden)
    return GradeSettings(settings.limits, tuple(Path(h) for h in hidden), secret, settings.uid, course / "submitted")


def grade_class(
    course: Path,
    source: Path,
    labs: Sequence[str] | None = None,
    *,
    settings: GradeSettings | None = None,
    jobs: int = 2,
    late: Mapping[str, LatePolicy] | None = None,
    progress: bool = True,
) -> list[Graded]:
    """Grade every submission of ``course`` (``submitted/<student>/<lab>/<lab>.ipynb``) against
    ``source/<lab>/<lab>.ipynb`` and ``course/release/<lab>/``; regrade only what changed."""
    course, source = course.resolve(), source.resolve()
    all_labs = sorted(p.name for p in source.iterdir() if (p / f"{p.name}.ipynb").is_file())
    labs = list(labs) if labs else all_labs
    secret = _secret(course)
    settings = grading_settings(course, source, settings or GradeSettings(), secret)
    todo, done = [], []
    stubs: dict[str, dict[str, list[str]]] = {}
    canonical: dict[str, dict[str, list[str]]] = {}
    for lab in labs:
        src_nb = source / lab / f"{lab}.ipynb"
        if not src_nb.is_file():
            raise ValidationError(f"lab {lab!r}: no {src_nb}")
        spec = lab_spec(src_nb)
        release = course / "release" / lab
        if not release.is_dir():
            raise ValidationError(f"lab {lab!r}: no release folder {release} (run `make student` first)")
        stubs[lab] = answer_stubs(spec, release)
        canonical[lab] = canonical_answers(spec)
        base = digest(src_nb.read_bytes(), _release_bytes(release), repr(settings.limits))
        for folder, why in _without_notebook(course / "submitted", lab, all_labs):  # 0 with why: never no row at all
            res = unreadable(spec, folder.parent.name, folder / f"{lab}.ipynb", FileNotFoundError(), 0.0, why=why)
            _write_result(course, res)
            done.append(res)
        for nb in sorted(course.glob(f"submitted/*/{lab}/{lab}.ipynb")):
            student = nb.parents[1].name
            try:  # a link (the notebook, or a folder above it) refused: never what it points to
                key = digest(base, read_submitted(nb, course / "submitted"), student)
            except (ValidationError, OSError) as exc:  # a link, a FIFO: this student's 0, and why
                res = unreadable(spec, student, nb, exc, 0.0, why=not_a_notebook(exc))
                _write_result(course, res)
                done.append(res)
                continue
            out = course / "graded" / student / lab / "result.json"
            if out.is_file():
                old = SubmissionResult.from_json(out.read_text())
                if old.digest == key:
                    done.append(old)
                    continue
            todo.append(((spec, release, nb, student, settings), key))
    from tqdm.auto import tqdm

    bar = tqdm(total=len(todo), desc="grading", unit="submission", disable=not progress or not todo)
    with bar, ProcessPoolExecutor(max_workers=max(1, jobs)) as pool:
        futures = {pool.submit(_grade_one, args): (args, key) for args, key in todo}
        for fut in as_completed(futures):
            args, key = futures[fut]
            try:
                res = fut.result()
            except ValidationError:  # the grader's set-up (the sandbox cannot read lorisnb...): every submission's
                raise
            except Exception as exc:  # noqa: BLE001 (this submission alone is not graded: 0, and why)
                res = unreadable(args[0], args[3], args[2], exc, 0.0)
            res.digest = "" if res.error else key  # not graded: tried again next time
            _write_result(course, res)
            done.append(res)
            bar.update()
    identical = {lab: identical_answers(_class_answers(course, lab, done), stubs[lab], canonical[lab]) for lab in labs}
    twins = {lab: same_variants([r.student for r in done if r.lab == lab]) for lab in labs}
    graded = []
    for res in sorted(done, key=lambda r: (r.lab, r.student)):
        stamp = f"submitted/{res.student}/{res.lab}/timestamp.txt"
        policy = (late or {}).get(res.lab)
        on_time = ""
        if policy:
            on_time = (f"so the late policy (due {policy.due.isoformat()}) could not be applied: counted as on time, "
                       "as a submission without a time is (check its time in the LMS or nbgrader's exchange)")  # fmt: skip
        notes, error = [], ""
        try:
            when = _read_time(course / stamp, policy.due.utcoffset() if policy else None, course / "submitted")
        except ValueError as exc:
            when, error = None, f"{stamp}: {exc}"
            notes.append(f"{error}: the submission's time is unknown" + (f", {on_time}" if policy else ""))
        if when is None and not error and policy:
            notes.append(f"no {stamp} (nbgrader collect and submit write it; a notebook put in submitted/ by hand "
                         f"has none): the submission's time is unknown, {on_time}")  # fmt: skip
        factor, days = policy.factor(when) if policy else (1.0, 0)
        lateness = max(0.0, (when - policy.due).total_seconds()) if policy and when else 0.0
        graded.append(Graded(res, when, days, factor, lateness, notes, error, when is None and policy is not None,
                             identical[res.lab].get(res.student, {}),
                             twins.get(res.lab, {}).get(res.student, ())))  # fmt: skip
        _write_feedback(course, res, notes)
    return graded


def _without_notebook(submitted: Path, lab: str, labs: Sequence[str] = ()) -> list[tuple[Path, str]]:
    """Each student's folder of ``lab`` (``submitted/<student>/<lab>/``) that holds no ``<lab>.ipynb``
    (a zip of it, another name), and each student's folder without a ``<lab>/`` folder that holds the
    lab's file (``<lab>.ipynb``, ``<lab>.zip``...) itself, or notebooks and no folder of any of
    ``labs`` (the course's), with why: such a student had no row in grades.csv and no word. Only the
    names of the folder's files are said, never read; a linked folder's are not even listed."""
    out = []
    for student in sorted(submitted.iterdir()) if submitted.is_dir() else []:
        folder = student / lab
        if not os.path.lexists(folder):  # no <lab>/: the notebook put in the student's folder itself?
            if student.is_dir() and not student.is_symlink():
                misplaced = _misplaced(student, lab, labs)
                if misplaced:
                    out.append((folder, f"{misplaced} is not where the grader looks: return it as "
                                        f"submitted/{student.name}/{lab}/{lab}.ipynb (a folder per lab, as nbgrader "
                                        "collects it), named as released"))  # fmt: skip
            continue
        if (folder / f"{lab}.ipynb").exists() or (folder / f"{lab}.ipynb").is_symlink():
            continue
        if student.is_symlink() or folder.is_symlink() or not folder.is_dir():
            out.append((folder, f"{student.name}/{lab} is a link or not a folder: refused, nothing in it read"))
            continue
        names = sorted(os.listdir(folder))
        found = ", ".join(names[:5]) + (f" and {len(names) - 5} more" if len(names) > 5 else "") if names else "nothing"
        out.append((folder, f"no notebook named {lab}.ipynb in {student.name}/{lab}/ (found: {found}); return the "
                            "notebook itself, named as released, not a zip or a copy under another name"))  # fmt: skip
    return out


def stray_files(submitted: Path) -> list[Path]:
    """The notebooks put straight in ``submitted/``, in no student's folder (``submitted/lab1.ipynb``):
    no student to grade them for, so no row; the grader names them (they were passed over without
    a word). Other files there (the course's ``README.md``) and hidden ones are left alone."""
    if not submitted.is_dir():
        return []
    return sorted(p for p in submitted.iterdir()
                  if not p.name.startswith(".") and p.suffix.lower() == ".ipynb" and not p.is_dir())  # fmt: skip


def _misplaced(student: Path, lab: str, labs: Sequence[str]) -> str:
    """The files of ``student``'s folder (which has no ``<lab>/``) that look like ``lab``'s
    submission, as ``<student>/<name>`` (the first three): those named after the lab, else, when the
    folder holds no folder of any lab of ``labs``, its notebooks; "" when none."""
    names = sorted(os.listdir(student))
    found = [n for n in names if n.lower().startswith(lab.lower())]
    if not found and not any(os.path.isdir(student / n) for n in names if n in labs):
        found = [n for n in names if n.lower().endswith(".ipynb")]
    shown = ", ".join(f"{student.name}/{n}" for n in found[:3]) + (
        f" and {len(found) - 3} more" if len(found) > 3 else ""
    )
    return shown


def _write_result(course: Path, res: SubmissionResult) -> None:
    folder = course / "graded" / res.student / res.lab
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "result.json").write_text(res.to_json())
    _write_feedback(course, res, ())


def _write_feedback(course: Path, res: SubmissionResult, extra: Sequence[str]) -> None:
    """``feedback.html``: each question's points and messages, the grader's notes, then ``extra``
    (the gradebook's notes on the submission's time); rewritten only when it changes."""
    folder = course / "graded" / res.student / res.lab
    folder.mkdir(parents=True, exist_ok=True)
    rows = "".join(
        f"<tr><td>{html.escape(s.question)}</td><td>{s.points:g} / {s.max_points:g}</td>"
        f"<td><pre>{html.escape(s.message)}</pre></td></tr>"
        for s in res.scores
    )
    notes = "".join(f"<li>{html.escape(n)}</li>" for n in [*res.notes, *extra])
    page = (
        f"<!doctype html><meta charset='utf-8'><title>{html.escape(res.lab)}: {html.escape(res.student)}</title>"
        f"<h1>{html.escape(res.lab)}: {res.points:g} / {res.max_points:g}</h1>"
        f"<table border=1><tr><th>question</th><th>points</th><th>what the checks said</th></tr>{rows}</table>"
        + (f"<h2>Notes</h2><ul>{notes}</ul>" if notes else "")
    )
    f = folder / "feedback.html"
    if not f.is_file() or f.read_text() != page:
        f.write_text(page)
    _release_copy(course, res, page)


#: what nbgrader's ``release_feedback`` reads of each submission besides its page: copied from the submission
RELEASE_FILES = ("timestamp.txt", "submission_secret.txt")


def _release_copy(course: Path, res: SubmissionResult, page: str) -> None:
    """The page where ``nbgrader release_feedback <lab>`` looks for it: nbgrader's feedback folder,
    ``feedback/<student>/<lab>/<lab>.html`` (named after the notebook), with the submission's
    ``timestamp.txt`` and ``submission_secret.txt`` (which name the page in nbgrader's exchange).
    Only for a submission that came through the exchange (``nbgrader collect`` writes both files):
    without them ``release_feedback`` would stop at that page, handing out nobody's."""
    submitted = course / "submitted" / res.student / res.lab
    texts = {}
    for name in RELEASE_FILES:
        try:  # a link (or a folder above it) refused, as every file of a submission
            texts[name] = read_submitted(submitted / name, course / "submitted", limit=4096)
        except (ValidationError, OSError):
            return
    folder = course / "feedback" / res.student / res.lab
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in texts.items():
        if not (folder / name).is_file() or (folder / name).read_bytes() != text:
            (folder / name).write_bytes(text)
    f = folder / f"{res.lab}.html"
    if not f.is_file() or f.read_text() != page:
        f.write_text(page)


def _n(x: float) -> str:
    """A number as the LMS reads it: 4, 4.5, 0.8333 (no trailing .0)."""
    return f"{round(float(x), 4):g}"


def _split(name: str) -> tuple[str, str]:
    """(first, last) of a roster name: "Last, First" as written, else the last word is the last name
    (a name of one word is all last name)."""
    last, comma, first = name.strip().partition(",")
    if comma:
        return first.strip(), last.strip()
    first, _, last = name.strip().rpartition(" ")
    return first.strip(), last


@dataclass(frozen=True)
class LeftOut:
    """Who the LMS exports leave out: students not on the roster (every export), and students with no
    e-mail on it (Moodle's and Gradescope's, which find a student by e-mail: Moodle gives a row with
    no identifier to the user of the row before)."""

    not_on_roster: list[str]
    no_email: list[str]

    def __bool__(self) -> bool:
        return bool(self.not_on_roster or self.no_email)


def write_exports(course: Path, graded: Sequence[Graded], roster: Mapping[str, Student] | None = None) -> LeftOut:
    """``grades.csv``, ``grades-demo.csv`` and the LMS exports; returns whom the exports leave out."""
    demo = [g for g in graded if g.result.student.startswith(DEMO_PREFIX)]
    real = [g for g in graded if not g.result.student.startswith(DEMO_PREFIX)]
    left_out = sorted({g.result.student for g in real if roster is not None and g.result.student not in roster})
    for rows, name in ((real, "grades.csv"), (demo, "grades-demo.csv")):
        _write_grades(course / name, rows, roster or {})
    exports = course / "exports"
    exports.mkdir(exist_ok=True)
    no_email: set[str] = set()
    for lab in sorted({g.result.lab for g in real}):
        rows = [g for g in real if g.result.lab == lab and g.result.student not in left_out]
        people = [(roster or {}).get(g.result.student, Student(g.result.student)) for g in rows]
        _canvas(exports / f"{lab}-canvas.csv", lab, rows, people)
        mailed = [(g, p) for g, p in zip(rows, people, strict=True) if p.email]
        no_email |= {p.id for p in people if not p.email}
        _moodle(exports / f"{lab}-moodle.csv", lab, [g for g, _ in mailed], [p for _, p in mailed])
        _gradescope(exports / f"{lab}-gradescope.csv", [g for g, _ in mailed], [p for _, p in mailed])
    return LeftOut(left_out, sorted(no_email))


def _write_grades(path: Path, rows: Sequence[Graded], roster: Mapping[str, Student]) -> None:
    questions = list(dict.fromkeys(s.question for g in rows for s in g.result.scores))
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(["student", "name", "email", "lab", *questions, "raw_score", "submitted", "days_late",
                    "late_factor", "score", "max_score", "isolation", "notes"])  # fmt: skip
        for g in rows:
            who = roster.get(g.result.student, Student(g.result.student))
            per = {s.question: s.points for s in g.result.scores}
            w.writerow([g.result.student, who.name, who.email, g.result.lab,
                        *[_n(per[q]) if q in per else "" for q in questions], _n(g.result.points),
                        g.submitted.isoformat() if g.submitted else "", g.days_late, _n(g.factor),
                        _n(g.score), _n(g.result.max_points), g.result.isolation,
                        " | ".join([*grader_notes(g.result), *g.notes, *g.leak_notes, *g.variant_notes,
                                    *g.copy_notes])])  # fmt: skip


#: A grader's note of an answer left as the handed-out stub (``raise NotImplementedError()``): its 0 says it.
_STUB_NOTE = re.compile(r"[^:\s]+: NotImplementedError:\s*")


def grader_notes(result: SubmissionResult) -> list[str]:
    """The grader's notes of a submission for the instructor's ``grades.csv`` (a sandbox ended, an
    answer's id carried by two cells, an output cut, a parameter drawing another variant): all of
    its feedback's but those of answers left as the stub, which their 0 points say."""
    return [n for n in result.notes if not _STUB_NOTE.fullmatch(n)]


def _canvas(path: Path, lab: str, rows: Sequence[Graded], people: Sequence[Student]) -> None:
    """Canvas' gradebook import layout: Student, ID, SIS User ID, SIS Login ID, Section, then one
    column per assignment; a "Points Possible" row first."""
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(["Student", "ID", "SIS User ID", "SIS Login ID", "Section", lab])
        w.writerow(["    Points Possible", "", "", "", "", _n(rows[0].result.max_points) if rows else ""])
        for g, p in zip(rows, people, strict=True):
            w.writerow([p.name or p.id, "", p.sis_id or p.id, p.login_id or p.email, p.section, _n(g.score)])


def _moodle(path: Path, lab: str, rows: Sequence[Graded], people: Sequence[Student]) -> None:
    """Moodle's grade import (Grades > Import > CSV file): a header, a user identifier column
    (map "Email address" to email), a grade column and its feedback column."""
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(["First name", "Last name", "ID number", "Email address", lab, f"{lab} feedback"])
        for g, p in zip(rows, people, strict=True):
            first, last = _split(p.name)
            fb = "; ".join(f"{s.question}: {s.points:g}/{s.max_points:g}" for s in g.result.scores)
            if g.days_late:
                fb += f"; {g.days_late} day(s) late: x{g.factor:g}"
            w.writerow([first, last, p.sis_id or p.id, p.email, _n(g.score), fb])


def _gradescope(path: Path, rows: Sequence[Graded], people: Sequence[Student]) -> None:
    """Gradescope's assignment score layout: First Name, Last Name, SID, Email, Total Score, Max
    Points, Status, Submission Time, Lateness (H:M:S), then one column per question
    ("1: name (p pts)")."""
    questions = list(dict.fromkeys(s.question for g in rows for s in g.result.scores))
    maxp = {s.question: s.max_points for g in rows for s in g.result.scores}
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(["First Name", "Last Name", "SID", "Email", "Total Score", "Max Points", "Status",
                    "Submission Time", "Lateness (H:M:S)",
                    *[f"{k}: {q} ({maxp[q]:g} pts)" for k, q in enumerate(questions, 1)]])  # fmt: skip
        for g, p in zip(rows, people, strict=True):
            first, last = _split(p.name)
            per = {s.question: s.points for s in g.result.scores}
            sec = int(g.lateness_s)
            hms = f"{sec // 3600}:{sec % 3600 // 60:02d}:{sec % 60:02d}"
            w.writerow([first, last, p.sis_id or p.id, p.email, _n(g.score), _n(g.result.max_points), "Graded",
                        g.submitted.isoformat() if g.submitted else "", hms,
                        *[_n(per[q]) if q in per else "" for q in questions]])  # fmt: skip
