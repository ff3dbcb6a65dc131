"""``rpe_tolerance`` applies wherever the RPE pairs use it: evo's all pairs in m (``rpe_all_pairs``),
and in deg or rad, whose all pairs are lorisnb's rule too (:func:`lorisnb.core.metrics.pairs.rpe_indices`).
It was refused with ``--rpe-unit deg`` although the tolerance changes the pairs there, as evo's
``--delta_tol`` does; with frames it changes nothing and is refused. One rule for the spec and the tables."""

from __future__ import annotations

import numpy as np
import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.alignment.geometry import quat_to_matrix
from lorisnb.core.metrics.pairs import rpe_indices
from lorisnb.core.spec.evo import tolerance_used
from lorisnb.io.readers.plain import read_trajectory


@pytest.fixture
def tum(data):
    t = data.root / "tum-rgbd"
    if not (t / "freiburg1_xyz-groundtruth.txt").is_file():
        pytest.skip("no tum-rgbd data")
    return t / "freiburg1_xyz-rgbdslam.txt", t / "freiburg1_xyz-groundtruth.txt"


def test_the_rule():
    assert tolerance_used("deg", None) and tolerance_used("rad", None) and tolerance_used("m", True)
    assert tolerance_used("d", True) and not tolerance_used("deg", False)
    assert not tolerance_used("m", None) and not tolerance_used("frames", True) and not tolerance_used("s", True)


def test_tolerance_with_deg_is_accepted_and_changes_the_result(tum, capsys):
    est, gt = tum
    ev = ln.evaluate_pairs(est, gt, "tum", rpe_unit="deg", rpe_delta=5, rpe_tolerance=0.5)
    wide = ev.sequences()["rpe_pairs"].iloc[0]
    narrow = ev.sequences(rpe_tolerance=0.01)["rpe_pairs"].iloc[0]
    default = ln.evaluate_pairs(est, gt, "tum", rpe_unit="deg", rpe_delta=5).sequences()["rpe_pairs"].iloc[0]
    assert len({wide, narrow, default}) == 3
    assert main(["evaluate", str(est), "--gt", str(gt), "--rpe-unit", "deg", "--rpe-delta", "5", "--rpe-tolerance",
                 "0.5", "--no-progress"]) == 0  # fmt: skip
    with pytest.raises(ln.ValidationError, match="only for evo's all pairs in m, deg or rad"):
        ln.evaluate_pairs(est, gt, "tum", rpe_unit="frames", rpe_all_pairs=True, rpe_tolerance=0.5)
    with pytest.raises(ln.ValidationError, match="only for evo's all pairs in m, deg or rad"):
        ev.sequences(rpe_unit="frames", rpe_all_pairs=True, rpe_tolerance=0.5)
    assert (
        main(["evaluate", str(est), "--gt", str(gt), "--rpe-unit", "m", "--rpe-tolerance", "0.5", "--no-progress"]) == 2
    )


@pytest.mark.parametrize("tol", [0.01, 0.1, 0.5])
def test_the_pairs_are_evos_all_pairs_within_the_tolerance(tum, tol):
    filters = pytest.importorskip("evo.core.filters")
    gt = read_trajectory(tum[1], "tum")
    n = 600  # the first 20 s: evo's all pairs by angle are quadratic in the poses
    pos, quat = gt.positions[:n], gt.quaternions[:n]
    i, j = rpe_indices(gt.stamps[:n], pos, quat, pos, quat, 5.0, "deg", "reference", None, tol)
    poses = []
    for p, q in zip(pos, quat, strict=True):
        m = np.eye(4)
        m[:3, :3], m[:3, 3] = quat_to_matrix(q[None])[0], p
        poses.append(m)
    want = filters.filter_pairs_by_angle(poses, 5.0, tol=5.0 * tol, degrees=True, all_pairs=True)
    assert len(want) > 0
    assert sorted(zip(i.tolist(), j.tolist(), strict=True)) == sorted(map(tuple, want))


def test_a_sweep_takes_the_tolerance_by_the_same_rule(tum):
    """The sweep's RPE options were checked without their unit (evo's all pairs asked for): a
    tolerance with deg was refused there while the spec and the tables took it."""
    est, gt = tum
    errors = ln.evaluate_pairs(est, gt, "tum", rpe_unit="deg", rpe_delta=5).errors
    wide = ln.sweep(errors, eps=[0.05], phi=[5.0], columns="all", rpe_unit="deg", rpe_delta=5, rpe_tolerance=0.5)
    narrow = ln.sweep(errors, eps=[0.05], phi=[5.0], columns="all", rpe_unit="deg", rpe_delta=5, rpe_tolerance=0.01)
    assert wide["rpe_pairs"].iloc[0] != narrow["rpe_pairs"].iloc[0]
    with pytest.raises(ln.ValidationError, match="rpe_tolerance: only for evo's all pairs"):
        ln.sweep(errors, eps=[0.05], phi=[5.0], columns="all", rpe_unit="frames", rpe_delta=5, rpe_tolerance=0.5)
