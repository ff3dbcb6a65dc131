"""A report's figures are the same at every run: seaborn's strip-plot jitter is seeded by
:func:`lorisnb.tools.figures.plotting.same_jitter`, which leaves numpy's global generator as it was."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from lorisnb.tools.evaluation.runner import evaluate
from lorisnb.tools.figures.trials import plot_trials
from lorisnb.tools.notebook.start import figure_png


@pytest.mark.thorough
def test_trial_figure_is_the_same_at_every_run_and_leaves_numpys_generator_alone(icra20):
    ev = evaluate([icra20 / "lifelong" / "maslam", icra20 / "lifelong" / "ds-slam"], jobs=1, progress=False)
    one = ev.sequences(eps=1.0)
    trials = [one.assign(trial=k, correct_time=one["correct_time"] * (1 - 0.1 * k)) for k in range(4)]
    table = pd.concat(trials, ignore_index=True)  # several dots per algorithm: jittered
    np.random.seed(123)
    expected = np.random.random()
    np.random.seed(123)
    first = figure_png(plot_trials(table, "cr"), dpi=60)
    assert np.random.random() == expected  # the caller's random numbers are untouched
    np.random.seed(7)  # another global state: the same figure
    assert figure_png(plot_trials(table, "cr"), dpi=60) == first


@pytest.mark.thorough
def test_heatmaps_measure_their_texts_with_one_renderer_and_look_the_same(icra20, monkeypatch):
    """A figure outside pyplot measures its texts with one kept renderer
    (:class:`lorisnb.tools.figures.plotting._MeasuredFigure`) instead of a new one per text: seaborn's
    heatmaps, which measure every tick label, come out pixel for pixel as with matplotlib's own."""
    import matplotlib.backends.backend_agg as agg
    from matplotlib.figure import Figure

    from lorisnb.core.lifelong.sweep import sweep, sweep_scenes
    from lorisnb.tools.figures import plotting

    ev = evaluate([icra20 / "lifelong" / "maslam", icra20 / "lifelong" / "ds-slam"], jobs=1, progress=False)
    grid = sweep_scenes(sweep(ev.errors, [0.1, 0.3, 1.0, 3.0, 10.0], [10.0, 30.0, 90.0], [1.0], [60.0]), ev.durations())
    made = []
    monkeypatch.setattr(agg, "RendererAgg", lambda *a, _real=agg.RendererAgg: made.append(a) or _real(*a))
    fig = plotting.plot_cr_heatmaps(grid, "cafe", mark=(3.0, 30.0))
    assert type(fig) is plotting._MeasuredFigure and len(made) == 1  # one renderer measured every text
    ours = figure_png(fig, dpi=60)
    monkeypatch.setattr(plotting, "_MeasuredFigure", Figure)  # matplotlib's: a new renderer per text
    made.clear()
    plain = plotting.plot_cr_heatmaps(grid, "cafe", mark=(3.0, 30.0))
    assert type(plain) is Figure and len(made) > 10  # one per tick label measured
    assert figure_png(plain, dpi=60) == ours
