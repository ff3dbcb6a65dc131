"""Sentences of the notebooks' prose that depend on the run: computed from its tables and spec and
shown by a code cell, so that they are true on the user's results and at any parameters (a typed
sentence is true only of the bundled data at the defaults)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

__all__ = ["rpe_words", "simulated_verdict", "tracking_and_accuracy"]


def rpe_words(spec: Any) -> str:
    """What the RPE columns of ``spec``'s tables are, in words: the step and how the pairs are taken."""
    step = f"{float(spec.rpe_delta):g} {spec.rpe_unit}"
    pairs = getattr(spec, "rpe_pairs", None)
    how = {
        "reference": "pose pairs that far apart along the ground truth, as the TUM benchmark defines it",
        "estimate": "pose pairs that far apart along the estimate, as evo takes them",
    }.get(str(pairs), f"pose pairs taken by the spec's rule ({pairs})")
    return f"The RPE columns give the relative pose error over {step} ({how}), over all such pairs and over pairs of correct poses."


def _label(row: Mapping[str, Any], rows: pd.DataFrame) -> str:
    """An algorithm's name, with its trial where the table holds several of it."""
    name = str(row["algorithm"])
    if "trial" in rows.columns and (rows["algorithm"] == row["algorithm"]).sum() > 1 and pd.notna(row.get("trial")):
        name += f" (trial {row['trial']})"
    return f"`{name}`"


def tracking_and_accuracy(scene_table: pd.DataFrame) -> str:
    """Per scene of ``scene_table`` (``ev.scenes()``: ``cr``, ``c_ate_rmse``), which algorithm tracked
    longest and which was most and least accurate, each with both numbers: the examples for the
    notebook's "tracking time and accuracy pull in opposite directions", from these inputs."""
    lines = []
    for scene, rows in scene_table.groupby("scene", sort=False):
        rows = rows[np.isfinite(pd.to_numeric(rows["cr"], errors="coerce"))]
        scored = rows[np.isfinite(pd.to_numeric(rows["c_ate_rmse"], errors="coerce"))]
        if len(scored) < 2:
            continue

        def said(r: Any, rows: pd.DataFrame = rows) -> str:
            return f"{_label(r, rows)} (CR {100 * r['cr']:.1f} %, C-ATE RMSE {r['c_ate_rmse']:.3f} m)"

        longest = rows.loc[rows["cr"].idxmax()]
        best, worst = scored.loc[scored["c_ate_rmse"].idxmin()], scored.loc[scored["c_ate_rmse"].idxmax()]
        if longest["algorithm"] == best["algorithm"] and longest.get("trial") == best.get("trial"):
            text = f"{said(longest)} tracked longest and was also the most accurate"
        else:
            text = f"{said(longest)} tracked longest; the most accurate was {said(best)}"
        if worst.name not in (longest.name, best.name):
            text += f"; the least accurate was {said(worst)}"
        lines.append(f"* {scene}: {text}.")
    if not lines:
        return "On these inputs no scene has two algorithms with both a CR and a C-ATE RMSE to compare."
    return "On these inputs:\n\n" + "\n".join(lines)


def simulated_verdict(pairs: pd.DataFrame, steady: str, drifting: str, twin: str, trials: int, alpha: float) -> str:
    """What the simulated section's test found (``pairs``: :func:`lorisnb.core.stats.pairwise` of the
    simulated algorithms), said of the three known cases: the drifting algorithm against each of the
    others (a real difference) and steady against its twin (none)."""

    def significant(a: str, b: str) -> bool | None:
        hit = pairs[((pairs["a"] == a) & (pairs["b"] == b)) | ((pairs["a"] == b) & (pairs["b"] == a))]
        return None if hit.empty else bool(hit["significant"].any())

    against = {other: significant(drifting, other) for other in (steady, twin)}
    separated = [o for o, s in against.items() if s]
    if len(separated) == 2:
        drift = f"`{drifting}` is separated from both others (a real difference)"
    elif separated:
        drift = (
            f"`{drifting}` is separated from `{separated[0]}` only, although it differs from both: "
            f"with {trials} trial(s) at these thresholds the test misses a real difference"
        )
    else:
        drift = (
            f"`{drifting}` is separated from neither of the others, although it drifts more: "
            f"with {trials} trial(s) at these thresholds (a large eps counts every pose correct) the test cannot see it"
        )
    same = significant(steady, twin)
    if same:
        twins = (
            f"`{steady}` and `{twin}` are separated although they are the same algorithm with other seeds: "
            f"a false positive, which the test allows with probability up to alpha = {alpha:g}"
        )
    elif same is None:
        twins = f"`{steady}` and `{twin}` were not compared"
    else:
        twins = f"`{steady}` and `{twin}` share a rank: the data cannot tell them apart, which is the truth here"
    return f"In the simulated section, {drift}; {twins}."
