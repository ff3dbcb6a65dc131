"""One unit of evaluation work per input, for every input kind: an OpenLORIS result file, an
estimate of a plain pair, or one algorithm's sessions of a manifest scene. A :class:`Job` is
picklable (process pools, Dask); :func:`run_job` reads what it needs (the edge: files, the data
root, caches of ground truth), runs the one pipeline
(:func:`lorisnb.core.pipeline.sessions.evaluate_sessions`) and never raises for bad input.
"""

from __future__ import annotations

import contextlib
import os
import warnings
from dataclasses import dataclass, replace
from functools import lru_cache, partial
from pathlib import Path
from typing import Any

import numpy as np

from lorisnb.core.lifelong.missing import with_missing
from lorisnb.core.lifelong.scoring import score_rows
from lorisnb.core.pipeline.model import FileErrors, ResultFile, check_label, scores_only
from lorisnb.core.pipeline.plausibility import no_rpe_pair
from lorisnb.core.pipeline.sessions import compute_errors, evaluate_sessions, moved_groundtruth, window_spans
from lorisnb.core.spec.evalspec import EvalSpec
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.core.trajectory.units import check_stamp_units
from lorisnb.errors import DataNotFoundError, LorisError, LorisWarning, ParseError, ValidationError
from lorisnb.io.datasets.manifest import Manifest, Session
from lorisnb.io.datasets.paths import DataPaths, groundtruth_spans, load_groundtruth, named_entry, read_groundtruth_file
from lorisnb.io.readers.bags import manifest_terms
from lorisnb.io.readers.openloris import declared_scene, read_openloris
from lorisnb.io.readers.plain import read_trajectory
from lorisnb.io.readers.registry import FORMATS, hint
from lorisnb.tools.evaluation.inputs import labels, missing_note, outside_results, real_path, unquoted
from lorisnb.tools.evaluation.pool import size_of
from lorisnb.tools.evaluation.result import Failure
from lorisnb.tools.evaluation.status import NOT_PUBLIC

#: Files at least this large show a progress bar of their own while read (when evaluated here).
BIG_FILE_BYTES = 64 * 2**20


@dataclass(frozen=True, kw_only=True)
class PairSource:
    """How the files of a pair are read: the ground truth, the formats, KITTI times files, bag
    topics or TF chains, and the scene label of the rows."""

    groundtruth: Path
    fmt: str = "tum"
    gt_fmt: str = "tum"
    scene: str = "sequence"
    est_times: Path | None = None
    gt_times: Path | None = None
    topic: str | None = None
    gt_topic: str | None = None
    tf: str | None = None
    gt_tf: str | None = None
    label_topic: bool = False  # one of several topics of the bag: the rows' algorithm is '<algorithm>:<topic>'


@dataclass(frozen=True, kw_only=True)
class Job:
    """Everything one worker needs to evaluate one input (picklable)."""

    kind: str  # openloris, pair or manifest
    path: Path  # the result or estimate file; a manifest: the algorithm's folder
    root: Path | None
    spec: EvalSpec
    trials_by: str | None = None
    data: DataPaths | None = None  # openloris: where the ground truth is
    scenes: frozenset[str] | None = None  # openloris: evaluate only these
    source: PairSource | None = None  # pair
    manifest: Manifest | None = None  # manifest
    scene: str = ""  # manifest: the scene of this job
    statistics: bool = True  # the spec's setting scored with the error statistics too (evaluate's ``statistics``)
    keep_poses: bool = True  # False: each pose's errors let go once that setting is scored (evaluate's ``keep_poses``)


def absolute_paths(job: Job) -> Job:
    """``job`` with every path it reads absolute (the input, its root, the data root, a pair's
    ground truth and times files, a manifest's file): a worker elsewhere (a Dask cluster's) opens
    a relative path in its own folder, which scored a file of that name there, or none."""

    def a(p: Any) -> Any:
        return None if p is None else Path(os.path.abspath(p))

    source = job.source
    if source is not None:
        source = replace(source, groundtruth=a(source.groundtruth), est_times=a(source.est_times),
                         gt_times=a(source.gt_times))  # fmt: skip
    data = job.data if job.data is None else replace(job.data, root=a(job.data.root))
    manifest = job.manifest if job.manifest is None else replace(job.manifest, path=a(job.manifest.path))
    return replace(job, path=a(job.path), root=a(job.root), source=source, data=data, manifest=manifest)


def _stamp(path: Path) -> tuple[float, int]:
    st = os.stat(path)
    return st.st_mtime, st.st_size


#: Ground-truth files up to this size are read once per process; larger ones for each input, so
#: that the pipeline can let them go once the estimate is matched (a million poses and more).
CACHED_BYTES = 32 << 20


#: An OpenLORIS ground truth (official format) loses its repeated poses under the ``openloris``
#: preset whatever the spec's rule, which is then the estimate's: the official tool reads it so with
#: or without ``-k`` (its ``--keep-repeated``). Under another preset it follows the spec's rule, as
#: the estimate does (:func:`gt_drops_repeated`).
GT_DROP = True


def gt_drops_repeated(spec: EvalSpec) -> bool:
    """Whether an OpenLORIS ground truth (official format) loses its repeated poses (a pose identical
    to the one before): :data:`GT_DROP` under the ``openloris`` preset (the official tool's reading,
    ``--keep-repeated`` being the estimate's alone, as its ``-k``), else the spec's rule, as an
    estimate in that format follows it (what the ``conventions:`` line says:
    :meth:`~lorisnb.core.spec.evalspec.EvalSpec.describe`)."""
    return GT_DROP if spec.preset_name == "openloris" else spec.repeated == "drop"


def _gt_rule(spec: EvalSpec, fmt: str, rule: str) -> str:
    """The repeated rule reading a ground truth of format ``fmt``: an OpenLORIS file's by
    :func:`gt_drops_repeated`, any other's ``rule``."""
    return ("drop" if gt_drops_repeated(spec) else "keep") if fmt == "openloris" else rule


def backwards(gt: Trajectory) -> tuple[int, str] | None:
    """Where a ground truth read from a text file has a stamp earlier than the one on the line
    before it, (line, reason), else None: a reader sorts such stamps (an estimate's, with a note),
    but the ground truth is the reference (its span is the time CR and CS-R divide by), and one
    corrupted stamp (written in nanoseconds, an hour early, 0) sorted into it changes every
    number. Found from the line numbers the sorted poses keep (increasing unless a stamp went
    back); repeated stamps are not backwards (the spec's ``repeated`` rule takes them)."""
    lines = gt.lines
    if lines is None or len(lines) < 2 or bool((lines[1:] > lines[:-1]).all()):
        return None
    order = np.argsort(lines, kind="stable")
    stamps, at = gt.stamps[order], lines[order]
    back = np.flatnonzero(stamps[1:] < stamps[:-1])
    if not back.size:  # pragma: no cover - line order broken only by a stamp going back
        return None
    k = int(back[0]) + 1
    return int(at[k]), (
        f"the ground truth's stamp {stamps[k]:.9f} goes back from {stamps[k - 1]:.9f} (line {int(at[k - 1])}; "
        f"{back.size} stamp(s) in all go back); a ground truth is the reference of every number and is not sorted: one "
        "of the two stamps is wrong (another unit, a clock jump, a stamp 0): fix or remove its line"
    )


def refuse_backwards(path: str | os.PathLike[str], gt: Trajectory, label: str = "") -> None:
    """A ParseError naming the line where ``gt`` (read from ``path``) goes back in time
    (:func:`backwards`); ``label`` names the sequence of a file of several."""
    found = backwards(gt)
    if found is not None:
        raise ParseError(path, found[0], label + found[1])


@lru_cache(maxsize=64)
def _read_groundtruth(
    path: Path, fmt: str, stamp: tuple[float, int], times: Path | None, topic: str | None, tf: str | None,
    repeated: str = "drop",
) -> tuple[Trajectory, tuple[str, ...], tuple[int, str] | None]:  # fmt: skip
    """A ground-truth trajectory, read once per process (until the file changes), arrays read-only,
    with the reader's notes (its LorisWarnings: poses skipped, stamps repeated) and where its stamps
    go back (:func:`backwards`; not for a bag: its messages are in the order they were received)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        gt = read_trajectory(path, fmt, stamps=times, topic=topic, tf=tf, repeated=repeated)
    for w in caught:  # another library's warning goes on as it came
        if not issubclass(w.category, LorisWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    for a in (gt.stamps, gt.positions, gt.quaternions, gt.lines):
        if a is not None:
            a.setflags(write=False)
    notes = tuple(dict.fromkeys(str(w.message) for w in caught if issubclass(w.category, LorisWarning)))
    return gt, notes, None if fmt == "bag" else backwards(gt)


def groundtruth_of(path: Path, fmt: str, times: Path | None = None, topic: str | None = None,
                   tf: str | None = None, repeated: str = "drop", notes: list[str] | None = None) -> Trajectory:  # fmt: skip
    """The ground truth of a pair or a manifest session (cached; read-only arrays); ``repeated``:
    the rule for poses of a repeated stamp (see :func:`lorisnb.io.readers.plain.read_trajectory`).
    The reader's notes (NaN poses skipped, repeated stamps, each naming the file and line) are
    added to ``notes`` on every call, as an estimate's are: the input's warnings say them. A text
    file whose stamps go back is refused (:func:`refuse_backwards`)."""
    stamp = _stamp(path) if path.is_file() else (0.0, 0)
    read = _read_groundtruth if stamp[1] < CACHED_BYTES else _read_groundtruth.__wrapped__  # a large one: not kept
    gt, said, back = read(path, fmt, stamp, times, topic, tf, repeated)
    if back is not None:
        raise ParseError(str(path), *back)
    if notes is not None:
        notes.extend(n for n in said if n not in notes)
    if len(gt) < 2:  # nothing to match an estimate to, or one instant: every later message would mislead
        raise ParseError(str(path), None, f"the ground truth has {'no pose' if not len(gt) else 'one pose'} (comments, "
                         "blank lines and skipped poses aside); expected at least two poses spanning the estimate's time")  # fmt: skip
    return gt


def openloris_groundtruth(path: Path, notes: list[str], spec: EvalSpec) -> ResultFile:
    """An OpenLORIS ground-truth file (every ``seq:`` block; cached, read-only arrays), as
    :func:`groundtruth_of` gives a plain one: its reader's notes added to ``notes``, a block whose
    stamps go back refused (:func:`refuse_backwards`); its repeated poses by :func:`gt_drops_repeated`."""
    gt = read_groundtruth_file(path, gt_drops_repeated(spec))
    for k, t in gt.sequences.items():
        refuse_backwards(path, t, f"seq {k}: " if len(gt.sequences) > 1 else "")
    notes.extend(n for n in gt.warnings if n not in notes)
    return gt


@lru_cache(maxsize=64)
def _moved(data: DataPaths, scene: str, drop_repeated: bool, frame: str, official: bool, stamp: tuple[float, int]
           ) -> dict[int, Trajectory]:  # fmt: skip
    """The scene's ground truth moved to a sensor frame, once per process (until the file changes)."""
    return moved_groundtruth(load_groundtruth(scene, data, drop_repeated), scene, frame, official)


def run_job(job: Job, progress: bool = False) -> tuple[str, FileErrors | Failure | PartialErrors | None]:
    """Evaluate one input: ``("ok", FileErrors)``, ``("failed" | "skipped", Failure)``,
    ``("filtered", None)`` when its scene is not wanted, or ``("partial", PartialErrors)``: a
    manifest job some of whose sessions failed alone. Never raises for bad input."""
    partial: list[Failure] = []
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", LorisWarning)  # kept in FileErrors.warnings
            if job.kind == "openloris":
                errors = _openloris(job, progress)
            elif job.kind == "pair":
                errors = _pair(job)
            else:
                got = _manifest(job)
                if isinstance(got, PartialErrors):
                    if got.errors is None:  # every session failed, each alone
                        return "partial", got
                    partial = got.failures
                    got = got.errors
                errors = got
        if errors is None:
            return "filtered", None
        o = job.spec.rpe_options()
        named = sequence_labels(job)
        for seq in errors.sequences:  # the RPE pairs of the spec, here (in a worker, when in parallel)
            i = seq.rpe(o["rpe_delta"], o["rpe_unit"], o["rpe_pairs"], o["rpe_all_pairs"], o["rpe_tolerance"])[0]
            # named as the pipeline's notes name the sequence (a manifest's session: its own estimate file)
            label = named.get(seq.seq) or f"{check_label(errors.path, errors.file)}, seq {seq.seq}"
            note = no_rpe_pair(label, len(i), seq.stamps, o["rpe_delta"], o["rpe_unit"])
            if note is not None and note not in errors.warnings:
                errors.warnings.append(note)
        scored = False
        with contextlib.suppress(LorisError):  # the spec's setting scored here too, with the statistics or without
            # (kept on each sequence: lorisnb.core.lifelong.scoring.sequence_scores), where the errors are, so that a
            # table at it is read in the process collecting the files; a setting the scores refuse is refused there
            score_rows(errors, job.spec.eps, job.spec.phi, job.spec.delta, job.spec.tau, stats=job.statistics, **o)
            scored = True
        if scored and not job.keep_poses:  # only that table is wanted: its scores travel, not each pose's errors
            errors.sequences = [scores_only(e) for e in errors.sequences]
        return ("partial", PartialErrors(errors, partial)) if partial else ("ok", errors)
    except DataNotFoundError as exc:
        return "skipped", Failure(job.path, str(exc), "not-public" if exc.scene in NOT_PUBLIC else "no-groundtruth")
    except LorisError as exc:  # said with the input it is about (an alignment's or an option's error names none)
        if isinstance(exc, ParseError) and job.kind != "manifest" and job.root is not None:
            # a file found in a folder, linked from outside it (/etc/passwd in a folder received): read, never quoted
            elsewhere = outside_results(job.path, job.root)  # (a link to nothing: its message quotes no content)
            if (
                elsewhere is not None
                and elsewhere.exists()
                and exc.path is not None
                and real_path(Path(exc.path)) == elsewhere
            ):
                exc = unquoted(exc, elsewhere, manifest=False)
        said = str(exc)
        if str(job.path) not in said and job.path.name not in said:
            said = f"{job.path}: {said}"
        return "failed", Failure(job.path, said, type(exc).__name__)


def sequence_labels(job: Job) -> dict[int, str]:
    """How the notes of a job name each of its sequences where the input's name alone does not say
    which it is (the pipeline's ``labels``): a manifest's sessions (:func:`session_labels`),
    and one of several topics of a bag, ``bags/run.bag (topic /odom), seq 1`` (the rows' algorithm is
    ``<algorithm>:<topic>``; a note naming the bag alone was said once for every topic). Empty: the
    input's name (and the sequence number) says it."""
    if job.kind == "manifest":
        return session_labels(job)
    src = job.source
    if job.kind == "pair" and src is not None and src.label_topic and src.topic:
        _, rel, _, _ = labels(job.path, job.root, job.trials_by)
        return {1: f"{check_label(job.path, rel)} (topic {src.topic}), seq 1"}
    return {}


def session_labels(job: Job) -> dict[int, str]:
    """How the notes of a manifest job name each of its sessions (by number, the pipeline's
    ``labels``; its errors name the file, as every route names that file's): the session's estimate
    file, as found in the algorithm's folder given (``res/orb/fr1_xyz.txt``), with the session's
    name and number, ``res/orb/fr1_xyz.txt (session 'fr1_xyz', seq 2)``. A note naming only the
    algorithm's folder left the user to find which file of it was meant."""
    m = job.manifest
    assert m is not None
    return {
        s.seq: f"{named_entry(job.path, s.estimate)} (session {s.name!r}, seq {s.seq})"
        for s in m.sessions
        if s.scene == job.scene
    }


def _read_result(job: Job, progress: bool = False) -> ResultFile:
    """The job's OpenLORIS result file, every ``seq:`` block (a progress bar for a big one)."""
    bar = None
    if progress and size_of(job.path) >= BIG_FILE_BYTES:
        from tqdm.auto import tqdm

        bar = tqdm(total=size_of(job.path), desc=f"reading {job.path.name}", unit="B", unit_scale=True, leave=False)
    try:
        return read_openloris(job.path, remove_repeated=job.spec.repeated == "drop", warn=False,
                              repair_stamps=job.spec.repair_stamps, progress=bar.update if bar is not None else None)  # fmt: skip
    except ParseError as exc:  # a file plainly in another format: say how to score it
        more = hint(job.path, "openloris")
        if not more:
            raise
        reason = exc.reason.replace(more, "")  # the reader's copy of the hint (with_hint): said once, complete
        more += "" if job.kind == "pair" else ", and give its ground truth with --gt FILE (evaluate_pairs in Python)"
        raise ParseError(exc.path, exc.line, f"{reason}{more}") from None
    finally:
        if bar is not None:
            bar.close()


def _openloris(job: Job, progress: bool) -> FileErrors | None:
    assert job.data is not None
    spec = job.spec
    algorithm, rel, suite, trial = labels(job.path, job.root, job.trials_by)
    declared = declared_scene(job.path)  # a scene without ground truth here (office's is not public): skipped
    # unread, with the DataNotFoundError reading the file in full would end in
    gt_path = job.data.groundtruth(declared) if declared is not None else None
    result = _read_result(job, progress)  # the estimate's repeated poses: by the spec's rule
    if job.scenes is not None and result.scene not in job.scenes:
        return None
    if gt_path is None or declared != result.scene:  # the scene's ground truth (load_groundtruth's file)
        gt_path = job.data.groundtruth(result.scene)
    said: list[str] = []
    gt = openloris_groundtruth(gt_path, said, spec)
    result.warnings[:0] = [n for n in said if n not in result.warnings]  # the ground truth's notes first
    drop = gt_drops_repeated(spec)
    moved = _moved(job.data, result.scene, drop, result.frame, spec.official_interpolation, _stamp(gt_path))
    return compute_errors(
        result, gt, spec, algorithm=algorithm, file=rel, suite=suite, trial=trial, in_frame=moved,
        other_spans=partial(groundtruth_spans, job.data, drop), release=result.sequences.pop,
    )  # fmt: skip


def _pair(job: Job) -> FileErrors:
    src = job.source
    assert src is not None
    algorithm, rel, suite, trial = labels(job.path, job.root, job.trials_by)
    if job.root is None:  # a file given alone: its name says which estimate it is
        algorithm = job.path.stem
    if src.label_topic and src.topic:  # one of several topics: told apart from the others and from other algorithms'
        algorithm = f"{algorithm}:{src.topic}"  # bags, as evo_ape names each by its topic (orb:/odom, orb:/pose)
    if "openloris" in (src.fmt, src.gt_fmt):  # every seq: block with its own number, as the native route
        return _openloris_pair(job, algorithm, rel, suite, trial)
    rule = job.spec.repeated_for(src.fmt)
    notes: list[str] = []  # the ground truth's first, then the estimate's
    gt = groundtruth_of(src.groundtruth, src.gt_fmt, src.gt_times, src.gt_topic, src.gt_tf,
                        _gt_rule(job.spec, src.gt_fmt, job.spec.repeated_for(src.gt_fmt)), notes)  # fmt: skip
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        est = read_trajectory(job.path, src.fmt, stamps=src.est_times, topic=src.topic, tf=src.tf, repeated=rule,
                              repair_stamps=job.spec.repair_stamps)  # fmt: skip
    check_stamp_units(est, gt, str(job.path))  # seconds against pose indices or nanoseconds: an error
    span = window_spans({1: gt}, job.spec)
    gts = {1: gt}
    del gt  # held by gts alone: let go once matched
    return evaluate_sessions(
        gts, {1: est}, job.spec, path=job.path, algorithm=algorithm, file=rel, scene=src.scene, suite=suite,
        trial=trial, notes=notes + [str(w.message) for w in caught], groundtruth_spans=span,
        release_groundtruth=gts.pop, quaternions=FORMATS[src.fmt].quaternions, labels=sequence_labels(job) or None,
    )  # fmt: skip


NATIVE = "score the result file as OpenLORIS files are scored: lorisnb evaluate FILE --data DIR (evaluate in Python)"


def _openloris_pair(job: Job, algorithm: str, rel: str, suite: str, trial: int) -> FileErrors:
    """A pair with an OpenLORIS file on either side, scored as the native route scores it: every
    ``seq:`` block with its own number against the same-numbered block of an OpenLORIS ground
    truth moved to the estimate's declared frame (:func:`compute_errors`); a plain file on the
    other side only where one trajectory and one frame make the pairing certain, else refused."""
    src = job.source
    assert src is not None
    gt_notes: list[str] = []
    if src.fmt == src.gt_fmt == "openloris":
        result = _read_result(job)
        gt_file = openloris_groundtruth(src.groundtruth, gt_notes, job.spec)
        result.warnings[:0] = [n for n in gt_notes if n not in result.warnings]  # the ground truth's notes first
        return compute_errors(result, gt_file, job.spec, algorithm=algorithm, file=rel, suite=suite, trial=trial,
                              release=result.sequences.pop)  # fmt: skip
    if src.fmt == "openloris":  # against a plain trajectory: one block, in the ground truth's frame
        result = _read_result(job)
        seqs = sorted(result.sequences)
        if len(seqs) != 1:
            raise ValidationError(
                f"{job.path}: {len(seqs)} sequences (seq: {', '.join(map(str, seqs))}) against one {src.gt_fmt} "
                f"ground-truth trajectory ({src.groundtruth}), which has no seq: blocks to pair them with; give the "
                f"OpenLORIS ground truth (--gt-format openloris), or {NATIVE}"
            )
        if result.frame != "base_link":
            raise ValidationError(
                f"{job.path}: poses of frame {result.frame} (its frame: header); a {src.gt_fmt} ground truth names "
                f"no frame, so it cannot be moved there: give the OpenLORIS ground truth (--gt-format openloris; moved "
                f"with the robot's extrinsics), or {NATIVE}; a ground truth already in {result.frame}: write the "
                f"estimate in {src.gt_fmt} too"
            )
        est = {seqs[0]: result.sequences[seqs[0]]}
        gt = groundtruth_of(src.groundtruth, src.gt_fmt, src.gt_times, src.gt_topic, src.gt_tf,
                            _gt_rule(job.spec, src.gt_fmt, job.spec.repeated), gt_notes)  # fmt: skip
        notes = gt_notes + [n for n in result.warnings if n not in gt_notes]
        gts = {seqs[0]: gt}
    else:  # a plain estimate against an OpenLORIS ground truth: one block
        gt_file = openloris_groundtruth(src.groundtruth, gt_notes, job.spec)
        seqs = sorted(gt_file.sequences)
        if len(seqs) != 1:
            raise ValidationError(
                f"{job.path}: one {src.fmt} trajectory against {len(seqs)} ground-truth sequences (seq: "
                f"{', '.join(map(str, seqs))} in {src.groundtruth}); a {src.fmt} file names no sequence: write the "
                f"estimate as an OpenLORIS result file (scene:, frame: and seq: N blocks) and {NATIVE}, or give one "
                "sequence's ground truth"
            )
        gts = dict(gt_file.sequences)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", LorisWarning)
            est = {seqs[0]: read_trajectory(job.path, src.fmt, stamps=src.est_times, topic=src.topic, tf=src.tf,
                                            repeated=job.spec.repeated)}  # fmt: skip
        notes = gt_notes + [str(w.message) for w in caught]
    check_stamp_units(est[seqs[0]], gts[seqs[0]], str(job.path))
    return evaluate_sessions(
        gts, est, job.spec, path=job.path, algorithm=algorithm, file=rel, scene=src.scene, suite=suite, trial=trial,
        notes=notes, groundtruth_spans=window_spans(gts, job.spec), release_groundtruth=gts.pop,
        quaternions=FORMATS[src.fmt].quaternions,
    )  # fmt: skip


def _manifest(job: Job) -> FileErrors | PartialErrors:
    m = job.manifest
    assert m is not None
    sessions = [s for s in m.sessions if s.scene == job.scene]
    gts: dict[int, Trajectory] = {}
    notes: list[str] = []  # the ground truths' first, then the estimates'
    for s in sessions:  # a handful of sessions
        if not s.groundtruth.exists():
            raise ParseError(
                s.groundtruth, None, f"ground truth of session {s.name!r} not found ({m.path}: root and groundtruth)"
            )
        try:
            gts[s.seq] = groundtruth_of(s.groundtruth, s.groundtruth_format, s.groundtruth_times, m.groundtruth_topic,
                                        m.groundtruth_tf, _gt_rule(job.spec, s.groundtruth_format, job.spec.repeated),
                                        notes)  # fmt: skip
        except ParseError as exc:  # a bag's choice: the manifest's keys, not the command line's options
            if s.groundtruth_format != "bag":
                raise
            raise ParseError(exc.path, exc.line, manifest_terms(exc.reason, "groundtruth_topic", "groundtruth_tf",
                                                                str(m.path))) from None  # fmt: skip
    ests: dict[int, Trajectory] = {}
    found = {s.seq: named_entry(job.path, s.estimate) for s in sessions}  # NFC or NFD, as the file system has it
    failed: list[Failure] = []  # sessions whose estimate cannot be read: each fails alone, the others are scored
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        for s in sessions:
            path = found[s.seq]
            if path.exists():
                try:
                    ests[s.seq] = _session_estimate(job, s, path, gts[s.seq])
                except DataNotFoundError:
                    raise
                except LorisError as exc:
                    said = str(exc)
                    if str(path) not in said and path.name not in said:
                        said = f"{path}: {said}"
                    failed.append(Failure(path, said, type(exc).__name__))
    notes += [str(w.message) for w in caught]
    bad = {s.seq for s in sessions if found[s.seq] in {f.path for f in failed}}
    out = _manifest_rows(job, sessions, gts, ests, notes, bad)
    if not failed:
        assert out is not None
        return out
    return PartialErrors(out, failed)


@dataclass(frozen=True)
class PartialErrors:
    """A manifest job some of whose sessions failed (an estimate that cannot be read): the errors of
    the others (None when every session failed) and a Failure for each failed session."""

    errors: FileErrors | None
    failures: list[Failure]


def _session_estimate(job: Job, s: Session, path: Path, gt: Trajectory) -> Trajectory:
    """One manifest session's estimate, read (its times file with it) and its stamps' unit checked
    against its ground truth's; an error names the manifest's keys, not the command line's options."""
    m = job.manifest
    assert m is not None
    elsewhere = None if m.outside else outside_results(path, job.root or job.path)
    try:
        est = read_trajectory(path, m.estimate_format, stamps=s.estimate_times, topic=m.estimate_topic,
                              tf=m.estimate_tf, repeated=job.spec.repeated, repair_stamps=job.spec.repair_stamps)  # fmt: skip
    except ParseError as exc:  # a link out of the results folder: read, never quoted
        if m.estimate_format == "bag":  # a bag's choice: the manifest's keys, not the command line's options
            exc = ParseError(
                exc.path, exc.line, manifest_terms(exc.reason, "estimate_topic", "estimate_tf", str(m.path))
            )
        if elsewhere is None:
            raise exc from None
        raise unquoted(exc, elsewhere) from None
    where = f"in its [[session]] table of {m.path}"
    check_stamp_units(est, gt, str(path), names={  # the manifest's keys, not the command line's options
        "est_times": f"estimate_times = 'FILE' {where}", "gt_times": f"groundtruth_times = 'FILE' {where}",
        "both_times": f"estimate_times and groundtruth_times {where}", "format": f"estimate_format = 'euroc' in {m.path}",
        "gt_format": f"groundtruth_format = 'euroc' in {m.path}",
    })  # fmt: skip
    return est


def _manifest_rows(
    job: Job, sessions: list[Session], gts: dict[int, Trajectory], ests: dict[int, Trajectory],
    notes: list[str], failed: set[int],
) -> FileErrors | None:  # fmt: skip
    """The rows of a manifest job: the sessions with an estimate scored, each other one without its
    file scored as missing output, as the paper scores it; one whose file failed (``failed``, by its
    number) has no row (its Failure says it; the scene's CR and coverage still count its time).
    None: every session failed."""
    m = job.manifest
    assert m is not None
    algorithm, _, suite, trial = labels(job.path / "x", job.root, job.trials_by)
    spans = window_spans(gts, job.spec)
    errors = None
    if ests:
        errors = evaluate_sessions(
            gts, ests, job.spec, path=job.path, algorithm=algorithm, scene=job.scene, suite=suite, trial=trial,
            notes=notes, groundtruth_spans=spans, sources={s.seq: str(named_entry(job.path, s.estimate)) for s in sessions},
            labels=session_labels(job),
            quaternions=FORMATS[m.estimate_format].quaternions,
        )  # fmt: skip
    absent = [s for s in sessions if s.seq not in ests and s.seq not in failed]
    if not absent:
        return errors
    # a declared session without its estimate: a row scored as the paper scores missing output, never dropped
    note = missing_note(job.path, algorithm, [(s.name, s.estimate) for s in absent], [s.estimate for s in sessions])
    out = with_missing(
        errors, gts, [s.seq for s in absent], path=job.path, algorithm=algorithm, scene=job.scene, suite=suite,
        trial=trial, lifelong=job.spec.lifelong_for(len(sessions)), note=note,
    )  # fmt: skip
    out.groundtruth_spans = spans
    if errors is None:  # no estimate at all: the ground truths' notes still said
        out.warnings[:0] = [n for n in notes if n not in out.warnings]
    out.sequences = [  # a missing session's duration is its ground truth's time as the spec evaluates it
        replace(e, gt_start=spans[e.seq][0], gt_end=spans[e.seq][1]) if e.matched == 0 and e.seq in spans else e
        for e in out.sequences
    ]
    return out
