"""What the labs show around their questions, computed: the data every student and the grader
use, and the explanations printed after a check (their formulas live here, not in a cell of the
student version, where they would give the answer away). Each returns Markdown text."""

from __future__ import annotations

import hashlib
import os
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from lorisnb.io.datasets.paths import DataPaths, find_data, sample_data

SAMPLE_NOTE = (
    "using the small sample data shipped with lorisnb (cafe scene only): every student and the grader "
    "evaluate on the same data. To use other data, set `data_root` in the parameters cell of the lab "
    "you hand out: every student and the grader then need that folder."
)


def lab_data(data_root: str | os.PathLike[str] | DataPaths | None = None) -> DataPaths:
    """The data of a lab: the sample data shipped with lorisnb unless the lab's ``data_root``
    parameter names a folder. Never ``$LORISNB_DATA`` or ``../shared/data``: the answers' reference
    numbers depend on the data, and the grader must see the data the student saw."""
    if data_root is None:
        print(SAMPLE_NOTE)
        return sample_data()
    return find_data(data_root)


#: What a student's variant draws from, uniformly and independently, question by question (lab 1).
#: Each value was chosen so that, on the sample data at the lab's thresholds, the right answer passes,
#: each typical mistake the question's check names fails with its hint, and two different values give
#: answers further apart than the check's tolerance (``tests/tools/test_teaching_variants.py``).
LOST_STARTS = tuple(float(s) for s in range(10, 21))  # B1: tracking lost from this second...
LOST_LENGTHS = tuple(float(s) for s in range(15, 26))  # ...for this many seconds
LATE_STARTS = tuple(float(s) for s in range(10, 31))  # B3: the estimate starts this late (seconds)
RELOC_DELAYS = tuple(float(s) for s in range(3, 31, 3))  # C2, D1: visit 2 re-localizes (wrongly) this late
TARGET_CRS = (0.27, 0.275, 0.29, 0.3, 0.305)  # E1: the scene CR whose smallest eps is asked
TIMELINE_EPS = (0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.1)  # F: the timeline's eps (metres)
ATE_SEQS = (1, 2)  # G1: the sequence of cafe whose ATE is normalized


@dataclass(frozen=True)
class LabVariant:
    """One student's data, all drawn from the student id: the simulator's ``seed``, Part B's
    ``lost_window`` (seconds after the start) and ``late_start`` (seconds), the delay after which
    visit 2 re-localizes wrongly in C2 and D1 (``reloc_delay``, seconds), E1's ``target_cr``, the
    eps of Part F's timeline (``timeline_eps``, metres) and G1's sequence of cafe (``ate_seq``)."""

    student_id: str
    seed: int
    lost_window: tuple[float, float]
    late_start: float
    reloc_delay: float
    target_cr: float
    timeline_eps: float
    ate_seq: int

    def describe(self) -> str:
        who = f"student id `{self.student_id}`" if self.student_id else "no student id (set `student_id`)"
        return (
            f"Your data variant ({who}): simulator seed {self.seed}; in B1 tracking is lost from "
            f"{self.lost_window[0]:g} s to {self.lost_window[1]:g} s; in B3 the estimate starts {self.late_start:g} s "
            f"late; in C2 and D1 visit 2 re-localizes after {self.reloc_delay:g} s; in E1 the target scene CR is "
            f"{self.target_cr:g}; in F the timeline is drawn at eps = {self.timeline_eps:g} m; in G1 the sequence is "
            f"cafe-{self.ate_seq}."
        )


def same_id(student_id: str) -> str:
    """A student id as the data variant is drawn from it: without spaces, in lower case (an id typed
    ``S1234567`` or ``s 1234567`` in the notebook draws the variant of the folder ``s1234567``), in
    one Unicode form (NFKC, case folded, NFKC again: Unicode's identifier caseless match), so an id
    that looks the same is the same: ``zoë`` typed as one character or as ``e`` and a combining
    diaeresis, full-width ``ｓ０００１`` and ``s0001``. An ASCII id is only stripped and lower-cased
    (its variant as before)."""
    import unicodedata

    text = unicodedata.normalize("NFKC", str(student_id))
    return unicodedata.normalize("NFKC", "".join(text.split()).casefold())


def lab_variant(
    student_id: str | None = None, seed: int | None = None, lab: str = "lab1_lifelong_metrics"
) -> LabVariant:
    """The data variant of a student: drawn from a seed derived from ``student_id`` (else
    ``$JUPYTERHUB_USER``), so that the grader, who knows the id, draws the same data; answers
    differ between students while the checks and their hints apply to every variant. ``seed``:
    given, it is used instead (the instructor's runs). The id is taken as :func:`same_id` takes it
    (case and spaces ignored: ``" S1234567 "`` is ``s1234567``, the folder the grader knows it by)."""
    sid = str(student_id if student_id is not None else os.environ.get("JUPYTERHUB_USER", ""))
    if seed is None:
        seed = int(hashlib.sha256(f"{lab}\0{same_id(sid)}".encode()).hexdigest()[:8], 16) % 2**31
    rng = np.random.default_rng(int(seed))

    def draw(values: tuple[Any, ...]) -> Any:
        return values[int(rng.integers(len(values)))]

    # drawn in this order (B1 and B3 first, as before the other questions varied: the same as then)
    start, length, late = (
        float(rng.integers(int(v[0]), int(v[-1]) + 1)) for v in (LOST_STARTS, LOST_LENGTHS, LATE_STARTS)
    )
    return LabVariant(
        sid, int(seed), (start, start + length), late,
        reloc_delay=draw(RELOC_DELAYS), target_cr=draw(TARGET_CRS), timeline_eps=draw(TIMELINE_EPS),
        ate_seq=draw(ATE_SEQS),
    )  # fmt: skip


def explain_gap(cr: float, ate_rmse: float, gap: tuple[float, float], delta: float, duration: float) -> str:
    """Question B1: a perfect estimate with no output during ``gap`` (seconds from the start)."""
    lost = gap[1] - gap[0]
    held = min(delta, lost)
    return (
        f"CR = {cr:.3f}: the {lost:g} s without output are lost except the last pose before the gap, which holds "
        f"for min(delta, {lost:g} s) = {held:g} s; so CR is about 1 - ({lost:g} - {held:g}) / {duration:.1f} = "
        f"{1 - (lost - held) / duration:.3f}. The ATE RMSE ({ate_rmse:.3f} m) does not see the gap at all: "
        "missing poses are simply not counted."
    )


def wrong_reloc_question(offset_m: float, yaw_deg: float, eps: float, phi: float, delay_s: float = 0.0) -> str:
    """Question C2's text, with the scenario's numbers and where they stand against the thresholds
    (``delay_s``: the seconds of visit 2 before its first pose, the student's variant)."""
    when = f" after {delay_s:g} s" if delay_s else ""
    return (
        "**Question C2 (predict, then run).** A lifelong run of two visits of cafe: the first visit is fine; on "
        f"the second the algorithm re-localizes{when}, {offset_m:g} m off ({offset_m / eps:g} times eps = {eps:g} m) and "
        f"turned by {yaw_deg:g} degrees (phi = {phi:g} degrees), and stays there. The whole run is aligned once, "
        "on visit 1 (as the paper's lifelong evaluation does). Predict CS-R of visit 2."
    )


def explain_wrong_reloc(visit: Mapping[str, Any], errors: Any, eps: float, phi: float, tau: float) -> str:
    """Question C2: ``visit``, the scored row of visit 2; ``errors``, its per-pose errors (``.ate``, ``.aoe``)."""
    t0 = float(visit["reloc_time"])
    ate, aoe = np.asarray(errors.ate), np.asarray(errors.aoe)
    ate_cmp = "≤" if ate[0] <= eps else ">"
    aoe_cmp = "≤" if aoe[0] <= phi else ">"
    correct = int(np.count_nonzero((ate <= eps) & (aoe <= phi)))
    verdict = "correct" if visit["first_correct"] else "wrong"
    why = (
        "Eq. (4) rewards it"
        if visit["first_correct"]
        else "a confident pose in the wrong place is worse than no pose, and Eq. (4) gives it nothing"
    )
    return (
        f"Visit 2 starts after {t0:.2f} s, so exp(-t/tau) = {np.exp(-t0 / tau):.3f} would reward a fast start; "
        f"but its first pose is {verdict} (ATE {ate[0]:.2f} m {ate_cmp} eps = {eps:g} m, AOE {aoe[0]:.1f} "
        f"degrees {aoe_cmp} phi = {phi:g} degrees), so CS-R = {float(visit['cs_r']):.3f}: {why}. "
        f"{correct} of its {len(ate)} poses are correct, so CR = {float(visit['cr']):.3f}."
    )


def explain_ate_percent(
    ate_rmse: float, path_length: float, outdoor: Mapping[str, float], outdoor_path: float, sequence: str = "cafe-1"
) -> str:
    """Part G: indoor ``sequence`` against ORDSLAM's published percentages (``outdoor``: difficulty -> %)."""
    return (
        f"ORB-SLAM2 on indoor {sequence}: ATE RMSE {ate_rmse:.3f} m over {path_length:.1f} m travelled, i.e. "
        f"{100 * ate_rmse / path_length:.2f} % of the distance; outdoors in ORDSLAM (published, on its mean "
        f"{outdoor_path:g} m path) "
        + ", ".join(f"{v:.2f} % ({k})" for k, v in outdoor.items())
        + ". **Discuss:** is outdoor harder? What else differs (ground truth, motion, length, the robot)?"
    )
