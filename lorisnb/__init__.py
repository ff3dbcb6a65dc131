"""lorisnb: evaluate SLAM the way lifelong robots need it (OpenLORIS-Scene metrics).

The core (``readers``, ``frames``, ``association``, ``geometry``, ``metrics``, ``evaluation``) is
pure functions on arrays and dataclasses; files, figures and reports sit at the edge.
"""

from .data import find_data
from .errors import DataNotFoundError, EvaluationError, FrameError, LorisError, LorisWarning, ParseError
from .evaluation import (
    Evaluation,
    FileErrors,
    SequenceErrors,
    aggregate_scenes,
    compute_errors,
    evaluate,
    load_groundtruth,
    pose_table,
    score,
)
from .frames import PAPER_EPS, PAPER_PHI, SCENES
from .readers import read_kitti, read_openloris, read_trajectory, read_tum
from .trajectory import Trajectory

__version__ = "0.1.0"

__all__ = [
    "DataNotFoundError", "EvaluationError", "Evaluation", "FileErrors", "FrameError", "LorisError",
    "LorisWarning", "PAPER_EPS", "PAPER_PHI", "ParseError", "SCENES", "SequenceErrors", "Trajectory",
    "aggregate_scenes", "compute_errors", "evaluate", "find_data", "load_groundtruth", "pose_table",
    "read_kitti", "read_openloris", "read_trajectory", "read_tum", "score",
]
