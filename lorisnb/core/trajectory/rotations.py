"""Quaternions of rotation matrices: Markley's method (as scipy's ``Rotation.from_matrix``) and,
for blocks that are not quite rotations (a KITTI file's printed digits), the quaternion of the
nearest rotation by power steps on Bar-Itzhack's 4x4 matrix (compiled in ``_rotations.c`` where the
install built it; the numpy code here is its reference and fallback). Arrays in, arrays out;
quaternions ``xyzw``."""

from __future__ import annotations

import importlib
import threading
from collections.abc import Callable, Sequence

import numpy as np

from lorisnb.core.trajectory.blocks import blockwise

_kernel: Callable[[Sequence[np.ndarray], np.ndarray, np.ndarray, np.ndarray], None] | None
try:  # the compiled form of _rotation_run (_rotations.c), where the install built it (an optional extension)
    _kernel = importlib.import_module("._rotations", __package__).nearest
except ImportError:  # pragma: no cover - a machine without a C compiler
    _kernel = None

__all__ = ["BarItzhack", "markley", "rotation_blocks", "rotation_entries", "times"]

#: Blocks given entry by entry: ``a[i][j]`` the (n,) entries ``B_ij`` of n 3x3 blocks.
Entries = Sequence[Sequence[np.ndarray]] | np.ndarray


class BarItzhack:
    """The ten entries of Bar-Itzhack's symmetric 4x4 matrix ``K + I`` of (n, 3, 3) blocks ``B``
    (J. Guid. Control Dyn. 23(6), 2000; ``q^T K q = tr(B^T R(q))`` for unit ``q``, ``xyzw``), each
    an (n,) array, and the trace; for a rotation ``B = R(q)``, ``K + I = 4 q q^T``. The diagonal is
    written as scipy writes Markley's quaternions (``1 - tr + 2 B_ii`` and ``1 + tr``), so that its
    columns are those quaternions to the last bit. ``rows``: a (20, n) array to compute in (the
    entries and trace in its first 11 rows; the blocks, entry by entry, in the others when they
    are not so laid out already), else new arrays."""

    trace: np.ndarray
    xx: np.ndarray
    yy: np.ndarray
    zz: np.ndarray
    ww: np.ndarray
    xy: np.ndarray
    xz: np.ndarray
    yz: np.ndarray
    xw: np.ndarray
    yw: np.ndarray
    zw: np.ndarray

    def __init__(self, m: np.ndarray, rows: np.ndarray | None = None) -> None:
        self._build(np.moveaxis(m, 0, -1), rows)  # (3, 3, n): each entry a row

    @classmethod
    def of_entries(cls, a: Entries, rows: np.ndarray | None = None) -> BarItzhack:
        """Of blocks given entry by entry: ``a[i][j]`` the (n,) entries ``B_ij`` (a (3, 3, n)
        array, or nested sequences of (n,) arrays such as a file's columns)."""
        k = cls.__new__(cls)
        k._build(a, rows)
        return k

    def _build(self, a: Entries, rows: np.ndarray | None) -> None:
        n = len(a[0][0])
        # each entry one contiguous float row, as a file's columns are; else (a row-major array) copied
        if any(e.dtype != np.float64 or e.strides[-1] != e.itemsize for row in a for e in row):
            copy = np.empty((3, 3, n)) if rows is None else rows[11:20].reshape(3, 3, n)
            for i in range(3):
                for j in range(3):
                    np.copyto(copy[i, j], a[i][j])
            a = copy
        self.a = a
        e = np.empty((11, n)) if rows is None else rows[:11]
        self.trace, self.xx, self.yy, self.zz, self.ww, self.xy, self.xz, self.yz, self.xw, self.yw, self.zw = e
        np.add(np.add(a[0][0], a[1][1], out=self.trace), a[2][2], out=self.trace)
        one_minus = np.subtract(1.0, self.trace, out=self.ww)  # 1 - tr, until ww is written
        for d, i in ((self.xx, 0), (self.yy, 1), (self.zz, 2)):
            np.add(one_minus, np.multiply(a[i][i], 2.0, out=d), out=d)
        np.add(self.trace, 1.0, out=self.ww)
        for out, (i, j), sign in zip(
            (self.xy, self.xz, self.yz, self.xw, self.yw, self.zw),
            ((1, 0), (2, 0), (2, 1), (2, 1), (0, 2), (1, 0)),
            (1, 1, 1, -1, -1, -1),
            strict=True,
        ):
            (np.add if sign > 0 else np.subtract)(a[i][j], a[j][i], out=out)

    @property
    def entries(self) -> tuple[np.ndarray, ...]:
        """``xx, yy, zz, ww, xy, xz, yz, xw, yw, zw``: what :func:`times` takes."""
        return self.xx, self.yy, self.zz, self.ww, self.xy, self.xz, self.yz, self.xw, self.yw, self.zw

    @property
    def columns(self) -> tuple[tuple[np.ndarray, ...], ...]:
        """The four columns of ``K + I`` (x, y, z, w), each as its four entries."""
        return (
            (self.xx, self.xy, self.xz, self.xw),
            (self.xy, self.yy, self.yz, self.yw),
            (self.xz, self.yz, self.zz, self.zw),
            (self.xw, self.yw, self.zw, self.ww),
        )


def times(
    k: tuple[np.ndarray, ...],
    x: np.ndarray,
    y: np.ndarray,
    z: np.ndarray,
    w: np.ndarray,
    out: np.ndarray | None = None,
    tmp: np.ndarray | None = None,
) -> tuple[np.ndarray, ...]:
    """``(K + I) q`` for quaternions given as four (n,) arrays, ``K + I`` as its ten
    :attr:`BarItzhack.entries` (of n blocks); computed into ``out`` (4, n) with ``tmp`` (n,) if
    given (each sum in order, ``((a x + b y) + c z) + d w``)."""
    xx, yy, zz, ww, xy, xz, yz, xw, yw, zw = k
    out = np.empty((4, len(x))) if out is None else out
    tmp = np.empty(len(x)) if tmp is None else tmp
    for o, row in zip(out, ((xx, xy, xz, xw), (xy, yy, yz, yw), (xz, yz, zz, zw), (xw, yw, zw, ww)), strict=True):
        np.multiply(row[0], x, out=o)
        for e, c in zip(row[1:], (y, z, w), strict=True):
            np.add(o, np.multiply(e, c, out=tmp), out=o)
    return tuple(out)


def markley(k: BarItzhack) -> np.ndarray:
    """(n, 4) quaternions ``xyzw``, before normalization, of rotation blocks by Markley's method
    (2008, as scipy): the largest of the trace and the diagonal picks the branch, whose quaternion
    is that column of ``K + I``."""
    n = len(k.trace)
    q = np.empty((4, n))
    _markley_into(k, q, np.empty((3, n), bool))
    return q.T.copy()


def _markley_into(k: BarItzhack, q: np.ndarray, masks: np.ndarray) -> None:
    """:func:`markley`'s quaternions into the rows ``x, y, z, w`` of ``q`` (4, n), with ``masks``
    (3, n) booleans to compute in: the branch is the first of ``B_00, B_11, B_22, tr`` that is
    largest (``np.argmax``'s choice; a block with NaN on its diagonal gets NaN in every branch)."""
    a = k.a
    d0, d1, d2, tr = a[0][0], a[1][1], a[2][2], k.trace
    c0, c1, c2 = masks
    _first_largest(d0, d1, d2, tr, masks)
    columns = k.columns
    for i, o in enumerate(q):
        np.copyto(o, columns[3][i])
        for c, col in ((c2, columns[2]), (c1, columns[1]), (c0, columns[0])):
            if c.any():
                np.copyto(o, col[i], where=c)


def _first_largest(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray, masks: np.ndarray) -> None:
    """Into ``masks`` (3, n): where ``a``, ``b``, ``c`` is the first largest of ``a, b, c, d``
    (``np.argmax``'s choice; where none is, ``d`` is, NaN included)."""
    c0, c1, c2 = masks
    np.greater_equal(a, b, out=c0)
    np.logical_and(c0, np.greater_equal(a, c, out=c1), out=c0)
    np.logical_and(c0, np.greater_equal(a, d, out=c1), out=c0)
    np.greater_equal(b, c, out=c1)
    np.logical_and(c1, np.greater_equal(b, d, out=c2), out=c1)
    np.logical_and(c1, ~c0, out=c1)
    np.greater_equal(c, d, out=c2)
    np.logical_and(c2, ~c0, out=c2)
    np.logical_and(c2, ~c1, out=c2)


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
    against an extended-precision polar decomposition in ``tests/io/test_whole.py``), with scipy's
    sign (the largest component positive), in about a twentieth of scipy's time on a million blocks.

    Where the install compiled ``_rotations.c`` (setuptools builds it where a C compiler is), each
    block is computed by it, with the same operations in the same order (the same bits; no fused
    multiply-add) and no GIL held, so that a file's pieces convert side by side on every core: a
    million 6-digit blocks in ~0.045 s on one core (-O3) against ~0.14 s for the numpy runs, which hold
    the GIL between their ~230 operations. Elsewhere the numpy runs compute them."""
    m = np.asarray(blocks, float).reshape(-1, 3, 3)
    return rotation_entries(np.moveaxis(m, 0, -1))


def rotation_entries(a: Entries) -> tuple[np.ndarray, np.ndarray]:
    """:func:`rotation_blocks` of blocks given entry by entry (``a[i][j]`` the (N,) entries
    ``B_ij``: a (3, 3, N) array, or a file's columns as they were read, with no copy)."""
    n = len(a[0][0])
    q, off = np.empty((n, 4)), np.empty(n)
    kernel = _kernel

    def run(lo: int, hi: int) -> None:
        if kernel is not None:  # the same bits, a block at a time, without the GIL
            entries = [np.ascontiguousarray(a[i][j][lo:hi], dtype=np.float64) for i in range(3) for j in range(3)]
            kernel(entries, _STEP_THRESHOLDS, q[lo:hi], off[lo:hi])
            return
        _rotation_run([[a[i][j][lo:hi] for j in range(3)] for i in range(3)], q[lo:hi], off[lo:hi])

    blockwise(run, n)  # in cache-sized runs of blocks: no page faults, no long temporaries
    return q, off


#: Scratch memory of each thread's runs, kept for its next run: freed and requested again, the
#: temporaries of a run cost the kernel's fresh pages every time (glibc gives the top of its heap
#: back at once), about as much as the arithmetic on them.
_scratch = threading.local()


def _scratch_rows(count: int, n: int, dtype: type = np.float64) -> np.ndarray:
    """A (count, n) C-contiguous array of this thread's scratch memory (its contents undefined),
    for a run of at most :data:`~lorisnb.core.trajectory.blocks.BLOCK_ROWS` blocks."""
    name = np.dtype(dtype).name
    pool = getattr(_scratch, name, None)
    if pool is None or len(pool) < count * n:
        pool = np.empty(count * n, dtype)
        setattr(_scratch, name, pool)
    return pool[: count * n].reshape(count, n)


#: A run's float scratch rows: 20 for Bar-Itzhack's entries (and a copy of row-major blocks),
#: 3 for sums, 12 for the quaternions (Markley's and two for the power steps).
_FLOAT_ROWS = 35

#: Power steps take a block within ``off`` of a rotation this many steps or more: the ``k``-th
#: threshold is the least ``off`` for which ``(off / 2) ** k`` is not below 2**-56.
_STEP_THRESHOLDS = np.array([2.0 ** (1 - 56 / k) for k in range(1, 13)])


def power_steps(off: np.ndarray) -> np.ndarray:
    """Power steps for blocks ``off`` from a rotation (see :func:`_nearest_rotation`): as many as
    bring ``(off / 2) ** (steps + 1)`` below 2**-56, from 1 to 12 (12 for blocks 0.25 or more
    away, or NaN)."""
    off = np.asarray(off, float)
    steps = np.searchsorted(_STEP_THRESHOLDS, off, side="right").clip(1, 12)
    return np.where((off > 0) & (off < 0.25), steps, 12).astype(np.int8)


def _rotation_run(entries: Entries, q: np.ndarray, off: np.ndarray) -> None:
    """:func:`rotation_entries` of a run of n blocks into ``q`` (n, 4) and ``off`` (n,), computed
    on one (n,) row per component in the thread's scratch memory (nothing allocated)."""
    n = len(q)
    rows = _scratch_rows(_FLOAT_ROWS, n)
    masks = _scratch_rows(6, n, np.bool_)  # branches (3), orthogonal, sign, a comparison
    k = BarItzhack.of_entries(entries, rows[:20])
    a = k.a
    t, u, det = rows[20:23]
    with np.errstate(over="ignore", invalid="ignore"):  # huge blocks: inf here, refused by the reader
        gram = off  # the largest entry of |R R^T - I|, then the distance
        for i, j in ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)):
            d = gram if (i, j) == (0, 0) else t
            np.multiply(a[i][0], a[j][0], out=d)
            np.add(d, np.multiply(a[i][1], a[j][1], out=u), out=d)
            np.add(d, np.multiply(a[i][2], a[j][2], out=u), out=d)
            if i == j:
                np.subtract(d, 1.0, out=d)
            np.abs(d, out=d)
            if d is not gram:
                np.maximum(gram, d, out=gram)
        # a rotation within 1e-12 in every entry of R R^T (scipy's np.isclose also lets a row norm
        # be 1e-5 off: a planar 6-digit block would keep Markley's 1e-8 error); NaN is none
        orthogonal = np.less_equal(gram, 1e-12, out=masks[3])
        np.multiply(a[0][0], _minor(a, 1, 1, 2, 2, t, u), out=det)
        np.subtract(det, np.multiply(a[0][1], _minor(a, 1, 0, 2, 2, t, u), out=t), out=det)
        np.add(det, np.multiply(a[0][2], _minor(a, 1, 0, 2, 1, t, u), out=t), out=det)
        np.maximum(gram, np.abs(np.subtract(det, 1.0, out=det), out=det), out=off)
    quat = rows[23:27]
    _markley_into(k, quat, masks[:3])
    if not orthogonal.all():
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            near = _nearest_rotation(k, quat, off, orthogonal, rows[27:35], masks, t)
        if orthogonal.any():
            for c, v in zip(near, quat, strict=True):
                np.copyto(c, v, where=orthogonal)
        quat = near
    x, y, z, w = quat
    norm = np.multiply(x, x, out=t)  # as np.linalg.norm(q, axis=1) sums: in order, to the last bit
    for c in (y, z, w):
        np.add(norm, np.multiply(c, c, out=u), out=norm)
    np.sqrt(norm, out=norm)
    for i, c in enumerate(quat):
        np.divide(c, norm, out=q[:, i])


def _minor(a: Entries, i: int, j: int, k: int, m: int, out: np.ndarray, tmp: np.ndarray) -> np.ndarray:
    """``a[i][j] * a[k][m] - a[i][m] * a[k][j]`` of the (3, 3, n) entries, into ``out``."""
    np.multiply(a[i][j], a[k][m], out=out)
    return np.subtract(out, np.multiply(a[i][m], a[k][j], out=tmp), out=out)


def _nearest_rotation(
    k: BarItzhack, q: np.ndarray, off: np.ndarray, orthogonal: np.ndarray, rows: np.ndarray, masks: np.ndarray,
    tmp: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """Quaternions ``x, y, z, w`` (rows of a (4, n) array, not normalized) of the rotations
    nearest to the blocks of ``k`` that are not ``orthogonal`` (the others' rows are left to the
    caller), which are ``off`` from a rotation: power steps on ``K + I`` from Markley's ``q``
    (4, n), whose error is about ``off / 4`` and shrinks by about ``off / 4`` a step (measured);
    each block takes :func:`power_steps` (two for 6-digit blocks, five at the readers' tolerance;
    at most 12, for blocks too far to be accepted; the vector grows by at most 4 a step), whatever
    the other blocks of its run need; then its largest component (the first of equal ones) is
    made positive, as scipy's Markley step on the projected block leaves it. ``rows``: (8, n)
    scratch, ``masks`` the run's (6, n) (its fourth row, ``orthogonal``, is left), ``tmp`` (n,)."""
    others = None if not orthogonal.any() else ~orthogonal
    lo = float(off.min(where=others, initial=np.inf) if others is not None else off.min())
    hi = float(off.max(where=others, initial=-np.inf) if others is not None else off.max())
    first, last = (int(s) for s in power_steps(np.array([lo, hi])))
    steps = None if first == last and not np.isnan([lo, hi]).any() else power_steps(off)
    if steps is not None:
        mine = steps if others is None else steps[others]
        first, last = int(mine.min()), int(mine.max())
    entries, out, x = k.entries, None, q
    sets = rows[:4], rows[4:]
    for step in range(1, last + 1):
        cur = sets[step % 2]
        times(entries, x[0], x[1], x[2], x[3], out=cur, tmp=tmp)
        x = cur
        if step < first:
            continue
        if steps is None:  # every block needs as many steps (as in a file of one precision)
            out = cur
            break
        if out is None:
            out = np.empty((4, len(tmp)))
        done = steps == step
        for o, c in zip(out, x, strict=True):
            np.copyto(o, c, where=done)
    assert out is not None
    free = sets[0] if out is sets[1] else sets[1]
    for c, a in zip(out, free, strict=True):
        np.abs(c, out=a)
    _first_largest(free[0], free[1], free[2], free[3], masks[:3])
    negative, below = masks[4], masks[5]  # the largest component's sign
    np.less(out[3], 0.0, out=negative)
    for c, mask in zip(out[:3], masks[:3], strict=True):
        np.copyto(negative, np.less(c, 0.0, out=below), where=mask)
    for c in out:
        np.negative(c, out=c, where=negative)
    return out
