"""The ``crosscheck`` command: lorisnb against evo on one ground truth and one estimate (the
agreement table on identical pairs, evo's own reading of each file, or a preset against evo). An
input that cannot be read or compared is exit status 1, as for every command. With
``--conventions``, a difference that a row's note explains by a stated definition (the preset's
conventions are not evo's, or evo has no such quantity) is listed and is exit status 0; only an
unexplained disagreement is 1."""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import pandas as pd

from lorisnb.cli.outputs import check_outputs
from lorisnb.cli.text import format_advice, say
from lorisnb.core.spec.evalspec import EvalSpec, make_spec
from lorisnb.core.trajectory.units import check_stamp_units
from lorisnb.errors import EvaluationError, LorisWarning, ParseError, ValidationError


def cmd_crosscheck(args: argparse.Namespace) -> int:
    from lorisnb.io.writers import write_csv

    check_outputs(args, [args.gt, args.est], ["csv"])
    try:
        with warnings.catch_warnings(record=True) as caught:  # printed as every command prints them
            warnings.simplefilter("always", LorisWarning)
            table = _crosscheck_table(args)
    except (ParseError, EvaluationError) as exc:  # an input that cannot be read or compared: 1, as every command
        say(f"error: {format_advice(str(exc), '--est-format {fmt}', '--format {fmt}', [args.gt])}")  # its options
        return 1
    finally:
        for n in dict.fromkeys(str(w.message) for w in caught if issubclass(w.category, LorisWarning)):
            say(f"warning: {n}")
    if isinstance(table, int):  # --conventions: printed and judged there
        return table
    from lorisnb.tools import require

    evo_version = require("evo").__version__

    if table.attrs.get("compared"):  # an OpenLORIS file holds sequences: which one was compared
        print(f"compared: {table.attrs['compared']}")
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
    return 0 if table.loc[must, "agrees"].all() and not _no_pairs(table) else 1


def _no_pairs(table: pd.DataFrame) -> int:
    """Rows not compared because a delta gave no RPE pair: said on stderr (they make the exit status 1:
    not everything asked was compared)."""
    from lorisnb.tools.peers.evo_bridge import NO_RPE_PAIR

    n = int(table["note"].str.startswith(NO_RPE_PAIR).sum())
    if n:
        print(f"{n} RPE quantit{'y' if n == 1 else 'ies'} not compared: {NO_RPE_PAIR} at the delta asked "
              "(see their notes; give a smaller delta)", file=sys.stderr)  # fmt: skip
    return n


def _crosscheck_table(args: argparse.Namespace) -> pd.DataFrame | int:
    """The agreement table of ``crosscheck`` (reads both inputs); with ``--conventions``, that
    comparison's exit status (it prints its own table)."""
    from lorisnb.io.readers.openloris import read_openloris
    from lorisnb.io.readers.plain import read_trajectory
    from lorisnb.tools.peers.crosscheck import crosscheck, crosscheck_openloris

    openloris = args.format == "openloris"
    times = [
        o for o, v in (("--times", args.times), ("--gt-times", args.gt_times), ("--est-times", args.est_times)) if v
    ]
    kitti = "kitti" in (args.format, args.est_format)
    refused = [o for o, v in (("--seq", args.seq), ("--data", args.data)) if v is not None and not openloris]
    refused += [o for o, v in (("--est-format", args.est_format),) if v is not None and openloris]
    refused += times if not kitti else []
    bag = "bag" in (args.format, args.est_format)
    refused += [o for o, v in (("--topic", args.topic), ("--gt-topic", args.gt_topic)) if v is not None and not bag]
    if refused:
        raise ValidationError(
            f"{', '.join(refused)}: does not apply to --format {args.format}"
            + (f" with --est-format {args.est_format}" if args.est_format else "")
            + " (--seq and --data: OpenLORIS files; --est-format: TUM/KITTI/EuRoC pairs; times files: KITTI;"
            " topics: bags)"
        )
    if args.align is not None and args.conventions is None:
        raise ValidationError("--align: only with --conventions (the crosscheck's own rows use none, se3 and sim3)")
    deltas = [(int(args.rpe_frames or 1), "f"), (float(args.rpe_metres or 1.0), "m")]
    gt_format = args.format
    est_format = args.est_format or ("tum" if args.format == "euroc" else args.format)
    if args.conventions is not None:
        return _crosscheck_conventions(args, gt_format, est_format)
    if args.gt == "auto" and args.format != "openloris":
        raise ValidationError("GT 'auto' (the data root's ground truth of the estimate's scene) is for OpenLORIS "
                              "result files: add --format openloris, or give the ground-truth file")  # fmt: skip
    if args.format == "openloris":
        gt_file = read_openloris(args.gt) if args.gt not in ("-", "auto") else None
        table = crosscheck_openloris(
            args.est,
            args.seq,
            scale=False if args.scale is None else args.scale,
            data_root=args.data,
            groundtruth=gt_file,
            rpe_deltas=deltas,
        )
    else:
        from lorisnb.io.readers.options import check_reading

        # a times file for a side read as KITTI only (evaluate's rule, one function): --gt-times on a
        # stamped ground truth was dropped, and a KITTI estimate against one was told to give both
        check_reading({"gt_times": args.gt_times, "est_times": args.est_times}, est_format, gt_format,
                      name=lambda key: "--" + key.replace("_", "-"))  # fmt: skip
        gt_times = args.gt_times or (args.times if gt_format == "kitti" else None)
        est_times = args.est_times or (args.times if est_format == "kitti" else None)
        unstamped = [(side, flag) for side, fm, t, flag in (("ground truth", gt_format, gt_times, "--gt-times"),
                                                            ("estimate", est_format, est_times, "--est-times"))
                     if fm == "kitti" and t is None]  # fmt: skip
        by_index = len(unstamped) == 2
        if len(unstamped) == 1:
            side, flag = unstamped[0]
            raise ValidationError(
                f"the {side} is a KITTI file, which has no stamps: give its times file ({flag} or --times), or "
                "pair two KITTI files of equal length by index (no times file for either)"
            )
        gt = read_trajectory(args.gt, gt_format, stamps=gt_times if gt_format == "kitti" else None,
                             topic=args.gt_topic if gt_format == "bag" else None)  # fmt: skip
        est = read_trajectory(args.est, est_format, stamps=est_times if est_format == "kitti" else None,
                              topic=args.topic if est_format == "bag" else None)  # fmt: skip
        if len(gt) and len(est):  # stamps in other units than seconds: said as evaluate says it (one rule)
            check_stamp_units(est, gt, str(args.est))
        spec = make_spec(None, surface="cli", **({} if args.scale is None else {"scale": args.scale}))
        with_scale = spec.alignment_for(Path(args.est).stem) == "sim3"
        table = crosscheck(gt, est, scale=with_scale, by_index=by_index, rpe_deltas=deltas, all_pairs=args.all_pairs,
                           spec=spec)  # fmt: skip
        from lorisnb.tools.peers.crosscheck_reading import crosscheck_reading  # and evo's own reading of each file

        parts = [crosscheck_reading(f, fm, t).assign(quantity=lambda x, w=w: w + ": " + x["quantity"])
                 for w, f, fm, t in (("ground truth", args.gt, gt_format, args.gt_topic),
                                     ("estimate", args.est, est_format, args.topic))]  # fmt: skip
        table = pd.concat([table, *parts], ignore_index=True)
    return table


def _conventions_options(args: argparse.Namespace) -> dict[str, object]:
    """The spec options ``crosscheck --conventions`` takes from its own options: ``--align``,
    ``--scale``, the RPE step (``--rpe-frames`` or ``--rpe-metres``, one of them) and
    ``--all-pairs``; times files are refused (evo reads the files itself, and a KITTI file has no
    stamps for it: pose i with pose i)."""
    times = [
        o for o, v in (("--times", args.times), ("--gt-times", args.gt_times), ("--est-times", args.est_times)) if v
    ]
    if times:
        raise ValidationError(
            f"{', '.join(times)}: with --conventions evo reads both files itself, and evo reads KITTI files without "
            "stamps (pose i with pose i); crosscheck without --conventions takes times files, as does lorisnb evaluate"
        )
    if args.rpe_frames is not None and args.rpe_metres is not None:
        raise ValidationError(
            "--rpe-frames and --rpe-metres: with --conventions the comparison has one RPE step; give one"
        )
    options: dict[str, object] = {}
    if args.align is not None:
        options["align"] = args.align
    if args.scale is not None:
        options["scale"] = args.scale
    if args.rpe_frames is not None:
        options.update(rpe_delta=args.rpe_frames, rpe_unit="f")
    elif args.rpe_metres is not None:
        options.update(rpe_delta=args.rpe_metres, rpe_unit="m")
    if args.all_pairs:
        options["rpe_all_pairs"] = True
    return options


def _not_evos(args: argparse.Namespace, spec: EvalSpec, order: str = "") -> str:
    """Why lorisnb's conventions here are not evo's: another preset, or options given with ``--conventions
    evo`` that depart from it (each with what evo does instead, :func:`~lorisnb.tools.peers.crosscheck_evo.evo_lacks`),
    or ``order``: unsorted stamps, sorted by lorisnb and kept in file order by evo
    (:func:`~lorisnb.tools.peers.crosscheck_evo.evo_order`)."""
    from lorisnb.tools.peers.crosscheck_evo import evo_lacks

    if spec.preset_name == "evo" and order and not evo_lacks(spec):  # options evo has too depart from nothing
        return order
    if order:
        return f"{_not_evos(args, spec)}; {order}"
    if spec.preset_name != "evo":
        return (
            f"the conventions of preset {spec.preset_name} are not evo's, see the notes; --conventions evo gives evo's"
        )
    given = [f"--{k.replace('_', '-')} {v}" for k, v in _conventions_options(args).items()]
    lacks = "; ".join(evo_lacks(spec)) or "see the notes"
    what = f"{' '.join(given)} {'departs' if len(given) == 1 else 'depart'}" if given else "the options given depart"
    return f"{what} from evo's conventions ({lacks}); without them --conventions evo gives evo's"


def _crosscheck_conventions(args: argparse.Namespace, gt_format: str, est_format: str) -> int:
    """``crosscheck --conventions P``: lorisnb under preset P against evo reading the files itself."""
    from lorisnb.io.writers import write_csv
    from lorisnb.tools.peers.crosscheck_evo import crosscheck_evo, explained
    from lorisnb.tools.peers.evo_bridge import NO_RPE_PAIR

    spec = make_spec(args.conventions, surface="cli", **_conventions_options(args))
    table = crosscheck_evo(args.gt, args.est, spec, fmt=est_format, gt_fmt=gt_format, topic=args.topic,
                           gt_topic=args.gt_topic, tol=1e-5 if "kitti" in (gt_format, est_format) else 1e-9)  # fmt: skip
    with pd.option_context("display.max_rows", 200, "display.width", 220, "display.max_colwidth", 110):
        print(table.to_string(index=False, float_format=lambda v: f"{v:.10g}"))
    stats = ~table["quantity"].str.contains(":")  # every statistic of the preset, each counted once below
    agree = stats & table["agrees"]  # evo's value and lorisnb's, the same
    why = explained(table) & stats  # differ, or evo has none, for a reason the note states
    no_pair = stats & ~agree & ~why & table["note"].str.startswith(NO_RPE_PAIR)  # said by _no_pairs
    unexplained = stats & ~agree & ~why & ~no_pair
    total = int(stats.sum())
    print(f"\n{int(agree.sum())} of {total} statistics agree with evo reading the files itself; the reading rows "
          "say where the readings differ and why", file=sys.stderr)  # fmt: skip
    if why.any():
        none = int((why & table["evo"].isna()).sum())
        parts = [f"{int(why.sum()) - none} differ from evo's value", f"evo has no value for {none}"]
        counts = ", ".join(x for x, n in zip(parts, (int(why.sum()) - none, none), strict=True) if n)
        reason = _not_evos(args, spec, table.attrs.get("order", ""))
        print(f"explained by a stated definition ({int(why.sum())} of {total}: {counts}; {reason}): "
              f"{', '.join(table.loc[why, 'quantity'])}", file=sys.stderr)  # fmt: skip
    if unexplained.any():
        print(f"DISAGREE, unexplained ({int(unexplained.sum())} of {total}): "
              f"{', '.join(table.loc[unexplained, 'quantity'])}", file=sys.stderr)  # fmt: skip
    if args.csv:
        write_csv(table, args.csv, args.force)
    return 1 if _no_pairs(table) or unexplained.any() else 0
