"""Statistics and decisions: repeated trials (:mod:`.trials`), intervals and pairwise tests
(:mod:`.inference`), the exact permutation test (:mod:`.permutation`), power (:mod:`.power`),
rankings (:mod:`.ranking`), the regression verdict of ``lorisnb diff`` (:mod:`.regression`,
:mod:`.tolerances`) and the reruns of a SLAM system made from one real output that measure the
verdict's error rates (:mod:`.reruns`).

May import: :mod:`lorisnb.core.alignment`, :mod:`lorisnb.core.lifelong`, :mod:`lorisnb.core.simulate`,
:mod:`lorisnb.core.spec`, :mod:`lorisnb.core.trajectory` and :mod:`lorisnb.errors`; none of them imports
it (enforced): decisions sit above the numbers they decide on.
"""

from typing import TYPE_CHECKING

from lorisnb._lazy import attach

if TYPE_CHECKING:
    from lorisnb.core.stats.inference import (
        GROUP,
        WEIGHTS,
        confidence_intervals,
        holm,
        pairwise,
        scene_means,
        scene_values,
        trial_summary,
        with_trials,
    )

__getattr__, __dir__ = attach(__name__)

__all__ = [
    "GROUP",
    "WEIGHTS",
    "confidence_intervals",
    "holm",
    "pairwise",
    "scene_means",
    "scene_values",
    "trial_summary",
    "with_trials",
]
