"""Grade a class in the sandbox and write the grades an LMS takes (`make grade`; teaching/README.md,
"Grading").

    python grade.py COURSE [--lab LAB] [--jobs 2] [--timeout 60] [--budget 300] [--memory-mb 3072]
                    [--roster roster.csv] [--due 2026-12-01T23:59+01:00 --late-per-day 0.1 --late-max-days 5]
                    [--hide FOLDER ...]

COURSE holds release/<lab>/ and submitted/<student>/<lab>/<lab>.ipynb; the labs' sources are
teaching/source/ (``--source``). Writes COURSE/graded/, grades.csv, grades-demo.csv, exports/.
Exit status 0 when every submission was graded, 1 otherwise (a message says why; a submission that
could not be graded, such as a notebook that is not JSON, scores 0, is named, and the others are
graded), 2 when an option is refused before anything is graded (a --due without a time zone, a
--late-per-day outside [0, 1], a --late-max-days below 0, a --lab with no source notebook or no
release folder, a --roster that cannot be read or is malformed, a --source or COURSE that is no folder). Warnings (the exit status stays 0) name the submissions whose time is unknown (a
timestamp.txt that is no time; with --due, how many have none: counted as on time), the submissions
whose folders name one id as the data variants take it (Alice and alice: the same numbers), the
submissions holding the instructor's nbgrader markers (the source notebook, with its solutions), and the
pairs whose answer cells are identical (possible copies: no points changed); grades.csv's notes
column says the same per student. The feedback pages are written where `nbgrader release_feedback`
hands them out (feedback/<student>/<lab>/<lab>.html) too.
"""

from __future__ import annotations

import argparse
import sys
from datetime import datetime
from pathlib import Path

from lorisnb.errors import ValidationError
from lorisnb.tools.teaching.autograde import GradeSettings
from lorisnb.tools.teaching.gradebook import (
    LatePolicy,
    Student,
    grade_class,
    read_roster,
    stray_files,
    write_exports,
)
from lorisnb.tools.teaching.sandbox import BUDGET_CELLS, BUDGET_MIN_S, Limits, can_isolate

HERE = Path(__file__).resolve().parent


def _positive(kind: type) -> object:
    def parse(text: str) -> object:
        value = kind(text)
        if not value > 0:
            raise argparse.ArgumentTypeError(f"must be > 0, got {text}")
        return value

    return parse


def _options(a: argparse.Namespace) -> tuple[dict[str, LatePolicy] | None, dict[str, Student] | None, Limits]:
    """The late policy per lab, the roster and the limits the options give; a refused option raises
    (ValidationError, ValueError or OSError) with a message naming it."""
    for what, folder in (("COURSE", a.course), ("--source", a.source)):
        if not folder.is_dir():
            raise ValidationError(f"{what} {folder} is not a folder")
    labs = a.lab or sorted(p.name for p in a.source.iterdir() if (p / f"{p.name}.ipynb").is_file())
    for lab in a.lab or []:
        if not (a.source / lab / f"{lab}.ipynb").is_file():
            known = sorted(p.name for p in a.source.iterdir() if (p / f"{p.name}.ipynb").is_file())
            raise ValidationError(f"--lab {lab}: no {a.source / lab / f'{lab}.ipynb'} (the labs: {', '.join(known)})")
    for lab in labs:
        if not (a.course / "release" / lab).is_dir():
            raise ValidationError(
                f"lab {lab!r}: no release folder {a.course / 'release' / lab} (run `make student` first)"
            )
    late = None
    if a.due is not None:
        try:
            due = datetime.fromisoformat(a.due)
        except ValueError:
            raise ValidationError(
                f"--due {a.due!r} is not an ISO 8601 date and time (write e.g. 2026-12-01T23:59+01:00)"
            ) from None
        try:
            policy = LatePolicy(due, a.late_per_day or 0.0, a.late_max_days)
        except ValidationError as exc:
            raise ValidationError(f"--due/--late-per-day/--late-max-days: {exc}") from None
        late = {lab: policy for lab in labs}
    roster = None
    if a.roster:
        try:
            roster = read_roster(a.roster)
        except OSError as exc:
            raise ValidationError(f"--roster {a.roster}: {exc.strerror or exc}") from None
    limits = Limits(cell_timeout_s=a.timeout, budget_s=a.budget, memory_bytes=a.memory_mb * 1024**2)
    return late, roster, limits


HONEST_CELL_S = 60.0  # below this --timeout, honest answer cells were stopped (E1's fine scan: 13 to 37 s measured)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("course", type=Path, nargs="?", default=HERE, help="the course folder (default: teaching/)")
    ap.add_argument("--source", type=Path, default=HERE / "source", help="the labs' instructor versions")
    ap.add_argument("--lab", action="append", help="grade this lab only (repeatable; default: every lab)")
    ap.add_argument("--jobs", type=_positive(int), default=2, help="submissions graded at once (default 2)")
    ap.add_argument("--timeout", type=_positive(float), default=60.0, help="seconds per cell (default 60)")
    ap.add_argument("--budget", type=_positive(float), help="seconds a submission's code may take in all "
                    f"(default {BUDGET_CELLS} x --timeout, at least {BUDGET_MIN_S:g})")  # fmt: skip
    ap.add_argument("--memory-mb", type=_positive(int), default=3072, help="address space per sandbox, MiB")
    ap.add_argument("--roster", type=Path, help="CSV with id,name,email[,sis_id,login_id,section]")
    ap.add_argument("--due", help="due date, ISO 8601 with a time zone (e.g. 2026-12-01T23:59+01:00)")
    ap.add_argument("--late-per-day", type=float, help="fraction of the points lost per started day late")
    ap.add_argument("--late-max-days", type=int, help="no points after this many days late")
    ap.add_argument("--hide", type=Path, action="append", default=[], help="another folder the sandbox must hide")
    ap.add_argument("--no-progress", action="store_true")
    a = ap.parse_args(argv)
    if (a.late_per_day is not None or a.late_max_days is not None) and a.due is None:
        ap.error("--late-per-day and --late-max-days need --due")
    if a.timeout < HONEST_CELL_S:
        print(
            f"warning: --timeout {a.timeout:g} s is below {HONEST_CELL_S:g} s: honest answer cells have taken up to "
            "37 s on a busy 2-core machine (E1's scan on a 2 mm grid, as its hint suggests), and a cell stopped "
            "at its limit scores 0 (teaching/README.md, 'A slow submission is stopped at its budget'); lower "
            "--budget instead to bound a class's time",
            file=sys.stderr,
        )
    try:  # the options, all refused (exit 2) before anything is graded
        late, roster, limits = _options(a)
    except (ValidationError, ValueError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    try:
        if not can_isolate():
            print(
                "warning: not root on Linux with unshare/setpriv: submissions run with time and memory limits "
                "but WITHOUT isolation (they can read and write what this user can; teaching/README.md)",
                file=sys.stderr,
            )
        graded = grade_class(a.course, a.source, a.lab, settings=GradeSettings(limits, tuple(a.hide)),
                             jobs=a.jobs, late=late, progress=not a.no_progress)  # fmt: skip
        left_out = write_exports(a.course, graded, roster)
    except (ValidationError, ValueError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    for g in graded:
        print(f"{g.result.student:24s} {g.result.lab}: {g.score:g} / {g.result.max_points:g}"
              + (f" ({g.days_late} day(s) late)" if g.days_late else ""))  # fmt: skip
    if left_out.not_on_roster:
        print(f"not on the roster, left out of the LMS exports: {', '.join(left_out.not_on_roster)}", file=sys.stderr)
    if left_out.no_email and roster is None:
        print(
            "no --roster: the Moodle and Gradescope exports, which find students by e-mail, are empty", file=sys.stderr
        )
    elif left_out.no_email:
        print(f"no e-mail on the roster, left out of the Moodle and Gradescope exports (they find students by "
              f"e-mail): {', '.join(left_out.no_email)}", file=sys.stderr)  # fmt: skip
    for g in graded:
        if g.time_error:
            print(f"warning: {g.result.student}: {g.notes[0]}", file=sys.stderr)
    no_time = [g.result.student for g in graded if g.no_time and not g.time_error]
    if no_time:
        print(f"warning: {len(no_time)} submission(s) have no timestamp.txt, so --due could not be applied to them: "
              f"counted as on time ({', '.join(no_time)}; nbgrader collect writes it)", file=sys.stderr)  # fmt: skip
    leaked = [g.result.student for g in graded if g.result.instructor_markers]
    if leaked:
        print(f"warning: {len(leaked)} submission(s) hold the instructor's nbgrader markers (### BEGIN SOLUTION, ### BEGIN "
              f"HIDDEN TESTS): the instructor's source notebook, or cells copied from it, so the lab's solutions "
              f"leaked; graded as any submission, an instructor decides ({', '.join(leaked)}; grades.csv's notes say "
              "which cells)", file=sys.stderr)  # fmt: skip
    alike = sorted(
        {(g.result.lab, tuple(sorted((g.result.student, *g.same_variant)))) for g in graded if g.same_variant}
    )
    for lab, students in alike:
        print(f"warning: {lab}: the submissions {', '.join(repr(s) for s in students)} got the same data variant (their "
              "folders name the same id once spaces and case are set aside, as the variant's seed is drawn): one "
              "student under two folders, or ids to tell apart (rename a folder and regrade); grades.csv's notes "
              "say so", file=sys.stderr)  # fmt: skip
    pairs = sorted({(g.result.lab, *sorted((g.result.student, other)), ", ".join(gids))
                    for g in graded for other, gids in g.identical.items()})  # fmt: skip
    if pairs:
        shown = "; ".join(f"{a} and {b} ({lab}: {gids})" for lab, a, b, gids in pairs[:10])
        print(f"warning: {len(pairs)} pair(s) of submissions with identical answer cells, possible copies (no points "
              f"changed: an instructor decides; grades.csv's notes column names them): {shown}"
              + (f"; and {len(pairs) - 10} more" if len(pairs) > 10 else ""), file=sys.stderr)  # fmt: skip
    failed = [g.result for g in graded if g.result.error]
    for res in failed:
        print(f"not graded (0 points): {res.error}", file=sys.stderr)
    stray = stray_files(a.course / "submitted")
    for f in stray:
        print(f"not graded: {f}: a notebook straight in submitted/, in no student's folder; nbgrader collects "
              "submitted/<student>/<lab>/<lab>.ipynb: move it into its student's folder and grade again",
              file=sys.stderr)  # fmt: skip
    print(f"{len(graded) - len(failed)} submission(s) graded: {a.course / 'grades.csv'}, {a.course / 'exports'}")
    if failed:
        print(f"{len(failed)} submission(s) could not be graded (named above): they score 0", file=sys.stderr)
    return 1 if failed or stray else 0


if __name__ == "__main__":
    sys.exit(main())
