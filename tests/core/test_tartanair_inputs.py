"""tartanair_tools run here (its ``TartanAirEvaluator``, tests/peers.py) on inputs its example never
gave it: the bundled fr1/xyz RGBD-SLAM run paired with its ground truth, cut to 3..101 poses (below 100
poses its RPE takes all n^2 pairs, i = j included, where the arccos of an identity error is rounding:
lorisnb differed by up to 4e-7 relative until it turned its relative poses into quaternions and back
as tartanair_tools does), and moved onto the plane z = 0 with the scale rule, where ground-truth steps
of exactly 0.1 mm (4-decimal positions) sit on the rule's threshold."""

from __future__ import annotations

import random

import numpy as np
import pytest
import test_tartanair_tools

from lorisnb.core.metrics.tartanair import tartanair_scores
from lorisnb.errors import LorisWarning

# tartanair_tools imported once, as its own tests import it
evaluator = test_tartanair_tools.evaluator
monkeypatch_module = test_tartanair_tools.monkeypatch_module


@pytest.fixture(scope="module")
def fr1(data):
    g = np.loadtxt(data.tum / "freiburg1_xyz-groundtruth.txt")
    e = np.loadtxt(data.tum / "freiburg1_xyz-rgbdslam.txt")
    k = np.clip(np.searchsorted(g[:, 0], e[:, 0]), 0, len(g) - 1)
    return g[k, 1:], e[:, 1:]


def _peer(evaluator, tmp_path, capsys, g, e, scale, seed):
    ev, _ = evaluator
    np.savetxt(tmp_path / "g.txt", g, fmt="%.17g")
    np.savetxt(tmp_path / "e.txt", e, fmt="%.17g")
    random.seed(seed)
    out = ev.evaluate_one_trajectory(str(tmp_path / "g.txt"), str(tmp_path / "e.txt"), scale=scale)
    printed = capsys.readouterr().out  # with scale: '  Scale, S' (its rule's)
    out["scale"] = float(printed.split("Scale, ")[1].split()[0]) if "Scale, " in printed else 1.0
    return out


@pytest.mark.parametrize("n", [3, 5, 10, 99, 101])
@pytest.mark.parametrize("scale", [False, True])
def test_short_cuts_equal_tartanair_tools(evaluator, fr1, tmp_path, capsys, n, scale):
    g, e = fr1[0][:n], fr1[1][:n]
    theirs = _peer(evaluator, tmp_path, capsys, g, e, scale, 0)
    ours = tartanair_scores(g[:, :3], g[:, 3:], e[:, :3], e[:, 3:], scale=scale, seed=0)
    assert ours["tartanair_ate"] == pytest.approx(theirs["ate_score"], rel=1e-12)
    assert ours["tartanair_rpe_rot"] == pytest.approx(theirs["rpe_score"][0], rel=1e-12)
    assert ours["tartanair_rpe_trans"] == pytest.approx(theirs["rpe_score"][1], rel=1e-12)
    kr, kt = theirs["kitti_score"]
    for col, want in (("tartanair_kitti_r", kr), ("tartanair_kitti_t", kt)):
        assert ours[col] == pytest.approx(want, rel=1e-12, nan_ok=True)


def test_a_step_on_the_scale_threshold_is_said(evaluator, fr1, tmp_path, capsys):
    g, e = fr1[0].copy(), fr1[1].copy()
    g[:, 2] = e[:, 2] = 0.0
    theirs = _peer(evaluator, tmp_path, capsys, g, e, True, 0)
    ours = tartanair_scores(g[:, :3], g[:, 3:], e[:, :3], e[:, 3:], scale=True, seed=0)
    assert ours["tartanair_rpe_trans"] == pytest.approx(theirs["rpe_score"][1], rel=1e-12)  # the file's own bits
    q = g[:, 3:] / np.linalg.norm(g[:, 3:], axis=1, keepdims=True)  # as lorisnb's reader gives them
    with pytest.warns(LorisWarning, match=r"step\(s\) are 0.1 mm to within rounding") as said:
        tartanair_scores(g[:, :3], q, e[:, :3], e[:, 3:], scale=True, seed=0)
    lo, hi = (float(v) for v in str(said[0].message).split("a scale from ")[1].split(" (")[0].split(" to "))
    assert lo * (1 - 1e-8) <= theirs["scale"] <= hi * (1 + 1e-8)
