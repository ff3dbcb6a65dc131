"""The real workload, first in ``make bench`` (issue 47): the bundled icra20 tree as users run it,
before any synthetic file.

- the whole tree in a whole process: ``lorisnb evaluate --scale auto --no-progress TREE``, wall
  time (best of several: the machine is shared) and the CPU of the process and its workers,
  beside an interpreter that only imports numpy (the floor of any run);
- the tree's 223 small files, parse only: lorisnb's reader (:func:`lorisnb.io.read_openloris`)
  against the public floor, ``pyarrow.csv.read_csv`` of each file's pose lines (one thread, the
  lines already cut out: its parse alone), side by side in alternation, CPU seconds;
- one threshold setting over the tree (:func:`lorisnb.core.score`);
- one slider change of the threshold explorer on the full data: the scene's table re-scored and
  its figure redrawn to the PNG the widget shows (goal 0.2 s);
- ``lorisnb sweep`` of 100 eps x 100 phi over the tree written to CSV (goal 60 s);
- the report, ``lorisnb report`` on the bundled data (:func:`floors.bench_report`).

Run alone: ``python benchmarks/workload.py`` (``LORISNB_BENCH_REPORT=0`` leaves out the report).
"""

from __future__ import annotations

import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

import floors
import numpy as np

LORISNB = floors.LORISNB


def _child_run(args: list[str]) -> tuple[float, float]:
    """Wall and CPU seconds (user + system, its worker processes included) of a command."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    subprocess.run(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime


def bench_whole_tree(root: Path, runs: int = 5) -> None:
    """``lorisnb evaluate`` over the tree in a whole process, against ``python -c 'import numpy'``."""
    tree = [LORISNB, "evaluate", "--scale", "auto", "--no-progress", str(root)]
    floor = [sys.executable, "-c", "import numpy"]
    walls, cpus, floor_walls = [], [], []
    for _ in range(runs):  # in alternation: a ratio of neighbours drifts less than either time
        w, c = _child_run(tree)
        walls.append(w)
        cpus.append(c)
        floor_walls.append(_child_run(floor)[0])
    print(
        f"whole tree, whole process: {min(walls):.2f} s wall (median {statistics.median(walls):.2f} s), "
        f"{min(cpus):.2f} s CPU; importing numpy alone {min(floor_walls):.2f} s"
    )
    floors.row("whole icra20 tree, whole process, seconds", min(walls), statistics.median(walls), "<= 1.0 s", 1.0, "s")


def _pose_lines(path: Path) -> tuple[bytes, int]:
    """A result file's pose lines (no header, ``seq:`` or comment line), single spaces, and their width."""
    lines = [ln for ln in path.read_bytes().splitlines() if ln.strip() and ln[:1] != b"#" and b":" not in ln]
    body = b"\n".join(b" ".join(ln.split()) for ln in lines) + b"\n"
    return body, len(lines[0].split()) if lines else 0


def bench_small_files(root: Path, runs: int = 5) -> None:
    """Parse only, every file of the tree: lorisnb's reader against pyarrow's parse of the pose
    lines, CPU seconds of each pass, in alternation."""
    import warnings

    import pyarrow as pa
    import pyarrow.csv as pc

    from lorisnb.io import read_openloris
    from lorisnb.tools.evaluation.runner import result_files

    files = [p for p, _ in result_files([root])]
    bodies = [b for b in map(_pose_lines, files) if b[1]]

    def ours() -> None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            for p in files:
                read_openloris(p, warn=False)

    def theirs() -> None:
        for body, _ in bodies:
            pc.read_csv(
                pa.py_buffer(body),
                pc.ReadOptions(autogenerate_column_names=True, use_threads=False, block_size=len(body) + 1),
                pc.ParseOptions(delimiter=" "),
            )

    a, b = floors.alternate(ours, theirs, runs, time.process_time)
    lo, med = floors.ratios(a, b)
    size = sum(len(x) for x, _ in bodies)
    print(
        f"the tree's {len(files)} files, parse only: lorisnb {min(a):.3f} s CPU, pyarrow.csv on their pose lines "
        f"({size / 1e6:.0f} MB) {min(b):.3f} s, {min(a) / len(files) * 1e3:.1f} ms a file"
    )
    print(f"  icra20 files, parse only / pyarrow.csv's parse: min {lo:.2f}x, median {med:.2f}x")


def bench_one_setting_and_slider(root: Path, runs: int = 5) -> None:
    """One threshold setting over the tree, and one slider change of the threshold explorer: its
    scene re-scored and its figure redrawn (``results()``), then rendered to the PNG the widget
    shows (:func:`lorisnb.tools.notebook.start.figure_png`: 150 dpi, tight bounding box), wall
    time and this process's CPU of each part."""
    import warnings

    from lorisnb.core import score
    from lorisnb.tools.evaluation.runner import evaluate
    from lorisnb.tools.notebook.start import figure_png
    from lorisnb.tools.notebook.widgets import ThresholdExplorer

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ev = evaluate([root], scale="auto", progress=False)
        ev.sequences()  # the RPE pairs, computed once per session
        settings = []
        for _ in range(runs):
            t = time.perf_counter()
            score(ev.errors, eps="paper", phi=30.0)
            settings.append(time.perf_counter() - t)
        explorer = ThresholdExplorer(ev.errors, ev.durations(), eps="paper", scene="market")
        explorer.results()  # the scene's figure made, as the widget's first display does
        slides, cpu_results, cpu_png = [], [], []
        for k in range(runs):
            explorer.phi = 20.0 + k  # a slider moved: the scene re-scored and redrawn
            t, c = time.perf_counter(), time.process_time()
            _, fig = explorer.results()
            c1 = time.process_time()
            figure_png(fig)
            slides.append(time.perf_counter() - t)
            cpu_results.append(c1 - c)
            cpu_png.append(time.process_time() - c1)
    print(
        f"one threshold setting over the tree: {min(settings):.3f} s; one slider change: {min(slides):.3f} s wall "
        f"(CPU: re-scored and redrawn {min(cpu_results):.3f} s, its PNG {min(cpu_png):.3f} s)"
    )
    floors.row("one slider change (re-scored, redrawn, PNG), seconds", min(slides), statistics.median(slides),
               "<= 0.2 s", 0.2, "s")  # fmt: skip


def bench_sweep_csv(root: Path, folder: Path) -> None:
    """``lorisnb sweep`` of 100 eps x 100 phi over the whole tree written to CSV, in a whole
    process: wall seconds, the file's size (goal: at most 60 s)."""
    out = folder / "sweep.csv"
    eps = ",".join(f"{v:.4g}" for v in np.linspace(0.05, 5.0, 100))
    phi = ",".join(f"{v:.4g}" for v in np.linspace(1.0, 100.0, 100))
    cmd = [LORISNB, "sweep", "--scale", "auto", "--no-progress", "--eps", eps, "--phi", phi, "--csv", str(out),
           str(root)]  # fmt: skip
    wall, cpu = _child_run(cmd)
    size = out.stat().st_size if out.exists() else 0
    out.unlink(missing_ok=True)
    print(f"sweep 100 eps x 100 phi over the tree to CSV: {wall:.1f} s wall, {cpu:.1f} s CPU, {size / 1e9:.2f} GB")
    floors.row("sweep 100 eps x 100 phi to CSV, seconds", wall, wall, "<= 60 s", 60.0, "s")


def main(root: Path, folder: Path) -> None:
    print("the real workload (the bundled icra20 tree):")
    bench_whole_tree(root)
    bench_small_files(root)
    bench_one_setting_and_slider(root)
    bench_sweep_csv(root, folder)
    if os.environ.get("LORISNB_BENCH_REPORT", "1") != "0":
        floors.bench_report(folder)


if __name__ == "__main__":
    import tempfile

    sys.path.insert(0, str(Path(__file__).parent))
    from lorisnb.io import find_data

    with tempfile.TemporaryDirectory(prefix="lorisnb-bench-") as tmp:
        main(find_data().icra20, Path(tmp))
    floors.print_tables()
