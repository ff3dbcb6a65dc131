"""rpg's relative error split into yaw and gravity (its ``rel_yaw``, ``rel_gravity``), against
rpg_trajectory_evaluation's own ``compute_relative_error`` run here on the same aligned poses (the
bundled TUM RGB-D pair under the rpg preset; the peer kept outside the repository: tests/peers.py)."""

from __future__ import annotations

import importlib
import sys

import numpy as np
import pytest
from peers import peer

import lorisnb
from lorisnb.core.metrics.relative import distances, rpg_relative_errors


@pytest.fixture(scope="module")
def rpg_errors():
    src = peer("rpg_trajectory_evaluation") / "src" / "rpg_trajectory_evaluation"
    sys.path.insert(0, str(src))
    try:
        return importlib.import_module("compute_trajectory_errors")
    finally:
        sys.path.remove(str(src))


@pytest.mark.parametrize("length", [0.5, 2.0, 4.0])
def test_yaw_and_gravity_equal_rpg(data, rpg_errors, length, capsys):
    tum = data.tum
    ev = lorisnb.evaluate_pairs(tum / "freiburg1_xyz-rgbdslam.txt", tum / "freiburg1_xyz-groundtruth.txt", "rpg")
    e = ev.errors[0].sequences[0]
    ours = rpg_relative_errors(e.gt_positions, e.gt_quaternions, e.est_positions, e.est_quaternions, [length])
    _, trans, _, yaw, gravity, rot, _ = rpg_errors.compute_relative_error(
        e.est_positions, e.est_quaternions, e.gt_positions, e.gt_quaternions, np.eye(4), length, 0.2 * length,
        distances(e.gt_positions),
    )  # fmt: skip
    capsys.readouterr()  # rpg prints its sample count
    assert len(ours) == len(yaw) > 100
    np.testing.assert_allclose(ours["trans"], trans, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(ours["rot"], rot, rtol=1e-7, atol=1e-6)  # rpg's arccos of the trace
    np.testing.assert_allclose(ours["yaw"], yaw, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(ours["gravity"], gravity, rtol=1e-9, atol=1e-10)
    assert (ours["gravity"] > 0).any() and (ours["yaw"] > 0).any()


def test_scale_error_equals_rpg(data, rpg_errors):
    """rpg's absolute scale error (its e_scale_perc) on the same aligned poses, as rpg computes it."""
    from lorisnb.core.metrics.relative import rpg_absolute_table, rpg_scale_errors

    tum = data.tum
    ev = lorisnb.evaluate_pairs(tum / "freiburg1_xyz-rgbdslam.txt", tum / "freiburg1_xyz-groundtruth.txt", "rpg")
    e = ev.errors[0].sequences[0]
    trans, _, rot, _, scale = rpg_errors.compute_absolute_error(
        e.est_positions, e.est_quaternions, e.gt_positions, e.gt_quaternions
    )
    np.testing.assert_allclose(rpg_scale_errors(e.gt_positions, e.est_positions), scale, rtol=1e-12, atol=1e-12)
    row = rpg_absolute_table(ev.errors).iloc[0]
    assert row["scale_perc_mean"] == pytest.approx(np.mean(scale), rel=1e-12)
    assert row["trans_rmse"] == pytest.approx(np.sqrt(np.mean(trans**2)), rel=1e-9)
    assert row["rot_rmse"] == pytest.approx(np.sqrt(np.mean(rot**2)), rel=1e-6)
    assert ev.rpg_absolute().equals(rpg_absolute_table(ev.errors))


def test_a_length_rpg_will_not_compute_is_said_not_dropped(data, rpg_errors, capsys, tmp_path):
    """A sub-trajectory length with fewer than 2 sub-trajectories: rpg prints "Too few samples! Will
    not compute." and gives nothing; lorisnb gives no row either, and says which input, sequence
    and length (it dropped them silently), in Python and on the command line."""
    import subprocess
    import warnings

    from lorisnb.core.metrics.relative import relative_table
    from lorisnb.errors import LorisWarning

    tum = data.tum
    est, gt = tum / "freiburg1_xyz-rgbdslam.txt", tum / "freiburg1_xyz-groundtruth.txt"
    ev = lorisnb.evaluate_pairs(est, gt, "rpg")
    e = ev.errors[0].sequences[0]
    total = float(distances(e.gt_positions)[-1])
    lengths = [1.0, round(total * 3, 2), round(total * 5, 2)]  # the last two: no sub-trajectory
    for length in lengths:
        errs = rpg_errors.compute_relative_error(
            e.est_positions, e.est_quaternions, e.gt_positions, e.gt_quaternions, np.eye(4), length, 0.2 * length,
            distances(e.gt_positions),
        )  # fmt: skip
        said = capsys.readouterr().out
        assert ("Too few samples" in said) == (length != 1.0) and (len(errs[1]) == 0) == (length != 1.0), said
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        table = relative_table(ev.errors, lengths=lengths)
    assert table["length"].tolist() == [1.0]
    notes = [str(w.message) for w in caught if issubclass(w.category, LorisWarning) and "Too few" in str(w.message)]
    assert len(notes) == 1 and f"{est}, seq 1 at {lengths[1]:g}, {lengths[2]:g} m" in notes[0], notes
    cli = [sys.executable, "-m", "lorisnb.cli", "evaluate", str(est), "--gt", str(gt), "--format", "tum",
           "--conventions", "rpg", "--relative-lengths", ",".join(f"{v:g}" for v in lengths), "--no-progress"]  # fmt: skip
    done = subprocess.run(cli, capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "warning: rpg's relative error is not computed" in done.stderr
    assert f"{est}, seq 1 at {lengths[1]:g}, {lengths[2]:g} m" in done.stderr
    assert "LorisWarning" not in done.stderr  # said as a note, not as Python's warning with its source line
