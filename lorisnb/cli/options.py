"""Command-line option types and checks: every value goes through :mod:`lorisnb.core.spec.validate`,
the same rules as the Python API, notebook parameters and widgets."""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from typing import Any

from lorisnb.core.conventions.evo_options import PLANES
from lorisnb.core.metrics.pairs import RPE_PAIRS
from lorisnb.core.metrics.relations import RELATIONS, UNITS
from lorisnb.core.spec import validate
from lorisnb.core.spec.evalspec import (
    ALIGNMENTS,
    ASSOCIATIONS,
    KITTI_PRECISIONS,
    PRESETS,
    RPE_UNITS,
    EvalSpec,
    make_spec,
    preset_over,
)
from lorisnb.core.spec.evo import check_evo
from lorisnb.errors import ValidationError
from lorisnb.io.datasets.manifest import BUILT_IN
from lorisnb.io.readers.plain import TRAJECTORY_FORMATS


def arg_type(func: Callable[[str], Any]) -> Callable[[str], Any]:
    """An argparse type from a validator of :mod:`lorisnb.core.spec.validate` (same rules as Python)."""

    def parse(text: str) -> Any:
        try:
            return func(text)
        except ValidationError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    parse.__name__ = getattr(func, "__name__", "value")
    return parse


def threshold_type(name: str) -> Callable[[str], Any]:
    return arg_type(lambda t: validate.eps_value(t) if name == "eps" else validate.threshold(name, t))


def threshold_list_type(name: str) -> Callable[[str], Any]:
    return arg_type(lambda t: validate.threshold_list(name, t))


def add_scale_option(p: argparse.ArgumentParser, help: str) -> None:
    """``--scale [auto|on|off|...]``: the words of :func:`lorisnb.core.spec.validate.scale_value`."""
    # a word, not a number: a fixed factor (TUM evaluate_ate.py's --scale 1.7) is not one of them
    p.add_argument("--scale", nargs="?", const="on", default=None, type=arg_type(scale_word),
                   metavar="{auto,on,off}", help=help)  # fmt: skip


def scale_word(text: str) -> str:
    """A ``--scale`` value checked (:func:`lorisnb.core.spec.validate.scale_value`) and kept as the
    command line's word, ``on``, ``off`` or ``auto`` (``yes`` is ``on``), which every surface takes:
    messages say it as typed, not as Python's True or False."""
    value = validate.scale_value(text)
    return value if isinstance(value, str) else ("on" if value else "off")


def add_threshold_options(p: argparse.ArgumentParser) -> None:
    """``--eps --phi --delta --tau``, one value each (``evaluate``, ``compare``); default: the
    spec's (the preset's, or a manifest's), the same for every command."""
    d = PRESETS["openloris"]
    p.add_argument("--eps", type=threshold_type("eps"), default=None,
                   help=f"ATE threshold in metres, 'inf', 'paper' (1/3/5 m by scene) or 'relative:F'; default "
                   f"{d.eps} (a manifest's eps, with --manifest)")  # fmt: skip
    p.add_argument("--phi", type=threshold_type("phi"), default=None,
                   help=f"AOE threshold in degrees; default {d.phi} (a manifest's phi, with --manifest)")  # fmt: skip
    p.add_argument("--delta", type=threshold_type("delta"), default=None,
                   help=f"validity window of a pose, s; default {d.delta:g}")  # fmt: skip
    p.add_argument("--tau", type=threshold_type("tau"), default=None,
                   help=f"re-localization time factor, s; default {d.tau:g}")  # fmt: skip


def add_input_options(p: argparse.ArgumentParser) -> None:
    """Inputs other than OpenLORIS result files: a ground truth and a format for plain pairs, or a
    manifest; and the conventions of association and alignment."""
    g = p.add_argument_group("pairs and manifests (TUM, EuRoC, KITTI, ROS bags, your own sessions)")
    g.add_argument("--gt", default=None, metavar="FILE", help="ground truth: score the inputs as estimates against it")
    g.add_argument("--format", default=None, choices=TRAJECTORY_FORMATS, help="format of the estimates (default tum)")
    g.add_argument("--gt-format", default=None, choices=TRAJECTORY_FORMATS, help="format of --gt (default: --format)")
    g.add_argument("--manifest", default=None, metavar="NAME_OR_TOML",
                   help=f"a multi-session manifest (built in: {', '.join(BUILT_IN)}); the inputs are folders of estimates")  # fmt: skip
    g.add_argument("--manifest-outside", action="store_true",
                   help="let the manifest name ground-truth files outside its own folder and its root (refused by "
                   "default: a manifest received from someone else reads only there), and show the content of an "
                   "estimate linked from outside the results folder in its errors")  # fmt: skip
    g.add_argument("--scene", default=None, help="scene label of a pair's rows (default: the ground truth's file name)")
    g.add_argument("--conventions", default=None, choices=list(PRESETS),
                   help="a preset of the evaluation spec (openloris: the official tool; tum: evaluate_ate.py; "
                   "rpg: rpg_trajectory_evaluation; vio: posyaw; evo: evo_ape/evo_rpe's defaults; kitti: the KITTI "
                   "odometry devkit's kitti_t_err and kitti_r_err; tartanair: tartanair_tools' scores)")  # fmt: skip
    g.add_argument("--association", default=None, choices=ASSOCIATIONS,
                   help="interpolate (default), nearest (TUM's greedy), evo-nearest or evo-interpolate (evo's sync)")  # fmt: skip
    g.add_argument("--max-gap", default=None, type=arg_type(lambda t: validate.positive("--max-gap", t, "seconds")),
                   help="interpolation bracket, seconds (default 0.5)")  # fmt: skip
    g.add_argument("--max-diff", default=None, type=arg_type(lambda t: validate.positive("--max-diff", t, "seconds")),
                   help="nearest associations: largest stamp difference, seconds (default 0.02; evo 0.01)")  # fmt: skip
    g.add_argument("--t-offset", default=None, type=arg_type(lambda t: validate.finite("--t-offset", t, "seconds")),
                   help="seconds added to every estimate stamp (a known clock offset)")  # fmt: skip
    a = g.add_mutually_exclusive_group()
    a.add_argument("--align", default=None, choices=ALIGNMENTS,
                   help="se3 (default), sim3, posyaw, none, auto (sim3 for monocular algorithms: dso, svo), scale "
                   "(the Sim(3) scale only: evo's -s without -a) or origin (evo's --align_origin)")  # fmt: skip
    a.add_argument("--align-origin", dest="align", action="store_const", const="origin",
                   help="align the first matched estimate pose onto the first ground-truth pose (evo's --align_origin)")  # fmt: skip
    g.add_argument("--align-frames", default=None, metavar="N",
                   type=arg_type(lambda t: int(validate.positive("--align-frames", t, validate.ALL_POSES, integer=True))),
                   help="fit the alignment on the first N matched poses only")  # fmt: skip
    g.add_argument("--t-start", default=None, type=arg_type(lambda t: check_evo("t_start", t, "--t-start")),
                   help="leave out ground-truth poses before this stamp, seconds (evo's --t_start)")  # fmt: skip
    g.add_argument("--t-end", default=None, type=arg_type(lambda t: check_evo("t_end", t, "--t-end")),
                   help="leave out ground-truth poses after this stamp, seconds (evo's --t_end)")  # fmt: skip
    g.add_argument("--project-to-plane", default=None, choices=PLANES,
                   help="errors of the aligned poses projected to a plane (evo's --project_to_plane)")  # fmt: skip
    g.add_argument("--downsample", default=None, metavar="N",
                   type=arg_type(lambda t: check_evo("downsample", t, "--downsample")),
                   help="reduce both trajectories to N evenly spaced poses first (evo's --downsample)")  # fmt: skip
    g.add_argument("--motion-filter", default=None, nargs=2, metavar=("METRES", "DEGREES"),
                   help="keep poses that moved or turned at least this much (evo's --motion_filter)")  # fmt: skip
    g.add_argument("--relation", default=None, choices=RELATIONS,
                   help="also the ape_* and rpe_* statistics of this pose relation (evo's -r)")  # fmt: skip
    g.add_argument("--change-unit", default=None, choices=UNITS,
                   help="the --relation columns in this unit: mm, cm, m, km or deg, rad (evo's --change_unit)")  # fmt: skip
    g.add_argument("--topic", default=None,
                   help="bags: the estimate's pose topic (evo's TF id /tf:parent.child too); several, comma-separated: a row each")  # fmt: skip
    g.add_argument("--gt-topic", default=None, help="bags: the ground truth's pose topic")
    g.add_argument("--tf", default=None, metavar="PARENT:CHILD", help="bags: the estimate as a TF chain")
    g.add_argument("--gt-tf", default=None, metavar="PARENT:CHILD", help="bags: the ground truth as a TF chain")
    g.add_argument("--relative", action="store_true",
                   help="also print rpg's relative error (10..50 %% of each sequence's length; %% and deg/m)")  # fmt: skip
    g.add_argument("--relative-lengths", default=None, metavar="M,M,...",
                   type=arg_type(lambda t: list(validate.positive_list("--relative-lengths", t, "metres"))),
                   help="rpg's relative error at these sub-trajectory lengths, metres (rpg's preset_boxplot_distances; "
                   "implies --relative)")  # fmt: skip
    g.add_argument("--kitti-precision", default=None, choices=KITTI_PRECISIONS,
                   help="--conventions kitti: the devkit's single-precision arithmetic (default) or double")  # fmt: skip
    g.add_argument("--tartanair-scale", action="store_true", default=None,
                   help="--conventions tartanair: its scale (monocular track) for the ATE, RPE and KITTI score")  # fmt: skip
    g.add_argument("--tartanair-seed", default=None, metavar="N",
                   type=arg_type(lambda t: int(validate.finite("--tartanair-seed", t, ""))),
                   help="--conventions tartanair: the seed of its random RPE pairs (default 0)")  # fmt: skip
    g.add_argument("--kitti-plot", default=None, metavar="PNG",
                   help="--conventions kitti: write the devkit's per-length plot (translation and rotation error)")  # fmt: skip
    g.add_argument("--gt-times", default=None, metavar="FILE", help="KITTI: the ground truth's times file")
    g.add_argument("--est-times", default=None, metavar="FILE", help="KITTI: the estimates' times file")


#: Command-line options that are values of the evaluation spec (dest -> spec name).
SPEC_OPTIONS = {
    "association": "association", "max_gap": "max_gap", "max_diff": "max_diff", "t_offset": "t_offset",
    "align": "align", "align_frames": "align_frames", "scale": "scale", "mode": "mode",
    "official_interpolation": "official_interpolation", "official_lifelong": "official_lifelong",
    "repair_stamps": "repair_stamps",
    "keep_repeated": "keep_repeated", "eps": "eps", "phi": "phi", "delta": "delta", "tau": "tau",
    "rpe_delta": "rpe_delta", "rpe_unit": "rpe_unit", "rpe_pairs": "rpe_pairs", "rpe_all_pairs": "rpe_all_pairs",
    "rpe_tolerance": "rpe_tolerance", "t_start": "t_start", "t_end": "t_end", "project_to_plane": "project_to_plane",
    "downsample": "downsample", "motion_filter": "motion_filter", "relation": "relation",
    "kitti_precision": "kitti_precision", "change_unit": "change_unit", "tartanair_scale": "tartanair_scale",
    "tartanair_seed": "tartanair_seed",
}  # fmt: skip


def spec_given(args: argparse.Namespace) -> dict[str, Any]:
    """The spec options given on the command line (name -> value); a sweep's lists are its grid."""
    # store_true: given when set
    flags = ("official_interpolation", "official_lifelong", "repair_stamps", "keep_repeated")
    return {
        name: getattr(args, dest)
        for dest, name in SPEC_OPTIONS.items()
        if getattr(args, dest, None) is not None
        and not (dest in flags and getattr(args, dest) is False)
        and not (isinstance(getattr(args, dest), list) and dest != "motion_filter")
    }


def spec_from_args(args: argparse.Namespace, base: EvalSpec | str | None = None) -> EvalSpec:
    """The evaluation spec the options ask for: ``--conventions`` (or ``base``, a manifest's spec),
    then every single option over it, validated by :func:`lorisnb.core.spec.evalspec.make_spec` as in Python.
    A sweep's threshold lists are its grid, not the spec's thresholds."""
    given = spec_given(args)
    preset = getattr(args, "conventions", None)
    if preset is None:
        preset = base
    elif isinstance(base, EvalSpec):  # over a manifest's spec: as in Python (preset_over)
        preset = preset_over(base, preset)
    return make_spec(preset, surface="cli", **given)


def add_rpe_options(p: argparse.ArgumentParser) -> None:
    """``--rpe-delta`` and ``--rpe-unit``: the RPE step of the tables."""
    d = PRESETS["openloris"]
    p.add_argument("--rpe-delta", default=None, type=arg_type(lambda t: check_evo("rpe_delta", t, "--rpe-delta")),
                   help=f"RPE step (default {d.rpe_delta:g}, in --rpe-unit)")  # fmt: skip
    p.add_argument("--rpe-unit", default=None, choices=(*RPE_UNITS, "d", "r"),
                   help=f"unit of the RPE step: s, m, f or frames, deg (d), rad (r); default {d.rpe_unit} (evo: frames)")  # fmt: skip
    p.add_argument("--rpe-pairs", default=None, choices=RPE_PAIRS,
                   help="measure m / deg / rad along the reference (lorisnb's default) or the aligned estimate (evo's)")  # fmt: skip
    g = p.add_mutually_exclusive_group()
    g.add_argument("--rpe-all-pairs", dest="rpe_all_pairs", action="store_const", const=True, default=None,
                   help="evo's all pairs (--all_pairs): in m, the pose closest to delta within the tolerance")  # fmt: skip
    g.add_argument("--rpe-consecutive", dest="rpe_all_pairs", action="store_const", const=False,
                   help="evo's consecutive pairs (evo's default; the evo preset's)")  # fmt: skip
    p.add_argument("--rpe-tolerance", default=None, type=arg_type(lambda t: check_evo("rpe_tolerance", t, "--rpe-tolerance")),
                   help="evo's --delta_tol for --rpe-all-pairs, a fraction of the delta (default 0.1)")  # fmt: skip
    p.add_argument("--digits", default=4, metavar="N",
                   type=arg_type(lambda t: validate.decimals("--digits", t)),
                   help="decimals of the printed tables (default 4; the CSV keeps every digit)")  # fmt: skip


#: What ``--csv`` writes, by command (evaluate's table unless named here).
CSV_HELP = {
    "compare": "write the comparison table (one row per algorithm and scene: value, interval, rank, test against the "
    "scene's top) to this CSV",
    "diff": "write the changes (one row per sequence and per scene, each metric: base, cand, status, decided_by) to "
    "this CSV",
}


#: The options a command shares with ``evaluate`` but cannot apply, with what to use instead: refused
#: when given (:func:`lorisnb.cli.outputs.refuse_unused`) and left out of the command's ``--help``
#: (:func:`hide_unused`; ``compare --help`` offered a Parquet table it then refused).
#: The KITTI and TartanAir preset options change only their own columns (``kitti_*``, ``tartanair_*``):
#: evaluate's table holds them; sweep's table, compare's metrics and diff's do not (the numbers stayed
#: the same and only the ``spec`` text changed).
PRESET_COLUMNS = {"kitti_precision": "lorisnb evaluate --conventions kitti (its kitti_t_err and kitti_r_err "
                                     "columns; {command} has no KITTI column)",
                  "tartanair_scale": "lorisnb evaluate --conventions tartanair (its tartanair_* columns; "
                                     "{command} has no TartanAir column)",
                  "tartanair_seed": "lorisnb evaluate --conventions tartanair (its tartanair_* columns; "
                                    "{command} has no TartanAir column)"}  # fmt: skip
UNUSED: dict[str, dict[str, str]] = {
    "sweep": {"relative": "lorisnb evaluate (rpg's relative error has no threshold to sweep)",
              "relative_lengths": "lorisnb evaluate --relative-lengths",
              "kitti_plot": "lorisnb evaluate --conventions kitti",
              **{k: v.format(command="sweep's table") for k, v in PRESET_COLUMNS.items()}},
    "compare": {"parquet": "--csv, --pairs-csv, --latex or --markdown", "relative": "lorisnb evaluate",
                "kitti_plot": "lorisnb evaluate --conventions kitti", "relative_lengths": "lorisnb evaluate",
                "relation": "lorisnb evaluate or sweep (evo's pose relation changes no value of --metric)",
                "change_unit": "lorisnb evaluate or sweep (the unit of evo's pose-relation columns)",
                **{k: v.format(command="--metric") for k, v in PRESET_COLUMNS.items()}},
    "diff": {"relative": "lorisnb evaluate (diff compares the RPE columns)",
             "kitti_plot": "lorisnb evaluate --conventions kitti", "relative_lengths": "lorisnb evaluate",
             "relation": "lorisnb evaluate (diff compares CR, CR-T, CS-R, ATE, AOE and RPE, not evo's "
             "pose-relation columns)",
             "change_unit": "lorisnb evaluate or sweep (the unit of evo's pose-relation columns)",
             **{k: v.format(command="diff (CR, CR-T, CS-R, ATE, AOE, RPE)") for k, v in PRESET_COLUMNS.items()}},
}  # fmt: skip


#: Options a command refuses by its own check (naming the option as typed), for every value of its
#: other options: ``compare``'s metrics hold no RPE, so its RPE step options are refused
#: (``cmd_compare``); left out of its ``--help`` as :data:`UNUSED` is.
REFUSED: dict[str, tuple[str, ...]] = {
    "compare": ("rpe_delta", "rpe_unit", "rpe_pairs", "rpe_all_pairs", "rpe_tolerance"),
}


def hide_unused(p: argparse.ArgumentParser, command: str) -> None:
    """Leave the options ``command`` refuses (:data:`UNUSED`, :data:`REFUSED`) out of its ``--help``;
    still parsed, so that giving one is refused with what to use, not an unknown option."""
    for action in p._actions:  # argparse has no public list of a parser's options
        if action.dest in UNUSED[command] or action.dest in REFUSED.get(command, ()):
            action.help = argparse.SUPPRESS


def add_evaluation_options(p: argparse.ArgumentParser, command: str = "evaluate") -> None:
    """Options shared by ``evaluate``, ``compare``, ``diff`` and ``sweep`` (same names, same
    meaning; ``command`` names the one whose parser this is, for what its outputs hold)."""
    p.add_argument(
        "paths", nargs="+", metavar="FILE_OR_DIR",
        help="result files, or folders walked as <algorithm>/*.txt (with --gt: estimates; with --manifest: folders)",
    )  # fmt: skip
    add_input_options(p)
    add_rpe_options(p)
    add_scale_option(p, "align with Sim(3) (scale); 'auto': only for monocular algorithms (dso, svo); 'off': the "
                     "alignment without a scale (sim3 becomes se3; evo's default, none, stays none)")  # fmt: skip
    g = p.add_mutually_exclusive_group()
    g.add_argument(
        "--per-seq", dest="mode", action="store_const", const="per-seq", help="align every sequence on itself"
    )
    g.add_argument(
        "--lifelong",
        dest="mode",
        action="store_const",
        const="lifelong",
        help="align on the first sequence and apply that to all (default for files with several seq: blocks)",
    )
    p.set_defaults(mode=None)
    p.add_argument(
        "--official-interpolation",
        action="store_true",
        help="reproduce the official tool's orientation slips in the interpolated ground truth (AOE; and the RPE, which lorisnb computes from the same poses)",
    )
    p.add_argument(
        "--official-lifelong",
        action="store_true",
        help="reproduce the official tool's lifelong alignment: none at all when a file's first sequence matches "
        "nothing (lorisnb aligns on the first sequence with matches)",
    )
    p.add_argument(
        "--repair-stamps",
        action="store_true",
        help="read stamps written as nanoseconds without zero padding as such (off: as the official tool)",
    )
    p.add_argument(
        "--keep-repeated",
        action="store_true",
        help="keep poses identical to the previous one (the official tool drops them)",
    )
    p.add_argument(
        "--data",
        default=None,
        metavar="DIR",
        help="data root (default: $LORISNB_DATA, else a shared/data folder beside the current folder or a parent, "
        "else beside the lorisnb checkout)",
    )
    p.add_argument(
        "--jobs",
        type=arg_type(lambda t: int(validate.positive("--jobs", t, "processes", integer=True))),
        default=None,
        metavar="N",
        help="processes evaluating files in parallel (default: all cores; 1: one)",
    )
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="evaluate on a running Dask cluster (tcp://host:8786); needs lorisnb[dask]")  # fmt: skip
    p.add_argument("--trials-by", default=None, metavar="REGEX",
                   help="regular expression whose first group is the trial number in a file's path "
                   "(default: _trial3, -trial-3, trial3/, run_2/, stamped_traj_estimate3)")  # fmt: skip
    p.add_argument("--csv", default=None, metavar="OUT",
                   help=CSV_HELP.get(command, "write the table (one row per sequence) to this CSV"))  # fmt: skip
    p.add_argument("--parquet", default=None, metavar="DIR",
                   help="write the table as a Parquet dataset partitioned by algorithm (needs lorisnb[parquet])")  # fmt: skip
    p.add_argument("--force", action="store_true", help="overwrite OUT if it exists")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def param_value(text: str, name: str = "-p value") -> Any:
    """A -p value: JSON when it parses (numbers, true/false, null, lists), else the string. Its
    numbers go through the number check of every surface (:mod:`lorisnb.core.spec.validate`): a
    literal too large for a float (``1e400``) is refused, not read as infinity; JSON's ``NaN`` and
    ``Infinity`` stay text, checked where the parameter is (as ``eps='NaN'`` in Python)."""
    low = text.strip().lower()
    if low in ("inf", "+inf", "infinity"):
        return float("inf")

    def number(literal: str) -> Any:  # one number check for -p as for every surface: 1e400 is no number
        value = validate.finite(name, literal, "")
        return int(literal) if literal.lstrip("-").isdigit() else value

    try:
        return json.loads(text, parse_float=number, parse_int=number, parse_constant=str)
    except ValidationError:
        raise
    except ValueError:
        return text


def probability_type(name: str) -> Callable[[str], Any]:
    """A probability strictly between 0 and 1 (``--level``, ``--alpha``)."""

    return arg_type(lambda t: validate.probability(name, t))


seed_type = arg_type(lambda text: validate.seed(text, "--seed"))


def add_compare_options(p: argparse.ArgumentParser) -> None:
    """``compare``'s own options: the metric, the interval level, the test's alpha, the bootstrap
    seed, the power question and the tables."""
    p.add_argument("--metric", choices=["cr", "cr_t", "cs_r", "c_ate_rmse"], default="cr",
                   help="the metric of the ranking, pairwise tests and tables (default cr)")  # fmt: skip
    p.add_argument("--level", type=probability_type("--level"), default=0.95,
                   help="confidence level of the intervals (default 0.95)")  # fmt: skip
    p.add_argument("--alpha", type=probability_type("--alpha"), default=0.05,
                   help="significance level of the pairwise permutation test, after Holm's correction (default 0.05)")  # fmt: skip
    p.add_argument("--seed", type=seed_type, default=0, metavar="N",
                   help="seed of the bootstrap and of sampled relabellings, a whole number >= 0 (default 0)")  # fmt: skip
    p.add_argument("--power", default=None, metavar="DELTA",
                   type=arg_type(lambda t: validate.positive("--power", t, "the metric's unit")),
                   help="for pairs not found different: the sequences or trials needed to detect a difference "
                   "DELTA of the metric (power 0.8)")  # fmt: skip
    p.add_argument("--pairs-csv", default=None, metavar="OUT",
                   help="write the pairwise test (p, min_p, Holm, effect sizes) to this CSV")  # fmt: skip
    p.add_argument("--latex", default=None, metavar="OUT", help="write the comparison table as LaTeX (booktabs, .tex)")
    p.add_argument("--markdown", default=None, metavar="OUT", help="write the comparison table as Markdown (.md)")


def add_diff_options(p: argparse.ArgumentParser) -> None:
    """``diff``'s own options: tolerances, the family-wise alpha and the verdict files."""
    from lorisnb.core.stats.tolerances import DEFAULT_TOLERANCES

    defaults = ",".join(f"{k}={v}" for k, v in DEFAULT_TOLERANCES.items())
    p.add_argument("--tolerance", default=None, metavar="M=V,...",
                   help="how much worse a metric may get before it is a regression: an amount in the metric's unit "
                   f"or a percentage of the base value (defaults: {defaults.replace('%', '%%')})")  # fmt: skip
    p.add_argument("--alpha", type=probability_type("--alpha"), default=0.05,
                   help="family-wise error rate of the verdict: the share of noise-only diffs that may end in a "
                   "regression, over all its sequences, scenes and metrics (default 0.05)")  # fmt: skip
    p.add_argument("--json", default=None, metavar="OUT", help="write the verdict as JSON")
    p.add_argument(
        "--junit", default=None, metavar="OUT", help="write the verdict as JUnit XML (one test per sequence)"
    )
    p.add_argument("--markdown", default=None, metavar="OUT",
                   help="write the verdict as Markdown (.md), for a pull-request comment or a CI job summary")  # fmt: skip
    p.add_argument("--badge", default=None, metavar="OUT", help="write an SVG badge of the verdict (.svg)")
    p.add_argument("--annotations", action="store_true",
                   help="print GitHub Actions annotations (::error per regression, ::notice per improvement)")  # fmt: skip
    p.add_argument("--baseline", choices=["last-comparable"], default=None,
                   help="last-comparable: BASE is a folder of earlier runs (report run folders or tables); the newest "
                   "one comparable with CAND is the baseline")  # fmt: skip


def add_history_options(p: argparse.ArgumentParser) -> None:
    """``history``'s options: the runs, the metrics, tolerances and the outputs."""
    p.add_argument("runs", nargs="+", metavar="RUN",
                   help="report run folders (run.json + tables) or per-sequence CSV/Parquet tables")  # fmt: skip
    p.add_argument("--metric", nargs="+", choices=["cr", "cr_t", "cs_r", "c_ate_rmse"],
                   default=["cr", "cr_t", "cs_r", "c_ate_rmse"], help="scene metrics to follow (default: all four)")  # fmt: skip
    p.add_argument("--tolerance", default=None, metavar="M=V,...",
                   help="how much a value may move before it counts as a change (as diff's --tolerance)")  # fmt: skip
    p.add_argument("--csv", default=None, metavar="OUT", help="write the history table to this CSV")
    p.add_argument("--out", default=None, metavar="DIR", help="write one figure per metric (PNG, SVG) into DIR")
    p.add_argument("--force", action="store_true", help="overwrite OUT / files in DIR")
