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

from ..core.aggregate import aggregate_scenes, durations_table
from ..core.model import FileErrors, ResultFile
from ..core.scoring import score
from ..core.simulate import Faults, simulated_errors
from ..core.validate import threshold
from .plotting import plot_timeline


def _render(out, results) -> None:
    """Replace the widget output with the table and figure of ``results()``."""
    from IPython.display import display

    with out:
        out.clear_output(wait=True)
        table, fig = results()
        display(table.round(3))
        display(fig)
        plt.close(fig)


class ThresholdExplorer:
    """Sliders for eps (m), phi (deg), delta (s), tau (s) and a scene dropdown."""

    def __init__(
        self,
        errors: Sequence[FileErrors],
        durations: pd.DataFrame,
        eps: float = 3.0,
        phi: float = 30.0,
        delta: float = 1.0,
        tau: float = 60.0,
        scene: str | None = None,
    ):
        self.errors = list(errors)
        self.durations = durations
        self.scenes = [s for s in durations["scene"].unique() if any(f.scene == s for f in self.errors)]
        self.eps, self.phi, self.delta, self.tau = (
            threshold(name, v) for name, v in (("eps", eps), ("phi", phi), ("delta", delta), ("tau", tau))
        )
        self.scene = scene if scene is not None else (self.scenes[0] if self.scenes else None)

    def results(self) -> tuple[pd.DataFrame, plt.Figure]:
        """Scene table and timeline figure for the current values."""
        files = [f for f in self.errors if f.scene == self.scene]
        table = aggregate_scenes(
            score(files, self.eps, self.phi, self.delta, self.tau),
            self.durations[self.durations["scene"] == self.scene],
        )
        fig = plot_timeline(
            files,
            self.durations[self.durations["scene"] == self.scene],
            table,
            self.eps,
            self.phi,
            self.delta,
            title=f"{self.scene}: eps {self.eps:g} m, phi {self.phi:g} deg, delta {self.delta:g} s, tau {self.tau:g} s",
        )
        cols = ["algorithm", "cr", "cr_t", "cs_r_mean", "c_ate_rmse", "c_matched", "matched"]
        return table[cols].sort_values("cr", ascending=False).reset_index(drop=True), fig

    def widget(self):
        """The interactive controls and their output (for JupyterLab)."""
        import ipywidgets as w

        style = {"description_width": "90px"}
        eps = w.FloatLogSlider(value=self.eps, base=10, min=-2, max=2, step=0.05, description="eps (m)", style=style)
        phi = w.FloatSlider(value=min(self.phi, 180.0), min=1, max=180, step=1, description="phi (deg)", style=style)
        delta = w.FloatLogSlider(
            value=self.delta, base=10, min=-1.3, max=1, step=0.05, description="delta (s)", style=style
        )
        tau = w.FloatLogSlider(value=self.tau, base=10, min=0, max=3, step=0.05, description="tau (s)", style=style)
        scene = w.Dropdown(options=self.scenes, value=self.scene, description="scene", style=style)
        out = w.Output()

        def update(_=None):
            self.eps, self.phi, self.delta, self.tau, self.scene = (
                eps.value,
                phi.value,
                delta.value,
                tau.value,
                scene.value,
            )
            _render(out, self.results)

        for c in (eps, phi, delta, tau, scene):
            c.observe(update, names="value")
        update()
        return w.VBox([w.HBox([w.VBox([eps, phi]), w.VBox([delta, tau]), scene]), out])


class FaultExplorer:
    """Sliders for the simulator's faults (:class:`lorisnb.core.simulate.Faults`) on one ground-truth
    sequence: every change re-simulates, re-scores and redraws the metrics and the timeline."""

    def __init__(
        self,
        groundtruth: ResultFile,
        seq: int = 1,
        eps: float = 1.0,
        phi: float = 30.0,
        delta: float = 1.0,
        tau: float = 60.0,
        seed: int = 0,
    ):
        self.groundtruth = groundtruth
        self.seq = seq
        self.eps, self.phi, self.delta, self.tau = (
            threshold(name, v) for name, v in (("eps", eps), ("phi", phi), ("delta", delta), ("tau", tau))
        )
        self.seed = seed
        self.duration = groundtruth.sequences[seq].duration
        d = durations_table({groundtruth.scene: groundtruth})
        self.durations = d[d["seq"] == seq]
        self.values = dict(
            position_noise_m=0.0,
            orientation_noise_deg=0.0,
            yaw_drift_deg_per_m=0.0,
            scale=1.0,
            init_delay_s=0.0,
            lost_from_s=0.0,
            lost_for_s=0.0,
            wrong_reloc_at_s=-1.0,
            rate_hz=0.0,
            clock_offset_s=0.0,
        )

    def faults(self) -> Faults:
        v = self.values
        lost = ((v["lost_from_s"], v["lost_from_s"] + v["lost_for_s"]),) if v["lost_for_s"] > 0 else ()
        return Faults(
            position_noise_m=v["position_noise_m"],
            orientation_noise_deg=v["orientation_noise_deg"],
            yaw_drift_deg_per_m=v["yaw_drift_deg_per_m"],
            scale=v["scale"],
            init_delay_s=v["init_delay_s"],
            lost=lost,
            wrong_reloc_at_s=v["wrong_reloc_at_s"] if v["wrong_reloc_at_s"] >= 0 else None,
            rate_hz=v["rate_hz"] or None,
            clock_offset_s=v["clock_offset_s"],
            seed=self.seed,
        )

    def results(self) -> tuple[pd.DataFrame, plt.Figure]:
        """Metrics table and timeline for the current slider values."""
        fe = simulated_errors(self.groundtruth, self.faults(), seqs=[self.seq], name="sliders")
        table = score(fe, self.eps, self.phi, self.delta, self.tau)
        fig = plot_timeline(
            [fe],
            self.durations,
            aggregate_scenes(table, self.durations),
            self.eps,
            self.phi,
            self.delta,
            title=self.faults().describe(),
        )
        cols = ["matched", "ate_rmse", "aoe_rmse", "c_ate_rmse", "cr", "cr_t", "reloc_time", "cs_r", "rpe_trans_rmse"]
        return table[cols], fig

    def widget(self):
        import ipywidgets as w

        d = self.duration
        spec = [
            ("position_noise_m", w.FloatSlider, dict(min=0, max=1, step=0.01, description="noise (m)")),
            ("orientation_noise_deg", w.FloatSlider, dict(min=0, max=45, step=1, description="noise (deg)")),
            ("yaw_drift_deg_per_m", w.FloatSlider, dict(min=0, max=5, step=0.1, description="yaw drift (deg/m)")),
            ("scale", w.FloatSlider, dict(min=0.2, max=2, step=0.05, description="scale")),
            ("init_delay_s", w.FloatSlider, dict(min=0, max=d, step=1, description="init delay (s)")),
            ("lost_from_s", w.FloatSlider, dict(min=0, max=d, step=1, description="lost from (s)")),
            ("lost_for_s", w.FloatSlider, dict(min=0, max=d, step=1, description="lost for (s)")),
            ("wrong_reloc_at_s", w.FloatSlider, dict(min=-1, max=d, step=1, description="wrong reloc at (s)")),
            ("rate_hz", w.FloatSlider, dict(min=0, max=10, step=0.1, description="rate (Hz, 0: all)")),
            ("clock_offset_s", w.FloatSlider, dict(min=-2, max=2, step=0.05, description="clock offset (s)")),
        ]
        style = {"description_width": "130px"}
        controls = {k: cls(value=self.values[k], style=style, continuous_update=False, **kw) for k, cls, kw in spec}
        out = w.Output()

        def update(_=None):
            self.values.update({k: c.value for k, c in controls.items()})
            _render(out, self.results)

        for c in controls.values():
            c.observe(update, names="value")
        update()
        items = list(controls.values())
        return w.VBox([w.HBox([w.VBox(items[:5]), w.VBox(items[5:])]), out])
