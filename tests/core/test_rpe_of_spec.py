"""The RPE settings an evaluation was computed under go with its errors: ``score`` and ``sweep``
of ``ev.errors`` use them unless given (they used lorisnb's 1 s rule: evo's numbers silently
became lorisnb's), files of different settings are refused until they are given, and the
``spec`` column of a table scored with other RPE settings says which (it said the evaluation's)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.core.spec.evalspec import EvalSpec
from lorisnb.errors import ValidationError

RPE = ["rpe_trans_rmse", "rpe_rot_rmse", "rpe_pairs"]


@pytest.fixture(scope="module")
def evo_pair(data):
    t = data.tum
    return ln.evaluate_pairs(t / "fr2_desk_ORB.txt", t / "fr2_desk_groundtruth.txt", conventions="evo")


def test_score_and_sweep_of_the_errors_use_the_evaluations_rpe(evo_pair):
    ev = evo_pair
    table = ev.sequences()
    assert ev.spec.rpe_options()["rpe_unit"] == "frames" and table["rpe_pairs"][0] == 2173  # evo: 1 frame
    pd.testing.assert_frame_equal(ln.score(ev.errors)[RPE], table[RPE])
    swept = ln.sweep(ev.errors, columns="all")
    np.testing.assert_array_equal(swept[RPE].to_numpy(), table[RPE].to_numpy())
    # given settings still win, and equal lorisnb's own rule when it is the one given
    own = ln.score(ev.errors, rpe_delta=1.0, rpe_unit="s", rpe_all_pairs=None)
    lorisnb_rule = ln.evaluate_pairs(ev.errors[0].path, ev.errors[0].path.parent / "fr2_desk_groundtruth.txt",
                                     conventions="evo", rpe_delta=1.0, rpe_unit="s", rpe_all_pairs=None).sequences()  # fmt: skip
    pd.testing.assert_frame_equal(own[RPE], lorisnb_rule[RPE])
    assert own["rpe_pairs"][0] != table["rpe_pairs"][0]


def test_files_of_different_rpe_settings_need_them_given(evo_pair, data):
    t = data.tum
    own = ln.evaluate_pairs(t / "freiburg1_xyz-rgbdslam.txt", t / "freiburg1_xyz-groundtruth.txt", conventions="tum")
    both = [*evo_pair.errors, *own.errors]
    with pytest.raises(ValidationError, match="rpe_all_pairs, rpe_pairs, rpe_unit: the errors were computed"):
        ln.score(both)
    scored = ln.score(both, rpe_delta=0.5, rpe_unit="s", rpe_pairs="reference", rpe_all_pairs=None)
    assert len(scored) == 2 and (scored["rpe_pairs"] > 0).all()


def test_the_spec_column_says_the_rpe_the_table_was_scored_with(data, icra20):
    files = sorted((icra20 / "per-seq" / "orbslam2_rgbd").glob("cafe_*.txt"))
    ev = ln.evaluate(files, data_root=data.root, jobs=1)
    table = ev.sequences(rpe_delta=2, rpe_unit="m")
    spec = EvalSpec.parse(table["spec"][0])
    assert (spec.rpe_delta, spec.rpe_unit) == (2.0, "m")
    again = ln.evaluate(files, spec, data_root=data.root, jobs=1).sequences()  # the row from its own spec text
    pd.testing.assert_frame_equal(again[RPE], table[RPE])
    assert not table["rpe_trans_rmse"].equals(ev.sequences()["rpe_trans_rmse"])
    assert EvalSpec.parse(ev.sequences()["spec"][0]).rpe_unit == "s"
