"""Files and data: readers and writers of every format, the byte scanner they share, and the
lookup of the data root and its ground truth."""

from typing import TYPE_CHECKING

from lorisnb._lazy import attach

if TYPE_CHECKING:
    from lorisnb.io.datasets.manifest import Manifest, read_manifest
    from lorisnb.io.datasets.paths import DataPaths, find_data, groundtruth_spans, load_groundtruth, scene_durations
    from lorisnb.io.readers.bags import read_bag
    from lorisnb.io.readers.covariance import read_covariances
    from lorisnb.io.readers.openloris import read_openloris
    from lorisnb.io.readers.ordslam import read_ordslam
    from lorisnb.io.readers.plain import TRAJECTORY_FORMATS, read_euroc, read_kitti, read_trajectory, read_tum
    from lorisnb.io.readers.times import read_times
    from lorisnb.io.writers import write_csv, write_openloris

__getattr__, __dir__ = attach(__name__)

__all__ = [
    "TRAJECTORY_FORMATS", "DataPaths", "find_data", "groundtruth_spans", "load_groundtruth", "read_euroc",
    "read_kitti", "read_openloris", "read_ordslam", "read_times", "read_trajectory", "read_tum", "scene_durations",
    "write_csv", "write_openloris", "read_bag", "Manifest", "read_manifest", "read_covariances",
]  # fmt: skip
