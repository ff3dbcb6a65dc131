"""The KITTI devkit's per-length plot (its ``plotErrorPlots`` ``_tl`` and ``_rl`` figures):
translation error (percent) and rotation error against the segment length, for the lengths with
at least 3 segments (the lengths the devkit writes). The devkit draws the rotation in deg/m
(``$2*57.3``); lorisnb's columns and this figure use degrees per 100 m (x 180/pi x 100)."""

from __future__ import annotations

import pandas as pd
from matplotlib.figure import Figure

from lorisnb.tools.decisions.escape import clean
from lorisnb.tools.figures.plotting import subplots


def kitti_length_figure(lengths: pd.DataFrame, totals_only: bool = True) -> Figure:
    """Two panels from :meth:`lorisnb.Evaluation.kitti_lengths` (or
    :func:`lorisnb.core.metrics.kitti_table.kitti_lengths`): one line per algorithm (its devkit
    total over all sequences; ``totals_only=False``: one per sequence too), marked points as the
    devkit plots them (``pt 4 w linespoints``)."""
    fig, (ax_t, ax_r) = subplots(1, 2, figsize=(10, 3.6))
    table = lengths[lengths.plotted]
    if totals_only:
        table = table[table.seq == ""]
    for (algorithm, trial, file, seq), g in table.groupby(["algorithm", "trial", "file", "seq"], sort=False):
        label = (
            clean(algorithm) + (f" trial {trial}" if trial else "") + (f" {clean(file)} seq {seq}" if seq else " (all)")
        )
        ax_t.plot(g.length, g.t_err, "s-", label=label, ms=4)
        ax_r.plot(g.length, g.r_err, "s-", label=label, ms=4)
    ax_t.set(xlabel="Path Length [m]", ylabel="Translation Error [%]")
    ax_r.set(xlabel="Path Length [m]", ylabel="Rotation Error [deg/100 m]")
    for ax in (ax_t, ax_r):
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
    if len(table):
        ax_t.legend(fontsize=7)
    else:
        ax_t.text(0.5, 0.5, "no length with 3 segments", ha="center", transform=ax_t.transAxes)
    fig.suptitle("KITTI odometry: error per segment length (devkit evaluate_odometry.cpp)", fontsize=10)
    fig.tight_layout()
    return fig
