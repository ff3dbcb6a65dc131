"""ipywidgets controls: explore eps, phi, delta and tau live on errors computed once.

:class:`ThresholdExplorer` re-scores precomputed per-pose errors (no re-reading, no re-alignment)
whenever a slider moves, and redraws the per-scene table and the timeline. ``results()`` gives the
same table and figure for the current values without any widget, which is what a notebook shows
when it runs in batch (papermill has no widget front end).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from lorisnb.core.lifelong.aggregate import DURATION_COLUMNS, aggregate_scenes, durations_table
from lorisnb.core.lifelong.scoring import as_files, score
from lorisnb.core.pipeline.model import Eps, FileErrors, ResultFile, scene_eps
from lorisnb.core.simulate import Faults, simulated_errors
from lorisnb.core.spec.evalspec import make_spec
from lorisnb.core.spec.validate import present
from lorisnb.core.spec.validate import seed as check_seed
from lorisnb.core.trajectory.frames import PAPER_EPS, PAPER_PHI
from lorisnb.errors import ValidationError
from lorisnb.tools.decisions.escape import clean
from lorisnb.tools.figures.plotting import Timeline, plot_timeline
from lorisnb.tools.notebook.start import show_figure, show_tables_escaped

STYLE = {"description_width": "110px"}
OFF = -1.0  # the "off" position of the wrong re-localization slider
SLIDER_WIDTH = "460px"  # long enough for about 80 positions
#: The paper's other ATE thresholds, metres: Table III's re-localization scores (0.3 m) and its
#: C^0.1-RPE example (0.1 m); its Fig. 3 uses PAPER_EPS, its Fig. 2 CR^inf (no threshold).
PAPER_OTHER_EPS = (0.1, 0.3)


def value_slider(description: str, value: float | str, grid: Iterable[float], exact: Iterable[float] = ()) -> Any:
    """A slider over a fixed list of values (a log or linear grid, rounded to 3 significant
    digits, plus ``value`` and the ``exact`` values themselves), so that it starts at ``value``
    exactly and offers the paper's values exactly; updates when released. A ``value`` that is not a
    number (eps ``relative:F``) is the slider's first position, under its own name."""
    import ipywidgets as w

    rounded = {float(f"{v:.3g}") for v in grid}
    word = isinstance(value, str)
    values = sorted(rounded | {float(v) for v in exact} | (set() if word else {float(value)}))
    return w.SelectionSlider(
        options=([(value, value)] if word else []) + [(f"{v:g}", v) for v in values],
        value=value if word else float(value), description=description, style=STYLE,
        continuous_update=False, layout=w.Layout(width=SLIDER_WIDTH),
    )  # fmt: skip


def explorer_eps(eps: Eps, scene: str | None) -> float | str:
    """The eps an explorer of ``scene`` starts at, from a value checked by
    :func:`lorisnb.core.spec.evalspec.make_spec`: metres as given, ``paper`` (or a mapping scene -> metres) as
    that scene's metres (:func:`lorisnb.core.pipeline.model.scene_eps`), ``relative:F`` as itself (a fraction
    of each sequence's extent, which the slider offers as its first position)."""
    if isinstance(eps, str) and eps.startswith("relative:"):
        return eps
    if isinstance(eps, (str, Mapping)) and scene is not None:
        return scene_eps(eps, scene)
    return float(eps)  # type: ignore[arg-type]


def checked_durations(durations: Any) -> pd.DataFrame:
    """``durations`` if it is a table of ground-truth spans (:data:`DURATION_COLUMNS`, seconds), as
    ``ev.durations()`` returns, else a :class:`ValidationError` saying what to pass."""
    if callable(durations):
        raise ValidationError("durations: got a method; call it: ev.durations() (ground-truth spans, seconds)")
    missing = [c for c in DURATION_COLUMNS if c not in getattr(durations, "columns", ())]
    if not isinstance(durations, pd.DataFrame) or missing:
        raise ValidationError(
            f"durations: expected the ground-truth spans of an evaluation, ev.durations() (columns "
            f"{', '.join(DURATION_COLUMNS)}), got {type(durations).__name__}"
            + (f" without {', '.join(missing)}" if isinstance(durations, pd.DataFrame) else "")
        )
    return durations


def _eps_text(eps: float | str) -> str:
    return eps if isinstance(eps, str) else f"{eps:g} m"


def _render(out: Any, results: Callable[[], tuple[pd.DataFrame, Figure]]) -> None:
    """Replace the widget output with the table and figure of ``results()``. The figure is a
    :class:`matplotlib.figure.Figure` outside pyplot, rendered to PNG on this thread, so no
    backend redraw can race with it (fast drags never show a blank or half-drawn figure)."""
    from IPython.display import display

    show_tables_escaped()  # the table's names as the terminal shows them, also without setup()
    with out:  # in a kernel, an error shows in the output area, not only in the kernel's log
        table, fig = results()
        out.clear_output(wait=True)
        display(table.round(3))
        show_figure(fig)


class ThresholdExplorer:
    """Sliders for eps (m), phi (deg), delta (s), tau (s) and a scene dropdown. The thresholds are
    checked by :func:`lorisnb.core.spec.evalspec.make_spec`, as on every other surface: eps takes metres,
    ``inf``, ``paper`` in any case (the scene's 1/3/5 m), a mapping scene -> metres, or
    ``relative:F`` (:func:`explorer_eps`). With ``paper`` or a mapping, eps follows the scene: a
    scene change moves it to the new scene's metres while it still sits at the old scene's (a
    value moved by hand stays). ``scene`` must be one of the explored scenes (:attr:`scenes`)."""

    def __init__(
        self,
        errors: Sequence[FileErrors],
        durations: pd.DataFrame,
        eps: Eps = 3.0,
        phi: float = 30.0,
        delta: float = 1.0,
        tau: float = 60.0,
        scene: str | None = None,
    ):
        self.errors = as_files(errors)
        self.durations = checked_durations(durations)
        self.scenes = [s for s in durations["scene"].unique() if any(f.scene == s for f in self.errors)]
        spec = make_spec(None, surface="widget", eps=eps, phi=phi, delta=delta, tau=tau)
        if not self.scenes:
            have = sorted({f.scene for f in self.errors})
            raise ValidationError(
                "ThresholdExplorer: nothing to explore: "
                + (f"durations has no sequence of the errors' scenes ({', '.join(have)})" if have else "no errors")
                + "; pass an evaluation's errors and its durations() (ev.errors, ev.durations())"
            )
        self.given: Eps = spec.eps  # the eps as given (checked): "paper" or a mapping follows the scene
        if isinstance(self.given, Mapping) and (missing := [s for s in self.scenes if s not in self.given]):
            raise ValidationError(
                f"eps: no metres for scene(s) {', '.join(missing)}; the explorer shows {', '.join(self.scenes)}: "
                "give eps for each of them, or one number, or 'paper'"
            )
        self._scene = self.scenes[0] if scene is None else present("scene", [scene], self.scenes)[0]
        for s in self.scenes:  # every scene's eps now: a scene change cannot fail inside the dropdown
            explorer_eps(self.given, s)
        self.eps: float | str = explorer_eps(self.given, self._scene)
        self.phi, self.delta, self.tau = float(spec.phi), float(spec.delta), float(spec.tau)
        self._timelines: dict[str, Timeline] = {}  # the shown scene's figure, redrawn in place

    @property
    def scene(self) -> str:
        """The scene shown (one of :attr:`scenes`)."""
        return self._scene

    @scene.setter
    def scene(self, scene: str) -> None:
        new = present("scene", [scene], self.scenes)[0]
        if isinstance(self.given, (str, Mapping)) and self.eps == explorer_eps(self.given, self._scene):
            self.eps = explorer_eps(self.given, new)  # still the scene's eps: the new scene's
        self._scene = new

    def eps_positions(self) -> list[float]:
        """The eps slider's values besides its grid, metres: the paper's (1/3/5 m of Fig. 3, 0.1 and
        0.3 m, ``inf``: no ATE threshold, as ``--eps inf`` and Fig. 2's CR^inf) and every scene's
        value of a mapping eps."""
        given = list(self.given.values()) if isinstance(self.given, Mapping) else []
        return [*PAPER_EPS.values(), *PAPER_OTHER_EPS, *given, float("inf")]

    def results(self) -> tuple[pd.DataFrame, Figure]:
        """Scene table and timeline figure for the current values. Several trials (or suites) of an
        algorithm are a row each: the table has a ``trial`` (``suite``) column and the timeline a
        row per trial, named ``algorithm trial N``. The figure is the scene's own, redrawn in place
        at each call (:class:`~lorisnb.tools.figures.plotting.Timeline`): a figure kept from an
        earlier call shows the latest values. The table is scored without the error statistics
        (``score(..., stats=False)``: its columns are the same values). One slider change on the
        full icra20 market scene (benchmarks/workload.py's slider row; issue 47's goal 0.2 s),
        measured side by side with the figure made anew at each change, three runs each on 2
        shared cores: re-scored and redrawn 0.32-0.45 -> 0.08 s of CPU; with the PNG the widget
        shows (0.31-0.49 s of CPU) 0.83-1.20 -> 0.40-0.42 s wall. The PNG blitted (the kept part
        of the figure restored, the changed artists drawn again: the same pixels as a full savefig)
        and encoded at zlib level 1 (:func:`~lorisnb.tools.figures.blit.encode_png`), two runs of 5
        changes each, before and after in alternation on 2 cores under load 4-5: the PNG 0.34-0.35
        -> 0.12-0.17 s of CPU; the slider change min 0.43-0.57 -> 0.22-0.30 s wall, median
        0.57-0.92 -> 0.31 s (about 0.2 s of CPU in all: the goal, were the cores not shared)."""
        files = [f for f in self.errors if f.scene == self.scene]
        durations = self.durations[self.durations["scene"] == self.scene]
        table = aggregate_scenes(score(files, self.eps, self.phi, self.delta, self.tau, stats=False), durations)
        keys = [k for k in ("suite", "trial") if k in table.columns and table[k].nunique() > 1]
        if self.scene not in self._timelines:  # a row per trial (timeline_rows), as the table has
            self._timelines = {self.scene: Timeline(files, durations)}  # one scene's figure kept at a time
        fig = self._timelines[self.scene].draw(
            table,
            self.eps,
            self.phi,
            self.delta,
            title=f"{clean(self.scene)}: eps {_eps_text(self.eps)}, phi {self.phi:g} deg, delta {self.delta:g} s, tau {self.tau:g} s",
        )
        cols = ["algorithm", *keys, "cr", "cr_t", "cs_r", "c_ate_rmse", "c_matched", "matched"]
        return table[cols].sort_values("cr", ascending=False).reset_index(drop=True), fig

    def widget(self) -> Any:
        """The interactive controls and their output (for JupyterLab). Each slider starts exactly at
        the explorer's value and offers the paper's values exactly (eps 0.1, 0.3, 1, 3, 5 m and
        ``inf``, :meth:`eps_positions`; phi 30 deg, delta 1 s, tau 60 s); eps follows the scene as
        :class:`ThresholdExplorer` says."""
        import ipywidgets as w

        eps = value_slider("eps (m)", self.eps, np.geomspace(0.01, 100, 81), self.eps_positions())
        phi = value_slider("phi (deg)", self.phi, np.arange(1, 181), [PAPER_PHI])
        delta = value_slider("delta (s)", self.delta, np.geomspace(0.05, 10, 47), [1.0])
        tau = value_slider("tau (s)", self.tau, np.geomspace(1, 1000, 61), [60.0])
        scene = w.Dropdown(options=self.scenes, value=self.scene, description="scene", style=STYLE)
        out = w.Output()
        moving = [False]  # the scene moves the eps slider: one redraw, not two

        def update(change: Any = None) -> None:
            if moving[0]:
                return
            if change is not None and change["owner"] is scene:
                self.scene = scene.value  # eps follows the scene where it should (the setter)
                moving[0] = True
                try:
                    eps.value = self.eps
                finally:
                    moving[0] = False
            self.eps, self.phi, self.delta, self.tau = eps.value, phi.value, delta.value, tau.value
            _render(out, self.results)

        for c in (eps, phi, delta, tau, scene):
            c.observe(update, names="value")
        update()
        return w.VBox([w.HBox([w.VBox([eps, phi]), w.VBox([delta, tau, scene])]), out])


class FaultExplorer:
    """Sliders for the simulator's faults (:class:`lorisnb.core.simulate.Faults`) on one ground-truth
    sequence: every change re-simulates, re-scores and redraws the metrics and the timeline. The
    thresholds and the RPE step (``rpe_delta`` in ``rpe_unit``) are checked by
    :func:`lorisnb.core.spec.evalspec.make_spec`, as on every other surface; ``seq`` must be a sequence of the
    ground truth and ``seed`` a whole number >= 0 (:func:`lorisnb.core.spec.validate.seed`)."""

    def __init__(
        self,
        groundtruth: ResultFile,
        seq: int = 1,
        eps: Eps = 1.0,
        phi: float = 30.0,
        delta: float = 1.0,
        tau: float = 60.0,
        seed: int = 0,
        rpe_delta: float = 1.0,
        rpe_unit: str = "s",
    ):
        if not isinstance(groundtruth, ResultFile):
            raise ValidationError(
                f"groundtruth: expected a scene's ground truth (a ResultFile), got {type(groundtruth).__name__}: "
                "pass lorisnb.load_groundtruth(scene, data_root) or lorisnb.read_openloris(path)"
            )
        if seq not in groundtruth.sequences:
            have = ", ".join(str(k) for k in sorted(groundtruth.sequences))
            raise ValidationError(f"seq={seq!r}: the ground truth of {groundtruth.scene} has sequence(s) {have}")
        self.groundtruth = groundtruth
        self.seq = seq
        spec = make_spec(None, surface="widget", eps=eps, phi=phi, delta=delta, tau=tau, rpe_delta=rpe_delta,
                         rpe_unit=rpe_unit)  # fmt: skip
        self.eps, self.phi, self.delta, self.tau = spec.eps, spec.phi, spec.delta, spec.tau
        self.rpe_delta, self.rpe_unit = spec.rpe_delta, spec.rpe_unit
        if isinstance(self.eps, Mapping) and groundtruth.scene not in self.eps:
            raise ValidationError(f"eps: no metres for scene {groundtruth.scene} (the ground truth's); give eps for it, "
                                  "or one number, or 'paper'")  # fmt: skip
        explorer_eps(self.eps, groundtruth.scene)  # 'paper' on a scene without a paper eps: refused now
        self.seed = check_seed(seed)
        self.duration = groundtruth.sequences[seq].duration
        d = durations_table({groundtruth.scene: groundtruth})
        self.durations = d[d["seq"] == seq]
        self.values: dict[str, Any] = dict(
            position_noise_m=0.0,
            orientation_noise_deg=0.0,
            yaw_drift_deg_per_m=0.0,
            scale=1.0,
            init_delay_s=0.0,
            lost_from_s=0.0,
            lost_for_s=0.0,
            wrong_reloc_at_s=OFF,
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
            wrong_reloc_at_s=None if v["wrong_reloc_at_s"] == OFF else v["wrong_reloc_at_s"],
            rate_hz=v["rate_hz"] or None,
            clock_offset_s=v["clock_offset_s"],
            seed=self.seed,
        )

    def results(self) -> tuple[pd.DataFrame, Figure]:
        """Metrics table and timeline for the current slider values."""
        fe = simulated_errors(self.groundtruth, self.faults(), seqs=[self.seq], name="sliders")
        table = score(fe, self.eps, self.phi, self.delta, self.tau, rpe_delta=self.rpe_delta, rpe_unit=self.rpe_unit)
        fig = plot_timeline(
            [fe],
            self.durations,
            aggregate_scenes(table, self.durations),
            self.eps,
            self.phi,
            self.delta,
            title=f"{self.faults().describe()}\neps {_eps_text(explorer_eps(self.eps, self.groundtruth.scene))}, "
            f"phi {self.phi:g} deg, delta {self.delta:g} s, tau {self.tau:g} s",
        )
        cols = ["matched", "ate_rmse", "aoe_rmse", "c_ate_rmse", "cr", "cr_t", "reloc_time", "cs_r", "rpe_trans_rmse"]
        return table[cols], fig

    def widget(self) -> Any:
        """Sliders for every fault (each starts at no fault), and their output. A wrong
        re-localization is "off" or happens at a time after the start: a jump at the very start
        would be absorbed by the alignment, so the slider starts at 5 s."""
        import ipywidgets as w

        d = self.duration
        spec = [
            ("position_noise_m", dict(min=0, max=1, step=0.01, description="noise (m)")),
            ("orientation_noise_deg", dict(min=0, max=45, step=1, description="noise (deg)")),
            ("yaw_drift_deg_per_m", dict(min=0, max=5, step=0.1, description="yaw drift (deg/m)")),
            ("scale", dict(min=0.2, max=2, step=0.05, description="scale")),
            ("init_delay_s", dict(min=0, max=d, step=1, description="init delay (s)")),
            ("lost_from_s", dict(min=0, max=d, step=1, description="lost from (s)")),
            ("lost_for_s", dict(min=0, max=d, step=1, description="lost for (s)")),
            ("rate_hz", dict(min=0, max=10, step=0.1, description="rate (Hz, 0: all)")),
            ("clock_offset_s", dict(min=-2, max=2, step=0.05, description="clock offset (s)")),
        ]
        style = {"description_width": "130px"}
        layout = w.Layout(width=SLIDER_WIDTH)
        controls = {
            k: w.FloatSlider(value=self.values[k], style=style, continuous_update=False, layout=layout, **kw)
            for k, kw in spec
        }
        times = [("off", OFF)] + [(f"{t:g}", float(t)) for t in np.arange(5.0, d, 5.0)]
        controls["wrong_reloc_at_s"] = w.SelectionSlider(
            options=times, value=OFF, description="wrong reloc at (s)", style=style, continuous_update=False,
            layout=layout,
        )  # fmt: skip
        out = w.Output()

        def update(_: Any = None) -> None:
            self.values.update({k: c.value for k, c in controls.items()})
            _render(out, self.results)

        for c in controls.values():
            c.observe(update, names="value")
        update()
        items = list(controls.values())
        return w.VBox([w.HBox([w.VBox(items[:5]), w.VBox(items[5:])]), out])
