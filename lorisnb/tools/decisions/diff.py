"""``lorisnb diff BASE CAND``: the changes between two runs and the verdict
(:mod:`lorisnb.core.stats.regression`), written as JSON and JUnit XML for CI."""

from __future__ import annotations

import json
import os
import xml.etree.ElementTree as ET
from collections.abc import Collection, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from lorisnb.core.spec import validate
from lorisnb.core.stats.inference import with_trials
from lorisnb.core.stats.regression import METRICS, Tolerance, changes, parse_tolerances, unjudged_line, verdict
from lorisnb.errors import ValidationError
from lorisnb.io.writers import write_text
from lorisnb.tools.decisions.comparison import check_table_duplicates
from lorisnb.tools.decisions.escape import clean, code_span, markdown_cell, workflow_data, workflow_property
from lorisnb.tools.decisions.runs import (
    COUNTS,
    INDICES,
    NUMBERS,
    SECONDS,
    mixed_setting,
    out_of_domain,
    repeated_key,
    setting_differences,
    shown,
)
from lorisnb.tools.evaluation.status import OK, UNSCORED

if TYPE_CHECKING:
    from lorisnb.tools.evaluation.result import Evaluation


@dataclass
class Diff:
    """``sequences`` and ``scenes``: the change tables; ``verdict``: the JSON-ready verdict."""

    sequences: pd.DataFrame
    scenes: pd.DataFrame
    verdict: dict

    @property
    def regressed(self) -> bool:
        return self.verdict["verdict"] == "regression"


def keyed(table: pd.DataFrame, name: str | None = None) -> pd.DataFrame:
    """A run's table ready to be matched: ``suite`` and ``trial`` present; one row per sequence and
    trial (a report run's tables are read as one, :func:`lorisnb.tools.decisions.runs.load_run`), else an
    error (a sweep holds several settings: diff one) that begins with ``name`` (the run) if given."""
    try:
        return _keyed(table)
    except ValidationError as exc:
        if name is None:
            raise
        raise ValidationError(f"{name}: {exc}") from None


def _keyed(table: pd.DataFrame) -> pd.DataFrame:
    t = with_trials(table)
    t["suite"] = t["suite"].fillna("").astype(str)
    check_numbers(t)
    if "table" not in t.columns and "eps_value" not in t.columns:
        check_table_duplicates(t)  # two files for one sequence: named, with what to do
    found = repeated_key(t)  # a table read from a file was refused when read, naming its lines (load_run)
    if found is not None:
        rows, what, _ = found
        where = f" in {t['table'].iloc[rows[0]]}" if "table" in t.columns else ""
        raise ValidationError(f"{what} has several rows{where} (rows {', '.join(map(str, rows))}, counted from 0): a "
                              "sweep or duplicate files; diff tables of one setting, with one row per sequence and "
                              "trial")  # fmt: skip
    return t


def check_numbers(t: pd.DataFrame) -> None:
    """The numbers the verdict reads, as a table read from a file is checked
    (:func:`lorisnb.tools.decisions.runs.read_table`): a number where a number is expected, and every
    judged metric in the domain an evaluation writes (a rate in [0, 1], never NaN; an RMSE finite and
    >= 0, NaN only without a pose to take it over); else an error naming the row, the column and the
    value (a table edited by hand, in Python as on the command line: NaN in CR would otherwise be
    "too little to judge", never a regression; ``compare`` took a CR of 1.7 and moved a scene's value by
    0.1 with no word). The columns are made numeric in place."""

    def whole(v: object) -> object:  # a number read as a float (1.0) said as written (1)
        return int(v) if isinstance(v, float) and v.is_integer() else v

    def where(i: int) -> str:
        r = t.iloc[i]
        return f"row {i} ({r.get('algorithm')} {r.get('scene')}-{whole(r.get('seq'))}, trial {whole(r.get('trial'))})"

    for c in (c for c in dict.fromkeys([*NUMBERS, *METRICS, *COUNTS, *INDICES, *SECONDS]) if c in t.columns):
        v = pd.to_numeric(t[c], errors="coerce")
        text = t[c].astype(str).str.strip().str.lower()
        bad = (v.isna() & t[c].notna() & ~text.isin(["nan", "", "none"])).to_numpy()
        if bad.any():
            i = int(bad.nonzero()[0][0])
            raise ValidationError(f"{where(i)}: column {c}: {shown(t[c].iloc[i])} is not a number; expected a "
                                  "per-sequence table as lorisnb evaluate writes it")  # fmt: skip
        t[c] = v.astype(float)
    for c in (c for c in dict.fromkeys([*METRICS, *INDICES, *SECONDS]) if c in t.columns):
        bad, expected = out_of_domain(t, c)
        if bad.any():
            i = int(bad.nonzero()[0][0])
            raise ValidationError(f"{where(i)}: column {c}: {shown(t[c].iloc[i])} is not {expected}; expected a "
                                  "per-sequence table as lorisnb evaluate writes it")  # fmt: skip
    for c in (c for c in INDICES if c in t.columns):  # whole numbers, checked: kept so (a label says 2, not 2.0)
        t[c] = t[c].astype("int64")


#: An error metric's tolerance letting it grow by this factor or more before it counts as worse
#: (:func:`wide_tolerances`): ``ate_rmse=100%``, or an amount as large as BASE's median value.
WIDE_FACTOR = 2.0


def wide_tolerances(tols: Mapping[str, Tolerance], base: pd.DataFrame | None = None) -> list[str]:
    """Warnings for the error metrics (ATE, AOE, RPE: judged as ratios, on a log scale) whose
    tolerance lets the error grow :data:`WIDE_FACTOR`-fold or more before any test, on top of the
    rerun noise the test allows: a percentage of 100 % or more, or an amount in the metric's unit at
    least BASE's median value of it (``ate_rmse=10`` is 10 m, against OpenLORIS' ATEs of centimetres
    to a few metres; known only with ``base``). A rate's tolerance of 1 or more is refused
    (no drop of a rate in [0, 1] exceeds it); an error has no upper bound, so no tolerance makes a
    regression impossible, but such a one hides nearly every real one: ``ate_rmse=1000%`` and
    ``ate_rmse=10`` were taken without a word."""
    from lorisnb.core.stats.regression import LOG_METRICS

    out = []
    for m, tol in tols.items():
        if m not in LOG_METRICS:
            continue
        if tol.relative:
            factor, at = 1 + tol.amount, ""
        else:
            values = pd.to_numeric(base[m], errors="coerce") if base is not None and m in base.columns else None
            values = values[(values > 0) & np.isfinite(values)] if values is not None else None
            if values is None or not len(values):
                continue
            median = float(values.median())
            factor, at = 1 + tol.amount / median, f" at BASE's median {m} ({median:.4g})"
        if factor >= WIDE_FACTOR:
            out.append(f"tolerance {m}={tol}: lets {m} grow {factor:.3g}-fold{at} before it counts as worse, on top "
                       f"of the rerun noise the test allows, so a regression of {m} will hardly ever be found; "
                       f"an error's tolerance is best a percentage of BASE's value (default {m}=10%)")  # fmt: skip
    return out


def diff_tables(
    base: pd.DataFrame,
    cand: pd.DataFrame,
    tolerances: Mapping[str, Tolerance] | Mapping[str, str | float] | str | None = None,
    alpha: float = 0.05,
    cand_failures: Mapping[str, str] | None = None,
    names: tuple[str, str] = ("BASE", "CAND"),
    expected: pd.DataFrame | None = None,
) -> Diff:
    """Compare two per-sequence tables (``Evaluation.sequences(...)``, or tables read back).
    ``tolerances``: :func:`lorisnb.core.stats.regression.parse_tolerances` of them, or the parsed ones
    (None: the defaults). ``cand_failures`` maps a result file (relative path, as in the ``file``
    column) that the candidate could not evaluate to the reason: a base sequence from that file is
    reported as failed, with the reason. ``names``: how a table's own error names it. ``expected``:
    every ground-truth sequence of the scenes (``Evaluation.durations()``, a report run's
    ``findings/durations.csv``), so that scene values count the sequences without a row as failed,
    as ``compare`` and the leaderboard do (see :func:`lorisnb.core.stats.regression.scene_changes`)."""
    tols: dict[str, Tolerance]
    if isinstance(tolerances, Mapping) and all(isinstance(v, Tolerance) for v in tolerances.values()):
        tols = {k: v for k, v in tolerances.items() if isinstance(v, Tolerance)}
    else:
        tols = parse_tolerances(tolerances)  # type: ignore[arg-type]
    for name, value in zip(names, (base, cand), strict=True):
        if not isinstance(value, pd.DataFrame):
            raise ValidationError(f"{name}: expected a per-sequence table (a DataFrame), got {type(value).__name__}")
    alpha = validate.probability("alpha", alpha)
    for name, value in zip(names, (base, cand), strict=True):  # as a table read from a file is refused
        mixed = mixed_setting(value)
        if mixed is not None:
            same, other, what = mixed
            raise ValidationError(f"{name} holds two settings for {what} (rows {_some(same)} against rows "
                                  f"{_some(other)}, counted from 0): its scene value would average rows scored two "
                                  "ways; score every row with one spec and one set of thresholds")  # fmt: skip
    differ = setting_differences(base, cand, *names)  # the CLI says it for runs; Python callers too
    if differ:
        raise ValidationError(f"{names[0]} and {names[1]} are not comparable (scored with different settings): "
                              + "; ".join(differ) + ". Compare tables scored with the same spec")  # fmt: skip
    b, c = keyed(base, names[0]), keyed(cand, names[1])
    seqs, scenes = changes(b, c, tols, alpha, expected)
    if cand_failures and "file" in b.columns and len(seqs):
        files = b.drop_duplicates(["suite", "algorithm", "scene", "seq"]).set_index(
            ["suite", "algorithm", "scene", "seq"]
        )["file"]
        for i in seqs.index[seqs["status"] == "missing"]:
            f = files.get(tuple(seqs.loc[i, ["suite", "algorithm", "scene", "seq"]]))
            if f in cand_failures:
                seqs.loc[i, ["status", "cand"]] = ["failed", f"failed: {cand_failures[f]}"]
    return Diff(seqs, scenes, verdict(seqs, scenes))


def _some(rows: list[int]) -> str:
    return ", ".join(map(str, rows[:5])) + (f" and {len(rows) - 5} more" if len(rows) > 5 else "")


def same_values(base: pd.DataFrame, cand: pd.DataFrame) -> bool:
    """Whether two per-sequence tables hold the same sequences and trials with every judged value
    (:data:`~lorisnb.core.stats.regression.METRICS`) equal: one run kept twice (a copy of tonight's
    run among the earlier ones), or a system whose every rerun is alike. ``diff`` says so: its "ok"
    then compared a run with itself."""
    b, c = keyed(base), keyed(cand)
    keys = ["suite", "algorithm", "scene", "seq", "trial"]
    cols = [m for m in METRICS if m in b.columns and m in c.columns]
    if len(b) != len(c) or not len(b):
        return False
    x, y = (t.sort_values(keys)[keys + cols].reset_index(drop=True) for t in (b, c))
    return bool(x[keys].astype(str).equals(y[keys].astype(str))) and bool(
        ((x[cols] == y[cols]) | (x[cols].isna() & y[cols].isna())).all().all()
    )


def same_run_note(base: pd.DataFrame, cand: pd.DataFrame, base_name: str, cand_name: str) -> str | None:
    """The note ``diff`` and ``history`` give when BASE holds every value of CAND
    (:func:`same_values`): the same run kept twice is no baseline ("ok" compared a run with itself: a
    copy of CAND kept among the earlier runs, or a CI job that re-uploaded the previous night's
    table after its own run crashed). None where the values differ. The exit status is the
    comparison's own (a run equal to its baseline is "ok", exit 0): the note says why that says
    nothing."""
    if not same_values(base, cand):
        return None
    return (f"{base_name} holds every value of {cand_name}, to the last digit: the same run kept twice (a copy of "
            f"{cand_name} among the earlier runs, or the earlier run's table uploaded again as {cand_name} after "
            "its own run failed?) is no baseline; reruns of a system differ")  # fmt: skip


def renamed(d: Diff) -> list[tuple[str, str, str, int]]:
    """The algorithms CAND seems to have renamed: (suite, the name BASE had, the new name, how many
    sequences). An algorithm of BASE every sequence of which is missing in CAND, and an algorithm
    new in CAND (none of its sequences in BASE) of the same suite holding exactly the same
    sequences (scene and number; its trials are not counted: a crashed trial is judged apart). Only
    an exact match of the sequences: a new algorithm that holds one sequence more or less is
    another algorithm, or a rename that also lost a sequence, and is not named."""
    s = d.sequences
    if s.empty:
        return []
    whole = s[s["metric"] == "sequence"]
    names = s.groupby(["suite", "algorithm"], sort=False)["status"]
    lost_algs = [k for k, g in names if set(g) == {"missing"}]
    new_algs = [k for k, g in names if set(g) == {"new"}]
    if not lost_algs or not new_algs:
        return []

    def held(key: tuple) -> frozenset:
        g = whole[(whole["suite"] == key[0]) & (whole["algorithm"] == key[1])]
        return frozenset(zip(g["scene"].astype(str), g["seq"].astype(int), strict=True))

    new_seqs = {k: held(k) for k in new_algs}
    out = []
    for key in lost_algs:
        seqs = held(key)
        out += [(str(key[0]), str(key[1]), str(n[1]), len(seqs)) for n, ns in new_seqs.items()
                if n[0] == key[0] and seqs and ns == seqs]  # fmt: skip
    return out


def rename_notes(d: Diff, base_name: str, cand_name: str, series: bool = False) -> list[str]:
    """What ``diff`` (and ``history``, with ``series``) says of each likely rename (:func:`renamed`):
    the verdict is kept (a sequence missing is missing), the note says why every later night will
    fail the same way and what to do."""
    out = []
    for suite, old, new, n in renamed(d):
        of = f" ({suite})" if suite else ""
        then = (f"or keep the new name and start a new series from {cand_name} (give history {cand_name} and the "
                "runs after it)" if series else f"or keep the new name and compare with a baseline made with it "
                f"(--baseline a run holding {new})")  # fmt: skip
        out.append(f"{new}{of} in {cand_name} holds exactly the {n} sequence(s) {old} had in {base_name}, and {old} is "
                   f"missing from {cand_name}: renamed? The verdict counts {old}'s sequences missing, and every "
                   f"run after it will too: rename it back ({old}/ in the results), {then}")  # fmt: skip
    return out


def unevaluated(ev: Evaluation, root: str | os.PathLike[str]) -> dict[str, str]:
    """The inputs of a result folder's evaluation that were not scored, as ``diff`` counts them for
    its exit status: the failures (a file that could not be read or evaluated) and the inputs read
    but not scored (:attr:`~lorisnb.tools.evaluation.result.Evaluation.unscored`: no pose matched the
    ground truth in time, a declared manifest session without an estimate, an empty estimate, an
    evaluation of nothing), each by its path relative to ``root`` (its name if outside) with the
    reasons. ``evaluate``, ``sweep`` and ``compare`` exit 1 on the same inputs
    (:func:`lorisnb.tools.evaluation.status.exit_status`); so does ``diff`` (:func:`exit_status`)."""
    base = Path(root)
    base = base if base.is_dir() else base.parent
    out: dict[str, str] = {}
    for f in [*ev.failures, *ev.unscored]:
        try:
            key = Path(f.path).relative_to(base).as_posix()
        except ValueError:
            key = Path(f.path).name
        out[key] = f"{out[key]}; {f.error}" if key in out else f.error
    return out


def exit_status(d: Diff, base_failed: Collection[str], cand_failed: Collection[str]) -> int:
    """``diff``'s exit status: 1 when CAND regressed or an input of either run was not evaluated or
    not scored (:func:`unevaluated`), so that 0 tells a script that every input was scored and
    nothing regressed; else 0."""
    return UNSCORED if d.regressed or base_failed or cand_failed else OK


#: The verdict of a diff with no regression where an input of either run was not scored: not "ok".
INCOMPLETE = "incomplete"


def with_unscored(d: Diff, base_failed: Collection[str], cand_failed: Collection[str]) -> Diff:
    """``d`` with the inputs of either run that were not evaluated or not scored (:func:`unevaluated`,
    a report run's ``findings/input_errors.csv``) in its verdict (``unscored_inputs``: ``base`` and
    ``cand``, each sorted), and a verdict of ``"ok"`` made :data:`INCOMPLETE`: every output (the JSON,
    JUnit's error cases, the Markdown, the annotations, the badge) then says what the exit status
    says (1). They said "ok", a green badge and no failed test, while ``diff`` exited 1."""
    if not base_failed and not cand_failed:
        return d
    v = dict(d.verdict, unscored_inputs=dict(base=sorted(base_failed), cand=sorted(cand_failed)))
    if v["verdict"] == "ok":
        v["verdict"] = INCOMPLETE
    return Diff(d.sequences, d.scenes, v)


def unscored_lines(d: Diff) -> list[tuple[str, str]]:
    """(run, input) of every input the verdict records as not scored (:func:`with_unscored`)."""
    u = d.verdict.get("unscored_inputs") or {}
    return [(side.upper(), f) for side in ("base", "cand") for f in u.get(side, [])]


def verdict_phrase(d: Diff) -> str:
    """What the verdict's line adds in brackets: what regressed
    (:func:`~lorisnb.core.stats.regression.regressed_phrase`), and the inputs not scored."""
    from lorisnb.core.stats.regression import regressed_phrase

    n = len(unscored_lines(d))
    lost = f"{n} input(s) not scored: not every sequence was compared" if n else ""
    what = regressed_phrase(d.verdict) if d.regressed else ""
    return "; ".join(x for x in (what, lost) if x)


def write_json(d: Diff, out: str | os.PathLike[str], force: bool, extra: Mapping[str, object]) -> Path:
    """The verdict as JSON: ``verdict``, ``regressions`` and what was compared (``extra``)."""
    body = {**d.verdict, **extra}
    return write_text(json.dumps(body, indent=2, allow_nan=False) + "\n", out, force)


def write_junit(d: Diff, out: str | os.PathLike[str], force: bool) -> Path:
    """JUnit XML: one test case per sequence and per scene value compared (class
    ``suite.algorithm.scene``), failed when it regressed, with each metric's base and candidate;
    improvements and comparisons too little to judge as the case's properties. Every name and
    value in it escaped as the terminal shows them (:func:`~lorisnb.tools.decisions.escape.clean`):
    a control character of a folder name, which XML 1.0 cannot hold, never reaches the file."""
    cases = []
    for level, t in (("sequence", d.sequences), ("scene", d.scenes)):
        if t.empty:
            continue
        keys = ["suite", "algorithm", "scene"] + (["seq"] if level == "sequence" else [])
        for key, g in t.groupby(keys, sort=False, dropna=False):
            suite, alg, scene = key[:3]
            name = f"{scene}-{key[3]}" if level == "sequence" else f"{scene} (scene)"
            bad = g[g["status"].isin(["regression", "missing", "failed"])]
            new = bool((g["status"] == "new").all())
            notes = [f"{r.status}: {r.metric} {r.base} -> {r.cand}" for r in g.itertuples()
                     if r.status in ("improvement", "unjudged")]  # fmt: skip
            cases.append((".".join(x for x in (str(suite), str(alg), str(scene)) if x), name, bad, new, notes))

    def element(parent: ET.Element, tag: str, text: str | None = None, **attrs: str) -> ET.Element:
        el = ET.SubElement(parent, tag, {k: clean(v) for k, v in attrs.items()})
        if text is not None:
            el.text = "\n".join(clean(line) for line in text.split("\n"))  # its own lines kept, a name's escaped
        return el

    lost = unscored_lines(d)  # an input not scored: an error case each (the exit status is 1)
    root = ET.Element("testsuites", name="lorisnb diff")
    suite_el = element(root, "testsuite", name="lorisnb diff", tests=str(len(cases) + len(lost)),
                       failures=str(sum(len(c[2]) > 0 for c in cases)), skipped=str(sum(c[3] for c in cases)),
                       errors=str(len(lost)))  # fmt: skip
    for side, f in lost:
        case = element(suite_el, "testcase", classname=f"inputs.{side}", name=f)
        element(case, "error", f"{side} input {f} could not be evaluated or was not scored",
                message=f"{side} input not scored: {f}"[:500], type="not scored")  # fmt: skip
    for cls, name, bad, new, notes in cases:
        case = element(suite_el, "testcase", classname=cls, name=name)
        if notes:  # improvements and what was too little to judge, named beside the verdict
            props = element(case, "properties")
            for k, note in enumerate(notes):
                element(props, "property", name=f"note{k + 1}", value=note)
        if len(bad):
            lines = [clean(f"{r.metric}: {r.status}, base {r.base}, cand {r.cand}") for r in bad.itertuples()]
            element(case, "failure", "\n".join(lines), message="; ".join(lines)[:500], type="regression")
        elif new:
            element(case, "skipped", message="new in the candidate: not in the base")
    ET.indent(root)
    text = '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
    return write_text(text, out, force)


def _where(r: Mapping) -> str:
    return f"{r['scene']}-{r['seq']}" if r["seq"] is not None else f"{r['scene']} (scene)"


def _value(v: object) -> str:
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def markdown(d: Diff, base: str, cand: str, label: str | None = None) -> str:
    """The verdict as Markdown, for a pull-request comment or a CI job summary: the verdict, the
    counts, regressions, improvements, trade-offs and what was too little to judge. Names and
    values escaped (:func:`~lorisnb.tools.decisions.escape.markdown_cell`, and
    :func:`~lorisnb.tools.decisions.escape.code_span` for the runs and the code's label): shown as the
    terminal shows them, never a row, tag or link of their own making."""
    md = markdown_cell
    v = d.verdict
    icon = "❌" if d.regressed else "⚠️" if v["verdict"] == INCOMPLETE else "✅"
    lines = [f"## {icon} lorisnb diff: {v['verdict']}", ""]
    lines.append(
        f"{code_span(base)} → {code_span(cand)}" + (f" (code under test: {code_span(label)})" if label else "")
    )
    lines.append("")
    counts = ", ".join(f"{n} {k}" for k, n in v["counts"].items() if n)
    lines.append(f"{v['sequences']} sequence(s); per metric and sequence: {counts or 'nothing compared'}.")
    if v.get("rule"):
        lines.append(f"Rule: {md(v['rule'])}")
    lost = unscored_lines(d)
    if lost:
        lines += ["", f"### Inputs not scored ({len(lost)}): not every sequence was compared", ""]
        lines += [f"- {side}: {code_span(f)}" for side, f in lost[:200]]
    for title, rows in (("Regressions", v["regressions"]), ("Improvements", v["improvements"])):
        if not rows:
            continue
        lines += ["", f"### {title} ({len(rows)})", "", "| algorithm | where | metric | base | cand | decided by |",
                  "|---|---|---|---|---|---|"]  # fmt: skip
        for r in rows[:200]:
            cells = (r["algorithm"], _where(r), r["metric"], _value(r["base"]), _value(r["cand"]),
                     r["decided_by"] or "")  # fmt: skip
            lines.append("| " + " | ".join(map(md, cells)) + " |")
        if len(rows) > 200:
            lines.append(f"| … {len(rows) - 200} more (the JSON has all) | | | | | |")
    if v["tradeoffs"]:
        lines += ["", "### Trade-offs", ""]
        for t in v["tradeoffs"]:
            lines.append(
                f"- **{md(t['algorithm'])}**: worse {md(', '.join(t['worse']))}; better {md(', '.join(t['better']))}"
            )
    if v["unjudged"]:
        lines += [
            "",
            f"{unjudged_line(v['unjudged'])}; the JSON lists them.",
        ]
    return "\n".join(lines) + "\n"


def github_annotations(d: Diff) -> list[str]:
    """GitHub Actions workflow commands: an ``::error`` per regression, a ``::notice`` per
    improvement; names and values escaped as the terminal shows them, then as GitHub's runner
    decodes them (:func:`~lorisnb.tools.decisions.escape.workflow_property` for the title,
    :func:`~lorisnb.tools.decisions.escape.workflow_data` for the message)."""
    out = [f"::error title={workflow_property(f'lorisnb diff: {side} input not scored')}::"
           f"{workflow_data(f'{f} could not be evaluated or was not scored: not every sequence was compared')}"
           for side, f in unscored_lines(d)]  # fmt: skip
    for kind, rows in (("error", d.verdict["regressions"]), ("notice", d.verdict["improvements"])):
        for r in rows:
            title = workflow_property(f"lorisnb diff: {r['status']} {r['algorithm']} {_where(r)}")
            message = workflow_data(f"{r['metric']}: {_value(r['base'])} -> {_value(r['cand'])}")
            out.append(f"::{kind} title={title}::{message}")
    return out


def badge(d: Diff) -> str:
    """An SVG badge (flat, offline: no font or script fetched): ``lorisnb diff | ok`` in green, or
    ``regression (N)`` in red."""
    from xml.sax.saxutils import escape

    n = d.verdict["regressed_sequences"] + len([r for r in d.verdict["regressions"] if r["seq"] is None])
    right, colour = ("ok", "#2e7d32") if not d.regressed else (f"regression ({n})", "#c62828")
    if not d.regressed and d.verdict["verdict"] == INCOMPLETE:
        right, colour = f"incomplete ({len(unscored_lines(d))} not scored)", "#e65100"
    left = "lorisnb diff"
    wl, wr = 6 * len(left) + 12, 6 * len(right) + 12
    return (f'<svg xmlns="http://www.w3.org/2000/svg" width="{wl + wr}" height="20" role="img" '
            f'aria-label="{escape(left)}: {escape(right)}"><title>{escape(left)}: {escape(right)}</title>'
            f'<rect width="{wl}" height="20" fill="#555"/><rect x="{wl}" width="{wr}" height="20" fill="{colour}"/>'
            f'<g fill="#fff" font-family="DejaVu Sans,Verdana,sans-serif" font-size="11">'
            f'<text x="6" y="14">{escape(left)}</text><text x="{wl + 6}" y="14">{escape(right)}</text></g></svg>\n')  # fmt: skip
