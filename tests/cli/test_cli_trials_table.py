"""The printed scene tables of ``lorisnb evaluate`` and ``lorisnb sweep`` (in memory and streamed
to Parquet) when the files are several trials: each trial's scene row says its trial, with the
values of ``Evaluation.scenes()`` for that trial (the rows looked alike before: two "dso home"
rows with different CR and nothing to tell them apart)."""

from __future__ import annotations

import numpy as np
import pytest

import lorisnb as ln
from lorisnb.cli import main

#: Two trials of one algorithm's results: trial 1 DSO's, trial 2 ORB-SLAM2's (real icra20 files).
TRIALS = {
    1: {"cafe-1-1-all.txt": "dso/cafe-1-1-all.txt", "home-1-1-all.txt": "dso/home-1-1-all.txt"},
    2: {
        "cafe-1-1-all.txt": "orbslam2_rgbd/cafe_1_1_orbslam2-original.txt",
        "home-1-1-all.txt": "orbslam2_rgbd/home_1_1_orbslam2-original.txt",
    },
}


@pytest.fixture
def trials(icra20, tmp_path):
    for trial, files in TRIALS.items():
        folder = tmp_path / "results" / "slam" / f"trial{trial}"
        folder.mkdir(parents=True)
        for name, source in files.items():
            (folder / name).symlink_to(icra20 / "per-seq" / source)
    return tmp_path / "results"


def _scene_rows(out: str, header_start: str) -> tuple[list[str], list[list[str]]]:
    lines = out.splitlines()
    at = next(i for i, line in enumerate(lines) if line.split()[:1] == [header_start] and "scene" in line.split())
    header = lines[at].split()
    rows = [line.split() for line in lines[at + 1 :] if line.strip() and len(line.split()) == len(header) - 1]
    return header, rows  # suite is empty: one token fewer


@pytest.mark.parametrize("command", ["evaluate", "sweep", "sweep-parquet"])
@pytest.mark.thorough
def test_scene_rows_name_their_trial(trials, tmp_path, capsys, command):
    expected = ln.evaluate(trials, progress=False, eps=1.0).scenes()
    assert sorted(expected["trial"].unique()) == [1, 2]
    argv = ["evaluate", str(trials)] if command == "evaluate" else ["sweep", str(trials), "--eps", "0.1,1"]
    if command == "sweep-parquet":
        argv += ["--parquet", str(tmp_path / "swept")]
    main([*argv, "--no-progress"] + (["--eps", "1"] if command == "evaluate" else []))
    header, rows = _scene_rows(capsys.readouterr().out, "suite")
    assert header[:4] == ["suite", "algorithm", "scene", "trial"]
    seen = set()
    for row in rows:
        values = dict(zip(header[1:], row, strict=True))
        if command != "evaluate" and float(values["eps"]) != 1.0:
            continue
        want = expected[(expected["scene"] == values["scene"]) & (expected["trial"] == int(values["trial"]))]
        assert len(want) == 1
        np.testing.assert_allclose(float(values["cr"]), want["cr"].iloc[0], atol=5e-5)  # printed to 4 digits
        seen.add((values["scene"], int(values["trial"])))
    assert seen == {(s, t) for s in ("cafe", "home") for t in (1, 2)}


def test_one_trial_prints_no_trial_column(icra20, tmp_path, capsys):
    folder = tmp_path / "results" / "slam"
    folder.mkdir(parents=True)
    (folder / "cafe-1-1-all.txt").symlink_to(icra20 / "per-seq" / "dso" / "cafe-1-1-all.txt")
    main(["evaluate", str(tmp_path / "results"), "--no-progress"])
    header, rows = _scene_rows(capsys.readouterr().out, "suite")
    assert "trial" not in header and len(rows) == 1
