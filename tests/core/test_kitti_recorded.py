"""The KITTI metric (and TartanAir's) against the peers' own numbers on data every machine with ../shared has: the
icra20 ORB-SLAM2 output of market-3 and its ground truth written as KITTI files
(:func:`peers.openloris_kitti_pair`, plain numpy), on which the official ``evaluate_odometry.cpp``
(compiled with g++ by :func:`peers.build_devkit`, run by :func:`peers.run_devkit` on 2026-11-28)
printed the values of :data:`DEVKIT`: its segment count, three of its segments (first frame,
r_err rad/m, t_err m/m, length m, speed m/frame; ``%.9g``) and its means. Where the devkit's source
is at hand (tests/peers.py) the same files are also run through it live."""

from __future__ import annotations

import numpy as np
import pytest
from peers import OPENLORIS_KITTI, build_devkit, openloris_kitti_pair, peers_root, run_devkit

from lorisnb.core.metrics.kitti import kitti_segments, kitti_summary

#: What the devkit printed for OPENLORIS_KITTI[0] (see the module docstring).
DEVKIT = {
    "segments": 136,
    "rows": {0: (0, 0.029720936, 0.312415242, 100, 0.309214592),
             67: (670, 0.0085396627, 0.265709907, 100, 0.348068208),
             135: (1350, 0.0203262903, 0.445078433, 100, 0.436300188)},
    "t_err": 0.297243357,
    "r_err": 0.0190973897,
}  # fmt: skip


@pytest.fixture(scope="module")
def pair(data, tmp_path_factory):
    scene, result = OPENLORIS_KITTI[0]
    return openloris_kitti_pair(data, scene, result, tmp_path_factory.mktemp("kitti"))


def _segments(pair):
    gt, est = (np.loadtxt(p).reshape(-1, 3, 4) for p in pair)
    return kitti_segments(gt, est)


def test_equals_the_devkits_recorded_numbers(pair):
    ours = _segments(pair)
    assert len(ours) == DEVKIT["segments"]
    for i, (first, r_err, t_err, length, speed) in DEVKIT["rows"].items():
        assert ours.first[i] == first and ours.length[i] == length
        assert ours.r_err[i] == pytest.approx(r_err, rel=1e-6)
        assert ours.t_err[i] == pytest.approx(t_err, rel=1e-6)
        assert ours.speed[i] == pytest.approx(speed, rel=1e-6)
    s = kitti_summary(ours)
    assert s["kitti_t_err"] == pytest.approx(100 * DEVKIT["t_err"], rel=1e-6)
    assert s["kitti_r_err"] == pytest.approx(np.degrees(DEVKIT["r_err"]) * 100, rel=1e-6)


@pytest.mark.thorough
def test_equals_the_devkit_run_live(pair, tmp_path):
    if not (peers_root() / "kitti_devkit").is_dir():
        pytest.skip(f"the KITTI devkit is not in {peers_root()} (see tests/peers.py); the recorded test checks it")
    exe = build_devkit(tmp_path)
    theirs, (t_mean, r_mean) = run_devkit(exe, *pair, tmp_path / "out")
    ours = _segments(pair)
    np.testing.assert_array_equal(ours.first, theirs[:, 0])
    np.testing.assert_allclose(ours.t_err, theirs[:, 2], rtol=1e-6)
    np.testing.assert_allclose(ours.r_err, theirs[:, 1], rtol=1e-6)
    assert (t_mean, r_mean) == pytest.approx((DEVKIT["t_err"], DEVKIT["r_err"]), rel=1e-8)


#: What tartanair_tools' ``TartanAirEvaluator.evaluate_one_trajectory`` returned on 2026-11-28 for
#: the same pair (positions and xyzw quaternions written with ``np.savetxt``, which round-trips),
#: after ``random.seed(0)``, without and with its scale: ate_score, rpe_score (rot, trans),
#: kitti_score (r, t).
TARTANAIR = {
    False: (2.1257302185826727, (1.878151479747989, 30.609313857710106), (5.560753242653356, 1.2172105568273834)),
    True: (2.1169955296593135, (1.878151479747989, 27.883943179949398), (5.560753242653356, 1.1084883406022232)),
}


@pytest.mark.parametrize("scale", [False, True])
def test_tartanair_equals_its_tools_recorded_numbers(data, scale):
    from peers import openloris_pose_pair

    from lorisnb.core.metrics.tartanair import tartanair_scores

    gp, gq, ep, eq = openloris_pose_pair(data, *OPENLORIS_KITTI[0])
    ours = tartanair_scores(gp, gq, ep, eq, scale=scale, seed=0)
    ate, (rpe_rot, rpe_trans), (kitti_r, kitti_t) = TARTANAIR[scale]
    assert ours["tartanair_ate"] == pytest.approx(ate, rel=1e-9)
    assert ours["tartanair_rpe_rot"] == pytest.approx(rpe_rot, rel=1e-9)
    assert ours["tartanair_rpe_trans"] == pytest.approx(rpe_trans, rel=1e-9)
    assert ours["tartanair_kitti_r"] == pytest.approx(kitti_r, rel=1e-9)
    assert ours["tartanair_kitti_t"] == pytest.approx(kitti_t, rel=1e-9)
