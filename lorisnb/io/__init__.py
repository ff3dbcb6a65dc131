"""Files and data: readers and writers of every format, the byte scanner they share, and the
lookup of the data root and its ground truth."""

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from .bags import read_bag
    from .data import DataPaths, find_data, groundtruth_spans, load_groundtruth, scene_durations
    from .formats import TRAJECTORY_FORMATS, read_euroc, read_kitti, read_trajectory, read_tum
    from .manifest import Manifest, read_manifest
    from .openloris import read_openloris
    from .ordslam import read_ordslam
    from .times import read_times
    from .writers import write_csv, write_openloris

__getattr__, __dir__ = attach(__name__)

__all__ = [
    "TRAJECTORY_FORMATS", "DataPaths", "find_data", "groundtruth_spans", "load_groundtruth", "read_euroc",
    "read_kitti", "read_openloris", "read_ordslam", "read_times", "read_trajectory", "read_tum", "scene_durations",
    "write_csv", "write_openloris", "read_bag", "Manifest", "read_manifest",
]  # fmt: skip
