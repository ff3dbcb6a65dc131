"""The report's findings: per scene, a leaderboard (scene value with its interval, rank with ties
from the pairwise tests, coverage) and one sentence in plain words.

Everything statistical comes from :mod:`lorisnb.core.stats.inference` (``confidence_intervals``,
``pairwise``) and :mod:`lorisnb.core.stats.ranking` (``ranking``); this module only joins their
tables with the coverage of each algorithm (sequences with output out of the scene's sequences
with ground truth, and trials) and words the result.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from lorisnb.core.spec import validate
from lorisnb.core.spec.evalspec import EvalSpec
from lorisnb.core.stats import inference as stats
from lorisnb.errors import LorisWarning, ValidationError
from lorisnb.io.datasets.paths import DataPaths
from lorisnb.tools.decisions.comparison import COPIES_TEST, compare_table

#: Names of the metrics in sentences, with whether higher is better.
METRICS: dict[str, tuple[str, bool]] = {
    "cr": ("correct rate CR", True),
    "cr_t": ("correct rate after initialization CR-T", True),
    "cs_r": ("re-localization score CS-R", True),
    "c_ate_rmse": ("ATE RMSE over correct poses C-ATE (m)", False),
}

BOARD_COLUMNS = [
    "suite", "scene", "rank", "algorithm", "metric", "value", "low", "high", "level", "sequences_covered",
    "sequences_total", "coverage", "trials", "tied_with",
]  # fmt: skip


@dataclass(frozen=True)
class Findings:
    """What the report's front page states: the leaderboard (one row per suite, scene and
    algorithm, :data:`BOARD_COLUMNS`), the pairwise tests behind its ranks, one sentence per
    (suite, scene), and the test the ranks come from, in words."""

    board: pd.DataFrame
    pairs: pd.DataFrame
    sentences: dict[tuple[str, str], str]
    test: str


def most_trials(table: pd.DataFrame) -> pd.DataFrame:
    """Per suite, scene and algorithm: the most trials of a sequence (``trials``)."""
    t = stats.with_trials(table)
    trials = t.groupby(["suite", "scene", "algorithm", "seq"])["trial"].nunique().groupby(level=[0, 1, 2]).max()
    return trials.rename("trials").reset_index()


def test_words(pairs: pd.DataFrame, alpha: float, who: str = "algorithms") -> str:
    """How the ranks were tested, in the words the tests report of themselves: the ``test`` and
    ``correction`` of each pair (:func:`lorisnb.core.stats.inference.pairwise`: one Holm family of
    every pair of every scene); ``who``: what is ranked (the challenge's board says teams)."""
    if pairs.empty or not {"test", "correction"} <= set(pairs.columns):
        return f"rank = 1 + the number of {who} significantly better (one per scene: no pair to test)"
    named = list(dict.fromkeys(pairs["test"].dropna().astype(str)))
    tests = "; ".join(t for t in named if t != COPIES_TEST) or "no test"
    corrections = "; ".join(dict.fromkeys(pairs["correction"].dropna().astype(str)))
    how = corrections or f"Holm over every pair of every scene, alpha {alpha:g}"
    untested = int((pairs["test"] == COPIES_TEST).sum())
    copies = (f"; {untested} pair(s) not tested: the trials of one of their {who} are copies of one run, counted as "
              "one" if untested else "")  # fmt: skip
    return f"rank = 1 + the number of {who} significantly better by {tests}, {how}{copies}"


def findings(
    table: pd.DataFrame,
    durations: pd.DataFrame,
    metric: str = "cr",
    alpha: float = 0.05,
    level: float = 0.95,
    seed: int = 0,
    who: str = "algorithms",
) -> Findings:
    """The leaderboard of ``table`` (a per-sequence table of :meth:`Evaluation.sequences`, with
    trials), its pairwise tests and the sentences (see the module docstring): the values, ranks and
    tests of ``lorisnb compare`` (:func:`lorisnb.tools.decisions.comparison.compare_table`; a sequence without
    output counts as a failed run). ``who``: what the ranks rank, in :attr:`Findings.test`'s words."""
    if table.empty:
        return Findings(pd.DataFrame(columns=BOARD_COLUMNS), pd.DataFrame(), {}, test_words(pd.DataFrame(), alpha, who))
    res = compare_table(table, durations, metric, level=level, alpha=alpha, seed=seed)  # what compare ranks on
    pairs = res.pairs
    board = res.algorithms.drop(columns=["coverage"]).rename(
        columns={
            "sequences_with_output": "sequences_covered",
            "scene_sequences": "sequences_total",
            "trials": "compare_trials",
        }
    )  # compare's coverage (lorisnb.core.lifelong.coverage.complete: the one rule of sequences with output)
    board = board.merge(most_trials(table), on=["suite", "scene", "algorithm"], how="left")
    # an algorithm without any row in the scene (its files failed) ran as compare counts it: one failed run
    board["trials"] = board["trials"].fillna(board["compare_trials"]).astype(int)
    board["coverage"] = [f"{c}/{n}" for c, n in zip(board["sequences_covered"], board["sequences_total"], strict=True)]
    higher = METRICS.get(metric, ("", True))[1]
    board = board.sort_values(["suite", "scene", "rank", "value"], ascending=[True, True, True, not higher])
    board = board[[c for c in BOARD_COLUMNS if c in board.columns]].reset_index(drop=True)
    sentences = {
        (suite, scene): sentence(g, pairs[(pairs["suite"] == suite) & (pairs["scene"] == scene)], alpha)
        for (suite, scene), g in board.groupby(["suite", "scene"], sort=False)
    }
    return Findings(board, pairs, sentences, test_words(pairs, alpha, who))


def _value(r: pd.Series) -> str:
    v = f"{r['value']:.2f}"
    if np.isfinite(r["low"]) and np.isfinite(r["high"]):
        v += f" [{r['low']:.2f}, {r['high']:.2f}]"
    return v


def sentence(board: pd.DataFrame, pairs: pd.DataFrame, alpha: float = 0.05) -> str:
    """One plain sentence (or three) about one scene's leaderboard: who is first, whether the data
    separates it from the others, and which algorithms did not cover every sequence."""
    scene, suite = board["scene"].iloc[0], board["suite"].iloc[0]
    where = f"In {scene}" + (f" ({suite})" if suite else "")
    metric = board["metric"].iloc[0]
    name = METRICS.get(metric, (metric, True))[0]
    if len(board) == 1:
        r = board.iloc[0]
        return f"{where}, only {r['algorithm']} has results: {name} {_value(r)}; there is nothing to compare it with."
    first = board[board["rank"] == board["rank"].min()]
    best = first.iloc[0]
    n_seq = int(pairs["sequences"].max()) if len(pairs) and "sequences" in pairs else 0
    trials = int(board["trials"].max()) if "trials" in board else 1
    sample = f"{n_seq} sequence(s)" + (f" x up to {trials} trials" if trials > 1 else "")
    if METRICS.get(metric, ("", True))[1] and (board["value"].fillna(0) == 0).all():
        text = f"{where}, no algorithm scored: {name} is 0 for every one ({sample}), so there is no order to tell."
    elif len(first) == 1:
        text = (
            f"{where}, {best['algorithm']} is first by {name} ({_value(best)}), and the tests separate it from "
            f"every other algorithm ({sample})."
        )
    else:
        others = [a for a in first["algorithm"] if a != best["algorithm"]]
        shown = ", ".join(others[:4]) + (f" and {len(others) - 4} more" if len(others) > 4 else "")
        text = (
            f"{where}, {best['algorithm']} has the highest {name} ({_value(best)})" if METRICS.get(metric, ("", True))[1]
            else f"{where}, {best['algorithm']} has the lowest {name} ({_value(best)})"
        )  # fmt: skip
        text += f", but the data cannot tell it apart from {shown} ({sample}): their order is not established."
        floor = pairs["min_p"].min() if "min_p" in pairs and len(pairs) else np.nan
        if np.isfinite(floor) and floor > alpha and trials < 3:
            dropped = n_seq > 0 and floor > 2.0 / 2**n_seq * (1 + 1e-9)  # 2 / 2^n with every sequence counted
            text += (
                f" With one run on {n_seq} sequence(s) no paired test can reach p < {alpha:g} "
                f"(smallest possible p {floor:.3g}"
                + ("; sequences on which two algorithms score the same, such as both 0, carry no evidence and "
                   "drop out of the paired test" if dropped else "")
                + "); more sequences or trials are needed."
            )  # fmt: skip
    short = board[board["sequences_covered"] < board["sequences_total"]]
    if len(short):
        listed = ", ".join(f"{a} ({c})" for a, c in zip(short["algorithm"][:5], short["coverage"][:5], strict=True))
        more = f" and {len(short) - 5} more" if len(short) > 5 else ""
        text += f" Output missing on some sequences: {listed}{more}."
    return text


#: The leaderboard's own settings and their defaults (the ``compare`` command's): a report
#: parameter of the same name overrides each. What the numbers are computed with is the evaluation
#: spec of the report's parameters (:func:`leaderboard_spec`).
SETTINGS: dict[str, Any] = {
    "metric": "cr", "alpha": 0.05, "level": 0.95, "seed": 0, "trials_by": None, "algorithms": None, "scenes": None,
}  # fmt: skip
#: Spec options whose default differs from the spec's: ``scale`` is ``auto`` (Sim(3) for monocular
#: algorithms), as in every notebook that evaluates results and in the paper, unless the parameters
#: choose the alignment (``scale``, ``align``) or a preset (``conventions``), whose alignment holds.
SPEC_DEFAULTS: dict[str, Any] = {"scale": "auto"}
#: The parameters that choose the alignment: given any, :data:`SPEC_DEFAULTS` does not apply.
ALIGNMENT_CHOICES = ("scale", "align", "conventions")


def leaderboard_spec(parameters: Mapping[str, Any]) -> EvalSpec:
    """The evaluation spec of the report's parameters, built as each notebook builds its own
    (:func:`lorisnb.tools.notebook.params.evaluation_spec`): every ``-p`` that is an option of the
    spec (thresholds, ``scale``, ``official_interpolation``, the RPE step, ``conventions``, ...)
    reaches the leaderboard, ``findings/`` and ``run.json`` as it reaches the notebooks; the
    thresholds not given are the spec's (eps = phi = inf, delta 1 s, tau 60 s: the ``compare``
    command's and ``per_sequence_benchmark``'s), ``scale`` is ``auto`` unless the parameters choose
    the alignment or a preset (``-p conventions evo`` aligns nothing, as ``evaluate --conventions
    evo`` and the notebook do). An option that cannot apply
    to OpenLORIS result files is refused, naming it."""
    from lorisnb.tools.notebook.params import evaluation_spec

    given = {k: v for k, v in parameters.items() if v is not None}
    defaults = {} if any(k in given for k in ALIGNMENT_CHOICES) else SPEC_DEFAULTS  # -p conventions evo: no alignment
    spec = evaluation_spec({**defaults, **given})
    spec.refuse_inapplicable("openloris", surface="notebook")
    return spec


def refuse_unscorable_scenes(scenes: Any, data: DataPaths) -> None:
    """Refuse a ``scenes`` filter none of whose scenes has ground truth in ``data`` (OpenLORIS'
    office in the bundled data): nothing would be scored, and every notebook would fail or show
    nothing. Called before anything runs; a filter keeping at least one scene with ground truth passes."""
    from lorisnb.tools.evaluation.inputs import names

    if scenes is None:
        return
    wanted = names("scenes", scenes)
    have = data.scenes_with_groundtruth()
    if wanted and not set(wanted) & set(have):
        raise ValidationError(
            f"-p scenes {list(wanted)}: the data root {data.root} holds no ground truth for "
            f"{', '.join(wanted)} (it has {', '.join(have) or 'none'}), so no result file would be scored; "
            "name a scene with ground truth"
        )


def report_findings(
    source: Path, data: DataPaths, parameters: Mapping[str, Any]
) -> tuple[Findings, Any, dict[str, Any]]:
    """Evaluate ``source`` once (a results folder, trials allowed) with the spec of the report's
    parameters (:func:`leaderboard_spec`) and build its :class:`Findings` at the leaderboard's
    settings (:data:`SETTINGS`, overridden by ``parameters``). Returns (findings, the evaluation,
    the settings used, ``scale`` in its one form (True, False or ``"auto"``): run.json's values)."""
    from lorisnb.tools.evaluation.runner import evaluate

    values: dict[str, Any] = {k: v if parameters.get(k) is None else parameters[k] for k, v in SETTINGS.items()}
    values["scale"] = SPEC_DEFAULTS["scale"] if parameters.get("scale") is None else parameters["scale"]
    spec = leaderboard_spec(parameters)
    with warnings.catch_warnings():  # the notebooks show the warnings about inputs, per file
        warnings.simplefilter("ignore", LorisWarning)
        ev = evaluate(
            source, spec, data_root=data, trials_by=values["trials_by"], algorithms=values["algorithms"],
            scenes=values["scenes"], jobs=1,  # beside the notebooks: one process
        )  # fmt: skip
    table = ev.sequences()  # at the spec's thresholds and RPE step
    f = findings(
        table, ev.durations() if len(table) else pd.DataFrame(columns=["scene", "seq"]), str(values["metric"]),
        alpha=float(values["alpha"]), level=float(values["level"]), seed=validate.seed(values["seed"]),
    )  # fmt: skip
    return f, ev, values


def by_algorithm(table: pd.DataFrame, values: str, columns: str = "scene") -> pd.DataFrame:
    """Algorithms x ``columns`` of ``values``: the mean over trials where there are several
    (a results folder with ``_trial3`` files has one row per trial), the value itself otherwise."""
    return table.pivot_table(index="algorithm", columns=columns, values=values, aggfunc="mean")
