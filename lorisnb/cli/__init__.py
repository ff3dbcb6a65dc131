"""The ``lorisnb`` command line: ``evaluate``, ``sweep``, ``compare``, ``diff``, ``history``, ``crosscheck``,
``consistency``, ``report``, ``verify``, ``render``, and
the challenge server's ``serve``, ``challenge add-team|export`` and ``submit``.

The command line is where lorisnb reports: tables on stdout, warnings and failures on stderr,
a non-zero exit status when any input failed (2 for a usage or output error, 130 on Ctrl-C).
"""

from __future__ import annotations

import argparse
import atexit
import contextlib
import gc
import importlib
import importlib.util
import os
import re
import signal
import sys
import weakref
from collections.abc import Callable
from functools import partial
from typing import Any, NoReturn

from lorisnb.cli.challenge import expiry as challenge_expiry
from lorisnb.cli.challenge import port as challenge_port
from lorisnb.cli.options import (
    add_compare_options,
    add_diff_options,
    add_evaluation_options,
    add_history_options,
    add_scale_option,
    add_threshold_options,
    arg_type,
    hide_unused,
    threshold_list_type,
)
from lorisnb.cli.text import message_line, say, warning_lines
from lorisnb.core.spec import validate
from lorisnb.core.spec.evalspec import ALIGNMENTS, OV_ALIGNMENTS, PRESETS
from lorisnb.core.trajectory.blocks import ordinary_pages
from lorisnb.errors import LorisError
from lorisnb.io.parsing.ranges import keep_freed_memory
from lorisnb.io.readers.registry import FORMAT_NAMES
from lorisnb.tools.report.lean_imports import jsonschema_without_iri_grammars, pandas_without_pyarrow

#: The status :func:`run` exits with, once its command is done (:func:`_exit_before_teardown`).
_STATUS: list[int] = []


def _exit_before_teardown() -> None:
    """End a finished ``lorisnb`` command (:func:`run`) once the interpreter's exit functions and
    threads are done, before it tears its modules and objects down: pyarrow's C++ thread pools abort
    the process there now and then ("terminate called without an active exception", exit status
    134 after every table was written: 1 of 40 and 1 of 300 runs of an evaluation on a loaded
    machine, pyarrow 26; apache/arrow#34314). Registered when this module is imported, before the
    exit functions of what the command imports, so it runs after them (the last registered runs
    first); of the modules imported above only ``logging`` registers one, called here."""
    if _STATUS:
        if "logging" in sys.modules:
            sys.modules["logging"].shutdown()  # its handlers flushed and closed, as at any exit
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):  # a closed pipe: nothing more to say
                stream.flush()
        os._exit(_STATUS[0])


atexit.register(_exit_before_teardown)


def _command(module: str, name: str) -> Callable[[argparse.Namespace], int]:
    """The command ``name`` of ``module``, imported when it runs (``--help`` imports neither the
    commands nor pandas, and a command imports pandas after :func:`pandas_without_pyarrow`)."""

    def run(args: argparse.Namespace) -> int:
        return int(getattr(importlib.import_module(module, __name__), name)(args) or 0)

    return run


#: evo_ape / evo_rpe options -> lorisnb's (the table of docs/guide/evo.md), for the hint an
#: unrecognized one gets. An option spelled with underscores where lorisnb has it with dashes
#: (``--max_diff``) is hinted without being listed here.
EVO_OPTIONS: dict[str, str] = {
    "--t_max_diff": "--max-diff", "--t_offset": "--t-offset",
    "--sync_method": "--association evo-nearest (nearest_time) or evo-interpolate (interpolation)",
    "-a": "--align se3", "--align": "--align se3", "-as": "--align sim3", "-s": "--align scale",
    "--correct_scale": "--align scale (--align sim3 for evo's -as)",
    "--n_to_align": "--align-frames", "--align_origin": "--align-origin",
    "--t_start": "--t-start", "--t_end": "--t-end", "--project_to_plane": "--project-to-plane",
    "--motion_filter": "--motion-filter", "-d": "--rpe-delta", "-u": "--rpe-unit",
    "--delta_unit": "--rpe-unit", "--all_pairs": "--rpe-all-pairs", "--delta_tol": "--rpe-tolerance",
    "--pairs_from_reference": "--rpe-pairs reference", "-r": "--relation", "--pose_relation": "--relation",
    "--change_unit": "--change-unit",
    "--save_results": "the output options (--csv, --json); evo's zips: lorisnb.tools.peers.evo_import",
}  # fmt: skip
_UNRECOGNIZED = "unrecognized arguments: "


def _option_strings(parser: argparse.ArgumentParser) -> set[str]:
    """Every option string of ``parser`` and of its sub-commands."""
    out = set(parser._option_string_actions)
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                out |= _option_strings(sub)
    return out


def evo_hints(message: str, known: set[str]) -> str:
    """For argparse's ``unrecognized arguments: ...``: the lorisnb option each evo spelling
    (:data:`EVO_OPTIONS`) or underscored spelling (``--max_diff``: ``--max-diff``) among them is,
    as ``; evo's --t_max_diff is lorisnb's --max-diff``; else ``""``."""
    if not message.startswith(_UNRECOGNIZED):
        return ""
    hints = []
    for token in message.removeprefix(_UNRECOGNIZED).split():
        option = token.split("=", 1)[0]
        if option in EVO_OPTIONS:
            hints.append(f"evo's {option} is lorisnb's {EVO_OPTIONS[option]}")
        elif option.startswith("--") and "_" in option and option.replace("_", "-") in known:
            hints.append(f"{option} is spelled {option.replace('_', '-')} (lorisnb's options use dashes)")
    evo = any(h.startswith("evo's") for h in hints)
    return "; " + "; ".join(hints) + (" (docs/guide/evo.md: evo's options in lorisnb)" if evo else "") if hints else ""


class Parser(argparse.ArgumentParser):
    """argparse's parser (its sub-commands' too) whose usage errors, quoting the value given, escape
    control characters as every other message line does (:func:`~lorisnb.cli.text.say`), and name
    lorisnb's option for an evo spelling it does not know (:func:`evo_hints`)."""

    def error(self, message: str) -> NoReturn:
        super().error(message_line(message + evo_hints(message, _option_strings(self))))


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(prog="lorisnb", description="Lifelong SLAM evaluation (OpenLORIS-Scene metrics)")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("evaluate", help="score result files: ATE, AOE, CR, CR-T, CS-R, C-ATE, RPE")
    add_evaluation_options(p)
    add_threshold_options(p)
    p.set_defaults(func=_command(".commands", "cmd_evaluate"))

    p = sub.add_parser("compare", help="compare algorithms over trials and sequences: intervals, tests, ranking")
    add_evaluation_options(p, "compare")
    add_threshold_options(p)
    add_compare_options(p)
    hide_unused(p, "compare")
    p.usage = "%(prog)s FILE_OR_DIR... [options]"  # argparse (3.11) cannot draw a usage line with its RPE group hidden
    p.set_defaults(func=_command(".commands", "cmd_compare"))

    p = sub.add_parser("diff", help="did CAND regress against BASE? two result folders, report runs or tables")
    add_evaluation_options(p, "diff")
    add_threshold_options(p)
    add_diff_options(p)
    hide_unused(p, "diff")
    p.set_defaults(func=_command(".runs", "cmd_diff"))
    p.set_defaults(defaults=vars(p.parse_args(["BASE", "CAND"])))

    p = sub.add_parser("history", help="scene values over many runs: first changes, runs not comparable")
    add_history_options(p)
    p.set_defaults(func=_command(".runs", "cmd_history"))

    p = sub.add_parser(
        "sweep", help="every metric over grids of eps, phi, delta and tau (one row per sequence and setting)"
    )
    add_evaluation_options(p)
    default = "; default the spec's: a manifest's, else {:g}"
    d = PRESETS["openloris"]
    p.add_argument("--eps", type=threshold_list_type("eps"), default=None,
                   help="comma-separated ATE thresholds in metres ('inf', 'paper' allowed)" + default.format(d.eps))  # fmt: skip
    p.add_argument("--phi", type=threshold_list_type("phi"), default=None,
                   help="comma-separated AOE thresholds, degrees" + default.format(d.phi))  # fmt: skip
    p.add_argument("--delta", type=threshold_list_type("delta"), default=None,
                   help="comma-separated validity windows, s" + default.format(d.delta))  # fmt: skip
    p.add_argument("--tau", type=threshold_list_type("tau"), default=None,
                   help="comma-separated re-localization factors, s" + default.format(d.tau))  # fmt: skip
    p.add_argument(
        "--relative-to",
        choices=["extent", "length"],
        default=None,
        help="read --eps as fractions of each sequence's ground-truth extent or length",
    )
    p.add_argument(
        "--columns",
        choices=["metrics", "all"],
        default="metrics",
        help="columns of the table written: 'metrics' (default, as lorisnb.sweep's: identity, thresholds and the "
        "metrics that depend on them, plus the spec) or 'all' (every column of evaluate's table, its error "
        "statistics and RPE repeated at each setting: for 100 eps x 100 phi over icra20, twice the file and 8 times "
        "the time)",
    )
    hide_unused(p, "sweep")
    p.set_defaults(func=_command(".commands", "cmd_sweep"))

    p = sub.add_parser("crosscheck", help="compare lorisnb with evo on one ground truth and one estimate")
    p.add_argument("gt", help="ground truth (for --format openloris: gt_<scene>_1.txt, or 'auto' to find it)")
    p.add_argument("est", help="estimate")
    p.add_argument(
        "--format",
        choices=FORMAT_NAMES,
        default="tum",
        help="format of GT (and of EST unless --est-format); euroc follows evo: the ground truth is the "
        "EuRoC CSV, the estimate TUM text",
    )
    p.add_argument(
        "--est-format",
        choices=[f for f in FORMAT_NAMES if f != "openloris"],
        default=None,
        help="format of EST when it differs",
    )
    p.add_argument("--conventions", choices=list(PRESETS), default=None,
                   help="lorisnb under this preset (e.g. evo) against evo reading the files itself: every statistic")  # fmt: skip
    p.add_argument("--align", choices=ALIGNMENTS, default=None, help="with --conventions: the alignment")
    p.add_argument("--topic", default=None, help="bags: the estimate's topic (evo's /tf:parent.child too)")
    p.add_argument("--gt-topic", default=None, help="bags: the ground truth's topic")
    add_scale_option(p, "Sim(3) for the RPE and association rows; 'auto': Sim(3) only for a monocular algorithm (dso, "
                     "svo) by its name (an OpenLORIS file's, or a pair's estimate file name; another pair: no scale)")  # fmt: skip
    p.add_argument("--times", default=None, help="KITTI: one times file (a stamp per line) for both files")
    p.add_argument("--gt-times", default=None, help="KITTI: the ground truth's times file")
    p.add_argument("--est-times", default=None, help="KITTI: the estimate's times file")
    p.add_argument("--seq", type=arg_type(lambda t: validate.seq_number("--seq", t)), default=None,
                   help="openloris: the sequence (default: the first with poses)")  # fmt: skip
    p.add_argument(
        "--rpe-frames",
        type=arg_type(lambda t: int(validate.positive("--rpe-frames", t, "frames", integer=True))),
        default=None,
        help="RPE delta in frames (default 1; with --conventions: the RPE step, instead of the preset's)",
    )
    p.add_argument(
        "--rpe-metres",
        type=arg_type(lambda t: validate.positive("--rpe-metres", t, "metres")),
        default=None,
        help="RPE delta in metres (default 1; with --conventions: the RPE step, instead of the preset's)",
    )
    p.add_argument("--all-pairs", action="store_true", help="RPE over all pairs (evo's default: consecutive)")
    p.add_argument("--data", default=None, metavar="DIR")
    p.add_argument("--csv", default=None, metavar="OUT")
    p.add_argument("--force", action="store_true")
    p.set_defaults(func=_command(".crosscheck", "cmd_crosscheck"))

    p = sub.add_parser(
        "consistency",
        help="an estimate with pose covariances (OpenVINS ov_eval's metrics): NEES, per-axis errors with 3-sigma "
        "bounds, yaw-only and 2D ATE",
    )
    p.add_argument("est", help="estimate: ov_eval's text layout (stamp, pose, 12 covariance numbers a line), a TUM file "
                   "(no covariances: no NEES or bounds) or a ROS bag (PoseWithCovarianceStamped or Odometry)")  # fmt: skip
    p.add_argument(
        "gt", help="ground truth (--gt-format; tum: 8 numbers a line, or ov_eval's 20, its covariances left)"
    )
    p.add_argument("--gt-format", choices=FORMAT_NAMES, default="tum", help="format of GT (default tum)")
    p.add_argument("--topic", default=None, help="bags: the estimate's topic")
    p.add_argument("--gt-topic", default=None, help="bags (--gt-format bag): the ground truth's topic")
    p.add_argument(
        "--seq",
        type=arg_type(lambda t: validate.seq_number("--seq", t)),
        default=None,
        help="an OpenLORIS ground truth (--gt-format openloris) of several sequences: the estimate's",
    )
    p.add_argument("--align", choices=OV_ALIGNMENTS, default="posyaw",
                   help="alignment, fitted both ways on all matched positions (ov_eval's; default posyaw: yaw-only)")  # fmt: skip
    p.add_argument(
        "--max-diff",
        type=arg_type(lambda t: validate.positive("--max-diff", t, "seconds")),
        default=0.02,
        help="association: at most this many seconds between paired stamps (ov_eval's 0.02)",
    )
    p.add_argument("--csv", default=None, metavar="OUT", help="the per-pose errors, bounds and NEES")
    p.add_argument("--summary-csv", default=None, metavar="OUT", help="the statistics of each series")
    p.add_argument(
        "--plot", default=None, metavar="OUT", help="the per-axis errors with their bounds (.png, .svg, .pdf)"
    )
    p.add_argument(
        "--digits",
        type=arg_type(lambda t: validate.significant("--digits", t)),
        default=6,
        help="significant digits printed, 1 to 17 (default 6)",
    )
    p.add_argument("--force", action="store_true", help="overwrite outputs")
    p.set_defaults(func=_command(".consistency", "cmd_consistency"))

    p = sub.add_parser("report", help="run the notebooks with papermill into a report folder under results/")
    p.add_argument("--out", default=None, help="run folder (default results/run-<date>-<time> in the current folder)")
    p.add_argument(
        "-p",
        "--parameter",
        nargs=2,
        action="append",
        metavar=("NAME", "VALUE"),
        help="notebook parameter (repeatable); VALUE is JSON if it parses, else a string",
    )
    p.add_argument("--notebooks", nargs="+", default=None, help="notebooks to run (default: all, in report order)")
    p.add_argument("--data", default=None, metavar="DIR", help="data root passed to the notebooks as data_root")
    p.add_argument(
        "--notebooks-dir",
        default=None,
        metavar="DIR",
        help="folder of the notebooks (default: those shipped with lorisnb)",
    )
    p.add_argument(
        "--results",
        default=None,
        metavar="DIR",
        help="your results folder (<algorithm>/*.txt, trials allowed): the leaderboard's input and the notebooks' "
        "results_dir; notebooks about the bundled data only are left out unless named",
    )
    p.add_argument(
        "--jobs",
        type=arg_type(lambda t: int(validate.positive("--jobs", t, "notebooks", integer=True))),
        default=None,
        help="notebooks run at a time (default: the cores)",
    )
    p.add_argument("--label", default=None, metavar="TEXT", type=arg_type(validate.code_label),
                   help="the code under test (a commit, tag or name, e.g. $GITHUB_SHA): recorded in run.json, shown on "
                   "the front page and by history")  # fmt: skip
    p.add_argument("--baseline", default=None, metavar="DIR",
                   help="a folder of earlier runs: the front page shows this run against the newest comparable one "
                   "(verdict, what changed, a trend of the last comparable runs)")  # fmt: skip
    p.add_argument("--gate", action="store_true",
                   help="with --baseline: exit 1 when this run regressed since its baseline (diff's verdict), and 2 "
                   "when no earlier run is comparable with it (nothing judged), as diff --baseline last-comparable")  # fmt: skip
    p.add_argument("--absolute-paths", action="store_true",
                   help="write the absolute paths of the inputs, the data root and the results into the run (default: "
                   "each path below a named root, {data} or {results}, so the run folder can travel)")  # fmt: skip
    p.add_argument("--force", action="store_true", help="replace --out if it is an earlier lorisnb run folder")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_command(".commands", "cmd_report"))

    p = sub.add_parser("serve", help="a challenge server: teams upload results, scored against hidden ground truth")
    p.add_argument("challenge", metavar="CHALLENGE.toml", help="the challenge file (docs/guide/challenge-server.md)")
    p.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1: this machine only)")
    p.add_argument("--port", type=arg_type(challenge_port), default=8000, help="port (default 8000)")
    p.add_argument("--max-connections", type=arg_type(lambda t: int(validate.positive("--max-connections", t,
                   "connections", integer=True))), default=200,
                   help="connections served at once; more are answered 503 (default 200)")  # fmt: skip
    p.set_defaults(func=_command(".challenge", "cmd_serve"))

    p = sub.add_parser("challenge", help="a challenge's teams and results: add-team, export")
    csub = p.add_subparsers(dest="action", required=True)
    q = csub.add_parser("add-team", help="add a team (or the admin) and print its token, stored hashed only")
    q.add_argument("challenge", metavar="CHALLENGE.toml")
    q.add_argument("name", metavar="NAME", help="the team's name on the leaderboard")
    q.add_argument("--admin", action="store_true", help="the admin's token (the admin page and API), not a team's")
    q.add_argument("--expires", type=arg_type(challenge_expiry), default=None, metavar="WHEN",
                   help="when the token stops working, e.g. 2026-12-01T18:00:00Z (default: the challenge's close for a team's token, 90 days after it for --admin)")  # fmt: skip
    q.set_defaults(func=_command(".challenge", "cmd_add_team"))
    q = csub.add_parser("export", help="every submission and its per-sequence scores as one CSV table")
    q.add_argument("challenge", metavar="CHALLENGE.toml")
    q.add_argument("--csv", required=True, metavar="OUT", help="the CSV file to write")
    q.add_argument("--force", action="store_true", help="replace OUT if it exists")
    q.set_defaults(func=_command(".challenge", "cmd_export"))

    p = sub.add_parser("submit", help="send result files to a challenge server (lorisnb serve)")
    p.add_argument("url", metavar="URL", help="the server, http://HOST:PORT")
    p.add_argument("files", nargs="+", metavar="FILES", help="result files (.txt, .csv), a folder of them or a .zip")
    p.add_argument("--token", default=None, help="your team's token (default: $LORISNB_TOKEN)")
    p.add_argument("--format", choices=("auto", "openloris", "tum", "euroc"), default=None,
                   help="the files' format (default auto: recognised by the server from each file; TUM and EuRoC "
                   "files are named after their sequence, cafe-1-2.txt)")  # fmt: skip
    p.add_argument("--wait", type=arg_type(lambda t: validate.positive("--wait", t, "seconds")), default=None,
                   metavar="SECONDS", help="wait up to SECONDS for the score and print it")  # fmt: skip
    p.set_defaults(func=_command(".challenge", "cmd_submit"))

    p = sub.add_parser("verify", help="re-check a report run's inputs against the checksums in its run.json")
    p.add_argument("run", metavar="RUN", help="a run folder written by lorisnb report (or its run.json)")
    p.add_argument("--data", default=None, metavar="DIR", help="where the run's data root ({data}) is here")
    p.add_argument("--results", default=None, metavar="DIR", help="where the run's results folder ({results}) is here")
    p.add_argument("--root", nargs=2, action="append", metavar=("NAME", "DIR"),
                   help="where another named root of the run ({NAME}, e.g. groundtruth) is here (repeatable); verify "
                   "reads nothing outside the run folder and the roots given")  # fmt: skip
    p.set_defaults(func=_command(".commands", "cmd_verify"))

    p = sub.add_parser("render", help="render a run folder's pages again from its own files (e.g. where it was copied)")
    p.add_argument("run", metavar="RUN", help="a run folder written by lorisnb report")
    p.set_defaults(func=_command(".commands", "cmd_render"))
    given_once(parser)
    return parser


def given_once(parser: argparse.ArgumentParser) -> None:
    """Every option of one value (of ``parser`` and its subcommands) refuses a second, different
    value: argparse keeps the last, silently dropping the first (``sweep --eps 0.05 --eps 0.1``
    swept 0.1 only). The same value twice is harmless and accepted. Every value, of an option or
    an argument, refuses to be empty (``--gt "$GT"`` with ``GT`` unset was read as no ``--gt``)."""
    seen: dict[int, tuple[weakref.ref, dict[str, tuple[Any]]]] = {}

    class Given(argparse._StoreAction):  # an argument's value (or values) as typed: not empty
        def __call__(self, p: Any, namespace: Any, values: Any, option_string: Any = None) -> None:
            for value in values if isinstance(values, list) else [values]:
                if isinstance(value, str) and not value.strip():
                    name = option_string or self.metavar or self.dest
                    p.error(f"{name}: an empty value (an unset shell variable?); give a value, or leave {name} out"
                            if option_string else f"{name}: an empty value (an unset shell variable?); give a value")  # fmt: skip
            super().__call__(p, namespace, values, option_string)

    class Once(Given):  # argparse has no hook for a repeated option
        def __call__(self, p: Any, namespace: Any, values: Any, option_string: Any = None) -> None:
            ref, given = seen.get(id(namespace), (None, {}))
            if ref is None or ref() is not namespace:  # a new parse
                given = {}
                seen[id(namespace)] = (weakref.ref(namespace), given)
            several = self.nargs in ("+", "*")  # --metric cr cs_r: several values after one option
            if several and len(set(map(str, values))) < len(values):
                twice = next(str(v) for i, v in enumerate(values) if str(v) in map(str, values[:i]))
                p.error(f"{option_string}: {twice} given twice in {' '.join(map(str, values))}; give each once")
            if self.dest in given and given[self.dest][0] != values:
                first = given[self.dest][0]
                lists = (f" (several values follow one {option_string}: {option_string} A B)" if several
                         else " (a list is one value, comma-separated: --eps 0.05,0.1)" if isinstance(values, list) and self.nargs is None
                         else "")  # fmt: skip
                p.error(f"{option_string} given twice ({first!r}, then {values!r}); the last would silently replace "
                        f"the first: give it once{lists}")  # fmt: skip
            given[self.dest] = (values,)
            super().__call__(p, namespace, values, option_string)

    def walk(p: argparse.ArgumentParser) -> None:
        for action in p._actions:  # argparse has no public list of a parser's options
            words = action.choices
            if action.type is None and isinstance(words, (list, tuple)) and all(isinstance(w, str) for w in words):
                # a word read as Python reads it (validate.choice: any case, spaces around): --align SE3 too
                label = action.option_strings[0] if action.option_strings else action.dest
                action.type = arg_type(partial(validate.choice, label, options=tuple(words)))
            if type(action) is argparse._StoreAction and action.option_strings:
                action.__class__ = Once  # one value, an optional one (--scale) or several (--metric cr cs_r): once
            elif type(action) is argparse._StoreAction:  # arguments, and options of several values
                action.__class__ = Given
            if isinstance(action, argparse._SubParsersAction):
                for sub in action.choices.values():
                    walk(sub)

    walk(parser)


#: A value that starts like a negative number or list of them (``-1,1``, ``-1e-3``, ``-inf``), which
#: argparse would take for an option (its own test accepts only ``-1`` and ``-1.5``).
NEGATIVE_VALUE = re.compile(r"^-(\d|\.\d|inf|nan)", re.IGNORECASE)


def glue_negative_values(parser: argparse.ArgumentParser, argv: list[str]) -> list[str]:
    """``--eps -1,1`` as ``--eps=-1,1``: an option that takes one value, followed by a value that
    starts like a negative number, gets it, so that the option's validator says what is wrong with
    it (argparse would say "expected one argument")."""
    takes_value: set[str] = set()

    def walk(p: argparse.ArgumentParser) -> None:
        for action in p._actions:  # argparse has no public list of a parser's options
            if action.option_strings and action.nargs is None:
                takes_value.update(action.option_strings)
            if isinstance(action, argparse._SubParsersAction):
                for sub in action.choices.values():
                    walk(sub)

    walk(parser)
    out: list[str] = []
    i = 0
    while i < len(argv):
        token = argv[i]
        if token == "--":  # everything after is positional
            return out + argv[i:]
        if token in takes_value and i + 1 < len(argv) and NEGATIVE_VALUE.match(argv[i + 1]):
            out.append(f"{token}={argv[i + 1]}")
            i += 2
            continue
        out.append(token)
        i += 1
    return out


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(glue_negative_values(parser, list(sys.argv[1:] if argv is None else argv)))
    args.argv = ["lorisnb", *(sys.argv[1:] if argv is None else argv)]  # the command line, as run.json records it
    keep_freed_memory()  # a command is one short process: reuse freed memory (see there)
    ordinary_pages(True)  # and new arrays in ordinary pages (see there)
    if not (getattr(args, "parquet", None) or getattr(args, "scheduler", None) or args.command == "report"):
        pandas_without_pyarrow()
    jsonschema_without_iri_grammars()
    previous = _terminate_as_interrupt()
    roots = {"results": getattr(args, "results", None), "data": getattr(args, "data", None)}
    try:
        with warning_lines({k: v for k, v in roots.items() if isinstance(v, str)}):  # every warning: one line
            return int(args.func(args) or 0)
    except LorisError as exc:
        say(f"error: {exc}")
        return 2
    except OSError as exc:  # writing an output failed once checked (a full disk, a file system that refuses)
        if isinstance(exc, BrokenPipeError):  # stdout closed by the reader: run() ends quietly
            raise
        where = f"{exc.filename}: " if exc.filename else "an output (the system named no file): "
        say(f"error: {where}{exc.strerror or exc}")
        return 2
    except KeyboardInterrupt as exc:
        terminated = isinstance(exc, Terminated)
        print("terminated" if terminated else "interrupted", file=sys.stderr)
        return 128 + signal.SIGTERM if terminated else 130
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


class Terminated(KeyboardInterrupt):
    """SIGTERM (a CI job's time-out, ``kill``), raised where Ctrl-C would be: a command cleans up
    the same way (a report removes its unfinished run folder and stops its workers and kernels)."""


def _terminate_as_interrupt() -> Any:
    """Have SIGTERM raise :class:`Terminated` in this process (its main thread); the handler it
    replaces, or None where signals cannot be set. A process forked from this one (a worker)
    keeps dying of SIGTERM as before."""
    import threading

    if threading.current_thread() is not threading.main_thread():
        return None
    me = os.getpid()

    def handler(signum: int, frame: Any) -> None:
        if os.getpid() != me:  # a forked worker: the default, as if no handler were set
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
            os.kill(os.getpid(), signal.SIGTERM)
            return
        raise Terminated

    return signal.signal(signal.SIGTERM, handler)


def run() -> None:
    """The ``lorisnb`` command: :func:`main`, then exit. A closed output pipe (``lorisnb evaluate
    ... | head``) ends it quietly; the interpreter's last garbage collection over everything the
    run made is skipped (about a tenth of a second after a large evaluation)."""
    try:
        code = main()
        sys.stdout.flush()
    except BrokenPipeError:
        devnull = os.open(os.devnull, os.O_WRONLY)  # Python's advice: no second error at exit
        os.dup2(devnull, sys.stdout.fileno())
        code = 1
    gc.freeze()
    _STATUS[:] = [code]  # the process ends with it before its teardown (_exit_before_teardown)
    sys.exit(code)
