"""The ``consistency`` command: OpenVINS ``ov_eval``'s metrics of one estimate that carries pose
covariances (:mod:`lorisnb.core.metrics.consistency`): NEES, per-axis errors with their 3-sigma
bounds, yaw-only and 2D ATE. Exit status 0 when the pair was scored, 1 when an input could not be
read or paired, 2 for a usage or output error."""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import pandas as pd

from lorisnb.cli.outputs import check_outputs
from lorisnb.cli.text import clean, format_advice, say
from lorisnb.errors import EvaluationError, LorisWarning, ParseError

#: How the note on an estimate's repeated stamps ends: ov_eval's rule differs from the one pose a stamp kept.
OV_EVAL_REPEATED = "ov_eval keeps every row (docs/guide/consistency.md)"


def cmd_consistency(args: argparse.Namespace) -> int:
    from lorisnb.core.metrics.consistency import ov_eval_errors
    from lorisnb.io.parsing.scanner import repeated_peer_clause
    from lorisnb.io.readers.covariance import read_covariances, read_ov_groundtruth
    from lorisnb.io.readers.plain import read_trajectory
    from lorisnb.io.writers import write_csv

    check_outputs(args, [args.est, args.gt], ["csv", "summary_csv", "plot"])
    from lorisnb.errors import ValidationError

    if args.gt_topic is not None and args.gt_format != "bag":
        raise ValidationError(f"--gt-topic applies to a ground truth in a bag (--gt-format bag), not {args.gt_format}")
    given = Path(args.est)  # the reader's rule (read_covariances), in this command's words, before anything is read
    if args.topic is not None and not (
        given.suffix in (".bag", ".db3", ".mcap") or (given / "metadata.yaml").is_file()
    ):
        raise ValidationError(f"--topic {args.topic}: {args.est} is a text file, which has no topics; --topic applies "
                              "to an estimate in a ROS bag")  # fmt: skip
    if args.seq is not None and args.gt_format != "openloris":
        raise ValidationError(
            f"--seq applies to an OpenLORIS ground truth (--gt-format openloris), not {args.gt_format}"
        )
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", LorisWarning)
            # of a repeated stamp one pose is kept, where ov_eval keeps every row: the note says so, not a peer's rule
            with repeated_peer_clause(f"; {OV_EVAL_REPEATED}"):
                est, cov = read_covariances(args.est, args.topic, required=False)
            # every row in file order, as ov_eval reads it: of a repeated stamp its association takes the first
            gt = (
                read_ov_groundtruth(args.gt)
                if args.gt_format == "tum"  # TUM's 8 numbers or ov_eval's 20
                else read_trajectory(args.gt, args.gt_format, seq=args.seq, topic=args.gt_topic, repeated="keep")
            )
            result = ov_eval_errors(est, gt, cov, align=args.align, max_diff=args.max_diff)
    except (ParseError, EvaluationError) as exc:  # advice in this command's options (an estimate's format is read)
        say(f"error: {format_advice(str(exc), None, '--gt-format {fmt}', [args.gt])}")
        return 1
    finally:
        for n in dict.fromkeys(str(w.message) for w in caught if issubclass(w.category, LorisWarning)):
            say(f"warning: {n}")
    for note in result.notes:
        say(f"note: {note}")
    if cov is None:
        say(f"note: {args.est} carries no covariances: errors without 3-sigma bounds, no NEES")
    print(f"ov_eval's metrics ({args.align} alignment, {len(result.poses)} of {len(est)} estimate poses matched "
          f"within {args.max_diff:g} s):")  # fmt: skip
    with pd.option_context("display.width", 200):
        print(result.summary.to_string(index=False, float_format=lambda v: f"{v:.{args.digits}g}"))
    if cov is not None:
        s = result.summary.set_index("series")
        print(f"\nNEES mean: orientation {s.loc['nees_ori', 'mean']:.{args.digits}g}, position "
              f"{s.loc['nees_pos', 'mean']:.{args.digits}g} (3 for an estimator whose covariance matches its errors; "
              "above: overconfident, below: too cautious)")  # fmt: skip
    if args.csv:
        write_csv(result.poses, args.csv, args.force)
    if args.summary_csv:
        write_csv(result.summary, args.summary_csv, args.force)
    if args.plot:
        from lorisnb.io.writers import write_atomically
        from lorisnb.tools.figures.consistency import consistency_figure

        fig = consistency_figure(result, title=f"{clean(args.est)}: per-axis errors ({args.align})")
        suffix = str(args.plot).lower().rsplit(".", 1)[-1]
        write_atomically(args.plot, lambda p: fig.savefig(p, dpi=120, format=suffix), args.force)
    return 0
