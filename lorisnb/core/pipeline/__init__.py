"""The one evaluation pipeline (:mod:`.sessions`): read poses in, per-pose errors out, through its
steps (:mod:`.steps`), with plausibility checks (:mod:`.checks`, :mod:`.plausibility`) and the
data model every layer shares (:mod:`.model`).

May import: :mod:`lorisnb.core.alignment`, :mod:`lorisnb.core.conventions`, :mod:`lorisnb.core.metrics`,
:mod:`lorisnb.core.spec`, :mod:`lorisnb.core.trajectory` and :mod:`lorisnb.errors`; never
:mod:`lorisnb.core.stats` (enforced).
"""

from typing import TYPE_CHECKING

from lorisnb._lazy import attach

if TYPE_CHECKING:
    from lorisnb.core.pipeline.sessions import (
        DEFAULT,
        FrameInfo,
        K,
        Spans,
        apply_alignment,
        compute_errors,
        errors_after_alignment,
        evaluate_sessions,
        groundtruth_frame,
        match,
        moved_groundtruth,
        sequence_errors,
        session_errors,
        window_spans,
        with_transform,
    )

__getattr__, __dir__ = attach(__name__)

__all__ = [
    "DEFAULT",
    "FrameInfo",
    "K",
    "Spans",
    "apply_alignment",
    "compute_errors",
    "errors_after_alignment",
    "evaluate_sessions",
    "groundtruth_frame",
    "match",
    "moved_groundtruth",
    "sequence_errors",
    "session_errors",
    "window_spans",
    "with_transform",
]
