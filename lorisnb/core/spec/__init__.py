"""The evaluation spec: every choice that decides a number, in one frozen validated value
(:mod:`.evalspec`), its evo options (:mod:`.evo`), its documentation table (:mod:`.table`), the
validation of every user value (:mod:`.validate`), and the inputs that exclude each other
(:mod:`.exclusive`: one registry for the command line, the notebooks and the report).

May import: :mod:`lorisnb.core.alignment`, :mod:`lorisnb.core.conventions`, :mod:`lorisnb.core.metrics`,
:mod:`lorisnb.core.pipeline`, :mod:`lorisnb.core.trajectory` and :mod:`lorisnb.errors`; never
:mod:`lorisnb.core.stats` (enforced). The spec's values name the choices the conventions and metrics
define.
"""

from typing import TYPE_CHECKING

from lorisnb._lazy import attach

if TYPE_CHECKING:
    from lorisnb.core.spec.evalspec import (
        ALIASES,
        ALIGNMENTS,
        ASSOCIATIONS,
        INPUT_KINDS,
        MAX_DIFF,
        MODES,
        PRESETS,
        REPEATED,
        RPE_UNITS,
        SPEC_NAMES,
        THRESHOLD_NAMES,
        UNSCALED,
        Conventions,
        EvalSpec,
        Transform,
        make_spec,
        preset_over,
        text,
    )

__getattr__, __dir__ = attach(__name__)

__all__ = [
    "ALIASES",
    "ALIGNMENTS",
    "ASSOCIATIONS",
    "Conventions",
    "EvalSpec",
    "INPUT_KINDS",
    "MAX_DIFF",
    "MODES",
    "PRESETS",
    "REPEATED",
    "RPE_UNITS",
    "SPEC_NAMES",
    "THRESHOLD_NAMES",
    "Transform",
    "UNSCALED",
    "make_spec",
    "preset_over",
    "text",
]
