"""The calibration harness scores its reruns at the thresholds asked: the paper's by default, none
(eps = phi = inf, ``diff``'s and ``compare``'s own default) with ``thresholds=UNBOUNDED``
(``benchmarks/calibrate.py --thresholds none``), so the guide's rates at the default are measured."""

from __future__ import annotations

import numpy as np

from lorisnb.core.stats.reruns import RerunNoise
from lorisnb.tools.decisions.calibration import UNBOUNDED, make_pool


def test_the_pool_is_scored_at_the_thresholds_given(data):
    kw = dict(algorithms=("orbslam2_rgbd",), data_root=data, seed=3)
    paper = make_pool(RerunNoise(), 1, **kw).tables[0]
    none = make_pool(RerunNoise(), 1, thresholds=UNBOUNDED, **kw).tables[0]
    assert np.isinf(none["eps"].astype(float)).all() and np.isinf(none["phi"].astype(float)).all()
    assert set(paper["eps"].astype(float)) <= {1.0, 3.0, 5.0} and set(paper["phi"].astype(float)) == {30.0}
    # the same reruns: every pose that is correct at the paper's thresholds is at none, and more are
    assert (none["cr"].to_numpy() >= paper["cr"].to_numpy() - 1e-12).all()
    assert (none["cr"].to_numpy() > paper["cr"].to_numpy() + 1e-9).any()
    assert none["ate_rmse"].tolist() == paper["ate_rmse"].tolist()
