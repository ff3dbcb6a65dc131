"""Checks of lab answers whose reference lorisnb computes from the lab's own inputs, so that the
student version's test cells show no solution (re-exported by :mod:`lorisnb.tools.teaching`)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np
import pandas as pd

from lorisnb.core.lifelong.scoring import score
from lorisnb.core.lifelong.sweep import eps_at_cr
from lorisnb.core.pipeline.model import FileErrors, ResultFile
from lorisnb.core.simulate import Faults, simulated_errors
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.errors import AnswerError
from lorisnb.tools.teaching._checks import check_choice, check_value
from lorisnb.tools.teaching._grading import how_far
from lorisnb.tools.teaching._mistakes import MISTAKES


def _differs(values: Mapping[str, float], expected: float, tol: float) -> dict[str, float]:
    """The mistakes whose value differs from the expected one (NaN ones dropped)."""
    return {k: float(v) for k, v in values.items() if np.isfinite(v) and abs(v - expected) > tol}


def check_alignment_cr(
    cr_lifelong: Any,
    cr_per_seq: Any,
    groundtruth: ResultFile,
    faults: Mapping[int, Faults],
    seq: int,
    eps: float,
    phi: float,
    delta: float,
    tau: float,
) -> bool:
    """CR of sequence ``seq`` of a simulated multi-sequence run, evaluated lifelong (one alignment
    fitted on the first sequence) and per sequence (each aligned on itself); a learner who swapped
    the two, or used one for both, is told about per-sequence vs lifelong alignment."""
    seqs = sorted(faults)
    ref = {
        m: float(score(simulated_errors(groundtruth, faults, seqs=seqs, mode=m), eps, phi, delta, tau)
                 .set_index("seq").loc[seq, "cr"])
        for m in ("lifelong", "per-seq")
    }  # fmt: skip
    tol = 0.005
    check_value(f"CR of sequence {seq}, lifelong", cr_lifelong, ref["lifelong"], tol=tol,
                mistakes=_differs({"alignment": ref["per-seq"]}, ref["lifelong"], tol))  # fmt: skip
    return check_value(f"CR of sequence {seq}, per sequence", cr_per_seq, ref["per-seq"], tol=tol,
                       mistakes=_differs({"alignment": ref["lifelong"]}, ref["per-seq"], tol))  # fmt: skip


def check_eps_at_cr(
    answer: Any, errors: Iterable[FileErrors], durations: pd.DataFrame, target: float, phi: float, delta: float
) -> bool:
    """The smallest eps (metres) at which one algorithm's scene CR reaches ``target``
    (:func:`lorisnb.core.lifelong.sweep.eps_at_cr`); hints when the answer ignores phi or the delta cap."""
    errors = list(errors)

    def at(p: float, d: float) -> float:
        table = eps_at_cr(errors, target, durations, p, d)
        if len(table) != 1:
            raise ValueError(f"check_eps_at_cr: expected the errors of one algorithm on one scene, got {len(table)}")
        return float(table["eps"].iloc[0])

    want = at(phi, delta)
    try:  # one number, as check_value reads it (a one-value Series or array too); anything else is its to tell
        a = np.asarray(answer, float) if answer is not Ellipsis else np.array([])
        v = float(a.reshape(())) if a.size == 1 else None
    except (TypeError, ValueError):
        v = None
    if v is not None and np.isnan(v) and np.isnan(at(np.radians(phi), delta)):
        raise AnswerError(  # eps_at_cr's NaN: no eps reaches the target, as with phi in radians
            f"✗ smallest eps for a scene CR of {target:g} (m): your answer is NaN, which eps_at_cr gives when no eps "
            f"reaches the target; with phi = {phi:g} degrees an eps does reach it"
            f"\nHint (degrees radians): {MISTAKES['degrees_radians']}"
        )
    if v is not None and want + 0.01 < v <= want + 0.2:  # past the step: a grid too coarse to find the smallest eps
        raise AnswerError(
            f"✗ smallest eps for a scene CR of {target:g} (m): you answered {v:.4g}, {how_far(v, want, 0.01)} "
            "(tolerance 0.01)"
            f"\nHint (coarse grid): {MISTAKES['coarse_grid']}"
        )
    return check_value(f"smallest eps for a scene CR of {target:g} (m)", answer, want, tol=0.01,
                       mistakes=_differs({"phi_ignored": at(np.inf, delta), "delta_cap": at(phi, np.inf)}, want, 0.01))  # fmt: skip


def check_silent_sequences(answer: Any, sequences: pd.DataFrame, seq: int) -> bool:
    """How many algorithms of a scored table output no matched pose in sequence ``seq``."""
    want = int(((sequences["seq"] == seq) & (sequences["matched"] == 0)).sum())
    return check_value(f"algorithms with no pose in sequence {seq}", answer, want, tol=0.1, source="the timeline")


def check_best_cr(answer: Any, scenes: pd.DataFrame, cr: Any = None) -> bool:
    """The algorithm with the highest scene CR (one scene) and, when ``cr`` is given, that CR: a
    fraction, as the timeline prints it (in percent) at the top left of the algorithm's row. A name
    that is the best by CR-T, or a CR that is the algorithm's CR-T, gets the CR vs CR-T hint; a CR in
    percent, or the row's other number (its C-ATE RMSE, metres), get theirs. The tolerance, 0.005,
    takes the printed percentage read as a fraction (0.1 % steps) or rounded to two decimals."""
    ranked = scenes.sort_values("cr", ascending=False)
    best = str(ranked["algorithm"].iloc[0])
    best_t = str(scenes.sort_values("cr_t", ascending=False)["algorithm"].iloc[0])
    why = "CR counts correct time over all the scene's sequences: look for the longest blue bars."
    if isinstance(answer, str) and answer.strip().lower() == best_t.lower() != best.lower():
        why += f"\nHint (cr vs crt): {MISTAKES['cr_vs_crt']}"
    check_choice("algorithm with the highest scene CR", answer, best, why)
    if cr is None:
        return True
    row, tol = ranked.iloc[0], 0.005
    want = float(row["cr"])
    mistakes = {"cr_vs_crt": float(row["cr_t"])}
    if "c_ate_rmse" in row.index:
        mistakes["timeline_label"] = float(row["c_ate_rmse"])
    return check_value(f"CR of {best} over the scene", cr, want, tol=tol, fraction=True,
                       mistakes=_differs(mistakes, want, tol))  # fmt: skip


def check_ate_percent(
    answer: Any, ate_rmse: float, c_ate_rmse: float, groundtruth: Trajectory, ate_mean: float | None = None
) -> bool:
    """ATE RMSE (metres) as a percentage of the ground truth's path length (metres travelled).
    ``ate_mean`` (metres, the scored table's ``ate_mean``): an answer made of the mean ATE gets the
    RMSE-vs-mean hint."""
    want = 100.0 * ate_rmse / groundtruth.path_length
    mistakes = {
        "percent": want / 100.0,
        "extent_vs_length": 100.0 * ate_rmse / groundtruth.extent,
        "c_ate": 100.0 * c_ate_rmse / groundtruth.path_length,
    }
    if ate_mean is not None:
        mistakes["rmse_vs_mean"] = 100.0 * float(ate_mean) / groundtruth.path_length
    return check_value("ATE RMSE as % of path length", answer, want, tol=0.05, mistakes=_differs(mistakes, want, 0.05))
