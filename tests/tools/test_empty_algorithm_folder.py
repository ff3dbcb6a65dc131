"""An algorithm folder holding no result file (every run of it crashed, or its files have another
suffix) was left out of every table and the report without a word; a warning names it. A folder
inside an algorithm's (its logs) is no algorithm and is not named."""

from __future__ import annotations

import shutil

import pytest

import lorisnb as ln
from lorisnb.errors import LorisWarning


def test_an_empty_algorithm_folder_is_named(tmp_path, icra20, data):
    res = tmp_path / "res"
    shutil.copytree(icra20 / "per-seq" / "odom", res / "odom")
    (res / "crashed").mkdir()
    (res / "crashed" / "log.out").write_text("segfault\n")
    (res / "odom" / "logs").mkdir()
    with pytest.warns(LorisWarning, match=r"1 folder\(s\) beside the algorithms' hold no result file.*: crashed$") as w:
        ev = ln.evaluate(res, data_root=data)
    assert set(ev.sequences()["algorithm"]) == {"odom"}
    assert not any("logs" in str(x.message) for x in w)


def test_nested_suites_and_the_current_folder_name_empty_algorithms_alike(tmp_path, icra20, data, monkeypatch):
    """The check on path strings (5,000 files: 0.2 s of pathlib objects before) names the same
    folders whether the root is given absolute, relative, as ``.`` or with a trailing slash, and
    with suites (``root/<suite>/<algorithm>/``): an algorithm folder of a suite without result
    files, never a suite holding algorithms."""
    res = tmp_path / "res"
    shutil.copytree(icra20 / "per-seq" / "odom", res / "per-seq" / "odom")
    (res / "per-seq" / "crashed" / "logs").mkdir(parents=True)
    (res / "lifelong" / "odom").mkdir(parents=True)
    shutil.copy(
        icra20 / "lifelong" / "vins_mono_color_imu_with_loop" / "cafe-1.txt", res / "lifelong" / "odom" / "c.txt"
    )
    monkeypatch.chdir(tmp_path)
    for root in (res, "res", "res/"):
        with pytest.warns(LorisWarning, match=r"1 folder\(s\) beside the algorithms' .*: per-seq/crashed$"):
            ln.evaluate(root, data_root=data)
    monkeypatch.chdir(res)
    with pytest.warns(LorisWarning, match=r"1 folder\(s\) beside the algorithms' .*: per-seq/crashed$"):
        ev = ln.evaluate(".", data_root=data)
    assert set(ev.sequences()["suite"]) == {"per-seq", "lifelong"}


def test_the_datas_ground_truth_among_the_inputs_is_left_out_whatever_it_is_named(tmp_path, icra20, data):
    """A link to the data root's ground truth among the result files (by another name) is left out
    with a warning: compared as the same file (device and inode), not by path."""
    res = tmp_path / "res"
    shutil.copytree(icra20 / "per-seq" / "odom", res / "odom")
    (res / "copied").mkdir()
    (res / "copied" / "cafe-1-1.txt").symlink_to(data.groundtruth("cafe"))
    with pytest.warns(LorisWarning, match=r"1 ground-truth file\(s\) of the data among the inputs, left out"):
        ev = ln.evaluate(res, data_root=data)
    assert set(ev.sequences()["algorithm"]) == {"odom"}
