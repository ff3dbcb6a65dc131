"""The edge: evaluation of files and folders, notebook helpers, figures, widgets, reports and the
bridge to evo. Optional dependencies (evo, papermill, ipywidgets) are imported when first used."""

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from ._extras import require
    from .evaluate import evaluate, evaluate_manifest, evaluate_pairs
    from .evaluation import Evaluation, Failure
    from .inputs import result_files
    from .notebook import Outputs, setup
    from .streaming import sweep_to_parquet

__getattr__, __dir__ = attach(__name__)

__all__ = [
    "Evaluation",
    "Failure",
    "Outputs",
    "evaluate",
    "require",
    "result_files",
    "setup",
    "sweep_to_parquet",
    "evaluate_pairs",
    "evaluate_manifest",
]
