"""Sentences of the notebooks' prose that depend on the run: computed from its tables and spec and
shown by a code cell, so that they are true on the user's results and at any parameters (a typed
sentence is true only of the bundled data at the defaults). They are Markdown: an algorithm's name
is a code span (:func:`~lorisnb.tools.decisions.escape.code_span`), a scene's name Markdown text
(:func:`~lorisnb.tools.decisions.escape.markdown_cell`), each shown as the terminal shows it."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from lorisnb.tools.decisions.escape import code_span, markdown_cell

__all__ = ["rank_reference_words", "rpe_words", "simulated_verdict", "threshold_words", "tracking_and_accuracy"]


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
    return code_span(name)


def _infinite(value: Any) -> bool:
    try:
        return bool(np.isinf(float(value)))
    except (TypeError, ValueError):
        return False  # "paper", "relative:0.05": finite thresholds


def tracking_and_accuracy(scene_table: pd.DataFrame, eps: Any = float("inf"), phi: Any = float("inf")) -> str:
    """Per scene of ``scene_table`` (``ev.scenes()``: ``cr``, ``c_ate_rmse``), which algorithm tracked
    longest and which was most and least accurate, each with both numbers: the examples for the
    notebook's "tracking time and accuracy pull in opposite directions", from these inputs. At
    infinite ``eps`` and ``phi`` CR is the time with output ("tracked longest"); at finite ones it is
    the correct rate, and is called so. Scenes with fewer than two algorithms to compare are named,
    not silently left out."""
    tracked = "tracked longest" if _infinite(eps) and _infinite(phi) else "had the highest correct rate"
    lines, alone = [], []
    for scene, rows in scene_table.groupby("scene", sort=False):
        rows = rows[np.isfinite(pd.to_numeric(rows["cr"], errors="coerce"))]
        scored = rows[np.isfinite(pd.to_numeric(rows["c_ate_rmse"], errors="coerce"))]
        if len(scored) < 2:
            names = ", ".join(code_span(a) for a in dict.fromkeys(map(str, scored["algorithm"])))
            alone.append(f"{markdown_cell(scene)} ({names + ' alone' if names else 'none'})")
            continue

        def said(r: Any, rows: pd.DataFrame = rows) -> str:
            return f"{_label(r, rows)} (CR {100 * r['cr']:.1f} %, C-ATE RMSE {r['c_ate_rmse']:.3f} m)"

        longest = rows.loc[rows["cr"].idxmax()]
        best, worst = scored.loc[scored["c_ate_rmse"].idxmin()], scored.loc[scored["c_ate_rmse"].idxmax()]
        if longest["algorithm"] == best["algorithm"] and longest.get("trial") == best.get("trial"):
            text = f"{said(longest)} {tracked} and was also the most accurate"
        else:
            text = f"{said(longest)} {tracked}; the most accurate was {said(best)}"
        if worst.name not in (longest.name, best.name):
            text += f"; the least accurate was {said(worst)}"
        lines.append(f"* {markdown_cell(scene)}: {text}.")
    left = (
        f"\n\nNot compared, with fewer than two algorithms that have both a CR and a C-ATE RMSE: {'; '.join(alone)}."
        if alone
        else ""
    )
    if not lines:
        return "On these inputs no scene has two algorithms with both a CR and a C-ATE RMSE to compare." + left
    return "On these inputs:\n\n" + "\n".join(lines) + left


def simulated_verdict(pairs: pd.DataFrame, steady: str, drifting: str, twin: str, trials: int, alpha: float) -> str:
    """What the simulated section's test found (``pairs``: :func:`lorisnb.core.stats.pairwise` of the
    simulated algorithms), said of the three known cases: the drifting algorithm against each of the
    others (a real difference) and steady against its twin (none)."""

    def significant(a: str, b: str) -> bool | None:
        hit = pairs[((pairs["a"] == a) & (pairs["b"] == b)) | ((pairs["a"] == b) & (pairs["b"] == a))]
        return None if hit.empty else bool(hit["significant"].any())

    drift_name, steady_name, twin_name = (code_span(n) for n in (drifting, steady, twin))
    against = {other: significant(drifting, other) for other in (steady, twin)}
    separated = [o for o, s in against.items() if s]
    if len(separated) == 2:
        drift = f"{drift_name} is separated from both others (a real difference)"
    elif separated:
        drift = (
            f"{drift_name} is separated from {code_span(separated[0])} only, although it differs from both: "
            f"with {trials} trial(s) at these thresholds the test misses a real difference"
        )
    else:
        drift = (
            f"{drift_name} is separated from neither of the others, although it drifts more: "
            f"with {trials} trial(s) at these thresholds (a large eps counts every pose correct) the test cannot see it"
        )
    same = significant(steady, twin)
    if same:
        twins = (
            f"{steady_name} and {twin_name} are separated although they are the same algorithm with other seeds: "
            f"a false positive, which the test allows with probability up to alpha = {alpha:g}"
        )
    elif same is None:
        twins = f"{steady_name} and {twin_name} were not compared"
    else:
        twins = f"{steady_name} and {twin_name} share a rank: the data cannot tell them apart, which is the truth here"
    return f"In the simulated section, {drift}; {twins}."


def threshold_words(eps: Any, phi: Any) -> str:
    """The eps and phi of a run in words: "the paper's eps (1, 3 or 5 m by scene) and phi (30 deg)" only
    when they are the paper's, else the values used ("eps = 0.5 m and phi = 20 deg")."""
    from lorisnb.core.trajectory.frames import PAPER_PHI

    if isinstance(eps, str) and eps.strip().lower() == "paper":
        e = "the paper's eps (1, 3 or 5 m by scene)"
    elif isinstance(eps, str) and eps.strip().lower().startswith("relative:"):
        e = f"eps = {float(eps.split(':', 1)[1]):g} of each sequence's extent"
    else:
        e = f"eps = {float(eps):g} m"
    p = f"phi = {float(phi):g} deg"
    if float(phi) == PAPER_PHI:
        p += " (the paper's)"
    return f"{e} and {p}"


def rank_reference_words(stability: pd.DataFrame, scenes: Any = ()) -> str:
    """What each scene's ranking in ``stability`` (:func:`lorisnb.core.lifelong.sweep.rank_stability`)
    is compared with: the paper's eps where the grid holds it, else the grid value nearest it (named),
    and the ``scenes`` of the sweep left out because they have fewer than two algorithms to rank."""
    from lorisnb.core.trajectory.frames import PAPER_EPS

    parts = []
    for scene, rows in stability.groupby("scene", sort=False):
        ref = float(rows["reference_eps"].iloc[0])
        paper = PAPER_EPS.get(str(scene))
        if paper is not None and np.isclose(ref, paper):
            parts.append(f"{markdown_cell(scene)}: the paper's eps, {ref:g} m")
        elif paper is not None:
            parts.append(
                f"{markdown_cell(scene)}: {ref:g} m, the grid value nearest the paper's {paper:g} m (not in the grid)"
            )
        else:
            parts.append(f"{markdown_cell(scene)}: {ref:g} m")
    text = "The reference ranking of each scene is the ranking at " + "; ".join(parts) + "." if parts else ""
    ranked = set(map(str, stability["scene"])) if len(stability) else set()
    left = [str(s) for s in dict.fromkeys(scenes) if str(s) not in ranked]
    if left:
        text += (" " if text else "") + (
            f"Left out, with fewer than two algorithms to rank: {', '.join(map(markdown_cell, left))}."
        )
    return text or "No scene has two algorithms to rank."
