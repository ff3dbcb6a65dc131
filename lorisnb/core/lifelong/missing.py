"""Declared sessions without an estimate, scored as the paper scores missing output: a row with
0 poses and 0 matched, so its correct time is 0 (CR, CR-T and CS-R 0) while the scene's ground
truth still counts all of its duration. A missing estimate never vanishes from the table."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path

from lorisnb.core.alignment.geometry import Sim3
from lorisnb.core.pipeline.model import FileErrors, SequenceErrors
from lorisnb.core.trajectory.poses import Trajectory


def missing_sequence(seq: int, gt: Trajectory) -> SequenceErrors:
    """The errors of a session with no estimate: no pose, no match, the ground truth's span."""
    start = float(gt.stamps[0]) if len(gt) else float("nan")
    end = float(gt.stamps[-1]) if len(gt) else float("nan")
    return SequenceErrors.unmatched(seq, 0, start, end)


def with_missing(
    errors: FileErrors | None,
    groundtruth: Mapping[int, Trajectory],
    missing: Iterable[int],
    *,
    path: str | Path,
    algorithm: str,
    scene: str,
    suite: str = "",
    trial: int = 0,
    lifelong: bool = False,
    note: str = "",
) -> FileErrors:
    """``errors`` (None when no session had an estimate) with a :func:`missing_sequence` row for
    every session in ``missing``, in session order; ``note`` is added to its warnings. A new
    FileErrors: ``errors`` is not changed."""
    rows = [missing_sequence(s, groundtruth[s]) for s in missing]
    if errors is None:
        errors = FileErrors(
            path=Path(path), algorithm=algorithm, file=Path(path).name, suite=suite, scene=scene, frame="",
            mode="lifelong" if lifelong else "per-seq", alignment=Sim3.identity(), aligned_on=None,
            official_interpolation=False, sequences=[], trial=trial,
        )  # fmt: skip
    sequences = sorted([*errors.sequences, *rows], key=lambda e: e.seq)
    warnings = [*errors.warnings, note] if note else list(errors.warnings)
    fields = {k: getattr(errors, k) for k in errors.__dataclass_fields__}
    return FileErrors(**{**fields, "sequences": sequences, "warnings": warnings})
