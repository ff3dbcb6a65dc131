"""Nearest association (TUM's greedy ``associate.py``) by mutual nearest neighbours: the same pairs
as a literal port of TUM's rule (``_greedy`` of test_pairs.py) on random and adversarial stamp sets
(grids with ties, differences that round to equal values near zero, nanosecond spacing of large
stamps, chains of growing gaps), and the same pairs as the rule over every candidate on large
sets. Hypothesis with a fixed seed (``derandomize=True``): CI runs the same cases."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_pairs import _greedy

from lorisnb.core.conventions.choices import associate_nearest

PROPERTY = settings(max_examples=400, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])


def _same_as_tum(g: np.ndarray, e: np.ndarray, max_diff: float) -> None:
    gi, ej = associate_nearest(g, e, max_diff)
    assert np.all(np.diff(ej) > 0)
    assert list(zip(g[gi].tolist(), e[ej].tolist(), strict=True)) == _greedy(g.tolist(), e.tolist(), max_diff)


@st.composite
def stamp_sets(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray, float]:
    """Two sets of stamps on a grid (``step`` apart, so many differences tie), shifted by a base
    that is near zero (rounded differences), ordinary, or large (nanosecond spacing)."""
    base = draw(st.sampled_from([0.0, -0.013, 1e-20, 7.5, 1.56e9, -3.0e4]))
    step = draw(st.sampled_from([0.001, 0.0025, 0.01, 1e-7, 2.4e-7, 1.0]))
    ticks = st.lists(st.integers(0, 60), max_size=45, unique=True)
    g = base + np.array(sorted(draw(ticks)), float) * step
    e = base + np.array(sorted(draw(ticks)), float) * step + draw(st.sampled_from([0.0, 0.5, 0.25, 1 / 3])) * step
    tiny = draw(st.lists(st.sampled_from([0.0, 1e-20, -1e-20, 3e-17, 5e-3, -2e-3, 1e-3]), max_size=4, unique=True))
    e = np.concatenate([e, np.array(tiny)]) if base == 0.0 else e
    max_diff = draw(st.sampled_from([0.02, 0.005, 3 * step, step, 1.5 * step]))
    return np.unique(g), np.unique(e), max_diff


@PROPERTY
@given(stamp_sets())
@pytest.mark.thorough
def test_same_pairs_as_tum_on_grids_with_ties(case):
    _same_as_tum(*case)


@PROPERTY
@given(st.integers(0, 2**32 - 1), st.integers(1, 60), st.integers(1, 60))
def test_same_pairs_as_tum_on_random_stamps(seed, n, m):
    rng = np.random.default_rng(seed)
    g = np.unique(np.round(np.cumsum(rng.uniform(0.0, 0.03, n)), rng.integers(2, 6)))
    e = np.unique(np.round(np.cumsum(rng.uniform(0.0, 0.03, m)), rng.integers(2, 6)))
    _same_as_tum(g, e, 0.02)


@pytest.mark.parametrize("n", [1, 2, 7, 40])
def test_chains_of_growing_gaps(n):
    """g e g e ... with every gap a little larger than the one before: one pair per round."""
    points = 5.0 + np.cumsum(0.01 + np.arange(2 * n) * 1e-5)
    _same_as_tum(points[0::2], points[1::2], 0.02)
    _same_as_tum(points[1::2], points[0::2], 0.02)


def test_empty_and_disjoint():
    for g, e in ((np.zeros(0), np.arange(3.0)), (np.arange(3.0), np.zeros(0)), (np.arange(3.0), np.arange(3.0) + 0.5)):
        gi, ej = associate_nearest(g, e, 0.02)
        assert gi.size == ej.size == 0 and gi.dtype == ej.dtype == np.int64


@pytest.mark.parametrize("seed", range(3))
def test_large_sets_match_every_candidate_rule(seed):
    """100,000 ground-truth stamps at 100 Hz and jittered estimate stamps at about 30 Hz and at
    100 Hz: the pairs of the rule over every candidate (the previous implementation, kept for
    what nearest neighbours cannot decide)."""
    from lorisnb.core.conventions import choices as conventions

    rng = np.random.default_rng(seed)
    g = 1.56e9 + np.arange(100_000) / 100.0
    for e in (
        np.unique(1.56e9 + np.sort(rng.uniform(0, 1000, 33_000))),
        np.unique(1.56e9 + np.arange(100_000) / 100.0 + rng.normal(0, 0.004, 100_000)),
    ):
        gi, ej = associate_nearest(g, e, 0.02)
        want = conventions._greedy_candidates(g, e, np.arange(g.size), np.arange(e.size), 0.02)
        assert np.array_equal(gi, want[0]) and np.array_equal(ej, want[1])
        assert gi.size > 0.9 * min(e.size, g.size) * (0.4 if e.size < 50_000 else 1)
