"""The commands: ``evaluate``, ``sweep``, ``compare``, ``crosscheck``, ``report``. Tables go to stdout,
warnings and failures to stderr; the exit status is non-zero when any input failed."""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..core.association import MAX_GAP
from ..errors import LorisError, LorisWarning, ValidationError
from .options import check_output, conventions_of, param_value

if TYPE_CHECKING:  # pandas is imported by the commands that print tables (not by --help)
    import pandas as pd


def _run_evaluation(args: argparse.Namespace) -> tuple[Any, list[str]]:
    from ..tools.evaluate import evaluate

    if getattr(args, "gt", None) or getattr(args, "manifest", None):
        return _run_pairs(args)
    pair_only = [
        f"--{k.replace('_', '-')}"
        for k in ("format", "gt_format", "conventions", "association", "max_diff", "t_offset", "align", "align_frames",
                  "topic", "gt_topic", "tf", "gt_tf", "gt_times", "est_times", "scene")
        if getattr(args, k, None) is not None
    ]  # fmt: skip
    if pair_only:
        raise ValidationError(
            f"{', '.join(pair_only)}: for estimates scored against --gt or a --manifest; OpenLORIS result files "
            "use the official conventions (choose --max-gap, --scale, --per-seq or --lifelong)"
        )

    executor = None
    if args.scheduler:
        from ..tools import require

        try:
            client = require("distributed").Client(args.scheduler, timeout=10)
        except (OSError, TimeoutError) as exc:
            raise LorisError(f"--scheduler {args.scheduler}: cannot reach the Dask scheduler ({exc})") from None
        executor = client.get_executor()

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        ev = evaluate(
            args.paths,
            mode=args.mode,
            scale=args.scale,
            official_interpolation=args.official_interpolation,
            remove_repeated=not args.keep_repeated,
            data_root=args.data,
            repair_stamps=args.repair_stamps,
            max_gap=args.max_gap if getattr(args, "max_gap", None) is not None else MAX_GAP,
            trials_by=args.trials_by,
            jobs=args.jobs,
            executor=executor,
            progress=not args.no_progress,
        )
    notes = list(dict.fromkeys(ev.warnings + [str(w.message) for w in caught]))
    return ev, notes


def _run_pairs(args: argparse.Namespace) -> tuple[Any, list[str]]:
    """``--gt`` (plain pairs) or ``--manifest`` (sessions): lorisnb.tools.pairs."""
    from ..io.manifest import read_manifest
    from ..tools.pairs import evaluate_manifest, evaluate_pairs

    if args.gt and args.manifest:
        raise ValidationError("--gt and --manifest: give one (a manifest names the ground truth of each session)")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        if args.gt:
            ev = evaluate_pairs(
                args.paths, args.gt, fmt=args.format or "tum", gt_fmt=args.gt_format,
                conventions=conventions_of(args), scene=args.scene, est_times=args.est_times,
                gt_times=args.gt_times, topic=args.topic, gt_topic=args.gt_topic, tf=args.tf, gt_tf=args.gt_tf,
                trials_by=args.trials_by, progress=not args.no_progress,
            )  # fmt: skip
        else:
            m = read_manifest(args.manifest)
            if m.openloris:
                return _run_evaluation(argparse.Namespace(**{**vars(args), "manifest": None}))
            lifelong = None if args.mode == "auto" else args.mode == "lifelong"
            ev = evaluate_manifest(
                m, args.paths, conventions=conventions_of(args, m.conventions), lifelong=lifelong,
                trials_by=args.trials_by, progress=not args.no_progress,
            )  # fmt: skip
    notes = list(dict.fromkeys(ev.warnings + [str(w.message) for w in caught]))
    print(f"conventions: {ev.conventions}", file=sys.stderr)
    return ev, notes


def _thresholds(args: argparse.Namespace, ev: Any) -> tuple[Any, Any]:
    """--eps and --phi as given, else the manifest's, else the command's defaults."""
    defaults = getattr(ev, "thresholds", {}) or {}
    eps = args.eps if args.eps is not None else defaults.get("eps", args.eps_default)
    phi = args.phi if args.phi is not None else defaults.get("phi", args.phi_default)
    return eps, phi


def _report_problems(ev: Any, notes: list[str]) -> None:
    for n in notes:
        print(f"warning: {n}", file=sys.stderr)
    for f in ev.failures:
        print(f"error: {f.error}", file=sys.stderr)
    if ev.skipped:
        reasons = sorted({f.error.split(":")[0] for f in ev.skipped})
        print(f"skipped {len(ev.skipped)} file(s): " + "; ".join(reasons), file=sys.stderr)


def _fmt(df: pd.DataFrame) -> str:
    import pandas as pd

    with pd.option_context("display.max_rows", 500, "display.width", 200, "display.max_columns", 30):
        return df.to_string(index=False, float_format=lambda v: f"{v:.4f}")


def cmd_evaluate(args: argparse.Namespace) -> int:
    from ..core.aggregate import aggregate_scenes
    from ..core.scoring import score
    from ..io.writers import write_csv, write_parquet

    check_output(args.csv, args.paths, args.force)
    check_output(args.parquet, args.paths, args.force, folder=True)
    ev, notes = _run_evaluation(args)
    eps, phi = _thresholds(args, ev)
    table = score(ev.errors, eps, phi, args.delta, args.tau)
    if not table.empty:
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
        print(_fmt(table[cols]))
        try:
            scenes = aggregate_scenes(table, ev.durations())
            print("\nper scene (CR over all ground-truth time of the scene; C-ATE RMSE weighted by correct poses):")
            print(_fmt(scenes[["suite", "algorithm", "scene", "sequences", "cr", "cr_t", "c_ate_rmse", "cs_r_mean"]]))
        except LorisError as exc:
            print(f"warning: no scene aggregate: {exc}", file=sys.stderr)
    if args.csv:
        out = write_csv(table, args.csv, args.force)
        print(f"\nwrote {len(table)} rows to {out}", file=sys.stderr)
    if args.parquet:
        print(f"wrote {len(table)} rows to {write_parquet(table, args.parquet, force=args.force)}", file=sys.stderr)
    if getattr(args, "relative", False):
        rel = ev.relative()
        print("\nrelative error (rpg_trajectory_evaluation: sub-trajectories of 10..50 % of the length):")
        print(_fmt(rel.drop(columns=["suite", "trial"])) if not rel.empty else "(no sequence long enough)")
    _report_problems(ev, notes)
    print(f"{len(ev.errors)} file(s) evaluated, {len(ev.failures)} failed, {len(ev.skipped)} skipped", file=sys.stderr)
    return 1 if ev.failures else 0


def cmd_sweep(args: argparse.Namespace) -> int:
    import pandas as pd

    from ..core.sweep import sweep, sweep_scenes
    from ..io.writers import write_csv, write_parquet

    check_output(args.csv, args.paths, args.force)
    check_output(args.parquet, args.paths, args.force, folder=True)
    ev, notes = _run_evaluation(args)
    keep_label = args.relative_to is not None or any(isinstance(e, str) for e in args.eps)
    grid = f"{len(args.eps)} eps x {len(args.phi)} phi x {len(args.delta)} delta x {len(args.tau)} tau"
    cols = ["suite", "algorithm", "scene", "eps", "phi", "delta", "tau", "cr", "cr_t", "c_ate_rmse"]
    if args.parquet and not args.csv:  # streamed, one group of files at a time: any grid size
        from ..tools.streaming import sweep_to_parquet

        durations = ev.durations()
        shown: list[pd.DataFrame] = []
        scene_rows = 0

        def summarize(part: pd.DataFrame) -> pd.DataFrame:
            nonlocal scene_rows
            scenes = sweep_scenes(part, durations)[cols]
            scene_rows += len(scenes)
            if sum(map(len, shown)) < 60:
                shown.append(scenes.head(60))
            return part if keep_label else part.drop(columns=["eps_value"])

        path, rows = sweep_to_parquet(
            ev.errors, args.parquet, args.eps, args.phi, args.delta, args.tau, relative_to=args.relative_to,
            force=args.force, progress=not args.no_progress, on_part=summarize,
        )  # fmt: skip
        print(f"{rows} rows: {len(ev.errors)} file(s) x {grid}")
        if shown:
            print(_fmt(pd.concat(shown).head(60)))
            if scene_rows > 60:
                print(f"... {scene_rows - 60} more scene rows (in the Parquet dataset, aggregate with sweep_scenes)")
        print(f"wrote {rows} rows to {path}", file=sys.stderr)
        _report_problems(ev, notes)
        return 1 if ev.failures else 0
    table = sweep(ev.errors, args.eps, args.phi, args.delta, args.tau, relative_to=args.relative_to, columns="all")
    print(f"{len(table)} rows: {len(ev.errors)} file(s) x {grid}")
    if not table.empty:
        scenes = sweep_scenes(table, ev.durations())
        view = scenes[cols]
        print(_fmt(view.head(60)))
        if len(view) > 60:
            print(f"... {len(view) - 60} more scene rows (write them all with --csv)")
    written = table if keep_label else table.drop(columns=["eps_value"])  # eps as given, when it differs
    if args.csv:
        print(f"wrote {len(table)} rows to {write_csv(written, args.csv, args.force)}", file=sys.stderr)
    if args.parquet:
        print(f"wrote {len(table)} rows to {write_parquet(written, args.parquet, force=args.force)}", file=sys.stderr)
    _report_problems(ev, notes)
    return 1 if ev.failures else 0


def cmd_compare(args: argparse.Namespace) -> int:
    """Scene values with bootstrap intervals, the ranking with ties the data cannot separate,
    significant pairwise differences; tables as CSV, LaTeX, Markdown."""
    import pandas as pd

    from ..core import ranking, stats
    from ..io.writers import write_csv
    from ..tools.tables import interval, write_comparison

    for out in (args.csv, args.latex, args.markdown):
        check_output(out, args.paths, args.force)
    ev, notes = _run_evaluation(args)
    eps, phi = _thresholds(args, ev)
    table = ev.sequences(eps, phi, args.delta, args.tau)
    if not table.empty:
        ci = stats.confidence_intervals(table, level=args.level, seed=args.seed)
        rank = ranking.ranking(table, args.metric, alpha=args.alpha, seed=args.seed)
        c = ci[ci["metric"] == args.metric].set_index(["suite", "scene", "algorithm"])
        cells = c.loc[list(zip(rank["suite"], rank["scene"], rank["algorithm"], strict=True))]
        rank["value [CI]"] = [
            interval(v, lo, hi, digits=3) for v, lo, hi in zip(cells["value"], cells["low"], cells["high"], strict=True)
        ]
        n_trials = table.groupby(["algorithm", "scene"])["trial"].nunique().max()
        units = ", ".join(sorted(set(ci["unit"])))
        print(f"{args.metric} per algorithm and scene, {args.level:.0%} bootstrap intervals over {units} "
              f"(up to {n_trials} trial(s)); rank = 1 + algorithms significantly better (Wilcoxon, Holm, "
              f"alpha {args.alpha}):")  # fmt: skip
        with pd.option_context("display.max_colwidth", 50):
            print(_fmt(rank[["suite", "scene", "algorithm", "value [CI]", "rank", "tied_with"]]))
        pairs = stats.pairwise(table, args.metric, alpha=args.alpha, seed=args.seed)
        sig = pairs[pairs["significant"]]
        print(f"\n{len(sig)} of {len(pairs)} pairs differ significantly" + (":" if len(sig) else "."))
        if len(sig):
            print(_fmt(sig[["scene", "a", "b", "value_a", "value_b", "p_a_better", "p_holm"]]))
        if args.csv:
            print(f"wrote {write_csv(ci, args.csv, args.force)}", file=sys.stderr)
        for out in (args.latex, args.markdown):
            if out:
                print(f"wrote {write_comparison(ci, args.metric, out, args.force)}", file=sys.stderr)
    _report_problems(ev, notes)
    return 1 if ev.failures else 0


def cmd_crosscheck(args: argparse.Namespace) -> int:
    import pandas as pd

    from ..io.formats import read_trajectory
    from ..io.openloris import read_openloris
    from ..io.writers import write_csv
    from ..tools.crosscheck import crosscheck, crosscheck_openloris

    check_output(args.csv, [args.gt, args.est], args.force)
    deltas = [(int(args.rpe_frames), "f"), (float(args.rpe_metres), "m")]
    gt_format = args.format
    est_format = args.est_format or ("tum" if args.format == "euroc" else args.format)
    if args.format == "openloris":
        gt_file = read_openloris(args.gt) if args.gt not in ("-", "auto") else None
        table = crosscheck_openloris(
            args.est, args.seq, scale=args.scale, data_root=args.data, groundtruth=gt_file, rpe_deltas=deltas
        )
    else:
        gt_times, est_times = args.gt_times or args.times, args.est_times or args.times
        by_index = "kitti" in (gt_format, est_format) and (gt_times is None or est_times is None)
        if by_index and (gt_format != est_format or gt_times is not None or est_times is not None):
            raise ValidationError(
                "--gt-times and --est-times: a KITTI file has no stamps; give stamps for both files (or for "
                "neither, to pair two KITTI files of equal length by index)"
            )
        gt = read_trajectory(args.gt, gt_format, stamps=gt_times if gt_format == "kitti" else None)
        est = read_trajectory(args.est, est_format, stamps=est_times if est_format == "kitti" else None)
        table = crosscheck(
            gt, est, scale=bool(args.scale), by_index=by_index, rpe_deltas=deltas, all_pairs=args.all_pairs
        )
    from ..tools import require

    evo_version = require("evo").__version__

    with pd.option_context("display.max_rows", 200, "display.width", 220, "display.max_colwidth", 110):
        print(table.to_string(index=False, float_format=lambda v: f"{v:.6g}"))
    must = table["note"].str.startswith("identical pairs")
    print(
        f"\nevo {evo_version}: {int(table.loc[must, 'agrees'].sum())} of {int(must.sum())} quantities computed "
        "on identical pairs agree; other rows explain where the definitions differ",
        file=sys.stderr,
    )
    if args.csv:
        write_csv(table, args.csv, args.force)
    return 0 if table.loc[must, "agrees"].all() else 1


def cmd_report(args: argparse.Namespace) -> int:
    from ..io.data import find_data
    from ..tools.report import run_report

    params = {k: param_value(v) for k, v in (args.parameter or [])}
    if args.data and "data_root" not in params:
        params["data_root"] = args.data
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
    )
    for r in runs:
        status = r.status if r.status != "ok" or not r.input_errors else f"ok, {r.input_errors} input file(s) failed"
        line = f"{r.name:28s} {status:7s} {r.seconds:6.1f} s"
        print(line + (f"  {r.error.splitlines()[0][:150]}" if r.error else ""))
    if wanted is not None and run_dir.resolve() != wanted:
        print(
            f"note: {args.out} appeared while this report ran (another run?); this run is in {run_dir}", file=sys.stderr
        )
    print(f"report: {run_dir / 'index.html'}")
    return 1 if any(r.status == "failed" or r.input_errors for r in runs) else 0
