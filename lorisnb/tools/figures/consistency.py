"""``ov_eval``'s per-axis error plot (its ``error_singlerun`` figures): the error of each position
axis (m) and of roll, pitch and yaw (deg) over time, with the 3-sigma bounds the estimator's own
covariance gives (:func:`lorisnb.core.metrics.consistency.ov_eval_errors`), and the NEES of
orientation and position against 3, its expected mean."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from lorisnb.core.metrics.consistency import Consistency
from lorisnb.tools.figures.plotting import subplots


def consistency_figure(result: Consistency, title: str = "") -> Figure:
    """Six panels of per-axis errors (position x, y, z in m; roll, pitch, yaw in deg) against time
    since the first matched pose, each with its +-3-sigma band where covariances were given, and a
    row with the two NEES (where given)."""
    poses = result.poses
    has_nees = "nees_ori" in poses
    fig, axes = subplots(3 if has_nees else 2, 3, figsize=(11, 7.5 if has_nees else 5.2), squeeze=False)
    t = poses["t"].to_numpy() - float(poses["t"].iloc[0]) if len(poses) else np.zeros(0)
    panels = [("pos_x", "x error [m]"), ("pos_y", "y error [m]"), ("pos_z", "z error [m]"),
              ("roll", "roll error [deg]"), ("pitch", "pitch error [deg]"), ("yaw", "yaw error [deg]")]  # fmt: skip
    for ax, (name, label) in zip(axes[:2].ravel(), panels, strict=True):
        ax.plot(t, poses[name], "-", color="tab:blue", lw=0.9, label="error")
        bound = f"{name}_3sigma"
        if bound in poses:
            b = poses[bound].to_numpy()
            ax.plot(t, b, "--", color="tab:red", lw=0.8, label="3 sigma")
            ax.plot(t, -b, "--", color="tab:red", lw=0.8)
            inside = float(np.mean(np.abs(poses[name]) <= b)) if len(b) else float("nan")
            ax.set_title(f"{100 * inside:.1f} % within 3 sigma", fontsize=8)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7, loc="upper left")
    if has_nees:
        for ax, name, label in (
            (axes[2, 0], "nees_ori", "orientation NEES"),
            (axes[2, 1], "nees_pos", "position NEES"),
        ):
            ax.plot(t, poses[name], "-", color="tab:green", lw=0.9)
            ax.axhline(3.0, color="k", lw=0.8, ls=":", label="3 (consistent)")
            mean = float(np.nanmean(poses[name])) if len(poses) else float("nan")
            ax.set_title(f"mean {mean:.2f}", fontsize=8)
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
            ax.legend(fontsize=7)
        axes[2, 2].axis("off")
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    fig.suptitle(title or "Per-axis errors with the estimator's 3-sigma bounds (ov_eval)", fontsize=10)
    fig.tight_layout()
    return fig
