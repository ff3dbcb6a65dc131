"""Many small files (issues 47 and 48): a folder of N copies of one real icra20 result file (each in
its own algorithm folder, as a lab's sweep of configurations writes them) evaluated by ``lorisnb
evaluate`` in a whole process, against parsing the same files alone (:func:`lorisnb.io.read_openloris`
in a loop), for several N: the time per file must stay flat as N grows (linear in the files), and
the evaluation within 2x of the parsing (issue 47: "a folder of 5,000 small files within 2x of only
parsing them"), with the peak resident memory of the evaluation's largest process (the one
collecting the results: it holds only the scores when the command only writes the table).

    python benchmarks/many_files.py [--poses P] [N ...]      (default 500 2000 5000)

``--poses P`` keeps only the file's first P poses (its header kept): tiny files, where the
per-file cost is all there is.
"""

from __future__ import annotations

import os
import shutil
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


def main(sizes: list[int], poses: int | None = None) -> int:
    lorisnb = [sys.executable, "-m", "lorisnb.cli"]
    print(f"{'files':>7s} {'evaluate s':>11s} {'ms/file':>8s} {'parse s':>8s} {'ms/file':>8s} {'ratio':>6s} "
          f"{'peak MB':>8s}")  # fmt: skip
    per_file = []
    for n in sizes:
        with tempfile.TemporaryDirectory(prefix="lorisnb-many-") as tmp:
            files = make_folder(Path(tmp) / "results", n, poses)
            t = time.perf_counter()
            with tempfile.TemporaryFile() as err:
                child = subprocess.Popen([*lorisnb, "evaluate", "--no-progress", "--csv", str(Path(tmp) / "out.csv"),
                                          str(Path(tmp) / "results")], stdout=subprocess.DEVNULL, stderr=err)  # fmt: skip
                _, status, usage = os.wait4(child.pid, 0)  # this run's own peak: the largest of its processes
                child.returncode = os.waitstatus_to_exitcode(status)
                ev = time.perf_counter() - t
                if child.returncode != 0:
                    err.seek(0)
                    print(err.read()[-2000:].decode(errors="replace"), file=sys.stderr)
                    return 1
            t = time.perf_counter()
            for f in files:
                read_openloris(f, warn=False)
            parse = time.perf_counter() - t
        per_file.append(ev / n)
        print(f"{n:7d} {ev:11.2f} {1e3 * ev / n:8.2f} {parse:8.2f} {1e3 * parse / n:8.2f} {ev / parse:6.2f} "
              f"{usage.ru_maxrss / 1024:8.0f}")  # fmt: skip
    print(f"time per file, largest N over smallest: {per_file[-1] / per_file[0]:.2f} (linear: about 1)")
    return 0


if __name__ == "__main__":
    argv = sys.argv[1:]
    poses = None
    if argv[:1] == ["--poses"]:
        poses, argv = int(argv[1]), argv[2:]
    raise SystemExit(main([int(a) for a in argv] or [500, 2000, 5000], poses))
