"""Labels never depend on the current directory: a file typed inside its algorithm's folder is that
algorithm's (``--scale auto`` knows dso: ATE 2.26, not SE(3)'s 3.21), a ground truth typed inside
its scene's folder names that scene (``groundtruth.txt`` inside ``fr2_desk/`` was scene
'groundtruth', so ``diff`` called identical numbers a regression)."""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import pytest

import lorisnb as ln
from lorisnb.errors import LorisWarning


@pytest.fixture
def est(tmp_path, data) -> Path:
    path = tmp_path / "orb.txt"
    shutil.copy(data.tum / "fr2_desk_ORB.txt", path)
    return path


def test_labels_do_not_depend_on_the_current_directory(data, icra20, monkeypatch):
    """cafe-1-1-all.txt typed inside dso/: algorithm '' and SE(3) (ATE 3.21); now dso, Sim(3) (2.26)."""
    folder = icra20 / "per-seq" / "dso"
    full = ln.evaluate(folder / "cafe-1-1-all.txt", data_root=data, scale="auto").sequences()
    monkeypatch.chdir(folder)
    here = ln.evaluate("cafe-1-1-all.txt", data_root=data, scale="auto").sequences()
    dot = ln.evaluate(".", data_root=data, scale="auto", scenes=["cafe"]).sequences()
    assert list(full["algorithm"]) == list(here["algorithm"]) == ["dso"] and set(dot["algorithm"]) == {"dso"}
    assert round(here["ate_rmse"].iloc[0], 4) == round(full["ate_rmse"].iloc[0], 4) == 2.2649


def test_a_pairs_scene_does_not_depend_on_the_current_directory(tmp_path, data, est, monkeypatch):
    scene = tmp_path / "fr2_desk"
    scene.mkdir()
    shutil.copy(data.tum / "fr2_desk_groundtruth.txt", scene / "groundtruth.txt")
    shutil.copy(data.tum / "fr2_desk_groundtruth.txt", scene / "gt.txt")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LorisWarning)
        given = ln.evaluate_pairs(est, scene / "groundtruth.txt").sequences()
        monkeypatch.chdir(scene)
        inside = ln.evaluate_pairs(est, "groundtruth.txt").sequences()
        short = ln.evaluate_pairs(est, "gt.txt").sequences()
    assert list(given["scene"]) == list(inside["scene"]) == list(short["scene"]) == ["fr2_desk"]
