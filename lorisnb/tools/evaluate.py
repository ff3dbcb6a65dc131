"""Evaluation of result files and folders: the edge that reads files, finds the ground truth in
the data root and runs the pure pipeline (:func:`lorisnb.core.pipeline.compute_errors`) on each,
collecting failures instead of stopping.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Iterable
from concurrent.futures import Executor
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..core import validate
from ..core.aggregate import aggregate_scenes, durations_table, spans_table
from ..core.association import MAX_GAP
from ..core.conventions import Conventions
from ..core.frames import SCENES
from ..core.model import Eps, FileErrors, ResultFile
from ..core.pipeline import compute_errors
from ..core.relative import RPG_FRACTIONS, relative_table
from ..core.scoring import pose_table, score
from ..core.trials import check_duplicates, check_trials_by, compile_trials_by, split_trial
from ..core.validate import choice, scale_value
from ..errors import DataNotFoundError, LorisError, LorisWarning, ValidationError
from ..io.data import DataPaths, DataRoot, find_data, groundtruth_spans, load_groundtruth, scene_durations
from ..io.openloris import read_openloris
from .pool import default_jobs, run_tasks, size_of

PathArg = str | os.PathLike[str]


@dataclass
class Failure:
    """A file that could not be evaluated, with the reason (file, line, what was expected)."""

    path: Path
    error: str
    kind: str


@dataclass
class Evaluation:
    """What :func:`evaluate` returns: the errors of every file evaluated, and the failures."""

    errors: list[FileErrors]
    failures: list[Failure]
    root: Path | None = None
    skipped: list[Failure] = field(default_factory=list)
    data: DataPaths | None = None
    groundtruth: dict[str, ResultFile] | None = None  # scene -> ground truth, for pairs and manifests
    conventions: str = ""  # what association and alignment were used, in words
    thresholds: dict[str, float] = field(default_factory=dict)  # default eps / phi (a manifest's)

    def sequences(
        self, eps: Eps = np.inf, phi: float = np.inf, delta: float = 1.0, tau: float = 60.0, **kw: Any
    ) -> pd.DataFrame:
        """Per-sequence table at one setting (see :func:`lorisnb.core.scoring.score`)."""
        return score(self.errors, eps, phi, delta, tau, **kw)

    def poses(self, eps: Eps = np.inf, phi: float = np.inf) -> pd.DataFrame:
        """Per-pose table (see :func:`lorisnb.core.scoring.pose_table`)."""
        return pose_table(self.errors, eps, phi)

    def scenes(self, eps: Eps = np.inf, phi: float = np.inf, delta: float = 1.0, tau: float = 60.0) -> pd.DataFrame:
        """Per algorithm and scene, as in the paper's figures (see
        :func:`lorisnb.core.aggregate.aggregate_scenes`)."""
        return aggregate_scenes(self.sequences(eps, phi, delta, tau), self.durations())

    def relative(self, fractions: tuple[float, ...] = RPG_FRACTIONS) -> pd.DataFrame:
        """rpg_trajectory_evaluation's relative error per sequence and sub-trajectory length
        (see :func:`lorisnb.core.relative.relative_table`)."""
        return relative_table(self.errors, fractions)

    @property
    def algorithms(self) -> list[str]:
        return sorted({f.algorithm for f in self.errors})

    def durations(self) -> pd.DataFrame:
        """Ground-truth durations of every sequence of the scenes evaluated, seconds."""
        if self.groundtruth is not None:
            return durations_table(self.groundtruth)
        scenes = sorted({f.scene for f in self.errors}, key=SCENES.index)
        known = {f.scene: f.groundtruth_spans for f in self.errors if f.groundtruth_spans}
        if set(known) == set(scenes):  # spans found while evaluating: no ground truth read again
            return spans_table({s: dict(sorted(known[s].items())) for s in scenes})
        return scene_durations(scenes, self.data)

    @property
    def warnings(self) -> list[str]:
        return [w for f in self.errors for w in f.warnings]

    def failures_table(self) -> pd.DataFrame:
        """Failed and skipped files with the reason, one row each."""
        rows = [dict(file=str(f.path), status="failed", kind=f.kind, error=f.error) for f in self.failures]
        rows += [dict(file=str(f.path), status="skipped", kind=f.kind, error=f.error) for f in self.skipped]
        return pd.DataFrame(rows, columns=["file", "status", "kind", "error"])


def is_hidden(path: Path) -> bool:
    """Hidden files and editor leftovers (``.x.txt``, ``.#x.txt``, ``~x.txt``) are not results."""
    return path.name.startswith((".", "~"))


def as_paths(paths: PathArg | Iterable[PathArg]) -> list[Path]:
    """One path or several, as Paths; an empty path or another type is a ValidationError."""
    items = [paths] if isinstance(paths, (str, os.PathLike)) else None
    if items is None:
        if isinstance(paths, (bytes, pd.DataFrame)) or not isinstance(paths, Iterable):
            raise ValidationError(
                f"paths: expected a file or folder path (str or pathlib.Path) or a list of them, "
                f"got {type(paths).__name__}"
            )
        items = list(paths)
    out = []
    for p in items:
        if not isinstance(p, (str, os.PathLike)):
            raise ValidationError(f"paths: expected str or pathlib.Path items, got {type(p).__name__} ({p!r:.60})")
        if str(p).strip() == "":
            raise ValidationError("paths: an empty path (an unset shell variable?); expected a file or folder")
        out.append(Path(p))
    if not out:
        raise ValidationError("paths: no path given; expected at least one file or folder")
    return out


def result_files(
    paths: PathArg | Iterable[PathArg], suffixes: tuple[str, ...] = (".txt",)
) -> list[tuple[Path, Path | None]]:
    """Expand files and folders into ``(file, root)`` pairs; a folder is walked for files ending in
    ``suffixes`` below it (``root/<algorithm>/*.txt``, or deeper: ``root/<suite>/<algorithm>/*.txt``),
    hidden files and folders left out. A ROS 2 bag (a folder holding ``metadata.yaml``) is one
    file when ``.bag`` is among the suffixes."""
    out: list[tuple[Path, Path | None]] = []
    bags = ".bag" in suffixes
    for p in as_paths(paths):
        if p.is_dir() and not (bags and (p / "metadata.yaml").is_file()):
            found = [f for f in p.rglob("*") if f.suffix in suffixes and f.is_file()]
            if bags:
                found += [m.parent for m in p.rglob("metadata.yaml")]
            files = sorted(f for f in found if not any(is_hidden(Path(part)) for part in f.relative_to(p).parts))
            out.extend((f, p) for f in files)
        else:
            out.append((p, None))
    return out


def _names(what: str, value: object) -> list[str]:
    """A name or a list of names (algorithms, scenes), checked."""
    items = [value] if isinstance(value, str) else value
    if not isinstance(items, Iterable) or isinstance(items, (bytes, pd.DataFrame)):
        raise ValidationError(f"{what}={value!r}: expected a name or a list of names")
    names = list(items)
    bad = [n for n in names if not isinstance(n, str)]
    if bad:
        raise ValidationError(f"{what}: expected names (str), got {bad[0]!r}")
    return names


def labels(path: Path, root: Path | None, trials_by: str | None = None) -> tuple[str, str, str, int]:
    """(algorithm, file relative to the root, suite, trial) for a result file; a trial token in
    the path (:func:`lorisnb.core.trials.split_trial`) is not part of the algorithm or suite."""
    if root is None:  # a file given alone: its algorithm is its folder, or the folder above a trial folder
        base, trial = split_trial("/".join(path.parts[-3:]), trials_by)
        parts = base.split("/")
        return (parts[-2] if len(parts) >= 2 else path.parent.name), path.name, "", trial
    rel = path.relative_to(root).as_posix()
    base, trial = split_trial(rel, trials_by)
    parts = base.split("/")
    algorithm = parts[-2] if len(parts) >= 2 else root.name
    return algorithm, rel, "/".join(parts[:-2]), trial


@dataclass(frozen=True, kw_only=True)
class FileJob:
    """Everything one worker needs to evaluate one file (picklable, for process pools and Dask)."""

    path: Path
    root: Path | None
    data: DataPaths
    mode: str
    scale: bool | str
    official_interpolation: bool
    remove_repeated: bool
    repair_stamps: bool
    max_gap: float
    trials_by: str | None
    scenes: frozenset[str] | None


def evaluate_file(job: FileJob, progress: bool = False) -> tuple[str, FileErrors | Failure | None]:
    """Evaluate one file: ``("ok", FileErrors)``, ``("failed" | "skipped", Failure)`` or
    ``("filtered", None)`` when its scene is not wanted. Never raises for bad input. With
    ``progress``, a file over :data:`BIG_FILE_BYTES` shows a bar of the bytes read."""
    algorithm, rel, suite, trial = labels(job.path, job.root, job.trials_by)
    bar = None
    if progress and size_of(job.path) >= BIG_FILE_BYTES:
        from tqdm.auto import tqdm

        bar = tqdm(total=size_of(job.path), desc=f"reading {job.path.name}", unit="B", unit_scale=True, leave=False)
    try:
        result = read_openloris(
            job.path, remove_repeated=job.remove_repeated, warn=False, repair_stamps=job.repair_stamps,
            progress=bar.update if bar is not None else None,
        )  # fmt: skip
        if job.scenes is not None and result.scene not in job.scenes:
            return "filtered", None
        gt = load_groundtruth(result.scene, job.data, job.remove_repeated)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", LorisWarning)  # kept in FileErrors.warnings
            errors = compute_errors(
                result, gt, algorithm=algorithm, file=rel, suite=suite, mode=job.mode, scale=job.scale,
                official_interpolation=job.official_interpolation, max_gap=job.max_gap, trial=trial,
                other_spans=partial(groundtruth_spans, job.data, job.remove_repeated), consume=True,
            )  # fmt: skip
        del result  # the poses as read are not needed for RPE: a long file's memory goes back first
        for seq in errors.sequences:  # the default RPE pairs, here (in a worker, when in parallel)
            seq.rpe()
        return "ok", errors
    except DataNotFoundError as exc:
        return "skipped", Failure(job.path, str(exc), "no-groundtruth")
    except LorisError as exc:
        return "failed", Failure(job.path, str(exc), type(exc).__name__)
    finally:
        if bar is not None:
            bar.close()


#: Files at least this large show a progress bar of their own while read (when evaluated here).
BIG_FILE_BYTES = 64 * 2**20


def evaluate(
    paths: PathArg | Iterable[PathArg],
    *,
    mode: str = "auto",
    scale: bool | str = False,
    official_interpolation: bool = False,
    remove_repeated: bool = True,
    data_root: DataRoot | DataPaths | None = None,
    algorithms: Iterable[str] | None = None,
    scenes: Iterable[str] | None = None,
    repair_stamps: bool = False,
    max_gap: float = MAX_GAP,
    trials_by: str | None = None,
    progress: bool = False,
    jobs: int | None = None,
    executor: Executor | None = None,
) -> Evaluation:
    """Evaluate OpenLORIS result files and folders. A file that fails (bad line, unknown frame,
    ...) is recorded in ``failures`` with its reason and the rest go on; a file whose scene has no
    ground truth in the data (office, in the bundled data) is recorded in ``skipped``.

    Args:
        paths: files, or folders walked as ``<algorithm>/*.txt`` (see :func:`result_files`).
        mode, scale, official_interpolation, max_gap: see
            :func:`lorisnb.core.pipeline.compute_errors`.
        remove_repeated, repair_stamps: see :func:`lorisnb.io.read_openloris`.
        data_root: where the ground truth is (see :func:`lorisnb.io.find_data`).
        algorithms, scenes: evaluate only these (None: all).
        trials_by: a regular expression whose first group is the trial number in a file's path
            (default: the tokens of :mod:`lorisnb.core.trials`: ``_trial3``, ``run_2/``, ...).
        progress: show a progress bar over files (tqdm; notebook-aware).
        jobs: processes evaluating files in parallel; default all local cores (:func:`lorisnb.tools.pool.default_jobs`),
            1 for one process. Small inputs run in this process: fewer than two files per process,
            or, where workers cannot be forked cheaply (inside Jupyter), under
            :data:`lorisnb.tools.pool.PARALLEL_MIN_BYTES`.
        executor: any ``concurrent.futures.Executor`` to run the files on instead, for example a
            Dask cluster's (``distributed.Client(address).get_executor()``). Results are the same
            and in the same order as one process gives.
    """
    mode = choice("mode", mode, ("auto", "per-seq", "lifelong"))
    compile_trials_by(trials_by)
    scale = scale_value(scale)
    items = result_files(paths)
    check_trials_by([labels(p, r, trials_by)[1] if r else "/".join(p.parts[-3:]) for p, r in items], trials_by)
    data = find_data(data_root)  # no data at all is an error for the whole call, not per file
    if algorithms is not None:
        wanted = set(_names("algorithms", algorithms))
        items = [(p, r) for p, r in items if labels(p, r, trials_by)[0] in wanted]
    scene_set = None if scenes is None else set(_names("scenes", scenes))
    n_jobs = default_jobs() if jobs is None else int(validate.positive("jobs", jobs, "processes", integer=True))
    if executor is not None and not isinstance(executor, Executor):
        raise ValidationError(f"executor: expected a concurrent.futures.Executor, got {type(executor).__name__}")
    template = FileJob(
        path=Path(), root=None, data=data, mode=mode, scale=scale, official_interpolation=official_interpolation,
        remove_repeated=remove_repeated, repair_stamps=repair_stamps, max_gap=max_gap, trials_by=trials_by,
        scenes=None if scene_set is None else frozenset(scene_set),
    )  # fmt: skip
    work = [replace(template, path=p, root=r) for p, r in items]
    done: list[FileErrors] = []
    failed: list[Failure] = []
    skipped: list[Failure] = []
    sizes = [size_of(j.path) for j in work]
    for status, value in run_tasks(
        evaluate_file, work, sizes, n_jobs, executor, progress, desc="evaluating", unit="file"
    ):
        if isinstance(value, FileErrors):
            done.append(value)
        elif isinstance(value, Failure):
            (failed if status == "failed" else skipped).append(value)
    check_duplicates([(str(f.path), (f.suite, f.algorithm, f.scene, f.trial), tuple(e.seq for e in f.sequences))
                      for f in done])  # fmt: skip
    roots = as_paths(paths)
    root = roots[0] if len(roots) == 1 and roots[0].is_dir() else None
    for w in dict.fromkeys(w for f in done for w in f.warnings):
        warnings.warn(w, LorisWarning, stacklevel=2)
    aligned = {"per-seq": "each sequence aligned on itself", "lifelong": "every file aligned on its first sequence"}
    how = (
        f"OpenLORIS: ground truth moved to each file's sensor frame, "
        f"{Conventions(max_gap=max_gap, align='sim3' if scale is True else 'se3').describe()}"
        f"{' (sim3 for monocular algorithms)' if scale == 'auto' else ''}; "
        f"{aligned.get(mode, 'files with several sequences aligned on their first')}"
    )
    return Evaluation(done, failed, root, skipped, data, conventions=how)
