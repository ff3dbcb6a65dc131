"""A report's figures are the same at every run: seaborn's strip-plot jitter is seeded by
:func:`lorisnb.tools.plotting.same_jitter`, which leaves numpy's global generator as it was."""

from __future__ import annotations

import numpy as np
import pandas as pd

from lorisnb.tools.evaluate import evaluate
from lorisnb.tools.notebook import figure_png
from lorisnb.tools.trial_plots import plot_trials


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
