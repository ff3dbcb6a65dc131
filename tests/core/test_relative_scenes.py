"""A relative eps (``relative:F``, a fraction of each sequence's extent) is one threshold setting
whose eps in metres differs between sequences. Scene rows grouped by eps in metres split a scene
into one partial row per sequence (``evaluate --eps relative:0.1`` printed four corridor rows whose
CR summed to the scene's; a relative sweep's scene curve averaged those parts). Scene rows are now
grouped by the setting: a sweep's ``eps_value``, else eps in metres unless each sequence has its own.
The oracle is the paper's Eq. 2 by hand: the scene's correct time over its ground-truth time."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from lorisnb.cli import main
from lorisnb.core.lifelong.aggregate import aggregate_scenes
from lorisnb.core.lifelong.sweep import sweep, sweep_scenes
from lorisnb.tools.evaluation.runner import evaluate


@pytest.fixture(scope="module")
def maslam(icra20):
    return evaluate([icra20 / "lifelong" / "maslam"], jobs=1, progress=False)


def _by_hand(table: pd.DataFrame, durations: pd.DataFrame) -> pd.Series:
    total = durations.groupby("scene")["gt_duration"].sum()
    correct = table.groupby("scene")["correct_time"].sum()
    return correct / total[correct.index]


def test_relative_eps_scene_rows_sum_every_sequence(maslam):
    seq = maslam.sequences(eps="relative:0.1")
    matched = seq[seq["matched"] > 0]
    assert matched.groupby("scene")["eps"].nunique().max() > 1  # each sequence its own eps in metres
    scenes = maslam.scenes(eps="relative:0.1")
    assert not scenes.duplicated(["algorithm", "scene"]).any()
    assert len(scenes) == seq["scene"].nunique() == 4
    truth = _by_hand(seq, maslam.durations())
    got = scenes.set_index("scene")["cr"]
    np.testing.assert_allclose(got[truth.index], truth, rtol=1e-12)
    corridor = scenes.set_index("scene").loc["corridor"]
    assert corridor["sequences"] == (seq["scene"] == "corridor").sum()
    assert np.isnan(corridor["eps"])  # no one eps in metres for the scene
    # an absolute eps: the scene's eps is the one given, as before
    assert (maslam.scenes(eps=1.0)["eps"] == 1.0).all()


def test_relative_sweep_scenes_are_the_evaluation_scenes(maslam):
    grid = sweep(maslam.errors, [0.05, 0.1], [np.inf], [1.0], [60.0], relative_to="extent")
    scenes = sweep_scenes(grid, maslam.durations())
    assert not scenes.duplicated(["algorithm", "scene", "eps_value"]).any()
    for f in (0.05, 0.1):
        part = scenes[scenes["eps_value"].astype(float) == f].set_index("scene")["cr"]
        one = maslam.scenes(eps=f"relative:{f}").set_index("scene")["cr"]
        np.testing.assert_allclose(part[one.index], one, rtol=1e-12)


def test_two_absolute_settings_in_one_table_stay_apart(maslam):
    both = pd.concat([maslam.sequences(eps=0.5), maslam.sequences(eps=2.0)], ignore_index=True)
    scenes = aggregate_scenes(both, maslam.durations())
    assert sorted(scenes["eps"].unique()) == [0.5, 2.0]
    assert len(scenes) == 2 * both["scene"].nunique()


def test_evaluate_prints_one_row_per_scene_for_relative_eps(icra20, capsys):
    main(["evaluate", str(icra20 / "lifelong" / "maslam"), "--eps", "relative:0.1", "--no-progress"])
    out = capsys.readouterr().out
    table = out[out.index("per scene") :]
    assert sum(" corridor " in line for line in table.splitlines()) == 1


def test_rankings_along_eps_refuse_a_relative_sweep(maslam):
    from lorisnb.core.lifelong.sweep import rank_stability, rank_swaps
    from lorisnb.errors import ValidationError

    grid = sweep(maslam.errors, [0.05, 0.1], [np.inf], [1.0], [60.0], relative_to="extent")
    scenes = sweep_scenes(grid, maslam.durations())
    for fn in (rank_stability, rank_swaps):
        with pytest.raises(ValidationError, match="relative eps"):
            fn(scenes)


def test_sweep_prints_the_fraction_of_each_relative_scene_row(icra20, capsys):
    main(
        ["sweep", str(icra20 / "lifelong" / "maslam"), "--eps", "0.05,0.1", "--relative-to", "extent", "--no-progress"]
    )
    lines = capsys.readouterr().out.splitlines()
    header = next(line for line in lines if line.split()[:1] == ["suite"])
    assert "eps_value" in header.split()
    corridor = [line.split() for line in lines if " corridor " in line]
    assert len(corridor) == 2 and {row[row.index("corridor") + 2] for row in corridor} == {"0.05", "0.1"}
