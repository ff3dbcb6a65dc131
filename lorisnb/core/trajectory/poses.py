"""The trajectory type: stamped poses as plain arrays, and the sizes of a path (length, extent)."""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

from lorisnb.core.alignment.geometry import quat_to_matrix, rotations_of
from lorisnb.core.trajectory.blocks import blockwise
from lorisnb.errors import LorisWarning, ValidationError

if TYPE_CHECKING:
    from scipy.spatial.transform import Rotation

K = TypeVar("K")

#: Below this squared norm a quaternion has no direction (the readers refuse it too).
QUAT_EPS = np.finfo(float).eps * 4.0


def path_length(positions: np.ndarray) -> float:
    """Distance travelled along (N, 3) positions: the sum of consecutive distances, metres
    (0 for fewer than two positions)."""
    p = np.asarray(positions, float)
    if len(p) < 2:
        return 0.0
    return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())


def extent(positions: np.ndarray) -> float:
    """Size of (N, 3) positions: the diagonal of their axis-aligned bounding box, metres (0 for
    fewer than two positions)."""
    p = np.asarray(positions, float)
    if len(p) < 2:
        return 0.0
    by_axis = p.T.copy()  # (3, N): numpy's max over axis 0 of (N, 3) took 80 us for 3,000 poses, this 5 us
    return float(np.linalg.norm(by_axis.max(axis=1) - by_axis.min(axis=1)))


def time_spans(trajectories: Mapping[K, Trajectory]) -> dict[K, tuple[float, float]]:
    """First and last stamp (seconds) of each non-empty trajectory of a mapping, by its key."""
    return {k: (float(t.stamps[0]), float(t.stamps[-1])) for k, t in trajectories.items() if len(t)}


#: What a relative threshold is a fraction of: ``extent`` (bounding-box diagonal) or ``length``
#: (distance travelled).
RELATIVE = ("extent", "length")


def size(positions: np.ndarray, relative_to: str = "extent") -> float:
    """The size a relative threshold is a fraction of, metres: :func:`extent` or
    :func:`path_length` of the positions (0 with fewer than two). The one rule of relative
    thresholds: scores and sweeps (the matched ground truth, :func:`lorisnb.core.pipeline.model.sequence_size`)
    and difficulty measures (the whole ground truth)."""
    if relative_to not in RELATIVE:
        raise ValidationError(f"relative_to={relative_to!r}: expected one of {', '.join(RELATIVE)}")
    if len(positions) < 2:
        return 0.0
    return extent(positions) if relative_to == "extent" else path_length(positions)


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Stamped poses, sorted by strictly increasing stamp.

    The constructor checks its arrays the way the file readers check a file's rows (one vectorized
    pass): lists and other sequences become float arrays; shapes must be (N,), (N, 3), (N, 4);
    stamps must be finite and quaternions non-zero and finite-norm (else a
    :class:`~lorisnb.errors.ValidationError` saying what to pass). As the readers do, with a
    :class:`~lorisnb.errors.LorisWarning`: poses with a NaN or infinite position or quaternion are
    skipped, and stamps that do not increase are sorted, keeping the last pose of a repeated
    stamp (the official tool's rule, :func:`lorisnb.read_tum`'s default). Readers and
    derivations of a checked trajectory use :meth:`from_checked`, which checks nothing.

    Attributes:
        stamps: (N,) seconds.
        positions: (N, 3) metres.
        quaternions: (N, 4) orientation as ``qx qy qz qw``, as read (not renormalized: the
            official tool's interpolation slip depends on the raw values).
        lines: (N,) 1-based line numbers in the source file, or None for computed poses.
        meta: free-form labels (for example ``{"simulated": True}``).
    """

    stamps: np.ndarray
    positions: np.ndarray
    quaternions: np.ndarray
    lines: np.ndarray | None = None
    meta: dict[str, Any] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.meta, dict):
            raise ValidationError(f"Trajectory meta: expected a dict, got {type(self.meta).__name__}")
        arrays = checked_arrays(self.stamps, self.positions, self.quaternions, self.lines)
        for name, value in zip(("stamps", "positions", "quaternions", "lines"), arrays, strict=True):
            object.__setattr__(self, name, value)

    @classmethod
    def from_checked(
        cls,
        stamps: np.ndarray,
        positions: np.ndarray,
        quaternions: np.ndarray,
        lines: np.ndarray | None = None,
        meta: dict[str, Any] | None = None,
    ) -> "Trajectory":
        """A Trajectory of arrays that already hold its invariants, taken as they are (no check,
        no copy): float arrays (N,), (N, 3), (N, 4), finite, quaternions non-zero, stamps
        increasing (or repeating, as a reader's ``repeated="keep"`` leaves them). For the readers
        (which check rows with line numbers) and for derivations of a checked trajectory; build
        anything else with the constructor."""
        traj = object.__new__(cls)
        for name, value in zip(
            ("stamps", "positions", "quaternions", "lines", "meta"),
            (stamps, positions, quaternions, lines, {} if meta is None else meta),
            strict=True,
        ):
            object.__setattr__(traj, name, value)
        return traj

    def __len__(self) -> int:
        return len(self.stamps)

    def __repr__(self) -> str:
        n = len(self.stamps)
        source = self.meta.get("source")
        where = f", from {str(source).rsplit('/', 1)[-1]}" if source else ""
        if n == 0:
            return f"<Trajectory: no poses{where}>"
        t0, t1 = float(self.stamps[0]), float(self.stamps[-1])
        span = (
            f"stamps {t0:g}..{t1:g} (pose indices)"
            if self.meta.get("stamps") == "index"
            else f"stamps {t0:.3f}..{t1:.3f} s ({t1 - t0:.3f} s)"
        )
        return f"<Trajectory: {n} poses, {span}, path {path_length(self.positions):.2f} m{where}>"

    @classmethod
    def empty(cls) -> "Trajectory":
        return cls.from_checked(np.zeros(0), np.zeros((0, 3)), np.zeros((0, 4)), np.zeros(0, dtype=int))

    @classmethod
    def from_rotations(
        cls, stamps: np.ndarray, positions: np.ndarray, rotations: Rotation, meta: dict[str, Any] | None = None
    ) -> "Trajectory":
        """Build from a scipy ``Rotation`` (stored as unit quaternions ``xyzw``)."""
        q = rotations.as_quat() if len(stamps) else np.zeros((0, 4))
        return cls(
            np.asarray(stamps, float),
            np.asarray(positions, float).reshape(-1, 3),
            q.reshape(-1, 4),
            None,
            dict(meta or {}),
        )

    def rotations(self) -> Rotation:
        """Orientations as a scipy ``Rotation`` (quaternions normalized)."""
        return rotations_of(self.quaternions)

    def subset(self, mask_or_index: Any) -> "Trajectory":
        """The poses selected by a boolean mask of the trajectory's length, an array (or list) of
        integer indices (negative ones count from the end, as in numpy), or a slice. The result
        is always sorted by stamp: indices that do not increase (after negative ones are taken
        from the end) are checked again and sorted as the constructor sorts, with its warning. An
        empty selection gives an empty trajectory. Anything else (a mask of another length,
        indices out of range, non-integer numbers, a single number) is a
        :class:`~lorisnb.errors.ValidationError`. ``traj[a:b]`` is ``traj.subset(slice(a, b))``."""
        sel = self._selection(mask_or_index)
        lines = None if self.lines is None else self.lines[sel]
        ordered = sel.dtype == bool or sel.size < 2 or bool((sel[1:] > sel[:-1]).all())
        return (Trajectory.from_checked if ordered else Trajectory)(
            self.stamps[sel],
            self.positions[sel],
            self.quaternions[sel],
            lines,
            dict(self.meta),
        )

    def _selection(self, value: Any) -> np.ndarray:
        """``value`` of :meth:`subset` as a boolean mask of this length or an array of
        non-negative integer indices below it."""
        n = len(self)
        if isinstance(value, slice):
            return np.arange(n)[value]
        if isinstance(value, (str, bytes)) or np.ndim(value) == 0:
            raise ValidationError(
                f"Trajectory.subset: got {type(value).__name__} {value!r:.40}; expected a boolean mask of "
                f"{n} values, an array of integer indices or a slice (for one pose: subset([i]))"
            )
        try:
            sel = np.asarray(value)
        except (TypeError, ValueError):
            raise ValidationError(
                f"Trajectory.subset: got {type(value).__name__}; expected a boolean mask of {n} values, "
                "an array of integer indices or a slice"
            ) from None
        if sel.ndim != 1:
            raise ValidationError(
                f"Trajectory.subset: an array of shape {sel.shape}; expected one dimension (a boolean mask of "
                f"{n} values or integer indices)"
            )
        if sel.size == 0:
            return np.zeros(0, dtype=np.intp)
        if sel.dtype == bool:
            if sel.size != n:
                raise ValidationError(
                    f"Trajectory.subset: a boolean mask of {sel.size} values for {n} poses; expected one value per pose"
                )
            return sel
        if sel.dtype.kind not in "iu":
            raise ValidationError(
                f"Trajectory.subset: values of type {sel.dtype}; expected a boolean mask of {n} values or "
                "integer indices"
            )
        lo, hi = int(sel.min()), int(sel.max())
        if lo < -n or hi >= n:
            bad = lo if lo < -n else hi
            raise ValidationError(
                f"Trajectory.subset: index {bad} is out of range for {n} poses; expected -{n} <= index < {n}"
            )
        return np.where(sel < 0, sel + n, sel) if lo < 0 else sel

    def __getitem__(self, key: Any) -> "Trajectory":
        """``traj[a:b]``, ``traj[mask]``, ``traj[[i, j]]``: :meth:`subset`. A single integer is
        refused (a Trajectory has no pose type: ``traj[[i]]`` is the one-pose trajectory,
        ``traj.stamps[i]`` its stamp)."""
        if isinstance(key, (int, np.integer)) or isinstance(key, tuple):
            raise ValidationError(
                f"Trajectory[{key!r}]: a Trajectory is indexed by a slice, a boolean mask or a list of "
                "indices (traj[[i]] for the one-pose trajectory; traj.stamps[i], traj.positions[i] for values)"
            )
        return self.subset(key)

    def __eq__(self, other: object) -> bool:
        """The same poses: equal stamps, positions, quaternions and line numbers (``meta`` is not
        compared). A Trajectory is mutable through ``meta`` and so not hashable."""
        if not isinstance(other, Trajectory):
            return NotImplemented
        if (self.lines is None) != (other.lines is None):
            return False
        pairs = [(self.stamps, other.stamps), (self.positions, other.positions), (self.quaternions, other.quaternions)]
        if self.lines is not None and other.lines is not None:
            pairs.append((self.lines, other.lines))
        return all(np.array_equal(a, b) for a, b in pairs)

    __hash__ = None  # type: ignore[assignment]

    @property
    def duration(self) -> float:
        """Last stamp minus first stamp, seconds (0 for fewer than two poses)."""
        return float(self.stamps[-1] - self.stamps[0]) if len(self) > 1 else 0.0

    @property
    def path_length(self) -> float:
        """Distance travelled, metres (:func:`path_length`)."""
        return path_length(self.positions)

    @property
    def extent(self) -> float:
        """Bounding-box diagonal of the positions, metres (:func:`extent`)."""
        return extent(self.positions)


#: How far (max abs entry) a block as written may be from the rotation of its pose's quaternion and
#: still be that pose's block: a reader's tolerance (1e-3) with a margin; an orientation changed since
#: (a body transform, an alignment) is further and drops the blocks.
WRITTEN_TOLERANCE = 2e-3


def keep_written_blocks(traj: Trajectory, blocks: np.ndarray) -> Trajectory:
    """``traj`` with the rotation blocks of its file as written ((N, 9) or (N, 3, 3), row-major),
    kept in its ``meta`` beside the line numbers they were read from (so every subset of the poses
    finds its own: :func:`written_blocks`). Returns ``traj`` (its meta updated)."""
    if traj.lines is not None and len(blocks) == len(traj):
        traj.meta["written_blocks"] = np.asarray(blocks, float).reshape(-1, 9)
        traj.meta["written_lines"] = traj.lines
    return traj


def written_blocks(traj: Trajectory) -> np.ndarray | None:
    """The (N, 3, 3) rotation blocks of ``traj``'s poses as its file wrote them (a KITTI file's
    7-digit matrices, not their nearest rotations), or None where they are not known: no blocks
    kept by the reader, poses without line numbers, or orientations changed since reading (a
    block further than :data:`WRITTEN_TOLERANCE` from its pose's quaternion)."""
    kept, lines = traj.meta.get("written_blocks"), traj.meta.get("written_lines")
    if kept is None or lines is None or traj.lines is None:
        return None
    if len(traj) == 0:
        return np.zeros((0, 3, 3))
    at = np.searchsorted(lines, traj.lines)
    if at.max() >= len(lines) or not np.array_equal(lines[at], traj.lines):
        return None
    blocks = kept[at].reshape(-1, 3, 3)
    if not np.abs(blocks - quat_to_matrix(traj.quaternions)).max() <= WRITTEN_TOLERANCE:
        return None
    return blocks


def sessions(name: str, value: Any) -> Mapping[int, Trajectory]:
    """``value`` as ``{session number: Trajectory}``: a mapping of integer keys to Trajectories as
    it is (the same object: a caller may let its poses go), one Trajectory as session 1;
    ValidationError for anything else."""
    if isinstance(value, Trajectory):
        return {1: value}
    if not isinstance(value, Mapping):
        raise ValidationError(
            f"{name}: expected a dict {{session number: Trajectory}} (or one Trajectory, taken as session 1), "
            f"got {type(value).__name__}"
        )
    for k, v in value.items():
        if not isinstance(k, (int, np.integer)) or isinstance(k, bool):
            raise ValidationError(f"{name}: key {k!r}: expected an integer session number (1, 2, ...)")
        if not isinstance(v, Trajectory):
            raise ValidationError(
                f"{name}[{k}]: expected a Trajectory (lorisnb.read_trajectory, or lorisnb.Trajectory(stamps, "
                f"positions, quaternions)), got {type(v).__name__}"
            )
    return value


def _array(name: str, value: Any, dtype: type = float) -> np.ndarray:
    kind = getattr(value, "dtype", None)
    if kind is not None and kind.kind in "cbOSUMm":  # complex (its imaginary part dropped), bool, text, dates
        raise ValidationError(f"Trajectory {name}: values of type {kind}; expected real numbers")
    try:
        return np.asarray(value, dtype)
    except (TypeError, ValueError):
        raise ValidationError(
            f"Trajectory {name}: expected numbers (a numpy array or a list), got {type(value).__name__}"
        ) from None


def checked_arrays(
    stamps: Any, positions: Any, quaternions: Any, lines: Any = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    """The arrays of a :class:`Trajectory` checked as the file readers check rows (one vectorized
    pass; see the class). Returns them as float arrays (no copy if they already are), poses with
    NaN or infinite values skipped and rows sorted by stamp (each with a LorisWarning)."""
    s, p, q = _array("stamps", stamps), _array("positions", positions), _array("quaternions", quaternions)
    ln = None if lines is None else _array("lines", lines, np.int64)
    if s.ndim != 1:
        raise ValidationError(f"Trajectory stamps: shape {s.shape}; expected (N,) seconds, one stamp per pose")
    n = s.size
    for name, a, shape in (("positions", p, (n, 3)), ("quaternions", q, (n, 4)), ("lines", ln, (n,))):
        if a is not None and a.shape != shape:
            what = {"positions": "x y z metres", "quaternions": "qx qy qz qw", "lines": "line numbers"}[name]
            raise ValidationError(
                f"Trajectory {name}: shape {a.shape} for {n} stamps; expected {shape} ({what}, one row per stamp)"
            )
    if not np.isfinite(s).all():
        i = int(np.flatnonzero(~np.isfinite(s))[0])
        raise ValidationError(f"Trajectory stamps: stamp {i} is {s[i]}; expected finite seconds")
    with np.errstate(over="ignore", invalid="ignore"):  # inf or NaN if a value is (or overflows: then per row)
        all_finite = bool(np.isfinite(p.sum()) and np.isfinite(q.sum()))
    if not all_finite:
        keep = np.isfinite(p).all(axis=1) & np.isfinite(q).all(axis=1)
        if not keep.all():
            warnings.warn(
                f"Trajectory: {int((~keep).sum())} of {n} pose(s) with NaN or infinite position or quaternion "
                f"skipped (first at index {int(np.flatnonzero(~keep)[0])}), as the file readers skip them",
                LorisWarning,
                stacklevel=4,
            )
            s, p, q, ln = s[keep], p[keep], q[keep], None if ln is None else ln[keep]
    if not quaternion_norms_fit(q):
        with np.errstate(over="ignore"):
            nq = np.einsum("ij,ij->i", q, q)
        i = int(np.flatnonzero(~((nq >= QUAT_EPS) & np.isfinite(nq)))[0])
        raise ValidationError(
            f"Trajectory quaternions: row {i} ({', '.join(f'{v:g}' for v in q[i])}) has zero or overflowing norm; "
            "expected a rotation qx qy qz qw of (about) unit norm"
        )
    if s.size > 1 and not (s[1:] > s[:-1]).all():
        back = np.flatnonzero(s[1:] <= s[:-1])
        i = int(back[0]) + 1
        kind = "repeats" if s[i] == s[i - 1] else "goes backwards"
        sorted_ = "sorted them and " if (s[1:] < s[:-1]).any() else ""  # only repeats: nothing was sorted
        warnings.warn(
            f"Trajectory: stamps are not increasing ({back.size} times; first at index {i}: {s[i]:.9f} {kind} "
            f"after {s[i - 1]:.9f}); {sorted_}kept the last pose of each repeated stamp, as the file "
            "readers do. Pass the poses sorted by stamp to avoid this",
            LorisWarning,
            stacklevel=4,
        )
        order = np.argsort(s, kind="stable")
        order = order[np.concatenate((s[order][1:] != s[order][:-1], [True]))]
        s, p, q, ln = s[order], p[order], q[order], None if ln is None else ln[order]
    return s, p, q, ln


def quaternion_norms_fit(quaternions: np.ndarray) -> bool:
    """Whether every quaternion's squared norm is finite and at least :data:`QUAT_EPS` (the usual
    case), looked at in row blocks on threads without a temporary of the array's length."""
    fits = [True]

    def rows(lo: int, hi: int) -> None:
        with np.errstate(over="ignore", invalid="ignore"):
            nq = np.einsum("ij,ij->i", quaternions[lo:hi], quaternions[lo:hi])
            if not (nq.min() >= QUAT_EPS and np.isfinite(nq.max())):  # NaN compares False
                fits[0] = False

    blockwise(rows, len(quaternions), 1 << 16)
    return fits[0]
