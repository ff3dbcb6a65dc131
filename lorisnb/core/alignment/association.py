"""Sensor frames and time association of an estimate with interpolated ground truth.

Association (OpenLORIS-Scene paper Sec. V-A; official tool ``associate_with_interpolation``): an
estimate stamp t inside the ground-truth time span is matched when its two bracketing
ground-truth stamps k1 <= t <= k2 satisfy ``max(t - k1, k2 - t) < max_gap`` (0.5 s). The
ground-truth position is interpolated linearly and the orientation by slerp. Where the ground
truth is sparser than the bracket (:func:`sparser_than`: its median interval is ``max_gap`` or
more, e.g. 1 Hz against 0.5 s), the bracket matches almost nothing, and a stamp equal to a
ground-truth stamp is matched whatever its bracket: its ground truth is that pose, interpolated
from nothing (an estimate at 100 Hz against a ground truth at 1 Hz matches at every ground-truth
stamp it shares). Denser ground truth (OpenLORIS's) keeps the official rule unchanged, gaps
included. Unmatched estimates are ignored (not counted wrong).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from lorisnb.core.alignment.geometry import (
    official_slerp,
    quat_multiply,
    quat_normalize,
    quat_rotate,
    quat_to_matrix,
    ros_quaternion_from_matrix,
    rotations_of,
    slerp,
)
from lorisnb.core.trajectory.blocks import blockwise
from lorisnb.core.trajectory.frames import extrinsic, relative_extrinsic
from lorisnb.core.trajectory.poses import Trajectory

if TYPE_CHECKING:
    from scipy.spatial.transform import Rotation

MAX_GAP = 0.5  # seconds; the official tool's bracket


def groundtruth_in_frame(
    gt: Trajectory, scene: str, frame: str, official_interpolation: bool = False, gt_frame: str = "base_link"
) -> Trajectory:
    """Ground-truth poses of ``gt_frame`` (``base_link`` in OpenLORIS) moved to sensor ``frame``:
    ``world_T_gt @ T_gt_frame``.

    With ``official_interpolation=True`` the quaternions are computed as the official tool computes them (ROS
    tf's ``quaternion_from_matrix``), whose signs decide its interpolation slip; otherwise they are
    scipy's. The same frame returns ``gt`` unchanged (raw quaternions, as read).
    """
    if frame == gt_frame:
        return gt
    if gt_frame == "base_link":
        t_off, q_off = extrinsic(scene, frame)
        q_off = quat_normalize(q_off)
    else:
        t_off, q_off = relative_extrinsic(scene, gt_frame, frame)
    q = quat_normalize(gt.quaternions)
    positions = gt.positions + quat_rotate(q, t_off)
    quats = quat_normalize(quat_multiply(q, q_off))
    if official_interpolation:
        quats = ros_quaternion_from_matrix(quat_to_matrix(quats))
    return Trajectory.from_checked(gt.stamps, positions, quats, gt.lines, dict(gt.meta))


@dataclass(frozen=True)
class Association:
    """Matched estimate poses and the ground truth interpolated at their stamps.

    Attributes:
        est_index: (M,) indices of the matched poses in the estimate.
        stamps: (M,) their stamps, seconds, increasing.
        gt_positions: (M, 3) interpolated ground-truth positions, metres.
        gt_quaternions: (M, 4) interpolated ground-truth orientations, unit quaternions ``xyzw``
            (None if M = 0); ``gt_rotations`` gives them as a scipy ``Rotation``.
        gt_start, gt_end: first and last ground-truth stamp of the sequence, seconds.
        gt_blocks: (M, 3, 3) the matched ground-truth poses' rotation blocks as their file wrote
            them (:func:`lorisnb.core.trajectory.poses.written_blocks`), where a convention
            composes the matrices as written and they are known; else None.
        gt_read_quaternions: (M, 4) the matched ground-truth poses' quaternions as read (not
            normalized), where the spec computes its numbers from the poses as read
            (``EvalSpec.poses_as_read``) and the poses are the file's (``nearest``); else None.
    """

    est_index: np.ndarray
    stamps: np.ndarray
    gt_positions: np.ndarray
    gt_quaternions: np.ndarray | None
    gt_start: float
    gt_end: float
    gt_blocks: np.ndarray | None = field(default=None, repr=False)
    gt_read_quaternions: np.ndarray | None = field(default=None, repr=False)

    def __len__(self) -> int:
        return len(self.stamps)

    def __repr__(self) -> str:
        span = f"{self.stamps[0]:.3f}..{self.stamps[-1]:.3f} s" if len(self.stamps) else "none"
        return f"<Association: {len(self.stamps)} matched poses ({span}); ground truth {self.gt_start:.3f}..{self.gt_end:.3f} s>"

    @property
    def gt_rotations(self) -> Rotation | None:
        """:attr:`gt_quaternions` as a scipy ``Rotation`` (built on request)."""
        return rotations_of(self.gt_quaternions)

    def est_rows(self, values: np.ndarray) -> np.ndarray:
        """The rows of an estimate's array (positions, quaternions) of the matched poses: a view
        when they are consecutive (the usual case: no copy of a million rows), else a copy. Read
        it, never write into it."""
        i = self.est_index
        if i.size and int(i[-1]) - int(i[0]) == i.size - 1 and (i.size < 2 or bool((i[1:] > i[:-1]).all())):
            return values[int(i[0]) : int(i[-1]) + 1]
        return values[i]


def sparser_than(gt_stamps: np.ndarray, max_gap: float) -> bool:
    """Whether ground truth of these stamps (seconds, increasing) is sparser than the bracket: its
    median interval is ``max_gap`` or more, so that interpolation within the bracket can match
    (almost) no estimate stamp, and :func:`associate` matches equal stamps whatever their bracket."""
    return len(gt_stamps) >= 2 and bool(np.median(np.diff(gt_stamps)) >= max_gap)


def associate(
    gt: Trajectory, est_stamps: np.ndarray, max_gap: float = MAX_GAP, official_interpolation: bool = False
) -> Association:
    """Match estimate stamps to the ground truth by interpolation (see the module docstring).

    Args:
        gt: ground truth in the estimate's frame, stamps strictly increasing.
        est_stamps: (N,) estimate stamps, seconds, strictly increasing.
        max_gap: the bracket in seconds (strict: ``max(t - k1, k2 - t) < max_gap``); a stamp equal to a
            ground-truth stamp is matched whatever its bracket where the ground truth is sparser
            than it (:func:`sparser_than`).
        official_interpolation: interpolate orientations as the official tool does (slip (a): see
            :func:`lorisnb.core.alignment.geometry.official_slerp`; at a stamp equal to a ground-truth stamp it
            uses the interval ending there). Positions are the same either way.
    """
    g = gt.stamps
    t = np.asarray(est_stamps, float)
    gt_start = float(g[0]) if len(g) else np.nan
    gt_end = float(g[-1]) if len(g) else np.nan
    if len(g) < 2 or len(t) == 0:
        return Association(np.zeros(0, int), np.zeros(0), np.zeros((0, 3)), None, gt_start, gt_end)
    i = np.empty(len(t), np.intp)
    ok = np.empty(len(t), bool)

    increasing = bool(np.all(t[1:] >= t[:-1]))  # as a Trajectory's stamps are
    sparse: list[bool] = []  # sparser_than(g, max_gap), worked out only where an equal stamp needs it (a median)

    def bracket(lo: int, hi: int) -> None:  # the ground-truth interval of each stamp, and whether it matches
        tt = t[lo:hi]
        w0, w1 = np.searchsorted(g, (tt[0], tt[-1]), side="left") if increasing else (0, len(g))
        # increasing stamps: only the ground truth between the block's first and last stamp can bracket them
        k = np.clip(np.searchsorted(g[w0 : w1 + 1], tt, side="left") + (w0 - 1), 0, len(g) - 2)
        i[lo:hi] = k
        g1, g2 = np.take(g, k), np.take(g, k + 1)
        inside = (tt >= g[0]) & (tt <= g[-1])
        near = np.maximum(tt - g1, g2 - tt) < max_gap
        ok[lo:hi] = inside & near
        exact = inside & ~near & ((tt == g1) | (tt == g2))  # the ground-truth pose itself: no interpolation, no
        if exact.any():  # bracket, where the ground truth is sparser than it
            if not sparse:
                sparse.append(sparser_than(g, max_gap))
            if sparse[0]:
                ok[lo:hi] |= exact

    blockwise(bracket, len(t))
    idx = np.flatnonzero(ok)
    if idx.size == 0:
        return Association(idx, np.zeros(0), np.zeros((0, 3)), None, gt_start, gt_end)
    t, i = t[idx], i[idx]
    p, q = gt.positions, gt.quaternions
    pos, quats = np.empty((len(t), 3)), np.empty((len(t), 4))

    def rows(lo: int, hi: int) -> None:
        k = i[lo:hi]
        k2 = k + 1
        take = np.take  # gathers: faster than fancy indexing, and without the GIL
        g1 = take(g, k)
        w2 = (t[lo:hi] - g1) / (take(g, k2) - g1)
        w1 = 1.0 - w2
        pos[lo:hi] = w1[:, None] * take(p, k, axis=0) + w2[:, None] * take(p, k2, axis=0)
        q1, q2 = take(q, k, axis=0), take(q, k2, axis=0)
        if official_interpolation:
            quats[lo:hi] = quat_normalize(official_slerp(q1, q2, w1, w2))
        else:  # slerp between the bracketing ground-truth poses (scipy's Slerp on each interval)
            quats[lo:hi] = slerp(q1, q2, w2)

    blockwise(rows, len(t))
    return Association(idx, t, pos, quats, gt_start, gt_end)
