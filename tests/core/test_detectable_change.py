"""The oracle bound that ``make calibrate`` prints beside the gate's measured power."""

import numpy as np
import pytest
from scipy import stats

from lorisnb.core.stats.power import detectable_change
from lorisnb.core.stats.tolerances import RERUN_SPREAD
from lorisnb.errors import ValidationError


@pytest.mark.parametrize("trials,comparisons", [(1, 1), (3, 1), (3, 300), (5, 40)])
def test_the_oracle_test_finds_the_bound_with_the_stated_power(trials, comparisons):
    sd, tol, alpha = RERUN_SPREAD["rate"], 0.02, 0.05
    d = detectable_change(sd, trials, tol, alpha, power=0.9, comparisons=comparisons)
    rng = np.random.default_rng(7)
    base = rng.normal(0.0, sd, (20000, trials)).mean(axis=1)
    cand = rng.normal(d, sd, (20000, trials)).mean(axis=1)
    z = (cand - base - tol) / (sd * np.sqrt(2 / trials))
    found = np.mean(z > stats.norm.isf(alpha / comparisons))
    assert found == pytest.approx(0.9, abs=0.01)


def test_more_trials_or_fewer_tests_find_smaller_changes():
    sd = RERUN_SPREAD["log"]
    assert detectable_change(sd, 5) < detectable_change(sd, 3) < detectable_change(sd, 1)
    assert detectable_change(sd, 3, comparisons=1) < detectable_change(sd, 3, comparisons=300)


@pytest.mark.parametrize(
    "kw", [dict(spread=0.0), dict(trials=0), dict(comparisons=0), dict(power=1.0), dict(alpha=2.0)]
)
def test_refuses_values_that_cannot_apply(kw):
    args = dict(spread=0.017, trials=3) | kw
    with pytest.raises(ValidationError):
        detectable_change(**args)


def test_the_manual_quotes_the_bound_it_computes():
    """docs/guide/regression-gating.md's table of the smallest detectable change is computed, not typed."""
    import re
    from pathlib import Path

    from lorisnb.core.stats.regression import parse_tolerances

    page = (Path(__file__).resolve().parents[2] / "docs" / "guide" / "regression-gating.md").read_text()
    rows = re.findall(r"^\s*\| (\d+) \| ([\d.]+) \| ([\d.]+) \| ([\d.]+) \| ([\d.]+) \|$", page, re.M)
    assert len(rows) == 4
    tol = parse_tolerances()
    cr_tol, ate_tol = tol["cr"].scaled("cr", 1.0), tol["ate_rmse"].scaled("ate_rmse", 1.0)
    for n, cr1, crm, a1, am in rows:
        n = int(n)
        assert float(cr1) == pytest.approx(detectable_change(RERUN_SPREAD["rate"], n, cr_tol), abs=6e-4)
        assert float(crm) == pytest.approx(
            detectable_change(RERUN_SPREAD["rate"], n, cr_tol, comparisons=450), abs=6e-4
        )
        assert float(a1) == pytest.approx(np.exp(detectable_change(RERUN_SPREAD["log"], n, ate_tol)), abs=6e-3)
        assert float(am) == pytest.approx(
            np.exp(detectable_change(RERUN_SPREAD["log"], n, ate_tol, comparisons=450)), abs=6e-3
        )
