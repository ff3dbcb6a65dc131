"""What makes CR grow with ``delta`` (Eq. 2: each correct pose earns ``min(t_{k+1} - t_k, delta)``): an
algorithm's normal output period, and the time in the gaps of its output longer than ``delta``, part of
which a larger ``delta`` credits to the pose before each gap (threshold_sensitivity's CR against delta)."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import pandas as pd

from lorisnb.core.lifelong.scoring import as_files
from lorisnb.core.lifelong.sweep import scene_totals
from lorisnb.core.metrics import openloris as metrics
from lorisnb.core.pipeline.model import FileErrors
from lorisnb.core.spec.validate import threshold


def output_gaps(errors: FileErrors | Iterable[FileErrors], durations: pd.DataFrame, delta: float = 1.0) -> pd.DataFrame:
    """One row per suite, algorithm, scene and trial: ``median_period`` (seconds: the median interval
    between consecutive matched poses, the normal output period; NaN with fewer than 2 poses in every
    sequence), ``gaps`` (the intervals ``t_{k+1} - t_k``, with ``t_{N+1} = t_max`` as in Eq. 2, longer
    than ``delta``), ``gap_time`` (seconds: their time beyond ``delta``, which no pose earns at this
    ``delta``; a larger one credits up to that much more of each gap to the pose before it, if correct)
    and ``gap_share`` (``gap_time`` over the scene's ground-truth time, the denominator of scene CR: by
    how much at most the scene CR can still grow with ``delta``). The time before a sequence's first
    pose is in no gap (no pose holds it). ``durations``: ``Evaluation.durations()``."""
    files = as_files(errors)
    delta = threshold("delta", delta)
    total = scene_totals(durations, (f.scene for f in files))
    parts: dict[tuple[str, str, str, int], list[tuple[np.ndarray, np.ndarray]]] = {}
    for f in files:
        chunks = parts.setdefault((f.suite, f.algorithm, f.scene, f.trial), [])  # listed even if never matched
        for e in f.sequences:
            if e.matched:
                chunks.append((np.diff(e.stamps), metrics.valid_intervals(e.stamps, e.gt_end, e.gt_start)))
    rows = []
    for (suite, alg, scene, trial), chunks in parts.items():
        steps = np.concatenate([s for s, _ in chunks] or [np.zeros(0)])
        held = np.concatenate([h for _, h in chunks] or [np.zeros(0)])
        beyond = held[held > delta] - delta
        rows.append(dict(suite=suite, algorithm=alg, scene=scene, trial=trial, delta=delta,
                         median_period=float(np.median(steps)) if len(steps) else np.nan, gaps=len(beyond),
                         gap_time=float(beyond.sum()), gap_share=float(beyond.sum()) / total[scene]))  # fmt: skip
    columns = ["suite", "algorithm", "scene", "trial", "delta", "median_period", "gaps", "gap_time", "gap_share"]
    return pd.DataFrame(rows, columns=columns)
