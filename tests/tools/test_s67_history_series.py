"""The calibration harness's noise-only history series (benchmarks/calibrate.py, the rates of
docs/guide/history.md): no night shares a rerun with a night it is judged against, the night
before (its baseline) nor the series' first night (history's drift check). Only the night before
was avoided: a later night drawing one of the first night's reruns again held a copy of the first
night's file, which the cross-side copy rule counts as no run (a missing trial), and 2 of 11
noise-only nights of a 24-rerun pool failed as "lost"."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest

from lorisnb.errors import LorisWarning, ValidationError
from lorisnb.tools.decisions.calibration import MODELS, Pool, _series, history_rates, make_pool


def _fake(size: int) -> Pool:
    tables = [pd.DataFrame({"rerun": [k], "cr": [0.5]}) for k in range(size)]
    return Pool(tables=tables, changed={}, expected=pd.DataFrame(), targets={})


@pytest.mark.parametrize("n", [1, 3])
def test_no_night_shares_a_rerun_with_the_first_night_or_the_night_before(n):
    pool = _fake(3 * n)
    nights = _series(pool, n, 40, np.random.default_rng(6))
    drawn = [set(t["rerun"]) for t in nights]
    assert all(len(d) == n for d in drawn)
    for k in range(1, len(drawn)):
        assert not drawn[k] & drawn[k - 1], k
        assert not drawn[k] & drawn[0], k


def test_a_pool_too_small_for_the_series_is_refused():
    with pytest.raises(ValidationError, match="expected a pool of at least 9"):
        _series(_fake(8), 3, 5, np.random.default_rng(0))


@pytest.mark.thorough
def test_noise_only_history_nights_lose_no_trial(data):
    """Real reruns (the harness's real noise model, a 9-rerun pool, the smallest a series of 3
    trials needs): no noise-only night fails by a lost sequence or trial."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LorisWarning)
        pool = make_pool(MODELS["real"], 9, data_root=str(data.root))
        rates = history_rates(pool, trials=(3,), series=1, nights=8)
    assert rates["nights"].tolist() == [7]
    assert rates["lost"].tolist() == [0], rates
