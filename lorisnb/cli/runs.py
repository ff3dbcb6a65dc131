"""The commands over runs: ``diff`` (did CAND regress against BASE?) and ``history`` (many runs
over time). Exit status of ``diff``: 0 no regression, 1 a regression (or an input of a run could not
be evaluated), 2 a usage error (bad option, runs that are not comparable)."""

from __future__ import annotations

import argparse
import os
import sys
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import pandas as pd

from lorisnb._version import __version__
from lorisnb.cli.commands import every_column, fmt_table, report_problems, run_evaluation, tables_only
from lorisnb.cli.options import UNUSED
from lorisnb.cli.outputs import check_outputs, refuse_unused
from lorisnb.cli.text import clean, say
from lorisnb.core.spec import validate
from lorisnb.errors import ValidationError

#: diff's own options; every other option is an evaluate option (for result folders only).
DIFF_OWN = {"paths", "tolerance", "alpha", "markdown", "badge", "annotations", "baseline", "json", "junit", "csv", "parquet", "force", "no_progress", "func",
            "command", "eps_default", "phi_default", "defaults", "digits"}  # fmt: skip


def _given_evaluate_options(args: argparse.Namespace, defaults: dict[str, Any]) -> list[str]:
    return [f"--{k.replace('_', '-')}" for k, v in vars(args).items()
            if k not in DIFF_OWN and k in defaults and v != defaults[k]]  # fmt: skip


def _short(v: object, digits: int = 4) -> str:
    """A value for the terminal: numbers to ``digits`` decimals (``--digits``), long text cut (the
    JSON keeps it whole)."""
    if isinstance(v, float):
        return "NaN" if v != v else f"{v:.{digits}f}"
    text = str(v)
    return text if len(text) <= 60 else text[:57] + "..."


def _side(path: str, args: argparse.Namespace) -> tuple[Any, dict[str, str], list[str]]:
    """A run (report run or table as read, or a result folder evaluated with the options), the
    files of it that failed (relative path -> reason), and notes."""
    from lorisnb.tools.decisions.diff import unevaluated
    from lorisnb.tools.decisions.runs import Run, is_report_run, is_table, load_run

    p = Path(path)
    if is_report_run(p) or is_table(p):
        run = load_run(p)  # a report run: the inputs its own evaluation did not score
        return run, dict(run.unscored), sorted(run.unscored)
    if not p.exists():
        raise ValidationError(f"{path}: no such result folder, run folder or table")
    ev, notes = run_evaluation(
        argparse.Namespace(**{**vars(args), "paths": [path]}),
        [],
        side=f" of {path}",
        statistics=every_column,
        poses=tables_only,
    )  # outputs: checked first; every column scored in the workers (the table below), only it sent back
    report_problems(ev, [f"{path}: {n}" for n in notes])
    failed = unevaluated(ev, p)  # not evaluated, or evaluated but not scored: as evaluate's exit status counts
    table = ev.sequences()  # at the spec's thresholds (the options', else the defaults)
    if isinstance(ev.spec.eps, str) and ev.spec.eps.startswith("relative:"):
        # each row's eps in metres follows the extent the estimate matched, so it differs wherever
        # CAND tracked more or less than BASE; both sides were scored with this one fraction
        table = table.assign(eps=ev.spec.eps)
    newest = _newest_input(ev, p)
    made = "modification time of its newest result file"
    now = datetime.now(timezone.utc)
    ahead = [] if newest is None or newest <= now else [
        f"{path}: its newest file's time {newest.isoformat()} is in the future (now {now.isoformat()}; another machine's "
        "clock?), so CAND's time is unknown: an earlier run holding every value of it is taken as its copy"]  # fmt: skip
    meta = {"lorisnb_version": __version__, "inputs": _groundtruth_sums(args, table)}  # as a report run records them
    run = Run(p, "results", table, meta=meta, expected=ev.durations(), created=None if ahead else newest,
              created_from=made, warnings=ahead)  # fmt: skip
    return run, failed, sorted(failed)


def _groundtruth_sums(args: argparse.Namespace, table: pd.DataFrame) -> dict[str, str]:
    """The SHA-256 of the ground-truth files a result folder was scored against, by path, as a report
    run's run.json records them (``inputs``; :meth:`~lorisnb.tools.decisions.runs.Run.groundtruth_sums`
    reads their names): the data root's ``gt_<scene>_1.txt`` of each OpenLORIS scene of the table, or
    the ``--gt`` file of a pair. None for a manifest's sessions (each names its own): then not checked,
    and :func:`lorisnb.tools.decisions.history.checked` says so."""
    from lorisnb.errors import LorisError
    from lorisnb.io.datasets.paths import find_data
    from lorisnb.tools.report.provenance import sha256

    files: list[Path] = []
    if getattr(args, "manifest", None):
        return {}
    if getattr(args, "gt", None):
        files = [Path(args.gt)]
    elif len(table):
        try:
            root = find_data(getattr(args, "data", None))
            files = [root.groundtruth(s) for s in sorted({str(x) for x in table["scene"]})]
        except LorisError:  # a scene without ground truth there was not scored against one
            files = []
    out = {}
    for f in files:
        try:
            out[os.path.abspath(f)] = sha256(f)
        except (OSError, LorisError):
            continue
    return out


def _refuse_no_common_algorithm(base: Any, cand: Any, paths: list[str]) -> None:
    """A ValidationError when BASE and CAND both hold sequences but no algorithm in common: every
    sequence of BASE would be called missing and every one of CAND new (two identical result
    folders holding their files directly, each file's algorithm named after its folder, ``base``
    and ``cand``, were judged a regression)."""
    algs = [sorted({str(a) for a in r.table["algorithm"]}) for r in (base, cand)]
    if not (algs[0] and algs[1]) or set(algs[0]) & set(algs[1]):
        return
    shown = [", ".join(a_[:5]) + (f" and {len(a_) - 5} more" if len(a_) > 5 else "") for a_ in algs]
    folders = [validate.label(Path(os.path.abspath(p)).name) for p in paths]  # as labels name them (NFC)
    flat = [Path(p).is_dir() and a == [f] for p, a, f in zip(paths, algs, folders, strict=True)]
    why = (
        "result files directly in a folder you gave are one algorithm named after that folder ("
        + ", ".join(f"{f}/" for f, fl in zip(folders, flat, strict=True) if fl)
        + "): put them in a folder named for the algorithm on each side (BASE/orb/*.txt, CAND/orb/*.txt)"
        if any(flat)
        else "an algorithm renamed? Compare different algorithms with lorisnb compare"
    )
    raise ValidationError(f"BASE and CAND share no algorithm (BASE: {shown[0]}; CAND: {shown[1]}), so nothing of "
                          f"CAND can be judged against BASE; {why}")  # fmt: skip


def _newest_input(ev: Any, folder: Path) -> Any:
    """When a result folder's content last changed: the newest modification time of the files it
    evaluated and of the folders holding them, up to ``folder`` (a file removed changes its folder's
    time), or None when none can be read. A run made at that time or after it evaluated this content:
    ``--baseline last-comparable`` passes it over, as a copy of CAND
    (:func:`lorisnb.tools.decisions.history.not_before`); the nightly recipe writes tonight's report
    run before its diff, and that run was taken as the baseline of its own results."""
    from lorisnb.tools.decisions.runs import modified

    folder = Path(os.path.abspath(folder))
    paths = {Path(os.path.abspath(f.path)) for f in [*ev.errors, *ev.failures]}
    folders = {d for p in paths for d in p.parents if d == folder or folder in d.parents}
    times = []
    for path in [*paths, *folders, folder]:
        try:
            times.append(modified(path))
        except OSError:  # a link to nothing, a file gone since
            continue
    return max(times, default=None)


def _last_comparable(folder: Path, cand: Any) -> Any:
    """The newest run in ``folder`` comparable with ``cand`` (:func:`lorisnb.tools.decisions.history.last_comparable`),
    named on stderr."""
    from lorisnb.tools.decisions.history import checked, last_comparable

    base, runs = last_comparable(folder, cand)
    print(f"baseline: {clean(base.path)} (the newest of {len(runs)} earlier run(s) comparable with CAND: "
          f"{checked(base, cand)})", file=sys.stderr)  # fmt: skip
    return base


def refuse_not_comparable(base: Any, cand: Any) -> None:
    """A ValidationError (exit 2) when BASE and CAND are not comparable by the one rule ``history``
    and ``--baseline last-comparable`` apply (:func:`lorisnb.tools.decisions.history.comparability`:
    the spec and thresholds, lorisnb's version, the ground truth's checksums, where both runs record
    them). ``diff`` noted a version change and judged, exit 0, where ``history`` of the same two runs
    exits 2."""
    from lorisnb.tools.decisions.history import comparability
    from lorisnb.tools.decisions.runs import spec_differences

    problems = comparability(base, cand)
    if not problems:
        return
    specs = spec_differences(base, cand)
    if len(problems) == len(specs):
        what, same = "different evaluation specs", "spec"
    else:
        what = "different evaluation specs, lorisnb versions or ground truth" if specs else (
            "made by another lorisnb version or against another ground truth")  # fmt: skip
        same = "spec, lorisnb version and ground truth"
    todo = []
    if specs:
        todo.append("evaluate again with the options that set the keys named (for a result folder: --eps, --phi, "
                    "--delta, --tau as the table's; align: --scale or --align, lorisnb report aligns monocular "
                    "systems with --scale auto)")  # fmt: skip
    if len(problems) > len(specs):
        todo.append("make BASE with the lorisnb version and ground truth CAND was made with (a new series starts "
                    "where either changes: compare CAND with a run made since)")  # fmt: skip
    raise ValidationError(f"BASE and CAND are not comparable ({what}): " + "; ".join(problems) + f". Compare runs "
                          f"made with the same {same}: " + "; ".join(todo))  # fmt: skip


def cmd_diff(args: argparse.Namespace) -> int:
    """``lorisnb diff BASE CAND`` (see the exit-status table of docs/guide/regression-gating.md)."""
    from lorisnb.core.stats.regression import parse_tolerances, unjudged_line
    from lorisnb.io.writers import write_csv, write_parquet, write_text
    from lorisnb.tools.decisions.diff import (
        badge,
        diff_tables,
        exit_status,
        github_annotations,
        markdown,
        rename_notes,
        same_run_note,
        verdict_phrase,
        wide_tolerances,
        with_unscored,
        write_json,
        write_junit,
    )
    from lorisnb.tools.decisions.runs import is_report_run, is_table

    refuse_unused(args, UNUSED["diff"])
    if len(args.paths) != 2:
        raise ValidationError(f"diff takes two runs, BASE and CAND; got {len(args.paths)} path(s)")
    check_outputs(args, args.paths, ["json", "junit", "csv", "markdown", "badge"], folders=("parquet",))
    tolerances = parse_tolerances(args.tolerance)
    tables = [is_report_run(Path(p)) or is_table(Path(p)) for p in args.paths]
    given = _given_evaluate_options(args, args.defaults)
    if all(tables) and given:
        raise ValidationError(f"{', '.join(given)}: evaluate options apply to result folders; BASE and CAND are "
                              "tables or report runs, whose numbers are already computed")  # fmt: skip
    if args.baseline == "last-comparable":
        (cand, cand_failed, _) = _side(args.paths[1], args)
        base = _last_comparable(Path(args.paths[0]), cand)
        base_failed = sorted(base.unscored)
        args.paths[0] = str(base.path)
    else:
        (base, _, base_failed), (cand, cand_failed, _) = (_side(p, args) for p in args.paths)
    for note in base.notes + cand.notes:
        say(f"note: {note}")
    for warning in cand.warnings:  # the baseline chosen by time against the dates the runs' names hold
        say(f"warning: {warning}")
    if base.table.empty:  # nothing to compare against: never a verdict of "ok"
        if not base_failed:  # a table or run of no rows: an error about the run, as a damaged one (exit 2)
            raise ValidationError(f"BASE {args.paths[0]} holds no scored sequence (no row at all): nothing can be "
                                  "compared; give a run with results as BASE")  # fmt: skip
        # its inputs could not be evaluated or were not scored: exit 1, as any input that was not
        say(f"error: BASE {args.paths[0]} holds no scored sequence ({len(base_failed)} input(s) could not be "
            "evaluated or were not scored): nothing was compared; give a run with results as BASE")  # fmt: skip
        return 1
    refuse_not_comparable(base, cand)
    for line in wide_tolerances(tolerances, base.table):  # an error's tolerance that hides its regressions
        say(f"warning: {line}")
    _refuse_no_common_algorithm(base, cand, args.paths)
    known = [r.expected for r in (base, cand) if r.expected is not None]  # every ground-truth sequence
    d = diff_tables(base.table, cand.table, tolerances, args.alpha, cand_failed,
                    names=(f"BASE {args.paths[0]}", f"CAND {args.paths[1]}"),
                    expected=pd.concat(known, ignore_index=True) if known else None)  # fmt: skip
    same = same_run_note(base.table, cand.table, f"BASE {args.paths[0]}", f"CAND {args.paths[1]}")
    if args.paths[0] != args.paths[1] and same:  # history says it with the same function
        say(f"note: {same}")
    for note in rename_notes(d, f"BASE {args.paths[0]}", f"CAND {args.paths[1]}"):
        say(f"note: {note}")
    bad = d.sequences[d.sequences["status"].isin(["regression", "missing", "failed"])]
    scene_bad = d.scenes[d.scenes["status"].isin(["regression", "missing", "failed"])]
    print(f"BASE {clean(args.paths[0])} ({base.kind}) against CAND {clean(args.paths[1])} ({cand.kind}); tolerances: "
          + ", ".join(f"{k} {v}" for k, v in tolerances.items()))  # fmt: skip
    counts = d.verdict["counts"]
    print(f"{d.verdict['sequences']} sequence(s); per metric and sequence: " + ", ".join(
        f"{v} {k}" for k, v in counts.items() if v))  # fmt: skip
    if len(bad):
        print("\nregressions per sequence:")
        shown = bad[["algorithm", "scene", "seq", "metric", "base", "cand", "worse_by", "tolerance", "status"]]
        shown = shown.assign(base=[_short(v, args.digits) for v in shown["base"]],
                             cand=[_short(v, args.digits) for v in shown["cand"]])  # fmt: skip
        print(fmt_table(shown, args.digits))
    if len(scene_bad):
        print("\nregressions per scene:")
        print(fmt_table(scene_bad[["algorithm", "scene", "metric", "base", "cand", "worse_by", "p_adj",
                                   "decided_by"]], args.digits))  # fmt: skip
    better = d.verdict["improvements"]
    if better:
        print(f"\nimprovements ({len(better)}):")
        for r in better[:50]:
            where = f"{r['scene']}-{r['seq']}" if r["seq"] is not None else f"{r['scene']} (scene)"
            print(f"  {clean(r['algorithm'])} {clean(where)} {r['metric']}: {_short(r['base'], args.digits)} -> "
                  f"{_short(r['cand'], args.digits)}")  # fmt: skip
        if len(better) > 50:
            print(f"  ... {len(better) - 50} more (--json lists all)")
    for tr in d.verdict["tradeoffs"]:
        print(
            f"trade-off: {clean(tr['algorithm'])} worse in {clean(', '.join(tr['worse']))}; better in "
            f"{clean(', '.join(tr['better']))}"
        )
    if d.verdict["unjudged"]:  # each reason with its count (a lever too short is no count of poses)
        print(f"{unjudged_line(d.verdict['unjudged'])}: listed in --json, never a regression")
    print(f"rule: {d.verdict['rule']}")
    d = with_unscored(d, base_failed, cand_failed)  # every output says what the exit status says
    what = verdict_phrase(d)
    print(f"\nverdict: {d.verdict['verdict']}" + (f" ({clean(what)})" if what else ""))  # names the sequences
    extra = dict(base=args.paths[0], cand=args.paths[1], tolerances={k: str(v) for k, v in tolerances.items()},
                 alpha=args.alpha, base_failed=base_failed, cand_failed=sorted(cand_failed),
                 exit_status=exit_status(d, base_failed, cand_failed))  # fmt: skip
    written = []
    if args.json:
        written.append(write_json(d, args.json, args.force, extra))
    if args.junit:
        written.append(write_junit(d, args.junit, args.force))
    both = pd.concat([d.sequences.assign(level="sequence"), d.scenes.assign(level="scene")], ignore_index=True)
    both = both.astype({"base": str, "cand": str})
    if args.csv:
        written.append(write_csv(both, args.csv, args.force))
    if args.parquet:
        written.append(write_parquet(both, args.parquet, force=args.force))
    if args.markdown:
        written.append(write_text(markdown(d, args.paths[0], args.paths[1], cand.label), args.markdown, args.force))
    if args.badge:
        written.append(write_text(badge(d), args.badge, args.force))
    if args.annotations:
        for line in github_annotations(d):
            print(line)
    for w in written:
        print(f"wrote {w}", file=sys.stderr)
    if base_failed or cand_failed:
        print(f"error: {len(base_failed)} input(s) of BASE and {len(cand_failed)} of CAND could not be evaluated or "
              "were not scored: not every sequence was compared", file=sys.stderr)  # fmt: skip
    return exit_status(d, base_failed, cand_failed)


def cmd_history(args: argparse.Namespace) -> int:
    """``lorisnb history RUN...``: scene values over runs, each run against its last comparable run
    by diff's rule; exit status :func:`lorisnb.tools.decisions.history.newest_verdict`."""
    from lorisnb.core.stats.regression import parse_tolerances
    from lorisnb.io.writers import write_csv
    from lorisnb.tools.decisions.diff import wide_tolerances
    from lorisnb.tools.decisions.history import (
        date_order_warnings,
        drift,
        first_changes,
        history_table,
        load_runs,
        newest_verdict,
        run_labels,
        write_figures,
    )

    check_outputs(args, args.runs, ["csv"], folders=("out",))
    tolerances = parse_tolerances(args.tolerance)
    passed: list[str] = []  # a damaged or foreign older run: passed over, named; a damaged newest one: exit 2
    runs = load_runs(args.runs, passed)
    for note in (n for r in runs for n in r.notes):
        say(f"note: {note}")
    for warning in passed:
        say(f"warning: {warning}")
    for warning in wide_tolerances(tolerances, pd.concat([r.table for r in runs], ignore_index=True)):
        say(f"warning: {warning}")
    for warning in date_order_warnings(runs):
        say(f"warning: {warning}")
    h, diffs = history_table(runs, args.metric, tolerances)
    how = sorted({r.created_from for r in runs})
    print(f"{len(runs)} run(s), oldest first, ordered by {' and '.join(how)}")
    names = run_labels(runs)  # as the table names them: two nightly tables of one file name apart
    first = h.drop_duplicates("run").set_index("run")
    for r, name in zip(runs, names, strict=True):
        base = first.loc[name, "baseline"] if name in first.index else ""
        print(f"  {clean(name)}: {r.created.isoformat() if r.created else '?'}" + (f", lorisnb {clean(r.version)}" if r.version else "")
              + (f", code {clean(r.label)}" if r.label else "") + (f", against {clean(base)}" if base else ""))  # fmt: skip
    for m in args.metric:
        # dropna=False: a run whose values are all missing keeps its column
        view = h[h["metric"] == m].pivot_table(index=["suite", "algorithm", "scene"], columns="run", values="value",
                                              sort=False, dropna=False)  # fmt: skip
        print(f"\n{m} per scene:")
        print(fmt_table(view[[n for n in names if n in view.columns]].reset_index()))
    for r in first[first["not_comparable"].astype(str) != ""].itertuples():
        then = f"; compared with {clean(r.baseline)} instead" if r.baseline else "; a new series starts here"
        print(f"\nnot comparable: {clean(r.Index)} with the run before it ({clean(r.not_comparable)}){then}")
    lines = first_changes(h)
    print("\n" + ("\n".join(clean(x) for x in lines) if lines else "no value changed by diff's rule"))
    rc, verdict_lines = newest_verdict(runs, diffs, names, drift(runs, tolerances))
    print("\n" + "\n".join(clean(x) for x in verdict_lines if not x.startswith("error: ")))
    for x in (x for x in verdict_lines if x.startswith("error: ")):
        print(clean(x), file=sys.stderr)
    if args.csv:
        print(f"wrote {write_csv(h, args.csv, args.force)}", file=sys.stderr)
    if args.out:
        paths = write_figures(h, args.out)
        print(f"wrote {len(paths)} figure file(s) to {args.out}", file=sys.stderr)
    return rc
