"""``lorisnb history DIR...``: scene values of many runs over time (nightly report runs, or
per-sequence CSV/Parquet tables), where a value first changed, and which runs cannot be compared
with the run before them.

Runs are ordered by ``created`` of their run.json; runs without one (bare tables) by the file's
modification time, and the table says which (``created_from``). A run is **not comparable** with
the run before it when their specs differ (:func:`lorisnb.tools.decisions.runs.spec_differences`), when
lorisnb's version differs, or when the checksums of their ground-truth files differ (run.json's
``inputs``); its change is then not computed and a new series starts there. A value **changed**
when it moved by more than its tolerance (:mod:`lorisnb.core.stats.regression`) against the previous
comparable run; scene values count missing sequences as failed runs (:mod:`lorisnb.core.lifelong.coverage`).
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from lorisnb.core.lifelong.coverage import complete, expected_from
from lorisnb.core.stats.inference import WEIGHTS, scene_means
from lorisnb.core.stats.regression import METRICS, Tolerance, parse_tolerances
from lorisnb.errors import ValidationError
from lorisnb.tools.decisions.diff import keyed
from lorisnb.tools.decisions.runs import Run, load_run, spec_differences

COLUMNS = ["run", "path", "created", "created_from", "lorisnb_version", "comparable", "not_comparable", "suite",
           "algorithm", "scene", "metric", "value", "change", "changed", "first_change"]  # fmt: skip


def load_runs(paths: Iterable[str | os.PathLike[str]]) -> list[Run]:
    """The runs, oldest first (see the module docstring)."""
    runs = [load_run(p) for p in paths]
    if len({r.path.resolve() for r in runs}) < len(runs):
        raise ValidationError("history: a run is given twice; give each run once")
    return sorted(runs, key=lambda r: (r.created is None, r.created, r.name))


def run_labels(runs: Sequence[Run]) -> list[str]:
    """A name per run, unique: its file or folder name, or, where two runs share it (nightly
    ``2026-02-01/sequences.csv`` and ``2026-02-02/sequences.csv``), as many of the last parts of
    their paths as tell them apart (the whole path if nothing shorter does)."""
    parts = [r.path.resolve().parts for r in runs]
    labels = [r.name for r in runs]
    for depth in range(2, max((len(p) for p in parts), default=0) + 1):
        clash = {x for x in labels if labels.count(x) > 1}
        if not clash:
            break
        labels = ["/".join(p[-depth:]) if lab in clash else lab for p, lab in zip(parts, labels, strict=True)]
    return [lab if labels.count(lab) == 1 else str(r.path.resolve()) for r, lab in zip(runs, labels, strict=True)]


def comparability(prev: Run, run: Run) -> list[str]:
    """Why ``run`` cannot be compared with ``prev`` (empty: it can)."""
    reasons = spec_differences(prev, run)
    if prev.version != run.version and (prev.version or run.version):
        reasons.append(f"lorisnb_version {prev.version} -> {run.version}")
    ga, gb = prev.groundtruth_sums(), run.groundtruth_sums()
    changed = sorted(k for k in set(ga) & set(gb) if ga[k] != gb[k])
    if changed:
        reasons.append(f"ground truth changed: {', '.join(changed)}")
    return reasons


def history_table(
    runs: Sequence[Run], metrics: Sequence[str] = tuple(WEIGHTS), tolerances: Mapping[str, Tolerance] | None = None
) -> pd.DataFrame:
    """One row per run, suite, algorithm, scene and metric (see :data:`COLUMNS`)."""
    tols = parse_tolerances() if tolerances is None else dict(tolerances)
    bad = [m for m in metrics if m not in WEIGHTS]
    if bad:
        raise ValidationError(f"history metric(s) {', '.join(bad)}: expected scene metrics {', '.join(WEIGHTS)}")
    tables = [keyed(r.table, str(r.path)) for r in runs]
    expected = expected_from(*tables, *(r.expected for r in runs if r.expected is not None))  # as the leaderboard
    rows = []
    names = run_labels(runs)  # the run column: one name per run, or two runs' rows would merge
    seen_series: dict[tuple, int] = {}  # (suite, algorithm, scene, metric) -> the first run that has it
    for k, (run, table) in enumerate(zip(runs, tables, strict=True)):
        reasons = comparability(runs[k - 1], run) if k else []
        meta = dict(run=names[k], path=str(run.path), created=run.created.isoformat() if run.created else "",
                    created_from=run.created_from, lorisnb_version=run.version or "", comparable=not reasons,
                    not_comparable="; ".join(reasons))  # fmt: skip
        full, _ = complete(table, expected)
        here = set()
        for m in metrics:
            for r in scene_means(full, m).itertuples():
                key = (r.suite, r.algorithm, r.scene, m)
                here.add(key)
                seen_series.setdefault(key, k)
                rows.append(dict(meta, suite=r.suite, algorithm=r.algorithm, scene=r.scene, metric=m, value=r.value))
        for key in (key for key in seen_series if key not in here):  # a scene the run lost: no value, a change
            rows.append(dict(meta, suite=key[0], algorithm=key[1], scene=key[2], metric=key[3], value=np.nan))
    out = pd.DataFrame(rows, columns=COLUMNS[:12])
    out["change"], out["changed"], out["first_change"] = np.nan, False, False
    for (_, _, _, m), g in out.groupby(["suite", "algorithm", "scene", "metric"], sort=False):
        prev = np.nan
        seen = False
        for i in g.index:
            v = out.at[i, "value"]
            if not out.at[i, "comparable"]:
                prev = v  # a new series starts here
                continue
            gone = np.isfinite(prev) and not np.isfinite(v)  # no value now (a lost scene, no correct pose): worse,
            if np.isfinite(prev) and np.isfinite(v):  # as diff counts a value defined in BASE, undefined in CAND
                change = v - prev
                out.at[i, "change"] = change
            if gone or (
                np.isfinite(prev) and np.isfinite(v) and abs(v - prev) > tols[m].of(prev) + 1e-12 * max(1.0, abs(prev))
            ):
                out.at[i, "changed"] = True
                out.at[i, "first_change"] = not seen
                seen = True
            prev = v
    return out


def first_changes(history: pd.DataFrame) -> list[str]:
    """One line per series with the first run where it changed."""
    lines = []
    first = history[history["first_change"].astype(bool)]
    for r in first.itertuples():
        i = history.index.get_loc(r.Index)
        before = history.iloc[:i]
        before = before[(before["suite"] == r.suite) & (before["algorithm"] == r.algorithm)
                        & (before["scene"] == r.scene) & (before["metric"] == r.metric)]  # fmt: skip
        was = before["value"].iloc[-1] if len(before) else np.nan
        sign = "better" if np.isfinite(r.value) and (r.change > 0) == (METRICS[r.metric] > 0) else "worse"
        now = f"{r.value:.4f}" if np.isfinite(r.value) else "no value"
        lines.append(f"{r.algorithm}{f' ({r.suite})' if r.suite else ''} {r.scene} {r.metric}: first change in "
                     f"{r.run} ({was:.4f} -> {now}, {sign})")  # fmt: skip
    return lines


def plot_history(history: pd.DataFrame, metric: str):
    """One panel per scene, one line per algorithm over the runs; runs not comparable with the one
    before are marked with a dashed line, changes with a ring."""
    from lorisnb.tools.figures.plotting import MAX_WIDTH_IN, subplots

    h = history[history["metric"] == metric]
    scenes = list(dict.fromkeys(h["scene"]))
    runs = list(dict.fromkeys(h["run"]))
    x = {r: i for i, r in enumerate(runs)}
    fig, axes = subplots(1, max(len(scenes), 1), figsize=(min(MAX_WIDTH_IN, 3.2 * max(len(scenes), 1)), 3.2),
                         squeeze=False, sharey=True)  # fmt: skip
    for ax, scene in zip(axes[0], scenes, strict=False):
        s = h[h["scene"] == scene]
        for (suite, alg), g in s.groupby(["suite", "algorithm"], sort=False):
            xs = g["run"].map(x).to_numpy()
            line = ax.plot(
                xs, g["value"].to_numpy(float), marker="o", ms=3, label=f"{alg}{f' ({suite})' if suite else ''}"
            )
            ch = g[g["changed"].astype(bool)]
            ax.plot(ch["run"].map(x), ch["value"], "o", mfc="none", ms=9, color=line[0].get_color())
        for r in s.loc[~s["comparable"], "run"].unique():
            ax.axvline(x[r] - 0.5, color="0.4", ls="--", lw=1)
        ax.set_title(scene)
        ax.set_xticks(range(len(runs)), runs, rotation=45, ha="right", fontsize=7)
    axes[0][0].set_ylabel(metric)
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.suptitle(f"{metric} over runs (ring: changed beyond tolerance; dashed: not comparable with the run before)",
                 fontsize=8)  # fmt: skip
    fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 3) or 1, fontsize=7, frameon=False)
    fig.tight_layout(rect=(0, 0.08 + 0.05 * ((len(labels) - 1) // 3), 1, 1))
    return fig


def write_figures(history: pd.DataFrame, out_dir: str | os.PathLike[str]) -> list[Path]:
    """``history_<metric>.png`` and ``.svg`` for every metric of the table."""
    from lorisnb.tools.figures.plotting import save_figure

    paths = []
    for m in dict.fromkeys(history["metric"]):
        paths += save_figure(plot_history(history, m), Path(out_dir), f"history_{m}", formats=("png", "svg"))
    return paths
