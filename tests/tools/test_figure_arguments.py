"""Figures refuse what they cannot draw truthfully: a timeline's scene table at other thresholds
(its CR texts were printed beside segments at others), and errors of the wrong kind (raw Python
errors before)."""

from __future__ import annotations

import matplotlib.pyplot as plt
import pytest

import lorisnb as ln
from lorisnb.errors import ValidationError
from lorisnb.tools.figures.plotting import plot_timeline, plot_trajectories


@pytest.fixture(scope="module")
def ev(icra20):
    return ln.evaluate(icra20 / "lifelong" / "maslam", progress=False)


@pytest.mark.parametrize(
    "table_at, message",
    [
        (dict(eps="paper", phi=10), "scene table is at phi=10"),
        (dict(eps=1.0, phi=30), r"scene table is at eps=1 m for maslam"),
        (dict(eps="paper", phi=30, delta=2.0), "scene table is at delta=2"),
        (dict(), "scene table is at phi=inf"),
    ],
)
def test_timeline_refuses_a_scene_table_at_other_thresholds(ev, table_at, message):
    with pytest.raises(ValidationError, match=message):
        plot_timeline(ev.errors, ev.durations(), ev.scenes(**table_at), eps="paper", phi=30)


def test_timeline_at_the_table_thresholds_is_drawn(ev):
    for eps in ("paper", 0.5, "relative:0.1"):
        fig = plot_timeline(ev.errors, ev.durations(), ev.scenes(eps=eps, phi=30), eps=eps, phi=30)
        plt.close(fig)


def test_figures_refuse_errors_of_another_kind_saying_what_to_pass(ev):
    with pytest.raises(ValidationError, match=r"one figure per file: plot_trajectories\(ev.errors\[0\]\)"):
        plot_trajectories(ev.errors)
    with pytest.raises(ValidationError, match=r"one FileErrors; expected a list of them"):
        plot_timeline(ev.errors[0], ev.durations(), ev.scenes())
    with pytest.raises(ValidationError, match="expected the scene table"):
        plot_timeline(ev.errors, ev.durations(), None)
