"""The error metrics on matched poses: the OpenLORIS-Scene paper's per-pose and threshold
metrics (:mod:`.openloris`, Eq. 1-4), the errors of poses composed as their files wrote them
(:mod:`.written`), the pose pairs of every RPE rule (:mod:`.pairs`), evo's pose relations
(:mod:`.relations`, :mod:`.relation_table`), rpg's relative error over sub-trajectories
(:mod:`.relative`), the KITTI odometry devkit's segment errors (:mod:`.kitti`) and its columns and
tables of evaluated sequences (:mod:`.kitti_table`), TartanAir's metrics (:mod:`.tartanair`), OpenVINS
ov_eval's NEES and per-axis errors of an estimate with pose covariances (:mod:`.consistency`), and
difficulty measures across datasets (:mod:`.difficulty`).

May import: :mod:`lorisnb.core.alignment`, :mod:`lorisnb.core.conventions`, :mod:`lorisnb.core.lifelong`,
:mod:`lorisnb.core.pipeline`, :mod:`lorisnb.core.spec`, :mod:`lorisnb.core.trajectory` and
:mod:`lorisnb.errors`; never :mod:`lorisnb.core.stats` (enforced).
"""

from typing import TYPE_CHECKING

from lorisnb._lazy import attach

if TYPE_CHECKING:
    from lorisnb.core.metrics.consistency import Consistency, PoseCovariances, ov_eval_errors
    from lorisnb.core.metrics.openloris import (
        RATES,
        RPE_UNITS,
        Orientations,
        aoe,
        ate,
        correct_rate,
        correct_rate_tracking,
        correct_time,
        correctness,
        relocalization_score,
        relocalization_time,
        rmse,
        rpe,
        rpe_pairs,
        valid_intervals,
    )

__getattr__, __dir__ = attach(__name__)

__all__ = [
    "Consistency",
    "PoseCovariances",
    "ov_eval_errors",
    "Orientations",
    "RATES",
    "RPE_UNITS",
    "aoe",
    "ate",
    "correct_rate",
    "correct_rate_tracking",
    "correct_time",
    "correctness",
    "relocalization_score",
    "relocalization_time",
    "rmse",
    "rpe",
    "rpe_pairs",
    "valid_intervals",
]
