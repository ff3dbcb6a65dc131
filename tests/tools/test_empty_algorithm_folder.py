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
