"""Pairing by index: pose i of the estimate with pose i of the ground truth (the spec's
``association="index"``), the only pairing two files without stamps allow (KITTI pose files read
without their times: the reader numbers the poses 0, 1, 2, ... and marks ``meta["stamps"] ==
"index"``).

No time bracket applies to such stamps (they are 1 apart, so OpenLORIS' 0.5 s bracket matched
nothing), and pairing by index is only right when both files hold the same poses: files of
different lengths are refused, as ``evo_ape kitti`` refuses them (evo 1.38, ``evo.core.metrics``:
"trajectories must have same number of poses"), since pose i of one is then not pose i of the
other.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import replace

import numpy as np

from lorisnb.core.alignment.association import Association
from lorisnb.core.alignment.geometry import quat_normalize
from lorisnb.core.spec.evalspec import EvalSpec
from lorisnb.core.trajectory.poses import Trajectory, written_blocks
from lorisnb.errors import EvaluationError, ValidationError

#: Spec options that say how stamps are matched in time, or that thin each trajectory on its own
#: (a motion filter keeps other poses of each; a time window cuts by stamps): they cannot apply to
#: pose indices (evo_ape kitti has neither a time window nor, without stamps, a motion filter).
TIME_OPTIONS = ("association", "max_gap", "max_diff", "t_offset", "official_interpolation", "motion_filter",
                "t_start", "t_end")  # fmt: skip


def indexed(trajectories: Iterable[Trajectory]) -> bool:
    """Whether every trajectory's stamps are pose indices made up by its reader (and there is one)."""
    trajs = list(trajectories)
    return bool(trajs) and all(t.meta.get("stamps") == "index" for t in trajs)


#: How each surface gives KITTI files their times (:func:`by_index`'s ``surface``).
TIMES_BY_SURFACE = {"manifest": "estimate_times and groundtruth_times in each [[session]] table"}


def by_index(spec: EvalSpec, surface: str = "cli") -> EvalSpec:
    """The spec for inputs whose stamps are pose indices: ``association="index"``, the rest kept.
    A ValidationError when the user set an option of matching in time (it cannot apply), naming
    the options and the times files as the caller's ``surface`` spells them (``cli``: ``max_diff
    (--max-diff)``, ``--est-times``; ``manifest``: its keys ``estimate_times``, ``groundtruth_times``)."""
    if spec.association == "index":
        return spec
    given = [n for n in TIME_OPTIONS if n in spec.explicit]
    if given:
        names = ", ".join(n if surface == "manifest" else f"{n} (--{n.replace('_', '-')})" for n in given)
        times = TIMES_BY_SURFACE.get(surface, "--est-times and --gt-times")
        raise ValidationError(
            f"{names}: the stamps of both files are pose indices (KITTI files read without times), so poses are "
            f"paired by index (pose i with pose i) and no matching in time applies; give both files their times "
            f"({times}) to match them in time, filter or cut them"
        )
    return replace(spec, association="index")


def match_by_index(gt: Trajectory, est: Trajectory, label: str = "estimate", as_written: bool = False) -> Association:
    """Pose i of ``est`` with pose i of ``gt`` (the estimate's stamps kept); an EvaluationError
    naming ``label`` when the two have different lengths (see the module docstring).
    ``as_written``: the ground truth's rotation blocks as written kept too (where known)."""
    g_start = float(gt.stamps[0]) if len(gt) else np.nan
    g_end = float(gt.stamps[-1]) if len(gt) else np.nan
    if len(gt) != len(est):
        fix = "Give both files their times (--est-times and --gt-times)" if indexed((gt, est)) else (
            "Choose the association interpolate or nearest (--association)"
        )  # fmt: skip
        raise EvaluationError(
            f"{label}: pairing by index (pose i with pose i) needs files of the same length, but the estimate has "
            f"{len(est)} poses and the ground truth {len(gt)}: pose i of one is not pose i of the other (evo_ape "
            f"refuses such KITTI files too: 'trajectories must have same number of poses'). {fix} to match them in "
            "time. Nothing was compared."
        )
    n = len(est)
    if n == 0:
        return Association(np.zeros(0, np.intp), np.zeros(0), np.zeros((0, 3)), None, g_start, g_end)
    blocks = written_blocks(gt) if as_written else None
    return Association(np.arange(n), est.stamps, gt.positions, quat_normalize(gt.quaternions), g_start, g_end, blocks)
