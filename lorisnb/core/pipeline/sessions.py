"""The one evaluation pipeline: threshold-free per-pose errors of estimate sequences against their
ground truth under an :class:`~lorisnb.core.spec.evalspec.EvalSpec`, for every input kind.

    read (the edge) -> frames / transform -> associate -> align -> per-pose errors -> metrics

:func:`evaluate_sessions` is the pipeline. An OpenLORIS result file is its ``seq:`` blocks plus the
scene's ground truth moved to the file's sensor frame, under the ``openloris`` preset
(:func:`compute_errors`); a plain pair is one session (:func:`sequence_errors`), a manifest's
sessions or a bag topic are sessions with other values of the spec (:func:`session_errors`).

Pure: the ground truth (and, for one plausibility check, the time spans of other ground-truth
sequences) are arguments; nothing here reads files, looks for data, or writes into its arguments.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from lorisnb.core.alignment.association import Association, groundtruth_in_frame
from lorisnb.core.alignment.geometry import MIN_LEVER, PositionPairs, Sim3
from lorisnb.core.alignment.index_pairs import by_index, indexed
from lorisnb.core.conventions import evo_steps
from lorisnb.core.conventions.choices import fit_alignment
from lorisnb.core.metrics.relations import median_of
from lorisnb.core.pipeline import checks, plausibility
from lorisnb.core.pipeline.model import FileErrors, ResultFile, SequenceErrors, check_label, is_monocular
from lorisnb.core.pipeline.steps import (
    DEFAULT,
    apply_alignment,
    errors_after_alignment,
    groundtruth_frame,
    match,
    moved_groundtruth,
    with_transform,
)
from lorisnb.core.spec.evalspec import THRESHOLD_NAMES, EvalSpec, make_spec
from lorisnb.core.spec.evo import EVO_ASSOCIATIONS
from lorisnb.core.trajectory.frames import FRAMES
from lorisnb.core.trajectory.poses import Trajectory, sessions, time_spans, written_blocks
from lorisnb.errors import EvaluationError, LorisWarning, ParseError, ValidationError

__all__ = [
    "DEFAULT", "FrameInfo", "Spans", "apply_alignment", "compute_errors", "errors_after_alignment", "evaluate_sessions",
    "groundtruth_frame", "match", "moved_groundtruth", "session_errors", "sequence_errors", "window_spans", "with_transform",
]  # fmt: skip

K = TypeVar("K")

#: Time spans (first, last stamp, seconds) of other ground-truth sequences by label (``cafe-2``),
#: or a function returning them (called only when a check needs them).
Spans = Mapping[str, tuple[float, float]] | Callable[[], Mapping[str, tuple[float, float]]]
#: The sensor frames of an OpenLORIS file, for its frame checks: (scene, frame, ground-truth frame,
#: the ground truth as read, in its own frame).
FrameInfo = tuple[str, str, str, Mapping[int, Trajectory]]


def evaluate_sessions(
    groundtruth: Mapping[int, Trajectory] | Trajectory,
    estimates: Mapping[int, Trajectory] | Trajectory,
    spec: EvalSpec | str | None = DEFAULT,
    *,
    path: str | Path = "estimate",
    algorithm: str = "estimate",
    file: str | None = None,
    scene: str = "sequence",
    suite: str = "",
    trial: int = 0,
    frame: str = "",
    checks_on: bool = True,
    other_spans: Spans | None = None,
    frames: FrameInfo | None = None,
    release: Callable[[int], object] | None = None,
    release_groundtruth: Callable[[int], object] | None = None,
    notes: list[str] | None = None,
    groundtruth_spans: dict[int, tuple[float, float]] | None = None,
    sources: Mapping[int, str] | None = None,
    quaternions: str | None = None,
    labels: Mapping[int, str] | None = None,
) -> FileErrors:
    """Per-pose errors of estimate sequences against their ground truth: the one pipeline.

    Args:
        groundtruth: sequence number -> ground truth in the estimate's frame (every estimate
            sequence needs one); one Trajectory is sequence 1.
        estimates: sequence number -> estimate poses (the edge's objects; never changed here);
            one Trajectory is sequence 1.
        spec: association, alignment, mode and the rest (:class:`~lorisnb.core.spec.evalspec.EvalSpec`,
            or a preset name as :func:`session_errors` takes it; None: the default).
        path, algorithm, file, scene, suite, trial, frame: labels of the result.
        checks_on: run the plausibility checks (:mod:`lorisnb.core.pipeline.checks`; warnings only).
        other_spans: time spans of other ground-truth sequences, for the time-overlap check.
        frames: an OpenLORIS file's frames and raw ground truth, for its sensor-frame check.
        release: called with each sequence number once its errors are computed and the pipeline
            no longer needs its poses (the edge lets a long file's poses go).
        release_groundtruth: called with each sequence number once the estimates are matched and
            the pipeline no longer needs its ground truth (the edge lets a long one go before the
            alignment and the errors are computed).
        notes: what the reader noticed, kept first in ``FileErrors.warnings``.
        sources: sequence number -> the file it was read from (a manifest's sessions), named in the
            errors about that sequence (default ``path``, with the sequence number if several), as
            the same file's errors are named on every route.
        labels: sequence number -> how the notes about that sequence name it, where the input's
            name does not say which it is (a manifest's session: its file, name and number; one
            topic of a bag); default the ``file`` label or ``path``, with the sequence number.
        quaternions: the order the estimate's file wrote its quaternions in, by its format
            (:attr:`lorisnb.io.readers.registry.Format.quaternions`): ``"xyzw"`` or ``"wxyz"``, the
            one order mistake its orientation check names; ``""`` none (matrices, named fields: no
            order to mistake); None unknown (either mistake named, whichever fits).

    Every note is issued as a LorisWarning and kept in ``FileErrors.warnings``.
    """
    if not isinstance(spec, EvalSpec):  # a preset name, as session_errors takes it
        if spec is not None and not isinstance(spec, str):
            raise ValidationError(
                f"spec: got {type(spec).__name__}; expected an EvalSpec (lorisnb.make_spec) or a preset name ('tum', ...)"
            )
        spec = make_spec(spec)
    groundtruth, estimates = sessions("groundtruth", groundtruth), sessions("estimates", estimates)
    seqs = sorted(estimates)
    if not seqs:
        raise EvaluationError(f"{path}: no sequence to evaluate")
    missing = [s for s in seqs if s not in groundtruth]
    if missing:
        raise EvaluationError(
            f"{path}: sequence {missing[0]} has no ground truth (ground truth has {sorted(groundtruth)})"
        )
    found: list[str | None] = list(notes or [])
    if indexed([*estimates.values(), *(groundtruth[s] for s in seqs)]):  # KITTI files without times
        spec = by_index(spec)
    name = check_label(path, file)
    method = spec.alignment_for(algorithm)

    def where(s: int) -> str:  # the input a sequence's error is about: its file (a manifest's session), or path, seq
        return (sources or {}).get(s) or (f"{path}, seq {s}" if len(seqs) > 1 else str(path))

    def said(s: int) -> str:  # how a note names a sequence: its own label (a manifest's session), or input, seq
        return (labels or {}).get(s) or f"{name}, seq {s}"

    lifelong = spec.lifelong_for(len(seqs))
    est = {s: with_transform(estimates[s], spec.transform) for s in seqs}
    assoc: dict[int, Association] = {}
    durations = window_spans({s: groundtruth[s] for s in seqs}, spec)  # each sequence's time (CR's denominator)
    for s in seqs:  # one iteration per sequence
        gt_s, est[s] = evo_steps.prepare(groundtruth[s], est[s], spec)  # evo's downsample, motion filter, window
        if spec.association in EVO_ASSOCIATIONS:
            assoc[s], est[s] = evo_steps.evo_match(gt_s, est[s], spec)
        else:
            assoc[s] = match(gt_s, est[s], spec, where(s))
        if s in durations and (assoc[s].gt_start, assoc[s].gt_end) != durations[s]:  # thinned: its time stays
            assoc[s] = replace(assoc[s], gt_start=durations[s][0], gt_end=durations[s][1])
        if checks_on:
            label = said(s)
            raw = frames[3][s] if frames is not None else groundtruth[s]
            if spec.association == "interpolate":
                found.append(plausibility.groundtruth_gaps(label, raw, spec.max_gap))
            if len(assoc[s]) == 0 and len(est[s]):
                more = other_spans() if callable(other_spans) else other_spans
                spans = checks.other_spans(frames[3] if frames is not None else groundtruth, scene, s, more)
                thinned = (len(groundtruth[s]), len(gt_s)), (len(estimates[s]), len(est[s]))
                found.append(
                    evo_steps.prepared_away(label, *thinned, spec)
                    or plausibility.time_overlap(label, est[s].stamps, assoc[s].gt_start, assoc[s].gt_end, spans)
                    or f"{label}: no estimate stamp matches the ground truth ({spec.describe().split(';')[0]}); "
                    f"estimate {est[s].stamps[0]:.3f}..{est[s].stamps[-1]:.3f} s, ground truth "
                    f"{assoc[s].gt_start:.3f}..{assoc[s].gt_end:.3f} s"
                )

    lengths = {s: evo_steps.whole_length(groundtruth[s]) for s in seqs}  # rpg's relative error needs them
    if release_groundtruth is not None:  # matched: the ground truth's poses are not needed any more
        del gt_s  # the loop's last references go (seqs is not empty)
        if checks_on:
            del raw
        for s in seqs:
            release_groundtruth(s)

    pairs: dict[
        int, PositionPairs | None
    ] = {}  # each fitted sequence's spread positions, once for the fit and both checks

    def spread_pairs(s: int) -> PositionPairs | None:
        if s not in pairs:
            pairs[s] = checks.spread_pairs(est[s].positions, assoc[s])
        return pairs[s]

    def fit(s: int) -> Sim3:
        a, e = assoc[s], est[s]
        q_e = a.est_rows(e.quaternions) if spec.align_frames == 1 or method == "origin" else None
        written = written_blocks(e) if method == "origin" and a.gt_blocks is not None and len(a) else None
        origin = None if written is None or a.gt_blocks is None else (written[a.est_index[0]], a.gt_blocks[0])
        # the checks' positions are these same ones where they spread over all matched poses: centred once for both
        every = method in ("se3", "sim3") and spec.align_frames is None and checks.spreads_all(len(a))
        shared = spread_pairs(s) if every else None
        try:  # an OpenLORIS file (frames given) is aligned as the official tool aligns it
            return fit_alignment(a.est_rows(e.positions), a.gt_positions, method, spec.align_frames, q_e,
                                 a.gt_quaternions, strict=frames is None, notes=found, origin_blocks=origin,
                                 label=said(s), pairs=shared)  # fmt: skip
        except EvaluationError as exc:  # named with the sequence (the session's file) it is about
            raise EvaluationError(f"{where(s)}: {exc}") from None

    aligned_on: int | None = None
    alignment = Sim3.identity()
    if lifelong:
        with_matches = [s for s in seqs if len(assoc[s])]
        if with_matches and with_matches[0] != seqs[0] and spec.official_lifelong:
            found.append(  # the official transform_world_frame returns before fitting: nothing is aligned
                f"{path}: sequence {seqs[0]} has no pose matched to ground truth, so no alignment is applied to "
                f"any sequence, as the official tool does (--official-lifelong, official_lifelong=True; without it, "
                f"lorisnb aligns all on sequence {with_matches[0]})"
            )
        elif with_matches:
            aligned_on = with_matches[0]
            alignment = fit(aligned_on)
            if aligned_on != seqs[0]:
                found.append(
                    f"{path}: sequence {seqs[0]} has no pose matched to ground truth, so the "
                    f"lifelong alignment was computed on sequence {aligned_on} (the official tool "
                    f"would apply no alignment at all, as --official-lifelong, official_lifelong=True, does)"
                )
        elif any(len(est[s]) for s in seqs):
            found.append(
                f"{path}: no pose of any sequence matches the ground truth in time; nothing to align "
                f"(see the time-span warnings; is the scene or the clock right?)"
            )
        per_seq = {s: alignment for s in seqs}
    else:
        per_seq = {s: fit(s) if len(assoc[s]) else Sim3.identity() for s in seqs}
        if len(seqs) == 1:
            alignment = per_seq[seqs[0]]
            aligned_on = seqs[0] if len(assoc[seqs[0]]) else None

    degenerate: set[int] = set()  # the sequences whose fit is said to be degenerate (said once, not twice)
    if frames is not None:  # an OpenLORIS file is aligned as the official tool aligns it, degenerate or not: said
        fitted = ([] if aligned_on is None else [aligned_on]) if lifelong else [s for s in seqs if len(assoc[s])]
        for s in fitted:  # in lifelong mode, the later sequences' errors come after that fit too: named
            applied = [k for k in seqs if k != s and len(assoc[k])] if lifelong else []
            note = checks.degenerate_note(said(s), est[s].positions, assoc[s], spread_pairs(s),
                                          method == "sim3", applied)  # fmt: skip
            if note is not None:
                degenerate.add(s)
                found.append(note)
    if checks_on and method == "se3":
        hint = "--scale, or --scale auto for dso/svo" if frames is not None else "--align sim3"
        if is_monocular(algorithm) and "align" not in spec.explicit:  # its scale is arbitrary: said once
            found.append(plausibility.monocular_without_scale(name, algorithm, hint))
        fitted = ([] if aligned_on is None else [aligned_on]) if lifelong else [s for s in seqs if len(assoc[s]) > 2]
        for s in fitted:
            found.append(checks.scale_note(said(s), spread_pairs(s), assoc[s], per_seq[s], hint))

    out: list[SequenceErrors] = []
    suspect: tuple[SequenceErrors, Association] | None = None
    first_seen = False  # the first sequence with matches, if its AOE is large: the orientation checks
    for s in seqs:
        a = assoc.pop(s)
        e = errors_after_alignment(s, est[s], a, per_seq[s], spec.official_interpolation)
        e = evo_steps.projected(e, spec.project_to_plane) if spec.project_to_plane else e
        out.append(e)
        if checks_on and not first_seen and e.matched > 10:
            first_seen = True
            suspect = (e, a) if plausibility.median_above(e.aoe, plausibility.SUSPECT_AOE) else None
        if suspect is None or suspect[0] is not e:
            if release is not None:
                release(s)
            del est[s]
    if suspect is not None:
        e, a = suspect
        label = said(e.seq)
        # the sequence the rotation was fitted on, on all its matched positions (se3, sim3): its lever
        on = next((x for x in out if x.seq == aligned_on), None) if lifelong else e
        fitted_on_all = on is not None and method in ("se3", "sim3") and spec.align_frames is None
        if on is not None and fitted_on_all and on.rotation_lever < MIN_LEVER:  # the rotation is the positions'
            if on.seq not in degenerate:  # noise: nothing to tell apart (a degenerate fit is said already)
                fitted_on = f"seq {on.seq}" if on.seq != e.seq else None  # a later sequence: named the fitted one
                found.append(plausibility.rotation_not_held(label, median_of(e.aoe), on.rotation_lever,
                                                            on.matched, fitted_on))  # fmt: skip
        elif frames is not None and frame in FRAMES:
            sc, fr, gt_frame, raw_gt = frames
            found += checks.frame_notes(
                label, est[e.seq], raw_gt[e.seq], sc, fr, gt_frame, method == "sim3", spec.max_gap,
                median_of(e.aoe),
            )  # fmt: skip
        else:
            median = median_of(e.aoe)
            if median >= plausibility.SUSPECT_AOE:  # read in the other order: w last (TUM's) or w first (EuRoC's)
                swapped = {k: checks.median_aoe_swapped(est[e.seq], a, per_seq[e.seq], shift=k) for k in (-1, 1)}
                # shift -1: a file read 'qx qy qz qw' that wrote 'qw qx qy qz'; +1: read w first, written w last;
                # the mistakes its format allows (quaternions unknown: either; matrices, named fields: none)
                mistakes = (-1, 1) if quaternions is None else {"xyzw": (-1,), "wxyz": (1,)}.get(quaternions, ())
                note = None
                if mistakes:
                    k = min(mistakes, key=lambda m: swapped[m])
                    note = plausibility.quaternion_order(label, median, swapped[k], k == 1)
                if note is None and len(mistakes) < 2:  # a move no order of its format explains fits
                    k = min((m for m in (-1, 1) if m not in mistakes), key=lambda m: swapped[m])
                    note = plausibility.orientations_permuted(label, median, swapped[k], quaternions or "")
                found.append(note)
        if release is not None:
            release(e.seq)
    kept = [n for n in dict.fromkeys(found) if n]
    for n in kept:
        warnings.warn(n, LorisWarning, stacklevel=2)
    return FileErrors(
        path=Path(path), algorithm=algorithm, file=file if file is not None else Path(path).name, suite=suite,
        scene=scene, frame=frame, mode="lifelong" if lifelong else "per-seq", alignment=alignment,
        aligned_on=aligned_on, official_interpolation=spec.official_interpolation, sequences=out, warnings=kept,
        trial=trial, groundtruth_spans={**(groundtruth_spans or {}), **durations},
        groundtruth_lengths=lengths, rpe=spec.rpe_options(),
    )  # fmt: skip


def window_spans(groundtruth: Mapping[K, Trajectory], spec: EvalSpec) -> dict[K, tuple[float, float]]:
    """Each ground-truth sequence's time span as the spec evaluates it (first and last stamp,
    seconds): within evo's time window (``t_start``/``t_end``) when one is set, and never shortened
    by ``downsample`` or ``motion_filter``, which thin the poses but not the sequence's time. A
    sequence's rows (CR = correct time / this duration) and its scene's total
    (:meth:`~lorisnb.tools.evaluation.result.Evaluation.durations`) both use it; a sequence with no
    ground-truth stamp in the window has no duration (its span starts and ends at the window)."""
    if spec.t_start is None and spec.t_end is None:
        return time_spans(groundtruth)
    lo = -np.inf if spec.t_start is None else spec.t_start
    hi = np.inf if spec.t_end is None else spec.t_end
    out: dict[K, tuple[float, float]] = {}
    for k, t in groundtruth.items():
        if not len(t):
            continue
        first, last = np.searchsorted(t.stamps, lo, "left"), np.searchsorted(t.stamps, hi, "right") - 1
        if first <= last:
            out[k] = (float(t.stamps[first]), float(t.stamps[last]))
        else:  # nothing of this sequence inside the window
            edge = float(min(max(lo, t.stamps[0]), hi))
            out[k] = (edge, edge)
    return out


def _refuse_thresholds(where: str, options: Mapping[str, Any]) -> None:
    """Thresholds given to a function computing errors (which score nothing) are refused, saying
    that :func:`lorisnb.score` (or ``evaluate``) takes them; the RPE options are the spec's and carry
    through to the scores (``FileErrors.rpe``)."""
    given = [k for k in THRESHOLD_NAMES if k in options]
    if given:
        shown = ", ".join(f"{k}={options[k]!r}" for k in given)
        raise ValidationError(
            f"{where}({shown}): thresholds are not used in computing errors; pass them to lorisnb.score(errors, "
            f"{shown}) (or to lorisnb.evaluate, whose tables use them)"
        )


def compute_errors(
    result: ResultFile,
    groundtruth: ResultFile,
    spec: EvalSpec | None = None,
    *,
    algorithm: str | None = None,
    file: str | None = None,
    suite: str = "",
    trial: int = 0,
    checks: bool = True,
    other_spans: Spans | None = None,
    in_frame: Mapping[int, Trajectory] | None = None,
    release: Callable[[int], object] | None = None,
    **options: Any,
) -> FileErrors:
    """Per-pose errors of one OpenLORIS result file against its scene's ground truth: the file's
    sequences and the ground truth moved to its sensor frame, through :func:`evaluate_sessions`.

    Steps (the official tool's order): ground truth moved to the estimate's frame; association by
    interpolation within ``max_gap`` seconds; alignment of estimated positions (Horn/Umeyama SE(3),
    or Sim(3) with scale); ATE (metres) and AOE (degrees) per matched pose.

    Args:
        result: the parsed result file (:func:`lorisnb.io.read_openloris`).
        groundtruth: the scene's ground truth (:func:`lorisnb.io.load_groundtruth`).
        spec: the evaluation spec (default the ``openloris`` preset); ``options`` are spec options
            over it (``mode``, ``scale``, ``official_interpolation``, ``max_gap``, ...; see
            :func:`lorisnb.core.spec.evalspec.make_spec`).
        algorithm: label; default the name of the folder holding the file.
        checks: run the plausibility checks (warnings only).
        other_spans: time spans of other ground-truth sequences, for the time-overlap check.
        in_frame: the ground truth already moved to the file's frame (the edge's cache), by sequence.
        release: see :func:`evaluate_sessions`.

    The thresholds (``eps``, ``phi``, ``delta``, ``tau``) are not options here: errors are computed
    once for every setting, and :func:`lorisnb.score` takes the setting (given here they were
    ignored by it: a ValidationError says so).
    """
    _refuse_thresholds("compute_errors", options)
    spec = make_spec(spec, **options)
    spec.refuse_inapplicable("openloris")
    if not isinstance(result, ResultFile) or not isinstance(groundtruth, ResultFile):
        raise EvaluationError(
            "compute_errors needs parsed files (lorisnb.read_openloris); to evaluate paths use lorisnb.evaluate"
        )
    path, seqs = result.path, sorted(result.sequences)
    if not seqs:
        raise ParseError(path, None, "no 'seq: N' block; expected at least one sequence")
    missing = [s for s in seqs if s not in groundtruth.sequences]
    if missing:
        raise ParseError(
            path, result.seq_lines.get(missing[0]),
            f"sequence {missing[0]} has no ground truth in {groundtruth.path.name} "
            f"(it has {', '.join(map(str, sorted(groundtruth.sequences)))})",
        )  # fmt: skip
    scene, frame, gt_frame = result.scene, result.frame, groundtruth_frame(groundtruth)
    if in_frame is None:
        in_frame = {
            s: groundtruth_in_frame(groundtruth.sequences[s], scene, frame, spec.official_interpolation, gt_frame)
            for s in seqs
        }
    frames = (scene, frame, gt_frame, groundtruth.sequences)
    return evaluate_sessions(
        {s: in_frame[s] for s in seqs}, result.sequences, spec, path=path,
        algorithm=algorithm if algorithm is not None else result.path.parent.name,
        file=file, scene=scene, suite=suite, trial=trial, frame=frame, checks_on=checks,
        other_spans=other_spans, frames=frames, release=release, notes=list(result.warnings),
        groundtruth_spans=window_spans(groundtruth.sequences, spec),
        quaternions="xyzw",  # OpenLORIS files write 'qx qy qz qw' (the format registry's openloris entry)
    )  # fmt: skip


def session_errors(
    groundtruth: Mapping[int, Trajectory] | Trajectory,
    estimates: Mapping[int, Trajectory] | Trajectory,
    conventions: EvalSpec | str | None = None,
    *,
    lifelong: bool = False,
    transform: Sim3 | np.ndarray | None = None,
    path: str | Path = "estimate",
    algorithm: str = "estimate",
    scene: str = "sequence",
    suite: str = "",
    trial: int = 0,
    frame: str = "",
    checks: bool = True,
) -> FileErrors:
    """Errors of estimate sessions against their ground truth, each a dict ``{session number:
    Trajectory}`` (every estimate session needs a ground-truth session of the same number; one
    Trajectory on either side is session 1), through :func:`evaluate_sessions`: ``lifelong`` fits
    one alignment on the first session with matches; ``transform`` (``T_est_gt``, the ground-truth
    body's pose in the estimate's body frame) is composed with each estimate pose first."""
    spec = make_spec(conventions, lifelong=lifelong, transform=transform)
    return evaluate_sessions(
        groundtruth, estimates, spec, path=path, algorithm=algorithm, scene=scene, suite=suite, trial=trial,
        frame=frame, checks_on=checks,
    )  # fmt: skip


def sequence_errors(
    gt: Trajectory, est: Trajectory, spec: EvalSpec | None = None, *, seq: int = 1, **options: Any
) -> SequenceErrors:
    """Per-pose errors of one estimate against one ground truth in the same frame (TUM RGB-D,
    ORDSLAM, a simulated estimate), through :func:`evaluate_sessions` without plausibility checks:
    by default association within ``max_gap`` seconds and the estimate aligned on itself (SE(3), or
    Sim(3) with ``scale=True``); ATE (m) and AOE (deg). Thresholds are :func:`lorisnb.score`'s, not
    options here (as for :func:`compute_errors`)."""
    _refuse_thresholds("sequence_errors", options)
    spec = make_spec(spec, **options)
    return evaluate_sessions({seq: gt}, {seq: est}, spec, checks_on=False).sequences[0]
