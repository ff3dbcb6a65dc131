"""ipywidgets controls: explore eps, phi, delta and tau live on errors computed once.

:class:`ThresholdExplorer` re-scores precomputed per-pose errors (no re-reading, no re-alignment)
whenever a slider moves, and redraws the per-scene table and the timeline. ``results()`` gives the
same table and figure for the current values without any widget, which is what a notebook shows
when it runs in batch (papermill has no widget front end).
"""

from __future__ import annotations

from typing import Sequence

import matplotlib.pyplot as plt
import pandas as pd

from .evaluation import FileErrors, aggregate_scenes, score
from .plotting import plot_timeline


class ThresholdExplorer:
    """Sliders for eps (m), phi (deg), delta (s), tau (s) and a scene dropdown."""

    def __init__(self, errors: Sequence[FileErrors], durations: pd.DataFrame, eps: float = 3.0, phi: float = 30.0,
                 delta: float = 1.0, tau: float = 60.0, scene: str | None = None):
        self.errors = list(errors)
        self.durations = durations
        self.scenes = [s for s in durations["scene"].unique() if any(f.scene == s for f in self.errors)]
        self.eps, self.phi, self.delta, self.tau = float(eps), float(phi), float(delta), float(tau)
        self.scene = scene if scene is not None else (self.scenes[0] if self.scenes else None)

    def results(self) -> tuple[pd.DataFrame, plt.Figure]:
        """Scene table and timeline figure for the current values."""
        files = [f for f in self.errors if f.scene == self.scene]
        table = aggregate_scenes(score(files, self.eps, self.phi, self.delta, self.tau),
                                 self.durations[self.durations["scene"] == self.scene])
        fig = plot_timeline(files, self.durations[self.durations["scene"] == self.scene], table, self.eps, self.phi,
                            self.delta, title=f"{self.scene}: eps {self.eps:g} m, phi {self.phi:g} deg, "
                                              f"delta {self.delta:g} s, tau {self.tau:g} s")
        cols = ["algorithm", "cr", "cr_t", "cs_r_mean", "c_ate_rmse", "c_matched", "matched"]
        return table[cols].sort_values("cr", ascending=False).reset_index(drop=True), fig

    def widget(self):
        """The interactive controls and their output (for JupyterLab)."""
        import ipywidgets as w
        from IPython.display import display

        style = {"description_width": "90px"}
        eps = w.FloatLogSlider(value=self.eps, base=10, min=-2, max=2, step=0.05, description="eps (m)", style=style)
        phi = w.FloatSlider(value=min(self.phi, 180.0), min=1, max=180, step=1, description="phi (deg)", style=style)
        delta = w.FloatLogSlider(value=self.delta, base=10, min=-1.3, max=1, step=0.05, description="delta (s)",
                                 style=style)
        tau = w.FloatLogSlider(value=self.tau, base=10, min=0, max=3, step=0.05, description="tau (s)", style=style)
        scene = w.Dropdown(options=self.scenes, value=self.scene, description="scene", style=style)
        out = w.Output()

        def update(_=None):
            self.eps, self.phi, self.delta, self.tau, self.scene = eps.value, phi.value, delta.value, tau.value, scene.value
            with out:
                out.clear_output(wait=True)
                table, fig = self.results()
                display(table.round(3))
                display(fig)
                plt.close(fig)

        for c in (eps, phi, delta, tau, scene):
            c.observe(update, names="value")
        update()
        return w.VBox([w.HBox([w.VBox([eps, phi]), w.VBox([delta, tau]), scene]), out])

