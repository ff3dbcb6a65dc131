"""Figures (matplotlib/seaborn): the paper's timeline (Fig. 2 / Fig. 3), trajectories coloured by
correctness, and helpers to save figures. Every function returns the Figure; none calls show().

Every name a figure draws (an algorithm, scene, suite, file or dataset, in a title, a label, a legend
or a tick label) is shown as the terminal shows it (:func:`~lorisnb.tools.decisions.escape.clean`:
``orb\\x1b`` for ``orb`` + ESC, ``\\\\`` for a backslash): a control character is drawn by no font
and an SVG (XML 1.0) cannot hold it. The figure functions escape the names they draw
(:func:`shown_names` for the columns seaborn draws from); the tables they are given and return keep
the names whole. Whatever text is still not printable when a figure is rendered (a title the caller
gave) is escaped then (:func:`escape_unprintable`, by :func:`save_figure` and the notebooks'
:func:`~lorisnb.tools.notebook.start.figure_png`).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from functools import partial
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import numpy as np
import pandas as pd
import seaborn as sns
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Rectangle
from matplotlib.text import Text

from lorisnb.core.lifelong.timeline import sequence_layout, timeline_rows, timeline_table
from lorisnb.core.metrics.openloris import correctness
from lorisnb.core.pipeline.model import FileErrors, sequence_eps
from lorisnb.core.spec.validate import eps_value, threshold
from lorisnb.errors import ValidationError
from lorisnb.io.writers import write_atomically
from lorisnb.tools.decisions.escape import clean
from lorisnb.tools.figures.blit import BlitCanvas

#: Widest figure, inches (about 1,200 px in a notebook): wider ones would be shrunk to unreadable text.
MAX_WIDTH_IN = 12.0


def subplots(nrows: int = 1, ncols: int = 1, **kw: Any) -> tuple[Figure, Any]:
    """Like ``plt.subplots``, but the figure is not registered with pyplot: no backend redraws or
    shows it behind the caller's back (a widget's figure stays the widget's, and a notebook shows
    each figure once, where :meth:`lorisnb.tools.notebook.start.Outputs.figure` displays it)."""
    figsize = kw.pop("figsize", None)
    fig = _MeasuredFigure(figsize=figsize)
    return fig, fig.subplots(nrows, ncols, **kw)


class _MeasuredFigure(Figure):
    """A figure outside pyplot that measures its texts with one renderer. A figure without a
    backend's canvas makes a new Agg renderer (a whole figure's pixel buffer, cleared) for every
    text it measures, and the text-size cache, keyed by renderer, never hits: seaborn's heatmaps
    check their tick labels for overlap, several hundred texts per figure. Kept here instead, one
    per size and resolution: the same Agg measurements, the same figure, about a fifth less time
    for a grid of heatmaps. Drawing still goes through the canvas of the format saved; a canvas
    with a renderer of its own (a backend's) is used as matplotlib would use it."""

    _measuring: tuple[tuple[int, int, float], Any] | None = None

    def _get_renderer(self) -> Any:
        if hasattr(self.canvas, "get_renderer"):
            return self.canvas.get_renderer()
        from matplotlib.backends.backend_agg import RendererAgg

        w, h = self.canvas.get_width_height(physical=True)
        key = (w, h, float(self.dpi))
        if self._measuring is None or self._measuring[0] != key:
            self._measuring = (key, RendererAgg(w, h, self.dpi))
        return self._measuring[1]


def _theme(style: str) -> None:
    """seaborn's paper theme, with titles at the top of their axes (``axes.titley`` 1.0): where
    nothing is drawn above an axes (none of these figures has tick labels on top) that is where
    matplotlib would place them, but finding it out measures every tick label of every axes at
    each draw, a fifth of the time of a figure of many panels."""
    sns.set_theme(style=style, context="paper", rc={"axes.titley": 1.0})


@contextmanager
def same_jitter(seed: int = 0) -> Iterator[None]:
    """Within the block, seaborn's strip plots jitter their points the same way at every run
    (they draw from numpy's global generator, which is seeded here and restored afterwards: the
    caller's random numbers are not touched), so that a report's figures are the same each night."""
    state = np.random.get_state()
    np.random.seed(seed)
    try:
        yield
    finally:
        np.random.set_state(state)


CORRECT = "#1f5fbf"
WRONG = "#d62728"


def shown_names(table: pd.DataFrame, columns: Iterable[str | None]) -> pd.DataFrame:
    """A copy of ``table`` whose ``columns`` (the ones a figure draws as names: a hue, a panel, a tick
    label; None and absent ones passed over) hold each text as the terminal shows it
    (:func:`~lorisnb.tools.decisions.escape.clean`, one-to-one: two names stay two), for seaborn to
    draw from; the caller's table is not changed."""
    cols = [c for c in dict.fromkeys(columns) if c is not None and c in table.columns]
    if not cols:
        return table
    return table.assign(**{c: table[c].map(lambda v: clean(v) if isinstance(v, str) else v) for c in cols})


def escape_unprintable(fig: Figure) -> None:
    """Every text of ``fig`` that holds a character that is not printable (a control character, a
    bidirectional override) shown escaped (:func:`~lorisnb.tools.decisions.escape.clean`), line by
    line (a title's own line breaks kept): drawn by no font, and an SVG (XML 1.0) cannot hold it. A
    text already printable is left as it is (the names the figure functions drew are escaped once,
    where they drew them)."""
    for t in fig.findobj(Text):
        shown = printable(t.get_text())
        if shown != t.get_text():
            t.set_text(shown)


def printable(text: str) -> str:
    """A caller's text (a title), as :func:`escape_unprintable` draws it: as it is where every
    character is printable, else line by line as the terminal shows it (its own line breaks kept)."""
    return text if text.replace("\n", "").isprintable() else "\n".join(map(clean, text.split("\n")))


def _pct(v: float) -> str:
    return "n/a" if v is None or not np.isfinite(v) else f"{100 * v:.1f}%"


#: The timeline's axis label: it also says what the numbers beside each scene's rows are.
TIMELINE_XLABEL = (
    "time (each sequence to scale; black dots mark sequence starts)\n"
    "per scene: CR top left, C-ATE RMSE (m, correct poses only) bottom right"
)


def plot_timeline(
    errors: Sequence[FileErrors],
    durations: pd.DataFrame,
    scene_table: pd.DataFrame,
    eps: float | str | Mapping[str, float] = np.inf,
    phi: float = np.inf,
    delta: float = 1.0,
    algorithms: Sequence[str] | None = None,
    labels: Mapping[str, str] | None = None,
    show_wrong: bool = True,
    title: str | None = None,
):
    """The paper's timeline figure.

    One row per algorithm, the scenes' sequences side by side on a shared time axis (each as long
    as its ground truth; black dots mark sequence starts). Correct tracking is drawn as blue
    segments, incorrect estimates as red ones (``show_wrong``, Fig. 3); the first pose of each
    sequence is a blue dot if correct (initialization / correct re-localization) or a red cross.
    Per scene, the CR is printed at the top left of each row and the C-ATE RMSE (metres) at the
    bottom right, from ``scene_table`` (:func:`lorisnb.core.lifelong.aggregate.aggregate_scenes`; with
    several trials of an algorithm, its ``suite`` and ``trial`` columns tell their rows apart).
    Several suites or trials of an algorithm are a row each (:func:`~lorisnb.core.lifelong.timeline.timeline_rows`).
    A figure to redraw at other thresholds: :class:`Timeline`.
    """
    errors = _file_list("plot_timeline", errors)
    return Timeline(errors, durations, algorithms, labels, show_wrong).draw(scene_table, eps, phi, delta, title)


def _file_list(where: str, errors: Any) -> list[FileErrors]:
    """``errors`` as a list of FileErrors (an Evaluation's ``errors``), else a ValidationError."""
    if isinstance(errors, FileErrors):
        raise ValidationError(
            f"{where}: errors is one FileErrors; expected a list of them (Evaluation.errors, or [errors] for one file)"
        )
    if isinstance(errors, (str, bytes, Mapping)) or not isinstance(errors, Iterable):
        raise ValidationError(f"{where}: errors is a {type(errors).__name__}; expected a list of FileErrors "
                              "(Evaluation.errors)")  # fmt: skip
    out = list(errors)
    bad = [type(f).__name__ for f in out if not isinstance(f, FileErrors)]
    if bad:
        raise ValidationError(f"{where}: errors holds a {bad[0]}; expected FileErrors (Evaluation.errors)")
    return out


def _same_thresholds(
    scene_table: Any, errors: Sequence[FileErrors], algorithms: Iterable[str], eps: Any, phi: Any, delta: Any
) -> None:
    """A scene table at other thresholds than a timeline's (its ``eps``, ``phi`` and ``delta``
    columns) is refused: its CR and C-ATE texts would be printed beside segments drawn at others."""
    if not isinstance(scene_table, pd.DataFrame) or not {"algorithm", "scene"} <= set(scene_table.columns):
        raise ValidationError(
            f"plot_timeline scene_table: got {type(scene_table).__name__}; expected the scene table at the same "
            "thresholds (Evaluation.scenes(eps=..., phi=..., delta=...) or aggregate_scenes)"
        )
    eps_v, phi_v, delta_v = eps_value(eps), threshold("phi", phi), threshold("delta", delta)
    wanted = set(algorithms)
    rows = scene_table[scene_table["algorithm"].isin(wanted)]
    told = f"eps={eps!r}, phi={phi!r}, delta={delta!r}"
    for name, value in (("phi", phi_v), ("delta", delta_v)):
        if name in rows.columns:
            other = sorted({float(v) for v in rows[name]} - {float(value)})
            if other:
                raise ValidationError(
                    f"plot_timeline: the scene table is at {name}={other[0]:g}, the figure at {told}; pass the scene "
                    f"table at the figure's thresholds (Evaluation.scenes({told}))"
                )
    if "eps" not in rows.columns:
        return
    expected: dict[tuple[str, str], set[float]] = {}
    for f in errors:
        for e in f.sequences:
            expected.setdefault((f.algorithm, f.scene), set()).add(float(sequence_eps(eps_v, f.scene, e)))
    for a, sc, got in zip(rows["algorithm"], rows["scene"], rows["eps"].astype(float), strict=True):
        want = expected.get((a, sc))
        if want is None or len(want) != 1 or np.isnan(got):  # sequences of several eps (relative): NaN in the table
            continue
        (w,) = want
        if not (got == w or np.isclose(got, w, rtol=1e-12, atol=0.0)):
            raise ValidationError(
                f"plot_timeline: the scene table is at eps={got:g} m for {a} {sc}, the figure at {told} ({w:g} m); "
                f"pass the scene table at the figure's thresholds (Evaluation.scenes({told}))"
            )


class Timeline:
    """:func:`plot_timeline`'s figure, kept to be redrawn at other thresholds: the axes, the scenes'
    spans, the rows and the legend are made once (:meth:`__init__`); :meth:`draw` replaces only
    what the thresholds change (the segments, the first poses, the CR and C-ATE texts, the title)
    in the same figure. The figure drawn equals :func:`plot_timeline`'s at the same thresholds,
    pixel for pixel (a test compares their PNGs). A threshold explorer's slider change on icra20's
    market scene (benchmarks/workload.py's slider row): the figure made anew took 0.21 s of CPU,
    while re-scoring, re-aggregating and redrawing it in place take 0.08 s in all. Its PNG
    (:func:`~lorisnb.tools.notebook.start.figure_png`) is blitted by its canvas
    (:class:`~lorisnb.tools.figures.blit.BlitCanvas`): the axes, row names and legend (drawn before
    the axes: the same pixels, a test checks) are drawn once and kept, and only the artists from the
    first one the thresholds change onwards are drawn again, the same image as a full savefig pixel
    for pixel. Measured with the slider row, old and new in alternation, 2 cores under load 4-5:
    the PNG took 0.34-0.35 s of CPU, now 0.12-0.17 s (most of it the ~30 CR and C-ATE texts and
    the title drawn, and the tight bounding box measured)."""

    def __init__(
        self,
        errors: Sequence[FileErrors],
        durations: pd.DataFrame,
        algorithms: Sequence[str] | None = None,
        labels: Mapping[str, str] | None = None,
        show_wrong: bool = True,
    ):
        self.errors = list(errors)
        self.layout = layout = sequence_layout(durations)
        self.algorithms = sorted({f.algorithm for f in self.errors}) if algorithms is None else algorithms
        labels = dict(labels or {})
        rows = timeline_rows(self.errors, self.algorithms)
        n = len(rows)
        width = max(8.0, 0.006 * (layout["offset"].iloc[-1] + layout["duration"].iloc[-1]) + 3) if len(layout) else 8
        _theme("white")
        self.figure, ax = subplots(figsize=(min(width, MAX_WIDTH_IN), 0.55 * n + 1.7))
        self.ax = ax
        self.show_wrong = show_wrong
        self.off = {(r.scene, r.seq): r.offset for r in layout.itertuples()}
        self.y_of = {key: n - i for i, key in enumerate(rows)}
        top = n + 0.8
        for scene, d in layout.groupby("scene", sort=False):
            x0, x1 = d["offset"].min(), (d["offset"] + d["duration"]).max()
            ax.plot([x0, x1], [top, top], "-k", lw=1)
            ax.plot(d["offset"], np.full(len(d), top), "ok", ms=3)
            ax.text((x0 + x1) / 2, top + 0.25, clean(scene), ha="center", va="bottom", fontsize=9)
            ax.axvline(x0, color="0.7", lw=0.6)
            ax.axvline(x1, color="0.7", lw=0.6)
        self._drawn: list[Any] = []  # the artists that the thresholds change
        BlitCanvas(self.figure, self._changing)  # its PNG redrawn from the first of them on (figure_png)
        self._laid_out: tuple[bool, int] | None = None  # the title tight_layout measured
        self.rows, self.labels = rows, labels

    def _changing(self) -> list[Any]:
        """The artists that :meth:`draw` changes: the segments, first poses, CR and C-ATE texts, title."""
        return [*self._drawn, self.ax.title]

    def _row_y(self, d: pd.DataFrame) -> np.ndarray:  # each segment's or first pose's row (NaN: not shown)
        keys = zip(d["algorithm"], d["suite"], d["trial"], strict=True)
        return np.array([self.y_of.get(k, np.nan) for k in keys], float)

    def draw(
        self,
        scene_table: pd.DataFrame,
        eps: float | str | Mapping[str, float] = np.inf,
        phi: float = np.inf,
        delta: float = 1.0,
        title: str | None = None,
    ) -> Figure:
        """The figure at these thresholds (``scene_table`` at the same ones: a table at others is a
        ValidationError, its CR and C-ATE texts would not be the segments'), drawn in place."""
        _same_thresholds(scene_table, self.errors, self.algorithms, eps, phi, delta)
        segments, firsts = timeline_table(self.errors, eps, phi, delta)
        ax, off, y_of, layout, row_y = self.ax, self.off, self.y_of, self.layout, self._row_y
        for artist in self._drawn:
            artist.remove()
        drawn = []
        for correct_flag, color in ((True, CORRECT), (False, WRONG)):
            if not self.show_wrong and not correct_flag:
                continue
            s = segments[segments["correct"] == correct_flag]
            s = s[
                np.array([(sc, q) in off for sc, q in zip(s["scene"], s["seq"], strict=True)], bool)
                & ~np.isnan(row_y(s))
            ]  # a mask, also when empty
            if s.empty:
                continue
            base = np.array([off[(sc, q)] for sc, q in zip(s["scene"], s["seq"], strict=True)])
            y = row_y(s)
            lines = np.stack([np.stack([base + s["start"], y], 1), np.stack([base + s["end"], y], 1)], 1)
            drawn.append(ax.add_collection(LineCollection(list(lines), colors=color, linewidths=2.2)))
        f = firsts[~np.isnan(row_y(firsts))]
        f = f[np.array([(sc, q) in off for sc, q in zip(f["scene"], f["seq"], strict=True)], bool)]
        if len(f):
            x = np.array([off[(sc, q)] for sc, q in zip(f["scene"], f["seq"], strict=True)]) + f["t"].to_numpy()
            y = row_y(f)
            ok = f["correct"].to_numpy(bool)
            drawn += ax.plot(x[ok], y[ok], "o", color=CORRECT, ms=4)
            drawn += ax.plot(x[~ok], y[~ok], "x", color=WRONG, ms=6, mew=1.5)
        told_at = {"suite": 0, "trial": 1}
        told = [k for k in told_at if k in scene_table.columns]  # what tells a row's runs apart
        for r in scene_table[scene_table["algorithm"].isin(self.algorithms)].to_dict("records"):
            d = layout[layout["scene"] == r["scene"]]
            at = [
                y for (a, *run), y in y_of.items() if a == r["algorithm"] and all(r[k] == run[told_at[k]] for k in told)
            ]
            if d.empty or len(at) != 1:  # a table over all trials of a run drawn a row each: no row is its
                continue
            x0, x1 = d["offset"].min(), (d["offset"] + d["duration"]).max()
            drawn.append(ax.text(x0 + 2, at[0] + 0.12, _pct(r["cr"]), fontsize=7, ha="left", va="bottom"))
            rmse = r["c_ate_rmse"]
            drawn.append(ax.text(x1 - 2, at[0] - 0.42, "N/A" if not np.isfinite(rmse) else f"{rmse:.3f} m", fontsize=7,
                                 ha="right", va="bottom"))  # fmt: skip
        self._drawn = drawn
        if self._laid_out is None:
            self._finish()
        if title or self._laid_out is not None:
            ax.set_title(printable(title or ""), fontsize=10, pad=18)
        # the title's height (its lines) is what moves the layout: a title narrower than the axes
        # and their row names (as these figures' are) leaves it where it was
        laid_out = (bool(title), (title or "").count("\n"))
        if laid_out != self._laid_out:
            self.figure.tight_layout(rect=(0, 0.3 / self.figure.get_figheight(), 1, 1))
            self._laid_out = laid_out
        return self.figure

    def _finish(self) -> None:
        """The axis, its row names and the legend: after the first thresholds' artists, as
        :func:`plot_timeline` always made them."""
        ax, layout, rows, labels = self.ax, self.layout, self.rows, self.labels
        names = [clean(labels.get(a, a) + name[len(a) :]) for (a, _, _), name in rows.items()]  # suite, trial too
        ax.set_yticks(list(self.y_of.values()), names)
        ax.set_ylim(0.4, len(rows) + 1.5)
        if len(layout):
            ax.set_xlim(layout["offset"].min() - 5, (layout["offset"] + layout["duration"]).max() + 5)
        ax.set_xticks([])
        ax.set_xlabel(TIMELINE_XLABEL)
        sns.despine(ax=ax, left=True, bottom=True)
        handles = [
            Line2D([], [], color=CORRECT, lw=2.2, label="correct pose estimates"),
            Line2D([], [], color=CORRECT, marker="o", ls="", label="correct (re-)localization"),
        ]
        if self.show_wrong:
            handles += [
                Line2D([], [], color=WRONG, lw=2.2, label="incorrect pose estimates"),
                Line2D([], [], color=WRONG, marker="x", ls="", label="incorrect (re-)localization"),
            ]
        # the legend gets its own strip under the axis label, so the two never overlap
        legend = self.figure.legend(handles=handles, loc="lower center", bbox_to_anchor=(0.5, 0.0),
                                    ncol=len(handles), frameon=False, fontsize=8)  # fmt: skip
        # drawn before the axes, not after: in a strip of its own, nothing drawn later covers it (the
        # same pixels, a test checks), and a redraw (BlitCanvas) keeps it with the axis and row names
        legend.set_zorder(-1)


def plot_trajectories(
    errors: FileErrors, eps: float | str | Mapping[str, float] = np.inf, phi: float = np.inf, max_cols: int = 3
):
    """Top view (x-y, metres) of each sequence: interpolated ground truth in grey, the aligned
    estimate as points coloured by correctness (blue correct, red wrong)."""
    if not isinstance(errors, FileErrors):
        many = not isinstance(errors, (str, bytes)) and isinstance(errors, Iterable)
        raise ValidationError(
            f"plot_trajectories: errors is a {type(errors).__name__}; expected one file's FileErrors"
            + (" (one figure per file: plot_trajectories(ev.errors[0]), ...)" if many else " (Evaluation.errors[i])")
        )
    eps, phi = eps_value(eps), threshold("phi", phi)  # validated as score's
    seqs = [e for e in errors.sequences if e.matched]
    n = max(1, len(seqs))
    cols = min(max_cols, n)
    rows = int(np.ceil(n / cols))
    _theme("whitegrid")
    fig, axes = subplots(rows, cols, figsize=(3.9 * cols, 3.8 * rows), squeeze=False)
    for ax, e in zip(axes.flat, seqs, strict=False):
        c = correctness(e.ate, e.aoe, sequence_eps(eps, errors.scene, e), phi)
        ax.plot(e.gt_positions[:, 0], e.gt_positions[:, 1], "-", color="0.6", lw=1.2, label="ground truth")
        ax.scatter(e.est_positions[c, 0], e.est_positions[c, 1], s=3, color=CORRECT, label="estimate, correct")
        ax.scatter(e.est_positions[~c, 0], e.est_positions[~c, 1], s=3, color=WRONG, label="estimate, wrong")
        ax.set_title(f"{clean(errors.scene)}-{e.seq}: {c.mean():.0%} of {e.matched} poses correct", fontsize=9)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_aspect("equal", adjustable="datalim")
    for ax in list(axes.flat)[len(seqs) :]:
        ax.axis("off")
    if seqs:
        axes.flat[0].legend(fontsize=7, loc="best", markerscale=3)
    fig.suptitle(f"{clean(errors.algorithm)}: {clean(errors.file)} ({errors.mode}, top view)", fontsize=10)
    fig.tight_layout()
    return fig


def _save(fig: Figure, tmp: Path, fmt: str) -> None:
    escape_unprintable(fig)
    fig.savefig(tmp, dpi=150, bbox_inches="tight", format=fmt)


def save_figure(fig, out_dir: str | Path, name: str, formats: Iterable[str] = ("png", "svg", "pdf")) -> list[Path]:
    """Write a figure as ``name.png``, ``name.svg`` and ``name.pdf`` in ``out_dir`` (each replaced
    whole, :func:`~lorisnb.io.writers.write_atomically`: a failed write, a full disk, names its
    file and leaves no part of it); returns the paths."""
    out_dir = Path(out_dir)
    made = not out_dir.exists()
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    try:
        for fmt in formats:
            p = out_dir / f"{name}.{fmt}"
            write_atomically(p, partial(_save, fig, fmt=fmt), force=True)
            paths.append(p)
    except BaseException:
        if made and not any(out_dir.iterdir()):  # the folder made for them, left empty: not left behind
            out_dir.rmdir()
        raise
    return paths


# --- threshold sensitivity -------------------------------------------------------------------


def _mark(ax, x, label: str | None = None, axis: str = "x") -> None:
    line = ax.axvline if axis == "x" else ax.axhline
    line(x, color="0.25", ls="--", lw=1)
    if label:
        ax.annotate(
            label,
            xy=(x, 1.0),
            xycoords=("data", "axes fraction"),
            xytext=(3, -12),
            textcoords="offset points",
            fontsize=7,
            color="0.25",
        )


def plot_metric_vs_threshold(
    scenes: pd.DataFrame,
    x: str,
    y: str = "cr",
    marks: Mapping[str, float] | float | None = None,
    log: bool = True,
    hue: str = "algorithm",
    col: str = "scene",
    xlabel: str | None = None,
    ylabel: str | None = None,
    col_wrap: int = 4,
):
    """Lines of a scene metric (``cr``, ``cr_t``, ``cs_r``, ...) against one threshold, one
    panel per scene, one line per algorithm; ``marks`` draws the paper's value (a number, or one
    per scene) as a dashed line. ``scenes`` is a scene aggregate of a sweep."""
    _theme("whitegrid")
    data = scenes.replace([np.inf], np.nan).dropna(subset=[x]) if log else scenes
    data = shown_names(data, [hue, col])  # the legend's and the panels' names, as the terminal shows them
    if isinstance(marks, Mapping):  # by panel, as the panels are named
        marks = {clean(k) if isinstance(k, str) else k: v for k, v in marks.items()}
    g = sns.relplot(
        data=data,
        x=x,
        y=y,
        hue=hue,
        col=col,
        kind="line",
        marker="o",
        markersize=3,
        col_wrap=min(col_wrap, data[col].nunique()) if col else None,
        height=2.8,
        aspect=1.15,
        facet_kws={"sharey": True, "sharex": True},
        seed=0,  # the interval band of several rows per point (trials): the same at every run
    )
    for key, ax in g.axes_dict.items():
        if log:
            ax.set_xscale("log")
        m = marks.get(key) if isinstance(marks, Mapping) else marks
        if m is not None and np.isfinite(m):
            _mark(ax, m, "paper")
    g.set_axis_labels(xlabel or x, ylabel or y)
    g.set_titles("{col_name}")
    return g.figure


def plot_cr_heatmaps(
    scenes: pd.DataFrame, scene: str, mark: tuple[float, float] | None = None, metric: str = "cr", max_cols: int = 3
):
    """Heatmaps of a scene metric over (eps, phi), one per algorithm, for one scene; ``mark``
    outlines the cell of the paper's (eps, phi)."""
    d = scenes[(scenes["scene"] == scene) & np.isfinite(scenes["eps"]) & np.isfinite(scenes["phi"])]
    algs = sorted(d["algorithm"].unique())
    cols = min(max_cols, max(1, len(algs)))
    rows = int(np.ceil(len(algs) / cols)) or 1
    _theme("white")
    fig, axes = subplots(rows, cols, figsize=(3.9 * cols, 3.3 * rows), squeeze=False)  # 3 columns fit 12 in
    for ax, alg in zip(axes.flat, algs, strict=False):
        wide = (
            d[d["algorithm"] == alg].pivot_table(index="phi", columns="eps", values=metric).sort_index(ascending=False)
        )
        sns.heatmap(
            wide,
            ax=ax,
            vmin=0,
            vmax=1,
            cmap="viridis",
            cbar=ax is axes.flat[cols - 1],
            xticklabels=[f"{v:.2g}" for v in wide.columns],
            yticklabels=[f"{v:.0f}" for v in wide.index],
        )
        ax.set_title(clean(alg), fontsize=9)
        ax.set_xlabel("eps (m)")
        ax.set_ylabel("phi (deg)")
        if mark is not None:
            ci = int(np.argmin(np.abs(np.asarray(wide.columns, float) - mark[0])))
            ri = int(np.argmin(np.abs(np.asarray(wide.index, float) - mark[1])))
            ax.add_patch(Rectangle((ci, ri), 1, 1, fill=False, edgecolor="red", lw=2))
    for ax in list(axes.flat)[len(algs) :]:
        ax.axis("off")
    fig.suptitle(
        f"{clean(scene)}: {metric.upper()} over ATE threshold eps and AOE threshold phi (red box: the paper's setting)",
        fontsize=10,
    )
    fig.tight_layout()
    return fig


def plot_rank_stability(stability: pd.DataFrame):
    """Kendall's tau between the ranking at each eps and at the reference (paper) eps, per scene."""
    _theme("whitegrid")
    fig, ax = subplots(figsize=(6.5, 3.6))
    d = shown_names(stability[np.isfinite(stability["eps"].astype(float))], ["scene"])
    if d.empty:  # one algorithm per scene: no ranking to compare
        ax.text(0.5, 0.5, "a ranking needs two or more algorithms in a scene", ha="center", va="center")
        ax.set_axis_off()
        return fig
    sns.lineplot(data=d, x="eps", y="kendall_tau", hue="scene", marker="o", ax=ax, seed=0)
    for scene, ref in d.groupby("scene")["reference_eps"].first().items():
        ax.axvline(ref, color=sns.color_palette()[list(d["scene"].unique()).index(scene) % 10], ls="--", lw=0.8)
    ax.set_xscale("log")
    ax.set_ylim(-1.05, 1.05)
    ax.set_xlabel("eps (m)")
    ax.set_ylabel("Kendall tau vs ranking at the paper's eps")
    ax.set_title("How stable is the ranking of algorithms by CR? (dashed: paper's eps)", fontsize=10)
    fig.tight_layout()
    return fig


def plot_crosscheck_scatter(per_pose: Mapping[str, pd.DataFrame]):
    """lorisnb ATE against evo APE (and AOE against evo's rotation angle), per pose, one column
    per dataset: points lie on the diagonal where the association coincides."""
    n = len(per_pose)
    _theme("whitegrid")
    fig, axes = subplots(2, n, figsize=(min(3.6 * n, MAX_WIDTH_IN), 6.6), squeeze=False)
    for k, (name, df) in enumerate(per_pose.items()):
        for r, (ours, theirs, unit) in enumerate((("ate_lorisnb", "ate_evo", "m"), ("aoe_lorisnb", "aoe_evo", "deg"))):
            ax = axes[r, k]
            ax.scatter(df[theirs], df[ours], s=4, alpha=0.5)
            hi = float(max(df[theirs].max(), df[ours].max())) if len(df) else 1.0
            ax.plot([0, hi], [0, hi], "--", color="0.3", lw=1)
            ax.set_xlabel(f"evo APE ({unit})")
            ax.set_ylabel(f"lorisnb {'ATE' if r == 0 else 'AOE'} ({unit})")
            diff = np.max(np.abs(df[ours] - df[theirs])) if len(df) else np.nan
            ax.set_title(f"{clean(name)}\nmax |difference| {diff:.1e} {unit}", fontsize=9)
    fig.tight_layout()
    return fig


def plot_normalized_accuracy(measures: pd.DataFrame, published: pd.DataFrame):
    """ATE RMSE as % of the distance travelled: computed sequences as points (one row per
    dataset, coloured by scene or sequence), published values as black diamonds on their own rows."""
    _theme("whitegrid")
    fig, ax = subplots(figsize=(8, 3.8))
    pts = shown_names(measures.dropna(subset=["ate_pct_length"]), ["dataset", "group"])
    with same_jitter():
        sns.stripplot(data=pts, y="dataset", x="ate_pct_length", hue="group", dodge=False, alpha=0.6, ax=ax, size=4)
    rows = [f"{clean(d)} (published)" for d in published["dataset"]]
    ax.scatter(published["ate_pct_length"], rows, marker="D", color="black", label="published values")
    ax.set_xscale("log")
    ax.set_xlabel("ATE RMSE, % of the distance travelled (log scale)")
    ax.set_ylabel("")
    ax.legend(fontsize=7, bbox_to_anchor=(1.01, 1), loc="upper left")
    ax.set_title("Accuracy normalized by path length: computed sequences and published values", fontsize=10)
    fig.tight_layout()
    return fig
