"""Scoring: each submission in a process of its own, forked from a server that has lorisnb's
evaluation already imported (``forkserver``), with a CPU-time and a memory limit
(``resource.setrlimit``) and a wall-clock deadline. The process scores the uploaded files as
``lorisnb evaluate`` scores them against the hidden ground truth: OpenLORIS result files with
:func:`lorisnb.tools.evaluation.runner.evaluate`, TUM and EuRoC files each against its sequence's
ground truth with :func:`lorisnb.tools.evaluation.runner.evaluate_pairs` (the upload's plan,
:func:`.uploads.plan`). It scores each set of sequences the submission's phase shows as the phases
close (:meth:`.config.Challenge.views`) on those sequences alone (the others stripped from the
files first: no number shown comes from ground truth still hidden), draws the paper's timeline
figure of each into a folder of its claim's (``claims/<claim>``), and writes its outcome to a JSON
file named for its claim (two scorings of one submission never write one file; each ends with its
server, :func:`die_with_parent`); the
server commits that outcome to the database (:func:`.store.finish`), and shows of it only what
is visible (:mod:`.board`).

:class:`Scorer` is the server's loop over the persisted queue (:mod:`.store`): it puts back what a
killed server left half-scored, runs up to ``workers`` processes at a time and commits each
outcome once. With ``[challenge] scheduler`` each scoring is a task of that Dask cluster
(:func:`score_on_worker`: a fresh process on the worker, under the same limits).
"""

from __future__ import annotations

import fcntl
import json
import math
import multiprocessing
import os
import pickle
import re
import resource
import shutil
import signal
import subprocess
import sys
import threading
import time
import warnings
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from sqlalchemy import Engine
from sqlalchemy.engine import make_url

from lorisnb.core.lifelong.aggregate import aggregate_scenes, spans_table
from lorisnb.core.pipeline.model import FileErrors, ResultFile
from lorisnb.core.pipeline.plausibility import SEQ_CHECK, SEQ_QUESTION
from lorisnb.core.spec.evalspec import EvalSpec
from lorisnb.core.stats.trials import check_duplicates, names_a_trial
from lorisnb.core.trajectory.frames import SCENES
from lorisnb.errors import FailedInputsWarning, LorisError, LorisWarning, ParseError, ValidationError
from lorisnb.io.datasets.paths import DataPaths, load_groundtruth, scene_durations, scene_spans
from lorisnb.io.readers import openloris as openloris_reader
from lorisnb.io.readers.openloris import FILE_KEYS, parse_headers, read_lines
from lorisnb.io.writers import write_openloris
from lorisnb.tools.challenge import store
from lorisnb.tools.challenge.board import nothing_scored, scored_nothing
from lorisnb.tools.challenge.config import Challenge, sequences_of
from lorisnb.tools.challenge.uploads import PLAN
from lorisnb.tools.evaluation.jobs import GT_DROP
from lorisnb.tools.evaluation.result import Evaluation, said_notes
from lorisnb.tools.evaluation.runner import evaluate, evaluate_pairs
from lorisnb.tools.evaluation.status import skipped_only

#: A sequence whose matched poses all lie this close to the ground truth, after the alignment
#: (positions: metres; orientations: degrees), is the ground truth copied, not an estimate: no
#: tracker is within a tenth of a millimetre, or a thousandth of a degree, at every pose (the
#: ground truth uploaded as it is gives 0 m and 6e-15 deg). A copy changed by more is not told.
COPY_ATE_M, COPY_AOE_DEG, COPY_MIN_POSES = 1e-4, 1e-3, 10

FILES = "files"  # a submission's folder: files/ (as uploaded), plan.json, result-<claim>.json, claims/<claim>/
CLAIMS = "claims"  # a submission's folder: each scoring's own work (pairs/, strip/, timeline-<k>.png) under its claim
GROUNDTRUTH = "groundtruth"  # the server folder's one-sequence ground truths (sequence_groundtruth)
LOCK = "scorer.lock"  # in the server's folder: held by the one scorer of its queue (Scorer._take_queue)


def _plain(value: Any) -> Any:
    """A table value as JSON holds it (numpy scalars as Python ones; NaN and infinities as None)."""
    if hasattr(value, "item"):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value if isinstance(value, (int, float, str, bool)) or value is None else str(value)


def scrub(text: str, folder: Path, data: DataPaths, groundtruth: Path | None = None) -> str:
    """A message with the server's paths taken out: the upload's folder (its files by name, also
    as linked for scoring, :func:`_pair_folder`) and the hidden ground truth's folders (the data
    root and ``groundtruth``, the server's one-sequence files: never named to a team)."""
    sep = re.escape(os.sep)
    pairs = f"(?:{CLAIMS}{sep}\\w+{sep})?(?:pairs|strip){sep}\\d+{sep}"
    text = re.sub(re.escape(f"{folder.parent}{os.sep}") + f"({pairs})?" + re.escape(f"{FILES}{os.sep}"), "", text)
    text = text.replace(f"{folder}{os.sep}", "").replace(str(folder.parent), "the upload")
    for root in [data.root.resolve(), data.root] + ([groundtruth.resolve(), groundtruth] if groundtruth else []):
        text = text.replace(str(root), "<ground truth>")
    return text


def _unnamed(error: str, name: str) -> str:
    """A file's error without its own name in front (the page and ``lorisnb submit`` put it there)."""
    for lead in (f"{name}: ", f"{name}, "):
        if error.startswith(lead):
            return error[len(lead) :]
    return error


def sequence_groundtruth(data: DataPaths, scene: str, seq: int, folder: Path) -> Path:
    """The ground truth of one sequence as an OpenLORIS file of its one ``seq:`` block, written
    once into ``folder`` (the server's, never an upload's; named for the scene file's time and
    size, so a changed ground truth is written anew): what a TUM or EuRoC file of that sequence is
    scored against, as ``lorisnb evaluate FILE --format tum --gt THIS --gt-format openloris`` scores it."""
    src = data.groundtruth(scene)
    st = src.stat()
    out = folder / f"gt_{scene}_1-seq{seq}-{st.st_mtime_ns}-{st.st_size}.txt"
    if not out.is_file():
        gt = load_groundtruth(scene, data, GT_DROP)
        if seq not in gt.sequences:
            raise LorisError(f"the ground truth of {scene} has no sequence {seq}; tell the organizers")
        write_openloris(out, {seq: gt.sequences[seq]}, scene, frame=gt.frame, overwrite=True)  # atomic
    return out


def _pair_folder(files: Path, work: Path, k: int, name: str) -> Path:
    """A folder named ``files`` in ``work`` holding only the upload's file ``name`` (of ``files``; a
    hard link): scored from it, a plain file's rows have the algorithm ``files`` as an OpenLORIS
    file's on the server (so ``scale = "auto"`` is the challenge's choice, never chosen by a file's name)."""
    folder = work / "pairs" / str(k) / FILES
    folder.mkdir(parents=True, exist_ok=True)
    dest = folder / name
    if not dest.exists():
        try:
            os.link(files / name, dest)
        except OSError:
            shutil.copyfile(files / name, dest)
    return folder


def _attributed(f: FileErrors, text: str) -> list[tuple[str, int]]:
    """The sequences a file's note is about: those of its sequences it names (``seq 2``), else all."""
    seqs = [e.seq for e in f.sequences]
    named = [q for q in map(int, re.findall(r"\bseq:? ?(\d+)", text)) if q in seqs]
    return [(f.scene, q) for q in (named or seqs)]


def groundtruth_copies(errors: Iterable[FileErrors]) -> list[str]:
    """Each sequence of ``errors`` (at least :data:`COPY_MIN_POSES` matched) whose positions, or
    orientations, equal the ground truth's at every matched pose (within :data:`COPY_ATE_M` and
    :data:`COPY_AOE_DEG` after the alignment), said as ``FILE: cafe-1's positions ...`` (the
    organizer's words: a team is told it as :func:`.board.copies_as_shown` says, at the time it reads it)."""
    out = []
    for f in errors:
        for e in f.sequences:
            if e.matched < COPY_MIN_POSES:
                continue
            pos, rot = bool(np.all(e.ate <= COPY_ATE_M)), bool(np.all(e.aoe <= COPY_AOE_DEG))
            if pos or rot:
                what = "positions and orientations" if pos and rot else "positions" if pos else "orientations"
                within = f"{COPY_ATE_M * 1000:g} mm" if pos else f"{COPY_AOE_DEG:g} deg"
                out.append(f"{Path(f.path).name}: {f.scene}-{e.seq}'s {what} are the ground truth's (all "
                           f"{e.matched} matched poses within {within} of it after the alignment)")  # fmt: skip
    return out


def _one_file_each(errors: list[FileErrors]) -> None:
    """Two files of an upload holding one sequence and trial are refused
    (:func:`~lorisnb.core.stats.trials.check_duplicates`), in the server's words: the files as
    uploaded and their sequence (every file of an upload is the team's one algorithm: not named),
    and the names the server reads trials from (``cafe-1-1_trial1.txt``: a TUM or EuRoC file's
    name names its sequence too; folders ``run_1/`` of a .zip)."""
    keys = [(Path(f.path).name, ("", "", f.scene, f.trial), tuple(e.seq for e in f.sequences)) for f in errors]
    try:
        check_duplicates(keys)
    except ValidationError:
        seen: dict[tuple[str, int, int], str] = {}
        for name, (_, _, scene, trial), seqs in keys:
            for q in seqs:
                other = seen.setdefault((scene, trial, q), name)
                if other != name:
                    numbered = [n for n in (other, name) if names_a_trial(n)]
                    if len(numbered) == 2:  # home-1-2_trial0.txt and home-1-2_trial00.txt
                        why = f"both hold {scene}-{q} trial {trial}: they carry the same trial number"
                    elif numbered:  # home-1-2.txt and home-1-2_trial0.txt
                        unnamed = other if numbered[0] == name else name
                        why = (f"both hold {scene}-{q} trial {trial}: {unnamed} names no trial, which is read as "
                               f"trial 0, and {numbered[0]} carries trial {trial}")  # fmt: skip
                    else:
                        held = f"{scene}-{q}{f' trial {trial}' if trial else ''}"
                        why = f"both hold {held}, with no trial number to tell them apart"
                    raise ValidationError(
                        f"{other} and {name} {why}; name each file for its trial ({scene}-1-{q}_trial1.txt, "
                        f"{scene}-1-{q}_trial2.txt, ...; or put them in folders run_1/, run_2/, ... of one .zip), "
                        f"or upload them in separate submissions"
                    ) from None
        raise


#: A note said where numpy warned while scoring a file (an overflow, an invalid value): its own words
#: ('overflow encountered in reduce') name nothing a team can act on.
NOT_COMPUTED = ("a computation on its values overflowed or had no value (numbers too large for floating point, "
                "or not numbers): its errors may be infinite or missing; check its values and their units "
                "(metres, seconds)")  # fmt: skip
#: The advice on which sequence a file is (:func:`lorisnb.core.pipeline.plausibility.time_overlap`),
#: and what a TUM or EuRoC file, whose name names its sequence, is told instead.
SEQ_ADVICE = ((SEQ_QUESTION, "is the sequence its name names ({seq}) the wrong one?"),
              (SEQ_CHECK, "check that its name names its sequence (it names {seq})"))  # fmt: skip


def plain_advice(text: str, name: str, plain: Mapping[str, Mapping[str, Any]]) -> str:
    """A message about the file ``name`` in words of its format: a TUM or EuRoC file (one of
    ``plain``) has no ``seq:`` line, its name names its sequence: advice to check the ``seq:``
    number is said of its name."""
    info = plain.get(name)
    if info is None:
        return text
    seq = f"{info['scene']}-1-{info['seq']}"
    for old, new in SEQ_ADVICE:
        text = text.replace(old, new.format(seq=seq))
    return text


class _Every:
    """The view of every sequence (``score_folder`` without ``views``): nothing is left out."""

    def __contains__(self, item: object) -> bool:
        return True


#: Header keys the reader takes from any line of a file (a ``scene:`` line after ``seq: 1`` names
#: the whole file's scene): kept, in place, where the block holding them is stripped.
@dataclass(frozen=True)
class Blocks:
    """An OpenLORIS result file's layout as :func:`~lorisnb.io.readers.openloris.read_openloris`
    reads it (:func:`read_blocks`): its scene, each ``seq: N`` line (1-based line, N) in file
    order, and the lines kept whatever is stripped (:data:`~lorisnb.io.readers.openloris.FILE_KEYS`)."""

    scene: str
    seqs: tuple[tuple[int, int], ...]
    kept: frozenset[int]

    @property
    def numbers(self) -> list[int]:
        return [q for _, q in self.seqs]


def read_blocks(path: Path) -> Blocks:
    """The :class:`Blocks` of the OpenLORIS result file ``path``, read as the reader reads it: its
    lines by :func:`~lorisnb.io.readers.openloris.read_lines` (a UTF-8 BOM dropped), their
    ``key: value`` and ``seq: N`` lines by :func:`~lorisnb.io.readers.openloris.parse_headers` (a key
    in any case and spacing, ``seq:`` read by Python's ``int``: any Unicode digits and spaces), its
    scene by :attr:`ResultFile.scene`. A :class:`ParseError` where the reader refuses the file (a
    malformed line, a ``seq:`` line without a whole number, no or an unknown scene): such a file is
    never scored, whole or in part."""
    heads = parse_headers(str(path), read_lines(path).specials)
    scene = ResultFile(path=path, header=heads.header, header_lines=heads.header_lines, sequences={}).scene
    kept = frozenset(line for line, key in heads.key_lines if key in FILE_KEYS)
    return Blocks(scene, tuple(heads.seq_at), kept)


def read_result(path: Path, spec: EvalSpec | None = None) -> tuple[ResultFile, Blocks]:
    """The OpenLORIS result file ``path`` read whole as the scorer reads it, under the rules of
    ``spec`` (default: lorisnb's): every line by
    :func:`~lorisnb.io.readers.openloris.read_openloris`, the header values the evaluation takes
    from it (its ``scene:`` and ``frame:``, :attr:`ResultFile.scene` and :attr:`ResultFile.frame`:
    none, or one the reader does not know, is refused), at least one ``seq: N`` block, and its
    :class:`Blocks` (:func:`read_blocks`). The one reading of an uploaded file: the upload's check
    (:func:`.uploads.read_upload`) and :func:`score_folder` both call it, so a file the scorer would
    refuse is refused when it is uploaded, in the same words. A :class:`ParseError` names the line."""
    drop = spec is None or spec.repeated == "drop"
    repair = bool(spec is not None and spec.repair_stamps)
    # called through its module: one reader, whoever stands in for it (a test counting its readings)
    result = openloris_reader.read_openloris(path, remove_repeated=drop, warn=False, repair_stamps=repair)
    blocks = read_blocks(path)
    _ = result.frame  # the scene is read by read_blocks; the frame is the evaluation's next question
    if not result.sequences:  # compute_errors' refusal, in its words: said at upload, not at scoring
        raise ParseError(path, None, "no 'seq: N' block; expected at least one sequence")
    return result, blocks


def seq_blocks(path: Path) -> list[int] | None:
    """The numbers of a result file's ``seq: N`` lines in order, as the reader reads them
    (:func:`read_blocks`); None where the reader refuses the file."""
    try:
        return read_blocks(path).numbers
    except (LorisError, OSError):
        return None


def strip_sequences(src: Path, dest: Path, keep: Iterable[int], blocks: Blocks | None = None) -> None:
    """Copy the OpenLORIS result file ``src`` to ``dest`` without the ``seq: N`` blocks whose N is
    not in ``keep``, as the reader finds them (``blocks``, default :func:`read_blocks`): each line
    of such a block is left blank (the reader skips blank lines; the others keep their line
    numbers), but for its ``scene:`` and ``frame:`` lines, which the reader takes for the whole
    file; the header and the kept blocks byte for byte. What a phase scores of a file, so that
    nothing of it, the lifelong alignment included, comes from a sequence the phase hides."""
    found = blocks if blocks is not None else read_blocks(src)
    kept = set(keep)
    lines = src.read_bytes().split(b"\n")
    starts = [line for line, _ in found.seqs] + [len(lines) + 1]
    for (first, seq), end in zip(found.seqs, starts[1:], strict=True):
        if seq not in kept:
            for line in range(first, min(end, len(lines) + 1)):
                if line not in found.kept:
                    lines[line - 1] = b""
    dest.parent.mkdir(parents=True, exist_ok=True)
    dest.write_bytes(b"\n".join(lines))


def score_folder(folder: Path, data: DataPaths, spec: EvalSpec, figures: Path | None = None, *,
                 plain: Mapping[str, Mapping[str, Any]] | None = None, groundtruth: Path | None = None,
                 views: Sequence[Iterable[tuple[str, int]]] | None = None, work: Path | None = None,
                 ) -> dict[str, Any]:  # fmt: skip
    """Score the result files in ``folder`` as ``lorisnb evaluate`` does: OpenLORIS result files
    with :func:`~lorisnb.tools.evaluation.runner.evaluate`, and each file of ``plain`` (name ->
    format, scene, seq: :func:`.uploads.plan`) with
    :func:`~lorisnb.tools.evaluation.runner.evaluate_pairs` against its sequence's ground truth
    (:func:`sequence_groundtruth`, in ``groundtruth``, default beside the upload's folder).

    ``views`` are the sets of sequences the submission's scores are shown for, in the order they
    are shown (:meth:`.config.Challenge.views` of its phase; None: one view of every sequence).
    Each view is scored on its own sequences alone: an OpenLORIS file is stripped of the other
    ``seq:`` blocks (:func:`strip_sequences`) before it is evaluated, so that no number of a
    sequence comes from ground truth not shown with it (a lifelong file is aligned on its first
    sequence: a hidden one would move the shown ones' errors). A sequence's row is the one of
    the first view holding it; a sequence in no view is not scored (said, per file).

    The outcome: per-sequence rows (every column of :meth:`Evaluation.sequence_rows`), each file
    that failed or was not scored with its reason (paths scrubbed, :func:`scrub`), the notes with
    the sequences each is about, and a timeline figure in ``figures`` of each view the submission
    has output in (``timeline-<k>.png``), drawn from that view's scores.

    ``work`` is the scoring's own folder (default beside ``folder``): the files it writes to score
    (the stripped copies, a plain file's folder) go there, so that two scorings of one upload
    never write one file (:class:`Scorer` gives each claim its own, ``claims/<claim>``)."""
    plain = dict(plain or {})
    work = work if work is not None else folder.parent
    gt_folder = groundtruth if groundtruth is not None else folder.parent / GROUNDTRUTH
    native = sorted(p for p in folder.iterdir() if p.is_file() and p.name not in plain)
    every: list[Any] = [_Every()] if views is None else [frozenset((s, int(q)) for s, q in v) for v in views]
    evaluated: dict[tuple[str, frozenset[int] | None], Evaluation | None] = {}
    # what each evaluation scored (its numbers come from those sequences' ground truth alone) and
    # the notes it raised: a note or a failure is shown with every sequence of its evaluation
    scope: dict[tuple[str, frozenset[int] | None], frozenset[tuple[str, int]]] = {}
    raised: dict[tuple[str, frozenset[int] | None], list[str]] = {}
    problems: list[tuple[str, str, str, frozenset[tuple[str, int]]]] = []  # status, file, error, about
    shapes: dict[str, Blocks | None] = {}
    for p in native:  # each file read whole by the reader first: one it refuses is never scored, whole or in part
        try:
            shapes[p.name] = read_result(p, spec)[1]
        except LorisError as exc:
            shapes[p.name] = None
            problems.append(("failed", p.name, str(exc), frozenset()))
        except OSError as exc:
            shapes[p.name] = None
            problems.append(("failed", p.name, f"cannot be read ({exc.strerror})", frozenset()))

    def run(key: tuple[str, frozenset[int] | None], seqs: frozenset[tuple[str, int]], go: Any) -> None:
        """One evaluation of ``seqs`` (its notes kept with them; other spans told: theirs alone)."""
        scope[key] = seqs
        with warnings.catch_warnings(record=True) as mine:
            warnings.simplefilter("always", LorisWarning)
            try:
                evaluated[key] = go()
            finally:
                # a FailedInputsWarning speaks to Python callers: each failure is told as one here; a
                # warning not lorisnb's (numpy's 'overflow encountered in reduce') is said in its words
                raised[key] = [str(w.message) for w in mine if issubclass(w.category, LorisWarning)
                               and not issubclass(w.category, FailedInputsWarning)]  # fmt: skip
                if any(not issubclass(w.category, LorisWarning) for w in mine):
                    raised[key].append(f"{key[0]}: {NOT_COMPUTED}")

    def in_view(view: Any) -> list[FileErrors]:
        """Every file's errors as scored on the sequences of ``view`` alone."""
        out: list[FileErrors] = []
        for p in native:
            shape = shapes[p.name]
            if shape is None:
                continue
            blocks = frozenset(shape.numbers)  # none: no pose either (a pose before any seq: is refused)
            kept = frozenset(q for q in blocks if (shape.scene, q) in view)
            if blocks and not kept:
                continue
            key = (p.name, None if kept == blocks else kept)
            if key not in evaluated:
                src = p
                if key[1] is not None:
                    src = work / "strip" / str(len(evaluated)) / FILES / p.name
                    strip_sequences(p, src, key[1], shape)
                seqs = frozenset((shape.scene, q) for q in kept)
                shown = replace(data, shown=seqs)  # the time-overlap check names these spans alone
                run(
                    key,
                    seqs,
                    lambda src=src, shown=shown: evaluate([src], spec, data_root=shown, jobs=1, progress=False),
                )
            one = evaluated[key]
            if one is not None:
                out += [f for f in one.errors if all((f.scene, e.seq) in view for e in f.sequences)]
        for k, (name, info) in enumerate(sorted(plain.items())):
            if (str(info["scene"]), int(info["seq"])) not in view:
                continue
            if (name, None) not in evaluated:
                seq = frozenset({(str(info["scene"]), int(info["seq"]))})
                try:
                    gt = sequence_groundtruth(data, str(info["scene"]), int(info["seq"]), gt_folder)
                    run((name, None), seq, lambda k=k, name=name, info=info, gt=gt: evaluate_pairs(
                        [_pair_folder(folder, work, k, name)], gt, spec, fmt=str(info["format"]), gt_fmt="openloris",
                        scene=str(info["scene"]), jobs=1, progress=False))  # fmt: skip
                except LorisError as exc:  # an option of the challenge's spec this format cannot take
                    evaluated[(name, None)] = None
                    scope[(name, None)] = seq
                    problems.append(("failed", name, str(exc), seq))
            one = evaluated[(name, None)]
            if one is not None:
                out += one.errors
        return out

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        by_view = [(view, in_view(view)) for view in every]
        taken: set[tuple[str, str, int]] = set()
        errors: list[FileErrors] = []
        for _view, found in by_view:  # a sequence's row: the first view's that holds it
            for f in found:
                name = Path(f.path).name
                seqs = [e for e in f.sequences if (name, f.scene, e.seq) not in taken]
                taken.update((name, f.scene, e.seq) for e in seqs)
                if seqs or not f.sequences:
                    errors.append(f if len(seqs) == len(f.sequences) else replace(f, sequences=seqs))
        _one_file_each(errors)
        copies = list(dict.fromkeys(groundtruth_copies(errors)))
        if copies:  # the whole submission: it is not ranked, and says why
            listed = "; ".join(copies)
            raise ValidationError(f"refused, not ranked: this upload holds the ground truth itself, not an estimate "
                                  f"({listed}). Upload your system's output")  # fmt: skip
        ev = Evaluation(errors, [], None, [], data, spec=spec, kind="openloris")
        rows = ev.sequence_rows()
    everything = frozenset().union(*scope.values())  # a note of no one evaluation: shown once all is
    for key, one in evaluated.items():
        if one is None:
            continue
        within = scope[key]
        said = [("failed", Path(f.path).name, f.error, within) for f in one.failures]
        said += [("not scored", Path(f.path).name, f.error, within) for f in one.unscored if f.kind != "nothing"]
        said += [("skipped", Path(f.path).name, f.error, within) for f in skipped_only(one)]
        if not said and not any(f.sequences for f in one.errors):  # each evaluation is of one file, key[0]:
            # nothing of it scored and no reason named for it ("nothing was evaluated", said for no
            # file) is a failure of that file, never a silent empty scoring
            why = next((f.error for f in one.unscored if f.kind == "nothing"), "nothing of it was scored")
            said.append(("failed", key[0], why, within))
        problems += said
    for p in native:  # a file none of whose sequences is in a view: never evaluated
        shape = shapes[p.name]
        if not any(name == p.name for name, _ in evaluated) and shape is not None and shape.seqs:
            problems.append(("not scored", p.name, f"{shape.scene} seq {', '.join(map(str, sorted(set(shape.numbers))))}: "
                             "in no phase this submission's scores are shown in; not scored", frozenset()))  # fmt: skip
    problems = list(dict.fromkeys(problems))
    failures = [dict(file=name, status=status, sequences=sorted(about),
                     error=_unnamed(scrub(plain_advice(error, name, plain), folder, data, gt_folder), name))
                for status, name, error, about in problems]  # fmt: skip
    # each note with the sequences it is about (a file's, or the seq N it names) and every
    # sequence of the evaluation that raised it: a number in it may come from any of them
    notes: dict[str, set[frozenset[tuple[str, int]]]] = {}
    for key, one in evaluated.items():
        if one is None:
            continue
        texts: dict[str, set[tuple[str, int]]] = {t: set() for t in raised.get(key, [])}
        for f in one.errors:
            for w in f.warnings:
                texts.setdefault(w, set()).update(_attributed(f, w))
        counted = set(said_notes(one.errors)) - {w for f in one.errors for w in f.warnings}
        for text, named in texts.items():
            if "could not be evaluated" not in text and text not in counted:
                notes.setdefault(plain_advice(text, key[0], plain), set()).add(frozenset(named | scope[key]))
    inside = {t for ts in raised.values() for t in ts}
    for text in dict.fromkeys(str(w.message) for w in caught if issubclass(w.category, LorisWarning)
                              and not issubclass(w.category, FailedInputsWarning)):  # fmt: skip
        if text not in inside and "could not be evaluated" not in text:
            notes.setdefault(text, set()).add(everything)
    out: dict[str, Any] = dict(
        rows=[{k: _plain(v) for k, v in r.items() if k != "spec"} | {"file": Path(str(r["file"])).name} for r in rows],
        failures=failures, conventions=ev.describe(), figures=[],
        notes=[dict(text=scrub(t, folder, data, gt_folder), sequences=sorted(q)) for t, qs in notes.items()
               for q in sorted(qs, key=len)],
    )  # fmt: skip
    if figures is not None and errors:
        _draw(out, by_view, views is None, data, spec, figures, folder, gt_folder)
    return out


def _draw(out: dict[str, Any], by_view: list[tuple[Any, list[FileErrors]]], whole: bool, data: DataPaths,
          spec: EvalSpec, folder: Path, upload: Path, groundtruth: Path) -> None:  # fmt: skip
    """The timeline figure of each view (a set of sequences) the submission has output in, drawn
    from that view's scores alone: their errors, their ground-truth durations, the scene's CR over
    them (``whole``: one view of every sequence)."""
    import matplotlib

    matplotlib.use("Agg")
    from lorisnb.tools.figures.plotting import plot_timeline

    for k, (view, found) in enumerate(by_view):
        scored = {(f.scene, e.seq) for f in found for e in f.sequences}
        if not scored:
            continue
        scenes = sorted({f.scene for f in found}, key=SCENES.index)
        spans = scene_spans(scenes, data)
        keep = {(s, q) for s in scenes for q in spans[s]} if whole else set(view)
        errors = [replace(f, groundtruth_spans={q: v for q, v in f.groundtruth_spans.items() if (f.scene, q) in keep})
                  for f in found if f.sequences]  # fmt: skip
        durations = spans_table({s: {q: v for q, v in spans[s].items() if (s, q) in keep} for s in scenes})
        shown = Evaluation(errors, [], None, [], data, spec=spec, kind="openloris")
        try:
            table = aggregate_scenes(shown.sequences(), durations)
            fig = plot_timeline(errors, durations, table, spec.eps, spec.phi, spec.delta, title="this submission")
            name = f"timeline-{k}.png"
            fig.savefig(folder / name, dpi=80)
            # named from the submission's folder (claims/<claim>/timeline-0.png: a scoring's own)
            rel = (folder / name).relative_to(upload.parent) if folder.is_relative_to(upload.parent) else Path(name)
            out["figures"].append(dict(sequences=sorted(keep), file=rel.as_posix()))
        except (LorisError, ValueError, ArithmeticError) as exc:  # the figure: a note, the scores stand
            note = f"no timeline figure: {scrub(str(exc), upload, data, groundtruth)}"
            out["notes"].append(dict(text=note, sequences=sorted(keep & scored)))


def _limit(cpu_seconds: int, memory_bytes: int) -> None:
    resource.setrlimit(resource.RLIMIT_CPU, (cpu_seconds, cpu_seconds + 5))  # SIGXCPU, then SIGKILL
    resource.setrlimit(resource.RLIMIT_AS, (memory_bytes, memory_bytes))


def _write(path: Path, outcome: dict[str, Any]) -> None:
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(outcome), encoding="utf-8")
    os.replace(tmp, path)


@dataclass(frozen=True)
class Task:
    """What a scoring process needs (picklable: a Dask worker gets it too): the submission's
    folder, the hidden ground truth, the spec, where its outcome goes, its limits, the server's
    folder of one-sequence ground truths, the sets of sequences to draw a figure of and the
    scoring's own folder (its claim's: ``claims/<claim>``; empty: the submission's folder)."""

    folder: str
    data: DataPaths
    spec: EvalSpec
    out: str
    cpu_seconds: int
    memory_bytes: int
    groundtruth: str
    views: tuple[tuple[tuple[str, int], ...], ...]
    work: str = ""


def die_with_parent() -> None:
    """End this process as soon as the process that started it ends, killed (SIGKILL) included: a
    scoring forked from the fork server watches its server by
    :func:`multiprocessing.parent_process` (the end of a pipe the server alone holds, closed by the
    system when it dies); one started by :func:`score_on_worker` watches for the Dask worker that
    started it (its parent process changes when that one ends). Without this, a scorer outlived
    a killed server and scored on beside the restarted server's scorer of the same submission."""
    parent = multiprocessing.parent_process()
    if parent is not None:

        def watch() -> None:
            parent.join()
            os._exit(1)

    else:
        first = os.getppid()

        def watch() -> None:
            while os.getppid() == first:
                time.sleep(0.5)
            os._exit(1)

    threading.Thread(target=watch, name="lorisnb-score-parent", daemon=True).start()


def score_in_child(task: Task) -> None:
    """The scoring process: ended with the server (:func:`die_with_parent`), limits set, then
    :func:`score_folder` (the upload's plan read from its folder; its work and figures in
    ``task.work``), its outcome written to ``task.out``."""
    die_with_parent()  # before the limits: the watching thread's stack is not charged to the scoring
    _limit(task.cpu_seconds, task.memory_bytes)
    sub = Path(task.folder)
    gt = Path(task.groundtruth)
    work = Path(task.work) if task.work else sub
    try:
        work.mkdir(parents=True, exist_ok=True)
        plain = json.loads((sub / PLAN).read_text(encoding="utf-8")) if (sub / PLAN).is_file() else {}
        outcome = score_folder(sub / FILES, task.data, task.spec, work, plain=plain, groundtruth=gt, views=task.views,
                               work=work)  # fmt: skip
    except MemoryError:
        outcome = dict(error=f"scoring needed more than the challenge's memory limit of {task.memory_bytes / 1e6:g} MB")
    except LorisError as exc:
        outcome = dict(error=scrub(str(exc), sub / FILES, task.data, gt))
    except Exception as exc:  # any other error of the scorer: said by its type only (no server detail)
        outcome = dict(error=f"the scorer could not score this upload ({type(exc).__name__}); tell the organizers")
    _write(Path(task.out), outcome)


#: Signals a scoring process ends by when an allocation fails under its memory limit
#: (RLIMIT_AS) in native code, which raises no MemoryError: Arrow and other C++ libraries abort
#: (SIGABRT, from std::bad_alloc or their own check), others crash on the NULL they got (SIGSEGV, SIGBUS).
MEMORY_SIGNALS = (signal.SIGABRT, signal.SIGSEGV, signal.SIGBUS)


def stopped(exitcode: int | None, cpu_seconds: int, memory_mb: float | None = None) -> str:
    """Why a scoring process ended without an outcome: killed at its CPU-time limit (SIGXCPU at
    the soft limit, SIGKILL at the hard one, or by the system out of memory), out of memory under
    its limit of ``memory_mb`` (:data:`MEMORY_SIGNALS`), or another exit status."""
    memory = f"{memory_mb:g} MB" if memory_mb is not None else None
    if exitcode == -signal.SIGXCPU or (exitcode == -signal.SIGKILL and memory is None):
        return f"scoring exceeded the challenge's limit of {cpu_seconds} CPU seconds"
    if exitcode == -signal.SIGKILL:
        return f"scoring exceeded the challenge's limit of {cpu_seconds} CPU seconds or of {memory} of memory (killed)"
    if memory is not None and exitcode is not None and -exitcode in MEMORY_SIGNALS:
        name = signal.Signals(-exitcode).name
        return (f"scoring needed more than the challenge's memory limit of {memory} (the scorer ran out of memory "
                f"and stopped, {name}); send smaller files, or fewer at once")  # fmt: skip
    return f"the scorer stopped (exit status {exitcode}); tell the organizers"


def score_on_worker(task: Task) -> int:
    """On a Dask worker (``[challenge] scheduler``): :func:`score_in_child` in a fresh Python
    process of its own, so that the limits bind that process and not the worker; its exit status
    (negative: the signal that ended it). The upload's folder, the server's folder and the ground
    truth must be at the same paths on the worker (a shared file system)."""
    cmd = [sys.executable, "-c", "from lorisnb.tools.challenge.scoring import child_main; child_main()"]
    try:
        done = subprocess.run(cmd, input=pickle.dumps(task), capture_output=True, timeout=2 * task.cpu_seconds + 30)
    except subprocess.TimeoutExpired:
        return -int(signal.SIGKILL)
    return int(done.returncode)


def child_main() -> None:
    """The process :func:`score_on_worker` starts: its task pickled on stdin (from the server
    itself, never from an upload)."""
    score_in_child(pickle.loads(sys.stdin.buffer.read()))


class _Remote:
    """A scoring on the Dask cluster, seen as a process (is_alive, kill, join, exitcode)."""

    def __init__(self, future: Any):
        self.future = future

    def is_alive(self) -> bool:
        return not self.future.done()

    def kill(self) -> None:
        self.future.cancel()

    def join(self, timeout: float | None = None) -> None:
        return None

    @property
    def exitcode(self) -> int | None:
        if self.future.status != "finished":
            return None
        return int(self.future.result())


@dataclass
class _Running:
    process: Any
    claim: str
    started: float
    out: Path


class Scorer:
    """The queue's loop (a thread of the server): see the module docstring."""

    def __init__(self, challenge: Challenge, engine: Engine, poll: float = 0.1):
        self.challenge = challenge
        self.engine = engine
        self.poll = poll
        self.limits = challenge.limits
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._running: dict[str, _Running] = {}
        self._context = multiprocessing.get_context("forkserver")
        self._context.set_forkserver_preload(["lorisnb.tools.challenge.preload"])
        self._client: Any = None
        if challenge.scheduler is not None:  # scoring on the Dask cluster lorisnb evaluates on
            from lorisnb.tools.evaluation.pool import connect_scheduler

            self._client = connect_scheduler(challenge.scheduler)
        self.requeued = 0
        self._lock: list[int] | None = None  # the queue's locks (_take_queue)
        self._waiting = False
        # the sets of sequences shown as the phases close: a submission is scored on each set its
        # phase shows alone (nothing from hidden ground truth), with a figure of each
        seqs = sequences_of(scene_durations(challenge.scenes, challenge.data))
        self.views = {p.name: tuple(tuple(sorted(v)) for v in challenge.views(seqs, p)) for p in challenge.phases}

    def start(self) -> None:
        """Score the queue from now on, once this scorer holds the challenge's queue
        (:meth:`_take_queue`): a second server of the challenge (one started on a port in use,
        which stops before it serves) never touches what the running one scores."""
        self._take_queue()
        self._thread = threading.Thread(target=self._loop, name="lorisnb-scorer", daemon=True)
        self._thread.start()

    def _take_queue(self) -> bool:
        """Whether this scorer holds the queue: exclusive locks on ``folder/scorer.lock`` and, for
        an SQLite database, on ``DATABASE.scorer.lock`` beside its file (two challenge files of
        other folders on one database: the other server claimed this one's submissions and failed
        them), each an ``flock`` released by the system when the process ends, a kill included,
        taken without waiting. Taken, the submissions a killed server left ``scoring`` go back to
        the queue; held by another server, nothing is touched (said once), and they are tried
        again each poll (scored here once that server stops)."""
        if self._lock is not None:
            return True
        held: list[int] = []
        for path in self.lock_paths():
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o600)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                os.close(fd)
                for other in held:
                    os.close(other)
                if not self._waiting:
                    self._waiting = True
                    print(f"lorisnb serve: scorer: another server scores this challenge's queue (it holds "
                          f"{path}); this one scores once that one stops", flush=True)  # fmt: skip
                return False
            held.append(fd)
        self._lock = held
        self.requeued = store.requeue_unfinished(self.engine)  # what a killed server left half-scored
        return True

    def lock_paths(self) -> list[Path]:
        """The files whose locks hold the queue (:meth:`_take_queue`), in the order they are taken."""
        paths = [self.challenge.folder / LOCK]
        url = make_url(self.challenge.database)
        if url.get_backend_name() == "sqlite" and url.database:
            paths.append(Path(f"{url.database}.{LOCK}"))
        return paths

    def stop(self) -> None:
        """Stop taking work; scorings under way are stopped and put back in the queue (their
        claims released), then the queue's lock."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=10)
        for sid, r in self._running.items():
            r.process.kill()
            r.process.join(timeout=5)
            try:
                store.release(self.engine, sid, r.claim)
            except Exception as exc:  # the database gone: the next start puts it back (requeue_unfinished)
                print(f"lorisnb serve: scorer: {type(exc).__name__}: {exc}", flush=True)
        self._running.clear()
        if self._client is not None:
            self._client.close()
        if self._lock is not None:
            for fd in self._lock:
                os.close(fd)  # the lock with it
            self._lock = None

    def _loop(self) -> None:
        while not self._stop.is_set():
            if not self._take_queue():
                self._stop.wait(max(self.poll, 0.5))
                continue
            try:
                self._reap()
                while len(self._running) < self.limits["workers"] and not self._stop.is_set():
                    claimed = store.claim_next(self.engine)
                    if claimed is None:
                        break
                    try:
                        self._start(*claimed)
                    except Exception:
                        store.release(self.engine, *claimed)  # queued again, not left half-taken
                        raise
            except Exception as exc:  # the database busy or gone for a moment: try again, say so
                print(f"lorisnb serve: scorer: {type(exc).__name__}: {exc}", flush=True)
            self._stop.wait(self.poll)

    def _start(self, sid: str, claim: str) -> None:
        folder = self.challenge.folder / "uploads" / sid
        out = folder / f"result-{claim}.json"
        sub = store.submission(self.engine, sid)
        views = self.views.get(sub["phase"] if sub is not None else "", ())
        task = Task(str(folder), self.challenge.data, self.challenge.spec, str(out), self.limits["score_seconds"],
                    self.limits["score_memory_mb"] * 1_000_000, str(self.challenge.folder / GROUNDTRUTH), views,
                    str(folder / CLAIMS / claim))  # fmt: skip
        if self._client is not None:
            future = self._client.submit(score_on_worker, task, key=f"lorisnb-score-{sid}-{claim}", pure=False)
            self._running[sid] = _Running(_Remote(future), claim, time.monotonic(), out)
            return
        p = self._context.Process(target=score_in_child, args=(task,), name=f"lorisnb-score-{sid}", daemon=True)
        p.start()
        self._running[sid] = _Running(p, claim, time.monotonic(), out)

    def _reap(self) -> None:
        deadline = 2 * self.limits["score_seconds"] + 30  # wall clock: a scorer asleep uses no CPU time
        for sid, r in list(self._running.items()):
            took = time.monotonic() - r.started
            if r.process.is_alive():
                if took > deadline:
                    r.process.kill()
                    r.process.join(5)
                    self._done(sid, r, "failed", None, f"scoring took longer than {deadline} s; stopped", took)
                continue
            r.process.join()
            outcome = json.loads(r.out.read_text(encoding="utf-8")) if r.out.is_file() else None
            if outcome is not None and "rows" in outcome and not scored_nothing(outcome):
                self._done(sid, r, "scored", outcome, None, took)
            elif outcome is not None and "rows" in outcome:  # nothing scored: failed, each file's reason kept
                self._done(sid, r, "failed", outcome, nothing_scored(outcome), took)
            elif outcome is not None:
                self._done(sid, r, "failed", None, str(outcome["error"]), took)
            else:
                why = stopped(r.process.exitcode, self.limits["score_seconds"], float(self.limits["score_memory_mb"]))
                self._done(sid, r, "failed", None, why, took)

    def _done(self, sid: str, r: _Running, status: str, result: Any, error: str | None, took: float) -> None:
        store.finish(self.engine, sid, r.claim, status, result, error, took)
        del self._running[sid]
