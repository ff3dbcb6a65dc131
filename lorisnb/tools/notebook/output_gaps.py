"""What makes CR grow with ``delta`` (Eq. 2: each correct pose earns ``min(t_{k+1} - t_k, delta)``): an
algorithm's normal output period, and the time in the gaps of its output longer than ``delta``, part of
which a larger ``delta`` credits to the pose before each gap (threshold_sensitivity's CR against delta)."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np
import pandas as pd

from lorisnb.core.lifelong.scoring import as_files
from lorisnb.core.lifelong.sweep import scene_totals, sweep, sweep_scenes
from lorisnb.core.metrics import openloris as metrics
from lorisnb.core.pipeline.model import FileErrors
from lorisnb.core.spec.validate import threshold
from lorisnb.tools.decisions.escape import code_span, markdown_cell


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


def delta_gain(
    errors: FileErrors | Iterable[FileErrors], durations: pd.DataFrame, eps: Any, phi: Any, delta: float, tau: float,
    delta_grid: Iterable[float],
) -> tuple[pd.DataFrame, pd.DataFrame, str]:  # fmt: skip
    """threshold_sensitivity's table and sentences below CR against delta: per algorithm and scene the
    output period and the gaps beyond ``delta`` (:func:`output_gaps`), CR at ``delta`` and at the
    largest delta of ``delta_grid`` and this run's (``delta_max``), and what the gain between them is.
    Returns (the gaps table, that table of rates sorted by the rise, the text). A grid that ends at
    ``delta`` or below has no larger delta to compare with, and says so (it swept ``[delta, delta]``,
    refused as a value twice: a ValidationError before the text)."""
    delta = threshold("delta", delta)
    delta_max = max(max(float(d) for d in delta_grid), delta)
    settings = [delta] if delta_max == delta else [delta, delta_max]
    ends = sweep_scenes(sweep(errors, [eps], [phi], settings, [tau]), durations)
    keys = ["algorithm", "scene"]
    cr_at = ends.pivot_table(index=keys, columns="delta", values="cr", aggfunc="mean")  # several trials: their mean
    gaps = output_gaps(errors, durations, delta)
    rates = gaps.groupby(keys)[["median_period", "gaps", "gap_share"]].mean()  # several trials: their mean
    rates = rates.assign(cr_at_delta=cr_at[delta], cr_at_max=cr_at[delta_max]).reset_index()
    rates = rates.assign(rise=rates["cr_at_max"] - rates["cr_at_delta"]).sort_values("rise", ascending=False)
    fast = rates[rates["median_period"] < delta]  # the output period is over at this delta
    climbing = fast[fast["rise"] > 0.005]
    if delta_max > delta and len(climbing):
        top = climbing.iloc[0]
        text = (
            f"In these results {len(climbing)} of the {len(fast)} algorithm-scene pairs whose normal output period is "
            f"under delta = {delta:g} s still gain CR between delta = {delta:g} s and {delta_max:g} s: that gain is "
            f"time in gaps. The largest is {code_span(top['algorithm'])} in {markdown_cell(top['scene'])}: a pose every "
            f"{top['median_period']:.3f} s (median, about {1 / top['median_period']:.0f} Hz), yet CR "
            f"{top['cr_at_delta']:.3f} at {delta:g} s and {top['cr_at_max']:.3f} at {delta_max:g} s. "
            f"{top['gap_share']:.1%} of the scene's time lies in its gaps longer than {delta:g} s, past their first "
            f"{delta:g} s: a larger delta credits up to delta seconds of each gap to the pose before it, if that "
            "pose is correct."
        )
    elif delta_max > delta:
        text = (
            f"In these results no algorithm whose normal output period is under delta = {delta:g} s gains CR between "
            f"delta = {delta:g} s and {delta_max:g} s: their correct poses leave no gap longer than {delta:g} s."
        )
    else:
        text = f"The grid ends at this run's delta ({delta:g} s): no larger delta to compare with."
    slow = rates[~(rates["median_period"] < delta)]
    if len(slow):
        text += (
            f" Output sparser than delta = {delta:g} s (median period at least delta, or fewer than 2 poses): "
            + ", ".join(f"{code_span(r.algorithm)} in {markdown_cell(r.scene)}" for r in slow.itertuples())
            + "."
        )
    return gaps, rates, text
