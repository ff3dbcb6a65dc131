"""Batch reports: the run (:mod:`.build`), its notebooks (:mod:`.notebooks`) and their kernels
(:mod:`.kernels`, :mod:`.lean_imports`), the front page (:mod:`.index`), the leaderboard
(:mod:`.leaderboard`), the run against its baseline (:mod:`.baseline`), offline HTML (:mod:`.html`),
provenance (:mod:`.provenance`), paths relative to named roots (:mod:`.portable`) and paper-ready
tables (:mod:`.tables`).

May import: :mod:`lorisnb.tools.evaluation`, :mod:`lorisnb.tools.decisions`, :mod:`lorisnb.tools.notebook`,
the optional-dependency check :mod:`lorisnb.tools._extras`, :mod:`lorisnb.io`, :mod:`lorisnb.core`,
:mod:`lorisnb.errors` and lorisnb's version (:mod:`lorisnb._version`); the decisions, the notebooks and
the figures import this package too (docs/architecture.md, "Sub-packages that import each other").
"""

from typing import TYPE_CHECKING

from lorisnb._lazy import attach

if TYPE_CHECKING:
    from lorisnb.tools.report.build import (
        DEFAULT_NOTEBOOKS,
        KERNEL_ARGS,
        NOTEBOOK_NEEDS,
        RUN_MARKER,
        WORKER_MODULES,
        NotebookRun,
        available_notebooks,
        check_parameters,
        declared_parameters,
        findings_input_errors,
        kernel_env,
        notebook_dir,
        notebook_path,
        run_notebook,
        run_report,
    )

__getattr__, __dir__ = attach(__name__)

__all__ = [
    "DEFAULT_NOTEBOOKS",
    "KERNEL_ARGS",
    "NOTEBOOK_NEEDS",
    "NotebookRun",
    "RUN_MARKER",
    "WORKER_MODULES",
    "available_notebooks",
    "check_parameters",
    "declared_parameters",
    "findings_input_errors",
    "kernel_env",
    "notebook_dir",
    "notebook_path",
    "run_notebook",
    "run_report",
]
