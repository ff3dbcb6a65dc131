"""The trajectory type and what it is made of: stamped poses as plain arrays (:mod:`.poses`), stamp
units (:mod:`.units`), the scenes' sensor frames and extrinsics (:mod:`.frames`), rotation
matrices to quaternions (:mod:`.rotations`, with its optional compiled kernel) and row blocks
for long per-pose computations (:mod:`.blocks`).

May import: the quaternion algebra of :mod:`lorisnb.core.alignment.geometry` and :mod:`lorisnb.errors`
(and of other packages numpy and scipy); no metric, pipeline, scoring or statistics (enforced).
"""

from typing import TYPE_CHECKING

from lorisnb._lazy import attach

if TYPE_CHECKING:
    from lorisnb.core.trajectory.poses import (
        QUAT_EPS,
        RELATIVE,
        K,
        Trajectory,
        checked_arrays,
        extent,
        path_length,
        quaternion_norms_fit,
        sessions,
        size,
        time_spans,
    )

__getattr__, __dir__ = attach(__name__)

__all__ = [
    "K",
    "QUAT_EPS",
    "RELATIVE",
    "Trajectory",
    "checked_arrays",
    "extent",
    "path_length",
    "quaternion_norms_fit",
    "sessions",
    "size",
    "time_spans",
]
