"""The numbers of the ``compare_algorithms`` notebook (and of a report's compare page, which runs it):
``lorisnb compare``'s own (:func:`lorisnb.tools.decisions.comparison.compare_table`), one function for
both, so a sequence an algorithm lacks counts as a failed run (CR 0, its ground-truth time counted) in
the scene values, the intervals, the test and the ranking alike, as ``evaluate`` and ``compare`` count
it (before, the notebook scored only the sequences with output: a scene an algorithm had no output for
dropped out of its page while the front page ranked it with coverage 0/2)."""

from __future__ import annotations

from dataclasses import dataclass

import pandas as pd

from lorisnb.tools.decisions.comparison import Comparison, compare_table

__all__ = ["NotebookComparison", "scene_comparison"]


@dataclass
class NotebookComparison:
    """``ci``: intervals of every metric; ``pairs``: the pairwise test; ``ranking``: one row per
    suite, scene and algorithm (``value``, ``rank``, ``tied_with``, ``better_than``, and the
    coverage: ``sequences_with_output`` of ``scene_sequences``, ``covered`` as ``compare`` prints
    it); ``coverage``; ``notes``: ``compare``'s warnings (missing sequences, copied trials);
    ``comparison``: everything ``compare`` computed."""

    ci: pd.DataFrame
    pairs: pd.DataFrame
    ranking: pd.DataFrame
    coverage: pd.DataFrame
    notes: list[str]
    comparison: Comparison


def scene_comparison(
    table: pd.DataFrame, durations: pd.DataFrame, metric: str = "cr", level: float = 0.95, alpha: float = 0.05,
    seed: int = 0,
) -> NotebookComparison:  # fmt: skip
    """The intervals, pairwise test and ranking of a per-sequence ``table``
    (``Evaluation.sequences()``) over the sequences of ``durations`` (``Evaluation.durations()``:
    every sequence of each scene, the ones an algorithm is expected to have), exactly as
    ``lorisnb compare`` computes them."""
    res = compare_table(table, durations, metric, level=level, alpha=alpha, seed=seed)
    ranking = res.algorithms.drop(columns=["value [CI]", "vs top [test interval]"])
    return NotebookComparison(res.ci, res.pairs, ranking, res.coverage, list(res.notes), res)
