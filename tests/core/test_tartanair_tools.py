"""TartanAir's metrics (:mod:`lorisnb.core.metrics.tartanair`) against tartanair_tools'
``TartanAirEvaluator`` run here (its ``evaluation/`` folder, kept outside the repository:
tests/peers.py) on its own example trajectories (a TartanAir ground truth and an estimate), with and
without its scale, its random RPE pairs drawn after ``random.seed(seed)``. Under numpy 2 two of its
spellings are read as numpy 1 read them (``numpy.linalg.linalg.svd``, ``float()`` of a 1x1 matrix)."""

from __future__ import annotations

import builtins
import importlib
import random

import numpy as np
import pytest
from peers import peer

from lorisnb.core.metrics.tartanair import tartanair_scores


@pytest.fixture(scope="module")
def evaluator(monkeypatch_module):
    folder = peer("tartanair_tools") / "evaluation"
    if not hasattr(np.linalg, "linalg") or not hasattr(np.linalg.linalg, "svd"):  # numpy 2: its module path
        monkeypatch_module.setattr(np.linalg, "linalg", np.linalg, raising=False)
    monkeypatch_module.syspath_prepend(str(folder))
    ate = importlib.import_module("evaluate_ate_scale")  # numpy 2: float() of its 1x1 matrix, read as the scalar
    monkeypatch_module.setattr(ate, "float", lambda x: builtins.float(np.asarray(x).item()), raising=False)
    return importlib.import_module("tartanair_evaluator").TartanAirEvaluator(), folder


@pytest.fixture(scope="module")
def monkeypatch_module():
    with pytest.MonkeyPatch.context() as mp:
        yield mp


@pytest.mark.parametrize("scale", [False, True])
@pytest.mark.parametrize("seed", [0, 7])
@pytest.mark.thorough
def test_scores_equal_tartanair_tools(evaluator, capsys, scale, seed):
    ev, folder = evaluator
    gt, est = folder / "pose_gt.txt", folder / "pose_est.txt"
    random.seed(seed)
    theirs = ev.evaluate_one_trajectory(str(gt), str(est), scale=scale)
    capsys.readouterr()  # it prints its scales
    g, e = np.loadtxt(gt), np.loadtxt(est)
    ours = tartanair_scores(g[:, :3], g[:, 3:], e[:, :3], e[:, 3:], scale=scale, seed=seed)
    assert ours["tartanair_ate"] == pytest.approx(theirs["ate_score"], rel=1e-9)
    assert ours["tartanair_rpe_rot"] == pytest.approx(theirs["rpe_score"][0], rel=1e-9)
    assert ours["tartanair_rpe_trans"] == pytest.approx(theirs["rpe_score"][1], rel=1e-9)
    assert ours["tartanair_kitti_r"] == pytest.approx(theirs["kitti_score"][0], rel=1e-9)
    assert ours["tartanair_kitti_t"] == pytest.approx(theirs["kitti_score"][1], rel=1e-9)
    if scale:
        assert ours["tartanair_scale"] != pytest.approx(1.0, abs=1e-3)


def test_conventions_tartanair_on_a_stamped_pair(evaluator, tmp_path, capsys):
    """``lorisnb evaluate --conventions tartanair``: the same numbers in the sequence table for the
    example written as TUM files (stamps 0.1 s apart), with its scale and a seed."""
    from lorisnb.cli import main

    ev, folder = evaluator
    files = []
    for name in ("pose_gt", "pose_est"):
        poses = np.loadtxt(folder / f"{name}.txt")
        tum = tmp_path / f"{name}.tum"
        tum.write_text(
            "".join(f"{0.1 * k:.1f} " + " ".join(f"{v:.17g}" for v in p) + "\n" for k, p in enumerate(poses))
        )
        files.append(tum)
    random.seed(5)
    theirs = ev.evaluate_one_trajectory(str(folder / "pose_gt.txt"), str(folder / "pose_est.txt"), scale=True)
    out = tmp_path / "t.csv"
    args = ["evaluate", str(files[1]), "--gt", str(files[0]), "--conventions", "tartanair", "--tartanair-scale",
            "--tartanair-seed", "5", "--csv", str(out), "--no-progress"]  # fmt: skip
    assert main(args) == 0
    assert "TartanAir (tartanair_tools)" in capsys.readouterr().err
    import pandas as pd

    row = pd.read_csv(out).iloc[0]
    assert row["matched"] == 734
    assert row["tartanair_ate"] == pytest.approx(theirs["ate_score"], rel=1e-9)
    assert row["tartanair_rpe_rot"] == pytest.approx(theirs["rpe_score"][0], rel=1e-9)
    assert row["tartanair_rpe_trans"] == pytest.approx(theirs["rpe_score"][1], rel=1e-9)
    assert row["tartanair_kitti_r"] == pytest.approx(theirs["kitti_score"][0], rel=1e-9)
    assert row["tartanair_kitti_t"] == pytest.approx(theirs["kitti_score"][1], rel=1e-9)
    assert main(["evaluate", str(files[1]), "--gt", str(files[0]), "--tartanair-seed", "5"]) == 2
