"""What a large pair holds while it is evaluated: the matched rows of the estimate are read in
place when they are consecutive, the ground truth goes once the estimate is matched (before the
alignment), and a large ground-truth file is not kept between inputs; the numbers do not change."""

from __future__ import annotations

import weakref

import numpy as np

from lorisnb.core.alignment.association import Association
from lorisnb.core.pipeline import sessions as pipeline
from lorisnb.core.pipeline.sessions import evaluate_sessions
from lorisnb.core.simulate import Faults, simulate
from lorisnb.io import read_tum
from lorisnb.tools.evaluation import jobs


def test_matched_rows_are_a_view_when_consecutive():
    values = np.arange(40.0).reshape(10, 4)
    stamps = np.arange(3.0)
    a = Association(np.array([2, 3, 4]), stamps, np.zeros((3, 3)), None, 0.0, 1.0)
    rows = a.est_rows(values)
    assert np.shares_memory(rows, values) and np.array_equal(rows, values[[2, 3, 4]])
    for index in ([2, 4, 6], [4, 3, 2], [2, 2, 3]):
        b = Association(np.array(index), stamps, np.zeros((3, 3)), None, 0.0, 1.0)
        assert not np.shares_memory(b.est_rows(values), values)
        np.testing.assert_array_equal(b.est_rows(values), values[index])
    empty = Association(np.zeros(0, int), np.zeros(0), np.zeros((0, 3)), None, 0.0, 1.0)
    assert empty.est_rows(values).shape == (0, 4)


def test_groundtruth_goes_before_the_alignment_with_the_same_numbers(data, monkeypatch):
    gt = read_tum(data.tum / "fr2_desk_groundtruth.txt")
    est = simulate(gt, Faults(position_noise_m=0.01, orientation_noise_deg=0.5, drift_per_m=0.01, seed=3))
    kept = evaluate_sessions({1: gt}, {1: est}, path="est")
    gts = {1: read_tum(data.tum / "fr2_desk_groundtruth.txt")}
    alive = weakref.ref(gts[1])
    seen = []
    fit = pipeline.fit_alignment

    def spy(*args, **kw):
        seen.append(alive() is None)
        return fit(*args, **kw)

    monkeypatch.setattr(pipeline, "fit_alignment", spy)
    let_go = evaluate_sessions(gts, {1: est}, path="est", release_groundtruth=gts.pop)
    assert seen == [True] and gts == {}
    a, b = kept.sequences[0], let_go.sequences[0]
    for name in ("ate", "aoe", "stamps", "est_positions", "gt_quaternions"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert kept.groundtruth_lengths == let_go.groundtruth_lengths


def test_a_large_groundtruth_file_is_read_for_each_input(data, monkeypatch):
    path = data.tum / "fr2_desk_groundtruth.txt"
    assert jobs.groundtruth_of(path, "tum") is jobs.groundtruth_of(path, "tum")  # small: read once
    monkeypatch.setattr(jobs, "CACHED_BYTES", 1024)
    first, again = jobs.groundtruth_of(path, "tum"), jobs.groundtruth_of(path, "tum")
    assert first is not again and np.array_equal(first.positions, again.positions)
    assert not first.positions.flags.writeable
