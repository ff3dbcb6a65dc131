"""The peers' own code, for tests that run it: kept OUTSIDE the repository (their licences differ
from lorisnb's, and tests use no network), in ``$LORISNB_PEERS`` or ``~/.cache/lorisnb/peers``.
A test that needs a peer missing there skips, saying how to fetch it (once, by hand):

- ``kitti_devkit/``: the KITTI odometry devkit's C++ (``evaluate_odometry.cpp``, ``matrix.h``,
  ``matrix.cpp``, ``mail.h``; GPL), e.g. from the devkit zip of cvlibs.net (``devkit/cpp``) or
  github.com/TurtleZhong/ORB_SLAM2_Evaluation at 152c8641ef7f6a549add6d881bc9fc90cead666a
  (``devkit/cpp``: the devkit's metric code unchanged, its ``eval()`` paths edited).
- ``kitti-odom-eval/``: github.com/Huangying-Zhan/kitti-odom-eval at
  4b850b0815dcd28edef893ca3422125b04a02397 (MIT): its Python evaluator and real KITTI poses
  (``dataset/kitti_odom/gt_poses/00..10.txt``, ``result/example_1/09.txt`` and ``10.txt``: a
  learned visual odometry's estimates).

- ``rpg_trajectory_evaluation/``: github.com/uzh-rpg/rpg_trajectory_evaluation at
  8c8ceec55c5c5094a6494208cfc5f54afe0bbc4d (MIT): its ``src/rpg_trajectory_evaluation`` modules.
- ``open_vins/``: github.com/rpng/open_vins at 6948812 (GPL): its ``ov_eval/src`` and
  ``ov_core/src/utils`` folders (``git archive HEAD ov_eval/src ov_core/src/utils``); built by
  :func:`build_ov_eval` with g++ where Eigen and Boost.Filesystem are installed (Debian:
  ``libeigen3-dev libboost-filesystem-dev``).

``git clone URL DIR && git -C DIR checkout COMMIT`` into the peers folder does it.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest

#: peer -> (a file that must exist in it, where to get it)
PEERS = {
    "kitti_devkit": ("evaluate_odometry.cpp", "the KITTI odometry devkit's devkit/cpp folder"),
    "kitti-odom-eval": ("kitti_odometry.py", "github.com/Huangying-Zhan/kitti-odom-eval"),
    "rpg_trajectory_evaluation": (
        "src/rpg_trajectory_evaluation/compute_trajectory_errors.py",
        "github.com/uzh-rpg/rpg_trajectory_evaluation",
    ),
    "tartanair_tools": ("evaluation/tartanair_evaluator.py", "github.com/castacks/tartanair_tools"),
    "open_vins": (
        "ov_eval/src/calc/ResultTrajectory.cpp",
        "github.com/rpng/open_vins (ov_eval/src, ov_core/src/utils)",
    ),
}


def peers_root() -> Path:
    return Path(os.environ.get("LORISNB_PEERS") or Path.home() / ".cache" / "lorisnb" / "peers")


def peer(name: str) -> Path:
    """The folder of peer ``name`` (see the module docstring); skips the test when it is missing."""
    must, where = PEERS[name]
    folder = peers_root() / name
    if not (folder / must).is_file():
        pytest.skip(f"{name} is not in {peers_root()} (LORISNB_PEERS): fetch {where} there (see tests/peers.py)")
    return folder


#: Our driver of the KITTI devkit: the devkit's functions on two files, every segment at float precision (%.9g round-trips
#: a float), its stats.txt and per-length files written by its own saveStats / saveErrorPlots
DRIVER = r"""
#define main devkit_main
#include "evaluate_odometry.cpp"
#undef main
int main(int argc, char *argv[]) {
  vector<Matrix> gt = loadPoses(argv[1]);
  vector<Matrix> est = loadPoses(argv[2]);
  vector<errors> err = calcSequenceErrors(gt, est);
  for (vector<errors>::iterator it = err.begin(); it != err.end(); it++)
    printf("%d %.9g %.9g %.9g %.9g\n", it->first_frame, it->r_err, it->t_err, it->len, it->speed);
  float t = 0, r = 0;
  for (vector<errors>::iterator it = err.begin(); it != err.end(); it++) { t += it->t_err; r += it->r_err; }
  float num = err.size();
  fprintf(stderr, "%.9g %.9g\n", t / num, r / num);
  char prefix[] = "seq";
  saveStats(err, argv[3]);
  saveErrorPlots(err, argv[3], prefix);
  return 0;
}
"""

#: Real KITTI sequences with an estimate of the same length (kitti-odom-eval's example_1).
KITTI_SEQUENCES = ("09", "10")


def kitti_pair(seq: str) -> tuple[Path, Path]:
    """Ground truth and estimate of a KITTI sequence (:data:`KITTI_SEQUENCES`), from kitti-odom-eval."""
    root = peer("kitti-odom-eval")
    return root / "dataset" / "kitti_odom" / "gt_poses" / f"{seq}.txt", root / "result" / "example_1" / f"{seq}.txt"


def build_devkit(out: Path) -> Path:
    """The KITTI devkit compiled with g++ into ``out`` with :data:`DRIVER` (skips without a compiler)."""
    src = peer("kitti_devkit")
    gxx = shutil.which("g++")
    if gxx is None:
        pytest.skip("no C++ compiler (g++) to build the KITTI devkit")
    (out / "driver.cpp").write_text(DRIVER)
    exe = out / "evaluate"
    built = subprocess.run(
        [gxx, "-O2", "-w", "-I", str(src), str(out / "driver.cpp"), str(src / "matrix.cpp"), "-o", str(exe)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert built.returncode == 0, built.stderr[-3000:]
    return exe


def run_devkit(exe: Path, gt: Path, est: Path, out: Path) -> tuple[np.ndarray, tuple[float, float]]:
    """The devkit's segments (first frame, r_err rad/m, t_err m/m, length, speed; one row each) and
    its mean t_err and r_err over them; its stats.txt and seq_tl/seq_rl.txt are written in ``out``."""
    out.mkdir()
    done = subprocess.run([str(exe), str(gt), str(est), str(out)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    rows = np.loadtxt(done.stdout.splitlines(), ndmin=2)
    t, r = (float(v) for v in done.stderr.split())
    return rows, (t, r)


#: An OpenLORIS pair written as KITTI files (:func:`openloris_kitti_pair`), long enough for the
#: devkit's 100 m segments (the only icra20 ORB-SLAM2 output tracked over 100 m): market-3 and its
#: ground truth, from ../shared/data (so the test that compares it with the devkit's recorded
#: numbers runs wherever the data is, with or without the peers).
OPENLORIS_KITTI = (("market", "market_1_3_orbslam2-original.txt"),)


def openloris_pose_pair(data: Any, scene: str, result: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """An icra20 ORB-SLAM2 result and its ground truth as paired poses: each estimate pose with the
    ground-truth pose of the nearest stamp (within 0.02 s), plain numpy (no lorisnb association or
    alignment): ground-truth positions (N, 3), quaternions (N, 4, xyzw), then the estimate's."""
    from lorisnb.io import load_groundtruth, read_openloris

    rf = read_openloris(data.icra20 / "per-seq" / "orbslam2_rgbd" / result, warn=False)
    seq, est = next(iter(rf.sequences.items()))
    gt = load_groundtruth(scene, data).sequences[seq]
    k = np.clip(np.searchsorted(gt.stamps, est.stamps), 1, len(gt.stamps) - 1)
    k = np.where(np.abs(gt.stamps[k - 1] - est.stamps) < np.abs(gt.stamps[k] - est.stamps), k - 1, k)
    keep = np.abs(gt.stamps[k] - est.stamps) < 0.02
    return gt.positions[k[keep]], gt.quaternions[k[keep]], est.positions[keep], est.quaternions[keep]


def openloris_kitti_pair(data: Any, scene: str, result: str, out: Path) -> tuple[Path, Path]:
    """:func:`openloris_pose_pair` as two KITTI pose files in ``out``, 12 numbers ``%.6e`` a line
    (as KITTI's files are; the devkit's errors are relative, so no alignment is needed)."""
    from scipy.spatial.transform import Rotation

    gp, gq, ep, eq = openloris_pose_pair(data, scene, result)
    files = []
    for name, (p, q) in (("gt", (gp, gq)), ("est", (ep, eq))):
        m = np.concatenate([Rotation.from_quat(q).as_matrix(), p[:, :, None]], axis=2)
        path = out / f"{Path(result).stem}_{name}.txt"
        np.savetxt(path, m.reshape(len(m), 12), fmt="%.6e")
        files.append(path)
    return files[0], files[1]


#: Our driver of ov_eval: its ``ResultTrajectory`` on an estimate, a ground truth and an alignment, every
#: statistic and every per-pose value (with its 3-sigma bound, -1 where none) of each series, ``%.17g``.
OV_DRIVER = r"""
#include "calc/ResultTrajectory.h"
#include <cstdio>
using namespace ov_eval;
static void put(const char *name, const Statistics &s) {
  printf("stat %s %.17g %.17g %.17g %.17g %.17g %.17g %zu\n", name, s.rmse, s.mean, s.median, s.std, s.min, s.max,
         s.values.size());
  for (size_t i = 0; i < s.values.size(); i++)
    printf("val %s %.17g %.17g %.17g\n", name, s.timestamps[i], s.values[i],
           i < s.values_bound.size() ? s.values_bound[i] : -1.0);
}
int main(int argc, char **argv) {
  ResultTrajectory traj(argv[1], argv[2], argv[3]);
  Statistics ao, ap, bo, bp, no, np, px, py, pz, ox, oy, oz, r, p, y;
  traj.calculate_ate(ao, ap); put("ate_ori", ao); put("ate_pos", ap);
  traj.calculate_ate_2d(bo, bp); put("ate2d_yaw", bo); put("ate2d_pos", bp);
  traj.calculate_nees(no, np); put("nees_ori", no); put("nees_pos", np);
  traj.calculate_error(px, py, pz, ox, oy, oz, r, p, y);
  put("pos_x", px); put("pos_y", py); put("pos_z", pz); put("ori_x", ox); put("ori_y", oy); put("ori_z", oz);
  put("roll", r); put("pitch", p); put("yaw", y);
  return 0;
}
"""


def build_ov_eval(out: Path) -> Path:
    """ov_eval's ``ResultTrajectory`` compiled with g++ into ``out`` with :data:`OV_DRIVER` (skips without
    a compiler, Eigen or Boost.Filesystem)."""
    src = peer("open_vins")
    gxx = shutil.which("g++")
    if gxx is None:
        pytest.skip("no C++ compiler (g++) to build ov_eval")
    eigen = next((d for d in (Path("/usr/include/eigen3"), Path("/usr/local/include/eigen3")) if d.is_dir()), None)
    if eigen is None or not Path("/usr/include/boost/filesystem.hpp").is_file():
        pytest.skip(
            "ov_eval needs Eigen and Boost.Filesystem (Debian: apt install libeigen3-dev libboost-filesystem-dev)"
        )
    (out / "driver.cpp").write_text(OV_DRIVER)
    exe = out / "ov_eval"
    ev, core = src / "ov_eval" / "src", src / "ov_core" / "src"
    sources = [ev / "alignment" / "AlignTrajectory.cpp", ev / "alignment" / "AlignUtils.cpp",
               ev / "calc" / "ResultTrajectory.cpp", ev / "utils" / "Loader.cpp", core / "utils" / "print.cpp"]  # fmt: skip
    built = subprocess.run(
        [gxx, "-O2", "-w", "-std=c++14", "-I", str(ev), "-I", str(core), "-I", str(eigen), str(out / "driver.cpp"),
         *map(str, sources), "-lboost_filesystem", "-o", str(exe)],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert built.returncode == 0, built.stderr[-3000:]
    return exe


def run_ov_eval(exe: Path, est: Path, gt: Path, align: str) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """ov_eval's statistics (rmse, mean, median, std, min, max, count) and per-pose rows (stamp, value,
    bound) of each series, by the names of :data:`lorisnb.core.metrics.consistency.SERIES`."""
    done = subprocess.run([str(exe), str(est), str(gt), align], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    stats: dict[str, np.ndarray] = {}
    rows: dict[str, list[list[float]]] = {}
    for line in done.stdout.splitlines():  # ov_eval prints its warnings on stdout too
        p = line.split()
        if p and p[0] == "stat":
            stats[p[1]] = np.array(p[2:], float)
        elif p and p[0] == "val":
            rows.setdefault(p[1], []).append([float(x) for x in p[2:]])
    return stats, {k: np.array(v) for k, v in rows.items()}
