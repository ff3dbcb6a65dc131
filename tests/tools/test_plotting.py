"""Plotting functions (figures are checked by what they draw, not by pixels) and the timeline data."""

from __future__ import annotations

import matplotlib
import pytest

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402

import lorisnb as ln  # noqa: E402
from lorisnb.core.lifelong.sweep import rank_stability, sweep, sweep_scenes  # noqa: E402
from lorisnb.core.lifelong.timeline import pose_segments, sequence_layout, timeline_table  # noqa: E402
from lorisnb.tools.figures import plotting


def test_pose_segments_by_hand():
    stamps = np.array([0.0, 0.5, 1.0, 3.0, 3.5, 4.0])
    correct = np.array([True, True, False, False, True, True])
    s, e, c = pose_segments(stamps, correct, 5.0, 1.0)
    # [0, 1) correct (two poses touching), [1, 2) wrong (held 1 s, gap to 3), [3, 3.5) wrong, [3.5, 5) correct
    np.testing.assert_allclose(s, [0.0, 1.0, 3.0, 3.5])
    np.testing.assert_allclose(e, [1.0, 2.0, 3.5, 5.0])
    assert c.tolist() == [True, False, False, True]


@pytest.fixture(scope="module")
def ev(icra20):
    return ln.evaluate(
        icra20 / "lifelong", algorithms=["vins_mono_color_imu_with_loop", "maslam"], scenes=["home", "cafe"]
    )


def test_timeline_draws_every_segment_and_first_pose(ev):
    durations = ev.durations()
    scenes = ev.scenes("paper", 30.0)
    fig = plotting.plot_timeline(ev.errors, durations, scenes, "paper", 30.0)
    ax = fig.axes[0]
    segs, firsts = timeline_table(ev.errors, "paper", 30.0)
    drawn = sum(len(c.get_segments()) for c in ax.collections if isinstance(c, LineCollection))
    assert drawn == len(segs)
    crosses = [ln_ for ln_ in ax.lines if ln_.get_marker() == "x"]
    assert sum(len(ln_.get_xdata()) for ln_ in crosses) == int((~firsts["correct"]).sum())
    texts = {t.get_text() for t in ax.texts}
    vins_home = scenes.set_index(["algorithm", "scene"]).loc[("vins_mono_color_imu_with_loop", "home"), "cr"]
    assert f"{100 * vins_home:.1f}%" in texts and "home" in texts
    assert [t.get_text() for t in ax.get_yticklabels()] == ["maslam", "vins_mono_color_imu_with_loop"]
    layout = sequence_layout(durations)
    assert layout["offset"].is_monotonic_increasing and len(layout) == 7
    plt.close(fig)


@pytest.mark.thorough
def test_trajectories_and_sensitivity_figures(ev):
    f = next(e for e in ev.errors if e.scene == "home" and e.algorithm.startswith("vins"))
    fig = plotting.plot_trajectories(f, 3.0, 30.0)
    assert len([a for a in fig.axes if a.has_data()]) == len(f.sequences)
    plt.close(fig)
    scenes = sweep_scenes(sweep(ev.errors, [0.3, 1, 3, 10], [10, 30, 180]), ev.durations())
    fig = plotting.plot_metric_vs_threshold(scenes[scenes["phi"] == 30], "eps", "cr", marks=ln.PAPER_EPS)
    assert len(fig.axes) == 2 and all(ax.get_xscale() == "log" for ax in fig.axes)
    plt.close(fig)
    fig = plotting.plot_cr_heatmaps(scenes, "home", mark=(3.0, 30.0))
    assert len([a for a in fig.axes if a.get_title()]) >= 2
    plt.close(fig)
    fig = plotting.plot_rank_stability(rank_stability(scenes[scenes["phi"] == 30]))
    assert fig.axes[0].has_data()
    plt.close(fig)
    alone = rank_stability(scenes[(scenes["phi"] == 30) & (scenes["algorithm"] == f.algorithm)])
    assert alone.empty  # one algorithm: no ranking; the figure says so instead of failing
    fig = plotting.plot_rank_stability(alone)
    assert "two or more algorithms" in fig.axes[0].texts[0].get_text()
    plt.close(fig)


def test_crosscheck_scatter_and_normalized_accuracy():
    df = pd.DataFrame(
        {"ate_lorisnb": [0.1, 0.2], "ate_evo": [0.1, 0.2], "aoe_lorisnb": [1.0, 2.0], "aoe_evo": [1.0, 2.0]}
    )
    fig = plotting.plot_crosscheck_scatter({"a": df})
    assert "max |difference| 0.0e+00 m" in fig.axes[0].get_title()
    plt.close(fig)
    meas = pd.DataFrame({"dataset": ["X", "X"], "group": ["g1", "g2"], "ate_pct_length": [1.0, 2.0]})
    pub = pd.DataFrame({"dataset": ["Y"], "ate_pct_length": [0.5]})
    fig = plotting.plot_normalized_accuracy(meas, pub)
    labels = [t.get_text() for t in fig.axes[0].get_yticklabels()]
    assert "Y (published)" in labels and "X" in labels
    plt.close(fig)
