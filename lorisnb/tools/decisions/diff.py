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

import pandas as pd

from lorisnb.core.spec import validate
from lorisnb.core.stats.inference import with_trials
from lorisnb.core.stats.regression import Tolerance, parse_tolerances, scene_changes, sequence_changes, verdict
from lorisnb.errors import ValidationError
from lorisnb.io.writers import write_text
from lorisnb.tools.decisions.comparison import check_table_duplicates
from lorisnb.tools.decisions.runs import setting_differences
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
    if "table" not in t.columns and "eps_value" not in t.columns:
        check_table_duplicates(t)  # two files for one sequence: named, with what to do
    dup = t.duplicated(["suite", "algorithm", "scene", "seq", "trial"], keep=False)
    if dup.any():
        r = t[dup].iloc[0]
        raise ValidationError(
            f"{r['algorithm']} {r['scene']}-{r['seq']} (trial {r['trial']}) has several rows"
            f"{' in ' + str(r['table']) if 'table' in t.columns else ''}: a sweep or duplicate files; diff tables of "
            "one setting, with one row per sequence and trial"
        )
    return t


def diff_tables(
    base: pd.DataFrame,
    cand: pd.DataFrame,
    tolerances: Mapping[str, Tolerance] | Mapping[str, str | float] | str | None = None,
    alpha: float = 0.05,
    seed: int = 0,
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
    differ = setting_differences(base, cand, *names)  # the CLI says it for runs; Python callers too
    if differ:
        raise ValidationError(f"{names[0]} and {names[1]} are not comparable (scored with different settings): "
                              + "; ".join(differ) + ". Compare tables scored with the same spec")  # fmt: skip
    b, c = keyed(base, names[0]), keyed(cand, names[1])
    seqs = sequence_changes(b, c, tols, alpha, seed)
    if cand_failures and "file" in b.columns and len(seqs):
        files = b.drop_duplicates(["suite", "algorithm", "scene", "seq"]).set_index(
            ["suite", "algorithm", "scene", "seq"]
        )["file"]
        for i in seqs.index[seqs["status"] == "missing"]:
            f = files.get(tuple(seqs.loc[i, ["suite", "algorithm", "scene", "seq"]]))
            if f in cand_failures:
                seqs.loc[i, ["status", "cand"]] = ["failed", f"failed: {cand_failures[f]}"]
    scenes = scene_changes(b, c, tols, alpha, seed, expected)
    return Diff(seqs, scenes, verdict(seqs, scenes))


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


def write_json(d: Diff, out: str | os.PathLike[str], force: bool, extra: Mapping[str, object]) -> Path:
    """The verdict as JSON: ``verdict``, ``regressions`` and what was compared (``extra``)."""
    body = {**d.verdict, **extra}
    return write_text(json.dumps(body, indent=2, allow_nan=False) + "\n", out, force)


def write_junit(d: Diff, out: str | os.PathLike[str], force: bool) -> Path:
    """JUnit XML: one test case per sequence and per scene value compared (class
    ``suite.algorithm.scene``), failed when it regressed, with each metric's base and candidate."""
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
            cases.append((".".join(x for x in (str(suite), str(alg), str(scene)) if x), name, bad, new))
    root = ET.Element("testsuites", name="lorisnb diff")
    suite_el = ET.SubElement(root, "testsuite", name="lorisnb diff", tests=str(len(cases)),
                             failures=str(sum(len(b) > 0 for _, _, b, _ in cases)),
                             skipped=str(sum(n for *_, n in cases)), errors="0")  # fmt: skip
    for cls, name, bad, new in cases:
        case = ET.SubElement(suite_el, "testcase", classname=cls, name=name)
        if len(bad):
            lines = [f"{r.metric}: {r.status}, base {r.base}, cand {r.cand}" for r in bad.itertuples()]
            fail = ET.SubElement(case, "failure", message="; ".join(lines)[:500], type="regression")
            fail.text = "\n".join(lines)
        elif new:
            ET.SubElement(case, "skipped", message="new in the candidate: not in the base")
    ET.indent(root)
    text = '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
    return write_text(text, out, force)
