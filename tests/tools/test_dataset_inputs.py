"""Walked inputs: the dataset folder's ground truth and documents are not estimates, and a file
named twice (alone and in its folder) has the same labels whatever the order of the inputs."""

from __future__ import annotations

import shutil

import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.errors import FailedInputsWarning
from lorisnb.tools.evaluation.inputs import result_files


def _results(icra20, root, names=("cafe-1-1.txt", "cafe-1-2.txt")):
    (root / "mine" / "ds-slam").mkdir(parents=True)
    for n in names:
        shutil.copy(icra20 / "per-seq" / "ds-slam" / n, root / "mine" / "ds-slam" / n)
    return root


def test_the_data_groundtruth_and_license_in_a_walk_are_not_estimates(data, icra20, tmp_path):
    """As the dataset folder holds them (groundtruth/gt_*.txt scored CR 1.0 as an algorithm
    'groundtruth'; LICENSE.txt failed): left out, the ground truth with a note."""
    root = _results(icra20, tmp_path / "ds")
    (root / "groundtruth").symlink_to(data.openloris / "groundtruth", target_is_directory=True)
    shutil.copy(data.openloris / "LICENSE.txt", root / "LICENSE.txt")
    (root / "mine" / "README.TXT").write_text("notes on the runs\n")
    assert [p.name for p, _ in result_files(root) if p.suffix == ".txt"].count("LICENSE.txt") == 0
    with pytest.warns(ln.LorisWarning, match=r"4 ground-truth file\(s\) of the data among the inputs, left out"):
        ev = ln.evaluate(root, data_root=data.root)
    assert sorted({f.algorithm for f in ev.errors}) == ["ds-slam"]
    assert ev.failures == [] and ev.exit_status() == 0
    with pytest.raises(ln.ValidationError, match="only the data's ground truth"):
        ln.evaluate(data.openloris / "groundtruth" / "gt_cafe_1.txt", data_root=data.root)


def test_a_license_named_as_an_input_is_read_as_any_file(data):
    with pytest.warns(FailedInputsWarning):
        ev = ln.evaluate(data.openloris / "LICENSE.txt", data_root=data.root)
    assert len(ev.failures) == 1


def test_a_file_named_alone_and_in_its_folder_has_the_folder_labels_in_any_order(icra20, tmp_path):
    root = _results(icra20, tmp_path / "res")
    f = root / "mine" / "ds-slam" / "cafe-1-1.txt"
    tables = []
    for order in ([root, f], [f, root], [f, root / "mine", root], [root / "mine", f, root]):
        with pytest.warns(ln.LorisWarning, match="named more than once"):
            ev = ln.evaluate(order, progress=False)
        s = ev.scenes(eps="paper", phi=30)
        assert s.suite.tolist() == ["mine"] and s.sequences.tolist() == [2]
        tables.append(s)
    for t in tables[1:]:
        pd.testing.assert_frame_equal(t, tables[0])
