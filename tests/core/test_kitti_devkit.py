"""The KITTI odometry metric (:mod:`lorisnb.core.metrics.kitti`) against the official devkit's
``evaluate_odometry.cpp`` compiled here with g++ (its ``calcSequenceErrors``, ``saveStats`` and
``saveErrorPlots`` called by a small driver of ours) and against kitti-odom-eval's double-precision
``KittiEvalOdom``, on real KITTI poses (sequences 09 and 10: the ground truth and a learned visual
odometry's estimates, from kitti-odom-eval; see tests/peers.py for where the peers are kept)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest
from peers import KITTI_SEQUENCES as SEQUENCES
from peers import build_devkit, kitti_pair, peer, run_devkit

from lorisnb.core.metrics.kitti import (
    KITTI_LENGTHS,
    kitti_length_errors,
    kitti_segments,
    kitti_summary,
)


@pytest.fixture(scope="module")
def devkit(tmp_path_factory) -> Path:
    return build_devkit(tmp_path_factory.mktemp("devkit"))


@pytest.fixture(scope="module")
def kitti_files() -> dict[str, tuple[Path, Path]]:
    return {s: kitti_pair(s) for s in SEQUENCES}


def matrices(path: Path) -> np.ndarray:
    return np.loadtxt(path).reshape(-1, 3, 4)


@pytest.mark.parametrize("seq", SEQUENCES)
@pytest.mark.thorough
def test_single_precision_equals_devkit(devkit, kitti_files, tmp_path, seq):
    gt_file, est_file = kitti_files[seq]
    theirs, (t_mean, r_mean) = run_devkit(devkit, gt_file, est_file, tmp_path / "out")
    ours = kitti_segments(matrices(gt_file), matrices(est_file))
    assert len(ours) == len(theirs) > 400
    np.testing.assert_array_equal(ours.first, theirs[:, 0])
    np.testing.assert_array_equal(ours.length, theirs[:, 3])
    np.testing.assert_allclose(ours.speed, theirs[:, 4], rtol=1e-6)
    np.testing.assert_allclose(ours.t_err, theirs[:, 2], rtol=1e-6)
    # the float angle: equal where the float cosine is (a rounding flip of the matrices' last bits would move it)
    np.testing.assert_allclose(ours.r_err, theirs[:, 1], rtol=1e-6)
    s = kitti_summary(ours)
    assert s["kitti_t_err"] == pytest.approx(100 * t_mean, rel=1e-6)
    assert s["kitti_r_err"] == pytest.approx(np.degrees(r_mean) * 100, rel=1e-6)
    stats = np.loadtxt(tmp_path / "out" / "stats.txt")  # the devkit's own file, %f: 6 decimals
    assert s["kitti_t_err"] / 100 == pytest.approx(stats[0], abs=5e-7)
    assert np.radians(s["kitti_r_err"] / 100) == pytest.approx(stats[1], abs=5e-7)
    lengths = kitti_length_errors(ours)
    tl = np.loadtxt(tmp_path / "out" / "seq_tl.txt", ndmin=2)
    rl = np.loadtxt(tmp_path / "out" / "seq_rl.txt", ndmin=2)
    plotted = lengths[lengths.plotted]
    np.testing.assert_array_equal(plotted.length, tl[:, 0])
    np.testing.assert_allclose(plotted.t_err / 100, tl[:, 1], atol=5e-7)
    np.testing.assert_allclose(np.radians(plotted.r_err / 100), rl[:, 1], atol=5e-7)


def test_both_sequences_averaged_as_the_devkit(kitti_files):
    """The devkit's summary is over every segment of every sequence (its total_err), not a mean of means."""
    from lorisnb.core.metrics.kitti import concat_segments

    parts = [kitti_segments(matrices(kitti_files[s][0]), matrices(kitti_files[s][1])) for s in SEQUENCES]
    both = kitti_summary(concat_segments(parts))
    t = np.cumsum(np.concatenate([p.t_err for p in parts]), dtype=np.float32)[-1] / np.float32(sum(map(len, parts)))
    assert both["kitti_t_err"] == pytest.approx(100 * float(t), rel=1e-7)
    each = [kitti_summary(p)["kitti_t_err"] for p in parts]
    assert both["kitti_t_err"] != pytest.approx(np.mean(each), rel=1e-4)


def _kitti_odom_eval():
    root = peer("kitti-odom-eval")
    spec = importlib.util.spec_from_file_location("kitti_odometry_peer", root / "kitti_odometry.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("kitti_odometry_peer", module)
    spec.loader.exec_module(module)
    return module.KittiEvalOdom()


@pytest.mark.parametrize("seq", SEQUENCES)
def test_double_precision_equals_kitti_odom_eval(kitti_files, seq):
    ev = _kitti_odom_eval()
    gt_file, est_file = kitti_files[seq]
    gt, est = ev.load_poses_from_txt(str(gt_file)), ev.load_poses_from_txt(str(est_file))
    theirs = np.array(ev.calc_sequence_errors(gt, est))
    ours = kitti_segments(matrices(gt_file), matrices(est_file), precision="double")
    np.testing.assert_array_equal(ours.first, theirs[:, 0])
    np.testing.assert_allclose(ours.r_err, theirs[:, 1], rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(ours.t_err, theirs[:, 2], rtol=1e-9)
    t, r = ev.compute_overall_err(theirs.tolist())
    s = kitti_summary(ours)
    assert s["kitti_t_err"] == pytest.approx(t * 100, rel=1e-12)
    assert s["kitti_r_err"] == pytest.approx(r / np.pi * 180 * 100, rel=1e-12)
    single = kitti_summary(kitti_segments(matrices(gt_file), matrices(est_file)))
    assert single["kitti_r_err"] != pytest.approx(s["kitti_r_err"], rel=1e-7)  # the float angle shows


def test_lengths_are_the_devkits():
    assert KITTI_LENGTHS == tuple(100.0 * k for k in range(1, 9))


def test_a_mirrored_block_is_refused_where_the_devkit_scores_it(devkit, kitti_files, tmp_path):
    """One rotation block of determinant -1 (an axis flipped by a conversion): the devkit composes it
    as written and gives its errors; lorisnb refuses the file, naming its line (the docs say so)."""
    import lorisnb
    from lorisnb.errors import ParseError

    gt_file, est_file = kitti_files["09"]
    rows = np.loadtxt(est_file)
    rows[5, [0, 4, 8]] *= -1  # the block's diagonal negated: determinant -1
    mirrored = tmp_path / "09.txt"
    np.savetxt(mirrored, rows, fmt="%.9g")
    theirs, (t_mean, _) = run_devkit(devkit, gt_file, mirrored, tmp_path / "out")
    assert len(theirs) > 400 and np.isfinite(t_mean)
    with pytest.raises(ParseError, match=r"line 6: not a rotation"):
        lorisnb.io.read_kitti(mirrored)
    ev = lorisnb.evaluate_pairs(mirrored, gt_file, "kitti", fmt="kitti")
    assert not ev.errors and len(ev.failures) == 1 and "line 6: not a rotation" in ev.failures[0].error
