"""Pure geometry on arrays: rigid/similarity alignment, quaternion algebra, and the two
orientation slips of the official OpenLORIS-Scene tool (reproduced only on request).

All functions are vectorized over poses. Positions are metres, angles degrees unless stated.
Orientations are quaternions ``xyzw`` (scipy's order) in plain arrays: the evaluation never builds
a scipy ``Rotation`` (whose import and per-call cost dominated a run over many small files), and
tests check every function here against ``scipy.spatial.transform``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, partial
from typing import TYPE_CHECKING

import numpy as np

from lorisnb.core.trajectory.blocks import each
from lorisnb.core.trajectory.rotations import BarItzhack, markley
from lorisnb.errors import EvaluationError

if TYPE_CHECKING:
    from scipy.spatial.transform import Rotation


@dataclass(frozen=True)
class Sim3:
    """A similarity transform ``x -> scale * rotation @ x + translation``."""

    rotation: np.ndarray  # (3, 3)
    translation: np.ndarray  # (3,)
    scale: float = 1.0

    @classmethod
    def identity(cls) -> "Sim3":
        return cls(np.eye(3), np.zeros(3), 1.0)

    def __repr__(self) -> str:
        angle = float(np.degrees(np.arccos(np.clip((np.trace(self.rotation) - 1) / 2, -1.0, 1.0))))
        t = ", ".join(f"{v:.4g}" for v in np.asarray(self.translation, float))
        return f"<Sim3: rotation {angle:.4g} deg, translation [{t}] m, scale {self.scale:.6g}>"

    def apply(self, points: np.ndarray) -> np.ndarray:
        """Transform (N, 3) points."""
        return self.scale * points @ self.rotation.T + self.translation

    def matrix(self) -> np.ndarray:
        """4x4 homogeneous matrix (scale folded into the rotation block)."""
        m = np.eye(4)
        m[:3, :3] = self.scale * self.rotation
        m[:3, 3] = self.translation
        return m


#: Relative size below which the second singular value of the cross-covariance counts as zero:
#: the positions lie on a line (or a point) and the rotation about it cannot be fitted.
DEGENERATE_RATIO = 1e-12


def degenerate_alignment(source: np.ndarray, target: np.ndarray) -> str | None:
    """Why no rotation can be fitted between matched (N, 3) positions, or None: fewer than 3
    positions, all positions of one side identical (zero spread), or all on one line (the
    rotation about it is undetermined; evo refuses these too: "degenerate covariance rank")."""
    source = np.asarray(source, float)
    target = np.asarray(target, float)
    if len(source) == 0:
        return "no matched position"
    return PositionPairs.of(source, target).degenerate()


@dataclass(frozen=True)
class PositionPairs:
    """Matched (N, 3) positions (N >= 1) with their means, the centred source and the
    cross-covariance ``xt^T xs / N``: what a fit (:meth:`fit`, :func:`umeyama`) and the test of
    whether one can be determined (:meth:`degenerate`) share, computed once for both (the
    pipeline's plausibility checks ask both questions of the same poses)."""

    source: np.ndarray
    target: np.ndarray
    mu_s: np.ndarray
    mu_t: np.ndarray
    xs: np.ndarray
    cov: np.ndarray

    @classmethod
    def of(cls, source: np.ndarray, target: np.ndarray) -> PositionPairs:
        mu_s, mu_t, xs, _, cov = _centered(source, target)
        return cls(source, target, mu_s, mu_t, xs, cov)

    @cached_property
    def svd(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``np.linalg.svd`` of the cross-covariance, once for :meth:`degenerate` and :meth:`fit`."""
        return np.linalg.svd(self.cov)

    def degenerate(self) -> str | None:
        """:func:`degenerate_alignment` of these positions."""
        return _degenerate(self.source, self.target, self.cov, self.svd[1])

    def fit(self, with_scale: bool = False) -> Sim3:
        """:func:`umeyama` of these positions (not strict)."""
        return _solve(self.mu_s, self.mu_t, self.xs, self.cov, with_scale, self.svd)


#: A lever (:func:`rotation_lever`, metres) below this and a sequence's alignment is too unstable to
#: judge: 5 mm of position noise would turn a fit on its matched positions by more than 1 degree
#: (0.005 / 0.29 rad), which moves AOE, ATE and what counts as correct. Most icra20 sequences have
#: levers of metres; 10 of its 182 matched ones, where an algorithm tracked only a short piece, have
#: 0.02-0.23 m (4 of them an AOE of 71-153 deg); a 15-pose, near-straight 30 cm piece has millimetres.
#: The regression gate (:mod:`lorisnb.core.stats.tolerances`) and the pipeline's orientation checks
#: (:func:`lorisnb.core.pipeline.plausibility.rotation_not_held`) use it.
MIN_LEVER = 0.29


def rotation_lever(positions: np.ndarray) -> float:
    """How firmly (N, 3) matched positions hold the rotation of an alignment fitted on them, in
    metres: ``sqrt(N (l2 + l3))`` with ``l1 >= l2 >= l3`` the variances of the centred positions
    along their principal axes. With position noise ``sigma`` (m) on the points, the fitted
    rotation about the least-held axis (the path's main direction) scatters by about
    ``sigma / lever`` radians (the Fisher information of a small rotation of point sets is
    ``N (tr C - C) / sigma^2``). A 1 km drive: hundreds of metres; 15 poses along a
    near-straight centimetre: a few centimetres, where 5 mm of noise turns the fit by degrees.
    0 for fewer than 3 positions or points on a line; NaN for none."""
    p = np.asarray(positions, float).reshape(-1, 3)
    if len(p) == 0:
        return float("nan")
    if len(p) < 3:
        return 0.0
    by_axis = p.T.copy()  # (3, N): np.cov of (N, 3) took 100 us for 3,000 poses (strided sums), this 20 us
    by_axis -= by_axis.mean(axis=1)[:, None]
    var = np.linalg.eigvalsh(by_axis @ by_axis.T / len(p))  # ascending
    return float(np.sqrt(len(p) * max(var[0] + var[1], 0.0)))


def _centered(source: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, ...]:
    """Means, centred positions and the cross-covariance ``xt^T xs / N`` of (N, 3) positions
    (N >= 1): what the fit and the degeneracy test share."""
    (mu_s, xs), (mu_t, xt) = each(partial(_center, source), partial(_center, target), rows=len(source))
    return mu_s, mu_t, xs, xt, xt.T @ xs / len(source)


def _center(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The mean of (N, 3) points and the points less it."""
    mu = points.mean(axis=0)
    return mu, points - mu


def _degenerate(
    source: np.ndarray, target: np.ndarray, cov: np.ndarray, singular: np.ndarray | None = None
) -> str | None:
    """:func:`degenerate_alignment` given the cross-covariance of the positions (and its singular
    values, where a fit computed them): a noun phrase, said as 'the alignment was fitted on {why}'
    and 'no alignment can be determined: {why}'."""
    n = len(source)
    if n == 1:  # (one position is no spread of positions: said as the count it is)
        return "only 1 matched position (fewer than 3)"
    for side, p in (("estimate", source), ("ground-truth", target)):
        hi = np.array([p[:, k].max() for k in range(3)])  # per column: several times as fast as axis=0
        lo = np.array([p[:, k].min() for k in range(3)])
        if (hi - lo).max() <= 1e-12 * max(1.0, float(max(np.abs(hi).max(), np.abs(lo).max()))):
            return f"{n} matched {side} positions, {'both' if n == 2 else 'all'} identical (zero spread)"
    d = np.linalg.svd(cov, compute_uv=False) if singular is None else singular
    if n < 3 or d[1] <= max(DEGENERATE_RATIO * d[0], np.finfo(float).eps):
        return f"{n} matched positions on one line" if n >= 3 else f"only {n} matched positions (fewer than 3)"
    return None


def umeyama(
    source: np.ndarray,
    target: np.ndarray,
    with_scale: bool = False,
    strict: bool = False,
    pairs: PositionPairs | None = None,
) -> Sim3:
    """Least-squares Sim(3)/SE(3) with ``target ~ s R source + t`` (Umeyama 1991; Horn's method
    without scale).

    Args:
        source: (N, 3) points to move (estimated positions), metres.
        target: (N, 3) reference points (ground truth), metres.
        with_scale: estimate the scale s (Sim(3)); otherwise s = 1 (SE(3)).
        strict: raise EvaluationError where no rotation can be determined
            (:func:`degenerate_alignment`); without it such input gets the SVD's arbitrary
            answer, as the official OpenLORIS tool computes it.
        pairs: these same positions' :class:`PositionPairs`, where the caller made them for its
            checks too (the pipeline's): their means, centring and SVD are used, not computed again
            (the same numbers: computed by the same calls).
    """
    source = np.asarray(source, float)
    target = np.asarray(target, float)
    if source.shape != target.shape or source.ndim != 2 or source.shape[1] != 3:
        raise ValueError(f"umeyama needs two (N, 3) arrays, got {source.shape} and {target.shape}")
    n = len(source)
    if n == 0:
        raise ValueError("umeyama needs at least one point pair")
    if pairs is not None and pairs.source.shape != source.shape:
        raise ValueError(f"umeyama: pairs of {pairs.source.shape} positions given for {source.shape}")
    if pairs is None:
        mu_s, mu_t, xs, _, cov = _centered(source, target)
    else:
        mu_s, mu_t, xs, cov = pairs.mu_s, pairs.mu_t, pairs.xs, pairs.cov
    if strict and (why := _degenerate(source, target, cov)) is not None:
        # a Sim(3) fit on one pose is refused (a scale needs 2 poses): its first-pose remedy drops the scale
        first = "without scale (--align se3 --align-frames 1)" if with_scale else "(--align-frames 1)"
        raise EvaluationError(
            f"no {'Sim(3)' if with_scale else 'SE(3)'} alignment can be determined: {why}, so the rotation "
            "about them is arbitrary; align on more poses (--align-frames N with N >= 3 poses not on one line), "
            f"on the first pose's orientation {first}, or not at all (--align none)"
        )
    return _solve(mu_s, mu_t, xs, cov, with_scale, None if pairs is None else pairs.svd)


def _solve(
    mu_s: np.ndarray,
    mu_t: np.ndarray,
    xs: np.ndarray,
    cov: np.ndarray,
    with_scale: bool,
    svd: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
) -> Sim3:
    """Umeyama's solution from the means, the centred source and the cross-covariance (and its
    ``np.linalg.svd``, where it was computed)."""
    u, d, vt = np.linalg.svd(cov) if svd is None else svd
    s_mat = np.eye(3)
    if np.linalg.det(u) * np.linalg.det(vt) < 0.0:
        s_mat[2, 2] = -1.0
    rot = u @ s_mat @ vt
    scale = 1.0
    if with_scale:
        var_s = np.einsum("ij,ij->", xs, xs) / len(xs)
        scale = float(np.trace(np.diag(d) @ s_mat) / var_s) if var_s > 0 else 1.0
    trans = mu_t - scale * rot @ mu_s
    return Sim3(rot, trans, scale)


def quat_from_matrix(matrices: np.ndarray) -> np.ndarray:
    """Unit quaternions ``xyzw`` of rotation matrices (..., 3, 3), as scipy's
    ``Rotation.from_matrix`` computes them (the largest of the trace and the diagonal picks the
    branch; to ~1e-16). The input must be orthonormal (as Umeyama's rotations are): scipy first
    projects other matrices onto rotations (:func:`lorisnb.core.trajectory.rotations.rotation_blocks` does too)."""
    m = np.asarray(matrices, float)
    if m.shape == (3, 3):  # one rotation (an alignment's): the same float operations on Python floats
        # (IEEE doubles, as numpy's elementwise ones), 8 us where the vectorized set-up took 75 us
        return quat_normalize(np.array([_markley_one(m)])).reshape(4)
    return quat_normalize(markley(BarItzhack(m.reshape(-1, 3, 3)))).reshape(*m.shape[:-2], 4)


def _markley_one(m: np.ndarray) -> list[float]:
    """:func:`lorisnb.core.trajectory.rotations.markley`'s quaternion (``xyzw``, not normalized) of
    one (3, 3) block, each entry of ``K + I`` and the branch computed as it computes them."""
    (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = m.tolist()
    tr = (a00 + a11) + a22
    one_minus = 1.0 - tr
    xx, yy, zz, ww = one_minus + a00 * 2.0, one_minus + a11 * 2.0, one_minus + a22 * 2.0, tr + 1.0
    xy, xz, yz = a10 + a01, a20 + a02, a21 + a12
    xw, yw, zw = a21 - a12, a02 - a20, a10 - a01
    if a00 >= a11 and a00 >= a22 and a00 >= tr:  # the first largest of the diagonal and the trace
        return [xx, xy, xz, xw]
    if a11 >= a22 and a11 >= tr:
        return [xy, yy, yz, yw]
    if a22 >= tr:
        return [xz, yz, zz, zw]
    return [xw, yw, zw, ww]


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of quaternions ``xyzw`` (normalized first), as scipy's
    ``Rotation.as_matrix``."""
    q = quat_normalize(q)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    xx, yy, zz, ww = x * x, y * y, z * z, w * w
    xy, zw, xz, yw, yz, xw = x * y, z * w, x * z, y * w, y * z, x * w
    m = np.empty(q.shape[:-1] + (3, 3))
    m[..., 0, 0] = xx - yy - zz + ww
    m[..., 1, 0] = 2 * (xy + zw)
    m[..., 2, 0] = 2 * (xz - yw)
    m[..., 0, 1] = 2 * (xy - zw)
    m[..., 1, 1] = -xx + yy - zz + ww
    m[..., 2, 1] = 2 * (yz + xw)
    m[..., 0, 2] = 2 * (xz + yw)
    m[..., 1, 2] = 2 * (yz - xw)
    m[..., 2, 2] = -xx - yy + zz + ww
    return m


def quat_normalize(q: np.ndarray) -> np.ndarray:
    """Quaternions scaled to unit norm (what scipy's ``Rotation.from_quat`` stores)."""
    q = np.asarray(q, float)
    return q / np.sqrt(np.einsum("...i,...i->...", q, q))[..., None]


def as_quaternions(rotations: object) -> np.ndarray:
    """Unit quaternions ``xyzw`` (N, 4) of a scipy ``Rotation`` or of a quaternion array (normalized),
    so that the metrics take either."""
    as_quat = getattr(rotations, "as_quat", None)
    if callable(as_quat):
        return np.asarray(as_quat(), float).reshape(-1, 4)
    return quat_normalize(np.asarray(rotations, float).reshape(-1, 4))


def rotations_of(quaternions: np.ndarray | None) -> Rotation | None:
    """A scipy ``Rotation`` of quaternions ``xyzw`` (None stays None): for users' code and for
    evo; scipy is imported here, not on the evaluation's path."""
    if quaternions is None:
        return None
    from scipy.spatial.transform import Rotation

    return Rotation.from_quat(quaternions)


def ros_quaternion_from_matrix(blocks: np.ndarray) -> np.ndarray:
    """Quaternions ``xyzw`` from (N, 3, 3) rotation blocks, exactly as ROS tf's
    ``transformations.quaternion_from_matrix`` computes them on a 4x4 matrix with ``M[3, 3] = 1``
    (trace branch when the trace of the block is positive, else Shepperd's largest-diagonal
    branch). The block may carry a scale, as in the official tool with Sim(3): then the result is
    neither unit nor the rotation's quaternion, which is slip (b) of the official tool.

    Only used to reproduce the official tool; lorisnb's own results never depend on the sign or
    scale this returns.
    """
    m = np.asarray(blocks, float).reshape(-1, 3, 3)
    n = len(m)
    q = np.empty((n, 4))
    tr = m[:, 0, 0] + m[:, 1, 1] + m[:, 2, 2] + 1.0  # trace of the 4x4 matrix
    t_pos = tr > 1.0
    t = np.empty(n)
    a = t_pos
    q[a, 3] = tr[a]
    q[a, 2] = m[a, 1, 0] - m[a, 0, 1]
    q[a, 1] = m[a, 0, 2] - m[a, 2, 0]
    q[a, 0] = m[a, 2, 1] - m[a, 1, 2]
    t[a] = tr[a]
    b = ~t_pos
    if b.any():
        mb = m[b]
        d = np.stack([mb[:, 0, 0], mb[:, 1, 1], mb[:, 2, 2]], axis=1)
        i = np.zeros(len(mb), dtype=int)
        i[d[:, 1] > d[:, 0]] = 1
        i = np.where(d[:, 2] > d[np.arange(len(mb)), i], 2, i)
        j = (i + 1) % 3
        k = (i + 2) % 3
        r = np.arange(len(mb))
        tb = mb[r, i, i] - (mb[r, j, j] + mb[r, k, k]) + 1.0
        qb = np.empty((len(mb), 4))
        qb[r, i] = tb
        qb[r, j] = mb[r, i, j] + mb[r, j, i]
        qb[r, k] = mb[r, k, i] + mb[r, i, k]
        qb[:, 3] = mb[r, k, j] - mb[r, j, k]
        q[b] = qb
        t[b] = tb
    q *= (0.5 / np.sqrt(t))[:, None]
    return q


def official_slerp(q1: np.ndarray, q2: np.ndarray, w1: np.ndarray, w2: np.ndarray) -> np.ndarray:
    """The OpenLORIS tool's quaternion interpolation, slip (a), vectorized.

    Its dot product uses ``q2.w * q2.w`` instead of ``q1.w * q2.w``, and its spherical weights are
    swapped (``sin(w2 theta)`` multiplies q1). The result is not normalized. Quaternions ``xyzw``;
    ``w1 = 1 - w2`` is the weight of q1.
    """
    q1 = np.asarray(q1, float)
    q2 = np.asarray(q2, float).copy()
    w1 = np.asarray(w1, float)
    w2 = np.asarray(w2, float)
    dot = q1[:, 0] * q2[:, 0] + q1[:, 1] * q2[:, 1] + q1[:, 2] * q2[:, 2] + q2[:, 3] * q2[:, 3]
    neg = dot < 0.0
    q2[neg] *= -1.0
    dot = np.where(neg, -dot, dot)
    near = dot > 0.99999
    with np.errstate(invalid="ignore", divide="ignore"):
        sin_theta = np.sqrt(1.0 - dot * dot)
        theta = np.arctan2(sin_theta, dot)
        k1 = np.where(near, w1, np.sin(w2 * theta) / sin_theta)
        k2 = np.where(near, w2, np.sin(w1 * theta) / sin_theta)
    return k1[:, None] * q1 + k2[:, None] * q2


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product of 3-vectors on the last axis (``np.cross`` without its per-call overhead)."""
    a1, a2, a3 = a[..., 0], a[..., 1], a[..., 2]
    b1, b2, b3 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a2 * b3 - a3 * b2, a3 * b1 - a1 * b3, a1 * b2 - a2 * b1], axis=-1)


def quat_multiply(q1: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """Hamilton product ``q1 (x) q2`` of quaternions ``xyzw``, broadcast over leading axes: the
    rotation that applies ``q2`` first, then ``q1`` (scipy's ``Rotation.__mul__``)."""
    q1, q2 = np.asarray(q1, float), np.asarray(q2, float)
    x1, y1, z1, w1 = q1[..., 0], q1[..., 1], q1[..., 2], q1[..., 3]
    x2, y2, z2, w2 = q2[..., 0], q2[..., 1], q2[..., 2], q2[..., 3]
    return np.stack(
        [
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
        ],
        axis=-1,
    )


def quat_conj_multiply(q1: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """``conj(q1) (x) q2`` of quaternions ``xyzw`` (for unit q1: ``q1^-1 q2``, the rotation from q1 to
    q2): the same numbers as ``quat_multiply(quat_conjugate(q1), q2)`` (the signs folded in, which
    is exact), without the conjugate's copy."""
    q1, q2 = np.asarray(q1, float), np.asarray(q2, float)
    x1, y1, z1, w1 = q1[..., 0], q1[..., 1], q1[..., 2], q1[..., 3]
    x2, y2, z2, w2 = q2[..., 0], q2[..., 1], q2[..., 2], q2[..., 3]
    return np.stack(
        [
            w1 * x2 - x1 * w2 - y1 * z2 + z1 * y2,
            w1 * y2 + x1 * z2 - y1 * w2 - z1 * x2,
            w1 * z2 - x1 * y2 + y1 * x2 - z1 * w2,
            w1 * w2 + x1 * x2 + y1 * y2 + z1 * z2,
        ],
        axis=-1,
    )


def quat_conjugate(q: np.ndarray) -> np.ndarray:
    """Conjugate of quaternions ``xyzw`` (the inverse rotation of unit quaternions)."""
    q = np.asarray(q, float)
    return q * np.array([-1.0, -1.0, -1.0, 1.0])


def quat_rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Vectors ``v`` (..., 3) rotated by unit quaternions ``q`` (..., 4) ``xyzw``."""
    q, v = np.asarray(q, float), np.asarray(v, float)
    u, w = q[..., :3], q[..., 3:]
    t = 2.0 * cross3(u, v)
    return v + w * t + cross3(u, t)


def quat_angle_deg(q: np.ndarray) -> np.ndarray:
    """Rotation angle of unit quaternions ``xyzw``, degrees in [0, 180] (as scipy's ``magnitude``)."""
    q = np.asarray(q, float)
    xyz = q[..., :3]
    return np.degrees(2.0 * np.arctan2(np.sqrt(np.einsum("...i,...i->...", xyz, xyz)), np.abs(q[..., 3])))


def slerp(q1: np.ndarray, q2: np.ndarray, w2: np.ndarray) -> np.ndarray:
    """Spherical linear interpolation between quaternions ``xyzw`` (N, 4) (normalized first), with
    weight ``w2`` (N,) of ``q2`` (0 gives q1, 1 gives q2), along the shorter arc; unit quaternions out.

    The same rotations as ``scipy.spatial.transform.Slerp`` over each pair (to ~1e-15), without
    its per-call cost."""
    q1 = quat_normalize(q1)
    q2 = quat_normalize(q2)
    w2 = np.asarray(w2, float)
    dot = np.einsum("...i,...i->...", q1, q2)
    sign = np.where(dot < 0, -1.0, 1.0)  # the shorter arc
    theta = np.arccos(np.clip(np.abs(dot), -1.0, 1.0))
    sin_theta = np.sin(theta)
    small = sin_theta < 1e-9
    with np.errstate(invalid="ignore", divide="ignore"):
        k1 = np.where(small, 1.0 - w2, np.sin((1.0 - w2) * theta) / sin_theta)
        k2 = np.where(small, w2, np.sin(w2 * theta) / sin_theta) * sign
    return quat_normalize(k1[..., None] * q1 + k2[..., None] * q2)
