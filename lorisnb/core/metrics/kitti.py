"""The KITTI odometry metric, as the KITTI devkit's ``evaluate_odometry.cpp`` computes it (the
number of the KITTI odometry leaderboard and of every visual-odometry paper on KITTI).

For every start frame ``first`` = 0, 10, 20, ... (the devkit's ``step_size`` of 10 frames) and
every segment length L of 100, 200, ..., 800 m, the end frame is the first frame whose distance
travelled along the ground truth exceeds the start's by more than L (``lastFrameFromSegmentLength``;
segments without one are left out). With the poses as 4x4 matrices ``[R | t; 0 0 0 1]`` *as
written* (the rotation blocks are not projected onto rotations; ``Matrix::inv`` is a general
inverse), the segment's error is::

    E = (P_est[first]^-1 P_est[last])^-1 (P_gt[first]^-1 P_gt[last])
    r_err = arccos(clip((E_00 + E_11 + E_22 - 1) / 2, -1, 1)) / L     (rad per metre)
    t_err = |E[:3, 3]| / L                                            (m per metre)

and the devkit's summary (``saveStats``) is the mean of ``t_err`` and of ``r_err`` over every
segment of every sequence evaluated, reported as ``kitti_t_err`` in percent (100 mean t_err) and
``kitti_r_err`` in degrees per 100 m (mean r_err x 180/pi x 100). Its per-length errors
(``saveErrorPlots``: ``*_tl.txt``, ``*_rl.txt``) are the same means over the segments of one
length, written for lengths with at least 3 segments.

Precision (``precision``): ``single`` is the devkit's arithmetic: matrices in double, but the
distances, the diagonal and translation of ``E``, the angle, the per-metre errors and the running
sums are C ``float`` (single precision), so an angle near zero is quantized by the float cosine
(up to 2 % of the rotation error against a double-precision rewrite); every operation is
reproduced in numpy float32 in the devkit's order. ``double`` is the same algorithm in double
precision throughout (as kitti-odom-eval's ``KittiEvalOdom`` computes it).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from lorisnb.core.spec.validate import choice
from lorisnb.errors import EvaluationError

if TYPE_CHECKING:
    import pandas as pd

#: The devkit's segment lengths, metres (``lengths[]`` of evaluate_odometry.cpp).
KITTI_LENGTHS = (100.0, 200.0, 300.0, 400.0, 500.0, 600.0, 700.0, 800.0)
#: The devkit's step between start frames (``step_size``; 1 s at KITTI's 10 Hz).
KITTI_STEP = 10
#: ``single``: the devkit's float arithmetic; ``double``: the same in double precision.
PRECISIONS = ("single", "double")
#: The devkit writes a per-length error only for lengths with more than 2.5 segments.
KITTI_MIN_SEGMENTS = 3
#: Frame rate the devkit assumes for its speeds (``0.1`` s per frame), Hz.
KITTI_RATE = 10.0


@dataclass(frozen=True)
class KittiSegments:
    """The devkit's segment errors of one sequence, in its order (start frame, then length).

    Attributes:
        first, last: (K,) start and end frame of each segment (indices of the paired poses).
        length: (K,) the segment length L, metres.
        r_err: (K,) rotation error per metre, radians per metre.
        t_err: (K,) translation error per metre, metres per metre.
        speed: (K,) L over the segment's duration at 10 Hz, metres per second (the devkit's).
        precision: ``single`` (float32 values, the devkit's) or ``double``.
    """

    first: np.ndarray
    last: np.ndarray
    length: np.ndarray
    r_err: np.ndarray
    t_err: np.ndarray
    speed: np.ndarray
    precision: str

    def __len__(self) -> int:
        return len(self.first)


def as_matrices(poses: np.ndarray, what: str = "poses") -> np.ndarray:
    """(N, 4, 4) float64 pose matrices of (N, 3, 4) ``[R | t]`` blocks as written, or of (N, 4, 4)
    matrices (taken as they are), or of (N, 12) rows of a KITTI file."""
    p = np.asarray(poses, float)
    if p.ndim == 2 and p.shape[1] == 12:
        p = p.reshape(-1, 3, 4)
    if p.ndim != 3 or p.shape[1:] not in ((3, 4), (4, 4)):
        raise EvaluationError(f"{what}: expected (N, 3, 4) or (N, 4, 4) pose matrices, got shape {p.shape}")
    if p.shape[1] == 4:
        return p
    out = np.zeros((len(p), 4, 4))
    out[:, :3, :] = p
    out[:, 3, 3] = 1.0
    return out


def kitti_distances(positions: np.ndarray, precision: str = "single") -> np.ndarray:
    """Distance travelled from the first position to each (``trajectoryDistances``), metres; in
    ``single`` precision as the devkit: each step's differences rounded to float, the squared
    norm, its root and the running sum in float."""
    precision = choice("precision", precision, PRECISIONS)
    p = np.asarray(positions, float)
    if len(p) == 0:
        return np.zeros(0, np.float32 if precision == "single" else float)
    d = p[:-1] - p[1:]
    if precision == "single":
        d = d.astype(np.float32)
        step = np.sqrt((d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1]) + d[:, 2] * d[:, 2])
        return np.concatenate((np.zeros(1, np.float32), np.cumsum(step, dtype=np.float32)))
    step = np.sqrt((d[:, 0] ** 2 + d[:, 1] ** 2) + d[:, 2] ** 2)
    return np.concatenate(([0.0], np.cumsum(step)))


def kitti_segments(
    gt_poses: np.ndarray,
    est_poses: np.ndarray,
    precision: str = "single",
    lengths: tuple[float, ...] = KITTI_LENGTHS,
    step: int = KITTI_STEP,
) -> KittiSegments:
    """The devkit's ``calcSequenceErrors`` on paired poses (pose i of ``est_poses`` with pose i of
    ``gt_poses``; see :func:`as_matrices` for the shapes): every segment's rotation and
    translation error per metre (see the module docstring). Vectorized: the end frames by
    ``searchsorted`` on the (non-decreasing) distances, the matrices inverted in one batch."""
    precision = choice("precision", precision, PRECISIONS)
    gt, est = as_matrices(gt_poses, "ground truth"), as_matrices(est_poses, "estimate")
    if len(gt) != len(est):
        raise EvaluationError(
            f"the KITTI metric pairs pose i with pose i: the estimate has {len(est)} poses, the ground truth "
            f"{len(gt)} (the devkit refuses such files: 'Couldn't read (all) poses')"
        )
    single = precision == "single"
    real = np.float32 if single else np.float64
    dist = kitti_distances(gt[:, :3, 3], precision)
    firsts = np.arange(0, len(gt), int(step))
    lens = np.asarray(lengths, real)
    first = np.repeat(firsts, lens.size)  # the devkit's order: start frame, then length
    length = np.tile(lens, firsts.size)
    target = dist[first] + length  # in float for single, as dist[first_frame]+len
    last = np.searchsorted(dist, target, side="right")  # first frame with dist > target (dist non-decreasing)
    ok = last < len(gt)
    first, last, length = first[ok], last[ok], length[ok]
    inv = np.linalg.inv
    delta_gt = inv(gt[first]) @ gt[last]
    delta_est = inv(est[first]) @ est[last]
    err = inv(delta_est) @ delta_gt
    diag = err[:, [0, 1, 2], [0, 1, 2]].astype(real)
    if single:  # float d = 0.5*(a+b+c-1.0): the float sum, then double arithmetic, rounded to float
        d = (0.5 * ((diag[:, 0] + diag[:, 1] + diag[:, 2]).astype(float) - 1.0)).astype(np.float32)
        angle = np.arccos(np.clip(d, np.float32(-1.0), np.float32(1.0)).astype(float)).astype(np.float32)
    else:
        angle = np.arccos(np.clip(0.5 * ((diag[:, 0] + diag[:, 1]) + diag[:, 2] - 1.0), -1.0, 1.0))
    t = err[:, :3, 3].astype(real)
    trans = np.sqrt((t[:, 0] * t[:, 0] + t[:, 1] * t[:, 1]) + t[:, 2] * t[:, 2])
    frames = (last - first + 1).astype(real)
    speed = (length.astype(float) / (0.1 * frames.astype(float))).astype(real)
    return KittiSegments(first, last, length, angle / length, trans / length, speed, precision)


def kitti_mean(values: np.ndarray, precision: str = "single") -> float:
    """The devkit's mean: a running sum in ``float`` divided by the count as ``float`` (``saveStats``);
    in ``double``, the running sum in double. NaN for no value."""
    v = np.asarray(values)
    if v.size == 0:
        return float("nan")
    if choice("precision", precision, PRECISIONS) == "single":
        return float(np.cumsum(v, dtype=np.float32)[-1] / np.float32(v.size))
    return float(np.cumsum(v, dtype=float)[-1] / v.size)


def concat_segments(parts: list[KittiSegments]) -> KittiSegments:
    """Segments of several sequences in order (the devkit's ``total_err``)."""
    if not parts:
        z = np.zeros(0)
        return KittiSegments(z.astype(int), z.astype(int), z, z, z, z, "single")
    precision = parts[0].precision
    if any(p.precision != precision for p in parts):
        raise EvaluationError("KITTI segments of different precisions cannot be averaged together")
    cat = {k: np.concatenate([getattr(p, k) for p in parts]) for k in ("first", "last", "length", "r_err", "t_err", "speed")}  # fmt: skip
    return KittiSegments(precision=precision, **cat)


def kitti_summary(segments: KittiSegments) -> dict[str, float]:
    """The devkit's summary (``stats.txt``) as the leaderboard reports it: ``kitti_t_err`` (percent),
    ``kitti_r_err`` (degrees per 100 m), ``kitti_segments`` (their count; 0 with NaN errors when no
    segment fits the ground truth's length)."""
    t = kitti_mean(segments.t_err, segments.precision)
    r = kitti_mean(segments.r_err, segments.precision)
    return {"kitti_t_err": 100.0 * t, "kitti_r_err": float(np.degrees(r)) * 100.0, "kitti_segments": len(segments)}


def kitti_length_errors(segments: KittiSegments, lengths: tuple[float, ...] = KITTI_LENGTHS) -> pd.DataFrame:
    """The devkit's per-length errors (``saveErrorPlots``'s ``_tl`` and ``_rl`` files): for each
    length, ``segments`` (count), ``t_err`` (percent) and ``r_err`` (degrees per 100 m), means of the
    segments of that length (``|len - L| < 1``); ``plotted``: the devkit writes (plots) a length
    only with at least :data:`KITTI_MIN_SEGMENTS` segments."""
    import pandas as pd

    rows = []
    for length in lengths:
        sel = np.abs(segments.length.astype(float) - float(length)) < 1.0
        n = int(sel.sum())
        rows.append(
            dict(
                length=float(length),
                segments=n,
                plotted=n >= KITTI_MIN_SEGMENTS,
                t_err=100.0 * kitti_mean(segments.t_err[sel], segments.precision),
                r_err=float(np.degrees(kitti_mean(segments.r_err[sel], segments.precision))) * 100.0,
            )  # fmt: skip
        )
    return pd.DataFrame(rows, columns=["length", "segments", "plotted", "t_err", "r_err"])
