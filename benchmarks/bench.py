"""Speed figures for lorisnb, printed as times and as ratios against baselines run in this same
process (so the ratios do not depend on the machine).

Baselines are plain-Python implementations of the same work in the style of the official tool
(a dict per sequence, one Python iteration per line and per pose).

Run: ``make bench`` (or ``python benchmarks/bench.py``).
"""

from __future__ import annotations

import math
import time
import warnings
from pathlib import Path

import numpy as np

from lorisnb.core import score
from lorisnb.errors import LorisWarning
from lorisnb.io import find_data, read_openloris
from lorisnb.tools.evaluate import evaluate, result_files


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


def main() -> None:
    warnings.simplefilter("ignore", LorisWarning)
    data = find_data()
    root = data.icra20
    files = [p for p, _ in result_files([root])]
    print(f"icra20_results: {len(files)} files")

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

    from lorisnb.core.sweep import sweep

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

    bench_surfaces(ev)

    gt_path = data.groundtruth("market")
    est_path = root / "lifelong" / "maslam" / "market.txt"
    gt_b = baseline_parse(gt_path)
    est_b = baseline_parse(est_path)
    t_base_assoc, _ = _timed(lambda: [baseline_associate(gt_b[s], est_b[s]) for s in est_b], repeat=1)
    from lorisnb.core.association import associate
    from lorisnb.io import load_groundtruth

    gt = load_groundtruth("market")
    est = read_openloris(est_path)
    t_assoc, _ = _timed(lambda: [associate(gt.sequences[s], est.sequences[s].stamps) for s in est.sequences])
    print(
        f"associate market     lorisnb {t_assoc:7.4f} s   baseline {t_base_assoc:7.4f} s   "
        f"speed-up x{t_base_assoc / t_assoc:5.1f}   (positions + slerp vs positions only)"
    )

    bench_against_evo(data)


def bench_surfaces(ev) -> None:
    """CR surfaces over a 1000 eps x 1000 phi grid for every algorithm and scene of the tree, by
    dominance counting, against the tidy sweep (the baseline) on a 50 x 50 grid in the same process."""
    import tracemalloc

    from lorisnb.core.surfaces import cr_surfaces
    from lorisnb.core.sweep import sweep

    durations = ev.durations()
    eps, phi = np.geomspace(0.01, 100, 1000), np.linspace(0.1, 180, 1000)
    tracemalloc.start()
    t_surf, surf = _timed(lambda: cr_surfaces(ev.errors, eps, phi, durations), repeat=1)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    t_small, _ = _timed(lambda: sweep(ev.errors, eps[::20], phi[::20]), repeat=1)
    per_point_surf = t_surf / (len(eps) * len(phi))
    per_point_sweep = t_small / (50 * 50)
    print(
        f"CR surfaces 1000x1000  lorisnb {t_surf:7.3f} s, peak {peak / 2**20:6.0f} MiB, {len(surf.groups)} surfaces "
        f"({surf.cr.nbytes / 2**20:.0f} MiB);  tidy sweep 50x50 {t_small:.3f} s: per grid point x"
        f"{per_point_sweep / per_point_surf:,.0f} faster"
    )


def bench_against_evo(data, n: int = 50_000) -> None:
    """lorisnb and evo on the same long trajectory: the TUM fr2/desk ground truth resampled to
    ``n`` poses, and a noisy, rigidly moved copy as the estimate (identical pairs)."""
    import copy

    from evo.core import metrics as em
    from scipy.spatial.transform import Rotation, Slerp

    from lorisnb.core import metrics
    from lorisnb.core.geometry import umeyama
    from lorisnb.core.trajectory import Trajectory
    from lorisnb.io import read_tum
    from lorisnb.tools.evo_bridge import to_evo

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
