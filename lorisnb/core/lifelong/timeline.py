"""Timeline data of the paper's Fig. 2 and Fig. 3: when each algorithm tracked correctly, when it
was wrong, and where it (re-)localized. Pure functions returning arrays and DataFrames; the
drawing is in :mod:`lorisnb.tools.figures.plotting`.

A pose at t_k stands for ``[t_k, min(t_{k+1}, t_k + delta)]`` (its validity window, Eq. 2);
consecutive windows that touch and agree in correctness merge into one segment.
"""

from __future__ import annotations

from typing import Iterable, Mapping

import numpy as np
import pandas as pd

from lorisnb.core.metrics import openloris as metrics
from lorisnb.core.pipeline.model import FileErrors, sequence_eps
from lorisnb.core.spec.validate import eps_value, threshold
from lorisnb.core.trajectory.frames import SCENES


def pose_segments(
    stamps: np.ndarray, correct: np.ndarray, t_end: float, delta: float, t_start: float = -np.inf
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Merged segments (start, end, correct) of one sequence inside the ground truth's span
    ``[t_start, t_end]``, seconds. Vectorized."""
    stamps = np.clip(np.asarray(stamps, float), t_start, t_end)
    if stamps.size == 0:
        return np.zeros(0), np.zeros(0), np.zeros(0, bool)
    dt = metrics.valid_intervals(stamps, t_end)
    end = stamps + np.minimum(dt, delta)
    nxt = np.append(stamps[1:], np.inf)
    correct = np.asarray(correct, bool)
    # a run continues from k to k+1 when the window of k reaches t_{k+1} and correctness agrees
    cont = (end[:-1] >= nxt[:-1]) & (correct[:-1] == correct[1:])
    starts = np.flatnonzero(np.concatenate(([True], ~cont)))
    ends = np.concatenate((starts[1:] - 1, [stamps.size - 1]))
    keep = end[ends] > stamps[starts]
    return stamps[starts][keep], end[ends][keep], correct[starts][keep]


def timeline_table(
    errors: Iterable[FileErrors],
    eps: float | str | Mapping[str, float] = np.inf,
    phi: float = np.inf,
    delta: float = 1.0,
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Segments and first poses of every sequence.

    Returns:
        segments: algorithm, suite, trial, scene, seq, start, end (seconds from the sequence's
            ground-truth start), correct.
        firsts: algorithm, suite, trial, scene, seq, t (first matched pose, seconds from the
            start), correct (a dot in the figure if correct, a cross if not).
    """
    eps_v, phi_v, delta_v = eps_value(eps), threshold("phi", phi), threshold("delta", delta)  # as score's
    labels: list[tuple[str, str, int, str, int]] = []  # each sequence's, then repeated per segment
    counts, starts, ends, oks, firsts = [], [], [], [], []
    for f in errors:
        for e in f.sequences:
            if e.matched == 0:
                continue
            c = metrics.correctness(e.ate, e.aoe, sequence_eps(eps_v, f.scene, e), phi_v)
            s, t, ok = pose_segments(e.stamps, c, e.gt_end, delta_v, e.gt_start)
            labels.append((f.algorithm, f.suite, f.trial, f.scene, e.seq))
            counts.append(len(s))
            starts.append(s - e.gt_start)
            ends.append(t - e.gt_start)
            oks.append(np.asarray(ok, bool))
            firsts.append(
                dict(
                    algorithm=f.algorithm,
                    suite=f.suite,
                    trial=f.trial,
                    scene=f.scene,
                    seq=e.seq,
                    t=max(0.0, e.stamps[0] - e.gt_start),
                    correct=bool(c[0]),
                )
            )
    seg_cols = ["algorithm", "suite", "trial", "scene", "seq", "start", "end", "correct"]
    if labels:  # one table of all the segments (a table per sequence, concatenated, took 5x longer)
        names = list(zip(*labels, strict=True))
        segments = pd.DataFrame(
            {
                "algorithm": np.repeat(np.array(names[0], object), counts),
                "suite": np.repeat(np.array(names[1], object), counts),
                "trial": np.repeat(np.array(names[2], np.int64), counts),
                "scene": np.repeat(np.array(names[3], object), counts),
                "seq": np.repeat(np.array(names[4], np.int64), counts),
                "start": np.concatenate(starts).astype(float),
                "end": np.concatenate(ends).astype(float),
                "correct": np.concatenate(oks),
            }
        )
    else:
        segments = pd.DataFrame(columns=seg_cols)
    return segments, pd.DataFrame(firsts, columns=["algorithm", "suite", "trial", "scene", "seq", "t", "correct"])


def timeline_rows(errors: Iterable[FileErrors], algorithms: Iterable[str]) -> dict[tuple[str, str, int], str]:
    """The timeline's rows, top to bottom: ``(algorithm, suite, trial)`` -> the row's name. An
    algorithm run once is one row named after it; several suites or trials of it are a row each,
    named ``algorithm suite trial N`` (by what tells them apart), so they are never drawn over
    each other. Only ``algorithms`` are shown, in that order."""
    runs: dict[str, list[tuple[str, int]]] = {}
    for f in errors:
        if (f.suite, f.trial) not in runs.setdefault(f.algorithm, []):
            runs[f.algorithm].append((f.suite, f.trial))
    rows = {}
    for a in algorithms:
        these = sorted(runs.get(a, [("", 0)]))
        suites, trials = len({s for s, _ in these}) > 1, len({t for _, t in these}) > 1
        for suite, trial in these:
            rows[(a, suite, trial)] = " ".join([a] + [suite] * suites + [f"trial {trial}"] * trials)
    return rows


def sequence_layout(
    durations: pd.DataFrame, scenes: Iterable[str] | None = None, scene_gap: float = 20.0
) -> pd.DataFrame:
    """x offsets of each sequence on the shared time axis: sequences of a scene side by side,
    each as long as its ground truth, ``scene_gap`` seconds between scenes (as in the paper)."""
    order = [s for s in SCENES if s in set(durations["scene"])] if scenes is None else list(scenes)
    rows, x = [], 0.0
    for scene in order:
        d = durations[durations["scene"] == scene].sort_values("seq")
        for _, r in d.iterrows():
            rows.append(dict(scene=scene, seq=int(r["seq"]), offset=x, duration=float(r["gt_duration"])))
            x += float(r["gt_duration"])
        x += scene_gap
    return pd.DataFrame(rows, columns=["scene", "seq", "offset", "duration"])
