"""Evaluating files and folders: the one runner for every input kind (:mod:`.runner`), what it
returns (:mod:`.result`), the inputs (:mod:`.inputs`), one job per input (:mod:`.jobs`) run on
local cores or a Dask cluster (:mod:`.pool`), the exit status (:mod:`.status`) and sweeps
streamed to Parquet (:mod:`.streaming`).

May import: :mod:`lorisnb.io`, :mod:`lorisnb.core`, :mod:`lorisnb.errors` and the optional-dependency
check :mod:`lorisnb.tools._extras` (for Dask's ``distributed``); no other tools sub-package.
"""

from typing import TYPE_CHECKING

from lorisnb._lazy import attach

if TYPE_CHECKING:
    from lorisnb.tools.evaluation.result import (
        Evaluation,
        Failure,
    )

__getattr__, __dir__ = attach(__name__)

__all__ = [
    "Evaluation",
    "Failure",
]
