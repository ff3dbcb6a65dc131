"""The edge: evaluation of files and folders, notebook helpers, figures, widgets, reports and the
bridge to evo. Optional dependencies (evo, papermill, ipywidgets) are imported when first used."""

from typing import TYPE_CHECKING

from lorisnb._lazy import attach

if TYPE_CHECKING:
    from lorisnb.tools._extras import require
    from lorisnb.tools.evaluation.inputs import result_files
    from lorisnb.tools.evaluation.result import Evaluation, Failure
    from lorisnb.tools.evaluation.runner import evaluate, evaluate_manifest, evaluate_pairs
    from lorisnb.tools.evaluation.streaming import sweep_to_csv, sweep_to_parquet
    from lorisnb.tools.notebook.start import Outputs, setup

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
    "sweep_to_csv",
    "evaluate_pairs",
    "evaluate_manifest",
]
