"""Does an estimator know its own error? OpenVINS' ``ov_eval`` metrics of a trajectory that carries
pose covariances: the normalized estimation error squared (NEES) of orientation and position, the
error on each axis with its 3-sigma bound, the yaw-only (``posyaw``) and 2D ATE.

Exactly as ``ov_eval``'s ``ResultTrajectory`` computes them (github.com/rpng/open_vins,
``ov_eval/src/calc/ResultTrajectory.cpp``; ``tests/core/test_ov_eval.py`` runs it on the same files):

- **Association** (``AlignUtils::perform_association``, offset 0, ``max_diff`` 0.02 s): each
  estimate pose, in order, takes the ground-truth pose nearest in time less than ``max_diff`` away
  among those after the one the previous match took (:func:`associate_sequential`, with ov_eval's
  comparisons of each difference as computed); a matched pose is stamped with its ground truth's stamp.
- **Alignment** (``align``: ``posyaw`` (ov_eval's default: translation and yaw), ``se3``, ``sim3``,
  ``none``; :func:`lorisnb.core.conventions.choices.fit_alignment`), fitted on all matched positions
  both ways: the estimate onto the ground truth for the ATE, the ground truth onto the estimate
  for the NEES and the per-axis errors (so these are in the estimate's frame, where its covariance
  lives).
- **ATE** per pose: position error (m) and orientation error (deg, the angle of
  ``R_est_aligned^T R_gt``); **2D ATE**: the error of x and y only, and the signed z component of
  that rotation's log (deg).
- **NEES** per pose (unitless; its mean is 3 for a consistent estimator, the dimension of each
  part): ``e^T P^-1 e`` with ``e`` the orientation error ``-log(R_gt^T R_est)`` (rad, about the
  estimate's body axes, the local error OpenVINS' covariance describes) and ``P`` the orientation
  block of the covariance (rad^2); for position ``e = p_gt - p_est`` (m, world axes) and the
  position block (m^2), inverted as ``ov_eval`` inverts it (Eigen's cofactors). A pose whose
  inverse gives NaN (a singular covariance, e.g. all zeros) has no NEES and is left out of the NEES
  statistics, as ``ov_eval`` skips it; a covariance that is not positive definite but can be
  inverted gives a NEES as in ``ov_eval`` (negative or meaningless), and a note says how many.
- **Per-axis errors** with 3-sigma bounds: position ``p_gt - p_est`` per world axis (m, bound
  ``3 sqrt(P_ii)``); orientation twice the vector part of the JPL error quaternion
  ``q_gt (x) q_est^-1`` turned into world axes (deg, the covariance turned likewise); roll, pitch
  and yaw of the ground truth minus those of the estimate (deg, wrapped to [-180, 180], the bound
  from the covariance mapped by the Euler-rate Jacobian).

Quaternions are used as written (``ov_eval`` does not normalize them) and read as ``ov_eval``
reads its files: the numbers ``qx qy qz qw`` of a ROS orientation (Hamilton, body to world) taken as
a JPL quaternion of world to body, which is the same rotation. The statistics of each series are
``ov_eval``'s ``Statistics``: RMSE, mean, median, standard deviation (n - 1), min and max.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from lorisnb.core.alignment.geometry import Sim3
from lorisnb.core.conventions.choices import fit_alignment
from lorisnb.core.spec.evalspec import OV_ALIGNMENTS
from lorisnb.core.spec.validate import choice, positive
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.errors import EvaluationError, ValidationError

#: ``ov_eval``'s association bracket, seconds.
OV_MAX_DIFF = 0.02
#: The series of :attr:`Consistency.summary`, in ``ov_eval``'s order, with their units.
SERIES = {
    "ate_ori": "deg", "ate_pos": "m", "ate2d_yaw": "deg", "ate2d_pos": "m", "nees_ori": "", "nees_pos": "",
    "pos_x": "m", "pos_y": "m", "pos_z": "m", "ori_x": "deg", "ori_y": "deg", "ori_z": "deg",
    "roll": "deg", "pitch": "deg", "yaw": "deg",
}  # fmt: skip
#: The per-axis series that have a 3-sigma bound column (``<name>_3sigma``) when covariances are given.
BOUNDED = ("pos_x", "pos_y", "pos_z", "ori_x", "ori_y", "ori_z", "roll", "pitch", "yaw")


@dataclass(frozen=True)
class PoseCovariances:
    """The covariance of each pose of a trajectory, as OpenVINS writes it (``ov_eval``'s file layout
    and ROS ``PoseWithCovariance``): ``orientation`` (N, 3, 3), rad^2, of the orientation error about
    the body axes; ``position`` (N, 3, 3), m^2, world axes. Symmetric (made so on construction, as
    ``ov_eval`` does: the mean of the matrix and its transpose) and finite."""

    orientation: np.ndarray
    position: np.ndarray

    def __post_init__(self) -> None:
        blocks = []
        for name in ("orientation", "position"):
            a = np.asarray(getattr(self, name), float)
            if a.ndim != 3 or a.shape[1:] != (3, 3):
                raise ValidationError(f"PoseCovariances.{name}: expected an (N, 3, 3) array, got shape {a.shape}")
            if not np.isfinite(a).all():
                raise ValidationError(f"PoseCovariances.{name}: expected finite numbers (a NaN or inf is in it)")
            blocks.append(0.5 * (a + a.transpose(0, 2, 1)))
        if len(blocks[0]) != len(blocks[1]):
            raise ValidationError(
                f"PoseCovariances: {len(blocks[0])} orientation and {len(blocks[1])} position blocks; expected one "
                "of each per pose"
            )
        object.__setattr__(self, "orientation", blocks[0])
        object.__setattr__(self, "position", blocks[1])

    def __len__(self) -> int:
        return len(self.orientation)

    def take(self, index: np.ndarray) -> "PoseCovariances":
        """The covariances of the poses ``index`` (an integer or boolean array)."""
        return PoseCovariances(self.orientation[index], self.position[index])

    @classmethod
    def from_upper(cls, values: np.ndarray) -> "PoseCovariances":
        """From ``ov_eval``'s 12 numbers a pose (N, 12): the upper triangles, row by row, of the
        orientation block (``Pr11 Pr12 Pr13 Pr22 Pr23 Pr33``) then of the position block."""
        v = np.asarray(values, float)
        if v.ndim != 2 or v.shape[1] != 12:
            raise ValidationError(f"PoseCovariances.from_upper: expected (N, 12) numbers, got shape {v.shape}")
        iu = ([0, 0, 0, 1, 1, 2], [0, 1, 2, 1, 2, 2])
        out = []
        for part in (v[:, :6], v[:, 6:]):
            m = np.zeros((len(v), 3, 3))
            m[:, iu[0], iu[1]] = part
            m[:, iu[1], iu[0]] = part
            out.append(m)
        return cls(out[0], out[1])

    @classmethod
    def from_ros(cls, covariance: np.ndarray) -> "PoseCovariances":
        """From ROS ``PoseWithCovariance.covariance`` (N, 36): row-major 6x6 in the order x, y, z,
        rotation about x, y, z; the position block is its top left, the orientation block its bottom
        right (as OpenVINS' ``Recorder`` takes them)."""
        c = np.asarray(covariance, float)
        if c.ndim != 2 or c.shape[1] != 36:
            raise ValidationError(f"PoseCovariances.from_ros: expected (N, 36) numbers, got shape {c.shape}")
        m = c.reshape(-1, 6, 6)
        return cls(m[:, 3:, 3:], m[:, :3, :3])


@dataclass
class Consistency:
    """``poses``: one row per matched pose (``t``, seconds, the ground truth's stamp; every series
    of :data:`SERIES` and, with covariances, the ``<axis>_3sigma`` bounds of :data:`BOUNDED` and
    ``nees_ori``, ``nees_pos``); ``summary``: one row per series (``series``, ``unit``, ``rmse``,
    ``mean``, ``median``, ``std``, ``min``, ``max``, ``count``; and for the bounded series
    ``within_3sigma``, the share of poses whose error is inside its bound: about 0.997 for a
    consistent estimator with Gaussian errors); ``to_gt`` / ``to_est``: the two alignments;
    ``notes``: what the alignment said (e.g. a tilt that posyaw cannot absorb)."""

    poses: pd.DataFrame
    summary: pd.DataFrame
    to_gt: Sim3
    to_est: Sim3
    notes: list[str] = field(default_factory=list)


def associate_sequential(
    gt_stamps: np.ndarray, est_stamps: np.ndarray, max_diff: float = OV_MAX_DIFF
) -> tuple[np.ndarray, np.ndarray]:
    """``ov_eval``'s association (``AlignUtils::perform_association`` with offset 0), with its
    floating-point comparisons: a pointer into the ground truth, which only moves forward, skips the
    rows with ``g < t`` and ``|g - t| > max_diff`` (each difference as computed, never ``t - max_diff``
    against ``g``), then takes rows while ``|g - t|`` is below ``max_diff`` and below the last one
    taken, and stops at the first that is not (so ties go to the earlier row, a repeated stamp to its
    first row, and a row exactly ``max_diff`` before ``t`` stops the scan without a match). The
    estimate pose is paired with the last row taken; the pointer stays after it. Returns the matched
    ``(gt index, est index)`` arrays, in estimate order.

    Vectorized: each estimate stamp's scan started where nothing before it would stop it (the first
    row it does not skip, found by bisection on ov_eval's own test); its result follows from the
    nearest rows around ``t``. Only where the previous match left the pointer beyond that row (an
    estimate denser than the ground truth), or where differences may round (stamps within
    ``2 max_diff`` of 0) or the ground truth is not in order, is ov_eval's scan run as written, on
    those poses alone, until its pointer is again where the vectorized scan has it."""
    g = np.asarray(gt_stamps, float)
    e = np.asarray(est_stamps, float)
    md = float(max_diff)
    n = g.size
    if n == 0 or e.size == 0:
        return np.zeros(0, int), np.zeros(0, int)
    if not np.all(g[1:] >= g[:-1]):  # not in order (NaN too): ov_eval's scan as written
        gi, ei = _ov_scan(g, e, md, np.zeros(1, np.intp), np.zeros(e.size, np.intp))
        return gi[gi >= 0], ei[gi >= 0]
    right = np.searchsorted(g, e, side="left")  # the first row with g >= t: never skipped
    lo, hi = np.zeros(e.size, np.intp), right.copy()
    while True:  # bisection: the rows ov_eval skips (g < t and |g - t| > max_diff) are a prefix
        active = lo < hi
        if not active.any():
            break
        mid = (lo + hi) // 2
        skip = np.abs(g.take(mid, mode="clip") - e) > md
        lo = np.where(active & skip, mid + 1, lo)
        hi = np.where(active & ~skip, mid, hi)
    first = lo  # where the scan of each stamp starts when the previous match does not hold it back
    d_first = np.abs(g.take(first, mode="clip") - e)
    matched = (first < n) & (d_first < md)  # below max_diff (<=) and below the best so far (max_diff)
    # the scan takes rows while |g - t| decreases: up to the row before t, or the one after if nearer
    # (not if as near: the earlier), or the first of a repeated stamp before t
    d_before = np.abs(g.take(right - 1, mode="clip") - e)
    d_after = np.where(right < n, np.abs(g.take(right, mode="clip") - e), np.inf)
    end = np.where(d_after < d_before, right, right - 1)
    repeat = np.where(np.append(g[1:] == g[:-1], False), np.arange(n), n)
    repeat = np.minimum.accumulate(repeat[::-1])[::-1]  # the first repeated row at or after each row
    best = np.where(first >= right, first, np.minimum(end, repeat.take(first, mode="clip")))
    after = np.where(matched, best + 1, first)  # the pointer after each stamp
    before = np.concatenate([[0], after[:-1]])
    exact = np.abs(e) >= 2 * md  # then every difference below max_diff is exact (Sterbenz), no two equal
    redo = np.flatnonzero((before > first) | ~exact)
    if redo.size:
        gi, ei = _ov_scan(g, e, md, redo, before, first, after)
        best[ei], matched[ei] = gi, gi >= 0
    ei = np.flatnonzero(matched)
    return best[ei], ei


def _ov_scan(
    g: np.ndarray,
    e: np.ndarray,
    md: float,
    starts: np.ndarray,
    pointer: np.ndarray,
    first: np.ndarray | None = None,
    sync: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """ov_eval's scan as written (``perform_association``), from each estimate index of ``starts``
    (increasing) with the pointer ``pointer[start]``, one pose at a time until the pointer after a
    pose equals ``sync`` there (None: to the end); ``first``: where each stamp's scan may begin (the
    rows before it are skipped anyway). Returns the scanned poses' ``(gt index or -1, est index)``."""
    gl, n = g.tolist(), g.size
    out_g, out_e = [], []
    done = -1
    for s in starts.tolist():  # poses whose pointer depends on the previous match, and no others
        if s <= done:
            continue
        p = int(pointer[s])
        for i in range(s, e.size):
            t = float(e[i])
            if first is not None:
                p = max(p, int(first[i]))
            while p < n and gl[p] < t and abs(gl[p] - t) > md:
                p += 1
            best, best_j = md, -1
            while p < n and abs(gl[p] - t) <= md:
                if abs(gl[p] - t) >= best:
                    break
                best, best_j = abs(gl[p] - t), p
                p += 1
            out_g.append(best_j)
            out_e.append(i)
            done = i
            if sync is not None and p == int(sync[i]):
                break
    return np.array(out_g, np.intp), np.array(out_e, np.intp)


def _jpl_matrix(q: np.ndarray) -> np.ndarray:
    """``ov_core::quat_2_Rot`` of (N, 4) quaternions as written: ``(2 w^2 - 1) I - 2 w [v]x + 2 v v^T``."""
    v, w = q[:, :3], q[:, 3]
    m = (2 * w**2 - 1)[:, None, None] * np.eye(3) + 2 * v[:, :, None] * v[:, None, :]
    m[:, 0, 1] += 2 * w * v[:, 2]
    m[:, 0, 2] -= 2 * w * v[:, 1]
    m[:, 1, 0] -= 2 * w * v[:, 2]
    m[:, 1, 2] += 2 * w * v[:, 0]
    m[:, 2, 0] += 2 * w * v[:, 1]
    m[:, 2, 1] -= 2 * w * v[:, 0]
    return m


def _jpl_multiply(q: np.ndarray, p: np.ndarray) -> np.ndarray:
    """``ov_core::quat_multiply``: the JPL product ``q (x) p`` of (N, 4) quaternions, its scalar made
    positive, normalized."""
    qv, qw, pv, pw = q[:, :3], q[:, 3:], p[:, :3], p[:, 3:]
    vec = qw * pv - np.cross(qv, pv) + qv * pw
    w = qw * pw - np.sum(qv * pv, axis=1, keepdims=True)
    out = np.concatenate([vec, w], axis=1)
    out = np.where(out[:, 3:] < 0, -out, out)
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def _inverse(q: np.ndarray) -> np.ndarray:
    return q * np.array([-1.0, -1.0, -1.0, 1.0])


def _rot_to_jpl(r: np.ndarray) -> np.ndarray:
    """``ov_core::rot_2_quat`` of one rotation matrix: the JPL quaternion whose matrix is ``r``."""
    t = np.trace(r)
    q = np.zeros(4)
    if r[0, 0] >= t and r[0, 0] >= r[1, 1] and r[0, 0] >= r[2, 2]:
        q[0] = np.sqrt((1 + 2 * r[0, 0] - t) / 4)
        q[1], q[2], q[3] = (
            (r[0, 1] + r[1, 0]) / (4 * q[0]),
            (r[0, 2] + r[2, 0]) / (4 * q[0]),
            (r[1, 2] - r[2, 1]) / (4 * q[0]),
        )
    elif r[1, 1] >= t and r[1, 1] >= r[0, 0] and r[1, 1] >= r[2, 2]:
        q[1] = np.sqrt((1 + 2 * r[1, 1] - t) / 4)
        q[0], q[2], q[3] = (
            (r[0, 1] + r[1, 0]) / (4 * q[1]),
            (r[1, 2] + r[2, 1]) / (4 * q[1]),
            (r[2, 0] - r[0, 2]) / (4 * q[1]),
        )
    elif r[2, 2] >= t and r[2, 2] >= r[0, 0] and r[2, 2] >= r[1, 1]:
        q[2] = np.sqrt((1 + 2 * r[2, 2] - t) / 4)
        q[0], q[1], q[3] = (
            (r[0, 2] + r[2, 0]) / (4 * q[2]),
            (r[1, 2] + r[2, 1]) / (4 * q[2]),
            (r[0, 1] - r[1, 0]) / (4 * q[2]),
        )
    else:
        q[3] = np.sqrt((1 + t) / 4)
        q[0], q[1], q[2] = (
            (r[1, 2] - r[2, 1]) / (4 * q[3]),
            (r[2, 0] - r[0, 2]) / (4 * q[3]),
            (r[0, 1] - r[1, 0]) / (4 * q[3]),
        )
    if q[3] < 0:
        q = -q
    return q / np.linalg.norm(q)


def _log_so3(r: np.ndarray) -> np.ndarray:
    """``ov_core::log_so3`` of (N, 3, 3) matrices (rad), its branches for angles near 0 and pi."""
    tr = np.trace(r, axis1=1, axis2=2)
    vee = np.stack([r[:, 2, 1] - r[:, 1, 2], r[:, 0, 2] - r[:, 2, 0], r[:, 1, 0] - r[:, 0, 1]], axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        theta = np.arccos((tr - 1.0) / 2.0)
        magnitude = np.where(tr - 3.0 < -1e-7, theta / (2.0 * np.sin(theta)), 0.5 - (tr - 3.0) / 12.0)
        out = magnitude[:, None] * vee
        at_pi = tr + 1.0 < 1e-10
        if at_pi.any():
            for k in np.flatnonzero(at_pi):  # a rotation by pi exactly: a few poses at most
                m = r[k]
                if abs(m[2, 2] + 1.0) > 1e-5:
                    out[k] = np.pi / np.sqrt(2.0 + 2.0 * m[2, 2]) * np.array([m[0, 2], m[1, 2], 1.0 + m[2, 2]])
                elif abs(m[1, 1] + 1.0) > 1e-5:
                    out[k] = np.pi / np.sqrt(2.0 + 2.0 * m[1, 1]) * np.array([m[0, 1], 1.0 + m[1, 1], m[2, 1]])
                else:
                    out[k] = np.pi / np.sqrt(2.0 + 2.0 * m[0, 0]) * np.array([1.0 + m[0, 0], m[1, 0], m[2, 0]])
    return out


def _rpy(r: np.ndarray) -> np.ndarray:
    """``ov_core::rot2rpy`` of (N, 3, 3) matrices: roll, pitch, yaw (rad)."""
    pitch = np.arctan2(-r[:, 2, 0], np.sqrt(r[:, 0, 0] ** 2 + r[:, 1, 0] ** 2))
    c = np.cos(pitch)
    regular = np.abs(c) > 1.0e-12
    with np.errstate(invalid="ignore", divide="ignore"):
        yaw = np.where(regular, np.arctan2(r[:, 1, 0] / c, r[:, 0, 0] / c), 0.0)
        roll = np.where(regular, np.arctan2(r[:, 2, 1] / c, r[:, 2, 2] / c), np.arctan2(r[:, 0, 1], r[:, 1, 1]))
    return np.stack([roll, pitch, yaw], axis=1)


def _rot_x(t: np.ndarray) -> np.ndarray:
    c, s = np.cos(t), np.sin(t)
    m = np.zeros((len(t), 3, 3))
    m[:, 0, 0] = 1.0
    m[:, 1, 1], m[:, 1, 2], m[:, 2, 1], m[:, 2, 2] = c, -s, s, c
    return m


def _rot_y(t: np.ndarray) -> np.ndarray:
    c, s = np.cos(t), np.sin(t)
    m = np.zeros((len(t), 3, 3))
    m[:, 1, 1] = 1.0
    m[:, 0, 0], m[:, 0, 2], m[:, 2, 0], m[:, 2, 2] = c, s, -s, c
    return m


def _eigen_inverse(m: np.ndarray) -> np.ndarray:
    """Eigen's ``inverse()`` of (N, 3, 3) matrices, as ``ov_eval`` inverts a covariance: the cofactors
    of the first column, their dot product with it as the determinant, the adjugate times ``1 / det``
    (inf or NaN for a singular matrix, a number for any other, positive definite or not)."""

    def cof(i: int, j: int) -> np.ndarray:
        i1, i2, j1, j2 = (i + 1) % 3, (i + 2) % 3, (j + 1) % 3, (j + 2) % 3
        return m[:, i1, j1] * m[:, i2, j2] - m[:, i1, j2] * m[:, i2, j1]

    c0 = [cof(0, 0), cof(1, 0), cof(2, 0)]
    det = (c0[0] * m[:, 0, 0] + c0[1] * m[:, 1, 0]) + c0[2] * m[:, 2, 0]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        inv_det = 1.0 / det
        out = np.empty_like(m)
        for i in range(3):
            for j in range(3):
                out[:, i, j] = (c0[j] if i == 0 else cof(j, i)) * inv_det
    return out


def _quadratic(e: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """``e^T cov^-1 e`` per pose as ``ov_eval`` computes it (:func:`_eigen_inverse`, then the row
    ``e^T cov^-1`` times ``e``): NaN where the inverse gives NaN (a singular covariance), and a number,
    negative or meaningless as it may be, for a covariance that is not positive definite."""
    inv = _eigen_inverse(cov)
    with np.errstate(invalid="ignore", over="ignore"):
        row = (e[:, 0, None] * inv[:, 0, :] + e[:, 1, None] * inv[:, 1, :]) + e[:, 2, None] * inv[:, 2, :]
        return (row[:, 0] * e[:, 0] + row[:, 1] * e[:, 1]) + row[:, 2] * e[:, 2]


#: A covariance whose smallest eigenvalue is below this share of its largest is singular to rounding:
#: its inverse, and the NEES with it, is rounding divided by rounding (a rank-2 block gives 1e-16 and
#: a NEES of 1e9 and more).
NEAR_SINGULAR = 1e-12


def _bad_covariances(cov: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Which (N, 3, 3) covariances are not positive definite (a zero or negative eigenvalue), and
    which are positive definite but singular to rounding (:data:`NEAR_SINGULAR`)."""
    ev = np.linalg.eigvalsh(cov)
    not_pd = ~(ev[:, 0] > 0)
    return not_pd, ~not_pd & (ev[:, 0] < NEAR_SINGULAR * ev[:, -1])


def _length_ratio_note(est_positions: np.ndarray, gt_positions: np.ndarray) -> str | None:
    """``ov_eval``'s warning on the two whole files (before association): the estimate's path length
    over the ground truth's outside 0.9..1.1 ("Trajectory is a bad ratio of ... length")."""
    lengths = [float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum()) if len(p) > 1 else 0.0
               for p in (est_positions, gt_positions)]  # fmt: skip
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = lengths[0] / lengths[1] if lengths[1] > 0 else np.inf if lengths[0] > 0 else np.nan
    if ratio > 1.1 or ratio < 0.9:  # NaN (neither moves): no note, as ov_eval's comparisons are false
        return (
            f"the estimate's path is {ratio:.2f} times as long as the ground truth's (estimate {lengths[0]:.2f} m, "
            f"ground truth {lengths[1]:.2f} m, whole files; ov_eval warns outside 0.9..1.1): a scale error "
            "(only sim3 absorbs it), or files that cover different spans"
        )
    return None


def statistics(values: np.ndarray) -> dict[str, float]:
    """``ov_eval``'s ``Statistics::calculate`` of one series: RMSE, mean, median, standard
    deviation (n - 1 in the denominator), min, max, count (NaN where there are no values)."""
    v = np.asarray(values, float)
    n = v.size
    if n == 0:
        return dict(rmse=np.nan, mean=np.nan, median=np.nan, std=np.nan, min=np.nan, max=np.nan, count=0)
    std = float(np.sqrt(np.sum((v - v.mean()) ** 2) / (n - 1))) if n > 1 else np.nan
    return dict(rmse=float(np.sqrt(np.mean(v * v))), mean=float(v.mean()), median=float(np.median(v)), std=std,
                min=float(v.min()), max=float(v.max()), count=n)  # fmt: skip


def ov_eval_errors(
    estimate: Trajectory,
    groundtruth: Trajectory,
    covariances: PoseCovariances | None = None,
    align: str = "posyaw",
    max_diff: float = OV_MAX_DIFF,
) -> Consistency:
    """``ov_eval``'s errors of ``estimate`` against ``groundtruth`` (see the module docstring):
    ATE, 2D ATE, per-axis errors and, when ``covariances`` (one per estimate pose) are given, their
    3-sigma bounds and the NEES. ``align``: one of :data:`OV_ALIGNMENTS`; ``max_diff``: the
    association bracket, seconds. Raises EvaluationError with fewer than 3 matched poses (as
    ``ov_eval`` stops)."""
    align = choice("align", align, OV_ALIGNMENTS)
    max_diff = positive("max_diff", max_diff, "seconds")
    for name, traj in (("estimate", estimate), ("groundtruth", groundtruth)):
        if not isinstance(traj, Trajectory):
            raise ValidationError(f"{name}: expected a Trajectory, got {type(traj).__name__}")
    if covariances is not None:
        if not isinstance(covariances, PoseCovariances):
            raise ValidationError(f"covariances: expected PoseCovariances, got {type(covariances).__name__}")
        if len(covariances) != len(estimate):
            raise ValidationError(
                f"covariances: {len(covariances)} of them for {len(estimate)} estimate poses; expected one per pose"
            )
    gi, ei = associate_sequential(groundtruth.stamps, estimate.stamps, max_diff)
    if gi.size < 3:
        raise EvaluationError(
            f"only {gi.size} estimate pose(s) are within {max_diff:g} s of a ground-truth stamp; ov_eval needs at "
            "least 3: do the two files share a clock (seconds)?"
        )
    notes: list[str | None] = [_length_ratio_note(estimate.positions, groundtruth.positions)]
    p_e, q_e = estimate.positions[ei], estimate.quaternions[ei]
    p_g, q_g = groundtruth.positions[gi], groundtruth.quaternions[gi]
    to_gt = fit_alignment(p_e, p_g, align, notes=notes)
    to_est = fit_alignment(p_g, p_e, align, notes=notes)
    deg = 180.0 / np.pi
    cols: dict[str, np.ndarray] = {"t": groundtruth.stamps[gi]}

    # ATE and 2D ATE: the estimate aligned to the ground truth
    p_ea = to_gt.apply(p_e)
    q_ea = _jpl_multiply(q_e, _inverse(np.broadcast_to(_rot_to_jpl(to_gt.rotation), q_e.shape)))
    e_r = np.transpose(_jpl_matrix(q_ea), (0, 2, 1)) @ _jpl_matrix(q_g)
    log = _log_so3(e_r)
    cols["ate_ori"] = deg * np.linalg.norm(log, axis=1)
    cols["ate_pos"] = np.linalg.norm(p_g - p_ea, axis=1)
    cols["ate2d_yaw"] = deg * log[:, 2]
    cols["ate2d_pos"] = np.linalg.norm(p_g[:, :2] - p_ea[:, :2], axis=1)

    # NEES and per-axis errors: the ground truth aligned to the estimate
    p_ga = to_est.apply(p_g)
    q_ga = _jpl_multiply(q_g, _inverse(np.broadcast_to(_rot_to_jpl(to_est.rotation), q_g.shape)))
    m_e, m_ga = _jpl_matrix(q_e), _jpl_matrix(q_ga)
    err_pos = p_ga - p_e
    e_q = _jpl_multiply(q_ga, _inverse(q_e))
    ori_global = np.einsum("nji,nj->ni", m_e, 2 * e_q[:, :3])  # R_GtoI^T (2 e_q.xyz)
    rpy_e = _rpy(np.transpose(m_e, (0, 2, 1)))
    rpy_err = _rpy(np.transpose(m_ga, (0, 2, 1))) - rpy_e
    rpy_err = np.where(rpy_err < -np.pi, rpy_err + 2 * np.pi, rpy_err)
    rpy_err = np.where(rpy_err > np.pi, rpy_err - 2 * np.pi, rpy_err)
    for k, axis in enumerate("xyz"):
        cols[f"pos_{axis}"] = err_pos[:, k]
    for k, axis in enumerate("xyz"):
        cols[f"ori_{axis}"] = deg * ori_global[:, k]
    for k, name in enumerate(("roll", "pitch", "yaw")):
        cols[name] = deg * rpy_err[:, k]
    if covariances is not None:
        c = covariances.take(ei)
        cov_ori, cov_pos = c.orientation, c.position
        cov_global = np.transpose(m_e, (0, 2, 1)) @ cov_ori @ m_e
        h = np.tile(np.eye(3), (len(ei), 1, 1))
        h[:, :, 1] = _rot_x(-rpy_e[:, 0]) @ np.array([0.0, 1.0, 0.0])
        h[:, :, 2] = _rot_x(-rpy_e[:, 0]) @ _rot_y(-rpy_e[:, 1]) @ np.array([0.0, 0.0, 1.0])
        h_inv = np.linalg.inv(h)
        cov_rpy = h_inv @ cov_ori @ np.transpose(h_inv, (0, 2, 1))
        with np.errstate(invalid="ignore"):  # a negative variance: NaN, as in ov_eval (said below)
            for k, axis in enumerate("xyz"):
                cols[f"pos_{axis}_3sigma"] = 3 * np.sqrt(cov_pos[:, k, k])
            for k, axis in enumerate("xyz"):
                cols[f"ori_{axis}_3sigma"] = 3 * deg * np.sqrt(cov_global[:, k, k])
            for k, name in enumerate(("roll", "pitch", "yaw")):
                cols[f"{name}_3sigma"] = 3 * deg * np.sqrt(cov_rpy[:, k, k])
        e_ori = -_log_so3(m_ga @ np.transpose(m_e, (0, 2, 1)))
        cols["nees_ori"] = _quadratic(e_ori, cov_ori)
        cols["nees_pos"] = _quadratic(err_pos, cov_pos)
        for part, block in (("orientation", cov_ori), ("position", cov_pos)):
            a = "an" if part == "orientation" else "a"
            not_pd, near = _bad_covariances(block)
            if not_pd.any():
                notes.append(
                    f"{int(not_pd.sum())} of {len(not_pd)} matched poses have {a} {part} covariance that is not "
                    f"positive definite (the first at {cols['t'][int(np.argmax(not_pd))]:.6f} s): their NEES is "
                    "computed as ov_eval computes it (from Eigen's inverse; negative, huge or left out where that is "
                    "NaN) and means nothing"
                )
            if near.any():
                k = int(np.argmax(near))
                notes.append(
                    f"{int(near.sum())} of {len(near)} matched poses have {a} {part} covariance that is singular to "
                    f"rounding (smallest eigenvalue below {NEAR_SINGULAR:g} of the largest; the first at "
                    f"{cols['t'][k]:.6f} s, NEES {cols[f'nees_{part[:3]}'][k]:.3g}): their NEES is computed as "
                    "ov_eval computes it (from Eigen's inverse) but is rounding divided by rounding, and the NEES "
                    "statistics with it; a covariance that is flat along one axis (rank 2)?"
                )
    poses = pd.DataFrame(cols)
    lost = [name for name in SERIES if name in poses and not name.startswith("nees") and poses[name].isna().any()]
    if lost:
        k = int(poses[lost].isna().any(axis=1).sum())
        notes.append(
            f"{k} matched pose(s) have no {', '.join(lost)} (NaN, so the statistics of these series are NaN): the "
            "orientation error is within rounding of a half turn, where ov_core's log_so3 of quaternions used as "
            "written (not unit length) takes the square root of a negative number; ov_eval stops there (an "
            "assertion in its Statistics)"
        )
    rows = []
    nees_ok = poses[["nees_ori", "nees_pos"]].notna().all(axis=1) if covariances is not None else None
    for name, unit in SERIES.items():
        if name not in poses:
            continue
        v = poses[name].to_numpy()
        if name.startswith("nees") and nees_ok is not None:
            v = v[nees_ok.to_numpy()]
        row = dict(series=name, unit=unit, **statistics(v))
        if covariances is not None and name in BOUNDED:
            row["within_3sigma"] = float(np.mean(np.abs(poses[name]) <= poses[f"{name}_3sigma"]))
        rows.append(row)
    return Consistency(poses, pd.DataFrame(rows), to_gt, to_est, list(dict.fromkeys(n for n in notes if n)))
