"""Many small files (issues 47 and 48): a folder of N copies of one real icra20 result file (each in
its own algorithm folder, as a lab's sweep of configurations writes them) evaluated by ``lorisnb
evaluate`` in a whole process, against parsing the same files alone (:func:`lorisnb.io.read_openloris`
in a loop), for several N: the time per file must stay flat as N grows (linear in the files), and
the evaluation within 2x of the parsing (issue 47: "a folder of 5,000 small files within 2x of only
parsing them"), with the peak resident memory of the evaluation's largest process (the one
collecting the results: it holds only the scores when the command only writes the table).

    python benchmarks/many_files.py [--poses P] [--runs R] [N ...]      (default 500 2000 5000)

``--poses P`` keeps only the file's first P poses (its header kept): tiny files, where the
per-file cost is all there is. ``--runs R``: each N evaluated and parsed R times in alternation
(medians and the smallest ratio printed). ``make bench`` runs 5,000 files 3 times
(:func:`bench_row`).
"""

from __future__ import annotations

import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from lorisnb.io import find_data, read_openloris

SOURCE = ("per-seq", "orbslam2_rgbd", "cafe_1_1_orbslam2-original.txt")


def make_folder(root: Path, n: int, poses: int | None = None) -> list[Path]:
    src = find_data().icra20.joinpath(*SOURCE)
    text = None
    if poses is not None:  # the header (key: value lines and blanks) and the first poses
        lines = src.read_text().splitlines(keepends=True)
        head = next(i for i, line in enumerate(lines) if line.strip() and ":" not in line)
        text = "".join(lines[: head + poses])
    files = []
    for i in range(n):
        d = root / f"config_{i:05d}"
        d.mkdir(parents=True)
        if text is None:
            files.append(Path(shutil.copy(src, d / src.name)))
        else:
            (d / src.name).write_text(text)
            files.append(d / src.name)
    return files


def evaluate_seconds(results: Path, out: Path) -> tuple[float, int]:
    """One whole ``lorisnb evaluate --csv`` process over ``results``: wall seconds and the peak
    resident memory of its largest process (KiB); exits with its error where it fails."""
    lorisnb = [sys.executable, "-m", "lorisnb.cli"]
    out.unlink(missing_ok=True)
    t = time.perf_counter()
    with tempfile.TemporaryFile() as err:
        child = subprocess.Popen([*lorisnb, "evaluate", "--no-progress", "--csv", str(out), str(results)],
                                 stdout=subprocess.DEVNULL, stderr=err)  # fmt: skip
        _, status, usage = os.wait4(child.pid, 0)  # this run's own peak: the largest of its processes
        took = time.perf_counter() - t
        if os.waitstatus_to_exitcode(status) != 0:
            err.seek(0)
            raise SystemExit(err.read()[-2000:].decode(errors="replace"))
    return took, usage.ru_maxrss


def parse_seconds(files: list[Path]) -> float:
    """Parsing the files alone, in this process (:func:`lorisnb.io.read_openloris` in a loop)."""
    t = time.perf_counter()
    for f in files:
        read_openloris(f, warn=False)
    return time.perf_counter() - t


def measure(n: int, runs: int, poses: int | None = None) -> dict:
    """``runs`` evaluations of a folder of ``n`` files, each followed by a parse of the same files
    (in alternation: this machine's speed drifts by a quarter within an hour, and a ratio of two
    runs side by side drifts less than either time): their seconds and ratios."""
    with tempfile.TemporaryDirectory(prefix="lorisnb-many-") as tmp:
        files = make_folder(Path(tmp) / "results", n, poses)
        ev, parse, peak = [], [], 0
        for _ in range(runs):
            took, rss = evaluate_seconds(Path(tmp) / "results", Path(tmp) / "out.csv")
            ev.append(took)
            parse.append(parse_seconds(files))
            peak = max(peak, rss)
    ratios = [a / b for a, b in zip(ev, parse, strict=True)]
    return dict(n=n, evaluate=ev, parse=parse, ratios=ratios, peak_mb=peak / 1024)


def main(sizes: list[int], poses: int | None = None, runs: int = 1) -> int:
    print(f"{'files':>7s} {'evaluate s':>11s} {'ms/file':>8s} {'parse s':>8s} {'ms/file':>8s} {'ratio':>6s} "
          f"{'min':>6s} {'peak MB':>8s}   (medians of {runs} alternating run(s))")  # fmt: skip
    per_file = []
    for n in sizes:
        m = measure(n, runs, poses)
        ev, parse = statistics.median(m["evaluate"]), statistics.median(m["parse"])
        per_file.append(ev / n)
        print(f"{n:7d} {ev:11.2f} {1e3 * ev / n:8.2f} {parse:8.2f} {1e3 * parse / n:8.2f} "
              f"{statistics.median(m['ratios']):6.2f} {min(m['ratios']):6.2f} {m['peak_mb']:8.0f}")  # fmt: skip
    print(f"time per file, largest N over smallest: {per_file[-1] / per_file[0]:.2f} (linear: about 1)")
    return 0


def bench_row(n: int = 5000, runs: int = 3) -> None:
    """``make bench``'s row of issue 47's goal: ``n`` real files evaluated within 2x of parsing them."""
    import floors

    m = measure(n, runs)
    print(f"\n{n:,} small files (copies of one real icra20 file), `evaluate --csv` / parsing them alone, "
          f"{runs} alternating runs: evaluate {min(m['evaluate']):.2f}-{max(m['evaluate']):.2f} s, parse "
          f"{min(m['parse']):.2f}-{max(m['parse']):.2f} s")  # fmt: skip
    floors.row(f"{n:,} small files, evaluate / parse only", min(m["ratios"]), statistics.median(m["ratios"]),
               "<= 2x", 2.0)  # fmt: skip


if __name__ == "__main__":
    argv = sys.argv[1:]
    poses, runs = None, 1
    while argv[:1] in (["--poses"], ["--runs"]):
        if argv[0] == "--poses":
            poses = int(argv[1])
        else:
            runs = int(argv[1])
        argv = argv[2:]
    raise SystemExit(main([int(a) for a in argv] or [500, 2000, 5000], poses, runs))
