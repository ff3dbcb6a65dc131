"""Figures of repeated trials: per-trial scene values of each algorithm, by scene (seaborn)."""

from __future__ import annotations

from collections.abc import Sequence

import pandas as pd
import seaborn as sns
from matplotlib.figure import Figure

from lorisnb.core.metrics.openloris import RATES
from lorisnb.core.stats.inference import scene_values, with_trials
from lorisnb.tools.figures.plotting import MAX_WIDTH_IN, same_jitter, shown_names, subplots
from lorisnb.tools.report.tables import LABELS


def plot_trials(table: pd.DataFrame, metric: str = "cr", scenes: Sequence[str] | None = None) -> Figure:
    """One panel per scene: a box of the per-trial scene values of ``metric`` for each algorithm,
    with every trial as a dot (a single trial shows as one dot)."""
    values = scene_values(with_trials(table), [metric], by=["suite", "algorithm", "scene", "trial"])
    if scenes is not None:
        values = values[values["scene"].isin(list(scenes))]
    values = shown_names(values, ["algorithm", "scene"])  # tick labels and titles as the terminal shows them
    panels = list(dict.fromkeys(values["scene"]))
    algs = sorted(values["algorithm"].unique())
    fig, axes = subplots(1, max(1, len(panels)), figsize=(min(3.2 * max(1, len(panels)), MAX_WIDTH_IN), 0.35 * len(algs) + 1.6),
                             sharey=True, squeeze=False)  # fmt: skip
    for ax, scene in zip(axes[0], panels, strict=False):
        d = values[values["scene"] == scene]
        sns.boxplot(data=d, x=metric, y="algorithm", order=algs, ax=ax, color="#dde6f3", fliersize=0, width=0.6)
        with same_jitter():
            sns.stripplot(data=d, x=metric, y="algorithm", order=algs, ax=ax, color="#1f5fbf", size=4, jitter=0.15)
        ax.set_title(scene)
        ax.set_xlabel(LABELS.get(metric, metric))
        ax.set_ylabel("")
        if metric in RATES:
            ax.set_xlim(-0.03, 1.03)
    fig.tight_layout()
    return fig
