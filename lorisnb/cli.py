"""The ``lorisnb`` command line.

The command line is where lorisnb reports: tables on stdout, warnings and failures on stderr,
a non-zero exit status when any input failed.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from .errors import LorisError, LorisWarning


def parse_threshold(text: str, allow_paper: bool = False) -> float | str:
    """A threshold from the command line: a number, ``inf`` or (for eps) ``paper``."""
    t = text.strip().lower()
    if allow_paper and t == "paper":
        return "paper"
    try:
        v = float(t)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a threshold; expected a number, 'inf'" + (" or 'paper'" if allow_paper else "")
        ) from None
    if math.isnan(v) or v < 0:
        raise argparse.ArgumentTypeError(f"{text!r}: a threshold must be >= 0")
    return v


def parse_list(text: str, allow_paper: bool = False) -> list:
    """A comma-separated list of thresholds (``1,2,inf``; ``paper`` for eps)."""
    return [parse_threshold(p, allow_paper) for p in text.split(",") if p.strip()]


def parse_scale(text: str) -> bool | str:
    t = text.lower()
    if t in ("auto",):
        return "auto"
    if t in ("on", "yes", "true", "1", "sim3"):
        return True
    if t in ("off", "no", "false", "0", "se3"):
        return False
    raise argparse.ArgumentTypeError(f"{text!r}: expected auto, on or off")


def add_evaluation_options(p: argparse.ArgumentParser) -> None:
    """Options shared by ``evaluate`` and ``sweep`` (same names, same meaning)."""
    p.add_argument("paths", nargs="+", metavar="FILE_OR_DIR",
                   help="result files, or folders walked as <algorithm>/*.txt")
    p.add_argument("--scale", nargs="?", const=True, default=False, type=parse_scale,
                   help="align with Sim(3) (scale); 'auto': only for monocular algorithms (dso, svo)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--per-seq", dest="mode", action="store_const", const="per-seq",
                   help="align every sequence on itself")
    g.add_argument("--lifelong", dest="mode", action="store_const", const="lifelong",
                   help="align on the first sequence and apply that to all (default for files "
                        "with several seq: blocks)")
    p.set_defaults(mode="auto")
    p.add_argument("--official-interpolation", action="store_true",
                   help="reproduce the official tool's orientation slips (AOE only)")
    p.add_argument("--repair-stamps", action="store_true",
                   help="read stamps written as nanoseconds without zero padding as such (off: as the official tool)")
    p.add_argument("--keep-repeated", action="store_true",
                   help="keep poses identical to the previous one (the official tool drops them)")
    p.add_argument("--data", default=None, metavar="DIR",
                   help="data root (default: $LORISNB_DATA, else ../shared/data next to the project)")
    p.add_argument("--csv", default=None, metavar="OUT", help="write one row per sequence to this CSV")
    p.add_argument("--force", action="store_true", help="overwrite OUT if it exists")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def _run_evaluation(args):
    from .evaluation import evaluate

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        ev = evaluate(args.paths, mode=args.mode, scale=args.scale,
                      official_interpolation=args.official_interpolation,
                      remove_repeated=not args.keep_repeated, data_root=args.data,
                      repair_stamps=args.repair_stamps, progress=not args.no_progress)
    notes = list(dict.fromkeys(ev.warnings + [str(w.message) for w in caught]))
    return ev, notes


def write_csv_safely(df: pd.DataFrame, out: str | os.PathLike, force: bool = False) -> Path:
    """Write a CSV through a temporary name and move it into place; refuse to replace an existing
    file unless ``force``."""
    out = Path(out)
    if out.exists() and not force:
        raise LorisError(f"{out} exists; choose another name or pass --force to replace it")
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.tmp-{os.getpid()}")
    df.to_csv(tmp, index=False)
    os.replace(tmp, out)
    return out


def _report_problems(ev, notes: list[str]) -> None:
    for n in notes:
        print(f"warning: {n}", file=sys.stderr)
    for f in ev.failures:
        print(f"error: {f.error}", file=sys.stderr)
    if ev.skipped:
        reasons = sorted({f.error.split(":")[0] for f in ev.skipped})
        print(f"skipped {len(ev.skipped)} file(s): " + "; ".join(reasons), file=sys.stderr)


def _fmt(df: pd.DataFrame) -> str:
    with pd.option_context("display.max_rows", 500, "display.width", 200, "display.max_columns", 30):
        return df.to_string(index=False, float_format=lambda v: f"{v:.4f}")


def cmd_evaluate(args) -> int:
    from .evaluation import aggregate_scenes, score

    ev, notes = _run_evaluation(args)
    table = score(ev.errors, args.eps, args.phi, args.delta, args.tau)
    if not table.empty:
        cols = ["algorithm", "file", "seq", "poses", "matched", "ate_rmse", "c_ate_rmse", "aoe_rmse",
                "cr", "cr_t", "cs_r"]
        print(_fmt(table[cols]))
        try:
            scenes = aggregate_scenes(table, data_root=args.data)
            print("\nper scene (CR over all ground-truth time of the scene; C-ATE RMSE weighted by "
                  "correct poses):")
            print(_fmt(scenes[["suite", "algorithm", "scene", "sequences", "cr", "cr_t", "c_ate_rmse",
                               "cs_r_mean"]]))
        except LorisError as exc:
            print(f"warning: no scene aggregate: {exc}", file=sys.stderr)
    if args.csv:
        out = write_csv_safely(table, args.csv, args.force)
        print(f"\nwrote {len(table)} rows to {out}", file=sys.stderr)
    _report_problems(ev, notes)
    print(f"{len(ev.errors)} file(s) evaluated, {len(ev.failures)} failed, {len(ev.skipped)} skipped",
          file=sys.stderr)
    return 1 if ev.failures else 0


def cmd_sweep(args) -> int:
    from .sweep import sweep, sweep_scenes

    ev, notes = _run_evaluation(args)
    table = sweep(ev.errors, args.eps, args.phi, args.delta, args.tau, relative_to=args.relative_to,
                  columns="all")
    print(f"{len(table)} rows: {len(ev.errors)} file(s) x {len(args.eps)} eps x {len(args.phi)} phi x "
          f"{len(args.delta)} delta x {len(args.tau)} tau")
    if not table.empty:
        scenes = sweep_scenes(table, data_root=args.data)
        view = scenes[["suite", "algorithm", "scene", "eps", "phi", "delta", "tau", "cr", "cr_t", "c_ate_rmse"]]
        print(_fmt(view.head(60)))
        if len(view) > 60:
            print(f"... {len(view) - 60} more scene rows (write them all with --csv)")
    if args.csv:
        keep_label = args.relative_to is not None or any(isinstance(e, str) for e in args.eps)
        out = write_csv_safely(table if keep_label else table.drop(columns=["eps_value"]), args.csv, args.force)
        print(f"wrote {len(table)} rows to {out}", file=sys.stderr)
    _report_problems(ev, notes)
    return 1 if ev.failures else 0


def cmd_crosscheck(args) -> int:
    from .evo_bridge import crosscheck, crosscheck_openloris
    from .readers import read_openloris, read_trajectory

    deltas = [(int(args.rpe_frames), "f"), (float(args.rpe_metres), "m")]
    if args.format == "openloris":
        gt = read_openloris(args.gt) if args.gt not in ("-", "auto") else None
        table = crosscheck_openloris(args.est, args.seq, scale=args.scale, data_root=args.data, groundtruth=gt,
                                     rpe_deltas=deltas)
    else:
        by_index = args.format == "kitti" and args.times is None
        gt = read_trajectory(args.gt, args.format, stamps=args.times)
        est = read_trajectory(args.est, args.format, stamps=args.times)
        table = crosscheck(gt, est, scale=bool(args.scale), by_index=by_index, rpe_deltas=deltas,
                           all_pairs=args.all_pairs)
    from evo import __version__ as evo_version

    with pd.option_context("display.max_rows", 200, "display.width", 220, "display.max_colwidth", 110):
        print(table.to_string(index=False, float_format=lambda v: f"{v:.6g}"))
    must = table["note"].str.startswith("identical pairs")
    print(f"\nevo {evo_version}: {int(table.loc[must, 'agrees'].sum())} of {int(must.sum())} quantities computed "
          "on identical pairs agree; other rows explain where the definitions differ", file=sys.stderr)
    if args.csv:
        write_csv_safely(table, args.csv, args.force)
    return 0 if table.loc[must, "agrees"].all() else 1


def _param_value(text: str):
    """A -p value: JSON when it parses (numbers, true/false, null, lists), else the string."""
    import json

    low = text.strip().lower()
    if low in ("inf", "+inf", "infinity"):
        return float("inf")
    try:
        return json.loads(text)
    except ValueError:
        return text


def cmd_report(args) -> int:
    from .report import run_report

    params = {k: _param_value(v) for k, v in (args.parameter or [])}
    if args.data and "data_root" not in params:
        params["data_root"] = args.data
    run_dir, runs = run_report(args.out, params, args.notebooks, force=args.force,
                               progress=not args.no_progress)
    for r in runs:
        line = f"{r.name:28s} {r.status:7s} {r.seconds:6.1f} s"
        print(line + (f"  {r.error.splitlines()[0][:150]}" if r.error else ""))
    print(f"report: {run_dir / 'index.html'}")
    return 1 if any(r.status != "ok" for r in runs) else 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="lorisnb", description="Lifelong SLAM evaluation (OpenLORIS-Scene metrics)")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("evaluate", help="score result files: ATE, AOE, CR, CR-T, CS-R, C-ATE, RPE")
    add_evaluation_options(p)
    p.add_argument("--eps", type=lambda s: parse_threshold(s, True), default=np.inf,
                   help="ATE threshold in metres, 'inf' or 'paper' (1/3/5 m by scene); default inf")
    p.add_argument("--phi", type=parse_threshold, default=np.inf, help="AOE threshold in degrees; default inf")
    p.add_argument("--delta", type=parse_threshold, default=1.0, help="validity window of a pose, s; default 1")
    p.add_argument("--tau", type=parse_threshold, default=60.0, help="re-localization time factor, s; default 60")
    p.set_defaults(func=cmd_evaluate)

    p = sub.add_parser("sweep", help="every metric over grids of eps, phi, delta and tau (one row per sequence and setting)")
    add_evaluation_options(p)
    p.add_argument("--eps", type=lambda s: parse_list(s, True), default=[np.inf],
                   help="comma-separated ATE thresholds in metres ('inf', 'paper' allowed)")
    p.add_argument("--phi", type=parse_list, default=[np.inf], help="comma-separated AOE thresholds, degrees")
    p.add_argument("--delta", type=parse_list, default=[1.0], help="comma-separated validity windows, s")
    p.add_argument("--tau", type=parse_list, default=[60.0], help="comma-separated re-localization factors, s")
    p.add_argument("--relative-to", choices=["extent", "length"], default=None,
                   help="read --eps as fractions of each sequence's ground-truth extent or length")
    p.set_defaults(func=cmd_sweep)

    p = sub.add_parser("crosscheck", help="compare lorisnb with evo on one ground truth and one estimate")
    p.add_argument("gt", help="ground truth (for --format openloris: gt_<scene>_1.txt, or 'auto' to find it)")
    p.add_argument("est", help="estimate")
    p.add_argument("--format", choices=["tum", "kitti", "euroc", "openloris"], default="tum")
    p.add_argument("--scale", nargs="?", const=True, default=False, type=parse_scale,
                   help="Sim(3) for the RPE and association rows ('auto' for openloris: by algorithm)")
    p.add_argument("--times", default=None, help="KITTI: times file (one stamp per line) for both files; "
                   "without it poses are paired by index, as evo does")
    p.add_argument("--seq", type=int, default=None, help="openloris: the sequence (default: the first with poses)")
    p.add_argument("--rpe-frames", type=int, default=1, help="RPE delta in frames (default 1)")
    p.add_argument("--rpe-metres", type=float, default=1.0, help="RPE delta in metres (default 1)")
    p.add_argument("--all-pairs", action="store_true", help="RPE over all pairs (evo's default: consecutive)")
    p.add_argument("--data", default=None, metavar="DIR")
    p.add_argument("--csv", default=None, metavar="OUT")
    p.add_argument("--force", action="store_true")
    p.set_defaults(func=cmd_crosscheck)

    p = sub.add_parser("report", help="run the notebooks with papermill into a report folder under results/")
    p.add_argument("--out", default=None, help="run folder (default results/run-<date>-<time>)")
    p.add_argument("-p", "--parameter", nargs=2, action="append", metavar=("NAME", "VALUE"),
                   help="notebook parameter (repeatable); VALUE is JSON if it parses, else a string")
    p.add_argument("--notebooks", nargs="+", default=None, help="notebooks to run (default: all, in report order)")
    p.add_argument("--data", default=None, metavar="DIR", help="data root passed to the notebooks as data_root")
    p.add_argument("--force", action="store_true", help="replace --out if it exists")
    p.add_argument("--no-progress", action="store_true")
    p.set_defaults(func=cmd_report)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except LorisError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
