"""The KITTI odometry metric (:mod:`lorisnb.core.metrics.kitti`) on evaluated sequences: its columns
of the sequence table (``--conventions kitti``), its per-length table and its leaderboard summary
over all sequences of an algorithm (the devkit's ``total_err``).

The poses of a sequence are its matched pairs in order (pose i of the estimate with pose i of the
ground truth: the devkit's pairing, which a KITTI file without times gets by index and any other
input by its association); positions as matched (the estimate's after the alignment, none by
default); orientations the rotation blocks as the files wrote them where the errors keep them
(``SequenceErrors.gt_blocks``: two KITTI files under a convention that composes matrices as
written), else the rotations of the quaternions.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import pandas as pd

from lorisnb.core.alignment.geometry import quat_to_matrix
from lorisnb.core.lifelong.scoring import as_files
from lorisnb.core.metrics.kitti import (
    KITTI_LENGTHS,
    KittiSegments,
    concat_segments,
    kitti_length_errors,
    kitti_segments,
    kitti_summary,
)
from lorisnb.core.pipeline.model import FileErrors, SequenceErrors

#: Per-length columns of the sequence table: ``kitti_t_err_100`` (percent) ... ``kitti_r_err_800``
#: (degrees per 100 m), NaN where a length has no segment.
LENGTH_COLUMNS = [f"kitti_{q}_err_{int(n)}" for q in ("t", "r") for n in KITTI_LENGTHS]
#: Columns :func:`kitti_columns` adds: the devkit's summary, the segment count, how the orientations
#: were taken (``as written`` or ``rotations``), then :data:`LENGTH_COLUMNS`.
KITTI_COLUMNS = ["kitti_t_err", "kitti_r_err", "kitti_segments", "kitti_matrices", *LENGTH_COLUMNS]


def poses_of(e: SequenceErrors) -> tuple[np.ndarray, np.ndarray, str]:
    """The (M, 4, 4) ground-truth and estimate matrices of a sequence's matched pairs and how their
    rotations were taken (``as written`` or ``rotations``)."""
    m = e.matched
    gt, est = np.zeros((m, 4, 4)), np.zeros((m, 4, 4))
    gt[:, 3, 3] = est[:, 3, 3] = 1.0
    gt[:, :3, 3], est[:, :3, 3] = e.gt_positions, e.est_positions
    if m == 0:
        return gt, est, "rotations"
    written = e.gt_blocks is not None and e.est_blocks is not None
    assert e.gt_quaternions is not None and e.est_quaternions is not None
    gt[:, :3, :3] = e.gt_blocks if written else quat_to_matrix(e.gt_quaternions)
    est[:, :3, :3] = e.est_blocks if written else quat_to_matrix(e.est_quaternions)
    return gt, est, "as written" if written else "rotations"


def sequence_segments(e: SequenceErrors, precision: str = "single") -> tuple[KittiSegments, str]:
    """The devkit's segments of one sequence's matched pairs, and how its rotations were taken."""
    gt, est, how = poses_of(e)
    return kitti_segments(gt, est, precision), how


def kitti_columns(errors: FileErrors | Iterable[FileErrors], precision: str = "single") -> pd.DataFrame:
    """One row per sequence (in the order of :func:`lorisnb.core.lifelong.scoring.score`): the
    columns :data:`KITTI_COLUMNS` (see :func:`lorisnb.core.metrics.kitti.kitti_summary` and
    :func:`~lorisnb.core.metrics.kitti.kitti_length_errors` for units)."""
    rows = []
    for f in as_files(errors):
        for e in f.sequences:
            seg, how = sequence_segments(e, precision)
            row: dict[str, object] = {**kitti_summary(seg), "kitti_matrices": how}
            lengths = kitti_length_errors(seg)
            for q in ("t", "r"):
                row.update({f"kitti_{q}_err_{int(n)}": v for n, v in zip(lengths.length, lengths[f"{q}_err"], strict=True)})  # fmt: skip
            rows.append(row)
    return pd.DataFrame(rows, columns=KITTI_COLUMNS)


def kitti_lengths(errors: FileErrors | Iterable[FileErrors], precision: str = "single") -> pd.DataFrame:
    """The devkit's per-length errors of every sequence (``algorithm``, ``file``, ``trial``, ``seq``),
    and of every algorithm and trial over all its sequences (``file`` and ``seq`` empty: the devkit's
    ``avg`` plot, over its ``total_err``): ``length`` (m), ``segments``, ``plotted`` (at least 3
    segments, as the devkit plots), ``t_err`` (percent), ``r_err`` (degrees per 100 m)."""
    parts: list[pd.DataFrame] = []
    totals: dict[tuple[str, int], list[KittiSegments]] = {}
    for f in as_files(errors):
        for e in f.sequences:
            seg, _ = sequence_segments(e, precision)
            totals.setdefault((f.algorithm, f.trial), []).append(seg)
            parts.append(kitti_length_errors(seg).assign(algorithm=f.algorithm, file=f.file, trial=f.trial, seq=str(e.seq)))  # fmt: skip
    for (algorithm, trial), segs in totals.items():
        parts.append(kitti_length_errors(concat_segments(segs)).assign(algorithm=algorithm, file="", trial=trial, seq=""))  # fmt: skip
    cols = ["algorithm", "file", "trial", "seq", "length", "segments", "plotted", "t_err", "r_err"]
    return pd.concat(parts, ignore_index=True)[cols] if parts else pd.DataFrame(columns=cols)


def kitti_totals(errors: FileErrors | Iterable[FileErrors], precision: str = "single") -> pd.DataFrame:
    """The leaderboard's numbers: per algorithm and trial, the devkit's summary over every segment of
    all its sequences (its ``stats.txt``, not a mean of the sequences' means): ``kitti_t_err``
    (percent), ``kitti_r_err`` (degrees per 100 m), ``kitti_segments``, ``sequences``."""
    totals: dict[tuple[str, int], list[KittiSegments]] = {}
    for f in as_files(errors):
        for e in f.sequences:
            totals.setdefault((f.algorithm, f.trial), []).append(sequence_segments(e, precision)[0])
    rows = [
        dict(algorithm=a, trial=t, sequences=len(segs), **kitti_summary(concat_segments(segs)))
        for (a, t), segs in totals.items()
    ]
    return pd.DataFrame(
        rows, columns=["algorithm", "trial", "sequences", "kitti_t_err", "kitti_r_err", "kitti_segments"]
    )
