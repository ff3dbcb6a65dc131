"""Stamp units of a trajectory (seconds, nanoseconds, pose indices) and the check that an estimate
and its ground truth use the same one: comparing seconds with indices or nanoseconds gives a
plausible-looking number that means nothing (a KITTI estimate with its times against a ground
truth without them: ATE 183 m), so a mismatch is an error naming the likely cause.

A trajectory's unit is ``meta["stamps"] == "index"`` when its reader made up the stamps (a KITTI
file read without times), else read from the values: stamps above :data:`NANOSECONDS` (1e14; as
seconds that is three million years) are nanoseconds, the rest seconds.
"""

from __future__ import annotations

import numpy as np

from ..errors import EvaluationError
from .trajectory import Trajectory

#: Stamps whose median is above this are nanoseconds (as seconds: 3 million years).
NANOSECONDS = 1e14
UNITS = ("seconds", "nanoseconds", "index")


def stamp_unit(traj: Trajectory) -> str:
    """``"index"`` (stamps made up from the pose order), ``"nanoseconds"`` or ``"seconds"``."""
    if traj.meta.get("stamps") == "index":
        return "index"
    t = np.asarray(traj.stamps, float)
    if t.size and float(np.median(np.abs(t))) > NANOSECONDS:
        return "nanoseconds"
    return "seconds"


def _cause(unit: str, role: str, option: str) -> str:
    if unit == "index":
        return (
            f"the {role}'s stamps are pose indices 0, 1, 2, ... (a KITTI file read without its times: "
            f"give {option} FILE)"
        )
    if unit == "nanoseconds":
        fmt = "--gt-format euroc" if role == "ground truth" else "--format euroc"
        return (
            f"the {role}'s stamps look like nanoseconds (a EuRoC CSV read as TUM text? {fmt}; or divide the "
            "stamps by 1e9)"
        )
    return f"the {role}'s stamps are seconds"


def check_stamp_units(est: Trajectory, gt: Trajectory, label: str = "estimate") -> None:
    """Raise EvaluationError when the estimate's and the ground truth's stamps are in different
    units (:func:`stamp_unit`), or either is in nanoseconds (every time option of lorisnb, max gap,
    max diff, delta, tau, is in seconds, so nothing would match), naming the likely cause and the
    option that fixes it. Two trajectories indexed by pose order (two KITTI files without times)
    agree."""
    ue, ug = stamp_unit(est), stamp_unit(gt)
    if ue == ug and ue != "nanoseconds":
        return
    if ue == ug:  # both in nanoseconds
        raise EvaluationError(
            f"{label}: the stamps of both files look like nanoseconds, but lorisnb's times (max gap, max diff, "
            "delta, tau) are seconds: EuRoC CSV files read as TUM text? (--format euroc / --gt-format euroc); "
            "else divide the stamps by 1e9. Nothing was compared."
        )
    both = f"{_cause(ue, 'estimate', '--est-times')}, but {_cause(ug, 'ground truth', '--gt-times')}"
    if "index" in (ue, ug):
        both += (
            "; give both files their times (--est-times and --gt-times), or neither to pair two KITTI files by index"
        )
    raise EvaluationError(f"{label}: stamps in different units: {both}. Nothing was compared.")
