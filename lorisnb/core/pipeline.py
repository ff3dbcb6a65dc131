"""Threshold-free per-pose errors of a result file against its ground truth, as the official tool
computes them: ground truth moved to the estimate's frame, association with interpolated ground
truth, alignment (per sequence, or on the first sequence for a lifelong file), ATE and AOE.

Pure: the ground truth (and, for one plausibility check, the time spans of other ground-truth
sequences) are arguments; nothing here reads files or looks for data.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping

import numpy as np

from ..errors import EvaluationError, LorisWarning, ParseError
from . import metrics, plausibility
from .association import MAX_GAP, Association, associate, groundtruth_in_frame
from .blocks import blockwise
from .frames import FRAMES, relative_extrinsic
from .geometry import (
    Sim3,
    quat_angle_deg,
    quat_conj_multiply,
    quat_from_matrix,
    quat_multiply,
    quat_normalize,
    quat_to_matrix,
    ros_quaternion_from_matrix,
    umeyama,
)
from .model import MODES, FileErrors, ResultFile, SequenceErrors, is_monocular
from .trajectory import Trajectory, path_length
from .validate import choice, scale_value

PLAUSIBILITY_POSES = 300  # estimate poses a plausibility check looks at (evenly spread)

#: Time spans (first, last stamp, seconds) of other ground-truth sequences by label (``cafe-2``),
#: or a function returning them (called only when a check needs them).
Spans = Mapping[str, tuple[float, float]] | Callable[[], Mapping[str, tuple[float, float]]]


def apply_alignment(
    sim: Sim3, positions: np.ndarray, quaternions: np.ndarray, official_interpolation: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """Apply an alignment to poses: positions (N, 3) metres and orientations (N, 4) quaternions
    ``xyzw`` (normalized here); unit quaternions out. With ``official_interpolation`` and a scale,
    the orientation is extracted from ``s * R * R_p`` as the official tool does (its slip (b))."""
    pos = sim.apply(positions)
    if official_interpolation and sim.scale != 1.0:
        blocks = sim.scale * np.einsum("ij,njk->nik", sim.rotation, quat_to_matrix(quaternions))
        return pos, quat_normalize(ros_quaternion_from_matrix(blocks))
    return pos, quat_normalize(quat_multiply(quat_from_matrix(sim.rotation), quat_normalize(quaternions)))


def errors_after_alignment(
    seq: int, est: Trajectory, a: Association, sim: Sim3, official_interpolation: bool = False
) -> SequenceErrors:
    """Per-pose ATE (m) and AOE (deg) of the matched poses of ``est`` after alignment ``sim``
    (in row blocks, :mod:`lorisnb.core.blocks`)."""
    if len(a) == 0 or a.gt_quaternions is None:
        return SequenceErrors.unmatched(seq, len(est), a.gt_start, a.gt_end)
    m = len(a)
    pos, q = np.empty((m, 3)), np.empty((m, 4))
    ate, aoe = np.empty(m), np.empty(m)
    gt_q = a.gt_quaternions

    def rows(lo: int, hi: int) -> None:
        k = a.est_index[lo:hi]
        p_k, q_k = np.take(est.positions, k, axis=0), np.take(est.quaternions, k, axis=0)  # without the GIL
        pos[lo:hi], q[lo:hi] = apply_alignment(sim, p_k, q_k, official_interpolation)
        ate[lo:hi] = metrics.ate(pos[lo:hi], a.gt_positions[lo:hi])
        aoe[lo:hi] = quat_angle_deg(quat_conj_multiply(gt_q[lo:hi], q[lo:hi]))  # unit on both sides

    blockwise(rows, m)
    return SequenceErrors(
        seq=seq, poses=len(est), stamps=a.stamps, ate=ate, aoe=aoe, est_positions=pos, gt_positions=a.gt_positions,
        est_quaternions=q, gt_quaternions=gt_q, gt_start=a.gt_start, gt_end=a.gt_end, scale=sim.scale,
    )  # fmt: skip


def sequence_errors(
    gt: Trajectory,
    est: Trajectory,
    *,
    scale: bool = False,
    max_gap: float = MAX_GAP,
    official_interpolation: bool = False,
    seq: int = 1,
) -> SequenceErrors:
    """Per-pose errors of one estimate against one ground truth in the same frame (TUM RGB-D,
    ORDSLAM, a simulated estimate): association within ``max_gap`` seconds, alignment of the
    estimate on itself (SE(3), or Sim(3) with ``scale``), ATE (m) and AOE (deg)."""
    a = associate(gt, est.stamps, max_gap, official_interpolation)
    if len(a) == 0:
        return SequenceErrors.unmatched(seq, len(est), a.gt_start, a.gt_end)
    sim = umeyama(est.positions[a.est_index], a.gt_positions, scale)
    return errors_after_alignment(seq, est, a, sim, official_interpolation)


def groundtruth_sequence(
    groundtruth: ResultFile, seq: int, scene: str, frame: str, official_interpolation: bool, gt_frame: str
) -> Trajectory:
    """Sequence ``seq`` of a ground-truth file moved to sensor ``frame``
    (:func:`~lorisnb.core.association.groundtruth_in_frame`), computed once per file, sequence and
    frame and kept in ``groundtruth.derived`` (a ground truth is shared by every result file of
    its scene)."""
    key = ("in_frame", seq, scene, frame, official_interpolation, gt_frame)
    found = groundtruth.derived.get(key)
    if not isinstance(found, Trajectory):
        found = groundtruth_in_frame(groundtruth.sequences[seq], scene, frame, official_interpolation, gt_frame)
        groundtruth.derived[key] = found
    return found


def compute_errors(
    result: ResultFile,
    groundtruth: ResultFile,
    *,
    algorithm: str | None = None,
    file: str | None = None,
    suite: str = "",
    mode: str = "auto",
    scale: bool | str = False,
    official_interpolation: bool = False,
    max_gap: float = MAX_GAP,
    checks: bool = True,
    other_spans: Spans | None = None,
    trial: int = 0,
    consume: bool = False,
) -> FileErrors:
    """Per-pose errors of one OpenLORIS result file against its scene's ground truth.

    Steps (the official tool's order): ground truth moved to the estimate's frame; association by
    interpolation within ``max_gap`` seconds; alignment of estimated positions (Horn/Umeyama SE(3),
    or Sim(3) with ``scale``); ATE (metres) and AOE (degrees) per matched pose.

    Args:
        result: the parsed result file (:func:`lorisnb.io.read_openloris`).
        groundtruth: the scene's ground truth (:func:`lorisnb.io.load_groundtruth`).
        algorithm: label; default the name of the folder holding the file.
        mode: ``per-seq`` aligns each sequence on itself; ``lifelong`` aligns on the
            lowest-numbered sequence with matches and applies that to every sequence;
            ``auto`` is lifelong for files with several ``seq:`` blocks, else per-seq.
        scale: True for Sim(3), False for SE(3), ``"auto"`` for Sim(3) on monocular
            algorithms (:func:`lorisnb.core.model.is_monocular`); the words of
            :func:`lorisnb.core.validate.scale_value` are accepted too.
        official_interpolation: reproduce the official tool's orientation slips (AOE only).
        checks: run the plausibility checks of :mod:`lorisnb.core.plausibility` (warnings only).
        other_spans: time spans of other ground-truth sequences, for the time-overlap check.
        trial: the trial number of this file (:mod:`lorisnb.core.trials`).
        consume: take each sequence out of ``result.sequences`` once its errors are computed, so
            that a long file's poses go while the next sequence is evaluated (for a caller that
            is done with ``result``; the one sequence a plausibility check still needs stays).

    Everything noticed (the reader's notes in ``result.warnings``, plausibility checks) is issued
    as LorisWarning and kept in ``FileErrors.warnings``.
    """
    mode = choice("mode", mode, MODES)
    scale = scale_value(scale)
    if not isinstance(result, ResultFile) or not isinstance(groundtruth, ResultFile):
        raise EvaluationError(
            "compute_errors needs parsed files (lorisnb.read_openloris); to evaluate paths use lorisnb.evaluate"
        )
    notes: list[str | None] = list(result.warnings)
    path = result.path
    algorithm = algorithm if algorithm is not None else path.parent.name
    scene, frame = result.scene, result.frame
    with_scale = is_monocular(algorithm) if scale == "auto" else bool(scale)
    seqs = sorted(result.sequences)
    if not seqs:
        raise ParseError(path, None, "no 'seq: N' block; expected at least one sequence")
    missing = [s for s in seqs if s not in groundtruth.sequences]
    if missing:
        s = missing[0]
        raise ParseError(
            path,
            result.seq_lines.get(s),
            f"sequence {s} has no ground truth in {groundtruth.path.name} "
            f"(it has {', '.join(map(str, sorted(groundtruth.sequences)))})",
        )
    lifelong = mode == "lifelong" or (mode == "auto" and len(seqs) > 1)
    gt_frame = groundtruth.header.get("frame", "base_link")
    if gt_frame not in FRAMES:
        raise ParseError(
            groundtruth.path,
            groundtruth.header_lines.get("frame"),
            f"unknown ground-truth frame {gt_frame!r}; expected one of {', '.join(FRAMES)}",
        )

    assoc: dict[int, Association] = {}
    for s in seqs:  # one iteration per sequence
        gt = groundtruth_sequence(groundtruth, s, scene, frame, official_interpolation, gt_frame)
        assoc[s] = associate(gt, result.sequences[s].stamps, max_gap, official_interpolation)
        if checks:
            label = f"{path.name}, seq {s}"
            notes.append(plausibility.groundtruth_gaps(label, groundtruth.sequences[s], max_gap))
            if len(assoc[s]) == 0 and len(result.sequences[s]):
                spans = {
                    f"{scene}-{k}": (float(t.stamps[0]), float(t.stamps[-1]))
                    for k, t in groundtruth.sequences.items()
                    if k != s and len(t)
                }
                more = other_spans() if callable(other_spans) else other_spans
                spans.update({k: v for k, v in (more or {}).items() if k not in spans and k != f"{scene}-{s}"})
                notes.append(
                    plausibility.time_overlap(
                        label, result.sequences[s].stamps, assoc[s].gt_start, assoc[s].gt_end, spans
                    )
                )

    def fit(s: int) -> Sim3:
        a = assoc[s]
        return umeyama(result.sequences[s].positions[a.est_index], a.gt_positions, with_scale)

    aligned_on: int | None = None
    alignment = Sim3.identity()
    per_seq_align: dict[int, Sim3] = {}
    if lifelong:
        with_matches = [s for s in seqs if len(assoc[s])]
        if with_matches:
            aligned_on = with_matches[0]
            alignment = fit(aligned_on)
            if aligned_on != seqs[0]:
                notes.append(
                    f"{path}: sequence {seqs[0]} has no pose matched to ground truth, so the "
                    f"lifelong alignment was computed on sequence {aligned_on} (the official tool "
                    f"would apply no alignment at all)"
                )
        elif any(len(result.sequences[s]) for s in seqs):
            notes.append(
                f"{path}: no pose of any sequence matches the ground truth in time; nothing to align "
                f"(see the time-span warnings; is the scene or the clock right?)"
            )
        per_seq_align = {s: alignment for s in seqs}
    else:
        for s in seqs:
            per_seq_align[s] = fit(s) if len(assoc[s]) else Sim3.identity()
        if len(seqs) == 1:
            alignment = per_seq_align[seqs[0]]
            aligned_on = seqs[0] if len(assoc[seqs[0]]) else None

    for s in [aligned_on] if lifelong and aligned_on is not None else [s for s in seqs if len(assoc[s])]:
        a = assoc[s]  # an alignment on positions that cannot fix a rotation: said, not changed (issue 24)
        notes.append(
            plausibility.degenerate_fit(
                f"{path.name}, seq {s}", result.sequences[s].positions[a.est_index], a.gt_positions
            )
        )
    if checks and not with_scale:
        fitted = [aligned_on] if lifelong and aligned_on is not None else [s for s in seqs if len(assoc[s]) > 2]
        for s in fitted:
            a = assoc[s]
            few = spread(len(a), 10 * PLAUSIBILITY_POSES)
            p_est, p_gt = (
                result.sequences[s].positions[a.est_index[few]],
                a.gt_positions[few],
            )  # a check: evenly spread poses
            sim, se3 = umeyama(p_est, p_gt, True), per_seq_align[s]
            if plausibility.scale_in_range(sim.scale):
                continue
            notes.append(
                plausibility.scale_far_from_one(
                    f"{path.name}, seq {s}",
                    sim.scale,
                    float(metrics.rmse(metrics.ate(se3.apply(p_est), p_gt))),
                    float(metrics.rmse(metrics.ate(sim.apply(p_est), p_gt))),
                    path_length(a.gt_positions),
                )
            )

    out: list[SequenceErrors] = []
    first_seen, suspect = False, None  # the first sequence with matches, if its AOE is large: the frame checks
    for s in seqs:
        e = errors_after_alignment(s, result.sequences[s], assoc.pop(s), per_seq_align[s], official_interpolation)
        out.append(e)
        if checks and not first_seen and e.matched > 10:
            first_seen, suspect = True, e if np.median(e.aoe) > 45.0 else None
        if consume and e is not suspect:
            del result.sequences[s]
    if suspect is not None:
        label = f"{path.name}, seq {suspect.seq}"
        by_frame, swapped = median_aoe_by_frame(
            result.sequences[suspect.seq], groundtruth.sequences[suspect.seq], scene, with_scale, max_gap, gt_frame,
            swapped_in=frame,
        )  # fmt: skip
        notes.append(plausibility.quaternion_order(label, float(np.median(suspect.aoe)), swapped))
        notes.append(plausibility.frame_mismatch(label, frame, by_frame))
    kept = [n for n in dict.fromkeys(notes) if n]
    for n in kept:
        warnings.warn(n, LorisWarning, stacklevel=2)
    return FileErrors(
        path=path, algorithm=algorithm, file=file if file is not None else path.name, suite=suite, scene=scene,
        frame=frame, mode="lifelong" if lifelong else "per-seq", alignment=alignment, aligned_on=aligned_on,
        official_interpolation=official_interpolation, sequences=out, warnings=kept, trial=trial,
        groundtruth_spans={k: (float(t.stamps[0]), float(t.stamps[-1])) for k, t in groundtruth.sequences.items() if len(t)},
    )  # fmt: skip


def spread(n: int, k: int) -> np.ndarray:
    """At most ``k`` indices of ``range(n)``, evenly spread, first and last included."""
    return np.round(np.linspace(0, n - 1, min(n, k))).astype(int) if n else np.zeros(0, int)


def median_aoe_by_frame(
    est: Trajectory,
    gt_base: Trajectory,
    scene: str,
    with_scale: bool,
    max_gap: float,
    gt_frame: str = "base_link",
    *,
    max_poses: int = PLAUSIBILITY_POSES,
    swapped_in: str | None = None,
) -> tuple[dict[str, float], float]:
    """Median AOE (deg) of one sequence with its ground truth moved to each sensor frame, and (with
    ``swapped_in``) the median AOE in that frame with each quaternion read ``qw qx qy qz``.

    A check, not a metric: at most ``max_poses`` estimate poses, evenly spread, are associated
    once with the ground truth as given and aligned once on its positions; the interpolated
    ground-truth orientations are then turned to each frame (``R_gt @ R_gt_frame``). Moving the
    positions by each frame's lever arm (a few centimetres) would change the alignment by far less
    than the tens of degrees this check looks for; the positions do not depend on the quaternion
    order either, so one alignment serves both questions. NaN where nothing matched."""
    if len(est) > max_poses:
        keep = spread(len(est), max_poses)
        est = est.subset(keep)
    a = associate(gt_base, est.stamps, max_gap)
    if len(a) < 3 or a.gt_quaternions is None:
        return {}, np.nan
    p_est = est.positions[a.est_index]
    q_est = est.quaternions[a.est_index]
    sim = umeyama(p_est, a.gt_positions, with_scale)
    q_rot = quat_from_matrix(sim.rotation)
    q_aligned = quat_multiply(q_rot, quat_normalize(q_est))
    offsets = np.stack([relative_extrinsic(scene, gt_frame, fr)[1] for fr in FRAMES])  # (7, 4)
    q_gt_fr = quat_multiply(a.gt_quaternions[None, :, :], offsets[:, None, :])  # every frame at once
    angles = quat_angle_deg(quat_conj_multiply(q_gt_fr, q_aligned[None, :, :]))
    by_frame = dict(zip(FRAMES, np.median(angles, axis=1).tolist(), strict=True))
    if swapped_in not in FRAMES:
        return by_frame, np.nan
    q_swapped = quat_multiply(q_rot, quat_normalize(np.roll(q_est, -1, axis=1)))
    k = FRAMES.index(swapped_in)
    return by_frame, float(np.median(quat_angle_deg(quat_conj_multiply(q_gt_fr[k], q_swapped))))
