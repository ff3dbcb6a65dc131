"""lorisnb: evaluate SLAM the way lifelong robots need it (OpenLORIS-Scene metrics).

Layers (enforced by an import contract; see the manual's Architecture page, docs/architecture.md): :mod:`lorisnb.core`
holds pure functions on arrays and dataclasses; :mod:`lorisnb.io` reads and writes files and finds
the data; :mod:`lorisnb.tools` evaluates folders and makes figures, widgets and reports;
:mod:`lorisnb.cli` is the command line. The names below are the public API.
"""

from typing import TYPE_CHECKING

from lorisnb._lazy import attach
from lorisnb._moved import install
from lorisnb._version import __version__

install()  # the former flat modules' names (lorisnb.core.scoring, ...) still import, with a warning

if TYPE_CHECKING:
    from lorisnb.core import (
        PAPER_EPS,
        PAPER_PHI,
        SCENES,
        Conventions,
        EvalSpec,
        FileErrors,
        OpenLorisFile,
        ResultFile,
        SequenceErrors,
        Trajectory,
        aggregate_scenes,
        compute_errors,
        evaluate_sessions,
        make_spec,
        pose_table,
        score,
        sequence_errors,
        session_errors,
        sweep,
    )
    from lorisnb.errors import (
        DataNotFoundError,
        EvaluationError,
        FrameError,
        LorisError,
        LorisWarning,
        MissingDependencyError,
        OutputError,
        ParseError,
        ValidationError,
    )
    from lorisnb.io import (
        find_data,
        load_groundtruth,
        read_euroc,
        read_kitti,
        read_manifest,
        read_openloris,
        read_ordslam,
        read_trajectory,
        read_tum,
        write_openloris,
    )
    from lorisnb.tools import Evaluation, evaluate, evaluate_manifest, evaluate_pairs, setup

__getattr__, __dir__ = attach(__name__)

__all__ = [
    "DataNotFoundError", "EvaluationError", "Evaluation", "FileErrors", "FrameError", "LorisError", "LorisWarning",
    "MissingDependencyError", "OpenLorisFile", "OutputError", "PAPER_EPS", "PAPER_PHI", "ParseError",
    "ResultFile", "SCENES", "SequenceErrors", "Trajectory", "ValidationError", "__version__", "aggregate_scenes",
    "compute_errors", "evaluate", "find_data", "load_groundtruth", "pose_table", "read_euroc", "read_kitti",
    "read_openloris", "read_ordslam", "read_trajectory", "read_tum", "score", "sequence_errors", "setup", "sweep",
    "write_openloris", "Conventions", "session_errors", "evaluate_pairs", "evaluate_manifest", "read_manifest",
    "EvalSpec", "make_spec", "evaluate_sessions",
]  # fmt: skip
