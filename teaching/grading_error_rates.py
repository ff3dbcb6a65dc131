"""How often lab 1's grader is wrong (teaching/README.md, "How often a grade is wrong"): a corpus of
right answers written in many ways and of wrong ones (the typical mistakes, slips, perturbed and
copied numbers), graded at many students' data variants by the grader's own code and sandboxes
(:mod:`lorisnb.tools.teaching.errorrates`), then a few generated submissions graded whole by
`make grade`'s route, and forged submissions (answers whose code writes the grader's replies itself,
one submission per technique). Prints the table of false fails and false passes per question, with 95 %
Wilson intervals, and every grading error found. Writes nothing in the checkout.

    python teaching/grading_error_rates.py [--students 12] [--submissions 4] [--jobs 2] [--quick] [--no-forgeries]
"""

from __future__ import annotations

import argparse
import datetime
import sys
import warnings
from pathlib import Path

from tqdm import tqdm

from lorisnb.errors import LorisWarning
from lorisnb.tools.teaching.errorrates import (
    LAB,
    errors_found,
    forgery_route,
    forgery_summary,
    grade_route,
    measure,
    rates,
    route_summary,
    table,
)

HERE = Path(__file__).resolve().parent


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--students", type=int, default=12, help="student ids whose variants are graded (default 12)")
    ap.add_argument("--submissions", type=int, default=4, help="generated submissions graded by make grade's route")
    ap.add_argument("--jobs", type=int, default=2, help="submissions graded at once (default 2)")
    ap.add_argument("--quick", action="store_true", help="2 students, no submission, no forgery (about a minute)")
    ap.add_argument(
        "--no-forgeries",
        action="store_true",
        help="leave out the forged submissions (one per technique, graded whole: about 2 minutes)",
    )
    a = ap.parse_args(argv)
    if a.quick:
        a.students, a.submissions = 2, 0
    if a.students < 1 or not 0 <= a.submissions <= a.students:
        ap.error("--students must be >= 1 and --submissions between 0 and --students")
    warnings.simplefilter("ignore", LorisWarning)
    source = HERE / "source"
    measured = measure(source / LAB / f"{LAB}.ipynb", a.students, progress=lambda x, **kw: tqdm(x, **kw))
    if a.submissions:
        measured.route = grade_route(source, measured, a.submissions, a.jobs)
    print(f"\nLab {LAB}, {a.students} students' variants, {datetime.date.today()}, isolation {measured.isolation}, "
          f"{measured.seconds:.0f} s for the corpus:\n")  # fmt: skip
    print(table(rates(measured.verdicts)))
    found = errors_found(measured.verdicts)
    print(f"\n{len(found)} grading error(s) found" + (":" if found else ""))
    for line in found:
        print(f"  {line}")
    if measured.route:
        print("\n" + route_summary(measured.route))
    if not (a.quick or a.no_forgeries):
        print("\n" + forgery_summary(forgery_route(source, jobs=a.jobs, progress=True)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
