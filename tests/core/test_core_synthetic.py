"""The core on synthetic data (tests/helpers.py), no ../shared/data needed: values that follow
from the construction of the trajectories, by hand."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import circle, openloris_fixture, perturbed

import lorisnb as ln
from lorisnb.core import durations_table, sequence_grid


@pytest.fixture
def fixture_errors(tmp_path):
    gt_path, est_path = openloris_fixture(tmp_path)
    gt = ln.read_openloris(gt_path)
    return ln.compute_errors(ln.read_openloris(est_path), gt, algorithm="synthetic"), gt


def test_fixture_scores_as_constructed(fixture_errors):
    errors, gt = fixture_errors
    assert errors.mode == "lifelong" and errors.aligned_on == 1
    table = ln.score(errors, eps=np.inf, phi=30.0, delta=1.0, tau=60.0).set_index("seq")
    # seq 2: poses 0..99 exact, 100..199 turned by 40 deg; 0.1 s apart over a 19.9 s span
    s2 = table.loc[2]
    assert s2["matched"] == 200 and s2["c_matched"] == 100
    assert s2["correct_time"] == pytest.approx(10.0, abs=1e-6)
    assert s2["cr"] == pytest.approx(10.0 / 19.9, abs=1e-6) and s2["cr_t"] == pytest.approx(10.0 / 19.9, abs=1e-6)
    assert s2["cs_r"] == pytest.approx(1.0) and s2["reloc_time"] == 0.0
    assert s2["aoe_rmse"] == pytest.approx(40.0 / np.sqrt(2), abs=0.1)  # plus the small rotation fitted on seq 1
    # seq 1: 0.05 m white noise per axis: ATE RMSE about 0.05 * sqrt(3) after alignment
    assert table.loc[1]["ate_rmse"] == pytest.approx(0.05 * np.sqrt(3), rel=0.15)
    assert table.loc[1]["cr"] == pytest.approx(1.0, abs=1e-9)
    scenes = ln.aggregate_scenes(table.reset_index(), durations_table({"cafe": gt}))
    assert scenes.iloc[0]["cr"] == pytest.approx((19.9 + 10.0) / (2 * 19.9), abs=1e-6)


def test_score_is_the_grid_kernel_on_one_point(fixture_errors):
    errors, _ = fixture_errors
    e = errors.sequences[0]  # seq 1
    grid = sequence_grid(e, [0.05, 0.1], [10.0, 30.0], [0.5, 1.0], [30.0, 60.0])
    for a, eps in enumerate([0.05, 0.1]):
        for b, phi in enumerate([10.0, 30.0]):
            row = ln.score(errors, eps, phi, delta=0.5, tau=60.0).set_index("seq").loc[1]
            assert row["cr"] == grid["cr"][a, b, 0, 1]
            assert row["c_matched"] == grid["c_matched"][a, b, 0, 1]


def test_sequence_errors_recovers_a_rigid_motion():
    gt = circle()
    moved = ln.Trajectory.from_rotations(gt.stamps, gt.positions + [3.0, -2.0, 1.0], gt.rotations())
    e = ln.sequence_errors(gt, moved)
    assert e.matched == len(gt) and np.max(e.ate) < 1e-9 and np.max(e.aoe) < 1e-6


def test_path_length_and_extent():
    gt = circle(n=400, radius_m=2.0)
    assert gt.path_length == pytest.approx(2 * np.pi * 2.0 * 399 / 400, rel=1e-4)  # the open polygon
    assert gt.extent == pytest.approx(np.hypot(4.0, 4.0), rel=1e-3)
    assert perturbed(gt).extent == gt.extent
