"""rpg's relative error the way rpg computes it (issue 23): sub-trajectory lengths from the whole
ground truth's path length (every row of the file), truncated to centimetres, or preset distances;
values from rpg_trajectory_evaluation itself (tests/reference_tools.py, ``whole_rpg_rel``)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from reference_tools import REFERENCE

from lorisnb.core.conventions.choices import Conventions
from lorisnb.core.metrics.relative import relative_table, rpg_lengths
from lorisnb.core.pipeline.sessions import session_errors
from lorisnb.io import read_tum

PAIRS = {
    "fr2_desk": ("fr2_desk_groundtruth.txt", "fr2_desk_ORB.txt"),
    "fr1_xyz": ("freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"),
}


@pytest.mark.parametrize("name", PAIRS)
def test_rpg_lengths_and_errors_from_the_whole_groundtruth(data, name):
    g, e = PAIRS[name]
    whole = read_tum(data.tum / g, repeated="keep")  # rpg reads every row (np.loadtxt)
    gt, est = read_tum(data.tum / g), read_tum(data.tum / e)
    ref = REFERENCE[name]
    assert whole.path_length == pytest.approx(ref["whole_rpg_length"], rel=1e-12)
    f = session_errors({1: gt}, {1: est}, Conventions.preset("rpg"))
    f.groundtruth_lengths = {1: whole.path_length}
    table = relative_table(f).set_index("fraction")
    wanted = {k: v for k, v in ref.items() if k.startswith("whole_rpg_rel")}
    assert len(table) == len(wanted) == 5
    for key, (length, samples, trans_perc, deg_per_m) in wanted.items():
        row = table.loc[float(key.split()[1].rstrip("%")) / 100]
        assert row["length"] == length and row["samples"] == samples, key
        assert row["trans_perc_mean"] == pytest.approx(trans_perc, rel=1e-9), key
        assert row["rot_deg_per_m_mean"] == pytest.approx(deg_per_m, rel=1e-9), key
    assert rpg_lengths(whole.positions) == [v[0] for v in wanted.values()]
    # without the whole ground truth's length: the matched ground truth's (the older rpg_rel values)
    f.groundtruth_lengths = {}
    older = relative_table(f)
    assert older["length"].tolist() == [v[0] for k, v in ref.items() if k.startswith("rpg_rel ")]
    # rpg's preset distances
    preset = relative_table(f, lengths=[1.0, 2.5])
    assert preset["length"].tolist() == [1.0, 2.5] and preset["fraction"].map(math.isnan).all()


def test_evaluation_relative_takes_preset_distances(data):
    import lorisnb as ln

    ev = ln.evaluate_pairs(data.tum / "freiburg1_xyz-rgbdslam.txt", data.tum / "freiburg1_xyz-groundtruth.txt",
                           conventions="rpg")  # fmt: skip
    assert ev.relative()["length"].tolist() == [0.91, 1.83, 2.74, 3.66, 4.57]  # rpg's, from the whole ground truth
    assert ev.relative(lengths=[2.0])["length"].tolist() == [2.0]


def test_a_length_given_twice_is_refused_in_python_and_on_the_command_line(data, capsys):
    """``--relative-lengths 1,1`` printed one row of length 1 with twice the samples (2,073 x 2)."""
    import lorisnb as ln
    from lorisnb.cli import main
    from lorisnb.errors import ValidationError

    ev = ln.evaluate_pairs(data.tum / "freiburg1_xyz-rgbdslam.txt", data.tum / "freiburg1_xyz-groundtruth.txt",
                           conventions="rpg")  # fmt: skip
    for lengths in ([1.0, 1.0], (1, 1.0, 2), np.array([0.5, 0.5])):
        with pytest.raises(ValidationError, match="are the same value; expected each value once"):
            ev.relative(lengths=lengths)
    with pytest.raises(ValidationError, match="are the same value"):
        ev.relative(fractions=(0.1, 0.1))
    with pytest.raises(SystemExit) as exc:  # refused as argparse refuses a bad value, before any work
        main(["evaluate", str(data.tum / "freiburg1_xyz-rgbdslam.txt"), "--gt",
              str(data.tum / "freiburg1_xyz-groundtruth.txt"), "--relative-lengths", "1,1", "--no-progress"])  # fmt: skip
    assert exc.value.code == 2 and "--relative-lengths=1,1: 1 and 1 are the same value" in capsys.readouterr().err
