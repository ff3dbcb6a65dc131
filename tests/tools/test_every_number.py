"""One trajectory, every benchmark's number (:mod:`lorisnb.tools.peers.every_number`): the same real
pair under every preset, each number the preset's own (checked against the peer where one runs here:
evo for the evo row, the KITTI devkit's numbers by the kitti tests)."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from evo.core import metrics as em
from evo.core import sync
from evo.main_ape import ape
from evo.tools import file_interface as fi

from lorisnb.tools.peers.every_number import PRESETS, every_number, side_by_side


def test_every_preset_on_the_tum_pair(data):
    gt, est = data.tum / "freiburg1_xyz-groundtruth.txt", data.tum / "freiburg1_xyz-rgbdslam.txt"
    table = every_number(est, gt)
    assert set(table.preset) == set(PRESETS) and table["why"].str.len().min() > 30
    wide = side_by_side(table)
    ate = wide.loc[("ATE RMSE", "m")]
    ref, e = sync.associate_trajectories(
        fi.read_tum_trajectory_file(gt), fi.read_tum_trajectory_file(est), max_diff=0.01
    )
    theirs = ape(copy.deepcopy(ref), copy.deepcopy(e), em.PoseRelation.translation_part).stats["rmse"]
    assert ate["evo"] == pytest.approx(theirs, rel=1e-9)  # evo's own number (no alignment)
    assert ate["tum"] < ate["evo"] and ate["rpg"] <= ate["tum"] + 1e-12  # SE(3) and Sim(3) fits absorb error
    assert wide.loc[("matched poses", "")]["evo"] == ref.num_poses
    # 9 m of ground truth: no 100 m KITTI segment, said as 0 segments and NaN errors
    assert wide.loc[("KITTI segments", "")]["kitti"] == 0 and np.isnan(
        wide.loc[("KITTI translational error", "%")]["kitti"]
    )
    assert np.isfinite(wide.loc[("TartanAir ATE", "m")]["tartanair"])


def test_a_preset_that_cannot_pair_says_why(data, tmp_path):
    gt = data.tum / "freiburg1_xyz-groundtruth.txt"
    late = tmp_path / "late.txt"
    rows = np.loadtxt(data.tum / "freiburg1_xyz-rgbdslam.txt")
    rows[:, 0] += 1000.0
    np.savetxt(late, rows, fmt="%.6f")
    table = every_number(late, gt, presets=("tum",))
    assert table.set_index("quantity").loc["matched poses", "value"] == 0
    assert table["value"].iloc[1:].isna().all() and "not scored" in table["why"].iloc[0]


def test_the_numbers_the_guide_quotes():
    """docs/guide/conventions-kitti-tartanair.md quotes these on KITTI 09 (kitti-odom-eval's example)."""
    from peers import kitti_pair

    gt, est = kitti_pair("09")
    wide = side_by_side(every_number(est, gt, fmt="kitti"))
    ate = wide.loc[("ATE RMSE", "m")]
    assert round(ate["openloris"], 2) == round(ate["tum"], 2) == 10.88
    assert round(wide.loc[("TartanAir ATE", "m")]["tartanair"], 2) == 10.88
    assert round(ate["rpg"], 2) == 10.73 and round(ate["evo"], 2) == round(ate["kitti"], 2) == 17.92
    assert round(wide.loc[("KITTI translational error", "%")]["kitti"], 2) == 2.61
    assert round(wide.loc[("KITTI rotational error", "deg/100 m")]["kitti"], 3) == 0.288
