"""CR surfaces over eps x phi grids of any resolution, in memory that does not grow with grid size
times poses.

Correct time over a grid of (eps, phi) is a weighted two-dimensional dominance count: a pose is
correct at (eps_i, phi_j) exactly when ``ATE <= eps_i`` and ``AOE <= phi_j`` (Eq. 1, thresholds
inclusive). Each pose is binned at the first eps and the first phi it satisfies, weighted by the
time it holds, ``min(t_next - t, delta)`` (Eq. 2), and cumulative sums over both grid axes give
the correct time at every grid point: O(poses + grid) per sequence, for a whole scene group at once.
CR-T divides by the tracked time instead of the ground-truth time.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import pandas as pd

from lorisnb.core.lifelong.scoring import as_files
from lorisnb.core.lifelong.sweep import grid_values, scene_totals
from lorisnb.core.metrics import openloris as metrics
from lorisnb.core.pipeline.model import FileErrors
from lorisnb.core.spec.validate import threshold
from lorisnb.core.trajectory.blocks import blockwise, ordinary_pages
from lorisnb.errors import ValidationError


@dataclass(frozen=True, kw_only=True)
class Surfaces:
    """CR and CR-T of every (suite, algorithm, scene) over an eps x phi grid.

    Attributes:
        eps: (E,) metres, increasing. phi: (P,) degrees, increasing.
        groups: one row per surface: suite, algorithm, scene, trial, sequences.
        correct_time: (G, E, P) seconds. cr: (G, E, P), correct time over the scene's ground-truth
            time (Eq. 2). cr_t: (G, E, P), over the tracked time (Eq. 3).
        delta: the validity window used, seconds.
    """

    eps: np.ndarray
    phi: np.ndarray
    groups: pd.DataFrame
    correct_time: np.ndarray
    cr: np.ndarray
    cr_t: np.ndarray
    delta: float

    def at(self, algorithm: str, scene: str, suite: str | None = None, trial: int | None = None) -> np.ndarray:
        """The CR surface (E, P) of one algorithm and scene; ``suite`` and ``trial`` needed only
        where several surfaces have that algorithm and scene (an error lists them)."""
        g = self.groups
        hit = (g["algorithm"] == algorithm) & (g["scene"] == scene)
        hit &= (g["suite"] == suite) if suite is not None else True
        hit &= (g["trial"] == trial) if trial is not None else True
        rows = np.flatnonzero(hit)
        if rows.size != 1:
            have = "; ".join(
                f"{k}s {', '.join(map(repr, sorted(set(g[k]))))}" for k in ("algorithm", "scene", "suite", "trial")
            )
            what = "no surface" if rows.size == 0 else f"{rows.size} surfaces (give suite= and trial=)"
            raise ValidationError(f"{what} for {algorithm!r} in {scene!r} (suite {suite!r}, trial {trial}); "
                                  f"the surfaces hold {have}")  # fmt: skip
        return self.cr[rows[0]]


def _outputs(count: int, shape: tuple[int, ...]) -> list[np.ndarray]:
    """``count`` new float64 arrays of ``shape`` in ordinary pages (:func:`~lorisnb.core.trajectory.blocks.ordinary_pages`:
    they are written once, in order)."""
    before = ordinary_pages(True)
    try:
        return [np.empty(shape) for _ in range(count)]
    finally:
        ordinary_pages(before)


def _grid(name: str, values: object) -> np.ndarray:
    """A validated grid, sorted, without repeats."""
    items = grid_values(name, values)
    if any(isinstance(x, (str, dict)) for x in items):
        raise ValidationError(f"{name}: a surface's grid is numbers (metres or degrees), not 'paper' or a mapping")
    return np.unique(np.asarray(items, float))


def cr_surfaces(
    errors: FileErrors | Iterable[FileErrors],
    eps: object,
    phi: object,
    durations: pd.DataFrame,
    delta: float = 1.0,
) -> Surfaces:
    """CR and CR-T surfaces over the grid ``eps`` x ``phi`` (metres, degrees; any resolution) of
    every (suite, algorithm, scene, trial), with ``delta`` the validity window (seconds) and
    ``durations`` the ground-truth durations (``Evaluation.durations()``). Each value equals the
    scene CR that :func:`lorisnb.core.lifelong.aggregate.aggregate_scenes` gives for that setting. Groups
    are computed on threads within :func:`lorisnb.core.trajectory.blocks.threads`."""
    files = as_files(errors)
    eps_a, phi_a = _grid("eps", eps), _grid("phi", phi)
    delta = threshold("delta", delta)
    total = scene_totals(durations, (f.scene for f in files))
    E, P = len(eps_a), len(phi_a)
    keys: dict[tuple[str, str, str, int], int] = {}
    cells: list[list[np.ndarray]] = []  # per group: the grid cell of each pose, and its held time
    weights: list[list[np.ndarray]] = []
    tracked: list[float] = []
    nseq: list[int] = []
    for f in files:  # per file and sequence, never per pose
        key = (f.suite, f.algorithm, f.scene, f.trial)
        if key not in keys:
            keys[key] = len(cells)
            cells.append([])
            weights.append([])
            tracked.append(0.0)
            nseq.append(0)
        k = keys[key]
        for e in f.sequences:
            nseq[k] += 1
            if e.matched == 0:
                continue
            held = np.minimum(metrics.valid_intervals(e.stamps, e.gt_end, e.gt_start), delta)
            i = np.searchsorted(eps_a, e.ate, side="left")  # first eps with ATE <= eps
            j = np.searchsorted(phi_a, e.aoe, side="left")
            inside = (i < E) & (j < P)
            cells[k].append(i[inside] * P + j[inside])
            weights[k].append(held[inside])
            tracked[k] += e.gt_end - max(float(e.stamps[0]), e.gt_start)
    groups = pd.DataFrame(list(keys), columns=["suite", "algorithm", "scene", "trial"]).assign(sequences=nseq)
    scene_time = groups["scene"].map(total).to_numpy(float)
    tr = np.asarray(tracked, float)
    ct, cr, cr_t = _outputs(3, (len(cells), E, P))

    def group(k: int, _: int) -> None:  # while its histogram is in cache: cumulative sums, then CR and CR-T
        with np.errstate(invalid="ignore", divide="ignore"):
            if cells[k]:
                ct[k] = np.bincount(np.concatenate(cells[k]), np.concatenate(weights[k]), minlength=E * P).reshape(E, P)
                np.cumsum(ct[k], axis=0, out=ct[k])
                np.cumsum(ct[k], axis=1, out=ct[k])
            else:
                ct[k] = 0.0
            np.divide(ct[k], scene_time[k], out=cr[k])
            if tr[k] > 0:
                np.divide(ct[k], tr[k], out=cr_t[k])
            else:
                cr_t[k] = np.nan

    blockwise(group, len(cells), 1)  # groups on threads when the caller lends them (blocks.threads)
    return Surfaces(eps=eps_a, phi=phi_a, groups=groups, correct_time=ct, cr=cr, cr_t=cr_t, delta=delta)
