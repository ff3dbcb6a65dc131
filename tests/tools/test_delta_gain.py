"""threshold_sensitivity's sentences below CR against delta (:func:`lorisnb.tools.notebook.output_gaps.delta_gain`):
a ``delta_grid`` whose largest value is not above ``delta`` (``[0.25, 0.5, 1]`` at delta 1) swept
``[delta, delta]`` and raised ValidationError ("1.0 and 1.0 are the same value"), so the cell's branch for
"no larger delta" was never reached; it is now what such a run says."""

from __future__ import annotations

import pytest

import lorisnb as ln
from lorisnb.tools.notebook.output_gaps import delta_gain


@pytest.fixture(scope="module")
def small(icra20):
    ev = ln.evaluate(icra20 / "lifelong" / "vins_mono_color_imu_with_loop" / "home-1.txt", progress=False)
    return ev.errors, ev.durations()


@pytest.mark.parametrize("grid", [[0.25, 0.5, 1.0], [0.25, 0.5]])
def test_a_grid_that_ends_at_delta_or_below_says_there_is_nothing_larger(small, grid):
    errors, durations = small
    gaps, rates, text = delta_gain(errors, durations, "paper", 30.0, 1.0, 60.0, grid)
    assert text.startswith("The grid ends at this run's delta (1 s): no larger delta to compare with.")
    assert len(rates) == 1 and (rates["rise"] == 0).all() and len(gaps) == 1


def test_a_grid_beyond_delta_compares_cr_at_both(small):
    errors, durations = small
    _, rates, text = delta_gain(errors, durations, "paper", 30.0, 1.0, 60.0, [0.5, 1.0, 5.0])
    assert "and 5 s" in text and "grid ends" not in text
    assert (rates["cr_at_max"] >= rates["cr_at_delta"]).all()
