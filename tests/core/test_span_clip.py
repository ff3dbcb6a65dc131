"""Time counts only inside the ground truth's span (Eq. 2-3): with nearest association an estimate
pose may be matched up to ``max_diff`` before the first or after the last ground-truth pose. Its
time used to count outside the span (CR 1.0002 on fr1_xyz read the other way round) and a last
pose after the span took time away (a negative interval). Every place that sums correct time
(per-sequence scores, sweeps, CR surfaces, timelines) follows the one rule,
:func:`lorisnb.core.metrics.openloris.valid_intervals`."""

from __future__ import annotations

import numpy as np
import pytest

import lorisnb as ln
from lorisnb.core.lifelong.surfaces import cr_surfaces
from lorisnb.core.lifelong.sweep import sweep
from lorisnb.core.lifelong.timeline import timeline_table
from lorisnb.tools.evaluation.runner import evaluate_pairs

GT, EST = "freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"


def _shifted(data, tmp_path, shift: float):
    """The ground truth itself as the estimate, every stamp moved by ``shift`` seconds (under half the 0.01 s spacing, so
    TUM's nearest rule matches each pose to its own ground-truth pose: every pose correct)."""
    lines = []
    for line in (data.tum / GT).read_text().splitlines():
        if line.strip() and not line.startswith("#"):
            stamp, rest = line.split(" ", 1)
            lines.append(f"{float(stamp) + shift:.4f} {rest}")
    est = tmp_path / f"shift{shift:+.3f}.txt"
    est.write_text("\n".join(lines) + "\n")
    return evaluate_pairs(est, data.tum / GT, conventions="tum", jobs=1)


@pytest.mark.parametrize("shift", [-0.003, 0.003])
def test_correct_time_counts_only_inside_the_ground_truth_span(data, tmp_path, shift):
    ev = _shifted(data, tmp_path, shift)
    gt = ln.read_tum(data.tum / GT)
    span = float(gt.stamps[-1] - gt.stamps[0])
    row = ev.sequences().iloc[0]
    assert row["matched"] == len(gt)  # every pose matched to its own ground-truth pose
    # early: the whole span is covered, not more; late: the span from the first pose on
    expected = span if shift < 0 else span - shift
    assert row["correct_time"] == pytest.approx(expected, abs=1e-6)
    assert row["cr"] == pytest.approx(expected / span, abs=1e-9) and row["cr"] <= 1
    assert row["cr_t"] == pytest.approx(1.0, abs=1e-9)
    # the sweep, the CR surfaces and the timeline sum the same time
    sw = sweep(ev.errors, [np.inf], [np.inf], [1.0], [60.0])
    assert sw["cr"].iloc[0] == pytest.approx(row["cr"], abs=1e-12)
    s = cr_surfaces(ev.errors, [np.inf], [180.0], ev.durations(), delta=1.0)
    assert s.correct_time[0, 0, 0] == pytest.approx(expected, abs=1e-6)
    assert s.cr_t[0, 0, 0] == pytest.approx(1.0, abs=1e-9)
    segs, _ = timeline_table(ev.errors, np.inf, np.inf, 1.0)
    assert segs["start"].min() >= 0 and segs["end"].max() == pytest.approx(span, abs=1e-9)
    assert (segs["end"] - segs["start"]).sum() == pytest.approx(expected, abs=1e-6)


def test_estimate_and_ground_truth_read_the_other_way_round_score_at_most_1(data):
    """The real rgbdslam output as the ground truth (30 Hz) and the real ground truth (100 Hz) as the
    estimate: the first estimate pose is matched 0.4 ms before the span; CR was 1.0002."""
    ev = evaluate_pairs(data.tum / GT, data.tum / EST, conventions="tum", jobs=1)
    row = ev.sequences().iloc[0]
    est = ln.read_tum(data.tum / EST)
    assert row["correct_time"] <= est.stamps[-1] - est.stamps[0] + 1e-12
    assert row["cr"] == pytest.approx(1.0, abs=1e-12) and row["cr_t"] == pytest.approx(1.0, abs=1e-12)


def test_a_last_pose_after_the_span_holds_no_time(data, tmp_path):
    """Only the last pose correct, matched 3 ms after the span: it held -3 ms (a negative CR)."""
    from lorisnb.core.metrics import openloris as metrics

    e = _shifted(data, tmp_path, 0.003).errors[0].sequences[0]
    assert e.stamps[-1] > e.gt_end
    last = np.zeros(e.matched, bool)
    last[-1] = True
    assert metrics.correct_time(e.stamps, last, e.gt_end, 1.0, e.gt_start) == 0.0
    assert metrics.valid_intervals(e.stamps, e.gt_end, e.gt_start).min() >= 0
