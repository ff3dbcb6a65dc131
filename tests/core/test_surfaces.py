"""CR surfaces by dominance counting equal scoring each setting alone, ties at bin edges included."""

from __future__ import annotations

import numpy as np
import pytest

import lorisnb as ln
from lorisnb.core import aggregate_scenes
from lorisnb.core.lifelong.surfaces import cr_surfaces


@pytest.fixture(scope="module")
def lifelong(icra20):
    return ln.evaluate(icra20 / "lifelong", scale="auto", scenes=["cafe", "home"], jobs=1)


@pytest.mark.thorough
def test_surfaces_equal_single_setting_scores(lifelong):
    ev = lifelong
    ate = np.concatenate([e.ate for f in ev.errors for e in f.sequences])
    aoe = np.concatenate([e.aoe for f in ev.errors for e in f.sequences])
    rng = np.random.default_rng(0)
    # a fine grid that contains exact ATE and AOE values of poses: thresholds are inclusive
    eps = np.unique(np.concatenate([np.geomspace(0.05, 50, 300), rng.choice(ate, 20)]))
    phi = np.unique(np.concatenate([np.linspace(1, 180, 180), rng.choice(aoe, 20)]))
    durations = ev.durations()
    s = cr_surfaces(ev.errors, eps, phi, durations, delta=1.0)
    assert s.cr.shape == (len(s.groups), len(eps), len(phi))
    picks = [
        (int(np.searchsorted(eps, v)), int(np.searchsorted(phi, w)))
        for v, w in zip(rng.choice(ate, 6), rng.choice(aoe, 6), strict=True)
    ]
    picks += [(int(i), int(j)) for i, j in zip(rng.integers(0, len(eps), 6), rng.integers(0, len(phi), 6), strict=True)]
    for i, j in picks:
        direct = aggregate_scenes(ln.score(ev.errors, eps[i], phi[j], 1.0, 60.0), durations)
        for g, row in s.groups.iterrows():
            d = direct[(direct["algorithm"] == row["algorithm"]) & (direct["scene"] == row["scene"])].iloc[0]
            assert s.cr[g, i, j] == pytest.approx(d["cr"], abs=1e-12)
            assert s.correct_time[g, i, j] == pytest.approx(d["correct_time"], abs=1e-9)
            assert s.cr_t[g, i, j] == pytest.approx(d["cr_t"], abs=1e-12, nan_ok=True)


def test_a_1000_by_1000_surface_stays_small(lifelong):
    eps, phi = np.geomspace(0.01, 100, 1000), np.linspace(0.1, 180, 1000)
    s = cr_surfaces(lifelong.errors, eps, phi, lifelong.durations())
    assert s.cr.shape[1:] == (1000, 1000) and s.cr.nbytes <= len(s.groups) * 8e6
    assert np.all(np.diff(s.cr, axis=1) >= -1e-15) and np.all(np.diff(s.cr, axis=2) >= -1e-15)  # monotone
    top = s.at("vins_mono_color_imu_with_loop", "home")
    assert top[-1, -1] == pytest.approx(aggregate_scenes(ln.score(lifelong.errors), lifelong.durations())
                                        .set_index(["algorithm", "scene"]).loc[("vins_mono_color_imu_with_loop", "home"), "cr"])  # fmt: skip
    with pytest.raises(ln.ValidationError):
        cr_surfaces(lifelong.errors, ["paper"], [30], lifelong.durations())
