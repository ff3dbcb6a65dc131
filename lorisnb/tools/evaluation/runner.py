"""Evaluation of every input kind through one runner: OpenLORIS result files and folders
(:func:`evaluate`), plain estimate / ground-truth pairs (:func:`evaluate_pairs`: TUM, EuRoC,
KITTI, ROS bags, OpenLORIS) and multi-session datasets described by a manifest
(:func:`evaluate_manifest`). Each builds the one evaluation spec
(:func:`lorisnb.core.spec.evalspec.make_spec`) from its keywords, refuses options that cannot apply to its
inputs, turns its inputs into jobs (:mod:`lorisnb.tools.evaluation.jobs`) and runs them here, on all local
cores or on any executor (a Dask cluster's), collecting failures instead of stopping.
"""

from __future__ import annotations

import contextlib
import importlib
import inspect
import os
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import Executor
from dataclasses import fields, replace
from pathlib import Path
from typing import Any

from lorisnb.core.alignment.index_pairs import by_index
from lorisnb.core.pipeline.model import FileErrors
from lorisnb.core.spec import validate
from lorisnb.core.spec.evalspec import EvalSpec, make_spec, preset_over
from lorisnb.core.stats.trials import check_duplicates, check_trials_by, compile_trials_by, trial_folders
from lorisnb.errors import FailedInputsWarning, LorisWarning, ParseError, ValidationError
from lorisnb.io.datasets.manifest import SUFFIX, Manifest, groundtruth_refusal, openloris_preset_refusal, read_manifest
from lorisnb.io.datasets.paths import DataPaths, DataRoot, find_data
from lorisnb.io.readers.openloris import declared_scene
from lorisnb.io.readers.options import check_reading
from lorisnb.io.readers.plain import TRAJECTORY_FORMATS
from lorisnb.io.readers.registry import FORMATS
from lorisnb.tools.evaluation.inputs import (
    absolute,
    algorithm_folders,
    as_paths,
    check_manifest_trials,
    find_inputs,
    labels,
    names,
    result_files,
    scene_label,
    without_dataset_groundtruth,
    without_groundtruth,
)
from lorisnb.tools.evaluation.jobs import BIG_FILE_BYTES, Job, PairSource, PartialErrors, absolute_paths, run_job
from lorisnb.tools.evaluation.pool import default_jobs, run_tasks, size_of
from lorisnb.tools.evaluation.result import Evaluation, Failure, said_notes

PathArg = str | os.PathLike[str]
__all__ = ["BIG_FILE_BYTES", "Evaluation", "Failure", "evaluate", "evaluate_manifest", "evaluate_pairs"]


def _refuse_unknown(function: Callable[..., Any], options: Mapping[str, Any]) -> None:
    """Refuse a keyword that is neither one of ``function``'s own (``data_root``, ``algorithms``,
    ``trials_by``, ...) nor an option of the evaluation spec (``options`` go to the spec), naming both
    lists and the nearest of either (``data`` -> ``data_root``, ``trials`` -> ``trials_by``)."""
    from lorisnb.core.spec.evalspec import ALIASES

    spec_keys = sorted(({f.name for f in fields(EvalSpec)} - {"explicit", "preset_name"}) | set(ALIASES))
    unknown = sorted(set(options) - set(spec_keys))
    if not unknown:
        return
    own = [n for n, p in inspect.signature(function).parameters.items() if p.kind is p.KEYWORD_ONLY]
    name = unknown[0]
    near = validate.near_miss(name, [*own, *spec_keys])
    if not near:  # a keyword short of its own: data -> data_root, algorithm -> algorithms, trials -> trials_by
        start = [
            k for k in [*own, *spec_keys] if len(name) > 2 and (k.startswith(name) or name.startswith(k.rstrip("s")))
        ]
        near = f"did you mean {start[0]!r}?" if len(start) == 1 else ""
    raise ValidationError(f"{name}: not a keyword of {function.__name__}{f' ({near})' if near else ''}; its own "
                          f"keywords are {', '.join(own)}, and the options of the evaluation spec "
                          f"{', '.join(spec_keys)}")  # fmt: skip


def _spec(spec: EvalSpec | str | None, conventions: EvalSpec | str | None, options: dict[str, Any]) -> EvalSpec:
    if spec is not None and conventions is not None:
        raise ValidationError("spec and conventions: give one (conventions is the older name of spec)")
    return make_spec(spec if spec is not None else conventions, **options)


def _table_library() -> None:
    """pandas (and pyarrow's compute functions, which write a CSV table) imported while the workers
    evaluate: the tables are built from their results with them (imported after them, pandas was
    0.3 s of a 5,000-file run's 13 s, with one core idle, and pyarrow.compute 0.06-0.09 s). Not
    when the workers send back neither poses nor statistics (:func:`_sent_back`): the caller then
    reads :meth:`Evaluation.sequence_rows`, which needs no pandas (``lorisnb evaluate`` printing
    its table): importing it beside the workers took a core from them, and the whole icra20 tree's
    process took 1.85-2.18 s with it, 1.53-1.76 s without (4 runs each, 2 shared cores, 2026-11-30)."""
    for name in ("pandas", "pyarrow.compute"):
        with contextlib.suppress(ImportError):  # the table says what is missing
            importlib.import_module(name)


def _as_given(job: Job, went: Job) -> list[tuple[str, str]]:
    """(absolute, as given) of each path of ``job`` that was sent to a worker elsewhere made
    absolute (:func:`~lorisnb.tools.evaluation.jobs.absolute_paths`), longest first: the input, a
    pair's ground truth and its times files."""
    if went is job:
        return []
    pairs = [(went.path, job.path)]
    if job.source is not None and went.source is not None:
        pairs += [(getattr(went.source, k), getattr(job.source, k)) for k in ("groundtruth", "est_times", "gt_times")]
    out = {str(w): str(g) for w, g in pairs if w is not None and g is not None and str(w) != str(g)}
    return sorted(out.items(), key=lambda kv: -len(kv[0]))


def _run(jobs: list[Job], spec: EvalSpec, kind: str, *, n_jobs: int | None, executor: Executor | None,
         progress: bool, root: Path | None = None, data: Any = None, notes: list[str] | None = None,
         empty: Sequence[tuple[Path, str, tuple[tuple[str, str, int], ...]]] = ()) -> Evaluation:  # fmt: skip
    """Run the jobs here, in a local pool or on ``executor``; results in the order of the jobs.
    ``empty``: trial folders that hold no result file (:func:`~lorisnb.tools.evaluation.inputs.find_inputs`),
    each a failed input (kind ``empty-trial``)."""
    n = default_jobs() if n_jobs is None else int(validate.positive("jobs", n_jobs, "processes", integer=True))
    if executor is not None and not isinstance(executor, Executor):
        raise ValidationError(f"executor: expected a concurrent.futures.Executor, got {type(executor).__name__}")
    done: list[FileErrors] = []
    failed: list[Failure] = []
    in_table = 0  # failed manifest sessions beside their algorithm's other sessions, which are scored
    skipped: list[Failure] = []
    sizes = [size_of(j.path) if j.path.is_file() else 1 for j in jobs]
    unit = "file" if kind != "manifest" else "session set"
    # on an executor (a Dask cluster's workers) a relative path is opened in the worker's folder, not here
    sent = jobs if executor is None else [absolute_paths(j) for j in jobs]
    tables = any(j.statistics or j.keep_poses for j in jobs)  # a DataFrame will be built from the results
    results = run_tasks(run_job, sent, sizes, n, executor, progress, desc="evaluating", unit=unit,
                        meanwhile=_table_library if tables else None)  # fmt: skip
    for job, went, (status, value) in zip(jobs, sent, results, strict=True):
        renamed = _as_given(job, went)
        if renamed:  # named as given, as a local run names them (the input, its ground truth, times files)

            def given(text: str, renamed: list[tuple[str, str]] = renamed) -> str:
                for was, typed in renamed:
                    text = text.replace(was, typed)
                return text

            if isinstance(value, Failure):
                value = replace(value, path=job.path, error=given(value.error))
            elif isinstance(value, FileErrors):
                value.path, value.warnings = job.path, [given(w) for w in value.warnings]
            elif isinstance(value, PartialErrors):  # a manifest's sessions: each failure names its own file
                if value.errors is not None:
                    value.errors.path, value.errors.warnings = job.path, [given(w) for w in value.errors.warnings]
                value = PartialErrors(value.errors, [replace(f, error=given(f.error)) for f in value.failures])
        if isinstance(value, PartialErrors):  # some sessions failed alone: the others are scored
            if value.errors is not None:
                done.append(value.errors)
                in_table += len(value.failures)
            failed += value.failures
        elif isinstance(value, FileErrors):
            done.append(value)
        elif isinstance(value, Failure):
            (failed if status == "failed" else skipped).append(value)
    check_duplicates([(str(f.path), (f.suite, f.algorithm, f.scene, f.trial), tuple(e.seq for e in f.sequences))
                      for f in done])  # fmt: skip
    failed += [Failure(folder, why, "empty-trial", runs) for folder, why, runs in empty]
    if kind == "openloris" and "mode" in spec.explicit and spec.mode != "auto" and done:
        if all(len(f.sequences) <= 1 for f in done):  # as a pair is told (EvalSpec.refuse_inapplicable)
            notes = [*(notes or []), f"mode {spec.mode}: every input has one sequence, so per-seq and lifelong agree"]
    # the spec's notes on the options (EvalSpec.refuse_inapplicable: harmless here), then the inputs'; a note many
    # inputs share: said in full for a few, then counted
    for w in [*dict.fromkeys(notes or []), *said_notes(done)]:
        warnings.warn(w, LorisWarning, stacklevel=3)
    if failed and in_table:  # a manifest's sessions that failed alone
        more = f" (and {len(failed) - 1} more)" if len(failed) > 1 else ""
        warnings.warn(f"{len(failed)} input(s) could not be evaluated and are in no table ({in_table} of them sessions "
                      "whose algorithm's other sessions are scored); Evaluation.failures lists them with the reason, "
                      f"exit_status() is 1: {failed[0].error}{more}", FailedInputsWarning, stacklevel=3)  # fmt: skip
    elif failed:  # tables without them would look complete: a notebook says so at the call
        more = f" (and {len(failed) - 1} more)" if len(failed) > 1 else ""
        warnings.warn(f"{len(failed)} of {len(jobs) + len(empty)} inputs could not be evaluated and are in no table; "
                      f"Evaluation.failures lists them with the reason, exit_status() is 1: "
                      f"{failed[0].error}{more}", FailedInputsWarning, stacklevel=3)  # fmt: skip
    ev = Evaluation(done, failed, root, skipped, data, spec=spec, kind=kind, notes=list(notes or []))
    if not done and not failed:  # empty tables would look like a result: said at the call, as the command line says it
        warnings.warn(_nothing_evaluated(ev, kind), FailedInputsWarning, stacklevel=3)
    return ev


#: What each input kind evaluates, for the message of a call that found nothing to evaluate.
EXPECTED = {
    "openloris": "OpenLORIS result files, or folders of them (<algorithm>/*.txt below the folder)",
    "pair": "estimate files in the format given, or folders of them",
    "manifest": "the manifest's sessions' estimates",
}


def _nothing_evaluated(ev: Evaluation, kind: str) -> str:
    """The warning of a call that evaluated nothing: the reason the exit status gives
    (:func:`lorisnb.tools.evaluation.status.unscored`, as ``lorisnb evaluate`` prints it), where
    it looked, what it expected, and why each input was skipped."""
    reason = next(f.error for f in ev.unscored if f.kind == "nothing")
    where = f" in {ev.root}" if ev.root is not None else ""
    if ev.skipped:  # each with the reason (its scene's ground truth is not in the data)
        more = f" (and {len(ev.skipped) - 1} more: Evaluation.skipped lists them)" if len(ev.skipped) > 1 else ""
        return (f"{reason}{where}: {ev.skipped[0].error.splitlines()[0]}{more}; the tables are empty and "
                "exit_status() is 1")  # fmt: skip
    return (f"{reason}{where}; the tables are empty and exit_status() is 1 (Evaluation.unscored says so); expected "
            f"{EXPECTED.get(kind, 'input files')}")  # fmt: skip


def poses_needed(spec: EvalSpec) -> str | None:
    """Why a table of ``spec`` needs each pose's errors in the process that collects the files (its
    columns are computed there from them), or None: evo's ``relation`` statistics, the KITTI
    devkit's and tartanair_tools' numbers."""
    if spec.relation is not None:
        return f"evo's relation {spec.relation!r} statistics"
    if spec.preset_name in ("kitti", "tartanair"):
        return f"the {spec.preset_name} preset's numbers"
    return None


def _sent_back(spec: EvalSpec, statistics: Any, keep_poses: Any) -> tuple[bool, bool]:
    """What the workers score and send back, the same for every input kind (a :class:`Job`'s
    ``statistics`` and ``keep_poses``), checked as yes/no values: ``keep_poses=False`` is refused
    where the spec's table needs the poses (:func:`poses_needed`)."""
    scored, keep = validate.flag("statistics", statistics), validate.flag("keep_poses", keep_poses)
    why = None if keep else poses_needed(spec)
    if why is not None:
        raise ValidationError(f"keep_poses=False: {why} are computed from each pose's errors after the files are "
                              "evaluated; keep them (keep_poses=True)")  # fmt: skip
    return scored, keep


def _check_trials(items: list[tuple[Path, Path | None]], trials_by: str | None) -> None:
    """A ``trials_by`` that matches none of the inputs' paths is an error (:func:`check_trials_by`)."""
    check_trials_by([labels(p, r, trials_by)[1] if r else "/".join(absolute(p).parts[-3:]) for p, r in items],
                    trials_by)  # fmt: skip


def _filtered(
    items: list[tuple[Path, Path | None]], algorithms: Any, scenes: Any, trials_by: str | None
) -> tuple[list[tuple[Path, Path | None]], frozenset[str] | None]:
    """The inputs the ``algorithms`` and ``scenes`` filters keep, and the scene set the jobs check.
    A filter value naming no algorithm folder (or no scene a file declares in its ``scene:``
    header) is refused by :func:`lorisnb.core.spec.validate.present`, listing what the inputs hold."""
    if algorithms is not None:
        have = [labels(p, r, trials_by)[0] for p, r in items]
        wanted = set(validate.present("algorithms", names("algorithms", algorithms), have))
        items = [item for item, alg in zip(items, have, strict=True) if alg in wanted]
    if scenes is None:
        return items, None
    declared = [declared_scene(p) for p, _ in items]
    scene_set = frozenset(validate.present("scenes", names("scenes", scenes), [s for s in declared if s]))
    # a file whose header names another scene is not read; one whose header is unclear is (and says why)
    return [item for item, s in zip(items, declared, strict=True) if s is None or s in scene_set], scene_set


def check_filters(
    paths: PathArg | Iterable[PathArg], algorithms: Any = None, scenes: Any = None, trials_by: str | None = None
) -> None:
    """Refuse an ``algorithms`` or ``scenes`` value that names nothing in ``paths`` (as
    :func:`evaluate` does), before anything is evaluated (``lorisnb report -p scenes``)."""
    if algorithms is not None or scenes is not None:
        _filtered(result_files(as_paths(paths)), algorithms, scenes, trials_by)


def evaluate(
    paths: PathArg | Iterable[PathArg],
    spec: EvalSpec | str | None = None,
    *,
    data_root: DataRoot | DataPaths | None = None,
    algorithms: Iterable[str] | None = None,
    scenes: Iterable[str] | None = None,
    trials_by: str | None = None,
    progress: bool = False,
    jobs: int | None = None,
    executor: Executor | None = None,
    statistics: bool = True,
    keep_poses: bool = True,
    conventions: EvalSpec | str | None = None,
    **options: Any,
) -> Evaluation:
    """Evaluate OpenLORIS result files and folders. A file that fails (bad line, unknown frame,
    ...) is recorded in ``failures`` with its reason and the rest go on; a file whose scene has no
    ground truth in the data (office, in the bundled data) is recorded in ``skipped``.

    Args:
        paths: files, or folders walked as ``<algorithm>/*.txt`` (see :func:`lorisnb.tools.evaluation.inputs.result_files`).
        spec: the evaluation spec or a preset name (default ``openloris``; ``conventions``, its
            older name, as :func:`evaluate_pairs` and :func:`evaluate_manifest` take it); ``options`` are spec
            options over it (``mode``, ``scale``, ``official_interpolation``, ``max_gap``,
            ``remove_repeated``, ``repair_stamps``, ``eps``, ``phi``, ...; see
            :func:`lorisnb.core.spec.evalspec.make_spec`). Options that cannot apply to OpenLORIS files
            (``transform``) are refused.
        data_root: where the ground truth is (see :func:`lorisnb.io.find_data`).
        algorithms, scenes: evaluate only these (None: all).
        trials_by: a regular expression whose first group is the trial number in a file's path
            (default: the tokens of :mod:`lorisnb.core.stats.trials`: ``_trial3``, ``run_2/``, ...).
        progress: show a progress bar over files (tqdm; notebook-aware).
        jobs: processes evaluating files in parallel; default all local cores, 1 for one process.
            Small inputs run in this process (see :mod:`lorisnb.tools.evaluation.pool`).
        executor: any ``concurrent.futures.Executor`` to run the files on instead, for example a
            Dask cluster's (``distributed.Client(address).get_executor()``). Results are the same
            and in the same order as one process gives.
        statistics: where the error statistics of the spec's setting (the ``*_mean``,
            ``*_median``, ... columns of :meth:`Evaluation.sequences`) are computed: True, with
            each file's errors (in the workers, when in parallel: a table with every column is
            then read); False, only when a table asks for them, in this process (the command
            line's printed table shows none: the workers then score a quarter of the work). Every
            table holds the same numbers either way.
        keep_poses: False lets each pose's errors go once the spec's setting is scored, so that
            only that setting's scores travel back from the workers (a hundredth of the bytes;
            ``lorisnb evaluate`` does this when it only prints or writes its table). The tables at
            the spec's setting then read as ever (with the error statistics where ``statistics``
            is True, else :meth:`Evaluation.sequence_rows` without them); another setting, a sweep,
            a figure or the poses raise an EvaluationError saying to keep them. Refused for specs
            whose tables are computed from the poses (:func:`poses_needed`).
    """
    _refuse_unknown(evaluate, options)
    the_spec = _spec(spec, conventions, options)
    notes = the_spec.refuse_inapplicable("openloris")
    compile_trials_by(trials_by)
    paths = as_paths(paths)  # once: a generator is read once
    found = find_inputs(paths, trials_by=trials_by)
    items = found.files
    _check_trials(items, trials_by)
    # folders read as trials of one name by a token beside other text (slam_run1/, slam_run2/): said
    notes += trial_folders([labels(p, r, trials_by)[1] for p, r in items if r is not None], trials_by)
    data = find_data(data_root)  # no data at all is an error for the whole call, not per file
    items = without_dataset_groundtruth(items, [data.groundtruth(s) for s in data.scenes_with_groundtruth()])
    items, scene_set = _filtered(items, algorithms, scenes, trials_by)
    scored, keep = _sent_back(the_spec, statistics, keep_poses)
    template = Job(kind="openloris", path=Path(), root=None, spec=the_spec, trials_by=trials_by, data=data,
                   scenes=scene_set, statistics=scored, keep_poses=keep)  # fmt: skip
    work = [replace(template, path=p, root=r) for p, r in items]
    roots = as_paths(paths)
    root = roots[0] if len(roots) == 1 and roots[0].is_dir() else None
    return _run(work, the_spec, "openloris", n_jobs=jobs, executor=executor, progress=progress, root=root, data=data,
                notes=notes, empty=found.lost_runs(trials_by))  # fmt: skip


#: The spec field each alias of :func:`lorisnb.core.spec.evalspec.make_spec` sets.
ALIAS_OF = {"scale": "align", "lifelong": "mode", "keep_repeated": "repeated", "remove_repeated": "repeated"}


def refuse_over_manifest(
    spec: EvalSpec, manifest: Manifest, given: Iterable[str], kind: str = "manifest", surface: str = "python"
) -> list[str]:
    """:meth:`~lorisnb.core.spec.evalspec.EvalSpec.refuse_inapplicable` of a spec built over a manifest's,
    saying which refused options the manifest set (its ``[conventions]``), not the call (``given``:
    the options of the call or the command line): ``max_diff`` from the manifest with
    ``--association interpolate`` is refused naming the manifest, on every path alike."""
    theirs = (spec.explicit & manifest.spec.explicit) - {ALIAS_OF.get(k, k) for k in given}
    return spec.refuse_inapplicable(kind, surface=surface, set_by=(theirs, f"the manifest {manifest.path}"))


def replaced_by_preset(manifest: Manifest, spec: EvalSpec, given: Iterable[str]) -> list[str]:
    """A note naming the manifest's ``[conventions]`` values that ``spec`` does not use: a preset given
    over the manifest (``--conventions``, ``conventions=``, a spec object) replaces its conventions
    (:func:`~lorisnb.core.spec.evalspec.preset_over`; its thresholds, body transform and mode stay),
    and they were dropped unsaid. Values the call's own options (``given``) set are the user's."""
    kept = {"eps", "phi", "transform", "mode"} | {ALIAS_OF.get(k, k) for k in given}
    lost = [k for k in sorted(manifest.spec.explicit - kept) if getattr(spec, k) != getattr(manifest.spec, k)]
    if not lost:
        return []
    said = ", ".join(f"{k} = {getattr(manifest.spec, k)!r} (now {getattr(spec, k)!r})" for k in lost)
    preset = spec.preset_name or "openloris"
    return [f"the manifest {manifest.path}: its [conventions] {said} not used: the conventions given over it (preset "
            f"{preset}) replace the manifest's (its thresholds, transform and mode stay); leave the preset out to use "
            "them, or give them as options"]  # fmt: skip


def _format(name: str, value: Any) -> str:
    return validate.choice(name, value, TRAJECTORY_FORMATS)


def pair_source(
    groundtruth: PathArg, fmt: str = "tum", gt_fmt: str | None = None, scene: str | None = None, *,
    est_times: PathArg | None = None, gt_times: PathArg | None = None, topic: str | None = None,
    gt_topic: str | None = None, tf: str | None = None, gt_tf: str | None = None,
) -> PairSource:  # fmt: skip
    """How a pair's files are read, checked: each reading option must apply to its format (times
    files to KITTI, topics and TF chains to bags), or it is refused."""
    fmt = _format("format", fmt)
    gt_fmt = _format("gt_format", gt_fmt if gt_fmt is not None else fmt)
    check_reading(
        {"est_times": est_times, "gt_times": gt_times, "topic": topic, "tf": tf, "gt_topic": gt_topic, "gt_tf": gt_tf},
        fmt, gt_fmt, name=lambda k: f"{k} (command line --{k.replace('_', '-')})",
    )  # fmt: skip
    if scene is not None and (not isinstance(scene, str) or not scene.strip()):  # a label, never str() of a number
        raise ValidationError(f"scene={scene!r}: expected a scene name (a non-empty string)")
    if scene is not None and fmt == "openloris":
        raise ValidationError("scene (command line --scene): OpenLORIS result files name their scene in their "
                              "header (scene: ...), which is used")  # fmt: skip
    gt_paths = as_paths(groundtruth)
    if len(gt_paths) != 1:
        raise ValidationError(f"groundtruth: {len(gt_paths)} paths given; expected one ground-truth file")
    gt_path = gt_paths[0]
    return PairSource(
        groundtruth=gt_path, fmt=fmt, gt_fmt=gt_fmt, scene=scene or scene_label(gt_path),
        est_times=None if est_times is None else Path(est_times), gt_times=None if gt_times is None else Path(gt_times),
        topic=topic, gt_topic=gt_topic, tf=tf, gt_tf=gt_tf,
    )  # fmt: skip


def pair_kind(fmt: str) -> str:
    """The input kind whose options apply to pairs of estimates in ``fmt``: OpenLORIS result files
    are scored as the native route scores them (their frames, every sequence), other files as pairs."""
    return "openloris" if fmt == "openloris" else "pair"


def _pair_suffixes(fmt: str) -> tuple[str, ...]:
    return (".bag", ".mcap", ".db3") if fmt == "bag" else tuple(dict.fromkeys((SUFFIX[fmt], ".txt", ".csv")))


def _refuse_reading(spec: EvalSpec, fmt: str, kind: str) -> None:
    """Spec options that only OpenLORIS' reader honours, refused for other formats (``repeated``
    keep: every reader keeps the poses of a repeated stamp, as evo)."""
    if fmt == "openloris":
        return
    for name, flag, on in (("repair_stamps", "--repair-stamps", spec.repair_stamps),):  # fmt: skip
        if name in spec.explicit and on:
            raise ValidationError(
                f"{name} (command line {flag}): only OpenLORIS result files are read with this rule; the {kind}'s "
                f"estimates are {fmt} files"
            )


def evaluate_pairs(
    estimates: PathArg | Iterable[PathArg],
    groundtruth: PathArg,
    spec: EvalSpec | str | None = None,
    *,
    fmt: str = "tum",
    gt_fmt: str | None = None,
    conventions: EvalSpec | str | None = None,
    scene: str | None = None,
    est_times: PathArg | None = None,
    gt_times: PathArg | None = None,
    topic: str | None = None,
    gt_topic: str | None = None,
    tf: str | None = None,
    gt_tf: str | None = None,
    trials_by: str | None = None,
    progress: bool = False,
    jobs: int | None = None,
    executor: Executor | None = None,
    statistics: bool = True,
    keep_poses: bool = True,
    **options: Any,
) -> Evaluation:
    """Score estimate files against one ground truth with every metric of lorisnb.

    Args:
        estimates: files, or folders of files (one sub-folder per algorithm).
        groundtruth: the ground-truth file (a ROS 2 bag: its folder).
        spec, conventions: the evaluation spec or a preset name (``tum``, ``rpg``, ``vio``,
            ``openloris``; default lorisnb's: interpolation, SE(3)); ``options`` are spec options
            over it (``association``, ``max_diff``, ``align``, ``transform``, ``eps``, ...).
        fmt, gt_fmt: formats of the estimates and of the ground truth (``tum``, ``euroc``,
            ``kitti``, ``bag``, ``openloris``); ``gt_fmt`` defaults to ``fmt``.
        scene: the scene label of the rows (default: the ground-truth file's name).
        est_times, gt_times: times files for KITTI poses (one stamp per line).
        topic, gt_topic, tf, gt_tf: what to read from bags (see :func:`lorisnb.io.readers.bags.read_bag`);
            ``topic`` may name several topics (or evo's TF ids) separated by commas: each bag's topics
            are evaluated alone, a row each, whose ``algorithm`` is the bag's algorithm label (its folder's
            name, or a bag given alone its name without the suffix) and the topic, ``'<algorithm>:<topic>'`` (``orb:/odom``,
            ``orb:/tf:map.base_link``), so that two algorithms' bags are told apart as well as the topics.
        jobs, executor, progress, trials_by, statistics, keep_poses: as for :func:`evaluate`.
    """
    _refuse_unknown(evaluate_pairs, options)
    the_spec = _spec(spec, conventions, options)
    src = pair_source(groundtruth, fmt, gt_fmt, scene, est_times=est_times, gt_times=gt_times, topic=topic,
                      gt_topic=gt_topic, tf=tf, gt_tf=gt_tf)  # fmt: skip
    notes = the_spec.refuse_inapplicable(pair_kind(src.fmt))
    if pair_kind(src.fmt) == "pair":  # eps='paper' for a scene not OpenLORIS': refused before any file is read
        the_spec.refuse_scenes([src.scene])
    _refuse_reading(the_spec, src.fmt, "pair")
    if src.fmt == src.gt_fmt == "kitti" and src.est_times is None and src.gt_times is None:
        the_spec = by_index(the_spec)  # stamps are pose indices: pose i with pose i, on every preset
    compile_trials_by(trials_by)
    if not src.groundtruth.exists():
        raise ParseError(src.groundtruth, None, "ground truth not found; expected a file (or a ROS 2 bag folder)")
    if src.groundtruth.is_dir() and src.gt_fmt != "bag":  # refused once, before any estimate is read
        raise ParseError(src.groundtruth, None, f"is a folder; expected the ground truth as a {FORMATS[src.gt_fmt].title} "
                         "(a folder is a ground truth only as a ROS 2 bag, --gt-format bag)")  # fmt: skip
    found = find_inputs(estimates, _pair_suffixes(src.fmt), trials_by)
    items = found.files
    if "bag" not in (src.fmt, src.gt_fmt):  # (one bag may hold both, on other topics)
        items = without_groundtruth(items, src.groundtruth)
    _check_trials(items, trials_by)
    topics = [t.strip() for t in src.topic.split(",")] if src.topic and "," in src.topic else [src.topic]
    if len(topics) > 1 and not all(topics):
        raise ValidationError(f"topic {src.topic!r}: expected topics separated by commas, none empty")
    sources = [src] if len(topics) == 1 else [replace(src, topic=t, label_topic=True) for t in topics]
    scored, keep = _sent_back(the_spec, statistics, keep_poses)
    work = [  # several topics of one bag: one row each, labelled '<algorithm>:<topic>' (PairSource.label_topic)
        Job(
            kind="pair",
            path=p,
            root=r,
            spec=the_spec,
            trials_by=trials_by,
            source=one,
            statistics=scored,
            keep_poses=keep,
        )
        for p, r in items
        for one in sources
    ]
    return _run(
        work,
        the_spec,
        "pair",
        n_jobs=jobs,
        executor=executor,
        progress=progress,
        notes=notes,
        empty=found.lost_runs(trials_by),
    )


def evaluate_manifest(
    manifest: Manifest | PathArg,
    results: PathArg | Iterable[PathArg],
    spec: EvalSpec | str | None = None,
    *,
    conventions: EvalSpec | str | None = None,
    lifelong: bool | None = None,
    trials_by: str | None = None,
    progress: bool = False,
    jobs: int | None = None,
    executor: Executor | None = None,
    statistics: bool = True,
    keep_poses: bool = True,
    data_root: DataRoot | DataPaths | None = None,
    **options: Any,
) -> Evaluation:
    """Score the results of a multi-session dataset: ``results`` holds one folder per algorithm
    with one estimate file per session (named as the manifest says), or is one such folder.
    The manifest's spec (its ``[conventions]``, ``lifelong``, ``transform``, thresholds) is the
    default; a preset name (``spec``/``conventions``) replaces its conventions and keeps the rest, a
    spec object is used as it is, and ``lifelong`` and ``options`` go over either. The built-in
    ``openloris`` manifest runs :func:`evaluate` (``data_root`` is its data). ``trials_by``,
    ``progress``, ``jobs``, ``executor``, ``statistics`` and ``keep_poses`` are :func:`evaluate`'s."""
    _refuse_unknown(evaluate_manifest, options)
    m = manifest if isinstance(manifest, Manifest) else read_manifest(manifest)
    if lifelong is not None:
        options["lifelong"] = lifelong
    if m.openloris:
        if spec is not None or conventions is not None:
            given = spec if spec is not None else conventions
            raise ValidationError(openloris_preset_refusal("spec" if spec is not None else "conventions", given))
        refuse_over_manifest(make_spec(m.spec, **options), m, options, "openloris")
        return evaluate(results, m.spec, data_root=data_root, trials_by=trials_by, progress=progress, jobs=jobs,
                        executor=executor, statistics=statistics, keep_poses=keep_poses, **options)  # fmt: skip
    if data_root is not None:
        raise ValidationError("data_root: a manifest names its own ground-truth files (root and groundtruth)")
    if spec is not None and conventions is not None:
        _spec(spec, conventions, {})  # refused: give one
    given = spec if spec is not None else conventions
    base = m.spec if given is None else preset_over(m.spec, given)
    the_spec = make_spec(base, **options)
    notes = refuse_over_manifest(the_spec, m, options) + replaced_by_preset(m, the_spec, options)
    the_spec.refuse_scenes(m.scenes)  # eps='paper' for scenes not OpenLORIS': refused before any file is read
    _refuse_reading(the_spec, m.estimate_format, "manifest")
    if m.estimate_format == "kitti" and all(
        s.groundtruth_format == "kitti" and s.estimate_times is None and s.groundtruth_times is None for s in m.sessions
    ):
        the_spec = by_index(
            the_spec, surface="manifest"
        )  # KITTI files without times (estimate_times, groundtruth_times): pose i with i
    compile_trials_by(trials_by)
    for s in m.sessions:  # an estimate lies in each algorithm's folder: a path leaving it reads one file for all
        name = os.path.normpath(s.estimate)
        if os.path.isabs(s.estimate) or name == os.pardir or name.startswith(os.pardir + os.sep):
            raise ParseError(m.path, None, f"[[session]] {s.name}: estimate = {s.estimate!r} lies outside the algorithm's "
                             f"folder; expected the name of a file in it (estimate = 'NAME{SUFFIX[m.estimate_format]}', "
                             "or a path below it), each algorithm's own")  # fmt: skip
    for s in m.sessions:  # a missing ground truth (or a folder not a ROS 2 bag's) is an error of the whole call
        why = groundtruth_refusal(s)
        if why is not None:
            raise ParseError(
                s.groundtruth, None, f"ground truth of session {s.name!r} {why} ({m.path}: root and groundtruth)"
            )
        for key, times in (("estimate_times", s.estimate_times), ("groundtruth_times", s.groundtruth_times)):
            if times is not None and not times.is_file():
                raise ParseError(times, None, f"{key} of session {s.name!r} not found; expected a times file, one stamp "
                                 f"in seconds per line ({m.path}: root and {key})")  # fmt: skip
    folders = algorithm_folders(results, m)
    check_manifest_trials(folders, m, trials_by)  # names the estimate files found, not placeholders
    # algorithm folders read as trials of one name (slam_run1/, slam_run2/): said, as evaluate says it
    notes += trial_folders([labels(f / "x", r, trials_by)[1] for f, r in folders if r is not None], trials_by)
    scored, keep = _sent_back(the_spec, statistics, keep_poses)
    work = [
        Job(
            kind="manifest",
            path=folder,
            root=root,
            spec=the_spec,
            trials_by=trials_by,
            manifest=m,
            scene=scene,
            statistics=scored,
            keep_poses=keep,
        )
        for folder, root in folders
        for scene in m.scenes
    ]
    return _run(work, the_spec, "manifest", n_jobs=jobs, executor=executor, progress=progress, notes=notes)
