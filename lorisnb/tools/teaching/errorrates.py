"""How often lab 1's grader is wrong: a corpus of answers to every graded question, right ones
written in many legitimately different ways and wrong ones (every typical mistake of
:data:`~lorisnb.tools.teaching.MISTAKES` that applies, and the slips, perturbations and copied
numbers around them), graded on the data variants of many student ids by the grader's own code
(``teaching/grading_error_rates.py`` prints the table; teaching/README.md, "How often a grade is
wrong", quotes it).

The answers go the way ``make grade`` takes them (:mod:`.autograde`), not through a copy of it:

- **formula answers** (A1, B2, C1) each run alone in their own numpy-only :class:`.sandbox.Sandbox`,
  and the checks call them there through :class:`.autograde.RemoteFunction`, arguments and results
  crossing the pipe as the grader's do;
- **predictions** (B1, B3, C2) run in a numpy-only sandbox given the lab's numbers only
  (:func:`._sandbox_child.given`, as the grader's process has them before the answer cell);
- **the other answers** (D1, E1, F, G1) run in a sandbox of the whole lab, with lorisnb, right after
  the lab's own answer cell, for the student's parameters; their values are read back as plain values;
- the **test cells** of the instructor's notebook (visible and hidden tests, ``hidden_seed`` drawn
  from a secret as the grader draws it) run in this process, the answers' values and sandboxed
  functions put in place of their names, as :func:`.autograde.grade_submission` does.

A subset (:func:`grade_route`) is also graded whole, as generated submissions through
:func:`.gradebook.grade_class` (the route of ``make grade``), and its grades compared with these.

A right answer rejected is a **false fail**, a wrong one accepted a **false pass**. A wrong answer
whose values are within the check's tolerance of the right ones at a student's variant (a number
copied from a classmate who drew the same value, E1's scan without the delta cap) is no wrong answer
there: it is counted apart (``coincide``), in neither rate. Where the check names a mistake, the
hint is compared with the mistake the answer makes (**hint accuracy**). The rates are shares of this
corpus (each formulation on each student's variant one trial), with 95 % Wilson intervals
(:func:`scipy.stats.binomtest`): they say how often the grader errs on answers like these, not on a
class whose answers are distributed otherwise.
"""

from __future__ import annotations

import ast
import builtins
import contextlib
import io
import math
import re
import tempfile
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import nbformat
import numpy as np

from lorisnb.core.metrics import openloris as metrics
from lorisnb.core.simulate import Faults, simulated_errors
from lorisnb.io.datasets.paths import load_groundtruth, sample_data
from lorisnb.tools.teaching._checks import CORRECTNESS_CASES, CR_CASES, CSR_CASES, cases_from
from lorisnb.tools.teaching._sandbox_child import given
from lorisnb.tools.teaching.autograde import (
    PRELUDE,
    GradeSettings,
    LabSpec,
    RemoteFunction,
    hidden_seed,
    lab_spec,
    without_lorisnb,
)
from lorisnb.tools.teaching.sandbox import Limits, NotPlain, Sandbox, can_isolate, claim_uids, decode

LAB = "lab1_lifelong_metrics"
#: the secret the harness draws the hidden tests' seeds from (a course's is random; any one will do)
SECRET = "lorisnb-grading-error-rates"
HINT = re.compile(r"\nHint \(([^)]+)\):")


@dataclass(frozen=True)
class Answer:
    """One answer cell as a student writes it: ``source`` for the cell ``cell`` (its grade_id);
    ``right``: a right answer; ``mistake``: the name in MISTAKES of the mistake it makes (a wrong
    answer whose mistake the registry names), else None; ``kind``: what sort of variant it is."""

    cell: str
    name: str
    source: str
    right: bool
    mistake: str | None = None
    kind: str = "written"  # written (in the corpus), edge (at the tolerance), perturbed, copied


def _r(cell: str, pairs: Iterable[tuple[str, str]]) -> list[Answer]:
    return [Answer(cell, name, src, True) for name, src in pairs]


def _w(cell: str, rows: Iterable[tuple[str, str | None, str]]) -> list[Answer]:
    return [Answer(cell, name, src, False, mistake) for name, mistake, src in rows]


def _fn(signature: str, body: str) -> str:
    """A function answer: ``def signature:`` and its body (lines indented here)."""
    return f"def {signature}:\n" + "".join(f"    {line}\n" for line in body.strip("\n").splitlines())


def _visible_crs() -> dict[tuple[float, float], float]:
    """CR on the check's visible cases, by (t_min, delta): what a learner copies from the visible
    checks' messages into a function that passes them (the hidden cases are real sequences)."""
    return {
        (float(c["t_min"]), float(c["delta"])): float(
            metrics.correct_rate(metrics.correct_time(c["stamps"], c["correct"], c["t_max"], c["delta"], c["t_min"]),
                                 c["t_min"], c["t_max"])
        )
        for c in CR_CASES
    }  # fmt: skip


_A1 = "correctness(ate_m, aoe_deg, eps, phi)"
_B2 = "correct_rate(stamps, correct, t_min, t_max, delta)"
_C1 = "cs_r(t0, t_min, first_correct, tau)"
_HELD = "held = np.minimum(np.diff(np.append(stamps, t_max)), delta)"
_EXP = "np.exp(-(t0 - t_min) / tau)"

# --- the corpus: formulas ----------------------------------------------------------------------

A1_RIGHT = _r("A1_correctness", [
    ("logical_and", _fn(_A1, "return np.logical_and(ate_m <= eps, aoe_deg <= phi)")),
    ("not greater", _fn(_A1, "return ~(ate_m > eps) & ~(aoe_deg > phi)")),
    ("De Morgan", _fn(_A1, "return ~((ate_m > eps) | (aoe_deg > phi))")),
    ("loop into an array", _fn(_A1, "out = np.zeros(len(ate_m), dtype=bool)\nfor k in range(len(ate_m)):\n"
                                    "    out[k] = ate_m[k] <= eps and aoe_deg[k] <= phi\nreturn out")),
    ("list of numpy bools", _fn(_A1, "return [a <= eps and o <= phi for a, o in zip(ate_m, aoe_deg)]")),
    ("list of Python bools", _fn(_A1, "return [bool(a <= eps) and bool(o <= phi) for a, o in zip(ate_m, aoe_deg)]")),
    ("tuple of bools", _fn(_A1, "return tuple(bool(a <= eps and o <= phi) for a, o in zip(ate_m, aoe_deg))")),
    ("np.where", _fn(_A1, "return np.where(ate_m <= eps, aoe_deg <= phi, False)")),
    ("boolean product", _fn(_A1, "return (ate_m <= eps) * (aoe_deg <= phi)")),
    ("float32", _fn(_A1, "return (np.float32(ate_m) <= np.float32(eps)) & (np.float32(aoe_deg) <= np.float32(phi))")),
    ("np.all over a stack", _fn(_A1, "return np.all([ate_m <= eps, aoe_deg <= phi], axis=0)")),
    ("difference <= 0", _fn(_A1, "return (ate_m - eps <= 0) & (aoe_deg - phi <= 0)")),
    ("np.minimum of bools", _fn(_A1, "return np.minimum(ate_m <= eps, aoe_deg <= phi)")),
    ("both in radians", _fn(_A1, "return (ate_m <= eps) & (np.radians(aoe_deg) <= np.radians(phi))")),
    ("in place &=", _fn(_A1, "c = np.asarray(ate_m) <= eps\nc &= np.asarray(aoe_deg) <= phi\nreturn c")),
    ("less_equal ufunc", _fn(_A1, "return np.less_equal(ate_m, eps) & np.less_equal(aoe_deg, phi)")),
])  # fmt: skip

A1_WRONG = _w("A1_correctness", [
    ("or", "and_or", _fn(_A1, "return (ate_m <= eps) | (aoe_deg <= phi)")),
    ("strict", "inclusive", _fn(_A1, "return (ate_m < eps) & (aoe_deg < phi)")),
    ("strict ATE", "inclusive", _fn(_A1, "return (ate_m < eps) & (aoe_deg <= phi)")),
    ("phi in radians", "degrees_radians", _fn(_A1, "return (ate_m <= eps) & (aoe_deg <= np.radians(phi))")),
    ("AOE in radians", "degrees_radians", _fn(_A1, "return (ate_m <= eps) & (np.deg2rad(aoe_deg) <= phi)")),
    ("thresholds swapped", "swapped", _fn(_A1, "return (ate_m <= phi) & (aoe_deg <= eps)")),
    ("ATE only", "ate_only", _fn(_A1, "return np.asarray(ate_m) <= eps")),
    ("AOE only", "aoe_only", _fn(_A1, "return np.asarray(aoe_deg) <= phi")),
    ("Python and", "elementwise", _fn(_A1, "return ate_m <= eps and aoe_deg <= phi")),
    ("renamed arguments", "signature", _fn("correctness(ate, aoe, eps, phi)", "return (ate <= eps) & (aoe <= phi)")),
    ("xor", None, _fn(_A1, "return (ate_m <= eps) ^ (aoe_deg <= phi)")),
    ("comparisons flipped", None, _fn(_A1, "return (ate_m >= eps) & (aoe_deg >= phi)")),
    ("shifted by one pose", None, _fn(_A1, "c = (ate_m <= eps) & (aoe_deg <= phi)\nreturn np.append(c[1:], c[-1])")),
    ("last pose dropped", None, _fn(_A1, "return ((ate_m <= eps) & (aoe_deg <= phi))[:-1]")),
    ("half phi", None, _fn(_A1, "return (ate_m <= eps) & (aoe_deg <= phi / 2)")),
    ("a 1 cm margin on eps", None, _fn(_A1, "return (ate_m <= eps + 0.01) & (aoe_deg <= phi)")),
    ("one pose flipped", None, _fn(_A1, "c = (ate_m <= eps) & (aoe_deg <= phi)\nc[len(c) // 2] = ~c[len(c) // 2]\n"
                                        "return c")),
])  # fmt: skip

B2_RIGHT = _r("B2_correct_rate", [
    ("loop", _fn(_B2, "total = 0.0\nfor k in range(len(stamps)):\n"
                      "    following = stamps[k + 1] if k + 1 < len(stamps) else t_max\n"
                      "    if correct[k]:\n        total += min(following - stamps[k], delta)\n"
                      "return total / (t_max - t_min)")),
    ("diff append= and a mask", _fn(_B2, "dt = np.diff(stamps, append=t_max)\n"
                                        "return np.sum(np.clip(dt, None, delta)[correct]) / (t_max - t_min)")),
    ("capped with >=", _fn(_B2, "dt = np.diff(np.append(stamps, t_max))\n"
                               "return float(np.sum(np.where(dt >= delta, delta, dt) * correct) / (t_max - t_min))")),
    ("np.where and np.dot", _fn(_B2, "dt = np.diff(np.append(stamps, t_max))\n"
                                    "return np.dot(np.where(dt > delta, delta, dt), correct) / (t_max - t_min)")),
    ("reversed sum", _fn(_B2, f"{_HELD}\nreturn float(np.sum((held * correct)[::-1]) / (t_max - t_min))")),
    ("math.fsum", _fn(_B2, f"{_HELD}\nreturn math.fsum(held * correct) / (t_max - t_min)")),
    ("cumsum", _fn(_B2, f"{_HELD}\nreturn np.cumsum(held * correct)[-1] / (t_max - t_min)")),
    ("mean times count", _fn(_B2, f"{_HELD}\nreturn np.mean(held * correct) * len(stamps) / (t_max - t_min)")),
    ("matmul, numpy scalar", _fn(_B2, f"{_HELD}\nreturn (held @ correct) / (t_max - t_min)")),
    ("next stamps by slicing", _fn(_B2, "held = np.minimum(np.append(stamps[1:], t_max) - stamps, delta)\n"
                                       "return float(np.sum(held * correct) / (t_max - t_min))")),
    ("rounded to 12 places", _fn(_B2, f"{_HELD}\nreturn round(float(np.sum(held * correct) / (t_max - t_min)), 12)")),
    ("0-d array", _fn(_B2, f"{_HELD}\nreturn np.array(np.sum(held * correct) / (t_max - t_min))")),
    ("sum where=", _fn(_B2, "held = np.fmin(np.diff(np.append(stamps, t_max)), delta)\n"
                           "return np.sum(held, where=np.asarray(correct, bool)) / (t_max - t_min)")),
    ("each term divided", _fn(_B2, f"{_HELD}\nreturn np.sum(held * correct / (t_max - t_min))")),
    ("one minus the rest", _fn(_B2, f"{_HELD}\nT = t_max - t_min\nreturn 1 - (T - np.sum(held * correct)) / T")),
    ("generator over zip", _fn(_B2, "following = list(stamps[1:]) + [t_max]\n"
                                   "return sum(min(b - a, delta) for a, b, c in zip(stamps, following, correct) if c) "
                                   "/ (t_max - t_min)")),
    ("float32 weights", _fn(_B2, f"{_HELD}\nreturn float(np.sum(held * np.asarray(correct).astype(np.float32)) "
                                 "/ (t_max - t_min))")),
    ("correct as floats", _fn(_B2, f"{_HELD}\nreturn float(np.sum(held * np.asarray(correct, float)) / (t_max - t_min))")),
])  # fmt: skip

B2_WRONG = _w("B2_correct_rate", [
    ("over t_max - t0", "cr_vs_crt", _fn(_B2, f"{_HELD}\nreturn float(np.sum(held * correct) / (t_max - stamps[0]))")),
    ("no delta cap", "delta_cap", _fn(_B2, "held = np.diff(np.append(stamps, t_max))\n"
                                          "return float(np.sum(held * correct) / (t_max - t_min))")),
    ("wrong poses count", "wrong_poses_count", _fn(_B2, f"{_HELD}\nreturn float(np.sum(held) / (t_max - t_min))")),
    ("last pose dropped", "last_pose", _fn(_B2, "held = np.minimum(np.diff(stamps), delta)\n"
                                              "return float(np.sum(held * correct[:-1]) / (t_max - t_min))")),
    ("last pose holds delta", "last_pose", _fn(_B2, "held = np.append(np.minimum(np.diff(stamps), delta), delta)\n"
                                                  "return float(np.sum(held * correct) / (t_max - t_min))")),
    ("last pose uncapped", "last_pose", _fn(_B2, "held = np.append(np.minimum(np.diff(stamps), delta), t_max - stamps[-1])\n"
                                               "return float(np.sum(held * correct) / (t_max - t_min))")),
    ("held backward", "held_backward", _fn(_B2, "held = np.minimum(np.diff(stamps, prepend=t_min), delta)\n"
                                              "return float(np.sum(held * correct) / (t_max - t_min))")),
    ("credited to the next pose", "held_backward", _fn(_B2, "held = np.minimum(np.diff(stamps), delta)\n"
                                                          "return float(np.sum(held * correct[1:]) / (t_max - t_min))")),
    ("each holds delta", "held_delta", _fn(_B2, "return float(np.count_nonzero(correct) * delta / (t_max - t_min))")),
    ("long gaps dropped", "delta_cut", _fn(_B2, "dt = np.diff(np.append(stamps, t_max))\n"
                                              "return float(np.sum(np.where(dt <= delta, dt, 0) * correct) "
                                              "/ (t_max - t_min))")),
    ("share of poses", "poses_not_time", _fn(_B2, "return float(np.mean(correct))")),
    ("over the estimate's span", "gt_span", _fn(_B2, f"{_HELD}\nreturn float(np.sum(held * correct) "
                                                     "/ (stamps[-1] - stamps[0]))")),
    ("over t_max", "absolute_time", _fn(_B2, f"{_HELD}\nreturn float(np.sum(held * correct) / t_max)")),
    ("percent", "fraction", _fn(_B2, f"{_HELD}\nreturn 100 * float(np.sum(held * correct) / (t_max - t_min))")),
    ("renamed arguments", "signature", _fn("correct_rate(t, c, t_min, t_max, delta)",
                                           "held = np.minimum(np.diff(np.append(t, t_max)), delta)\n"
                                           "return float(np.sum(held * c) / (t_max - t_min))")),
    ("denominator sign", None, _fn(_B2, f"{_HELD}\nreturn float(np.sum(held * correct) / (t_min - t_max))")),
    ("one minus the wrong time", None, _fn(_B2, f"{_HELD}\nc = np.asarray(correct, bool)\n"
                                                "return float(1 - np.sum(held * ~c) / (t_max - t_min))")),
    ("delta in milliseconds", None, _fn(_B2, "held = np.minimum(np.diff(np.append(stamps, t_max)), delta / 1000)\n"
                                            "return float(np.sum(held * correct) / (t_max - t_min))")),
    ("denominator plus delta", None, _fn(_B2, f"{_HELD}\nreturn float(np.sum(held * correct) "
                                              "/ (t_max - t_min + delta))")),
    ("one part in a million off", None, _fn(_B2, f"{_HELD}\nreturn float(np.sum(held * correct) "
                                                 "/ (t_max - t_min)) * (1 + 1e-6)")),
    ("fitted to the visible cases", None, _fn(_B2, f"known = {_visible_crs()!r}\n"
                                                  "return known.get((float(t_min), float(delta)), 0.5)")),
])  # fmt: skip

C1_RIGHT = _r("C1_cs_r", [
    ("times the boolean", _fn(_C1, f"return {_EXP} * first_correct")),
    ("math.exp, int 0", _fn(_C1, "return math.exp((t_min - t0) / tau) if first_correct else 0")),
    ("float of the boolean", _fn(_C1, f"return float(first_correct) * {_EXP}")),
    ("np.where, 0-d array", _fn(_C1, f"return np.where(first_correct, {_EXP}, 0.0)")),
    ("one over exp", _fn(_C1, "return 1 / np.exp((t0 - t_min) / tau) * first_correct")),
    ("power of e", _fn(_C1, "return np.e ** (-(t0 - t_min) / tau) if first_correct else 0.0")),
    ("is True", _fn(_C1, f"if first_correct is True:\n    return float({_EXP})\nreturn 0.0")),
    ("early return, numpy scalar", _fn(_C1, f"if not first_correct:\n    return 0.0\nreturn {_EXP}")),
    ("np.subtract, int()", _fn(_C1, "return np.exp(-np.subtract(t0, t_min) / tau) * int(first_correct)")),
    ("power of 2", _fn(_C1, "return 2 ** (-(t0 - t_min) / (tau * np.log(2))) if first_correct else 0.0")),
    ("== 1", _fn(_C1, f"return {_EXP} if first_correct == 1 else 0")),
    ("rounded to 12 places", _fn(_C1, f"return round(float({_EXP}), 12) if first_correct else 0.0")),
])  # fmt: skip

C1_WRONG = _w("C1_cs_r", [
    ("first pose ignored", "first_pose", _fn(_C1, f"return float({_EXP})")),
    ("stamp alone", "absolute_time", _fn(_C1, "return float(np.exp(-t0 / tau)) if first_correct else 0.0")),
    ("tau over the wait", "tau_inverted", _fn(_C1, "return float(np.exp(-tau / (t0 - t_min))) * first_correct")),
    ("times tau", "tau_inverted", _fn(_C1, "return float(np.exp(-(t0 - t_min) * tau)) * first_correct")),
    ("positive exponent", "tau_sign", _fn(_C1, "return float(np.exp((t0 - t_min) / tau)) * first_correct")),
    ("linear", "linear", _fn(_C1, "return (1 - (t0 - t_min) / tau) * first_correct")),
    ("percent", "fraction", _fn(_C1, f"return 100 * float({_EXP}) * first_correct")),
    ("NaN when wrong", "nan", _fn(_C1, f"return float({_EXP}) if first_correct else float('nan')")),
    ("renamed arguments", "signature", _fn("cs_r(t_first, t_start, ok, tau)",
                                           "return float(np.exp(-(t_first - t_start) / tau)) * ok")),
    ("tau in minutes", None, _fn(_C1, "return float(np.exp(-(t0 - t_min) / (60 * tau))) * first_correct")),
    ("one minus", None, _fn(_C1, f"return (1 - float({_EXP})) * first_correct")),
    ("a second late", None, _fn(_C1, "return float(np.exp(-(t0 - t_min + 1) / tau)) * first_correct")),
    ("boolean inverted", None, _fn(_C1, f"return float({_EXP}) * (not first_correct)")),
    ("squared", None, _fn(_C1, f"return float({_EXP}) ** 2 * first_correct")),
    ("base 10", None, _fn(_C1, "return 10 ** (-(t0 - t_min) / tau) * first_correct")),
])  # fmt: skip

# --- the corpus: predictions -------------------------------------------------------------------

_LOST = "(lost_window[1] - lost_window[0])"
B1_RIGHT = _r("B1_prediction", [
    ("delta subtracted", f"predicted_cr_lost = 1 - ({_LOST} - delta) / T\n"),
    ("what is kept", f"predicted_cr_lost = (T - {_LOST} + delta) / T\n"),
    ("unpacked, max", "start, end = lost_window\npredicted_cr_lost = (T - max(end - start - delta, 0)) / T\n"),
    ("numpy scalar", f"predicted_cr_lost = np.float64(1 - ({_LOST} - min(delta, {_LOST})) / T)\n"),
    ("float32", f"predicted_cr_lost = np.float32(1 - ({_LOST} - delta) / T)\n"),
    ("rounded to 2 places", f"predicted_cr_lost = round(1 - ({_LOST} - delta) / T, 2)\n"),
    ("rounded to 3 places", f"predicted_cr_lost = round(1 - ({_LOST} - delta) / T, 3)\n"),
    ("np.diff, a 1-element array", "predicted_cr_lost = 1 - (np.diff(lost_window) - delta) / T\n"),
])  # fmt: skip
B1_WRONG = _w("B1_prediction", [
    ("no delta cap", "delta_cap", "predicted_cr_lost = 1.0\n"),
    ("the gap all lost", "gap_last_pose", f"predicted_cr_lost = 1 - {_LOST} / T\n"),
    ("percent", "fraction", f"predicted_cr_lost = 100 * (1 - ({_LOST} - delta) / T)\n"),
    ("the lost share", None, f"predicted_cr_lost = {_LOST} / T\n"),
    ("delta added", None, f"predicted_cr_lost = 1 - ({_LOST} + delta) / T\n"),
    ("the end of the gap", None, "predicted_cr_lost = 1 - lost_window[1] / T\n"),
    ("half", None, "predicted_cr_lost = 0.5\n"),
])  # fmt: skip

B3_RIGHT = _r("B3_prediction", [
    ("int 1", "predicted_cr_t_late = 1\n"),
    ("numpy scalar", "predicted_cr_t_late = np.float64(1.0)\n"),
    ("the formula", "predicted_cr_t_late = (T - late_start) / (T - late_start)\n"),
    ("float32", "predicted_cr_t_late = np.float32(1)\n"),
    ("nothing lost", "predicted_cr_t_late = 1 - 0 / T\n"),
])  # fmt: skip
B3_WRONG = _w("B3_prediction", [
    ("CR", "crt_vs_cr", "predicted_cr_t_late = 1 - late_start / T\n"),
    ("percent", "fraction", "predicted_cr_t_late = 100.0\n"),
    ("the late share", None, "predicted_cr_t_late = late_start / T\n"),
    ("zero", None, "predicted_cr_t_late = 0.0\n"),
    ("over the rest", None, "predicted_cr_t_late = 1 - late_start / (T - late_start)\n"),
    ("stretched", None, "predicted_cr_t_late = T / (T + late_start)\n"),
])  # fmt: skip

C2_RIGHT = _r("C2_prediction", [
    ("int 0", "predicted_cs_r_wrong = 0\n"),
    ("numpy scalar", "predicted_cs_r_wrong = np.float64(0.0)\n"),
    ("times False", "predicted_cs_r_wrong = float(np.exp(-reloc_delay / tau) * False)\n"),
    ("zero times", "predicted_cs_r_wrong = 0 * math.exp(-reloc_delay / tau)\n"),
    ("minus zero", "predicted_cs_r_wrong = -0.0\n"),
    ("int(False)", "predicted_cs_r_wrong = int(False)\n"),
])  # fmt: skip
C2_WRONG = _w("C2_prediction", [
    ("first pose ignored", "first_pose", "predicted_cs_r_wrong = float(np.exp(-reloc_delay / tau))\n"),
    ("percent of it", None, "predicted_cs_r_wrong = 100 * float(np.exp(-reloc_delay / tau))\n"),
    ("one", None, "predicted_cs_r_wrong = 1.0\n"),
    ("tau over the delay", None, "predicted_cs_r_wrong = float(np.exp(-tau / reloc_delay))\n"),
    ("one minus", None, "predicted_cs_r_wrong = 1 - float(np.exp(-reloc_delay / tau))\n"),
    ("half", None, "predicted_cs_r_wrong = 0.5\n"),
])  # fmt: skip

# --- the corpus: numbers computed with the lab ---------------------------------------------------

_SCORE = "ln.score(simulated_errors(gt, wrong_reloc, seqs=[1, 2]{mode}), eps, phi, delta, tau)"
_LIFE, _PER = _SCORE.format(mode=""), _SCORE.format(mode=", mode='per-seq'")
D1_RIGHT = _r("D1_alignment", [
    ("simulate_and_score", "cr_visit2_lifelong = t_wrong.loc[2, 'cr']\n"
                           "cr_visit2_per_seq = simulate_and_score(wrong_reloc, seqs=(1, 2), mode='per-seq')[1]"
                           ".loc[2, 'cr']\n"),
    ("query, iloc", f"cr_visit2_lifelong = {_LIFE}.query('seq == 2')['cr'].iloc[0]\n"
                    f"cr_visit2_per_seq = {_PER}.query('seq == 2')['cr'].iloc[0]\n"),
    ("1-row Series", f"cr_visit2_lifelong = {_LIFE}.query('seq == 2')['cr']\n"
                     f"cr_visit2_per_seq = {_PER}.query('seq == 2')['cr']\n"),
    ("rounded as printed", f"cr_visit2_lifelong = round(float({_LIFE}.set_index('seq').loc[2, 'cr']), 3)\n"
                           f"cr_visit2_per_seq = round(float({_PER}.set_index('seq').loc[2, 'cr']), 3)\n"),
    ("float32", f"cr_visit2_lifelong = np.float32({_LIFE}.set_index('seq').loc[2, 'cr'])\n"
                f"cr_visit2_per_seq = np.float32({_PER}.set_index('seq').loc[2, 'cr'])\n"),
])  # fmt: skip
D1_WRONG = _w("D1_alignment", [
    ("per sequence for both", "alignment", f"cr_visit2_lifelong = cr_visit2_per_seq = {_PER}.set_index('seq')"
                                           ".loc[2, 'cr']\n"),
    ("lifelong for both", "alignment", f"cr_visit2_lifelong = cr_visit2_per_seq = {_LIFE}.set_index('seq')"
                                       ".loc[2, 'cr']\n"),
    ("swapped", "alignment", f"cr_visit2_lifelong = {_PER}.set_index('seq').loc[2, 'cr']\n"
                             f"cr_visit2_per_seq = {_LIFE}.set_index('seq').loc[2, 'cr']\n"),
    ("CR-T", None, f"cr_visit2_lifelong = {_LIFE}.set_index('seq').loc[2, 'cr_t']\n"
                   f"cr_visit2_per_seq = {_PER}.set_index('seq').loc[2, 'cr_t']\n"),
    ("visit 1", None, f"cr_visit2_lifelong = {_LIFE}.set_index('seq').loc[1, 'cr']\n"
                      f"cr_visit2_per_seq = {_PER}.set_index('seq').loc[1, 'cr']\n"),
    ("percent", None, f"cr_visit2_lifelong = 100 * {_LIFE}.set_index('seq').loc[2, 'cr']\n"
                      f"cr_visit2_per_seq = 100 * {_PER}.set_index('seq').loc[2, 'cr']\n"),
])  # fmt: skip

_EPS = "eps_at_cr(ev_orb.errors, target_cr, ev_orb.durations(), {phi}, {delta})['eps']"
_IMPORT = "from lorisnb.core.lifelong.sweep import eps_at_cr\n"
_SCAN = ("eps_for_cr = next(e for e in {grid} "
         "if ev_orb.scenes(eps=e, phi=phi, delta=delta, tau=tau)['cr'].iloc[0] >= target_cr)\n")  # fmt: skip
E1_RIGHT = _r("E1_threshold", [
    ("item()", _IMPORT + f"eps_for_cr = {_EPS.format(phi='phi', delta='delta')}.item()\n"),
    ("a 1-row Series", _IMPORT + f"eps_for_cr = {_EPS.format(phi='phi', delta='delta')}\n"),
    ("rounded to 3 places", _IMPORT + f"eps_for_cr = round(float({_EPS.format(phi='phi', delta='delta')}.iloc[0]), 3)\n"),
    ("rounded to 2 places", _IMPORT + f"eps_for_cr = round(float({_EPS.format(phi='phi', delta='delta')}.iloc[0]), 2)\n"),
    ("float32", _IMPORT + f"eps_for_cr = np.float32({_EPS.format(phi='phi', delta='delta')}.iloc[0])\n"),
    ("a 1 cm scan", _SCAN.format(grid="np.round(np.arange(0.40, 2.0, 0.01), 2)")),
    ("bisection", "lo, hi = 0.0, 2.0\nfor _ in range(30):\n    mid = (lo + hi) / 2\n"
                  "    if ev_orb.scenes(eps=mid, phi=phi, delta=delta, tau=tau)['cr'].iloc[0] >= target_cr:\n"
                  "        hi = mid\n    else:\n        lo = mid\neps_for_cr = hi\n"),
])  # fmt: skip
E1_WRONG = _w("E1_threshold", [
    ("phi left out", "phi_ignored", _IMPORT + f"eps_for_cr = {_EPS.format(phi='np.inf', delta='delta')}.iloc[0]\n"),
    ("phi in radians", "degrees_radians", _IMPORT + f"eps_for_cr = {_EPS.format(phi='np.radians(phi)', delta='delta')}"
                                                    ".iloc[0]\n"),
    ("the curve's grid", "coarse_grid", _SCAN.format(grid="np.linspace(0.05, 2.0, 40)")),
    ("a 10 cm grid", "coarse_grid", _SCAN.format(grid="np.round(np.arange(0.1, 2.01, 0.1), 2)")),
    ("no delta cap", "delta_cap", _IMPORT + f"eps_for_cr = {_EPS.format(phi='phi', delta='np.inf')}.iloc[0]\n"),
    ("in centimetres", None, _IMPORT + f"eps_for_cr = 100 * {_EPS.format(phi='phi', delta='delta')}.iloc[0]\n"),
    ("target in percent", None, _IMPORT + "eps_for_cr = eps_at_cr(ev_orb.errors, 100 * target_cr, ev_orb.durations(), "
                                          "phi, delta)['eps'].iloc[0]\n"),
])  # fmt: skip

_BEST = "life_scenes.sort_values('{by}', ascending=False).iloc[{k}]"
_SILENT = "silent_in_visit2 = int(((life['seq'] == 2) & (life['matched'] == 0)).sum())\n"
F_RIGHT = _r("F_timeline", [
    ("idxmax", _SILENT + "best_algorithm = life_scenes.loc[life_scenes['cr'].idxmax(), 'algorithm']\n"
                         "best_cr = life_scenes['cr'].max()\n"),
    ("len, numpy count", "silent_in_visit2 = len(life[(life.seq == 2) & (life.matched == 0)])\n"
                         f"best_algorithm = {_BEST.format(by='cr', k=0)}['algorithm']\n"
                         f"best_cr = {_BEST.format(by='cr', k=0)}['cr']\n"),
    ("a numpy integer", "silent_in_visit2 = ((life['seq'] == 2) & (life['matched'] == 0)).sum()\n"
                        f"best_algorithm = {_BEST.format(by='cr', k=0)}['algorithm']\n"
                        f"best_cr = float({_BEST.format(by='cr', k=0)}['cr'])\n"),
    ("name in capitals", _SILENT + f"best_algorithm = {_BEST.format(by='cr', k=0)}['algorithm'].upper()\n"
                                   f"best_cr = {_BEST.format(by='cr', k=0)}['cr']\n"),
    ("name with a space", _SILENT + f"best_algorithm = {_BEST.format(by='cr', k=0)}['algorithm'] + ' '\n"
                                    f"best_cr = {_BEST.format(by='cr', k=0)}['cr']\n"),
    ("a numpy string", _SILENT + "names = np.array(life_scenes['algorithm'].tolist())\n"
                                 "best_algorithm = names[np.argmax(life_scenes['cr'].to_numpy())]\n"
                                 "best_cr = float(np.max(life_scenes['cr'].to_numpy()))\n"),
    ("read off the figure", _SILENT + f"best_algorithm = {_BEST.format(by='cr', k=0)}['algorithm']\n"
                                      f"best_cr = round(100 * {_BEST.format(by='cr', k=0)}['cr'], 1) / 100\n"),
    ("float32", _SILENT + f"best_algorithm = {_BEST.format(by='cr', k=0)}['algorithm']\n"
                          f"best_cr = np.float32({_BEST.format(by='cr', k=0)}['cr'])\n"),
])  # fmt: skip
F_WRONG = _w("F_timeline", [
    ("by CR-T", "cr_vs_crt", _SILENT + f"best_algorithm = {_BEST.format(by='cr_t', k=0)}['algorithm']\n"
                                       f"best_cr = {_BEST.format(by='cr_t', k=0)}['cr_t']\n"),
    ("percent", "fraction", _SILENT + f"best_algorithm = {_BEST.format(by='cr', k=0)}['algorithm']\n"
                                      f"best_cr = round(100 * {_BEST.format(by='cr', k=0)}['cr'], 1)\n"),
    ("the C-ATE label", "timeline_label", _SILENT + f"best_algorithm = {_BEST.format(by='cr', k=0)}['algorithm']\n"
                                                    f"best_cr = round({_BEST.format(by='cr', k=0)}['c_ate_rmse'], 3)\n"),
    ("one silent more", None, "silent_in_visit2 = int(((life['seq'] == 2) & (life['matched'] == 0)).sum()) + 1\n"
                              f"best_algorithm = {_BEST.format(by='cr', k=0)}['algorithm']\n"
                              f"best_cr = {_BEST.format(by='cr', k=0)}['cr']\n"),
    ("visit 1's silent", None, "silent_in_visit2 = int(((life['seq'] == 1) & (life['matched'] == 0)).sum())\n"
                               f"best_algorithm = {_BEST.format(by='cr', k=0)}['algorithm']\n"
                               f"best_cr = {_BEST.format(by='cr', k=0)}['cr']\n"),
    ("the second best", None, _SILENT + f"best_algorithm = {_BEST.format(by='cr', k=1)}['algorithm']\n"
                                        f"best_cr = {_BEST.format(by='cr', k=1)}['cr']\n"),
    ("the worst", None, _SILENT + f"best_algorithm = {_BEST.format(by='cr', k=-1)}['algorithm']\n"
                                  f"best_cr = {_BEST.format(by='cr', k=-1)}['cr']\n"),
])  # fmt: skip

_PCT = "orb_seq['ate_rmse'] / gt_seq.path_length"
G1_RIGHT = _r("G1_difficulty", [
    ("attributes", "ate_percent_cafe = orb_seq.ate_rmse / gt_seq.path_length * 100\n"),
    ("path length by hand", "steps = np.diff(gt_seq.positions, axis=0)\n"
                            "ate_percent_cafe = 100 * orb_seq['ate_rmse'] / np.sum(np.linalg.norm(steps, axis=1))\n"),
    ("rounded to 2 places", f"ate_percent_cafe = round(100 * float({_PCT}), 2)\n"),
    ("float32", f"ate_percent_cafe = np.float32(100 * {_PCT})\n"),
    ("Python floats", "ate_percent_cafe = 100 * float(orb_seq['ate_rmse']) / float(gt_seq.path_length)\n"),
])  # fmt: skip
G1_WRONG = _w("G1_difficulty", [
    ("a ratio", "percent", f"ate_percent_cafe = {_PCT}\n"),
    ("over the extent", "extent_vs_length", "ate_percent_cafe = 100 * orb_seq['ate_rmse'] / gt_seq.extent\n"),
    ("mean ATE", "rmse_vs_mean", "ate_percent_cafe = 100 * orb_seq['ate_mean'] / gt_seq.path_length\n"),
    ("C-ATE", "c_ate", "ate_percent_cafe = 100 * orb_seq['c_ate_rmse'] / gt_seq.path_length\n"),
    ("over the duration", None, "ate_percent_cafe = 100 * orb_seq['ate_rmse'] / gt_seq.duration\n"),
    ("cafe-1 always", None, "ate_percent_cafe = 100 * orb_seq['ate_rmse'] / gt.sequences[1].path_length\n"),
    ("millimetres", None, f"ate_percent_cafe = 1000 * {_PCT}\n"),
])  # fmt: skip

CORPUS: dict[str, list[Answer]] = {
    "A1_correctness": A1_RIGHT + A1_WRONG, "B1_prediction": B1_RIGHT + B1_WRONG,
    "B2_correct_rate": B2_RIGHT + B2_WRONG, "B3_prediction": B3_RIGHT + B3_WRONG, "C1_cs_r": C1_RIGHT + C1_WRONG,
    "C2_prediction": C2_RIGHT + C2_WRONG, "D1_alignment": D1_RIGHT + D1_WRONG, "E1_threshold": E1_RIGHT + E1_WRONG,
    "F_timeline": F_RIGHT + F_WRONG, "G1_difficulty": G1_RIGHT + G1_WRONG,
}  # fmt: skip

#: answer cell -> the typical mistakes its check can name (every one of MISTAKES applies to some cell)
APPLIES: dict[str, tuple[str, ...]] = {
    "A1_correctness": ("and_or", "inclusive", "degrees_radians", "swapped", "ate_only", "aoe_only", "elementwise",
                       "signature"),
    "B1_prediction": ("delta_cap", "gap_last_pose", "fraction"),
    "B2_correct_rate": ("cr_vs_crt", "delta_cap", "wrong_poses_count", "last_pose", "held_backward", "held_delta",
                        "delta_cut", "poses_not_time", "gt_span", "absolute_time", "fraction", "signature"),
    "B3_prediction": ("crt_vs_cr", "fraction"),
    "C1_cs_r": ("first_pose", "absolute_time", "tau_inverted", "tau_sign", "linear", "fraction", "nan", "signature"),
    "C2_prediction": ("first_pose",),
    "D1_alignment": ("alignment",),
    "E1_threshold": ("phi_ignored", "degrees_radians", "coarse_grid", "delta_cap"),
    "F_timeline": ("cr_vs_crt", "fraction", "timeline_label"),
    "G1_difficulty": ("percent", "extent_vs_length", "rmse_vs_mean", "c_ate"),
}  # fmt: skip

#: graded value -> the check's tolerance (absolute; None: a name, compared as the check does)
TOLERANCE: dict[str, float | None] = {
    "predicted_cr_lost": 0.01, "predicted_cr_t_late": 0.01, "predicted_cs_r_wrong": 0.01,
    "cr_visit2_lifelong": 0.005, "cr_visit2_per_seq": 0.005, "eps_for_cr": 0.01, "silent_in_visit2": 0.1,
    "best_algorithm": None, "best_cr": 0.005, "ate_percent_cafe": 0.05,
}  # fmt: skip
#: a prediction -> what its check compares it with (the test cell's reference, in the grader's run of the
#: lab); every other value's reference is what the instructor's solution computes there
REFERENCE: dict[str, str] = {
    "predicted_cr_lost": "cr_lost", "predicted_cr_t_late": "t_late.loc[1, 'cr_t']",
    "predicted_cs_r_wrong": "t_wrong.loc[2, 'cs_r']",
}  # fmt: skip
#: formula answer -> the check's tolerance (booleans: equal)
FORMULA_TOL = 1e-9
#: values that are counts: no answer "at the edge of the tolerance" is made of them (1.9 algorithms)
COUNTS = ("silent_in_visit2",)


def instructor_solutions(spec: LabSpec) -> list[Answer]:
    """The instructor's own answer cells, the first right answer of each cell."""
    out = []
    for cell in spec.notebook.cells:
        meta = cell.get("metadata", {}).get("nbgrader", {})
        if cell.cell_type == "code" and meta.get("solution"):
            source = re.sub(r"(?m)^[ \t]*### (BEGIN|END) SOLUTION[ \t]*\n?", "", cell.source)
            out.append(Answer(str(meta["grade_id"]), "the instructor's solution", source, True))
    return out


# --- the formulas' reference, for the corpus's own checks -----------------------------------------


def _formula_reference(cell: str) -> Callable[..., Any]:
    if cell == "A1_correctness":
        return metrics.correctness
    if cell == "B2_correct_rate":
        return lambda stamps, correct, t_min, t_max, delta: float(
            metrics.correct_rate(metrics.correct_time(stamps, correct, t_max, delta, t_min), t_min, t_max)
        )
    return lambda t0, t_min, first_correct, tau: float(metrics.relocalization_score(t0, t_min, first_correct, tau))


def hidden_cases(cell: str) -> list[dict[str, Any]]:
    """Cases from real sequences (cafe of the sample data) made as the lab's hidden tests make them,
    with their faults and thresholds at hidden seed 0 (the grader draws its own from its secret)."""
    gt = load_groundtruth("cafe", sample_data())
    if cell == "A1_correctness":
        fe = simulated_errors(gt, Faults(position_noise_m=0.4, orientation_noise_deg=12.0, seed=7), seqs=[1])
        return cases_from(fe, 0.5, 15.0, 1.0, 60.0)["correctness"]
    if cell == "B2_correct_rate":
        fe = simulated_errors(
            gt,
            {1: Faults(position_noise_m=0.3, lost=((5.0, 9.0),), rate_hz=2.0, seed=3),
             2: Faults(init_delay_s=12.0, yaw_drift_deg_per_m=1.0)},
            seqs=[1, 2],
        )  # fmt: skip
        return cases_from(fe, 0.5, 10.0, 0.3, 60.0)["correct_rate"]
    rng = np.random.default_rng(11)  # the lab's draw of the delays and tau at hidden seed 0
    d1, d2, tau = (round(float(rng.uniform(a, b)), 1) for a, b in ((4.0, 10.0), (1.0, 5.0), (15.0, 35.0)))
    fe = simulated_errors(gt, {1: Faults(init_delay_s=d1), 2: Faults(wrong_reloc_at_s=0.0, init_delay_s=d2)},
                          seqs=[1, 2])  # fmt: skip
    return cases_from(fe, 1.0, 30.0, 1.0, tau)["cs_r"]


def formula_cases(cell: str) -> list[dict[str, Any]]:
    """The check's visible cases and :func:`hidden_cases`: where a formula answer is told right or wrong."""
    visible = {"A1_correctness": CORRECTNESS_CASES, "B2_correct_rate": CR_CASES, "C1_cs_r": CSR_CASES}[cell]
    return [*visible, *hidden_cases(cell)]


def formula_differs(answer: Answer, cases: Sequence[Mapping[str, Any]], name: str) -> bool:
    """Whether a formula answer, run here with numpy, differs from lorisnb's formula on one of
    ``cases`` by more than the check's tolerance (or fails, or returns another shape); ``name``:
    the function the answer defines, called with the check's argument names."""
    ns: dict[str, Any] = {}
    exec(compile(PRELUDE + answer.source, f"<answer {answer.cell}: {answer.name}>", "exec"), ns)  # noqa: S102
    fn = ns[name]
    reference = _formula_reference(answer.cell)
    for case in cases:
        args = {k: (np.array(v, copy=True) if isinstance(v, np.ndarray) else v) for k, v in case.items()}
        try:
            with np.errstate(all="ignore"):
                got = np.asarray(fn(**args), float)
        except Exception:  # noqa: BLE001 (an answer that fails on a case differs there)
            return True
        want = np.asarray(reference(**case), float)
        if got.shape != want.shape or not np.allclose(got, want, rtol=FORMULA_TOL, atol=FORMULA_TOL, equal_nan=True):
            return True
    return False


# --- what the grader read, and its verdicts --------------------------------------------------------


@dataclass
class Verdict:
    """One answer graded at one student's variant: ``passed`` (its question's points), the check's
    message, the hints it named; ``coincide``: a wrong answer within the tolerance of the right one
    there (counted in neither rate)."""

    student: str
    question: str
    answer: Answer
    passed: bool
    message: str
    hints: tuple[str, ...] = ()
    coincide: bool = False
    values: dict[str, Any] = field(default_factory=dict)


def hints_in(message: str) -> tuple[str, ...]:
    """The mistakes a check's message names (``Hint (delta cap): ...`` -> ``delta_cap``)."""
    return tuple(h.replace(" ", "_") for h in HINT.findall(message))


def _value(plain: Mapping[str, Any]) -> Any:
    """A value the sandbox read back as the grader takes it (``autograde``: no value, and why, for an error)."""
    if "error" in plain:
        return NotPlain("no value", error=str(plain["error"]))
    return decode(dict(plain))


def _close(a: Any, b: Any, tol: float | None) -> bool:
    """Whether a graded value ``a`` is the right one ``b`` within the check's tolerance."""
    if tol is None:
        return isinstance(a, str) and a.strip().lower() == str(b).strip().lower()
    try:
        x = np.asarray(a, float)
    except (TypeError, ValueError):
        return False
    return x.size == 1 and abs(float(x.reshape(())) - float(b)) <= tol


def _scoped(tree: ast.AST) -> set[str]:
    """The names a comprehension binds (its own, not the cell's)."""
    return {t.id for c in ast.walk(tree) if isinstance(c, ast.comprehension) for t in ast.walk(c.target)
            if isinstance(t, ast.Name)}  # fmt: skip


def _loaded(source: str) -> set[str]:
    tree = ast.parse(source)
    return {n.id for n in ast.walk(tree) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)} - _scoped(tree)


def _bound(source: str) -> set[str]:
    tree = ast.parse(source)
    names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}
    names |= {n.name for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    names |= {(a.asname or a.name).split(".")[0] for n in ast.walk(tree)
              if isinstance(n, (ast.Import, ast.ImportFrom)) for a in n.names}  # fmt: skip
    return names - _scoped(tree)


def lab_names(spec: LabSpec) -> set[str]:
    """Every name the lab's own cells (not answers, not tests) bind."""
    names: set[str] = set()
    for cell in spec.notebook.cells:
        meta = cell.get("metadata", {}).get("nbgrader", {})
        if cell.cell_type == "code" and not meta.get("solution") and not meta.get("grade"):
            names |= _bound(cell.source)
    return names


def check_corpus(spec: LabSpec, answers: Iterable[Answer]) -> None:
    """Each answer reads only what its cell may read (the lab's names; a prediction's the lab's
    numbers before it, numpy and math; a formula its arguments) and binds none of the lab's names
    (they run one after another in one sandbox): else a ValueError naming it."""
    lab = lab_names(spec)
    builtin = set(dir(builtins)) | {"np", "math"}
    for a in answers:
        bound, loaded = _bound(a.source), _loaded(a.source)
        if spec.functions.get(a.cell):
            fn = next(n for n in ast.parse(a.source).body if isinstance(n, ast.FunctionDef))
            allowed = builtin | bound | {arg.arg for arg in fn.args.args}
        elif a.cell in spec.predictions:
            allowed = builtin | bound | set(spec.predictions[a.cell])
        else:
            allowed = builtin | bound | lab
        if loaded - allowed or (bound & lab and not spec.functions.get(a.cell)):
            raise ValueError(f"{a.cell} {a.name!r}: reads {sorted(loaded - allowed)}, binds {sorted(bound & lab)}")


# --- one student: the grader's run of the lab, the student's values, the test cells ------------------


def _parameters(source: str, params: Mapping[str, Any]) -> str:
    return source + "\n# injected by the error-rate harness\n" + "".join(f"{k} = {v!r}\n" for k, v in params.items())


def _exec(source: str, ns: dict[str, Any], name: str) -> None:
    with contextlib.redirect_stdout(io.StringIO()):
        exec(compile(source, name, "exec"), ns)  # noqa: S102 (the instructor's notebook, as the grader runs it)


class GraderRun:
    """The instructor's notebook run as the grader runs it for ``student`` (step 3 of
    :func:`.autograde.grade_submission`): the namespace before each answer cell (what a prediction is
    given) and at each test cell (where the check runs), and the instructor's values there (the
    right answers at this variant: a prediction's is what its check compares it with, :data:`REFERENCE`)."""

    def __init__(self, spec: LabSpec, student: str, out: Path) -> None:
        import matplotlib.pyplot as plt

        self.spec, self.student = spec, student
        self.before: dict[str, dict[str, Any]] = {}
        self.at_test: dict[str, dict[str, Any]] = {}
        params = {"student_id": student, "hidden_seed": hidden_seed(SECRET, student, spec.name), "output_dir": str(out)}
        ns: dict[str, Any] = {"__name__": "__main__"}
        for cell in spec.notebook.cells:
            meta = cell.get("metadata", {}).get("nbgrader", {})
            if cell.cell_type != "code":
                continue
            gid = str(meta.get("grade_id"))
            source = cell.source
            if "parameters" in cell.get("metadata", {}).get("tags", []):
                source = _parameters(source, params)
            if meta.get("solution"):
                self.before[gid] = dict(ns)
            if meta.get("grade"):
                self.at_test[gid] = dict(ns)
                continue
            _exec(source, ns, f"<instructor {gid}>")
            plt.close("all")
        self.right = {
            a: {n: eval(REFERENCE.get(n, n), dict(self.at_test[q.grade_id])) for n in spec.values[a]}  # noqa: S307
            for q in spec.questions
            for a in q.answers
        }  # the right values at this variant (the test cells' references)

    def grade(self, question: str, student: Mapping[str, Any]) -> tuple[bool, str]:
        """The test cell ``question`` with the student's values and functions in place of their names."""
        import matplotlib.pyplot as plt

        cell = next(c for c in self.spec.notebook.cells if c.get("metadata", {}).get("nbgrader", {}).get("grade_id")
                    == question)  # fmt: skip
        ns = dict(self.at_test[question])
        ns.update(student)
        buf = io.StringIO()
        try:
            with contextlib.redirect_stdout(buf):
                exec(compile(cell.source, f"<test {question}>", "exec"), ns)  # noqa: S102
            return True, buf.getvalue().strip()
        except Exception as exc:  # noqa: BLE001 (as the grader: a failed check, or the answer's own error)
            text = str(exc) if isinstance(exc, AssertionError) else f"{type(exc).__name__}: {exc}"
            return False, (buf.getvalue() + text).strip()
        finally:
            plt.close("all")


def _plain_values(values: Mapping[str, Any]) -> dict[str, str | float]:
    """Right values as a student types them: names as text, numbers as Python floats."""
    return {n: (str(v) if TOLERANCE[n] is None else float(v)) for n, v in values.items()}


def generated(run: GraderRun, others: Sequence[GraderRun], rng: np.random.Generator) -> list[Answer]:
    """The answers made of numbers at this student's variant: each right value at the edge of its
    tolerance (0.98 of it, either side; right by the check's stated rule), the right values
    perturbed beyond it (1.05 to 20 times, either side), and the right values of ``others``
    (classmates: copied numbers), for every answer that is a value (not a function)."""
    out = []
    for cell, right in run.right.items():
        if not right:
            continue

        def literal(values: Mapping[str, Any]) -> str:
            return "".join(f"{n} = {v!r}\n" for n, v in values.items())

        plain = _plain_values(right)
        numbers = {n: float(v) for n, v in plain.items() if TOLERANCE[n] is not None}
        for n, v in numbers.items():
            tol = TOLERANCE[n] or 0.0
            if n in COUNTS:
                continue
            for sign in (-1, 1):
                out.append(Answer(cell, f"{n} at {sign * 0.98:+g} x tolerance", literal({**plain, n: v + sign * 0.98 * tol}),
                                  True, kind="edge"))  # fmt: skip
        for k in range(3):
            n = list(numbers)[k % len(numbers)]
            tol = TOLERANCE[n] or 0.0
            off = float(rng.choice([-1, 1]) * rng.uniform(1.05, 20.0) * tol)
            w = round(numbers[n] + off) if n in COUNTS else numbers[n] + off
            out.append(Answer(cell, f"{n} off by {off / tol:+.2f} x tolerance", literal({**plain, n: w}), False,
                              kind="perturbed"))  # fmt: skip
        for other in others:
            out.append(Answer(cell, f"copied from {other.student}", literal(_plain_values(other.right[cell])), False,
                              kind="copied"))  # fmt: skip
    return out


def _capture(box: Sandbox, source: str, names: Sequence[str], name: str) -> dict[str, Any]:
    reply = box.run(source, list(names), name=name)
    values = dict(reply.get("values", {}))
    if not reply.get("ok"):
        values = {n: {"error": str(reply.get("error"))} for n in names}
    return values


def student_values(spec: LabSpec, run: GraderRun, answers: Sequence[Answer], work: Path, uid: int,
                   limits: Limits) -> list[dict[str, Any]]:  # fmt: skip
    """What the grader reads back of each value answer (not a function) at this student's variant:
    predictions run alone, given the lab's numbers; the others in a sandbox of the lab, right after
    its answer cell (the instructor's solution), as the grader reads a submission's."""
    import lorisnb

    by_cell: dict[str, list[int]] = {}
    for k, a in enumerate(answers):
        by_cell.setdefault(a.cell, []).append(k)
    values: list[dict[str, Any]] = [{} for _ in answers]
    # predictions: alone, with the lab's numbers as the grader's process has them before the cell
    predicting = [c for c in by_cell if c in spec.predictions]
    if predicting:
        (work / "predictions").mkdir()
        with Sandbox(work / "predictions", limits=limits, uid=uid + 1, no_lorisnb=True) as box:
            for cell in predicting:
                lab = {n: given(run.before[cell][n]) for n in spec.predictions[cell] if n in run.before[cell]}
                usable = {n: v for n, v in lab.items() if "not_plain" not in v}
                for k in by_cell[cell]:
                    box.bind(usable)
                    values[k] = _capture(box, PRELUDE + without_lorisnb(answers[k].source), spec.values[cell],
                                         f"<answer {cell}>")  # fmt: skip
    # the others: in the lab's sandbox, each right after its cell
    rest = {c for c in by_cell if c not in spec.predictions}
    if not rest:
        return values
    (work / "lab").mkdir()
    py_path = Path(lorisnb.__file__).resolve().parents[1]
    with Sandbox(work / "lab", limits=limits, uid=uid, python_path=[py_path]) as box:
        for i, cell in enumerate(spec.notebook.cells):
            meta = cell.get("metadata", {}).get("nbgrader", {})
            if cell.cell_type != "code" or meta.get("grade"):
                continue
            source = cell.source
            if "parameters" in cell.get("metadata", {}).get("tags", []):
                source = _parameters(source, {"student_id": run.student, "output_dir": str(work / "lab" / "out")})
            gid = str(meta.get("grade_id"))
            reply = box.run(source, (), f"<cell {i}>", locked=not meta.get("solution"))
            if not reply.get("ok"):
                raise RuntimeError(f"the lab's cell {gid} failed in the sandbox: {reply.get('error')}")
            for k in by_cell.get(gid, []) if gid in rest else []:
                values[k] = _capture(box, answers[k].source, spec.values[gid], f"<answer {gid}>")
    return values


def grade_values(spec: LabSpec, run: GraderRun, answers: Sequence[Answer], read: Sequence[Mapping[str, Any]]
                 ) -> list[Verdict]:  # fmt: skip
    """Each value answer's test cell with what the grader read of it."""
    questions = {a: q.grade_id for q in spec.questions for a in q.answers}
    out = []
    for a, plain in zip(answers, read, strict=True):
        student = {n: _value(v) for n, v in plain.items()}
        student.update({n: Ellipsis for n in spec.values[a.cell] if n not in student})
        passed, message = run.grade(questions[a.cell], student)
        coincide = not a.right and all(_close(student[n], run.right[a.cell][n], TOLERANCE[n]) for n in student)
        out.append(Verdict(run.student, questions[a.cell], a, passed, message, hints_in(message), coincide, student))
    return out


def grade_formulas(spec: LabSpec, runs: Sequence[GraderRun], answers: Sequence[Answer], work: Path, uid: int,
                   limits: Limits, progress: Callable[[Iterable[Any]], Iterable[Any]] = lambda x: x,
                   ) -> list[Verdict]:  # fmt: skip
    """Each formula answer run alone in its own numpy-only sandbox (as the grader runs it), its
    test cell run at each student's variant with the function called there."""
    questions = {a: q.grade_id for q in spec.questions for a in q.answers}
    cases = {cell: formula_cases(cell) for cell in {a.cell for a in answers}}
    out = []
    for k, a in enumerate(progress(answers)):
        folder = work / f"fn-{k}"
        folder.mkdir()
        with Sandbox(folder, limits=limits, uid=uid + 1, no_lorisnb=True) as box:
            reply = box.run(PRELUDE + without_lorisnb(a.source), name=f"<answer {a.cell}>")  # as grade_submission
            (fname,) = spec.functions[a.cell]
            error = None if reply.get("ok") else (
                f"RuntimeError: the answer cell, run alone with numpy only (no lorisnb, as graded), failed: "
                f"{reply.get('error')}")  # fmt: skip
            coincide = not a.right and not formula_differs(a, cases[a.cell], fname)
            for run in runs:
                fn = RemoteFunction(None if error else box, fname, error, None, limits.cell_timeout_s)
                passed, message = run.grade(questions[a.cell], {fname: fn})
                out.append(Verdict(run.student, questions[a.cell], a, passed, message, hints_in(message), coincide))
    return out


# --- the whole measurement -------------------------------------------------------------------------


@dataclass
class Measured:
    """Every verdict, the students, each student's right values (answer cell -> name -> value), and
    the grade route's comparison (``route``)."""

    verdicts: list[Verdict]
    students: list[str]
    seconds: float
    isolation: str
    right: dict[str, dict[str, dict[str, Any]]] = field(default_factory=dict)
    route: list[RouteGrade] = field(default_factory=list)


def students(n: int) -> list[str]:
    """``n`` student ids, ``s0001``... (their variants drawn from them, as the lab draws a student's)."""
    return [f"s{k + 1:04d}" for k in range(n)]


def measure(source_nb: Path, n_students: int = 12, *, seed: int = 0, copies: int = 2, limits: Limits | None = None,
            progress: Callable[..., Any] | None = None) -> Measured:  # fmt: skip
    """Grade the corpus (and the numbers generated at each variant) at ``n_students`` students'
    variants; ``progress``: a tqdm-like wrapper (``progress(iterable, desc=...)``)."""
    wrap = progress or (lambda x, **_: x)
    limits = limits or Limits()
    t0 = time.monotonic()
    spec = lab_spec(source_nb)
    corpus = [*instructor_solutions(spec), *(a for answers in CORPUS.values() for a in answers)]
    check_corpus(spec, corpus)
    ids = students(n_students)
    rng = np.random.default_rng(seed)
    uid = claim_uids(GradeSettings().uid, 2) if can_isolate() else GradeSettings().uid
    verdicts: list[Verdict] = []
    runs: list[GraderRun] = []
    with tempfile.TemporaryDirectory(prefix="lorisnb-errorrates-") as tmp:
        root = Path(tmp)
        root.chmod(0o711)
        for sid in wrap(ids, desc="students (grader's run)"):
            runs.append(GraderRun(spec, sid, root / "reference" / sid))
        values = [a for a in corpus if not spec.functions.get(a.cell)]
        for k, run in enumerate(wrap(runs, desc="students (values, in the sandbox)")):
            others = [runs[(k - j) % len(runs)] for j in range(1, min(copies, len(runs) - 1) + 1)]
            mine = values + generated(run, others, rng)
            work = root / f"student-{k}"
            work.mkdir()
            read = student_values(spec, run, mine, work, uid, limits)
            verdicts += grade_values(spec, run, mine, read)
            run.before = {}  # the formulas' test cells only are left to run (memory)
            run.at_test = {g: ns for g, ns in run.at_test.items() if g in _formula_tests(spec)}
        formulas = [a for a in corpus if spec.functions.get(a.cell)]
        (root / "formulas").mkdir()
        verdicts += grade_formulas(spec, runs, formulas, root / "formulas", uid, limits,
                                   lambda x: wrap(x, desc="formula answers (each in its sandbox)"))  # fmt: skip
    right = {run.student: run.right for run in runs}
    return Measured(verdicts, ids, time.monotonic() - t0, "full" if can_isolate() else "limits", right)


def _formula_tests(spec: LabSpec) -> set[str]:
    return {q.grade_id for q in spec.questions if any(spec.functions.get(a) for a in q.answers)}


# --- the table -----------------------------------------------------------------------------------


def wilson(k: int, n: int) -> tuple[float, float]:
    """The 95 % Wilson interval of a share ``k`` of ``n`` (scipy.stats), (nan, nan) when n is 0."""
    from scipy.stats import binomtest

    if n == 0:
        return math.nan, math.nan
    ci = binomtest(k, n).proportion_ci(0.95, method="wilson")
    return float(ci.low), float(ci.high)


@dataclass(frozen=True)
class Rates:
    """One question's counts: right answers and false fails, wrong ones and false passes, wrong
    ones that coincide with the right one (in neither), and the hints of the wrong ones."""

    question: str
    right: int
    false_fail: int
    wrong: int
    false_pass: int
    coincide: int
    named: int  # wrong answers rejected whose mistake MISTAKES names
    hint_right: int  # ... whose message names that mistake
    hint_other: int  # ... whose message names another mistake only
    unnamed_hinted: int  # wrong answers rejected whose mistake MISTAKES does not name, given a hint anyway

    def fail_ci(self) -> tuple[float, float]:
        return wilson(self.false_fail, self.right)

    def pass_ci(self) -> tuple[float, float]:
        return wilson(self.false_pass, self.wrong)


def rates(verdicts: Iterable[Verdict]) -> list[Rates]:
    """The counts of each question (by name: the lab's order), then of all of them (``all``)."""
    by: dict[str, list[Verdict]] = {}
    for v in verdicts:
        by.setdefault(v.question, []).append(v)
    out = []
    for q, vs in [*sorted(by.items()), ("all", [v for these in by.values() for v in these])]:
        right = [v for v in vs if v.answer.right]
        wrong = [v for v in vs if not v.answer.right and not v.coincide]
        named = [v for v in wrong if not v.passed and v.answer.mistake]
        out.append(Rates(
            q, len(right), sum(not v.passed for v in right), len(wrong), sum(v.passed for v in wrong),
            sum(v.coincide for v in vs), len(named), sum(v.answer.mistake in v.hints for v in named),
            sum(bool(v.hints) and v.answer.mistake not in v.hints for v in named),
            sum(bool(v.hints) for v in wrong if not v.passed and not v.answer.mistake),
        ))  # fmt: skip
    return out


def _pct(k: int, n: int) -> str:
    return f"{100 * k / n:.1f} %" if n else "-"


def _ci(ci: tuple[float, float]) -> str:
    return "-" if math.isnan(ci[0]) else f"[{100 * ci[0]:.1f}, {100 * ci[1]:.1f}]"


def table(rows: Sequence[Rates]) -> str:
    """The Markdown table of :func:`rates` (the docs quote it as printed)."""
    lines = [
        "| question | right answers | false fails | rate [95 % CI] | wrong answers | false passes | rate [95 % CI] "
        "| coincide | hint names the mistake | another hint only | a hint for an unnamed slip |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        name = "**all**" if r.question == "all" else r.question.removeprefix("test_")
        hint = f"{r.hint_right} of {r.named}" if r.named else "-"
        lines.append(
            f"| {name} | {r.right} | {r.false_fail} | {_pct(r.false_fail, r.right)} {_ci(r.fail_ci())} | {r.wrong} "
            f"| {r.false_pass} | {_pct(r.false_pass, r.wrong)} {_ci(r.pass_ci())} | {r.coincide} | {hint} "
            f"| {r.hint_other} | {r.unnamed_hinted} |"
        )
    return "\n".join(lines)


def errors_found(verdicts: Iterable[Verdict]) -> list[str]:
    """One line per distinct grading error (a right answer rejected, a wrong one accepted): the
    question, the answer, how many students, and the first message."""
    seen: dict[tuple[str, str, str], list[Verdict]] = {}
    for v in verdicts:
        if v.coincide or v.passed == v.answer.right:
            continue
        seen.setdefault((v.question, v.answer.name, v.answer.kind), []).append(v)
    out = []
    for (q, name, kind), vs in seen.items():
        what = "false fail" if vs[0].answer.right else "false pass"
        first = vs[0].message.splitlines()[0] if vs[0].message else ""
        out.append(f"{what}: {q} {name!r} ({kind}) at {len(vs)} student(s), e.g. {vs[0].student}: {first[:160]}")
    return out


# --- the route of `make grade`, on generated submissions ---------------------------------------


@dataclass(frozen=True)
class RouteGrade:
    """One question of one generated submission graded by ``make grade``'s route, against the
    verdict of :func:`measure` for the same answer at the same student's variant."""

    student: str
    question: str
    answer: str
    right: bool
    points: float
    measured_passed: bool | None  # None: the measurement has no verdict for this answer (not measured)

    @property
    def agrees(self) -> bool:
        return self.measured_passed is None or (self.points > 0) == self.measured_passed


def grade_route(source: Path, measured: Measured, n: int = 4, jobs: int = 2, limits: Limits | None = None,
                progress: bool = True) -> list[RouteGrade]:  # fmt: skip
    """Grade ``n`` generated submissions with :func:`.gradebook.grade_class` in a temporary course
    (the harness's secret, so the hidden tests draw the same cases): submission k, of student k (of
    the measurement's), answers every question with the k-th right answer of its cell (even k) or
    the k-th wrong one that the measurement graded there (odd k, ones that coincide left out)."""
    from lorisnb.tools.teaching.gradebook import grade_class

    spec = lab_spec(source / LAB / f"{LAB}.ipynb")
    by_student: dict[str, list[Verdict]] = {}
    for v in measured.verdicts:
        by_student.setdefault(v.student, []).append(v)
    if n > len(measured.students):
        raise ValueError(f"{n} submissions need as many students measured, not {len(measured.students)}")
    chosen: dict[str, dict[str, Verdict]] = {}
    for k in range(n):
        sid = measured.students[k]
        pick: dict[str, Verdict] = {}
        for q in spec.questions:
            (cell,) = q.answers
            pool = [v for v in by_student[sid] if v.answer.cell == cell and v.answer.right == (k % 2 == 0)
                    and not v.coincide]  # fmt: skip
            if pool:
                pick[cell] = pool[(k // 2 * 7 + len(cell)) % len(pool)]
        chosen[sid] = pick
    out = []
    with tempfile.TemporaryDirectory(prefix="lorisnb-errorrates-course-") as tmp:
        course = Path(tmp)
        (course / "release" / LAB).mkdir(parents=True)
        (course / ".grading-secret").write_text(SECRET)
        for sid, pick in chosen.items():
            nb = nbformat.read(source / LAB / f"{LAB}.ipynb", as_version=4)
            for cell in nb.cells:
                gid = cell.get("metadata", {}).get("nbgrader", {}).get("grade_id")
                if cell.cell_type == "code" and gid in pick:
                    cell.source = pick[gid].answer.source
            dest = course / "submitted" / sid / LAB / f"{LAB}.ipynb"
            dest.parent.mkdir(parents=True)
            nbformat.write(nb, dest)
        graded = grade_class(course, source, [LAB], settings=GradeSettings(limits or Limits()), jobs=jobs,
                             progress=progress)  # fmt: skip
        for g in graded:
            pick = chosen[g.result.student]
            for s in g.result.scores:
                q = next(q for q in spec.questions if q.grade_id == s.question)
                made = pick.get(q.answers[0])
                if made is not None:
                    out.append(RouteGrade(g.result.student, s.question, made.answer.name, made.answer.right, s.points,
                                          made.passed))  # fmt: skip
    return out


def route_summary(route: Sequence[RouteGrade]) -> str:
    """One line: how many question grades of the generated submissions agree with the measurement."""
    agree = sum(r.agrees for r in route)
    wrong = [f"{r.student} {r.question} {r.answer!r}: {r.points:g} points, measured "
             f"{'pass' if r.measured_passed else 'fail'}" for r in route if not r.agrees]  # fmt: skip
    subs = len({r.student for r in route})
    text = (
        f"{agree} of {len(route)} question grades of {subs} generated submission(s) graded by make grade's route "
        "agree with the measurement"
    )
    return text + ("" if not wrong else ": disagree: " + "; ".join(wrong))


# --- forgeries: answers whose code writes the grader's replies itself ---------------------------------------------

#: The code a forged answer cell starts with: it walks up from the cell (or from the answer's function, called by a
#: check) to the sandbox child's loop and writes a reply of its own to the request being run, carrying the values
#: of the instructor's solution (which the cell computed aside), then, by ``how``: nothing more (``reply``), also
#: reads the grader's sync request and answers it (``sync``), then ends the process (``exit``) or keeps the child's
#: own reply from being written (``hide``).
FORGE_HELPER = """import sys as _lx_sys, json as _lx_json
def _lx_forge(payload, how):
    f = _lx_sys._getframe()
    while f is not None and "request_id" not in f.f_locals:
        f = f.f_back
    if f is None:
        return
    L, plain, rep = f.f_locals, f.f_globals["_plain"], f.f_locals["reply"]
    ns = payload.get("ns")
    body = ({"values": {n: plain(ns[n]) if n in ns else {"missing": True} for n in L["req"].get("capture", [])}}
            if ns is not None else {"result": plain(payload["result"])})
    rep.write(_lx_json.dumps({"ok": True, "id": L["request_id"], **body}, default=str) + "\\n")
    rep.flush()
    if how == "reply":
        return
    sync = _lx_json.loads(L["requests"].readline())
    rep.write(_lx_json.dumps({"ok": True, "id": sync["id"]}) + "\\n")
    rep.flush()
    if how == "exit":
        import os
        os._exit(0)
    if how == "hide":
        def _lx_write(s, _r=rep):
            del _r.write
            return len(s)
        rep.write = _lx_write
"""

#: How each forgery writes into the grader's channel (see :data:`FORGE_HELPER`), and whether the grader is meant
#: to find it: ``hide`` keeps the sandbox's own reply from being written, which no check can see from outside the
#: process (best effort, docs/guide/teaching.md; what it reports is only what the answer's code computed).
FORGERIES = {"reply": True, "sync": True, "exit": True, "hide": False}
#: The answers forged in each forged submission: a prediction, a formula and a value answer of lab 1.
FORGED_CELLS = ("B1_prediction", "C1_cs_r", "D1_alignment")


@dataclass(frozen=True)
class ForgeryGrade:
    """One forged answer graded by ``make grade``'s route: its points, whether the grade's message
    or the submission's notes say the code wrote into the grader's channel (``told``), and whether
    the grader is meant to find that technique (``findable``)."""

    technique: str
    question: str
    points: float
    max_points: float
    told: bool
    findable: bool

    @property
    def found(self) -> bool:
        """Scored 0, told why: the forgery was found."""
        return self.points == 0 and self.told


def forged_source(spec: LabSpec, cell: str, how: str) -> str:
    """An answer cell for ``cell`` whose own values are wrong but whose replies to the grader carry
    the instructor's solution's (computed aside, in a namespace of its own), written by ``how``."""
    solution = next(a.source for a in instructor_solutions(spec) if a.cell == cell)
    aside = f"_lx_ns = dict(globals())\nexec({solution!r}, _lx_ns)\n"
    defs = spec.functions.get(cell, ())
    if defs:  # a formula: each call by a check forges its reply, the function returns a wrong number
        wrappers = "".join(
            f"def {d}(*args, **kwargs):\n    _lx_forge({{'result': _lx_ns[{d!r}](*args, **kwargs)}}, {how!r})\n"
            "    return 0.123\n"
            for d in defs
        )
        return FORGE_HELPER + aside + wrappers
    wrong = "".join(f"{n} = -0.123\n" for n in spec.values.get(cell, ()))
    return FORGE_HELPER + aside + wrong + f"_lx_forge({{'ns': _lx_ns}}, {how!r})\n"


def forgery_route(source: Path, jobs: int = 2, limits: Limits | None = None, progress: bool = True,
                  techniques: Sequence[str] = tuple(FORGERIES)) -> list[ForgeryGrade]:  # fmt: skip
    """Grade one submission per forgery technique of ``techniques`` (:data:`FORGERIES`) with
    :func:`.gradebook.grade_class` in a temporary course: the instructor's solution everywhere but
    :data:`FORGED_CELLS`, whose values are wrong and whose replies forge the solution's. A forged
    answer is found when it scores 0 with a note saying the code wrote into the grader's channel."""
    from lorisnb.tools.teaching.gradebook import grade_class

    spec = lab_spec(source / LAB / f"{LAB}.ipynb")
    solutions = {a.cell: a.source for a in instructor_solutions(spec)}
    with tempfile.TemporaryDirectory(prefix="lorisnb-errorrates-forged-") as tmp:
        course = Path(tmp)
        (course / "release" / LAB).mkdir(parents=True)
        (course / ".grading-secret").write_text(SECRET)
        for how in techniques:
            nb = nbformat.read(source / LAB / f"{LAB}.ipynb", as_version=4)
            for cell in nb.cells:
                gid = cell.get("metadata", {}).get("nbgrader", {}).get("grade_id")
                if cell.cell_type == "code" and gid in solutions:
                    cell.source = forged_source(spec, gid, how) if gid in FORGED_CELLS else solutions[gid]
            dest = course / "submitted" / f"forged-{how}" / LAB / f"{LAB}.ipynb"
            dest.parent.mkdir(parents=True)
            nbformat.write(nb, dest)
        graded = grade_class(course, source, [LAB], settings=GradeSettings(limits or Limits()), jobs=jobs,
                             progress=progress)  # fmt: skip
    out = []
    for g in graded:
        how = g.result.student.removeprefix("forged-")
        notes = " ".join(g.result.notes)
        for s in g.result.scores:
            q = next(q for q in spec.questions if q.grade_id == s.question)
            if q.answers[0] in FORGED_CELLS:
                told = "grader's reply channel" in s.message or f"{q.answers[0]}: RuntimeError" in notes
                out.append(ForgeryGrade(how, s.question, s.points, s.max_points, told, FORGERIES[how]))
    return sorted(out, key=lambda f: (list(FORGERIES).index(f.technique), f.question))


def forgery_summary(forged: Sequence[ForgeryGrade]) -> str:
    """The forgeries' table: per technique, each forged question's points and what the grade said."""
    lines = ["forged answers (wrong values, replies forged with the solution's), graded by make grade's route:"]
    for how in dict.fromkeys(f.technique for f in forged):
        cells = ", ".join(
            f"{f.question.removeprefix('test_')} {f.points:g}/{f.max_points:g} "
            + ("found" if f.found else "scored 0, another cause told" if f.points == 0 else "scored")
            for f in forged if f.technique == how
        )  # fmt: skip
        meant = "findable" if FORGERIES[how] else "not findable: it hides the sandbox's own reply (best effort)"
        lines.append(f"  {how} ({meant}): {cells}")
    findable = [f for f in forged if f.findable]
    others = [f for f in forged if not f.findable]
    lines.append(f"findable forged answers that scored: {sum(f.points > 0 for f in findable)} of {len(findable)} "
                 f"({sum(f.found for f in findable)} told as forgeries); not findable ones that scored: "
                 f"{sum(f.points > 0 for f in others)} of {len(others)} (with values their own code computed)")  # fmt: skip
    return "\n".join(lines)
