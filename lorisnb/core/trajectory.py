"""The trajectory type: stamped poses as plain arrays, and the sizes of a path (length, extent)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

from .geometry import rotations_of

if TYPE_CHECKING:
    from scipy.spatial.transform import Rotation

K = TypeVar("K")


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
    return float(np.linalg.norm(p.max(axis=0) - p.min(axis=0)))


def time_spans(trajectories: Mapping[K, Trajectory]) -> dict[K, tuple[float, float]]:
    """First and last stamp (seconds) of each non-empty trajectory of a mapping, by its key."""
    return {k: (float(t.stamps[0]), float(t.stamps[-1])) for k, t in trajectories.items() if len(t)}


#: What a relative threshold is a fraction of: ``extent`` (bounding-box diagonal) or ``length``
#: (distance travelled).
RELATIVE = ("extent", "length")


def size(positions: np.ndarray, relative_to: str = "extent") -> float:
    """The size a relative threshold is a fraction of, metres: :func:`extent` or
    :func:`path_length` of the positions (0 with fewer than two). The one rule of relative
    thresholds: scores and sweeps (the matched ground truth, :func:`lorisnb.core.model.sequence_size`)
    and difficulty measures (the whole ground truth)."""
    if relative_to not in RELATIVE:
        from ..errors import ValidationError

        raise ValidationError(f"relative_to={relative_to!r}: expected one of {', '.join(RELATIVE)}")
    if len(positions) < 2:
        return 0.0
    return extent(positions) if relative_to == "extent" else path_length(positions)


@dataclass(frozen=True)
class Trajectory:
    """Stamped poses, sorted by strictly increasing stamp.

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
        n = len(self.stamps)
        if self.positions.shape != (n, 3) or self.quaternions.shape != (n, 4):
            raise ValueError(
                f"Trajectory arrays disagree: {n} stamps, positions {self.positions.shape}, "
                f"quaternions {self.quaternions.shape}; expected (N,), (N, 3), (N, 4)"
            )

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
        return cls(np.zeros(0), np.zeros((0, 3)), np.zeros((0, 4)), np.zeros(0, dtype=int))

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

    def subset(self, mask_or_index: np.ndarray) -> "Trajectory":
        """The poses selected by a boolean mask or an index array."""
        lines = None if self.lines is None else self.lines[mask_or_index]
        return Trajectory(
            self.stamps[mask_or_index],
            self.positions[mask_or_index],
            self.quaternions[mask_or_index],
            lines,
            dict(self.meta),
        )

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
