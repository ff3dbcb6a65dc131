"""The conventions of the field, selectable: how each peer (OpenLORIS, TUM, rpg, evo) matches and
aligns poses (:mod:`.choices`), and evo's own rules for matching in time (:mod:`.evo_sync`), its
steps inside the pipeline (:mod:`.evo_steps`) and its remaining options (:mod:`.evo_options`).

May import: :mod:`lorisnb.core.alignment`, :mod:`lorisnb.core.metrics`, :mod:`lorisnb.core.pipeline`,
:mod:`lorisnb.core.spec`, :mod:`lorisnb.core.trajectory` and :mod:`lorisnb.errors`; never
:mod:`lorisnb.core.stats` (enforced).
"""

from typing import TYPE_CHECKING

from lorisnb._lazy import attach

if TYPE_CHECKING:
    from lorisnb.core.conventions.choices import (
        ALIGNMENTS,
        ASSOCIATIONS,
        FEW_POSES,
        MAX_DIFF,
        TILT_DEGREES,
        TILT_GAIN,
        Conventions,
        associate_nearest,
        fit_alignment,
    )

__getattr__, __dir__ = attach(__name__)

__all__ = [
    "ALIGNMENTS",
    "ASSOCIATIONS",
    "Conventions",
    "FEW_POSES",
    "MAX_DIFF",
    "TILT_DEGREES",
    "TILT_GAIN",
    "associate_nearest",
    "fit_alignment",
]
