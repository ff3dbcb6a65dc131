"""Issue 45, point 3: evo's ``-r point_distance_error_ratio`` (evo_rpe) and ``--change_unit`` as
``--relation`` / ``--change-unit`` of ``lorisnb evaluate --conventions evo``, against evo 1.38's API on
the bundled TUM RGB-D pair (sync as evo_ape / evo_rpe do)."""

from __future__ import annotations

import copy

import pandas as pd
import pytest
from evo.core import metrics as em
from evo.core import sync
from evo.core.units import Unit
from evo.main_ape import ape
from evo.main_rpe import rpe
from evo.tools import file_interface as fi

from lorisnb.cli import main

STATS = ("rmse", "mean", "median", "std", "min", "max", "sse")
GT, EST = "freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"


def ours(data, tmp_path, args: list[str]) -> pd.Series:
    out = tmp_path / "out.csv"
    assert main(["evaluate", str(data.tum / EST), "--gt", str(data.tum / GT), "--conventions", "evo", *args,
                 "--csv", str(out), "--force", "--no-progress"]) == 0  # fmt: skip
    return pd.read_csv(out).iloc[0]


def theirs(data):
    ref, est = fi.read_tum_trajectory_file(data.tum / GT), fi.read_tum_trajectory_file(data.tum / EST)
    return sync.associate_trajectories(ref, est, max_diff=0.01)


@pytest.mark.parametrize("delta", [1, 10])
def test_point_distance_error_ratio_equals_evo_rpe(data, tmp_path, delta):
    row = ours(data, tmp_path, ["--relation", "point_distance_error_ratio", "--rpe-delta", str(delta)])
    ref, est = theirs(data)
    r = rpe(ref, est, em.PoseRelation.point_distance_error_ratio, delta=delta, delta_unit=em.Unit.frames)
    for k in STATS:
        assert row[f"rpe_{k}"] == pytest.approx(r.stats[k], rel=1e-9), k
    assert all(pd.isna(row[f"ape_{k}"]) for k in STATS)  # evo_ape has no such relation


@pytest.mark.parametrize(
    ("relation", "evo_relation", "unit", "evo_unit"),
    [("trans_part", em.PoseRelation.translation_part, "mm", Unit.millimeters),
     ("angle_deg", em.PoseRelation.rotation_angle_deg, "rad", Unit.radians),
     ("point_distance", em.PoseRelation.point_distance, "km", Unit.kilometers)],
)  # fmt: skip
def test_change_unit_equals_evo(data, tmp_path, relation, evo_relation, unit, evo_unit):
    row = ours(data, tmp_path, ["--relation", relation, "--change-unit", unit])
    ref, est = theirs(data)
    a = ape(copy.deepcopy(ref), copy.deepcopy(est), evo_relation, change_unit=evo_unit)
    r = rpe(copy.deepcopy(ref), copy.deepcopy(est), evo_relation, delta=1, delta_unit=em.Unit.frames,
            change_unit=evo_unit)  # fmt: skip
    for k in STATS:
        assert row[f"ape_{k}"] == pytest.approx(a.stats[k], rel=1e-9), k
        assert row[f"rpe_{k}"] == pytest.approx(r.stats[k], rel=1e-9), k


@pytest.mark.parametrize(
    ("args", "message"),
    [(["--change-unit", "mm"], "give a relation"),
     (["--relation", "angle_deg", "--change-unit", "cm"], "cannot convert"),
     (["--relation", "full", "--change-unit", "m"], "no unit")],
)  # fmt: skip
def test_change_unit_refused_where_evo_refuses(data, tmp_path, capsys, args, message):
    rc = main(["evaluate", str(data.tum / EST), "--gt", str(data.tum / GT), "--conventions", "evo", *args,
               "--no-progress"])  # fmt: skip
    assert rc == 2 and message in capsys.readouterr().err
