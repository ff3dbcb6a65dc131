"""Measure how long a class takes to grade (teaching/README.md, "Grading"): write N generated
submissions of a lab (most right, some with the typical mistakes of demo_submissions.py, one with an
endless loop) into a temporary course and grade them with grade.py's settings. Writes nothing in the
checkout.

    python teaching/time_class.py [N=30] [--jobs 2] [--lab lab1_lifelong_metrics]
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from pathlib import Path

import nbformat

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from demo_submissions import MISTAKES, fill_cells  # noqa: E402

from lorisnb.tools.teaching.autograde import GradeSettings  # noqa: E402
from lorisnb.tools.teaching.gradebook import grade_class  # noqa: E402
from lorisnb.tools.teaching.sandbox import Limits, can_isolate  # noqa: E402

LOOP = {"C1_cs_r": "while True:\n    pass\n"}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("n", type=int, nargs="?", default=30, help="students (default 30)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--lab", default="lab1_lifelong_metrics")
    ap.add_argument("--timeout", type=float, default=60.0, help="seconds per answer cell (grade.py's default)")
    a = ap.parse_args()
    if a.n < 1 or a.jobs < 1:
        ap.error("n and --jobs must be >= 1")
    source = HERE / "source"
    src_nb = source / a.lab / f"{a.lab}.ipynb"
    with tempfile.TemporaryDirectory(prefix="lorisnb-class-") as tmp:
        course = Path(tmp)
        (course / "release" / a.lab).mkdir(parents=True)
        for k in range(a.n):
            nb = nbformat.read(src_nb, as_version=4)  # the instructor's answers...
            if k % 4 == 3:
                nb = fill_cells(nb, MISTAKES)  # ...or the typical mistakes (a quarter of the class)
            if k == a.n - 1:
                nb = fill_cells(nb, LOOP)  # and one endless loop
            dest = course / "submitted" / f"s{k + 1:03d}" / a.lab / f"{a.lab}.ipynb"
            dest.parent.mkdir(parents=True)
            nbformat.write(nb, dest)
        t0 = time.monotonic()
        graded = grade_class(
            course, source, [a.lab], settings=GradeSettings(Limits(cell_timeout_s=a.timeout)), jobs=a.jobs
        )
        seconds = time.monotonic() - t0
        scores = sorted(g.score for g in graded)
        shutil.rmtree(course / "graded")
    print(
        f"{len(graded)} submissions of {a.lab} graded in {seconds:.0f} s ({seconds / len(graded):.1f} s each, "
        f"{a.jobs} at once; isolation: {'full' if can_isolate() else 'limits only'}); scores {scores[0]:g}..{scores[-1]:g}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
