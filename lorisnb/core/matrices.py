"""Quaternions of rotation matrices: Markley's method (as scipy's ``Rotation.from_matrix``) and,
for blocks that are not quite rotations (a KITTI file's printed digits), the quaternion of the
nearest rotation by power steps on Bar-Itzhack's 4x4 matrix. Arrays in, arrays out; quaternions
``xyzw``."""

from __future__ import annotations

import numpy as np

from .blocks import blockwise

__all__ = ["BarItzhack", "markley", "rotation_blocks", "times"]


class BarItzhack:
    """The ten entries of Bar-Itzhack's symmetric 4x4 matrix ``K + I`` of (n, 3, 3) blocks ``B``
    (J. Guid. Control Dyn. 23(6), 2000; ``q^T K q = tr(B^T R(q))`` for unit ``q``, ``xyzw``), each
    an (n,) array, and the trace; for a rotation ``B = R(q)``, ``K + I = 4 q q^T``. The diagonal is
    written as scipy writes Markley's quaternions (``1 - tr + 2 B_ii`` and ``1 + tr``), so that its
    columns are those quaternions to the last bit."""

    def __init__(self, m: np.ndarray) -> None:
        a = np.moveaxis(m, 0, -1)  # (3, 3, n): each entry one contiguous row (a column-major
        if a.strides[-1] != a.itemsize:  # file's numbers are already; a row-major array is copied)
            a = np.ascontiguousarray(a)
        self.a = a
        self.trace = a[0, 0] + a[1, 1] + a[2, 2]
        one_minus = 1.0 - self.trace
        self.xx, self.yy, self.zz = one_minus + 2.0 * a[0, 0], one_minus + 2.0 * a[1, 1], one_minus + 2.0 * a[2, 2]
        self.ww = 1.0 + self.trace
        self.xy, self.xz, self.yz = a[1, 0] + a[0, 1], a[2, 0] + a[0, 2], a[2, 1] + a[1, 2]
        self.xw, self.yw, self.zw = a[2, 1] - a[1, 2], a[0, 2] - a[2, 0], a[1, 0] - a[0, 1]

    @property
    def entries(self) -> tuple[np.ndarray, ...]:
        """``xx, yy, zz, ww, xy, xz, yz, xw, yw, zw``: what :func:`times` takes."""
        return self.xx, self.yy, self.zz, self.ww, self.xy, self.xz, self.yz, self.xw, self.yw, self.zw


def times(
    k: tuple[np.ndarray, ...], x: np.ndarray, y: np.ndarray, z: np.ndarray, w: np.ndarray
) -> tuple[np.ndarray, ...]:
    """``(K + I) q`` for quaternions given as four (n,) arrays, ``K + I`` as its ten
    :attr:`BarItzhack.entries` (of n blocks)."""
    xx, yy, zz, ww, xy, xz, yz, xw, yw, zw = k
    return (
        xx * x + xy * y + xz * z + xw * w,
        xy * x + yy * y + yz * z + yw * w,
        xz * x + yz * y + zz * z + zw * w,
        xw * x + yw * y + zw * z + ww * w,
    )


def markley(k: BarItzhack) -> np.ndarray:
    """(n, 4) quaternions ``xyzw``, before normalization, of rotation blocks by Markley's method
    (2008, as scipy): the largest of the trace and the diagonal picks the branch, whose quaternion
    is that column of ``K + I``."""
    return np.stack(_markley_parts(k), axis=1)


def _markley_parts(k: BarItzhack) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`markley`'s quaternions as four (n,) arrays ``x, y, z, w``: the branch is the first
    of ``B_00, B_11, B_22, tr`` that is largest (``np.argmax``'s choice; a block with NaN on its
    diagonal gets NaN in every branch)."""
    a = k.a
    d0, d1, d2, tr = a[0, 0], a[1, 1], a[2, 2], k.trace
    c0 = (d0 >= d1) & (d0 >= d2) & (d0 >= tr)  # np.argmax's first largest, without stacking
    c1 = ~c0 & (d1 >= d2) & (d1 >= tr)
    c2 = ~c0 & ~c1 & (d2 >= tr)
    return (
        np.where(c0, k.xx, np.where(c1, k.xy, np.where(c2, k.xz, k.xw))),
        np.where(c0, k.xy, np.where(c1, k.yy, np.where(c2, k.yz, k.yw))),
        np.where(c0, k.xz, np.where(c1, k.yz, np.where(c2, k.zz, k.zw))),
        np.where(c0, k.xw, np.where(c1, k.yw, np.where(c2, k.zw, k.ww))),
    )


def rotation_blocks(blocks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit quaternions ``xyzw`` of finite (N, 3, 3) rotation blocks, and how far each block is
    from a rotation: the larger of ``max |R R^T - I|`` and ``|det R - 1|``, so that a reader can
    refuse what is none.

    A block that is a rotation within 1e-12 (every entry of ``R R^T`` against ``I``) gets
    Markley's quaternion (:func:`markley`), as scipy's ``Rotation.from_matrix`` computes it to the
    last bit. Any other block (a KITTI file's 6-7 printed digits) stands for the rotation nearest
    to it in the Frobenius norm, ``U V^T`` of its SVD, which scipy computes with an SVD per block
    (but not for a block whose rows are orthogonal and only their norms up to 1e-5 off, such as a
    planar 6-digit one: scipy's ``np.isclose`` test passes it, and Markley's method on it is ~1e-8
    off); here its quaternion is the top eigenvector of Bar-Itzhack's ``K + I``
    (:class:`BarItzhack`), reached by power steps from Markley's quaternion, which is a column of
    ``K + I``. The other eigenvalues of ``K + I`` are of the order of the block's distance from a
    rotation while the top one is about 4, so each step shrinks the error by about that distance:
    two to five steps give the nearest rotation to ~3e-16 (scipy's SVD: ~3e-15; both measured
    against an extended-precision polar decomposition in ``tests/test_whole.py``), with scipy's
    sign (the largest component positive), in a thirteenth of scipy's time on a million blocks."""
    m = np.asarray(blocks, float).reshape(-1, 3, 3)
    q, off = np.empty((len(m), 4)), np.empty(len(m))

    def run(lo: int, hi: int) -> None:
        q[lo:hi], off[lo:hi] = _rotation_run(m[lo:hi])

    blockwise(run, len(m))  # in cache-sized runs of blocks: no page faults, no long temporaries
    return q, off


def _rotation_run(m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`rotation_blocks` of a run of (n, 3, 3) blocks, computed on one (n,) array per
    component (no (n, 4) temporaries until the result)."""
    k = BarItzhack(m)
    a = k.a
    with np.errstate(over="ignore", invalid="ignore"):  # huge blocks: inf here, refused by the reader
        diag = [np.abs(a[i, 0] * a[i, 0] + a[i, 1] * a[i, 1] + a[i, 2] * a[i, 2] - 1.0) for i in range(3)]
        cross = [np.abs(a[i, 0] * a[j, 0] + a[i, 1] * a[j, 1] + a[i, 2] * a[j, 2]) for i, j in ((0, 1), (0, 2), (1, 2))]
        det = (
            a[0, 0] * (a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1])
            - a[0, 1] * (a[1, 0] * a[2, 2] - a[1, 2] * a[2, 0])
            + a[0, 2] * (a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0])
        )
        gram = diag[0]  # the largest entry of |R R^T - I|, in place over the new arrays
        for d in (*diag[1:], *cross):
            np.maximum(gram, d, out=gram)
        # a rotation within 1e-12 in every entry of R R^T (scipy's np.isclose also lets a row norm
        # be 1e-5 off: a planar 6-digit block would keep Markley's 1e-8 error); NaN is none
        orthogonal = gram <= 1e-12
        off = np.maximum(gram, np.abs(det - 1.0, out=det), out=gram)
    q = list(_markley_parts(k))
    if not orthogonal.all():
        rest = None if not orthogonal.any() else np.flatnonzero(~orthogonal)
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            near = _nearest_rotation(k, q, rest, off if rest is None else off[rest])
        if rest is None:
            q = list(near)
        else:
            for c, v in zip(q, near, strict=True):
                c[rest] = v
    x, y, z, w = q
    norm = np.sqrt(x * x + y * y + z * z + w * w)  # as np.linalg.norm(q, axis=1) sums: in order, to the last bit
    out = np.empty((len(x), 4))
    for i, c in enumerate(q):
        np.divide(c, norm, out=out[:, i])
    return out, off


def _nearest_rotation(
    k: BarItzhack, q: list[np.ndarray], rest: np.ndarray | None, off: np.ndarray
) -> tuple[np.ndarray, ...]:
    """Quaternions ``x, y, z, w`` (four arrays), not normalized, of the rotations nearest to the
    blocks ``rest`` of ``k`` (None: all), which are ``off`` from a rotation: power steps on ``K + I``
    from Markley's ``q`` (four arrays, see :func:`rotation_blocks`), whose error is about
    ``off / 4`` and shrinks by about ``off / 4`` a step (measured); each block takes as many steps
    as bring ``(off / 2) ** (steps + 1)`` below 2**-56 (two for 6-digit blocks, five at the
    readers' tolerance; at most 12, for blocks too far to be accepted; the vector grows by at most
    4 a step), whatever the other blocks of its run need; then its largest component (the first
    of equal ones) is made positive, as scipy's Markley step on the projected block leaves it."""
    with np.errstate(divide="ignore", invalid="ignore"):
        need = np.ceil(56 * np.log(2) / -np.log(off / 2)) - 1
    steps = np.where((off > 0) & (off < 0.25), need, 12).clip(1, 12).astype(np.int8)
    entries = k.entries if rest is None else tuple(e[rest] for e in k.entries)
    x, y, z, w = q if rest is None else (c[rest] for c in q)
    first, last = int(steps.min()), int(steps.max())
    out = None
    for step in range(1, last + 1):
        x, y, z, w = times(entries, x, y, z, w)
        if step < first:
            continue
        if first == last:  # every block needs as many steps (as in a file of one precision)
            out = [x, y, z, w]
            break
        if out is None:
            out = [np.empty_like(x) for _ in range(4)]
        done = steps == step
        for o, c in zip(out, (x, y, z, w), strict=True):
            np.copyto(o, c, where=done)
    assert out is not None
    ax, ay, az, aw = (np.abs(c) for c in out)
    big = np.where(
        (ax >= ay) & (ax >= az) & (ax >= aw), out[0], np.where((ay >= az) & (ay >= aw), out[1], np.where(az >= aw, out[2], out[3]))
    )  # fmt: skip
    sign = np.where(big < 0, -1.0, 1.0)
    return tuple(c * sign for c in out)
