"""The commands: ``evaluate``, ``sweep``, ``compare``, ``crosscheck``, ``report``, ``verify``. Tables go to stdout,
warnings and failures to stderr; the exit status is non-zero when any input failed."""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from lorisnb.cli.options import UNUSED, param_value, spec_from_args, spec_given
from lorisnb.cli.outputs import check_outputs, refuse_unused
from lorisnb.cli.text import clean, format_advice, format_table, frame_columns, say
from lorisnb.errors import EvaluationError, FailedInputsWarning, LorisError, LorisWarning, ValidationError

if TYPE_CHECKING:
    import pandas as pd

    from lorisnb.tools.evaluation.result import Evaluation


def _executor(args: argparse.Namespace) -> Any:
    """A Dask cluster's executor for ``--scheduler ADDRESS`` (None without it)."""
    if getattr(args, "scheduler", None) is None:
        return None
    from lorisnb.tools.evaluation.pool import SCHEDULER_TIMEOUT, WatchedExecutor, connect_scheduler

    client = connect_scheduler(args.scheduler)  # checked and probed: one line, never a hang
    try:  # a scheduler with no worker runs nothing: the command waited for ever, silent
        client.wait_for_workers(1, timeout=SCHEDULER_TIMEOUT)
    except TimeoutError:
        client.close()
        raise EvaluationError(f"--scheduler {args.scheduler}: the scheduler has no worker (waited "
                              f"{SCHEDULER_TIMEOUT:g} s); start one (dask worker {args.scheduler}) and run again") from None  # fmt: skip
    return WatchedExecutor(client.get_executor(), lambda: len(client.scheduler_info().get("workers", {})),
                           f"--scheduler {args.scheduler}")  # fmt: skip


def every_column(spec: Any) -> bool:
    """A command's table holds every column, the error statistics too (``_run_evaluation``'s ``statistics``)."""
    return True


def tables_only(spec: Any) -> bool:
    """Whether a command that reads only the tables at the spec's setting (``compare``, ``diff`` and
    ``history`` of a result folder) needs each pose's errors all the same (``_run_evaluation``'s
    ``poses``): only where the spec's columns are computed from them
    (:func:`~lorisnb.tools.evaluation.runner.poses_needed`)."""
    from lorisnb.tools.evaluation.runner import poses_needed

    return poses_needed(spec) is not None


def _run_evaluation(
    args: argparse.Namespace, files: list[str], folders: tuple[str, ...] = (),
    swept: Callable[[Any], str] | None = None, side: str = "", statistics: Callable[[Any], bool] | None = None,
    poses: Callable[[Any], bool] | None = None, refuse: Callable[[Any], None] | None = None,
) -> tuple[Any, list[str]]:  # fmt: skip
    """Every input kind through one spec (:func:`spec_from_args`) and one runner: OpenLORIS result
    files, ``--gt`` pairs or a ``--manifest``'s sessions. The output options ``files`` and
    ``folders`` are checked first against every input (:func:`~.outputs.check_outputs`: the
    estimates, the ground truth, times files, the manifest and its ground-truth files, the data
    root). Prints the ``conventions:`` line (``side``: which run, for ``diff``'s two). ``statistics``:
    whether the command's table shows the error statistics, given the spec (the workers then
    compute them; :func:`~lorisnb.tools.evaluation.runner.evaluate`'s ``statistics``). ``poses``:
    whether the command reads each pose's errors once the files are evaluated, given the spec (by
    default it does; else only the scores at the spec's setting travel back from the workers:
    ``evaluate``'s ``keep_poses``). ``refuse``: the command's own refusals of its options under the
    spec, made with the spec's (before any input is read: exit 2 means nothing was read)."""
    from lorisnb.core.spec.exclusive import EXCLUSIVE_INPUTS, option_refusal
    from lorisnb.io.datasets.manifest import openloris_preset_refusal, read_manifest
    from lorisnb.tools.evaluation.result import said_notes
    from lorisnb.tools.evaluation.runner import (
        evaluate,
        evaluate_manifest,
        evaluate_pairs,
        pair_kind,
        pair_source,
        refuse_over_manifest,
    )

    for pair in EXCLUSIVE_INPUTS:  # the registry the notebooks and the report read too
        if all(getattr(args, o.lstrip("-").replace("-", "_"), None) for o in pair.options):
            raise ValidationError(option_refusal(pair))
    refuse_tables(args.paths, getattr(args, "command", None) or "this command")
    if getattr(args, "manifest_outside", False) and not args.manifest:
        raise ValidationError("--manifest-outside: applies to the files a --manifest reads; give one")
    outside = bool(getattr(args, "manifest_outside", False))
    manifest = read_manifest(args.manifest, outside=outside) if args.manifest else None
    base = manifest.spec if manifest is not None else None  # its thresholds, mode and [conventions]
    if manifest is not None and manifest.openloris:
        if args.conventions:
            raise ValidationError(openloris_preset_refusal("--conventions", args.conventions))
        manifest = None
    reading = ["format", "gt_format", "topic", "gt_topic", "tf", "gt_tf", "gt_times", "est_times", "scene"]
    if not args.gt:
        given = [f"--{k.replace('_', '-')}" for k in reading if getattr(args, k, None) is not None]
        if given:
            raise ValidationError(
                f"{', '.join(given)}: for estimates scored against --gt (a manifest names its formats); "
                "OpenLORIS result files name their scene and frame in their header"
            )
    if getattr(args, "data", None) is not None and (args.gt or manifest is not None):
        raise ValidationError(
            "--data: the data root holds OpenLORIS ground truth; "
            + ("a pair's ground truth is --gt" if args.gt else "a manifest names its ground-truth files")
        )
    spec = spec_from_args(args, base)
    kind = pair_kind(args.format or "tum") if args.gt else "manifest" if manifest is not None else "openloris"
    if base is not None:  # refused options the manifest set are said to be its own
        refuse_over_manifest(spec, read_manifest(args.manifest, outside=outside), spec_given(args), kind, surface="cli")
    spec.refuse_inapplicable(kind, surface="cli")
    if kind == "pair":  # an eps that gives no threshold for the input's scenes: refused before any file is read
        spec.refuse_scenes(
            [pair_source(args.gt, args.format or "tum", args.gt_format, args.scene).scene], surface="cli"
        )
    elif kind == "manifest" and manifest is not None:
        spec.refuse_scenes(manifest.scenes, surface="cli")
    if refuse is not None:
        refuse(spec)
    inputs = list(args.paths)  # the options' inputs too (check_outputs), and a manifest's ground truth
    if manifest is not None:
        inputs += [str(manifest.path), *(str(s.groundtruth) for s in manifest.sessions)]
        args.manifest_groundtruth = [str(s.groundtruth) for s in manifest.sessions]  # for the errors' advice
    check_outputs(args, inputs, files, folders)
    kw: dict[str, Any] = dict(trials_by=args.trials_by, progress=not args.no_progress, jobs=args.jobs,
                              executor=_executor(args), statistics=statistics is not None and statistics(spec),
                              keep_poses=poses is None or poses(spec))  # fmt: skip
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        if args.gt:
            ev = evaluate_pairs(
                args.paths, args.gt, spec, fmt=args.format or "tum", gt_fmt=args.gt_format, scene=args.scene,
                est_times=args.est_times, gt_times=args.gt_times, topic=args.topic, gt_topic=args.gt_topic,
                tf=args.tf, gt_tf=args.gt_tf, **kw,
            )  # fmt: skip
        elif manifest is not None:
            ev = evaluate_manifest(manifest, args.paths, spec, **kw)
        else:
            ev = evaluate(args.paths, spec, data_root=args.data, **kw)
    # FailedInputsWarning speaks to Python callers (Evaluation.failures); here each failure is an error: line
    said = [str(w.message) for w in caught if not issubclass(w.category, FailedInputsWarning)]
    notes = list(dict.fromkeys(ev.notes + said_notes(ev.errors) + said))
    grid = swept(ev.spec) if swept is not None else None  # a sweep: its grid, not the spec's thresholds
    kitti_files = args.gt and "kitti" in (args.format, args.gt_format or args.format)
    projected = "; KITTI files: each rotation block projected to its nearest rotation" * bool(
        kitti_files and not ev.spec.as_written
    )  # evo and kitti compose them as written (said in the spec's words)
    print(f"conventions{side}: {ev.describe(grid)}{projected}", file=sys.stderr)
    return ev, notes


def lorisnb_table(path: str) -> bool:
    """Whether ``path`` is a per-sequence table lorisnb wrote (``evaluate --csv`` / ``--parquet``, a
    report's ``findings/sequences.csv``): a Parquet file, or a CSV file whose header names every
    column such a table must have (:data:`lorisnb.tools.decisions.runs.REQUIRED`). No estimate's
    header does (a EuRoC CSV's is ``#timestamp,p_RS_R_x...``)."""
    import csv

    p = Path(path)
    if not p.is_file():
        return False
    if p.suffix.lower() == ".parquet":
        return True
    try:
        with open(p, encoding="utf-8-sig", errors="replace", newline="") as f:
            header = {h.strip() for h in next(csv.reader([f.readline()]), [])}
    except OSError:
        return False
    if "algorithm" not in header:  # an estimate: decided without importing the tables' module (pandas)
        return False
    from lorisnb.tools.decisions.runs import REQUIRED

    return set(REQUIRED) <= header


def refuse_tables(paths: list[str], command: str) -> None:
    """A :class:`~lorisnb.errors.ValidationError` (exit 2, nothing read) when an input is a table
    lorisnb wrote (:func:`lorisnb_table`): ``evaluate``, ``sweep`` and ``compare`` read result files
    or folders, and such a table was read as a result file and failed on its header line ("has 1
    fields; expected 8 or 9 numbers"), exit 1."""
    tables = [p for p in paths if lorisnb_table(p)]
    if tables:
        raise ValidationError(f"{', '.join(tables)}: a per-sequence table lorisnb wrote (evaluate --csv / --parquet), "
                              f"not a result file: lorisnb {command} reads result files or folders of them "
                              "(<algorithm>/*.txt); tables are compared with lorisnb diff BASE CAND, or over runs "
                              "with lorisnb history RUN...")  # fmt: skip


#: How a manifest chooses the format of its estimates and of its ground truth (:func:`format_advice`).
MANIFEST_FORMATS = ("estimate_format = '{fmt}' in the manifest", "groundtruth_format = '{fmt}' in the manifest")


def _report_problems(ev: Any, notes: list[str], args: argparse.Namespace | None = None) -> None:
    for n in notes:
        say(f"warning: {n}")
    # a manifest's ground-truth files: the advice on one of them names groundtruth_format, never estimate_format
    gt_files = list(getattr(args, "manifest_groundtruth", None) or [])
    for f in ev.failures:  # a manifest names its files' formats (the readers' advice names the options of pairs)
        say(
            f"error: {format_advice(f.error, MANIFEST_FORMATS[0], MANIFEST_FORMATS[1], gt_files) if ev.kind == 'manifest' else f.error}"
        )
    for f in ev.unscored:  # in the table, scored as the paper scores it; the exit status says so
        say(f"not scored: {f.error}")
    from lorisnb.tools.evaluation.status import skipped_only

    skipped = skipped_only(ev)
    if skipped:
        reasons = sorted({f.error.split(":")[0] for f in skipped})
        say(f"skipped {len(skipped)} file(s): " + "; ".join(reasons))


def _fmt(df: pd.DataFrame, digits: int = 4) -> str:
    return format_table(frame_columns(df), digits)


def _with_trial(ev: Any, cols: list[str]) -> list[str]:
    """A printed scene table's columns, with ``trial`` after ``scene`` when the files are several
    trials (each trial's scene row is its own: without it two rows would look alike)."""
    if len({f.trial for f in ev.errors}) < 2:
        return cols
    at = cols.index("scene") + 1
    return [*cols[:at], "trial", *cols[at:]]


def cmd_evaluate(args: argparse.Namespace) -> int:
    from lorisnb.core.lifelong.aggregate import aggregate_columns, spans_columns
    from lorisnb.io.writers import write_csv, write_parquet

    def whole_table(spec: Any) -> bool:  # a table with every column: written, or the preset's own columns
        return bool(args.csv or args.parquet) or spec.relation is not None or spec.preset_name in ("kitti", "tartanair")

    def statistics(spec: Any) -> bool:  # error statistics shown: scored with the errors, in the workers
        return whole_table(spec) or spec.preset_name == "evo"

    def poses(spec: Any) -> bool:  # each pose's errors read here: else only the table's scores leave the workers
        return tables_only(spec) or bool(args.kitti_plot or getattr(args, "relative", False) or args.relative_lengths)

    def refuse(spec: Any) -> None:  # before any input is read
        if args.kitti_plot and spec.preset_name != "kitti":
            raise ValidationError("--kitti-plot: the KITTI metric's plot, only with --conventions kitti")

    ev, notes = _run_evaluation(args, ["csv", "kitti_plot"], folders=("parquet",), statistics=statistics, poses=poses,
                                refuse=refuse)  # fmt: skip
    kitti = ev.spec.preset_name == "kitti"
    table = ev.sequences() if whole_table(ev.spec) else None
    # the rows printed: error statistics only where printed (evo's); without them a setting's scores
    # take about a quarter of the time (lorisnb.core.lifelong.scoring.score's ``stats``): the whole
    # icra20 tree's process 2.62 -> 2.34 s of CPU (medians of 6 runs side by side, 2 shared cores)
    printed = ev.spec.preset_name == "evo"
    columns = frame_columns(table) if table is not None else _rows_as_columns(ev.sequence_rows(stats=printed))
    if columns and len(columns["seq"]):  # printed from the rows: pandas only for a table written
        cols = [
            "algorithm",
            "file",
            "seq",
            "poses",
            "matched",
            "ate_rmse",
            "c_ate_rmse",
            "aoe_rmse",
            "cr",
            "cr_t",
            "cs_r",
        ]
        if ev.spec.preset_name == "evo":  # evo's statistics, as evo_ape / evo_rpe print them
            cols += ["ate_mean", "ate_median", "ate_max", "rpe_trans_rmse", "rpe_rot_rmse"]
        if kitti:  # the devkit's numbers: % and deg/100 m
            cols += ["kitti_t_err", "kitti_r_err", "kitti_segments", "kitti_matrices"]
        if ev.spec.preset_name == "tartanair":  # tartanair_tools' ate_score, rpe_score, kitti_score
            cols += [
                "tartanair_ate",
                "tartanair_rpe_rot",
                "tartanair_rpe_trans",
                "tartanair_kitti_r",
                "tartanair_kitti_t",
            ]
        print(format_table({c: columns[c] for c in cols}, args.digits))
        try:
            scenes = aggregate_columns(columns, spans_columns(ev.spans()))
            print(
                "\nper scene (CR over all ground-truth time of the scene; CS-R the mean over all its sequences, "
                "one without output counting 0; C-ATE RMSE weighted by correct poses):"
            )
            scenes["coverage"] = np.array(
                [f"{k}/{n}" for k, n in zip(scenes["sequences_with_output"], scenes["scene_sequences"], strict=True)],
                object,
            )
            view = _with_trial(ev, ["suite", "algorithm", "scene", "coverage", "cr", "cr_t", "c_ate_rmse", "cs_r"])
            print(format_table({c: scenes[c] for c in view}, args.digits))
        except LorisError as exc:
            say(f"warning: no scene aggregate: {exc}")
    if table is not None and args.csv:
        out = write_csv(table, args.csv, args.force)
        print(f"\nwrote {len(table)} rows to {out}", file=sys.stderr)
    if table is not None and args.parquet:
        print(f"wrote {len(table)} rows to {write_parquet(table, args.parquet, force=args.force)}", file=sys.stderr)
    if kitti:
        _print_kitti(ev, args)
    if ev.spec.preset_name == "tartanair" and table is not None:  # NaN numbers said, as the KITTI preset's
        from lorisnb.core.metrics.tartanair import tartanair_gaps

        for what, seqs, why in tartanair_gaps(table):
            shown = "; ".join(seqs[:5]) + (f" and {len(seqs) - 5} more" if len(seqs) > 5 else "")
            say(f"note: {len(seqs)} sequence(s) {what} ({shown}): {why}")  # (say escapes the line)
    if getattr(args, "relative", False) or args.relative_lengths:
        with warnings.catch_warnings(record=True) as caught:  # said with the other notes, after the tables
            warnings.simplefilter("always", LorisWarning)
            rel = ev.relative(lengths=args.relative_lengths)
        notes += [str(w.message) for w in caught if issubclass(w.category, LorisWarning)]
        for w in caught:  # any other warning as Python shows it
            if not issubclass(w.category, LorisWarning):
                warnings.showwarning(w.message, w.category, w.filename, w.lineno)
        which = (f"{', '.join(f'{v:g}' for v in args.relative_lengths)} m" if args.relative_lengths
                 else "10..50 % of the length")  # fmt: skip
        print(f"\nrelative error (rpg_trajectory_evaluation: sub-trajectories of {which}; yaw and gravity: its "
              "split of the rotation error, deg):")  # fmt: skip
        print(_fmt(rel.drop(columns=["suite", "trial"]), args.digits) if not rel.empty else "(no sequence long enough)")
        print("\nabsolute error and scale error (rpg_trajectory_evaluation's compute_absolute_error; scale in %):")
        print(_fmt(ev.rpg_absolute().drop(columns=["trial"]), args.digits))
    from lorisnb.tools.evaluation.status import skipped_only

    _report_problems(ev, notes, args)
    unscored = [f for f in ev.unscored if f.kind != "nothing"]  # "nothing was evaluated" is no input: said above
    print(f"{len(ev.errors)} file(s) evaluated, {len(ev.failures)} failed, {len(unscored)} not scored, "
          f"{len(skipped_only(ev))} skipped", file=sys.stderr)  # fmt: skip
    return ev.exit_status()


def _print_kitti(ev: Any, args: argparse.Namespace) -> None:
    """The KITTI devkit's summary over all sequences of each algorithm (the leaderboard's numbers) and
    its per-length errors; the per-length plot with ``--kitti-plot``."""
    totals = ev.kitti_totals()
    if len(totals):  # no table of nothing (every input refused: the errors say why)
        print(f"\nKITTI odometry (devkit, {ev.spec.kitti_precision} precision; every segment of all sequences: "
              "t_err %, r_err deg/100 m):")  # fmt: skip
        print(_fmt(totals, args.digits))
    lengths = ev.kitti_lengths()
    overall = lengths[lengths.seq == ""].drop(columns=["file", "seq"])
    if len(overall):
        print("\nper segment length (all sequences; the devkit plots lengths with at least 3 segments):")
        print(_fmt(overall, args.digits))
    per_seq = lengths[lengths.seq != ""].groupby(["algorithm", "file", "trial", "seq"], sort=False)["segments"].sum()
    short = [f"{file}, seq {seq}" for (_, file, _, seq), n in per_seq.items() if n == 0]
    if short:  # NaN errors said, as a missing RPE pair is
        shown = "; ".join(short[:5]) + (f" and {len(short) - 5} more" if len(short) > 5 else "")
        say(f"note: {len(short)} sequence(s) hold no KITTI segment ({shown}): the devkit measures drift over "
            "100 to 800 m of ground-truth path, and these travel less (or match too few poses); their kitti_t_err and "
            "kitti_r_err are empty, and they add nothing to the totals")  # fmt: skip
    if args.kitti_plot and not len(overall):  # (the figure of no sequence was a traceback)
        say(f"note: --kitti-plot: no sequence was evaluated, so no plot was written to {args.kitti_plot}")
    elif args.kitti_plot:
        from lorisnb.io.writers import write_atomically
        from lorisnb.tools.figures.kitti import kitti_length_figure

        fig = kitti_length_figure(lengths)
        out = write_atomically(args.kitti_plot, lambda p: fig.savefig(p, dpi=150, bbox_inches="tight", format="png"), args.force)  # fmt: skip
        print(f"wrote the per-length plot to {out}", file=sys.stderr)


def _rows_as_columns(rows: list[dict[str, Any]]) -> dict[str, np.ndarray]:
    """Rows of one table (dicts with the same keys) as numpy columns, text as objects."""
    if not rows:
        return {}
    out = {}
    for k in rows[0]:
        values = [r[k] for r in rows]
        kinds = {type(v) for v in values}
        numeric = all(issubclass(t, (int, float, np.number)) and not issubclass(t, (bool, np.bool_)) for t in kinds)
        out[k] = np.array(values) if numeric else np.array(values, object)
    return out


def _sequences_of(ev: Evaluation) -> str:
    """What a sweep's rows are per threshold setting: one per sequence (a file of several ``seq:``
    blocks has several), so the header's factors multiply to its row count."""
    n = sum(len(f.sequences) for f in ev.errors)
    return f"{n} sequence(s) of {len(ev.errors)} file(s)"


def cmd_sweep(args: argparse.Namespace) -> int:
    import pandas as pd

    from lorisnb.core.lifelong.sweep import sweep, sweep_scenes
    from lorisnb.io.writers import write_csv, write_parquet

    refuse_unused(args, UNUSED["sweep"])
    if args.columns == "metrics" and args.relation is None:  # no column of the lean table depends on the RPE
        given_rpe = [f"--{k.replace('_', '-')}" for k in ("rpe_delta", "rpe_unit", "rpe_pairs", "rpe_all_pairs",
                     "rpe_tolerance") if getattr(args, k, None) is not None]  # fmt: skip
        if given_rpe:
            raise ValidationError(f"{given_rpe[0]}: the RPE is in the table of sweep --columns all (or of --relation); the "
                                  "default --columns metrics holds the thresholds' metrics only")  # fmt: skip
    if args.relative_to is not None:  # refused before any file is read, as sweep() would refuse after
        if args.eps is None:
            raise ValidationError(f"--relative-to {args.relative_to}: no --eps to read as fractions of each sequence's "
                                  f"{args.relative_to} (the spec's eps is in metres); give --eps fractions "
                                  "(--eps 0.05,0.1) or leave --relative-to out")  # fmt: skip
        words = [v for v in args.eps if isinstance(v, (str, dict))]
        if words:
            raise ValidationError(f"--eps {words[0]} with --relative-to {args.relative_to}: with --relative-to, --eps "
                                  "values are fractions (numbers), not 'paper' or 'relative:F'")  # fmt: skip
    relative = f" (fractions of each sequence's {args.relative_to})" if args.relative_to is not None else " m"
    units = {"eps": relative, "phi": " deg", "delta": " s", "tau": " s"}

    def swept(spec: Any) -> str:
        """The grid: each threshold's list, or the spec's one value (a manifest's, a preset's)."""
        for k in units:
            if getattr(args, k) is None:
                setattr(args, k, [getattr(spec, k)])
        return "swept " + ", ".join(f"{k} " + ",".join(f"{v:g}" if isinstance(v, float) else str(v) for v in getattr(args, k))
                                    + unit for k, unit in units.items())  # fmt: skip

    ev, notes = _run_evaluation(args, ["csv"], folders=("parquet",), swept=swept)
    # the spec's RPE where a column depends on it (refused above where given and of no use)
    rpe = ev.spec.rpe_options() if args.columns == "all" or ev.spec.relation is not None else {}
    keep_label = args.relative_to is not None or any(isinstance(e, str) for e in args.eps)
    grid = f"{len(args.eps)} eps x {len(args.phi)} phi x {len(args.delta)} delta x {len(args.tau)} tau"
    cols = _with_trial(ev, ["suite", "algorithm", "scene", "eps", "phi", "delta", "tau", "cr", "cr_t", "c_ate_rmse"])
    if keep_label:  # eps as given (a fraction, 'paper'): what tells the rows apart where eps in metres does not
        cols.insert(4, "eps_value")
    if bool(args.parquet) != bool(args.csv):  # one output: streamed, one group of files at a time
        from lorisnb.tools.evaluation.streaming import sweep_to_parquet

        durations = ev.durations()
        shown: list[pd.DataFrame] = []
        scene_rows = 0

        def summarize(part: pd.DataFrame) -> pd.DataFrame:
            nonlocal scene_rows
            scenes = sweep_scenes(part, durations)[cols]
            scene_rows += len(scenes)
            if sum(map(len, shown)) < 60:
                shown.append(scenes.head(60))
            part = part if keep_label else part.drop(columns=["eps_value"])
            part["spec"] = ev.spec.canonical(thresholds=False)
            return part

        path, rows = sweep_to_parquet(
            ev.errors, args.parquet or args.csv, args.eps, args.phi, args.delta, args.tau, relative_to=args.relative_to,
            force=args.force, progress=not args.no_progress, on_part=summarize, relation=ev.spec.relation,
            columns=args.columns, change_unit=ev.spec.change_unit, fmt="parquet" if args.parquet else "csv", **rpe,
        )  # fmt: skip
        print(f"{rows} rows: {_sequences_of(ev)} x {grid}")
        if shown:
            print(_fmt(pd.concat(shown).head(60), args.digits))
            if scene_rows > 60:
                where = "Parquet dataset" if args.parquet else "CSV"
                print(f"... {scene_rows - 60} more scene rows (in the {where}, aggregate with sweep_scenes)")
        print(f"wrote {rows} rows to {path}", file=sys.stderr)
        _report_problems(ev, notes, args)
        return ev.exit_status()
    table = sweep(
        ev.errors, args.eps, args.phi, args.delta, args.tau, relative_to=args.relative_to, columns=args.columns,
        relation=ev.spec.relation, change_unit=ev.spec.change_unit, **rpe,
    )  # fmt: skip
    table["spec"] = ev.spec.canonical(thresholds=False)
    print(f"{len(table)} rows: {_sequences_of(ev)} x {grid}")
    if not table.empty:
        scenes = sweep_scenes(table, ev.durations())
        view = scenes[cols]
        print(_fmt(view.head(60), args.digits))
        if len(view) > 60:
            print(f"... {len(view) - 60} more scene rows (write them all with --csv)")
    written = table if keep_label else table.drop(columns=["eps_value"])  # eps as given, when it differs
    if args.csv:
        print(f"wrote {len(table)} rows to {write_csv(written, args.csv, args.force)}", file=sys.stderr)
    if args.parquet:
        print(f"wrote {len(table)} rows to {write_parquet(written, args.parquet, force=args.force)}", file=sys.stderr)
    _report_problems(ev, notes, args)
    return ev.exit_status()


def cmd_compare(args: argparse.Namespace) -> int:
    """Scene values with bootstrap intervals, the ranking with ties from one permutation test,
    its significant pairs; tables as CSV, LaTeX, Markdown (see :mod:`lorisnb.tools.decisions.comparison`)."""
    import pandas as pd

    from lorisnb.tools.decisions.comparison import compare_table, write_outputs

    rpe = [o for o, v in (("--rpe-delta", args.rpe_delta), ("--rpe-unit", args.rpe_unit), ("--rpe-pairs", args.rpe_pairs),
                          ("--rpe-all-pairs" if args.rpe_all_pairs else "--rpe-consecutive", args.rpe_all_pairs),
                          ("--rpe-tolerance", args.rpe_tolerance)) if v is not None]  # fmt: skip
    if rpe and not args.metric.startswith(("rpe", "c_rpe")):
        raise ValidationError(f"{', '.join(rpe)}: the RPE step changes no value of --metric {args.metric}")
    for name, uses in (("delta", ("cr", "cr_t")), ("tau", ("cs_r",))):  # Eq. 2-3 (delta), Eq. 4 (tau)
        if getattr(args, name, None) is not None and args.metric not in uses:
            raise ValidationError(f"--{name}: changes no value of --metric {args.metric} (it changes "
                                  f"{' and '.join(uses)}); leave it out, or compare {' or '.join(uses)}")  # fmt: skip
    refuse_unused(args, UNUSED["compare"])
    ev, notes = _run_evaluation(args, ["csv", "pairs_csv", "latex", "markdown"], statistics=every_column,
                                poses=tables_only)  # fmt: skip
    table = ev.sequences()
    lacking = 0  # a trial or sequence an algorithm lacks, counted a failed run (Comparison.exit_status)
    if not table.empty:
        res = compare_table(table, ev.durations(), args.metric, level=args.level, alpha=args.alpha,
                            seed=args.seed, power_delta=args.power,
                            lost=[t for f in ev.failures for t in f.trials])  # fmt: skip
        notes += res.notes
        lacking = res.exit_status
        sp = ev.spec
        print(f"thresholds: eps {sp.eps}, phi {sp.phi:g} deg, delta {sp.delta:g} s, tau {sp.tau:g} s")
        print(res.header)
        with pd.option_context("display.max_colwidth", 60):
            print(
                _fmt(
                    res.algorithms[
                        [
                            "suite",
                            "scene",
                            "algorithm",
                            "value [CI]",
                            "covered",
                            "rank",
                            "vs top [test interval]",
                            "tied_with",
                        ]
                    ],
                    args.digits,
                )
            )
        print("\n" + res.summary)
        if len(res.significant):
            print(
                _fmt(
                    res.significant[["scene", "a", "b", "value_a", "value_b", "difference", "p", "p_holm"]], args.digits
                )
            )
        if res.power is not None and len(res.power):
            m = max(len(res.pairs), 1)  # each pair sized at Holm's level for the smallest of the m p-values
            print(f"\nruns needed to detect a difference of {args.power} in {args.metric} (power 0.8, each pair at "
                  f"alpha {args.alpha:g} / {m} pairs = {args.alpha / m:.3g}, the level Holm's correction holds the "
                  "smallest p-value to) where no difference was found:")  # fmt: skip
            sized = res.power[["scene", "a", "b", "unit", "have", "needed"]]
            unknown = res.power["needed"].lt(0)  # -1 in Python: the spread is unknown, no number of runs
            if unknown.any():  # printed as -1, read as "minus one run"
                sized = sized.astype({"needed": object})
                sized.loc[unknown, "needed"] = "unknown"
            print(_fmt(sized, args.digits))
            for r in res.power[unknown].itertuples():
                print(f"needed unknown for {r.scene} {r.a} vs {r.b}: {r.needed_note}")
        elif res.power is not None:
            print(f"\n{res.power_note}")
        for path in write_outputs(res, args.metric, args.csv, args.pairs_csv, args.latex, args.markdown, args.force,
                                  args.alpha):  # fmt: skip
            print(f"wrote {path}", file=sys.stderr)
    _report_problems(ev, notes, args)
    return max(ev.exit_status(), lacking)


def cmd_report(args: argparse.Namespace) -> int:
    from lorisnb.io.datasets.paths import find_data
    from lorisnb.tools.report.build import findings_input_errors, run_report

    params: dict[str, Any] = {}
    for k, v in args.parameter or []:  # a name given twice: refused, as a repeated option is (cli.given_once)
        value = param_value(v, f"-p {k}")
        if k in params and params[k] != value:
            raise ValidationError(f"-p {k} given twice ({params[k]!r}, then {value!r}); the last would "
                                  "silently replace the first: give each parameter once")  # fmt: skip
        params[k] = value
    if (
        args.data
        and params.get("data_root") is not None
        and Path(str(params["data_root"])).resolve() != Path(args.data).resolve()
    ):  # one would silently win, as --results and -p results_dir
        raise ValidationError("--data and -p data_root name two folders; give one")
    if args.data and params.get("data_root") is None:  # -p data_root null is the default: --data names it
        params["data_root"] = args.data
    if args.gate and args.baseline is None:
        raise ValidationError("--gate: judges this run against its baseline; give --baseline DIR too")
    protect = [str(find_data(params.get("data_root")).root)]
    protect += [str(v) for k, v in params.items() if k in ("results_dir", "path", "ordslam_dir") and v]
    wanted = Path(args.out).resolve() if args.out else None
    run_dir, runs = run_report(
        args.out,
        params,
        args.notebooks,
        force=args.force,
        progress=not args.no_progress,
        notebooks_dir=args.notebooks_dir,
        protect=protect,
        results=args.results,
        jobs=args.jobs,
        command=getattr(args, "argv", None),
        label=args.label,
        baseline=args.baseline,
        absolute_paths=args.absolute_paths,
    )
    for r in runs:
        status = (
            r.status
            if r.status != "ok" or not r.input_errors
            else f"ok, {r.input_errors} input file(s) failed or not scored"
        )
        line = f"{r.name:28s} {status:7s} {r.seconds:6.1f} s"
        print(line + (f"  {clean(r.error.splitlines()[0][:150])}" if r.error else ""))
    if wanted is not None and run_dir.resolve() != wanted:
        say(f"note: {args.out} appeared while this report ran (another run?); this run is in {run_dir}")
    failed_inputs = findings_input_errors(run_dir)
    if failed_inputs:
        print(f"leaderboard: {failed_inputs} input file(s) could not be evaluated (listed in index.html)")
    print(f"report: {run_dir / 'index.html'}")
    if args.baseline is not None:  # the baseline chosen by time against the dates the runs' names hold
        _baseline_warnings(run_dir)
    failed = 1 if failed_inputs or any(r.status == "failed" or r.input_errors for r in runs) else 0
    return max(failed, _gate(run_dir)) if args.gate else failed


def _baseline_warnings(run_dir: Path) -> None:
    """``report --baseline``'s warnings on the baseline chosen (``findings/since_baseline.json``'s
    ``warnings``: :func:`lorisnb.tools.decisions.history.last_comparable`), as ``diff`` says them."""
    import json

    f = run_dir / "findings" / "since_baseline.json"
    if f.is_file():
        for w in json.loads(f.read_text(encoding="utf-8")).get("warnings") or []:
            say(f"warning: {w}")


def _gate(run_dir: Path) -> int:
    """``report --gate``: 1 when the run regressed since its baseline (``findings/since_baseline.json``),
    2 when nothing was judged (no comparable earlier run), else 0; the verdict said on stderr. The
    run's files name its own folder ``{run}`` (a portable run, :mod:`lorisnb.tools.report.portable`):
    said here with the folder's path (the gate printed the literal ``{run}`` for the candidate)."""
    import json

    from lorisnb.core.stats.regression import regressed_phrase
    from lorisnb.tools.report.portable import mark

    def shown(text: object) -> str:  # (said by say, which escapes the line once)
        return str(text).replace(mark("run"), str(run_dir))

    since = json.loads((run_dir / "findings" / "since_baseline.json").read_text(encoding="utf-8"))
    if since.get("verdict") is None:
        say(f"gate: nothing judged ({shown(since.get('no_baseline'))}); exit 2, as diff --baseline last-comparable")
        return 2
    v = since["verdict"]
    if v["verdict"] == "regression":
        say(f"gate: regression since the baseline {shown(since['baseline'])} ({shown(regressed_phrase(v))})")
        return 1
    say(f"gate: {v['verdict']} since the baseline {shown(since['baseline'])}")
    return 0


def cmd_verify(args: argparse.Namespace) -> int:
    """Re-check a run's inputs against run.json, and its own files against its marker: exit 1 if
    any changed, is missing, or appeared in a folder the run read or in the run."""
    from lorisnb.tools.report.provenance import (
        NOT_A_FILE,
        read_run_json,
        root_name_problem,
        roots_used,
        run_folder,
        unchecked_baseline,
        verify_run,
    )

    record = read_run_json(args.run)
    run_dir = run_folder(args.run)  # RUN may be its run.json
    roots: dict[str, str] = {}
    used = roots_used(record)
    for name, folder in args.root or []:  # a name twice: the last silently won
        problem = root_name_problem(name)
        if problem:
            raise ValidationError(f"--root {name!r} {folder}: {problem}")
        if name not in used:  # read all the same: a folder a link of the run's folders leads into
            names = ", ".join(f"{{{n}}}" for n in sorted(used)) or "none"
            print(f"note: --root {clean(name)}: the run names no root {{{clean(name)}}} (its roots: {names}); its "
                  "folder is read only where a link in the run's folders leads into it", file=sys.stderr)  # fmt: skip
        if name in roots and Path(roots[name]).resolve() != Path(folder).resolve():
            raise ValidationError(f"--root {name} given twice ({roots[name]}, then {folder}); give each root once")
        roots[name] = folder
    for name in ("data", "results"):
        folder = getattr(args, name)
        if folder is not None:
            if roots.get(name, folder) != folder:
                raise ValidationError(f"--{name} {folder} and --root {name} {roots[name]} name two folders; give one")
            roots[name] = folder
    problems = verify_run(args.run, roots)
    from lorisnb.tools.report.build import missing_run_files, not_as_written

    edited = not_as_written(run_dir)  # the run's own files against its marker, as render checks them
    gone = set(missing_run_files(run_dir))
    for path, what in problems:
        print(f"{what}: {clean(path)}")
    for rel in edited or []:
        print(f"{'missing' if rel in gone else 'edited'}: {clean(run_dir / rel)}")
    if edited is None:
        print("note: the run's marker lists no files (a run of an earlier lorisnb): its own files are not checked",
              file=sys.stderr)  # fmt: skip
    n = len(record["inputs"])
    skipped = unchecked_baseline(record, roots)
    if skipped:
        print(f"note: {skipped} file(s) of the earlier run this run's verdict was made against (report --baseline) "
              "are not checked: give its folder of earlier runs with --root baseline DIR", file=sys.stderr)  # fmt: skip
    else:
        n += len(record.get("baseline_inputs") or {})
    if "input_roots" not in record:
        print("note: run.json has no input_roots (a run of an earlier lorisnb): files added to the folders it read "
              "are not noticed; only its inputs are checked", file=sys.stderr)  # fmt: skip
    if edited:
        print(f"{len(edited)} file(s) of the run itself added, changed or removed since it was written (its pages, "
              "tables or figures are not what its run wrote)", file=sys.stderr)  # fmt: skip
    if problems:
        added = sum(what == "added" for _, what in problems)
        outside = sum(what == "outside" for _, what in problems)
        odd = sum(what == NOT_A_FILE for _, what in problems)
        changed = len(problems) - added - outside - odd
        said = [f"{changed} of {n} input file(s) changed or missing since the run"] if changed else []
        said += [f"{added} file(s) added to the folders it read"] if added else []
        said += [f"{odd} file(s) in the folders it read are not regular files (a FIFO, a device): not read; a "
                 "folder of inputs holds none"] if odd else []  # fmt: skip
        said += [f"{outside} file(s) or folder(s) lead (links) outside the run folder and the roots given here: not "
                 "read; to check them, name the folder they lead to with --root NAME DIR"] if outside else []  # fmt: skip
        print("; ".join(said), file=sys.stderr)
        return 1
    print(f"all {n} input file(s) unchanged", file=sys.stderr)
    return 1 if edited else 0


def cmd_render(args: argparse.Namespace) -> int:
    """Render a run folder's pages again from its own files."""
    from lorisnb.tools.report.build import render_run

    for page in render_run(args.run):
        print(f"wrote {clean(page)}")
    return 0


#: The helpers other command modules (:mod:`lorisnb.cli.runs`) share with these commands.
run_evaluation, report_problems, fmt_table = _run_evaluation, _report_problems, _fmt
