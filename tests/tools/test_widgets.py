"""ipywidgets controls: moving a slider re-scores from errors computed once."""

from __future__ import annotations

import pytest
from helpers import widget_controls

import lorisnb as ln
from lorisnb.io import load_groundtruth
from lorisnb.tools.notebook.widgets import FaultExplorer, ThresholdExplorer


def test_threshold_explorer_updates_without_recomputing(icra20):
    ev = ln.evaluate(icra20 / "lifelong", algorithms=["vins_mono_color_imu_with_loop"], scenes=["home"])
    ex = ThresholdExplorer(ev.errors, ev.durations(), eps=3.0, phi=30.0)
    box = ex.widget()
    table, _ = ex.results()
    assert table.set_index("algorithm").loc["vins_mono_color_imu_with_loop", "cr"] == pytest.approx(0.335952, abs=1e-6)
    widget_controls(box)["phi (deg)"].value = 180.0
    assert ex.phi == 180.0
    table2, _ = ex.results()
    assert table2["cr"].iloc[0] > table["cr"].iloc[0]


def test_fault_explorerwidget_controls():
    ex = FaultExplorer(load_groundtruth("cafe"), seq=1, eps=1.0, phi=30.0)
    box = ex.widget()
    t0, _ = ex.results()
    assert t0["cr"].iloc[0] == pytest.approx(1.0, abs=1e-3)
    widget_controls(box)["init delay (s)"].value = 30.0
    t1, _ = ex.results()
    assert t1["cs_r"].iloc[0] == pytest.approx(0.6065, abs=2e-3) and t1["cr_t"].iloc[0] == pytest.approx(1.0)


def test_sliders_start_exactly_at_the_parameters_and_offer_the_papers_values(icra20):
    ev = ln.evaluate(icra20 / "lifelong", algorithms=["vins_mono_color_imu_with_loop"], scenes=["home"])
    ex = ThresholdExplorer(ev.errors, ev.durations(), eps=5.0, phi=30.0, delta=1.0, tau=60.0)
    s = widget_controls(ex.widget())
    assert (s["eps (m)"].value, s["phi (deg)"].value, s["delta (s)"].value, s["tau (s)"].value) == (
        5.0,
        30.0,
        1.0,
        60.0,
    )
    assert {1.0, 3.0, 5.0} <= set(s["eps (m)"].options_values if hasattr(s["eps (m)"], "options_values") else
                                  [v for _, v in s["eps (m)"].options])  # fmt: skip
    assert ex.results()[0]["cr"].iloc[0] == pytest.approx(ex.results()[0]["cr"].iloc[0])
    odd = ThresholdExplorer(ev.errors, ev.durations(), eps=2.345, phi=17.5, tau=63.0)
    s = widget_controls(odd.widget())
    assert (s["eps (m)"].value, s["phi (deg)"].value, s["tau (s)"].value) == (2.345, 17.5, 63.0)


def test_widget_figures_are_not_pyplot_figures_and_not_blank():
    import io

    import matplotlib.pyplot as plt
    import numpy as np
    from PIL import Image

    from lorisnb.tools.notebook.start import figure_png

    ex = FaultExplorer(load_groundtruth("cafe"), seq=1)
    before = plt.get_fignums()
    _, fig = ex.results()
    assert plt.get_fignums() == before  # outside pyplot: no backend redraws it behind the widget's back
    img = np.asarray(Image.open(io.BytesIO(figure_png(fig))).convert("L"), float)
    assert img.shape[0] > 100 and (img < 250).mean() > 0.02 and img.std() > 20
    widget_controls(ex.widget())["wrong reloc at (s)"].value = 20.0
    assert ex.faults().wrong_reloc_at_s == 20.0


def test_fault_explorer_takes_the_rpe_step_through_the_spec(data):
    """The explorer's RPE column follows rpe_delta / rpe_unit, checked by make_spec as everywhere."""
    gt = load_groundtruth("cafe", data)
    default = FaultExplorer(gt, seq=1)
    frames = FaultExplorer(gt, seq=1, rpe_delta=30, rpe_unit="f")
    for ex in (default, frames):
        ex.values.update(position_noise_m=0.05)
    a, b = default.results()[0]["rpe_trans_rmse"].iloc[0], frames.results()[0]["rpe_trans_rmse"].iloc[0]
    assert a > 0 and b > 0 and a != pytest.approx(b, rel=1e-3)
    with pytest.raises(ln.ValidationError, match="rpe_unit=km: expected one of"):
        FaultExplorer(gt, seq=1, rpe_unit="km")
