"""Evaluation of plain estimate / ground-truth pairs (TUM, EuRoC, KITTI, ROS bags, OpenLORIS) and
of multi-session datasets described by a manifest, with every metric lorisnb has.

Estimates are files or folders (one folder per algorithm, as for OpenLORIS results); each is
scored against the ground truth under the chosen conventions (:mod:`lorisnb.core.conventions`).
The result is an :class:`~lorisnb.tools.evaluate.Evaluation`, so ``.sequences(eps, phi)``,
``.scenes(...)``, sweeps, surfaces, figures and reports work as for OpenLORIS files.
"""

from __future__ import annotations

import os
import re
import warnings
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..core.conventions import Conventions
from ..core.geometry import Sim3
from ..core.missing import with_missing
from ..core.model import ResultFile
from ..core.pairs import session_errors
from ..core.trajectory import Trajectory
from ..core.units import check_stamp_units
from ..errors import LorisError, LorisWarning, ParseError, ValidationError
from ..io.formats import TRAJECTORY_FORMATS, read_trajectory
from ..io.manifest import SUFFIX, Manifest, read_manifest
from .evaluate import Evaluation, Failure, as_paths, labels, result_files
from .inputs import holds_any, missing_note, unique_files

PathArg = str | os.PathLike[str]


def _suffixes(fmt: str) -> tuple[str, ...]:
    return (".bag",) if fmt == "bag" else tuple(dict.fromkeys((SUFFIX[fmt], ".txt", ".csv")))


def _groundtruth_file(path: Path, scene: str, sequences: dict[int, Trajectory]) -> ResultFile:
    return ResultFile(path=path, header={"scene": scene}, header_lines={}, sequences=sequences)


@contextmanager
def _ticks(total: int, progress: bool) -> Iterator[Callable[[], object]]:
    """A progress bar's update (a no-op without ``progress``), closed at the end."""
    if not progress:
        yield lambda: None
        return
    from tqdm.auto import tqdm

    with tqdm(total=total, desc="evaluating", unit="file") as bar:
        yield bar.update


def evaluate_pairs(
    estimates: PathArg | Iterable[PathArg],
    groundtruth: PathArg,
    *,
    fmt: str = "tum",
    gt_fmt: str | None = None,
    conventions: Conventions | str | None = None,
    scene: str | None = None,
    est_times: PathArg | None = None,
    gt_times: PathArg | None = None,
    topic: str | None = None,
    gt_topic: str | None = None,
    tf: str | None = None,
    gt_tf: str | None = None,
    transform: Sim3 | np.ndarray | None = None,
    trials_by: str | None = None,
    progress: bool = False,
) -> Evaluation:
    """Score estimate files against one ground truth with every metric of lorisnb.

    Args:
        estimates: files, or folders of files (one sub-folder per algorithm).
        groundtruth: the ground-truth file (a ROS 2 bag: its folder).
        fmt, gt_fmt: formats of the estimates and of the ground truth (``tum``, ``euroc``,
            ``kitti``, ``bag``, ``openloris``); ``gt_fmt`` defaults to ``fmt``.
        conventions: a :class:`~lorisnb.core.conventions.Conventions` or a preset name (``tum``,
            ``rpg``, ``vio``, ``openloris``); default lorisnb's (interpolation, SE(3)).
        scene: the scene label of the rows (default: the ground-truth file's name).
        est_times, gt_times: times files for KITTI poses (one stamp per line).
        topic, gt_topic, tf, gt_tf: what to read from bags (see :func:`lorisnb.io.bags.read_bag`).
        transform: ``T_est_gt``, the ground-truth body's pose in the estimate's body frame, when
            the estimate tracks another body (see :func:`lorisnb.core.pairs.with_transform`).
    """
    if isinstance(conventions, str):
        conventions = Conventions.preset(conventions)
    conv = conventions if conventions is not None else Conventions()
    fmt = _format("format", fmt)
    gt_fmt = _format("gt_format", gt_fmt or fmt)
    gt_paths = as_paths(groundtruth)
    if len(gt_paths) != 1:
        raise ValidationError(f"groundtruth: {len(gt_paths)} paths given; expected one ground-truth file")
    gt_path = gt_paths[0]
    gt = read_trajectory(gt_path, gt_fmt, stamps=gt_times, topic=gt_topic, tf=gt_tf)
    label = scene or scene_label(gt_path)
    jobs = result_files(estimates, _suffixes(fmt))
    errors, failures = [], []
    with _ticks(len(jobs), progress) as tick:
        for path, root in jobs:  # one file at a time
            algorithm, rel, suite, trial = labels(path, root, trials_by)
            if root is None:  # a file given alone: its name says which estimate it is
                algorithm = path.stem
            try:
                with warnings.catch_warnings(record=True) as caught:
                    warnings.simplefilter("always", LorisWarning)
                    est = read_trajectory(path, fmt, stamps=est_times, topic=topic, tf=tf)
                    check_stamp_units(est, gt, str(path))  # seconds vs indices or nanoseconds
                    fe = session_errors(
                        {1: gt}, {1: est}, conv, transform=transform, path=path, algorithm=algorithm, scene=label,
                        suite=suite, trial=trial,
                    )  # fmt: skip
                fe.warnings[:0] = [str(w.message) for w in caught if issubclass(w.category, LorisWarning)]
                fe.file = rel
                errors.append(fe)
            except LorisError as exc:
                failures.append(Failure(path, str(exc), type(exc).__name__))
            tick()
    return Evaluation(
        errors=errors, failures=failures, groundtruth={label: _groundtruth_file(gt_path, label, {1: gt})},
        conventions=conv.describe(),
    )  # fmt: skip


def scene_label(gt_path: Path) -> str:
    """A scene name from a ground-truth path: ``fr2_desk_groundtruth.txt`` -> ``fr2_desk``;
    EuRoC's ``V1_01_easy/mav0/state_groundtruth_estimate0/data.csv`` -> ``V1_01_easy``."""
    generic = {"data", "groundtruth", "gt", "mav0", "state_groundtruth_estimate0", "poses", "metadata"}
    for part in [gt_path.stem, *[p.name for p in gt_path.parents]]:
        name = re.sub(r"[-_.]?(groundtruth|ground_truth|gt)$", "", part, flags=re.IGNORECASE)
        if name and name.lower() not in generic:
            return name
    return gt_path.stem


def _format(name: str, value: str) -> str:
    if not isinstance(value, str) or value.strip().lower() not in TRAJECTORY_FORMATS:
        raise ValidationError(f"{name}={value!r}: expected one of {', '.join(TRAJECTORY_FORMATS)}")
    return value.strip().lower()


def evaluate_manifest(
    manifest: Manifest | PathArg,
    results: PathArg | Iterable[PathArg],
    *,
    conventions: Conventions | str | None = None,
    lifelong: bool | None = None,
    trials_by: str | None = None,
    progress: bool = False,
    **openloris: object,
) -> Evaluation:
    """Score the results of a multi-session dataset: ``results`` holds one folder per algorithm
    with one estimate file per session (named as the manifest says), or is one such folder.
    Sessions are aligned together (``lifelong``, the manifest's default) or each on itself.
    The built-in ``openloris`` manifest runs :func:`lorisnb.evaluate` (``openloris`` keywords
    are passed on)."""
    m = manifest if isinstance(manifest, Manifest) else read_manifest(manifest)
    if m.openloris:
        from .evaluate import evaluate

        if conventions is not None:
            raise ValidationError(
                "conventions: OpenLORIS result files are scored with the official conventions "
                "(choose max_gap, scale and lifelong instead)"
            )
        mode = "auto" if lifelong is None else ("lifelong" if lifelong else "per-seq")
        return evaluate(results, mode=mode, trials_by=trials_by, progress=progress, **openloris)  # type: ignore[arg-type]
    if isinstance(conventions, str):
        conventions = Conventions.preset(conventions)
    conv = conventions if conventions is not None else m.conventions
    along = m.lifelong if lifelong is None else bool(lifelong)
    gts: dict[str, dict[int, Trajectory]] = {}
    for s in m.sessions:  # a handful of sessions
        if not s.groundtruth.exists():
            raise ParseError(
                s.groundtruth, None, f"ground truth of session {s.name!r} not found ({m.path}: root and groundtruth)"
            )
        gts.setdefault(s.scene, {})[s.seq] = read_trajectory(
            s.groundtruth, s.groundtruth_format, topic=m.groundtruth_topic, tf=m.groundtruth_tf
        )
    folders = _algorithm_folders(results, m)
    errors, failures, missing = [], [], []
    with _ticks(len(folders) * len(m.scenes), progress) as tick:
        for folder, root in folders:
            algorithm, _, suite, trial = labels(folder / "x", root, trials_by)
            for scene in m.scenes:
                sessions = [s for s in m.sessions if s.scene == scene]
                ests: dict[int, Trajectory] = {}
                try:
                    for s in sessions:
                        path = folder / s.estimate
                        if path.exists():
                            ests[s.seq] = read_trajectory(
                                path, m.estimate_format, topic=m.estimate_topic, tf=m.estimate_tf
                            )
                            check_stamp_units(ests[s.seq], gts[scene][s.seq], str(path))
                    fe = None
                    if ests:
                        fe = session_errors(
                            gts[scene], ests, conv, lifelong=along, transform=m.transform, path=folder,
                            algorithm=algorithm, scene=scene, suite=suite, trial=trial,
                        )  # fmt: skip
                    absent = [s for s in sessions if s.seq not in ests]
                    if absent:  # scored as the paper scores missing output, never dropped
                        note = missing_note(folder, algorithm, [(s.name, s.estimate) for s in absent])
                        fe = with_missing(
                            fe, gts[scene], [s.seq for s in absent], path=folder, algorithm=algorithm, scene=scene,
                            suite=suite, trial=trial, lifelong=along, note=note,
                        )  # fmt: skip
                        names = ", ".join(s.name for s in absent)
                        missing.append(
                            Failure(folder, f"{folder}: no estimate for session(s) {names}", "missing-estimate")
                        )
                    if fe is not None:  # not None: the scene has sessions
                        errors.append(fe)
                except LorisError as exc:
                    failures.append(Failure(folder, str(exc), type(exc).__name__))
                tick()
    return Evaluation(
        errors=errors, failures=failures,
        groundtruth={sc: _groundtruth_file(m.path, sc, seqs) for sc, seqs in gts.items()}, missing=missing,
        conventions=conv.describe() + ("; one alignment for all sessions" if along else "; each session aligned on itself"),
        thresholds={k: v for k, v in (("eps", m.eps), ("phi", m.phi)) if v is not None},
    )  # fmt: skip


def _algorithm_folders(results: PathArg | Iterable[PathArg], m: Manifest) -> list[tuple[Path, Path | None]]:
    """Folders holding estimate files of the manifest's sessions: each given folder if it holds
    one itself, else its sub-folders that do."""
    names = {s.estimate for s in m.sessions}
    out: list[tuple[Path, Path | None]] = []
    for p in as_paths(results):
        if not p.is_dir():
            raise ValidationError(f"{p}: expected a folder of estimates (one per session, named as in {m.path.name})")
        if holds_any(p, names):
            out.append((p, None))
            continue
        subs = sorted(d for d in p.rglob("*") if d.is_dir() and holds_any(d, names))
        out.extend((d, p) for d in subs)
        if not subs:
            raise ValidationError(f"{p}: no estimate named {', '.join(sorted(names))} in it or below it")
    return unique_files(out)  # a folder named twice is scored once
