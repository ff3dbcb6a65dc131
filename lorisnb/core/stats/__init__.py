"""Statistics and decisions: repeated trials (:mod:`.trials`), intervals and pairwise tests
(:mod:`.inference`), the exact permutation test (:mod:`.permutation`), power (:mod:`.power`),
rankings (:mod:`.ranking`), and the regression verdict of ``lorisnb diff``
(:mod:`.regression`, :mod:`.tolerances`).

May import: every other core sub-package; none of them imports it (enforced): decisions sit
above the numbers they decide on.
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
