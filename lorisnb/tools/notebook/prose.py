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

__all__ = [
    "every_number_words",
    "rank_reference_words",
    "rpe_words",
    "simulated_verdict",
    "threshold_words",
    "tracking_and_accuracy",
]


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


def _than(value: float, low: float, high: float, rel: float = 0.02) -> str:
    """``value`` against the range ``low`` .. ``high``: "smaller", "larger" or "about the same"
    (within ``rel`` of the range)."""
    if value < low * (1 - rel):
        return "smaller"
    if value > high * (1 + rel):
        return "larger"
    return "about the same"


def every_number_words(wide: pd.DataFrame, truth: Any, estimate: Any) -> str:
    """``every_number``'s "why they differ, on this pair" (``wide``: :func:`lorisnb.tools.peers.every_number.side_by_side`
    of the pair; ``truth`` and ``estimate``: the pair's trajectories, as read), every comparison
    computed: which tolerance is tighter (from the presets), how the unaligned ATE stands against
    the aligned ones, the length of one frame of this estimate against 1 s and whether evo's
    one-frame RPE is smaller or larger than the RPE over 1 s, and what the path's length says of
    KITTI's segments. Typed, "a smaller number for a shorter step" was said of an estimate with one
    pose every 2 s, whose RPE over one frame was larger, and "a desk-sized scene" of any path under
    100 m."""
    from lorisnb.core.spec.evalspec import PRESETS

    ate = wide.loc[("ATE RMSE", "m")]
    matched = wide.loc[("matched poses", "")]
    aligned, unaligned = ate[["openloris", "tum", "rpg"]], ate[["evo", "kitti"]]
    rpe = wide.loc[("RPE translation RMSE", "m")]
    rpe_1s, rpe_frame = rpe[["openloris", "tum", "rpg"]], float(rpe["evo"])
    tum_tol, evo_tol = float(PRESETS["tum"].max_diff), float(PRESETS["evo"].max_diff)
    tol = "tighter" if evo_tol < tum_tol else "looser" if evo_tol > tum_tol else "equal"
    lines = [
        f"* **Matching in time.** Interpolating the ground truth (`openloris`) matched {matched['openloris']:.0f} poses; "
        f"the nearest stamp within TUM's tolerance of {tum_tol:g} s (`tum`, `rpg`) {matched['tum']:.0f}; within evo's "
        f"{tol} one of {evo_tol:g} s {matched['evo']:.0f}. Each tool averages over its own set of poses."
    ]
    ratio = float(unaligned.max() / aligned.max())
    if ratio > 1.05:
        against = f"{ratio:.1f} times the largest aligned value"
    elif ratio < 0.95:
        against = f"smaller than the largest aligned value ({ratio:.2f} times it)"
    else:
        against = "about the largest aligned value"
    lines.append(
        f"* **Alignment.** With an alignment the ATE RMSE is {aligned.min():.4f} to {aligned.max():.4f} m "
        f"(`rpg`'s Sim(3) also fits a scale: {ate['rpg']:.4f} m against `tum`'s SE(3) {ate['tum']:.4f} m). "
        f"Without one (evo's and the devkit's default) it is {unaligned.max():.4f} m, {against}: the estimate is "
        "compared in its own frame. Before quoting an evo number, check whether it was run with `-a` (align) or `-as`."
    )
    stamps = np.asarray(estimate.stamps, dtype=float)
    step = float(np.median(np.diff(stamps))) if len(stamps) > 1 else float("nan")
    length = "shorter" if step < 0.95 else "longer" if step > 1.05 else "about as long"  # (NaN: neither)
    number = _than(rpe_frame, float(rpe_1s.min()), float(rpe_1s.max()))
    said = {"smaller": "a smaller number", "larger": "a larger number", "about the same": "about the same number"}[
        number
    ]
    if (length, number) in (("shorter", "smaller"), ("longer", "larger")):
        why = f"{said} for a {length} step, not a {'better' if number == 'smaller' else 'worse'} run"
    elif np.isnan(step):
        why = "over a step this estimate cannot say"
    elif length == "about as long":
        why = f"{said}, over a step about as long as 1 s"
    else:
        why = f"{said} although the step is {length}: over another step the RPE measures another drift"
    if np.isnan(step):
        step_words = "this estimate has one pose"
    else:
        than = "about as long as 1 s" if length == "about as long" else f"{length} than 1 s"
        step_words = f"here {step:.3g} s, the median time between this estimate's poses, {than}"
    lines.append(
        f"* **Relative error.** The RPE over 1 s (`openloris`, `tum`, `rpg`) is {rpe_1s.min():.4f} to "
        f"{rpe_1s.max():.4f} m; evo's default step of one frame ({step_words}) gives {rpe_frame:.4f} m, {why}; "
        f"tartanair_tools draws random pairs ({wide.loc[('TartanAir RPE translation', 'm'), 'tartanair']:.4f} m)."
    )
    segments = wide.loc[("KITTI segments", ""), "kitti"]
    path = float(truth.path_length)
    if segments == 0:
        short = (
            f"a path of {path:.1f} m, shorter than the devkit's shortest segment (100 m)"
            if path < 100
            else f"a path of {path:.1f} m on which no segment of 100 to 800 m starts at one of the devkit's frames"
        )
        lines.append(
            f"* **KITTI's metric needs long paths.** The devkit averages over segments of 100 to 800 m; this ground "
            f"truth travels {path:.1f} m, so it has {segments:.0f} segments and no KITTI error (NaN): the metric of "
            f"driving datasets says nothing about {short}."
        )
    else:
        lines.append(
            f"* **KITTI's metric** averages {segments:.0f} segments of 100 to 800 m: translational error "
            f"{wide.loc[('KITTI translational error', '%'), 'kitti']:.3f} % and rotational error "
            f"{wide.loc[('KITTI rotational error', 'deg/100 m'), 'kitti']:.3f} deg/100 m."
        )
    return "\n".join(lines)
