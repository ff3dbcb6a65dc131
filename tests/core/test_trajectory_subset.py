"""Trajectory.subset, slicing and equality: every selection gives a sorted, valid trajectory or a
ValidationError saying what to pass (negative indices once skipped the sort check: CR -0.62)."""

from __future__ import annotations

import numpy as np
import pytest

import lorisnb as ln
from lorisnb.errors import LorisWarning, ValidationError


@pytest.fixture(scope="module")
def fr1(data):
    return ln.read_tum(data.tum / "freiburg1_xyz-groundtruth.txt"), ln.read_tum(data.tum / "freiburg1_xyz-rgbdslam.txt")


def _score(gt, est):
    return ln.score(ln.session_errors(gt, est, "tum")).iloc[0]


def test_negative_indices_count_from_the_end_and_are_sorted_as_positive_ones(fr1):
    gt, est = fr1
    n = len(est)
    with pytest.warns(LorisWarning, match="stamps are not increasing"):
        neg = est.subset(np.r_[np.arange(-100, 0), np.arange(0, 100)])
    with pytest.warns(LorisWarning, match="stamps are not increasing"):
        pos = est.subset(np.r_[np.arange(n - 100, n), np.arange(0, 100)])
    assert (np.diff(neg.stamps) > 0).all()
    assert neg == pos
    a, b = _score(gt, neg), _score(gt, pos)
    assert 0 <= a.cr <= 1 and a.track_time >= 0
    assert (a.cr, a.track_time, a.matched) == (b.cr, b.track_time, b.matched)


def test_increasing_negative_indices_stay_unchecked(fr1):
    _, est = fr1
    tail = est.subset(np.arange(-10, 0))
    assert tail == est.subset(np.arange(len(est) - 10, len(est)))


@pytest.mark.parametrize(
    "selection, message",
    [
        (np.array([True, False]), "boolean mask of 2 values"),
        (np.array([0.0, 1.0]), "values of type float64"),
        (np.array([[0, 1]]), "one dimension"),
        (3, "for one pose: subset"),
        ("0:3", "expected a boolean mask"),
        (np.array([10**6]), "out of range"),
        (np.array([-(10**6)]), "out of range"),
    ],
)
def test_bad_selections_are_refused_saying_what_to_pass(fr1, selection, message):
    _, est = fr1
    with pytest.raises(ValidationError, match=message):
        est.subset(selection)


def test_empty_selections_give_an_empty_trajectory(fr1):
    _, est = fr1
    for empty in ([], np.zeros(0, int), np.zeros(len(est), bool), slice(5, 5)):
        assert len(est.subset(empty)) == 0


def test_slicing_is_subset(fr1):
    _, est = fr1
    assert est[0:10] == est.subset(np.arange(10))
    assert est[-10:] == est.subset(np.arange(len(est) - 10, len(est)))
    assert est[est.stamps < est.stamps[5]] == est[:5]
    with pytest.warns(LorisWarning, match="sorted them"):
        assert est[::-1] == est
    with pytest.raises(ValidationError, match=r"traj\[\[i\]\]"):
        est[0]


def test_equality_compares_the_poses(fr1):
    gt, est = fr1
    assert est == est.subset(slice(None))
    assert est != gt
    assert est != est[1:]
    assert (est == "x") is False
    with pytest.raises(TypeError, match="unhashable"):
        hash(est)
