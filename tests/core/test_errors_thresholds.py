"""Thresholds are the scores' (lorisnb.score, evaluate), not options of the functions computing
errors: given there they were accepted and then ignored by score (CR at eps=inf)."""

from __future__ import annotations

import pytest

import lorisnb as ln
from lorisnb.errors import ValidationError


@pytest.mark.parametrize("given", [dict(eps=0.1), dict(phi=5), dict(delta=0.5), dict(tau=10), dict(eps=0.1, tau=10)])
def test_compute_errors_refuses_thresholds_saying_to_give_them_to_score(data, icra20, given):
    r = ln.read_openloris(icra20 / "per-seq" / "ds-slam" / "cafe-1-2.txt")
    gt = ln.load_groundtruth(r.scene, data_root=data.root)
    with pytest.raises(ValidationError, match=r"pass them to lorisnb\.score\(errors, " + list(given)[0]):
        ln.compute_errors(r, gt, **given)
    e = ln.compute_errors(r, gt)
    assert ln.score(e, **given)[list(given)].iloc[0].to_dict() == {k: float(v) for k, v in given.items()}


def test_sequence_errors_refuses_thresholds(data):
    gt, est = (ln.read_tum(data.tum / f"freiburg1_xyz-{n}.txt") for n in ("groundtruth", "rgbdslam"))
    with pytest.raises(ValidationError, match="sequence_errors.*lorisnb.score"):
        ln.sequence_errors(gt, est, eps=0.1)
    assert ln.sequence_errors(gt, est, max_diff=0.02).matched > 0
