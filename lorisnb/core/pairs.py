"""Per-pose errors of plain estimate / ground-truth pairs and of multi-session datasets, under any
of the field's conventions (:mod:`lorisnb.core.conventions`): TUM RGB-D, EuRoC, KITTI, ROS bags,
your own sessions. The result is a :class:`~lorisnb.core.model.FileErrors` like an OpenLORIS
file's, so every metric (ATE, AOE, RPE, correctness, CR, CR-T, CS-R, C-ATE, C-RPE) and every
table, sweep and figure of lorisnb applies.

Sessions in order: per session each estimate is matched with its ground truth; with
``lifelong=True`` one alignment is fitted on the first session that has matches and applied to
every session (the estimate keeps one map frame, as OpenLORIS' lifelong evaluation), else each
session is aligned on itself. ``transform`` (``T_est_gt``: the pose of the ground-truth body in the
estimate's body frame, a :class:`~lorisnb.core.geometry.Sim3` or a 4x4 matrix) is composed with
each estimate pose on the right first, when the estimate tracks another body (a camera on the
robot whose base the ground truth tracks): ``pose_est @ T_est_gt`` is then a pose of the
ground-truth body.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from ..errors import EvaluationError
from .association import Association, associate
from .conventions import Conventions, associate_nearest, fit_alignment
from .geometry import Sim3, quat_from_matrix, quat_multiply, quat_normalize, quat_rotate
from .model import FileErrors
from .pipeline import errors_after_alignment
from .trajectory import Trajectory

DEFAULT = Conventions()  # lorisnb's own: interpolation within 0.5 s, SE(3) on all matched poses


def match(gt: Trajectory, est: Trajectory, conventions: Conventions = DEFAULT) -> Association:
    """Matched poses of ``est`` and ``gt`` by the conventions' association (stamps shifted by
    ``t_offset`` first); for ``nearest`` the ground-truth poses are taken as they are."""
    stamps = est.stamps + conventions.t_offset
    if conventions.association == "interpolate":
        return associate(gt, stamps, conventions.max_gap)
    g_start = float(gt.stamps[0]) if len(gt) else np.nan
    g_end = float(gt.stamps[-1]) if len(gt) else np.nan
    gi, ej = associate_nearest(gt.stamps, stamps, conventions.max_diff)
    if ej.size == 0:
        return Association(ej, np.zeros(0), np.zeros((0, 3)), None, g_start, g_end)
    return Association(ej, stamps[ej], gt.positions[gi], quat_normalize(gt.quaternions[gi]), g_start, g_end)


def with_transform(est: Trajectory, transform: Sim3 | np.ndarray | None) -> Trajectory:
    """Estimate poses composed on the right with ``T_est_gt`` (poses of the ground-truth body;
    None: unchanged)."""
    if transform is None:
        return est
    m = transform.matrix() if isinstance(transform, Sim3) else np.asarray(transform, float)
    if m.shape != (4, 4):
        raise EvaluationError(f"transform: expected a 4x4 matrix T_est_gt, got shape {m.shape}")
    q_off = quat_from_matrix(m[:3, :3])
    q = quat_normalize(est.quaternions)
    pos = est.positions + quat_rotate(q, m[:3, 3])
    return Trajectory(est.stamps, pos, quat_multiply(q, q_off), est.lines, dict(est.meta))


def session_errors(
    groundtruth: Mapping[int, Trajectory],
    estimates: Mapping[int, Trajectory],
    conventions: Conventions = DEFAULT,
    *,
    lifelong: bool = False,
    transform: Sim3 | np.ndarray | None = None,
    path: str | Path = "estimate",
    algorithm: str = "estimate",
    scene: str = "sequence",
    suite: str = "",
    trial: int = 0,
    frame: str = "",
) -> FileErrors:
    """Errors of estimate sessions against their ground truth (see the module docstring).

    Args:
        groundtruth, estimates: session number -> trajectory; every estimate session needs a
            ground-truth session of the same number.
        conventions: association and alignment (:class:`~lorisnb.core.conventions.Conventions`).
        lifelong: one alignment for all sessions, fitted on the first with matches.
        transform: ``T_est_gt`` composed with each estimate pose first (None: same body).
        path, algorithm, scene, suite, trial, frame: labels of the result.
    """
    missing = sorted(set(estimates) - set(groundtruth))
    if missing:
        raise EvaluationError(
            f"{path}: session {missing[0]} has no ground truth (ground truth has {sorted(groundtruth)})"
        )
    seqs = sorted(estimates)
    if not seqs:
        raise EvaluationError(f"{path}: no session to evaluate")
    est = {s: with_transform(estimates[s], transform) for s in seqs}
    assoc = {s: match(groundtruth[s], est[s], conventions) for s in seqs}

    def fit(s: int) -> Sim3:
        a, e = assoc[s], est[s]
        k = a.est_index[: conventions.align_frames]  # the poses the fit uses; all of them: no copy
        positions = e.positions if len(k) == len(e) else e.positions[k]
        return fit_alignment(
            positions, a.gt_positions[: len(k)], conventions.align, conventions.align_frames,
            e.quaternions[k[:1]], a.gt_quaternions,  # the first orientation (used for one pose only)
        )  # fmt: skip

    notes: list[str] = []
    aligned_on: int | None = None
    if lifelong:
        with_matches = [s for s in seqs if len(assoc[s])]
        aligned_on = with_matches[0] if with_matches else None
        alignment = fit(aligned_on) if aligned_on is not None else Sim3.identity()
        per_seq = {s: alignment for s in seqs}
        if aligned_on is None:
            notes.append(f"{path}: no pose of any session matches the ground truth in time; nothing to align")
    else:
        per_seq = {s: fit(s) if len(assoc[s]) else Sim3.identity() for s in seqs}
        alignment = per_seq[seqs[0]]
        aligned_on = seqs[0] if len(assoc[seqs[0]]) else None
    for s in seqs:
        if len(est[s]) and not len(assoc[s]):
            notes.append(
                f"{path}, session {s}: no estimate stamp matches the ground truth ({conventions.describe()}); "
                f"estimate {est[s].stamps[0]:.3f}..{est[s].stamps[-1]:.3f} s, ground truth "
                f"{assoc[s].gt_start:.3f}..{assoc[s].gt_end:.3f} s"
            )
    out = [errors_after_alignment(s, est[s], assoc[s], per_seq[s]) for s in seqs]
    return FileErrors(
        path=Path(path), algorithm=algorithm, file=Path(path).name, suite=suite, scene=scene, frame=frame,
        mode="lifelong" if lifelong else "per-seq", alignment=alignment, aligned_on=aligned_on,
        official_interpolation=False, sequences=out, warnings=notes, trial=trial,
    )  # fmt: skip
