"""Trajectories that carry pose covariances, with their covariances
(:class:`lorisnb.core.metrics.consistency.PoseCovariances`), for the NEES and the 3-sigma bounds:

- **Text**, OpenVINS ``ov_eval``'s layout (what its ``pose_to_file`` records): a line per pose
  ``stamp tx ty tz qx qy qz qw Pr11 Pr12 Pr13 Pr22 Pr23 Pr33 Pt11 Pt12 Pt13 Pt22 Pt23 Pt33``: the
  TUM pose (seconds, metres, quaternion ``xyzw``), then the upper triangle of the orientation
  covariance (rad^2, about the body axes) and of the position covariance (m^2), row by row; ``#``
  comments; spaces, tabs or commas between values.
- **ROS bags**: a ``geometry_msgs/PoseWithCovarianceStamped`` or ``nav_msgs/Odometry`` topic
  (its ``pose.covariance``: x, y, z, then rotation about x, y, z, row-major 6x6).

Rows are checked as every reader checks them (a line that is not 20 numbers, a zero quaternion, a
non-finite stamp: ParseError with the file and line; NaN poses skipped; unsorted or repeated stamps
sorted with a warning), and the covariances follow their poses.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np

from lorisnb.core.metrics.consistency import PoseCovariances
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.errors import LorisWarning, ParseError, ValidationError
from lorisnb.io.parsing.chunks import read_rows
from lorisnb.io.parsing.scanner import check_rows, finish
from lorisnb.io.readers.bags import COVARIANCE_TYPES

#: What a line of the text layout holds.
LAYOUT = "stamp tx ty tz qx qy qz qw Pr11 Pr12 Pr13 Pr22 Pr23 Pr33 Pt11 Pt12 Pt13 Pt22 Pt23 Pt33"


def _checked(spath: str, stamps: np.ndarray, values: np.ndarray, line_no: np.ndarray, what: str,
             repeated: str = "drop") -> tuple[Trajectory, PoseCovariances]:  # fmt: skip
    """Poses (N, 7) and covariances (N, 12 upper triangles) as read: checked, NaN poses skipped,
    sorted (``repeated``: the rule for a repeated stamp's poses, as the scanner's ``finish``); the
    covariances of the poses kept, in their order; a non-finite covariance refused."""
    notes: list[str] = []
    cov = values[:, 7:]
    bad = ~np.isfinite(cov).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ParseError(spath, int(line_no[i]), f"the covariance of this {what} is not finite; expected numbers")
    keep = check_rows(spath, stamps, values[:, :3], values[:, 3:7], line_no, notes)
    stamps, values, line_no = stamps[keep], values[keep], line_no[keep]
    traj = finish(spath, stamps, values[:, :3].copy(), values[:, 3:7].copy(), line_no, "", notes, repeated)
    rows = np.searchsorted(line_no, np.asarray(traj.lines))  # line numbers increase in file order
    for note in notes:
        warnings.warn(note, LorisWarning, stacklevel=3)
    return traj, PoseCovariances.from_upper(values[rows, 7:])


def read_covariance_text(path: str | os.PathLike, repeated: str = "drop") -> tuple[Trajectory, PoseCovariances]:
    """A trajectory and its pose covariances from a text file in ``ov_eval``'s layout
    (:data:`LAYOUT`, see the module docstring); ``repeated``: the poses of a repeated stamp, ``drop``
    all but the last or ``keep`` them all in file order."""
    spath = str(path)
    rows = read_rows(
        path,
        (20,),
        what="a trajectory with covariances (ov_eval's layout)",
        numbers=f"numbers '{LAYOUT}'",
        bad_width=lambda text, n: (
            f"{text[:80]!r} has {n} fields; expected 20 numbers '{LAYOUT}' (ov_eval's layout: the pose, then the "
            "upper triangles of the orientation and position covariances)"
            + (
                "; these are TUM poses without covariances: read them with required=False (lorisnb consistency "
                "does), for errors without NEES or 3-sigma bounds"
                if n == 8
                else ""
            )
        ),  # fmt: skip
        separators=b",",
    )
    values = np.ascontiguousarray(rows.values[:, :20])
    if values.shape[0] == 0:
        raise ParseError(spath, None, f"no pose in this file; expected lines of 20 numbers '{LAYOUT}'")
    line_no = np.asarray(rows.lines)
    return _checked(spath, values[:, 0].copy(), _pose_cov(values[:, 1:8], values[:, 8:20]), line_no, "line", repeated)


def _pose_cov(pose: np.ndarray, upper: np.ndarray) -> np.ndarray:
    return np.concatenate([pose, upper], axis=1)


def read_covariance_bag(path: str | os.PathLike, topic: str | None = None) -> tuple[Trajectory, PoseCovariances]:
    """A trajectory and its pose covariances from a ROS 1 or ROS 2 bag: the ``topic`` of
    ``PoseWithCovarianceStamped`` or ``Odometry`` messages (None: the bag's only such topic)."""
    from lorisnb.io.readers.bags import covariance_messages

    where, t, a = covariance_messages(path, topic)
    # the upper triangles OpenVINS' Recorder writes: orientation (bottom right), then position (top left)
    upper = a[:, 7:][:, [21, 22, 23, 28, 29, 35, 0, 1, 2, 7, 8, 14]]
    try:  # a message's number stands for the line of a text file, as in read_bag
        return _checked(where, t, _pose_cov(a[:, :7], upper), np.arange(1, len(t) + 1), "message")
    except ParseError as exc:
        raise ParseError(where if exc.line is None else f"{where}, message {exc.line}", None, exc.reason) from None


def _text_fields(path: str | os.PathLike) -> int:
    """The number of fields on the first line of ``path`` that is neither blank nor a comment (0 if none
    in its first 64 KiB)."""
    with open(path, "rb") as f:
        head = f.read(1 << 16)
    for raw in head.splitlines():
        line = raw.replace(b",", b" ").strip()
        if line and not line.startswith(b"#"):
            return len(line.split())
    return 0


def read_covariances(
    path: str | os.PathLike, topic: str | None = None, required: bool = True
) -> tuple[Trajectory, PoseCovariances | None]:
    """A trajectory with its pose covariances: a ROS bag (``.bag``, a ROS 2 bag folder, ``.db3`` or
    ``.mcap``; ``topic`` chooses among its topics) or a text file in ``ov_eval``'s layout (``topic``
    refused there). With ``required=False`` an input without covariances is read too (a TUM file of
    8 numbers a line, a bag topic of poses without covariance) and given with None, as ``ov_eval``
    reads such files: errors without bounds or NEES."""
    from lorisnb.io.readers.bags import read_bag
    from lorisnb.io.readers.plain import read_tum

    p = Path(path)
    if p.suffix in (".bag", ".db3", ".mcap") or (p.is_dir() and (p / "metadata.yaml").is_file()):
        if not required:
            from lorisnb.io.readers.bags import message_types

            kinds = message_types(path)
            if (topic is not None and kinds.get(topic) not in COVARIANCE_TYPES) or (
                topic is None and not any(m in COVARIANCE_TYPES for m in kinds.values())
            ):
                return read_bag(path, topic), None
        return read_covariance_bag(path, topic)
    if topic is not None:
        raise ValidationError(f"topic={topic!r}: {path} is a text file, which has no topics; topic applies to ROS bags")
    if not p.is_file():
        raise ParseError(str(path), None, "file not found; expected a trajectory with covariances "
                                          f"('{LAYOUT}' a line) or a ROS bag")  # fmt: skip
    if not required and _text_fields(path) == 8:
        return read_tum(path), None
    return read_covariance_text(path)


def read_ov_groundtruth(path: str | os.PathLike) -> Trajectory:
    """A ground truth in a text file as ``ov_eval`` reads one: TUM's 8 numbers a line or its own
    layout of 20 (:data:`LAYOUT`; the covariances read and left, as ov_eval's metrics use the
    estimate's alone), every row kept in file order (of a repeated stamp, its association takes the
    first)."""
    from lorisnb.io.readers.plain import read_trajectory

    if Path(path).is_file() and _text_fields(path) == 20:
        return read_covariance_text(path, repeated="keep")[0]
    return read_trajectory(path, "tum", repeated="keep")
