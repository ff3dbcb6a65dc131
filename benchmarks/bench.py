"""Speed figures for lorisnb, printed as times and as ratios against baselines run in this same
process (so the ratios do not depend on the machine).

Baselines are plain-Python implementations of the same work in the style of the official tool
(a dict per sequence, one Python iteration per line and per pose).

It opens with the real workload, the bundled icra20 tree as users run it (:mod:`workload`: the
whole tree in a whole process, its files parsed, one threshold setting, one slider change, the
report), before the synthetic files.

Run: ``make bench`` (or ``python benchmarks/bench.py``). ``LORISNB_BENCH_LIFELONG=0`` leaves out
the 10M-pose lifelong OpenLORIS file, ``LORISNB_BENCH_HUGE=0`` the 10M-pose TUM pair,
``LORISNB_BENCH_SERVE=0`` the challenge server's load run (:mod:`challenge_load`). Issue 27's
figures against the floors (pandas, evo_ape, parsing alone) are :mod:`floors`.
"""

from __future__ import annotations

import math
import time
import warnings
from pathlib import Path

import floors
import numpy as np
import workload

from lorisnb.core import score
from lorisnb.errors import LorisWarning
from lorisnb.io import find_data, read_openloris
from lorisnb.tools.evaluation.runner import evaluate, result_files


def _timed(fn, repeat: int = 3):
    best = math.inf
    out = None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def baseline_parse(path: Path) -> dict:
    """Line-by-line parsing as the official tool does it (for comparison only)."""
    seqs: dict = {}
    seq = None
    last = None
    with open(path) as fh:
        for line in fh:
            if line.startswith("#") or not line.strip():
                continue
            if line.startswith("seq:"):
                seq = int(line[4:])
                seqs[seq] = {}
                continue
            if ":" in line:
                continue
            s = line.split()
            pose = [float(v) for v in s[-7:]]
            if any(math.isnan(v) for v in pose) or pose == last:
                continue
            seqs[seq][float(s[0])] = pose
            last = pose
    return seqs


def baseline_associate(gt: dict, est: dict) -> list:
    """Per-pose interpolation loop (positions only) in the official tool's style."""
    keys = sorted(gt)
    out = []
    idx = 0
    for t in sorted(est):
        if t < keys[0] or t > keys[-1]:
            continue
        while not (keys[idx] <= t <= keys[idx + 1]):
            idx += 1
        k1, k2 = keys[idx], keys[idx + 1]
        if max(t - k1, k2 - t) < 0.5:
            w = (t - k1) / (k2 - k1)
            p = [(1 - w) * a + w * b for a, b in zip(gt[k1][:3], gt[k2][:3], strict=True)]
            out.append((t, p))
    return out


#: (goal, figure, target, met) of every issue-12 goal, printed together at the end
GOALS: list[tuple[str, str, str, bool]] = []


def goal(name: str, figure: str, target: str, met: bool) -> None:
    GOALS.append((name, figure, target, met))
    print(f"  -> {name}: {figure} (goal {target}) {'met' if met else 'NOT MET'}")


def child(code: str, *args: str) -> dict:
    """Run ``code`` in a fresh interpreter; it prints a dict literal as its last line (time,
    memory: each measured inside that process, so the generator's memory does not count)."""
    import ast
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, check=True).stdout
    return ast.literal_eval(out.strip().splitlines()[-1])


MEASURE = """
import sys, time, warnings
def mem(field):  # kB fields of /proc/self/status: VmRSS now, VmHWM the peak (reset by exec)
    with open('/proc/self/status') as f:
        return next(int(ln.split()[1]) * 1024 for ln in f if ln.startswith(field))
{imports}
warnings.simplefilter('ignore')
base = mem('VmRSS:')
t = time.perf_counter()
{work}
took = time.perf_counter() - t
print(dict(seconds=took, added_bytes=mem('VmHWM:') - base))
"""


def bench_reading(folder: Path) -> None:
    """A 2-million-pose OpenLORIS file (one space between numbers): lorisnb's reader against pandas'
    fastest exact call on the same pose lines (``sep=" "``, the header and 'seq:' lines skipped; in
    this process, best of 2), peak memory added by each (in a fresh process), stamps
    equal to Python's float() of each token, nanosecond digits read exactly."""
    import pandas as pd
    from textgen import lifelong_groundtruth, write_lines

    from lorisnb.io.parsing.chunks import stamp_digits

    path = folder / "two_million.txt"
    write_lines(path, "market", lifelong_groundtruth(2_000_000, 2), simulated=True, single=True)
    size = path.stat().st_size
    skip = [0, 1, 2, 3, 1_000_004]  # header lines and the second 'seq:' line
    t_ours, f = _timed(lambda: read_openloris(path), repeat=2)
    t_pd, df = _timed(lambda: pd.read_csv(path, sep=" ", header=None, skiprows=skip, engine="c"), repeat=2)
    ratio = t_ours / t_pd
    print(f"read 2M poses ({size / 1e6:.0f} MB)  lorisnb {t_ours:.2f} s   pandas read_csv {t_pd:.2f} s   x{ratio:.2f}")
    goal("read 2M-pose file, time vs pandas", f"x{ratio:.2f} ({t_ours:.2f} s)", "<= x1.5", ratio <= 1.5)
    ours = child(MEASURE.format(imports="from lorisnb.io import read_openloris", work=f"read_openloris({str(path)!r})"))
    theirs = child(MEASURE.format(
        imports="import numpy as np, pandas as pd",
        work=f"pd.read_csv({str(path)!r}, sep=' ', header=None, skiprows={skip}, engine='c')",
    ))  # fmt: skip
    mem = ours["added_bytes"] / size
    print(f"  memory added: lorisnb {ours['added_bytes'] / 2**20:.0f} MiB ({mem:.2f}x the file), "
          f"pandas {theirs['added_bytes'] / 2**20:.0f} MiB")  # fmt: skip
    goal("read 2M-pose file, peak memory", f"{mem:.2f}x file size", "<= 3x", mem <= 3)
    stamps = np.concatenate([t.stamps for t in f.sequences.values()])
    text = path.read_bytes().split(b"\n")
    tokens = [ln.split(None, 1)[0] for ln in text if ln[:1] not in (b"s", b"f", b"") and b":" not in ln]
    exact = np.array_equal(stamps, np.array([float(x) for x in tokens])) and np.array_equal(stamps, df[0].to_numpy())
    lines = np.concatenate([t.lines for t in f.sequences.values()])
    pick = np.sort(np.random.default_rng(0).choice(lines, 1000, replace=False))
    ndig, frac = stamp_digits(path, pick)
    digits = all(
        text[k - 1].split()[0].split(b".")[1] == f"{v:0{d}d}".encode() for k, d, v in zip(pick, ndig, frac, strict=True)
    )
    goal(
        "stamps exact",
        f"float() of every token: {exact}; nanosecond digits of 1000 lines: {digits}",
        "both",
        exact and digits,
    )
    binary = folder / "binary.txt"
    binary.write_bytes(np.random.default_rng(1).integers(0, 256, 200 * 2**20, dtype=np.uint8).tobytes())
    t = time.perf_counter()
    try:
        read_openloris(binary)
    except Exception as exc:  # noqa: BLE001 (the ParseError is the point)
        kind = type(exc).__name__
    t_bin = time.perf_counter() - t
    goal("200 MB binary file rejected", f"{t_bin * 1000:.1f} ms ({kind})", "after the first few KB", t_bin < 0.05)


def bench_checks(root: Path) -> None:
    """The plausibility checks' share of a run: every file's errors with and without them, against
    a whole evaluation of the tree in one process (reading, errors, default RPE)."""
    from lorisnb.core.pipeline.sessions import compute_errors
    from lorisnb.io import load_groundtruth

    files = [read_openloris(p, warn=False) for p, _ in result_files([root])]
    files = [f for f in files if f.header.get("scene", "").lower() != "office"]
    gts = {f.scene: load_groundtruth(f.scene) for f in files}

    def run(checks: bool) -> None:
        for f in files:
            compute_errors(f, gts[f.scene], checks=checks, scale="auto")

    t_on, _ = _timed(lambda: run(True), repeat=7)  # a difference of two short times: the best of several
    t_off, _ = _timed(lambda: run(False), repeat=7)
    t_run, _ = _timed(lambda: evaluate([root], scale="auto", jobs=1), repeat=2)
    share = max(t_on - t_off, 0.0) / t_run
    print(f"plausibility checks  {t_on - t_off:.3f} s; a whole evaluation in one process {t_run:.3f} s ({share:.0%})")
    goal("plausibility checks' share of a run", f"{share:.0%}", "<= 10%", share <= 0.10)


def bench_lifelong(folder: Path, real_data: Path) -> None:
    """A simulated week at 16 Hz: 10 million poses in 5 sessions (ground truth of the same size),
    evaluated end to end as a user would: ``lorisnb evaluate`` on the simulated result file with
    the ground truth in a data folder, in a fresh process (imports, reading, errors, every metric
    at eps 5 m and phi 30 deg, the table printed)."""
    import os

    from textgen import lifelong_files

    t = time.perf_counter()
    gt, est = lifelong_files(folder)
    print(
        f"lifelong: wrote {gt.stat().st_size / 1e9:.2f} + {est.stat().st_size / 1e9:.2f} GB in {time.perf_counter() - t:.0f} s"
    )
    data = folder / "data" / "openloris-scene"
    (data / "groundtruth").mkdir(parents=True)
    os.replace(gt, data / "groundtruth" / "gt_market_1.txt")
    os.symlink((real_data / "openloris-scene" / "extrinsics.json").resolve(), data / "extrinsics.json")
    (folder / "results" / "simulated").mkdir(parents=True)
    os.replace(est, folder / "results" / "simulated" / "market.txt")
    args = [
        "evaluate",
        str(folder / "results"),
        "--data",
        str(folder / "data"),
        "--eps",
        "5",
        "--phi",
        "30",
        "--no-progress",
    ]
    work = f"from lorisnb.cli import main\nimport contextlib, io\nwith contextlib.redirect_stdout(io.StringIO()):\n    main({args!r})"
    runs = [child(MEASURE.format(imports="", work=work)) for _ in range(LIFELONG_RUNS)]
    seconds, peak = min(r["seconds"] for r in runs), max(r["added_bytes"] for r in runs)
    each = ", ".join(f"{r['seconds']:.1f} s" for r in runs)
    print(f"lifelong 10M poses, lorisnb evaluate: {each}; peak {peak / 1e9:.2f} GB ({peak / 2**30:.2f} GiB)")
    goal("10M-pose lifelong file end to end", f"{seconds:.1f} s (best of {len(runs)}), {peak / 1e9:.2f} GB (most)",
         "<= 15 s, <= 3 GB", seconds <= 15 and peak <= 3e9)  # fmt: skip


LIFELONG_RUNS = 3  # whole runs in fresh processes: the best time (this machine's speed drifts), the largest peak


def main() -> None:
    import os
    import subprocess
    import sys
    import tempfile

    warnings.simplefilter("ignore", LorisWarning)
    lorisnb_dir = Path(__file__).resolve().parents[1] / "lorisnb"  # as `make bench` leaves it: bytecode written
    subprocess.run([sys.executable, "-m", "compileall", "-q", str(lorisnb_dir)], check=True)
    data = find_data()
    root = data.icra20
    with tempfile.TemporaryDirectory(prefix="lorisnb-bench-") as tmp:  # the real workload first (issue 47)
        workload.main(root, Path(tmp))
    if os.environ.get("LORISNB_BENCH_MANY", "1") != "0":  # then many small real files (issues 47, 48)
        import many_files

        many_files.bench_row()
    files = [p for p, _ in result_files([root])]
    print(f"\nicra20_results: {len(files)} files")

    t_parse, parsed = _timed(lambda: [read_openloris(p) for p in files])
    t_base_parse, _ = _timed(lambda: [baseline_parse(p) for p in files], repeat=1)
    n_poses = sum(f.n_poses for f in parsed)
    print(
        f"parse only           lorisnb {t_parse:7.3f} s   baseline {t_base_parse:7.3f} s   "
        f"speed-up x{t_base_parse / t_parse:5.1f}   ({n_poses} poses)"
    )

    t_eval, ev = _timed(lambda: evaluate([root], scale="auto"), repeat=2)
    t_score, _ = _timed(lambda: score(ev.errors, eps="paper", phi=30.0))
    print(
        f"evaluate whole tree  lorisnb {t_eval:7.3f} s   ({len(ev.errors)} files scored, "
        f"{len(ev.skipped)} skipped without ground truth); one threshold setting after that: {t_score:.3f} s"
    )
    print("                     (the official tool needs about 270 s for one setting over the same files)")

    from lorisnb.core.lifelong.sweep import sweep

    grid = (np.geomspace(0.05, 50, 50), np.linspace(5, 180, 10), [0.1, 0.5, 1.0, 2.0, 5.0], [10, 30, 60, 120, 300])
    ev.sequences()  # the threshold-free RPE pairs are computed once here, as in a session
    t_cold = time.perf_counter()
    table = sweep(ev.errors, *grid)
    t_cold = time.perf_counter() - t_cold
    del table
    t_sweep, table = _timed(lambda: sweep(ev.errors, *grid))
    n_set = 50 * 10 * 5 * 5
    print(
        f"sweep 50x10x5x5      lorisnb {t_sweep:7.3f} s (first call {t_cold:.3f} s)   {len(table)} rows;"
        f" one setting at a time: {t_score:.3f} s x {n_set} = {t_score * n_set:.0f} s  "
        f"speed-up x{t_score * n_set / t_sweep:,.0f}"
    )
    goal("tidy sweep 50x10x5x5", f"{t_sweep:.2f} s, x{t_score * n_set / t_sweep:,.0f} vs one setting at a time",
         "faster than 2.1 s (before this change)", t_sweep < 2.1)  # fmt: skip

    floors.bench_surfaces_runs(ev)

    gt_path = data.groundtruth("market")
    est_path = root / "lifelong" / "maslam" / "market.txt"
    gt_b = baseline_parse(gt_path)
    est_b = baseline_parse(est_path)
    t_base_assoc, _ = _timed(lambda: [baseline_associate(gt_b[s], est_b[s]) for s in est_b], repeat=1)
    from lorisnb.core.alignment.association import associate
    from lorisnb.io import load_groundtruth

    gt = load_groundtruth("market")
    est = read_openloris(est_path)
    t_assoc, _ = _timed(lambda: [associate(gt.sequences[s], est.sequences[s].stamps) for s in est.sequences])
    print(
        f"associate market     lorisnb {t_assoc:7.4f} s   baseline {t_base_assoc:7.4f} s   "
        f"speed-up x{t_base_assoc / t_assoc:5.1f}   (positions + slerp vs positions only)"
    )

    bench_against_evo(data)
    bench_checks(root)
    with tempfile.TemporaryDirectory(prefix="lorisnb-bench-") as tmp:
        bench_reading(Path(tmp))
        if os.environ.get("LORISNB_BENCH_LIFELONG", "1") != "0":
            bench_lifelong(Path(tmp), data.root)
    floors.bench_small_pair_and_help(data)
    floors.bench_nearest()
    with tempfile.TemporaryDirectory(prefix="lorisnb-bench-") as tmp:
        floors.bench_readers(Path(tmp))
        floors.bench_growth(Path(tmp))
    if os.environ.get("LORISNB_BENCH_SERVE", "1") != "0":
        bench_challenge_server(data)
    if os.environ.get("LORISNB_BENCH_CALIBRATE", "1") != "0":
        # the regression gate's error rates, a small run of `make calibrate` (docs/guide/regression-gating.md quotes the full run)
        import calibrate

        print("\nregression gate: measured error rates (a small run of make calibrate)")
        calibrate.main(["--quick", "--trials", "1", "3"])
    print("\nissue-12 goals on this machine:")
    for name, figure, target, met in GOALS:
        print(f"  {'met    ' if met else 'NOT MET'}  {name:40s} {figure:45s} goal {target}")
    floors.print_tables()


def bench_challenge_server(data, n: int = 50) -> None:
    """The challenge server under load on loopback (:mod:`challenge_load`): optional, needs the
    ``serve`` extra; ``LORISNB_BENCH_SERVE=0`` leaves it out."""
    import importlib.util
    import tempfile

    if importlib.util.find_spec("fastapi") is None:
        print("\nchallenge server: skipped (pip install 'lorisnb[serve]')")
        return
    import challenge_load

    with tempfile.TemporaryDirectory(prefix="lorisnb-bench-serve-") as tmp:
        f = challenge_load.run_load(Path(tmp), data, n=n, workers=2)
    print("\n" + challenge_load.describe(f))
    goal("challenge server, 50 concurrent uploads", f"{f['once']}/{n} scored once in {f['all_scored_s']:.0f} s, "
         f"page max {f['page_max']:.1f} s", "all scored exactly once, page < 10 s",
         f["once"] == n and f["page_max"] < 10)  # fmt: skip


def bench_against_evo(data, n: int = 50_000) -> None:
    """lorisnb and evo on the same long trajectory: the TUM fr2/desk ground truth resampled to
    ``n`` poses, and a noisy, rigidly moved copy as the estimate (identical pairs)."""
    import copy

    from evo.core import metrics as em
    from scipy.spatial.transform import Rotation, Slerp

    from lorisnb.core.alignment.geometry import umeyama
    from lorisnb.core.metrics import openloris as metrics
    from lorisnb.core.trajectory.poses import Trajectory
    from lorisnb.io import read_tum
    from lorisnb.tools.peers.evo_bridge import to_evo

    gt0 = read_tum(data.tum / "fr2_desk_groundtruth.txt")
    t = np.linspace(gt0.stamps[0], gt0.stamps[-1], n)
    pos = np.stack([np.interp(t, gt0.stamps, gt0.positions[:, k]) for k in range(3)], 1)
    rot = Slerp(gt0.stamps, gt0.rotations())(t)
    rng = np.random.default_rng(0)
    g = Rotation.from_euler("z", 30, degrees=True)
    gt = Trajectory.from_rotations(t, pos, rot)
    est = Trajectory.from_rotations(
        t,
        g.apply(pos + rng.normal(scale=0.01, size=pos.shape)) + 1.0,
        g * rot * Rotation.from_rotvec(rng.normal(scale=0.01, size=(n, 3))),
    )
    ref_e, est_e = to_evo(gt), to_evo(est)
    est_rot, gt_rot = est.rotations(), gt.rotations()

    def ours_ate():
        sim = umeyama(est.positions, gt.positions)
        return metrics.rmse(metrics.ate(sim.apply(est.positions), gt.positions))

    def evo_ape(relation):
        e = copy.deepcopy(est_e)
        e.align(ref_e)
        m = em.APE(relation)
        m.process_data((ref_e, e))
        return m.get_statistic(em.StatisticsType.rmse)

    def ours_aoe():
        sim = umeyama(est.positions, gt.positions)
        return metrics.rmse(metrics.aoe(Rotation.from_matrix(sim.rotation) * est_rot, gt_rot))

    def ours_rpe():
        i, j = metrics.rpe_pairs(t, pos, 10, "f")
        tr, rr = metrics.rpe(gt.positions, gt_rot, est.positions, est_rot, i, j)
        return metrics.rmse(tr)

    def evo_rpe():
        m = em.RPE(em.PoseRelation.translation_part, 10, em.Unit.frames, all_pairs=True)
        m.process_data((ref_e, est_e))
        return m.get_statistic(em.StatisticsType.rmse)

    print(f"lorisnb vs evo on {n} poses (same process, same pairs):")
    evo_ate = lambda: evo_ape(em.PoseRelation.translation_part)  # noqa: E731
    evo_aoe = lambda: evo_ape(em.PoseRelation.rotation_angle_deg)  # noqa: E731
    for name, ours, theirs in (
        ("align + ATE", ours_ate, evo_ate),
        ("align + AOE", ours_aoe, evo_aoe),
        ("RPE 10 frames", ours_rpe, evo_rpe),
    ):
        t_o, v_o = _timed(ours)
        t_e, v_e = _timed(theirs, repeat=1)
        print(
            f"  {name:14s} lorisnb {t_o:7.4f} s   evo {t_e:7.4f} s   evo/lorisnb x{t_e / t_o:6.1f}   "
            f"(values {v_o:.6f} / {v_e:.6f})"
        )


if __name__ == "__main__":
    main()
