"""ipywidgets controls: moving a slider re-scores from errors computed once."""

from __future__ import annotations

import pytest

import lorisnb as ln
from lorisnb.io import load_groundtruth
from lorisnb.tools.widgets import FaultExplorer, ThresholdExplorer


def _sliders(box):
    out = []
    stack = [box]
    while stack:
        w = stack.pop()
        if hasattr(w, "children"):
            stack.extend(w.children)
        elif hasattr(w, "value") and hasattr(w, "description"):
            out.append(w)
    return {w.description: w for w in out}


def test_threshold_explorer_updates_without_recomputing(icra20):
    ev = ln.evaluate(icra20 / "lifelong", algorithms=["vins_mono_color_imu_with_loop"], scenes=["home"])
    ex = ThresholdExplorer(ev.errors, ev.durations(), eps=3.0, phi=30.0)
    box = ex.widget()
    table, _ = ex.results()
    assert table.set_index("algorithm").loc["vins_mono_color_imu_with_loop", "cr"] == pytest.approx(0.335952, abs=1e-6)
    _sliders(box)["phi (deg)"].value = 180.0
    assert ex.phi == 180.0
    table2, _ = ex.results()
    assert table2["cr"].iloc[0] > table["cr"].iloc[0]


def test_fault_explorer_sliders():
    ex = FaultExplorer(load_groundtruth("cafe"), seq=1, eps=1.0, phi=30.0)
    box = ex.widget()
    t0, _ = ex.results()
    assert t0["cr"].iloc[0] == pytest.approx(1.0, abs=1e-3)
    _sliders(box)["init delay (s)"].value = 30.0
    t1, _ = ex.results()
    assert t1["cs_r"].iloc[0] == pytest.approx(0.6065, abs=2e-3) and t1["cr_t"].iloc[0] == pytest.approx(1.0)
