"""Issue 27's figures: lorisnb against its floors, measured side by side in the same run.

Each figure is a ratio of lorisnb's time (or memory) to a baseline's, both run in alternation
(lorisnb, baseline, lorisnb, baseline, ...), and printed with the smallest and the median ratio
over the runs (this machine is shared; a ratio of two runs next to each other drifts less than
either time). Baselines:

- reading: the fastest public reader (the one of the smallest median time, its times run by run
  against lorisnb's), of pandas' fastest exact parse of the same
  file, ``pd.read_csv(path, sep=" ", header=None, engine="c")``, ``pyarrow.csv.read_csv`` with its
  threads, and ``polars.read_csv`` with its threads where polars is installed (``make bench``
  installs it), columns to numpy (``sep=","`` and the header line skipped for EuRoC), each file in
  a new process where all run (:func:`bench_readers`);
- a small pair, ``--help``: ``evo_ape`` (evo's command line), whole processes, wall time and peak
  resident memory;
- a large pair: a process that only parses both files with that pandas call;
- nearest association: the rule over every candidate pair (the implementation before issue 27).

Growth from 10k to 10M poses: whole ``lorisnb evaluate`` processes on simulated TUM pairs, time,
time per pose and peak memory per pose above the process's start-up (importing what the run
imports: pandas for files larger than numpy reads). ``LORISNB_BENCH_HUGE=0``
leaves out the 10M-pose pair (two 0.9 GB files).
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

ROWS: list[tuple[str, str, str, str, bool]] = []  # (figure, min, median, goal, met)


def row(name: str, lo: float, med: float, goal: str, limit: float, unit: str = "x") -> None:
    fmt = (lambda v: f"{v:.2f}x") if unit == "x" else (lambda v: f"{v:,.0f} {unit}" if v >= 10 else f"{v:.2f} {unit}")
    met = med <= limit
    ROWS.append((name, fmt(lo), fmt(med), goal, met))
    print(f"  {name}: min {fmt(lo)}, median {fmt(med)} (goal {goal}) {'met' if met else 'NOT MET'}")


def alternate(
    ours: Callable[[], object], theirs: Callable[[], object], runs: int, clock: Callable[[], float] = time.perf_counter
) -> tuple[list[float], list[float]]:
    """Times of ``ours`` and ``theirs`` run one after the other, ``runs`` times each: wall, or by
    ``clock`` (``time.process_time``: the CPU of this process's threads)."""
    b, a = in_turn([theirs, ours], runs, clock)
    return a, b


def in_turn(
    fns: list[Callable[[], object]], runs: int, clock: Callable[[], float] = time.perf_counter
) -> list[list[float]]:
    """Times of each of ``fns``, run in turn ``runs`` times (one list per function), in a new
    (seeded) order each turn: a reader right after one whose threads still spin or whose memory
    fills the caches runs slower (lorisnb's 10,000-pose TUM read took 3.4-3.7 ms right after
    polars' threads, 2.1-3.0 ms elsewhere), so that no function always follows the same one."""
    times: list[list[float]] = [[] for _ in fns]
    order = np.random.default_rng(0)
    for _ in range(runs):
        for k in order.permutation(len(fns)):
            t = clock()
            fns[k]()
            times[k].append(clock() - t)
    return times


def ratios(a: list[float], b: list[float]) -> tuple[float, float]:
    r = [x / y for x, y in zip(a, b, strict=True)]
    return min(r), statistics.median(r)


DRIVER = """
import resource, subprocess, sys, time
t = time.perf_counter()
code = subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode
took = time.perf_counter() - t
print(took, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024, code)
"""


def process(args: list[str]) -> tuple[float, int]:
    """Wall time and peak resident memory (bytes) of a command run to its end. It is started by a
    small driver process: a child forked from this large process would count this process's
    memory as its own peak."""
    out = subprocess.run([sys.executable, "-c", DRIVER, *args], capture_output=True, text=True, check=True).stdout
    took, peak, code = out.split()
    if int(code) not in (0, 1):
        raise RuntimeError(f"{' '.join(args)} exited with {code}")
    return float(took), int(peak)


def processes(ours: list[str], theirs: list[str], runs: int) -> dict[str, list[float]]:
    """Times and peaks of two commands run in alternation."""
    out: dict[str, list[float]] = {"t_ours": [], "t_theirs": [], "m_ours": [], "m_theirs": []}
    for _ in range(runs):
        for args, key in ((theirs, "theirs"), (ours, "ours")):
            t, m = process(args)
            out[f"t_{key}"].append(t)
            out[f"m_{key}"].append(m)
    return out


LORISNB = str(Path(sys.executable).with_name("lorisnb"))


def _evo_ape() -> str:
    """evo's ``evo_ape``: $EVO_APE, else beside this interpreter, else on the PATH."""
    import shutil

    beside = Path(sys.executable).with_name("evo_ape")
    return os.environ.get("EVO_APE") or (str(beside) if beside.exists() else shutil.which("evo_ape") or "evo_ape")


EVO_APE = _evo_ape()
NO_PYARROW = "import sys; sys.modules['pyarrow'] = None\n"  # pandas' own parser, pyarrow not loaded


def parse_only(*paths: Path) -> list[str]:
    """A process that only parses the files with pandas' fastest exact call."""
    code = (
        NO_PYARROW
        + "import pandas as pd\n"
        + "".join(f"pd.read_csv({str(p)!r}, sep=' ', header=None, engine='c')\n" for p in paths)
    )
    return [sys.executable, "-c", code]


READ_LINE = "floors read: "


def bench_readers(folder: Path) -> None:
    """TUM, KITTI, EuRoC readers against pandas on the same file, 10k and 1M poses, each file in a
    new process that only reads it (both sides, in alternation): in a process that has done other
    work, freed memory may be reused or not depending on how its heap lies (after the bench's other
    figures, pandas' columns of a million rows, 8 MB each, took about 7,000 new pages per read
    against 22,000 in a new process, and read the 1M-pose files 10-25% faster, while the readers'
    arrays are new pages either way), so the figures would depend on what ran before them."""
    from textgen import lifelong_groundtruth, write_plain

    print(
        "\nreading, lorisnb / the fastest public reader of the same file (pandas.read_csv(sep=' ', header=None, "
        "engine='c'), pyarrow.csv.read_csv and polars.read_csv with their threads), a new process each:"
    )
    for n, runs in ((10_000, 75), (1_000_000, 9)):
        traj = lifelong_groundtruth(n, 1)[1]
        for fmt in ("tum", "kitti", "euroc"):
            path = folder / f"{fmt}_{n}.txt"
            write_plain(path, traj, fmt)
            cmd = [sys.executable, __file__, "read", fmt, str(path), str(runs)]
            out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
            times = json.loads(next(ln for ln in out.splitlines() if ln.startswith(READ_LINE))[len(READ_LINE) :])
            a, theirs = times.pop("lorisnb"), times
            # the fastest public reader is the one of the smallest median time, compared run by run (the
            # least of the readers' times in each run is no one reader's time: it lies at or below each)
            best = min(theirs, key=lambda name: statistics.median(theirs[name]))
            lo, med = ratios(a, theirs[best])
            print(
                f"  {fmt} {n:>9,} poses ({path.stat().st_size / 1e6:.0f} MB), medians: lorisnb "
                f"{statistics.median(a):.4f} s, "
                + ", ".join(f"{name} {statistics.median(t):.4f} s" for name, t in theirs.items())
                + f"; the fastest: {best}"
            )
            name = fmt.upper() if fmt != "euroc" else "EuRoC"
            row(f"read {name} {n:,} poses / fastest public reader", lo, med, "<= 1.1x", 1.1)
            path.unlink()


def _read(fmt: str, path: Path, runs: int) -> None:
    """One file of :func:`bench_readers`, in this process: the times of lorisnb, pandas, pyarrow and
    (where installed) polars, printed."""
    import warnings

    import pandas as pd
    import pyarrow.csv as pc

    from lorisnb.io import read_euroc, read_kitti, read_tum

    read = {"tum": read_tum, "kitti": read_kitti, "euroc": read_euroc}[fmt]
    sep, skip = (",", 1) if fmt == "euroc" else (" ", 0)
    arrow = (pc.ReadOptions(autogenerate_column_names=True, skip_rows=skip), pc.ParseOptions(delimiter=sep))
    readers = {
        "pandas": lambda: pd.read_csv(path, sep=sep, header=None, engine="c", skiprows=skip),
        "pyarrow": lambda: [col.to_numpy() for col in pc.read_csv(path, *arrow).columns],
    }
    try:
        import polars as pl
    except ImportError:
        pass
    else:
        readers["polars"] = lambda: [
            c.to_numpy() for c in pl.read_csv(path, separator=sep, has_header=False, skip_rows=skip).get_columns()
        ]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        times = in_turn([*readers.values(), lambda: read(path)], runs)
    print(READ_LINE + json.dumps(dict(zip([*readers, "lorisnb"], times, strict=True))))


def bench_small_pair_and_help(data) -> None:
    """fr2_desk (2,893 poses) with lorisnb's and evo's command lines, and --help."""
    gt, est = data.tum / "fr2_desk_groundtruth.txt", data.tum / "fr2_desk_ORB.txt"
    ours = [LORISNB, "evaluate", str(est), "--gt", str(gt), "--format", "tum", "--no-progress"]
    theirs = [EVO_APE, "tum", str(gt), str(est), "-a"]
    print(f"\nsmall pair (fr2_desk, TUM) and --help, whole processes, lorisnb / {Path(EVO_APE).name}:")
    r = processes(ours, theirs, 9)
    print(f"  evaluate: lorisnb {min(r['t_ours']):.3f} s, {max(r['m_ours']) / 2**20:.0f} MiB; "
          f"evo_ape {min(r['t_theirs']):.3f} s, {max(r['m_theirs']) / 2**20:.0f} MiB")  # fmt: skip
    row("small pair, wall time / evo_ape", *ratios(r["t_ours"], r["t_theirs"]), "<= 0.5x", 0.5)
    row("small pair, peak memory / evo_ape", *ratios(r["m_ours"], r["m_theirs"]), "<= 1.0x", 1.0)
    r = processes([LORISNB, "--help"], [EVO_APE, "--help"], 9)
    print(f"  --help: lorisnb {min(r['t_ours']):.3f} s, evo_ape {min(r['t_theirs']):.3f} s")
    row("--help, wall time / evo_ape", *ratios(r["t_ours"], r["t_theirs"]), "<= 0.5x", 0.5)


def pair_files(folder: Path, n: int) -> tuple[Path, Path]:
    """A simulated TUM pair of ``n`` poses each (noise, drift; every estimate pose matches)."""
    from textgen import lifelong_groundtruth, write_plain

    from lorisnb.core.simulate import Faults, simulate

    g = lifelong_groundtruth(n, 1)[1]
    e = simulate(g, Faults(position_noise_m=0.02, orientation_noise_deg=0.5, drift_per_m=0.002, seed=1))
    gt, est = folder / f"gt_{n}.txt", folder / f"est_{n}.txt"
    write_plain(gt, g, "tum")
    write_plain(est, e, "tum")
    return gt, est


def bench_growth(folder: Path) -> None:
    """Whole ``lorisnb evaluate`` processes on TUM pairs of 10k..10M poses each: time, against a
    process that only parses both files, and peak memory per pose above the start-up's (the
    parse-only process's too, above a process importing pandas); evo_ape
    up to 100k poses."""
    from lorisnb.io.parsing.pieces import pyarrow_installed
    from lorisnb.io.parsing.whole import NUMPY_MAX_BYTES

    sizes = [10_000, 100_000, 1_000_000] + ([10_000_000] if os.environ.get("LORISNB_BENCH_HUGE", "1") != "0" else [])
    imports = "import lorisnb.cli, lorisnb.tools.evaluation.runner"
    # the start-up of a process importing what the run imports: pyarrow's CSV reader, its threads started by a
    # first parse, where installed (every file is parsed by it); else pandas for files numpy does not read
    arrow = (
        "import pyarrow as pa, pyarrow.csv as pc\n"
        "pc.read_csv(pa.py_buffer(b'1 2\\n'), pc.ReadOptions(column_names=['a', 'b']), pc.ParseOptions(delimiter=' '))\n"
    )
    if pyarrow_installed():
        starts = dict.fromkeys((False, True), arrow)
    else:
        starts = {large: NO_PYARROW + ("import pandas\n" if large else "") for large in (False, True)}
    bases = {
        large: min(process([sys.executable, "-c", code + imports])[1] for _ in range(3))
        for large, code in starts.items()
    }
    pandas_only = min(process([sys.executable, "-c", NO_PYARROW + "import pandas"])[1] for _ in range(3))
    if pyarrow_installed():
        start = f"{bases[False] / 2**20:.0f} MiB (pyarrow's reader imported and started, as the run does)"
    else:
        start = (f"{bases[False] / 2**20:.0f} MiB ({bases[True] / 2**20:.0f} MiB with pandas, which files over "
                 f"{NUMPY_MAX_BYTES >> 20} MB need)")  # fmt: skip
    print(f"\ngrowth: lorisnb evaluate EST --gt GT (TUM, n poses each), whole processes; start-up {start}")
    table = []
    for n in sizes:
        gt, est = pair_files(folder, n)
        base = bases[max(gt.stat().st_size, est.stat().st_size) > NUMPY_MAX_BYTES]
        ours = [LORISNB, "evaluate", str(est), "--gt", str(gt), "--no-progress"]
        runs = 5 if n <= 1_000_000 else 1
        r = processes(ours, parse_only(gt, est), runs)
        evo = process([EVO_APE, "tum", str(gt), str(est), "-a"])[0] if n <= 100_000 else None
        lo, med = ratios(r["t_ours"], r["t_theirs"])
        per_pose = (max(r["m_ours"]) - base) / n
        floor = (max(r["m_theirs"]) - pandas_only) / n  # the parse alone, above a process importing pandas
        t = min(r["t_ours"])
        table.append((n, t, min(r["t_theirs"]), lo, med, t / n * 1e6, per_pose, floor, evo))
        print(f"  {n:>10,}: lorisnb {t:7.2f} s  parse only {min(r['t_theirs']):7.2f} s  x{lo:.2f}/x{med:.2f}  "
              f"{t / n * 1e6:6.2f} us/pose  {per_pose:5.0f} B/pose (parse only {floor:4.0f})"
              + (f"  evo_ape {evo:.2f} s" if evo else ""))  # fmt: skip
        if n == 1_000_000:
            row("1M-pose pair, wall time / parse only", lo, med, "<= 2x", 2.0)
            row("1M-pose pair, peak bytes per pose", per_pose, per_pose, "<= 250 B", 250, "B")
        if n == 10_000_000:
            row("10M-pose pair, peak bytes per pose", per_pose, per_pose, "bounded (<= 250 B)", 250, "B")
        gt.unlink()
        est.unlink()
    GROWTH[:] = table


GROWTH: list[tuple] = []


def bench_nearest(n: int = 1_000_000) -> None:
    """TUM's greedy nearest association of 1M ground-truth stamps (100 Hz) and 1M jittered estimate
    stamps: mutual nearest neighbours against the rule over every candidate, time and peak
    memory (tracemalloc), the same pairs."""
    import tracemalloc

    from lorisnb.core.conventions import choices as conventions

    rng = np.random.default_rng(0)
    g = 1.56e9 + np.arange(n) / 100.0
    e = np.unique(g + rng.normal(0, 0.004, n))
    full = np.arange(g.size), np.arange(e.size)
    ours = lambda: conventions.associate_nearest(g, e, 0.02)  # noqa: E731
    theirs = lambda: conventions._greedy_candidates(g, e, *full, 0.02)  # noqa: E731
    a, b = alternate(ours, theirs, 5)
    peaks = []
    for fn in (ours, theirs):
        tracemalloc.start()
        got = fn()
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
        peaks.append(got)
    same = all(np.array_equal(x, y) for x, y in zip(peaks[1], peaks[3], strict=True))
    print(f"\nnearest association, {n:,} + {e.size:,} stamps: {min(a):.3f} s, {peaks[0] / n:.0f} B/pose; "
          f"every candidate {min(b):.3f} s, {peaks[2] / n:.0f} B/pose; same pairs: {same}")  # fmt: skip
    row("nearest association 1M, time / every-candidate rule", *ratios(a, b), "linear, same pairs", 1.0 if same else -1)


def bench_surfaces_runs(ev, runs: int = 3) -> None:
    """CR surfaces 1000 x 1000 for every algorithm and scene of the tree: the first call in this
    process and the next ones (min, median), peak memory (tracemalloc)."""
    import tracemalloc

    from lorisnb.core.lifelong.surfaces import cr_surfaces

    durations = ev.durations()
    eps, phi = np.geomspace(0.01, 100, 1000), np.linspace(0.1, 180, 1000)
    times, peak = [], 0
    for _ in range(runs):
        tracemalloc.start()
        t = time.perf_counter()
        surf = cr_surfaces(ev.errors, eps, phi, durations)
        times.append(time.perf_counter() - t)
        peak = max(peak, tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
        del surf
    print(
        f"\nCR surfaces 1000x1000: {', '.join(f'{t:.2f} s' for t in times)} (first call first), peak {peak / 1e9:.2f} GB"
    )
    row("CR surfaces 1000x1000, seconds", min(times), statistics.median(times), "<= 3 s", 3.0, "s")
    row("CR surfaces 1000x1000, peak GB", peak / 1e9, peak / 1e9, "<= 2 GB", 2.0, "GB")


def bench_report(folder: Path, runs: int = 3) -> None:
    """The main job, ``lorisnb report`` on the bundled data (8 notebooks), ``runs`` times: wall
    time (min, median) and the CPU its processes used (user + system, kernels included)."""
    import resource

    walls, cpus = [], []
    for k in range(runs):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t = time.perf_counter()
        subprocess.run([LORISNB, "report", "--out", str(folder / f"report-{k}")], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
        walls.append(time.perf_counter() - t)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
    print(f"\nbatch report (lorisnb report, 8 notebooks): {', '.join(f'{w:.1f} s' for w in walls)} wall, "
          f"{', '.join(f'{c:.0f} s' for c in cpus)} CPU")  # fmt: skip
    row("batch report on the bundled data, seconds", min(walls), statistics.median(walls), "<= 40 s", 40.0, "s")


def main() -> None:
    import tempfile
    import warnings

    from lorisnb.errors import LorisWarning
    from lorisnb.io import find_data
    from lorisnb.tools.evaluation.runner import evaluate

    warnings.simplefilter("ignore", LorisWarning)
    subprocess.run([sys.executable, "-m", "compileall", "-q", str(Path(__file__).parents[1] / "lorisnb")], check=True)
    data = find_data()
    bench_small_pair_and_help(data)
    bench_nearest()
    bench_surfaces_runs(evaluate([data.icra20], scale="auto", jobs=1, progress=False))
    with tempfile.TemporaryDirectory(prefix="lorisnb-floors-") as tmp:
        bench_readers(Path(tmp))
        bench_growth(Path(tmp))
    print_tables()


def print_tables() -> None:
    print("\nissue-27 figures (ratios: lorisnb / baseline, side by side in this run):\n")
    print("| figure | min | median | goal | met |\n|---|---|---|---|---|")
    for name, lo, med, goal, met in ROWS:
        print(f"| {name} | {lo} | {med} | {goal} | {'yes' if met else 'no'} |")
    if GROWTH:
        print(
            "\n| poses (each file) | lorisnb evaluate | parse only | ratio min / median | us per pose | bytes per pose "
            "| parse only, bytes per pose | evo_ape |"
        )
        print("|---|---|---|---|---|---|---|---|")
        for n, t, parse, lo, med, us, b, floor, evo in GROWTH:
            print(f"| {n:,} | {t:.2f} s | {parse:.2f} s | {lo:.2f}x / {med:.2f}x | {us:.2f} | {b:,.0f} | {floor:,.0f} | "
                  f"{f'{evo:.2f} s' if evo else '-'} |")  # fmt: skip


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).parent))
    if sys.argv[1:2] == ["read"]:  # a process of bench_readers
        _read(sys.argv[2], Path(sys.argv[3]), int(sys.argv[4]))
    else:
        main()
