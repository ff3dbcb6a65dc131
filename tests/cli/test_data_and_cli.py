"""Data location, shipped extrinsics, and the `lorisnb evaluate` command line."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from helpers import write

from lorisnb.cli import main
from lorisnb.core.pipeline.model import SEQUENCE_COLUMNS
from lorisnb.core.trajectory.frames import extrinsic
from lorisnb.errors import DataNotFoundError
from lorisnb.io import find_data


def test_find_data_order_and_error(tmp_path, monkeypatch, data):
    monkeypatch.delenv("LORISNB_DATA", raising=False)  # whatever the developer has set
    try:
        fallback = find_data().root  # ../shared/data next to the folder or the project
    except DataNotFoundError:
        fallback = None
    monkeypatch.setenv("LORISNB_DATA", str(data.root))
    assert find_data().root == data.root
    assert find_data(data.root).root == data.root
    monkeypatch.setenv("LORISNB_DATA", str(tmp_path / "missing"))
    # the environment variable set to no data root is an error, not passed over for ../shared/data
    # (a typo would quietly evaluate against other data)
    with pytest.raises(DataNotFoundError, match=r"LORISNB_DATA=.*missing: does not exist"):
        find_data()
    (tmp_path / "empty").mkdir()
    monkeypatch.setenv("LORISNB_DATA", str(tmp_path / "empty"))
    with pytest.raises(DataNotFoundError, match="empty: not a data root"):
        find_data()
    assert find_data(data.root).root == data.root  # an explicit root comes first
    monkeypatch.setenv("LORISNB_DATA", "")  # empty: not set
    if fallback is None:
        with pytest.raises(DataNotFoundError):
            find_data()
    else:
        assert find_data().root == fallback
    with pytest.raises(DataNotFoundError) as exc:
        find_data(tmp_path / "nowhere")
    msg = str(exc.value)
    assert str(tmp_path / "nowhere") in msg and "LORISNB_DATA" in msg and "--data" in msg
    # one line: the command line escapes a message's line breaks (it printed "It looked at:\n  - ...")
    assert "\n" not in msg
    done = subprocess.run([sys.executable, "-m", "lorisnb.cli", "evaluate", str(tmp_path), "--data",
                           str(tmp_path / "nowhere"), "--no-progress"], capture_output=True, text=True, timeout=60)  # fmt: skip
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and "\\n" not in done.stderr, done.stderr
    assert f"It looked at: {tmp_path / 'nowhere'} (argument): does not exist." in done.stderr
    (tmp_path / "gt.txt").write_text("1 0 0 0 0 0 0 1\n")  # a file where a folder goes: said so (it "did not exist")
    with pytest.raises(DataNotFoundError, match=r"gt.txt \(argument\): a file, not a folder\."):
        find_data(tmp_path / "gt.txt")


def test_missing_groundtruth_names_the_file(tmp_path):
    (tmp_path / "openloris-scene" / "groundtruth").mkdir(parents=True)
    with pytest.raises(DataNotFoundError, match="gt_cafe_1.txt"):
        find_data(tmp_path).groundtruth("cafe")


def test_shipped_extrinsics_equal_the_benchmark_json(data):
    doc = json.loads(data.extrinsics_json.read_text())
    n = 0
    for robot in doc["robots"].values():
        for tr in robot["transforms"]:
            if tr["parent"] != "base_link":
                continue
            for scene in robot["scenes"]:
                t, q = extrinsic(scene, tr["child"])
                np.testing.assert_array_equal(t, tr["xyz"])
                np.testing.assert_array_equal(q, tr["quat_xyzw"])
                n += 1
    assert n == 6 * 5


@pytest.fixture
def results_tree(tmp_path, icra20):
    root = tmp_path / "results"
    for rel in [
        "per-seq/orbslam2_rgbd/cafe_1_1_orbslam2-original.txt",
        "per-seq/vins_mono_color_imu_with_loop/home-1-3.txt",
    ]:
        src = icra20 / rel
        write(root, f"{src.parent.name}/{src.name}", src.read_bytes())
    write(root, "broken/cafe 1 1 bad.txt", "scene: cafe\nframe: d400_color\nseq: 1\n1 2 3\n")
    return root


def test_evaluate_cli_reports_broken_file_and_writes_csv(results_tree, tmp_path, capsys):
    out = tmp_path / "out.csv"
    rc = main(["evaluate", str(results_tree), "--csv", str(out), "--no-progress"])
    assert rc == 1  # one file failed
    err = capsys.readouterr().err
    assert "cafe 1 1 bad.txt, line 4:" in err and "expected 8 or 9 numbers" in err
    df = pd.read_csv(out)
    assert list(df.columns[: len(SEQUENCE_COLUMNS)]) == SEQUENCE_COLUMNS
    assert set(df["algorithm"]) == {"orbslam2_rgbd", "vins_mono_color_imu_with_loop"}
    row = df.set_index("algorithm").loc["vins_mono_color_imu_with_loop"]
    assert row["file"] == "vins_mono_color_imu_with_loop/home-1-3.txt"
    assert row["cr"] == pytest.approx(0.926380, abs=1e-6)
    # an existing CSV is not replaced without --force
    before = out.read_bytes()
    assert main(["evaluate", str(results_tree), "--csv", str(out), "--no-progress"]) == 2
    assert out.read_bytes() == before
    assert "exists" in capsys.readouterr().err


def test_evaluate_cli_paper_thresholds(icra20, tmp_path, capsys):
    out = tmp_path / "ll.csv"
    rc = main(
        [
            "evaluate",
            str(icra20 / "lifelong/maslam/cafe.txt"),
            "--eps",
            "0.3",
            "--phi",
            "10",
            "--csv",
            str(out),
            "--no-progress",
        ]
    )
    assert rc == 0
    df = pd.read_csv(out).set_index("seq")
    assert df.loc[2, "cr"] == pytest.approx(0.137731, abs=1e-6)
    assert (df["eps"] == 0.3).all() and (df["phi"] == 10).all()
    assert "scene" in capsys.readouterr().out


def test_cli_rejects_bad_threshold(capsys):
    with pytest.raises(SystemExit):
        main(["evaluate", "x.txt", "--eps", "big"])
    assert "is not a number" in capsys.readouterr().err


def test_command_ends_quietly_when_its_output_is_cut(icra20):
    """``lorisnb evaluate ... | head``: when the reader is gone, no traceback, exit status 1."""
    import os
    import subprocess
    import sys

    read, write = os.pipe()
    os.close(read)  # the reader left before the first line
    try:
        proc = subprocess.run(
            [sys.executable, "-m", "lorisnb.cli", "evaluate", "--no-progress", str(icra20 / "lifelong" / "ds-slam")],
            stdout=write, stderr=subprocess.PIPE, timeout=120, check=False,
        )  # fmt: skip
    finally:
        os.close(write)
    err = proc.stderr.decode()
    assert proc.returncode == 1, err
    assert "Traceback" not in err and "BrokenPipe" not in err


def test_a_lone_file_of_a_scene_without_ground_truth_is_counted_once(tmp_path, icra20, capsys):
    """A file whose scene has no public ground truth (office) alone: '0 not scored, 1 skipped', exit 1
    (it read '1 not scored, 1 skipped': the line 'nothing was evaluated' counted as an input)."""
    src = (icra20 / "per-seq" / "odom" / "cafe-1-1-odom.txt").read_text()
    f = write(tmp_path, "office.txt", src.replace("scene: cafe", "scene: office"))
    assert main(["evaluate", str(f), "--no-progress"]) == 1
    err = capsys.readouterr().err
    assert "nothing was evaluated: every input was skipped" in err
    assert "0 file(s) evaluated, 0 failed, 0 not scored, 1 skipped" in err, err
