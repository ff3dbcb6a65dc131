"""Stamp units of a trajectory (seconds, milliseconds, microseconds, nanoseconds, pose indices) and
the check that an estimate and its ground truth are in seconds, or both pose indices: comparing
seconds with indices, or any stamps not in seconds, gives a plausible-looking number that means
nothing (a KITTI estimate with its times against a ground truth without them: ATE 183 m; both
files in milliseconds: every ground-truth gap "longer than 0.5 s", or RPE "over 1 s" taken over
1 ms), so anything else is an error naming the likely cause.

A trajectory's unit is ``meta["stamps"] == "index"`` when its reader made up the stamps (a KITTI
file read without times), else read from the values, first their size (:data:`MAGNITUDES`: a
median stamp above 1e11 is after the year 5000 as seconds; Unix time now is 1.7e9 s, 1.7e12 ms,
1.7e15 us, 1.7e18 ns), then, for stamps small enough to be seconds from any start (0, a ROS sim
clock), their spacing: the median step between poses of every real file of ../shared/data is
0.0033 s to 0.32 s; one above :data:`MAX_STEP` (5 s) is not seconds (milliseconds at 200 Hz or
slower, microseconds, nanoseconds, by its size), one below :data:`MIN_STEP` (2e-4 s: faster than
5 kHz) is a unit read too small (EuRoC CSV stamps written in milliseconds or microseconds and
read as nanoseconds). The spacing alone never refuses a file whose poses lie in the time span of
the other file, in seconds: poses a few seconds apart there are sparse, not milliseconds.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.errors import EvaluationError

#: (median |stamp| above which, unit): larger than any stamp in seconds.
MAGNITUDES = ((1e17, "nanoseconds"), (1e14, "microseconds"), (1e11, "milliseconds"))
#: Median step (in the stamps' own numbers) above which stamps are not seconds, and the largest
#: step of each finer unit (200 Hz .. 0.2 Hz in milliseconds, then microseconds, then nanoseconds).
MAX_STEP = 5.0
STEP_UNITS = ((5e3, "milliseconds"), (5e6, "microseconds"), (np.inf, "nanoseconds"))
#: Median step below which the stamps are a unit read too small (faster than 5 kHz).
MIN_STEP = 2e-4
#: Poses (and steps to the next pose) a long trajectory is judged on, evenly spread: a heuristic
#: needs no pass over millions of stamps.
SAMPLE = 4096
#: Steps needed before the spacing is judged (fewer poses: the size alone).
MIN_STEPS = 10
UNITS = ("seconds", "milliseconds", "microseconds", "nanoseconds", "index", "too fine")
#: What to divide stamps of each unit by for seconds.
DIVISOR = {"milliseconds": "1e3", "microseconds": "1e6", "nanoseconds": "1e9"}


def diagnose(traj: Trajectory) -> tuple[str, str]:
    """The unit of a trajectory's stamps (one of :data:`UNITS`) and the evidence in words."""
    if traj.meta.get("stamps") == "index":
        return "index", "pose indices 0, 1, 2, ..."
    t = np.asarray(traj.stamps, float)
    if t.size > 2 * SAMPLE:  # a long trajectory: its size and spacing from evenly spread poses
        k = np.linspace(0, t.size - 2, SAMPLE).astype(np.intp)
        t, d = t[k], t[k + 1] - t[k]
    else:
        d = np.diff(t)
    t = t[np.isfinite(t)]
    if t.size == 0:
        return "seconds", ""
    size = float(np.median(np.abs(t)))
    for bound, unit in MAGNITUDES:
        if size > bound:
            return unit, f"median stamp {size:.3g}"
    d = d[d > 0]
    if d.size < MIN_STEPS:
        return "seconds", ""
    step = float(np.median(d))
    if step > MAX_STEP:
        unit = next(u for bound, u in STEP_UNITS if step <= bound)
        return unit, f"poses a median {step:.3g} apart"
    if step < MIN_STEP:
        return "too fine", f"poses a median {step:.3g} s apart"
    return "seconds", ""


def _by_spacing(why: str) -> bool:
    """Whether :func:`diagnose` judged by the spacing of the poses alone (not by the stamps' size)."""
    return why.startswith("poses a median")


def _overlap(a: Trajectory, b: Trajectory) -> bool:
    """Whether the two trajectories' time spans overlap (stamps in one unit, or a coincidence)."""
    if len(a) == 0 or len(b) == 0:
        return False
    return bool(a.stamps[0] <= b.stamps[-1] and b.stamps[0] <= a.stamps[-1])


def stamp_unit(traj: Trajectory) -> str:
    """``"index"`` (stamps made up from the pose order), ``"seconds"``, ``"milliseconds"``,
    ``"microseconds"``, ``"nanoseconds"`` or ``"too fine"`` (see the module docstring)."""
    return diagnose(traj)[0]


#: How the command line names the options that fix a stamp unit (a manifest names its keys instead).
CLI_NAMES = {"est_times": "--est-times FILE", "gt_times": "--gt-times FILE", "format": "--format euroc",
             "gt_format": "--gt-format euroc", "both_times": "--est-times and --gt-times"}  # fmt: skip


def _cause(unit: str, why: str, role: str, option: str, euroc: str = "") -> str:
    """Why one file's stamps are not seconds; ``option``: how the caller gives its times file
    (``--est-times FILE``), ``euroc``: how it reads the file as EuRoC (``--format euroc``)."""
    if unit == "index":
        return f"the {role}'s stamps are pose indices 0, 1, 2, ... (a KITTI file read without its times: give {option})"
    if unit == "too fine":
        return (
            f"the {role}'s stamps look read in too small a unit ({why}, faster than 5 kHz: EuRoC CSV stamps "
            "written in milliseconds or microseconds instead of nanoseconds?)"
        )
    if unit in DIVISOR:
        hint = ""
        if unit == "nanoseconds":
            fallback = "--gt-format euroc" if role == "ground truth" else "--format euroc"
            hint = f"a EuRoC CSV read as TUM text? {euroc or fallback}; or "
        return f"the {role}'s stamps look like {unit} ({why}; {hint}divide the stamps by {DIVISOR[unit]})"
    return f"the {role}'s stamps are seconds"


def check_stamp_units(
    est: Trajectory, gt: Trajectory, label: str = "estimate", names: Mapping[str, str] | None = None
) -> None:
    """Raise EvaluationError unless the estimate's and the ground truth's stamps are both seconds or
    both pose indices (:func:`diagnose`; two KITTI files without times are paired by index). Every
    time option of lorisnb (max gap, max diff, delta, tau, the RPE step) is in seconds, so stamps in
    other units match nothing or give numbers that mean nothing; the message names the likely cause
    and the option that fixes it. ``names``: how the caller's surface gives those options (keys of
    :data:`CLI_NAMES`, the command line's spellings by default; a manifest's keys for its sessions)."""
    said = {**CLI_NAMES, **(names or {})}
    (ue, we), (ug, wg) = diagnose(est), diagnose(gt)
    if ue == ug and ue in ("seconds", "index"):
        return
    if "seconds" in (ue, ug) and _by_spacing(we if ue != "seconds" else wg) and _overlap(est, gt):
        return  # sparse poses (a keyframe every few seconds) in the time span of the other file: seconds
    if ue == ug:  # both in the same unit, not seconds
        fix = f"divide the stamps of both by {DIVISOR[ue]}" if ue in DIVISOR else ""
        if ue == "nanoseconds":
            fix = f"EuRoC CSV files read as TUM text? ({said['format']} / {said['gt_format']}); else {fix}"
        elif ue == "too fine":
            fix = "EuRoC CSV stamps written in milliseconds or microseconds instead of nanoseconds? write them as nanoseconds"
        unit = "a unit read too small" if ue == "too fine" else ue
        raise EvaluationError(
            f"{label}: the stamps of both files look like {unit} (estimate: {we}; ground truth: {wg}), but "
            f"lorisnb's times (max gap, max diff, delta, tau, the RPE step) are seconds: {fix}. Nothing was compared."
        )
    both = (f"{_cause(ue, we, 'estimate', said['est_times'], said['format'])}, but "
            f"{_cause(ug, wg, 'ground truth', said['gt_times'], said['gt_format'])}")  # fmt: skip
    if "index" in (ue, ug):
        both += f"; give both files their times ({said['both_times']}), or neither to pair two KITTI files by index"
    raise EvaluationError(f"{label}: stamps in different units: {both}. Nothing was compared.")
