"""Runs as ``diff`` and ``history`` read them: a report run folder (``run.json`` and the CSV tables
its notebooks wrote), or a per-sequence table as ``lorisnb evaluate --csv`` / ``--parquet`` writes it.

A run's **spec** is what its numbers depend on besides the estimates: the ``spec`` of ``run.json``
when there is one (its ``values`` but those of :data:`NOT_NUMBERS`: where the results live and the
leaderboard's test settings), and the thresholds recorded in the table's own columns (``eps``,
``phi``, ``delta``, ``tau`` per scene, ``official_interpolation``). Two runs are comparable when their
specs agree (:func:`spec_differences`, which names every key that differs).

A report run holds a sequence in several tables (the report's own ``findings/sequences.csv`` and
each notebook's, at the notebook's own settings, simulated algorithms too): the report's own table
(:data:`FIRST_TABLE`) is the run, with the report's ``findings/durations.csv`` (every ground-truth
sequence of its scenes: a sequence no row holds counts as failed in a scene value, as in the
leaderboard). A run whose run.json records no evaluation of the report's own (its spec has no
``values``: no findings were written) is read from its notebooks' tables, each sequence once, from
the first table that holds it by path; a run that records one but lost its findings (or whose
``findings`` is a link leading out of it) is refused, naming them.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterator
from dataclasses import dataclass, field
from datetime import datetime, timezone
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from lorisnb.core.metrics.openloris import RATES
from lorisnb.core.spec import validate
from lorisnb.core.spec.evalspec import PRESETS, EvalSpec
from lorisnb.core.stats.inference import WEIGHTS as STATS_WEIGHTS
from lorisnb.core.stats.inference import with_trials
from lorisnb.core.stats.regression import METRICS
from lorisnb.errors import DataNotFoundError, ParseError, ValidationError
from lorisnb.tools.notebook.start import INPUT_ERRORS_CSV
from lorisnb.tools.report.provenance import (  # created_of: history reads it from here
    RUN_JSON,
    created_of,
    read_run_json,
    run_file,
    spec_problem,
)

#: Columns a per-sequence table must have to be read as one.
REQUIRED = ["algorithm", "scene", "seq", "cr", "eps", "phi", "delta", "tau"]
#: Columns that hold numbers besides the metrics (:data:`lorisnb.core.stats.regression.METRICS`) and weights.
NUMBERS = ["matched", *(w for w in STATS_WEIGHTS.values() if w)]
#: Table columns that are part of the spec (per scene).
SPEC_COLUMNS = ["eps", "phi", "delta", "tau", "official_interpolation", "spec"]
#: A row's key: one row per sequence and trial of a suite.
KEYS = ["suite", "algorithm", "scene", "seq", "trial"]
#: The report's own per-sequence table, read first (evaluated at run.json's spec).
FIRST_TABLE = "findings/sequences.csv"
#: Keys of run.json's ``spec.values`` that do not change a per-sequence number: the results folder
#: (``source``), the leaderboard's test settings and its selection of rows.
NOT_NUMBERS = frozenset({"source", "metric", "alpha", "level", "seed", "algorithms", "scenes"})


@dataclass
class Run:
    """One run: its per-sequence ``table`` (a ``table`` column names the CSV it came from inside a
    report run), the ``meta`` of its run.json ({} for a bare table), when it was made (``created``:
    run.json's, else the file's modification time; ``created_from`` says which), and ``kind``."""

    path: Path
    kind: str  # "report", "table"
    table: pd.DataFrame
    meta: dict[str, Any] = field(default_factory=dict)
    created: datetime | None = None
    created_from: str = ""
    notes: list[str] = field(default_factory=list)
    #: inputs of a report run's own evaluation that failed or were not scored (file -> reason)
    unscored: dict[str, str] = field(default_factory=dict)
    #: every ground-truth sequence of the scenes evaluated (``scene``, ``seq``, ``gt_duration``), when
    #: known: a scene value counts the sequences no row holds as failed, as ``compare`` does
    expected: pd.DataFrame | None = None
    #: what may make a decision about the run wrong (the baseline chosen for it by time where the
    #: names of the runs say another order), said as warnings
    warnings: list[str] = field(default_factory=list)

    @property
    def name(self) -> str:
        return self.path.name

    @property
    def version(self) -> str | None:
        v = self.meta.get("lorisnb_version")
        return None if v is None else str(v)

    @property
    def spec(self) -> Any:
        return self.meta.get("spec")

    @property
    def label(self) -> str | None:
        """The code under test, as the run recorded it (``report --label``, run.json's ``label``)."""
        v = self.meta.get("label")
        return None if v in (None, "") else str(v)

    def groundtruth_sums(self) -> dict[str, str]:
        """name -> sha256 of the ground-truth files among run.json's inputs."""
        inputs = self.meta.get("inputs") or {}
        if not isinstance(inputs, dict):
            return {}
        return {Path(p).name: str(h) for p, h in inputs.items() if "groundtruth" in str(p) or "gt_" in Path(p).name}

    def table_spec(self) -> pd.DataFrame:
        """The spec columns per scene (one row per distinct setting)."""
        return table_settings(self.table)

    def sources(self) -> list[Path]:
        """The files a decision about the run reads: a report run's ``run.json``, its per-sequence
        tables (the ``table`` column), its table of ground-truth sequences and of inputs not
        scored, where it has them; a table's file, or every file of a Parquet dataset folder. A
        report run made against this one records them with their SHA-256 (``baseline_inputs`` of
        its run.json), so that ``verify`` tells a baseline changed since."""
        p = self.path
        if self.kind != "report":
            return [p] if p.is_file() else sorted(f for f in p.rglob("*") if f.is_file())
        tables = sorted({str(t) for t in self.table["table"]}) if "table" in self.table.columns else []
        names = dict.fromkeys([RUN_JSON, *tables, DURATIONS, f"findings/{INPUT_ERRORS_CSV}"])
        return [p / n for n in names if (p / n).is_file()]


def table_settings(table: pd.DataFrame) -> pd.DataFrame:
    """A per-sequence table's spec columns (:data:`SPEC_COLUMNS`) per scene, one row per distinct
    setting, as text."""
    cols = [c for c in SPEC_COLUMNS if c in table.columns]
    keys = ["table"] if "table" in table.columns else []
    return table[keys + ["scene"] + cols].astype(str).drop_duplicates().sort_values(keys + ["scene"] + cols)


def is_table(path: Path) -> bool:
    """A CSV or Parquet file, or a Parquet dataset folder (``algorithm=NAME/`` parts)."""
    if path.is_file():
        return path.suffix.lower() in (".csv", ".parquet")
    return path.is_dir() and (any(path.glob("algorithm=*")) or any(path.glob("*.parquet")))


def holds_run_json(path: Path) -> bool:
    """A folder with a ``run.json`` entry, whatever it is (a damaged received run's may be a FIFO):
    a report run, readable or not (:func:`is_report_run` refuses the damaged one)."""
    return path.is_dir() and os.path.lexists(path / RUN_JSON)


def is_report_run(path: Path) -> bool:
    """A folder holding ``run.json``. One whose ``run.json`` is no regular file (a FIFO, a device:
    a received run's) or a link leading out of it is refused (:func:`run_file`), never taken for a
    result folder."""
    if not path.is_dir():
        return False
    marker = path / RUN_JSON
    if os.path.lexists(marker):
        run_file(path, marker)
    return marker.is_file()


#: What a per-sequence table read back should be, ending every message that refuses one.
PER_SEQUENCE = "a per-sequence table as written by lorisnb evaluate --csv / --parquet"


def read_table(path: Path) -> pd.DataFrame:
    """A per-sequence table from CSV (:func:`read_csv`: its shape checked first) or Parquet, checked
    as a run is judged: its columns and values (:func:`check_values`) and one row per sequence and
    trial (:func:`check_keys`). Every check a table must pass to be judged is made here, when the
    run is read: a table failing one is a damaged run, passed over by ``history``, ``diff
    --baseline last-comparable`` and ``report --baseline`` where it is older than the run judged (a
    row repeated was found only when two runs were compared, so the damaged night was taken as a
    baseline, exit 2, the newest night's regression never judged)."""
    return check_settings(check_keys(_table_rows(path), path, PER_SEQUENCE), path, PER_SEQUENCE)


def _table_rows(path: Path) -> pd.DataFrame:
    """A per-sequence table as :func:`read_table` reads it, its rows not yet checked to hold each
    sequence and trial once (a notebook's sweep holds several: :func:`_report_tables` leaves it out)."""
    try:
        if path.is_file() and path.suffix.lower() == ".csv":
            df = read_csv(path, PER_SEQUENCE)
        else:
            df = pd.read_parquet(path)
    except ImportError:
        from lorisnb.errors import MissingDependencyError

        raise MissingDependencyError("reading Parquet needs pyarrow: pip install 'lorisnb[parquet]'") from None
    except ParseError:
        raise
    except (ValueError, OSError) as exc:
        raise ParseError(path, None, f"not a readable CSV or Parquet table ({exc})") from None
    missing = [c for c in dict.fromkeys([*REQUIRED, *NEEDED]) if c not in df.columns]
    if missing:
        raise ParseError(path, None, f"lacks column(s) {', '.join(missing)}; expected {PER_SEQUENCE}")
    return check_values(df, path, PER_SEQUENCE)


def read_csv(path: Path, expected: str, **options: Any) -> pd.DataFrame:
    """A CSV table lorisnb wrote, read back by pandas (``options``: :func:`pandas.read_csv`'s) once
    its shape is checked (:func:`csv_records`): a header naming each column once, and every row
    with as many fields as the header. Else a :class:`~lorisnb.errors.ParseError` naming the file,
    the line and what is wrong, ending with ``expected``: pandas would silently rename a second
    column of one name, fill a short row with NaN, and take an extra field in every row for the
    row's name (every column shifted by one)."""
    header: list[str] | None = None
    for line, record in csv_records(path, expected):
        if header is None:
            header = record
            seen: dict[str, int] = {}
            for k, name in enumerate(record, 1):
                if name in seen:
                    raise ParseError(path, line, f"column {name!r} is named twice in the header (fields {seen[name]} "
                                     f"and {k}); expected one column of each name, {expected}")  # fmt: skip
                seen[name] = k
        elif len(record) != len(header):
            why = "cells left out?" if len(record) < len(header) else "an unquoted comma, or a cell without a column?"
            raise ParseError(path, line, f"the row has {len(record)} field(s) against the header's {len(header)} "
                             f"({why}); expected {expected}")  # fmt: skip
    return pd.read_csv(path, **options)


def csv_records(path: Path, expected: str = "a CSV table") -> Iterator[tuple[int, list[str]]]:
    """The records of a CSV file (blank lines left out, as pandas leaves them out), each with the
    line of the file it begins on. Lines end at a newline only, as editors and ``grep -n`` count
    them: a carriage return inside a quoted cell (a folder name may hold one) ends none, and a
    file written with CRLF reads as well. A carriage return outside a quoted cell (pandas would
    end a row there) is refused, naming the line."""
    import csv

    with open(path, "rb") as f:
        lines = (raw.decode("utf-8-sig" if k == 0 else "utf-8", "replace") for k, raw in enumerate(f))
        reader = csv.reader(lines)
        end = 0  # the line the last record ended on
        while True:
            try:
                record = next(reader)
            except StopIteration:
                return
            except csv.Error:
                raise ParseError(path, reader.line_num, "a carriage return outside a quoted cell (lorisnb quotes "
                                 f"a cell that holds one); expected {expected}") from None  # fmt: skip
            if record:
                yield end + 1, record
            end = reader.line_num


#: Columns the verdict reads besides :data:`REQUIRED`: the scene values' metrics and their weights
#: (:data:`lorisnb.core.stats.inference.WEIGHTS`) and the matched poses. Every table lorisnb
#: evaluate writes has them, under every preset; a table without one is refused, naming it.
NEEDED = ["matched", *STATS_WEIGHTS, *(w for w in STATS_WEIGHTS.values() if w)]
#: Counts of a per-sequence table, and the count each error metric is NaN with (no pose or pair to
#: take it over): the only place an evaluation writes NaN in the columns diff and history judge.
COUNTS = ("matched", "c_matched", "rpe_pairs", "c_rpe_pairs")
NAN_WHEN_NONE = {"ate_rmse": "matched", "aoe_rmse": "matched", "c_ate_rmse": "c_matched", "c_aoe_rmse": "c_matched",
                 "rpe_trans_rmse": "rpe_pairs", "rpe_rot_rmse": "rpe_pairs", "rotation_lever": "matched"}  # fmt: skip
#: A row's numbers (whole numbers >= 0): its sequence and trial, matched between runs.
INDICES = {"seq": "a sequence number", "trial": "a trial number"}
#: Durations the scene values are weighted by (seconds): finite and >= 0, never NaN (a sequence
#: without a match has a ground-truth duration and tracks 0 s).
SECONDS = ("gt_duration", "track_time")
#: Labels a row is matched and grouped by: never empty (an algorithm or scene named by no one).
LABELS = {"algorithm": "an algorithm name", "scene": "a scene name"}
#: Yes-or-no columns: whether the first pose was correct (CS-R's tie rule), the official interpolation:
#: ``True`` or ``False`` as evaluate writes them (any case, as pandas reads them; a Parquet table's booleans),
#: never 1 or 0 (a number in a yes-or-no column is some other column's, or an edit).
FLAGS = ("first_correct", "official_interpolation")
#: Every numeric column :func:`check_values` reads.
NUMERIC = list(dict.fromkeys([*NUMBERS, *METRICS, *COUNTS, *NAN_WHEN_NONE, *INDICES, *SECONDS]))


def check_values(df: pd.DataFrame, path: Path, expected: str) -> pd.DataFrame:
    """``df`` (read from ``path``) with every value diff and history read checked by one rule
    (:func:`out_of_domain`), labels in NFC and numbers made numeric; else a
    :class:`~lorisnb.errors.ParseError` naming the file, the line (CSV) or row, the column and
    the value, ending with ``expected`` (what the file should be). Thresholds (``eps``, ``phi``,
    ``delta``, ``tau``) are checked as the command line checks them."""
    place = row_place(path)

    def refuse(i: int, c: str, what: str) -> ParseError:
        line = place(i)[0]
        at = "" if line is not None else f"{rows_said(path, [i])}: "  # a Parquet table's row, and its file
        return ParseError(path, line, f"{at}column {c}: {what}; expected {expected}")

    for c in ("algorithm", "scene", "suite", "file"):  # labels as evaluations make them (NFC): one algorithm
        if c in df.columns:  # whether a table was written from an NFD folder name or not
            df[c] = df[c].astype(str).where(df[c].notna(), "").map(validate.label)
    for c, words in LABELS.items():
        if c in df.columns:
            empty = (df[c].str.strip() == "").to_numpy()
            if empty.any():
                raise refuse(int(empty.nonzero()[0][0]), c, f"an empty cell is not {words}")
    for c in (c for c in NUMERIC if c in df.columns):
        if not pd.api.types.is_numeric_dtype(df[c]) or pd.api.types.is_bool_dtype(df[c]):
            text = df[c].astype(str).str.strip()
            values = pd.to_numeric(text.replace({"": None}), errors="coerce")
            words = text.str.lower()  # True and False are not the numbers 1 and 0 here
            bad = (values.isna() & df[c].notna() & (words != "nan")) | words.isin(["true", "false"])
            if bad.any():
                i = int(bad.to_numpy().nonzero()[0][0])
                raise refuse(i, c, f"{shown(df[c].iloc[i])} is not a number")
            df[c] = values
    for c in (c for c in FLAGS if c in df.columns):
        text = df[c].astype(str).str.strip().str.lower()
        bad = ~text.isin(["true", "false"]).to_numpy()
        if bad.any():
            i = int(bad.nonzero()[0][0])
            raise refuse(i, c, f"{shown(df[c].iloc[i])} is not True or False (as lorisnb evaluate writes a yes or no)")
        df[c] = (text == "true").to_numpy()
    for c in (c for c in NUMERIC if c in df.columns):  # a number no evaluation gives: a damaged table
        bad, words = out_of_domain(df, c)
        if bad.any():
            i = int(bad.nonzero()[0][0])
            raise refuse(i, c, f"{shown(df[c].iloc[i])} is not {words}")
    if "spec" in df.columns:  # each distinct spec once, by the spec's rules: a damaged one is no other spec
        codes, specs = pd.factorize(df["spec"], use_na_sentinel=False)
        for k, text in enumerate(specs):
            problem = spec_cell_problem(text)
            if problem:
                raise refuse(int((codes == k).nonzero()[0][0]), "spec", problem)
    for c in (c for c in validate.THRESHOLDS if c in df.columns):  # as --eps, --phi, --delta, --tau are checked
        codes, values = pd.factorize(df[c], use_na_sentinel=False)
        for k, value in enumerate(values):  # each distinct value once
            try:
                validate.threshold(c, value)
            except ValidationError as exc:
                raise refuse(int((codes == k).nonzero()[0][0]), c, str(exc)) from None
    return df


def spec_cell_problem(text: Any) -> str | None:
    """What is wrong with a table's ``spec`` cell (None: nothing): not the JSON of an object, as
    ``lorisnb evaluate`` writes every spec (an edit, a cell cut short), or values no spec holds
    (:func:`~lorisnb.tools.report.provenance.spec_problem`). The cell is quoted by its beginning
    only (:func:`spec_excerpt`), never whole. A cell that was no JSON was compared as text: two tables
    holding the same damaged cell were judged "ok" (exit 0), and one that differed was named with
    the other's whole JSON."""
    try:
        value = json.loads(str(text))
    except (ValueError, RecursionError):  # RecursionError: nested too deeply to be read
        return f"{spec_excerpt(text)} is not the JSON of an evaluation spec (an object, as lorisnb evaluate writes it)"
    if not isinstance(value, dict):
        return f"{spec_excerpt(text)} is not an evaluation spec (a JSON object, as lorisnb evaluate writes it)"
    return spec_problem(value)


def spec_excerpt(text: Any, width: int = 30) -> str:
    """A ``spec`` cell as a message quotes it: its first ``width`` characters, quoted (a spec's whole
    JSON is hundreds of characters; the keys that differ are named where specs are compared)."""
    t = str(text)
    return shown(t) if len(t) <= width else f"{shown(t[:width])}... ({len(t)} characters)"


def row_place(path: Path) -> Any:
    """A function giving, for a row of the table read from ``path`` (0-based, as read), the line it
    begins on (a CSV file's, else None), the file of a Parquet dataset folder holding it (its rows
    are its files' in order; None for a file) and its row there, counted from 1
    (:func:`rows_said` words them). A damaged value of a Parquet table was named without its row."""
    if path.is_file() and path.suffix.lower() == ".csv":
        return lambda i: (csv_line(path, i), None, i + 1)
    if path.is_file():
        return lambda i: (None, None, i + 1)
    parts: list[tuple[str, int]] = []
    try:
        import pyarrow.dataset as ds

        for fr in ds.dataset(path, format="parquet", partitioning="hive").get_fragments():
            parts.append((Path(fr.path).relative_to(path).as_posix(), fr.count_rows()))
    except (ImportError, OSError, ValueError):
        parts = []

    def place(i: int) -> tuple[None, str | None, int]:
        k = i
        for name, n in parts:
            if k < n:
                return None, name, k + 1
            k -= n
        return None, None, i + 1

    return place


def rows_said(path: Path, rows: list[int], more: str = "") -> str:
    """Rows of a Parquet table (0-based, as read) in words: ``row 5 of the table (counted from 1)``,
    ``rows 2 and 4 of algorithm=orb/part-0.parquet (counted from 1)`` in a dataset folder (each
    file's rows after its name); ``more`` ends the list (``and 3 more``)."""
    place = row_place(path)
    by_file: dict[str | None, list[str]] = {}
    for i in rows:
        _, part, k = place(i)
        by_file.setdefault(part, []).append(str(k))
    said = [f"row{'s' if len(ks) > 1 else ''} {_and(ks)} of {part or 'the table'}" for part, ks in by_file.items()]
    return f"{_and(said)}{more} (counted from 1)"


def repeated_key(table: pd.DataFrame) -> tuple[list[int], str, list[str]] | None:
    """The first sequence and trial a per-sequence table holds in several rows: their positions
    (0-based, in the table's order), the sequence in words (``vins home-1 (trial 0)``, with the
    result files the rows came from where they differ) and those files (empty where the rows name
    one or none); None when each is held once (:data:`KEYS`)."""
    t = with_trials(table)
    t = t.assign(suite=t["suite"].fillna("").astype(str))
    dup = t.duplicated(KEYS, keep=False).to_numpy()
    if not dup.any():
        return None
    first = t.iloc[int(dup.nonzero()[0][0])]
    same = np.ones(len(t), bool)
    for k in KEYS:
        same &= (t[k] == first[k]).to_numpy()
    rows = [int(i) for i in same.nonzero()[0]]

    def whole(x: Any) -> Any:
        return int(x) if isinstance(x, (int, float, np.integer, np.floating)) and float(x).is_integer() else x

    suite = f" ({first['suite']})" if first["suite"] else ""
    what = f"{first['algorithm']}{suite} {first['scene']}-{whole(first['seq'])} (trial {whole(first['trial'])})"
    files = list(dict.fromkeys(str(t["file"].iloc[i]) for i in rows)) if "file" in t.columns else []
    if len(files) < 2:
        return rows, what, []
    return rows, f"{what} (from the result files {_and(files)})", files


def _and(items: list[str]) -> str:
    return items[0] if len(items) == 1 else f"{', '.join(items[:-1])} and {items[-1]}"


def check_keys(df: pd.DataFrame, path: Path, expected: str) -> pd.DataFrame:
    """``df`` (read from ``path``) when it holds each sequence and trial once (:func:`repeated_key`);
    else a :class:`~lorisnb.errors.ParseError` naming the file and the lines (CSV) or rows (Parquet)
    of the repeated rows, ending with ``expected``. A table judged one row per sequence and trial
    cannot tell which of two rows is the run's."""
    found = repeated_key(df)
    if found is None:
        return df
    rows, what, files = found
    csv = path.is_file() and path.suffix.lower() == ".csv"
    if csv:
        starts = [line for line, _ in csv_records(path)][1:]  # each data row's first line (the header left out)
        lines = [starts[i] if i < len(starts) else i + 2 for i in rows]
        where, at = f"lines {_and([str(x) for x in lines])}", lines[1]
    else:
        where, at = rows_said(path, rows), None
    why = ("two result files of one sequence and trial: evaluate them again with their trials named (cafe_trial1.txt, "
           "or --trials-by REGEX)" if files else "a sweep of several settings, tables "
           "stacked, or a row copied by an edit? Keep one row per sequence and trial")  # fmt: skip
    raise ParseError(path, at, f"{what} has several rows ({where}); {why}; expected {expected}")


#: A row's group whose rows must be scored with one setting (:func:`mixed_setting`): the rows an
#: algorithm's scene value averages.
SETTING_GROUP = ["suite", "algorithm", "scene"]


def mixed_setting(table: pd.DataFrame) -> tuple[list[int], list[int], str] | None:
    """The first algorithm and scene whose rows were scored with two settings (:data:`SPEC_COLUMNS`:
    two specs, or two values of ``phi``, ``delta``, ``tau`` or ``official_interpolation``; ``eps``
    given on some rows, infinite on others): the positions (0-based) of the rows holding its first
    setting and of those holding the others, and what differs in words, naming each key (``spec
    align: "se3" against "sim3"``); None when every algorithm's scene holds one. A scene value
    averages its rows: an se3 row among sim3 rows, or a trial at eps 3 m among eps inf, was
    averaged in without a word. ``eps`` in metres differs per sequence under a relative eps (``--eps
    relative:F``, its fraction of each sequence's extent), so only eps given against eps infinite
    is told; algorithms of one scene may be scored apart (a monocular one with Sim(3))."""
    cols = [c for c in SPEC_COLUMNS if c in table.columns and c != "eps"]
    if not len(table) or (not cols and "eps" not in table.columns):
        return None
    t = with_trials(table)
    frame = pd.DataFrame({k: t[k].fillna("").astype(str).to_numpy() for k in SETTING_GROUP})
    if "eps" in table.columns:  # given (a number, per sequence under a relative eps) or not (inf)
        eps = pd.to_numeric(t["eps"], errors="coerce").to_numpy(float)
        frame["eps"] = np.where(np.isinf(eps), "inf", "given")
    for c in cols:
        frame[c] = t[c].astype(str).to_numpy()
    setting = [c for c in frame.columns if c not in SETTING_GROUP]
    distinct = frame.drop_duplicates(SETTING_GROUP + setting)
    several = distinct.duplicated(SETTING_GROUP, keep=False).to_numpy()
    if not several.any():
        return None
    first = distinct[several].iloc[0]
    group = np.ones(len(frame), bool)
    for k in SETTING_GROUP:
        group &= (frame[k] == first[k]).to_numpy()
    same = group.copy()
    for c in setting:
        same &= (frame[c] == first[c]).to_numpy()
    other = group & ~same
    words = []
    for c in setting:
        x, y = sorted(set(frame.loc[same, c])), sorted(set(frame.loc[other, c]))
        if x == y:
            continue
        if c == "eps":  # the values in metres, as the table holds them
            x, y = (sorted({shown(float(v)) for v in eps[rows]}, key=float) for rows in (same, other))
            x, y = (v[:3] + ["..."] if len(v) > 3 else v for v in (x, y))
        if c == "spec":
            words.append(_spec_keys([(v,) for v in x], [(v,) for v in y])
                         or f"spec = {_rows([(spec_excerpt(v),) for v in x])} against "
                         f"{_rows([(spec_excerpt(v),) for v in y])}")  # fmt: skip
        else:
            words.append(f"{c} = {'/'.join(x)} against {'/'.join(y)}")
    suite = f" ({first['suite']})" if first["suite"] else ""
    what = f"{first['algorithm']}{suite} {first['scene']}: " + "; ".join(words)
    return [int(i) for i in same.nonzero()[0]], [int(i) for i in other.nonzero()[0]], what


def check_settings(df: pd.DataFrame, path: Path, expected: str) -> pd.DataFrame:
    """``df`` (read from ``path``) when each algorithm's scene was scored with one setting
    (:func:`mixed_setting`); else a :class:`~lorisnb.errors.ParseError` naming the file, the lines
    (CSV) or rows (Parquet) of each setting and the keys that differ: its scene value would average
    rows scored two ways, and no comparison with another run could tell."""
    found = mixed_setting(df)
    if found is None:
        return df
    same, other, what = found
    csv = path.is_file() and path.suffix.lower() == ".csv"
    starts = [line for line, _ in csv_records(path)][1:] if csv else []

    def where(rows: list[int]) -> str:
        more = f" and {len(rows) - 5} more" if len(rows) > 5 else ""
        if not csv:  # a Parquet file's rows (and a dataset's files)
            return rows_said(path, rows[:5], more)
        shown_rows = [str(starts[i] if i < len(starts) else i + 2) for i in rows[:5]]
        return f"line{'s' if len(rows) > 1 else ''} {', '.join(shown_rows)}{more}"

    at = (starts[other[0]] if other[0] < len(starts) else other[0] + 2) if csv else None
    raise ParseError(path, at, f"the table holds two settings for {what} (the first at {where(same)}, the other at "
                     f"{where(other)}): its scene value would average "
                     "rows scored two ways; score every row with one spec and one set of thresholds (evaluate the "
                     f"results again with one set of options), or keep the rows apart in two tables; expected {expected}")  # fmt: skip


def shown(value: Any) -> str:
    """A value as a message quotes it: text in quotes, a number with every digit Python writes
    (``1.0000001`` is not shown as ``1``: it would read as a value in the domain), a whole float
    without its ``.0``, numpy's scalars as Python's (never ``np.True_``)."""
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):
        value = value.item()
    if isinstance(value, float):
        text = repr(value)
        return text[:-2] if text.endswith(".0") else text
    return repr(value)


def csv_line(path: Path, row: int) -> int:
    """The line of a CSV file where its data row ``row`` (0-based, as pandas reads it: the header and
    blank lines left out) begins (:func:`csv_records`): a quoted cell may hold a newline (a folder
    name with one)."""
    for k, (line, _) in enumerate(csv_records(path)):
        if k == row + 1:
            return line
    return row + 2


def out_of_domain(df: pd.DataFrame, c: str) -> tuple[Any, str]:
    """Which values of column ``c`` no evaluation writes (a boolean array), and what it writes in
    words; the one rule every number :func:`read_table` reads passes. A rate (CR, CR-T, CS-R) is in
    [0, 1], never NaN (a sequence without a match has CR 0); a count, a sequence or trial number
    is a whole number >= 0; a duration finite and >= 0; an RMSE (and the rotation lever) finite and
    >= 0, NaN only where its count (:data:`NAN_WHEN_NONE`) is 0 (or absent)."""
    import numpy as np

    v = df[c].to_numpy(float)
    nan = np.isnan(v)
    if c in RATES:
        return nan | (v < 0) | (v > 1), "a rate between 0 and 1 (NaN is none: a sequence without a match has 0)"
    if c in COUNTS or c in INDICES:
        words = f"{INDICES.get(c, 'a count')} (a whole number >= 0)"
        finite = np.isfinite(v)  # inf, -inf (1e400 as read) are no whole number: never taken modulo 1 (a
        # RuntimeWarning of numpy's was printed before the error)
        return ~finite | (v < 0) | (np.mod(np.where(finite, v, 0), 1) != 0), words
    if c in SECONDS:
        return nan | (v < 0) | ~np.isfinite(v), "a duration in seconds (finite, >= 0)"
    count = NAN_WHEN_NONE.get(c)
    may_be_nan = df[count].to_numpy(float) == 0 if count in df.columns else np.ones(len(v), bool)
    with np.errstate(invalid="ignore"):
        bad = (nan & ~may_be_nan) | (v < 0) | np.isinf(v)
    what = "a lever in metres" if c == "rotation_lever" else "an RMSE"
    return bad, f"{what} >= 0 (NaN only where {count or 'its count'} is 0)"


def _report_tables(folder: Path, notes: list[str], spec: Any = None) -> pd.DataFrame:
    """The report's own per-sequence table (:data:`FIRST_TABLE`), else every per-sequence CSV table
    of the run, stacked, one row per sequence and trial (from the first table that holds it, by
    path), with a ``table`` column (its path in the run); tables that are not per-sequence (scenes,
    pairs, ...) are left out, and so are tables with several rows per sequence and trial (sweeps),
    with a note in ``notes``. A run whose run.json ``spec`` records the report's own evaluation (its
    ``values``: every lorisnb report that evaluated wrote its findings with them) must hold that
    table: without it (a run copied in part, its ``findings`` a link leading out of it), an error
    naming what is missing, never the notebooks' tables at their own settings in its place."""
    parts = []
    own = folder / FIRST_TABLE  # the report's own evaluation: the notebooks' tables hold other settings
    findings = own.parent
    if findings.exists() or findings.is_symlink():
        run_file(folder, findings)  # a link leading out of the run: refused, never read
    if os.path.lexists(own):
        run_file(folder, own)  # a FIFO or a device in its place: refused, not called missing
    recorded = isinstance(spec, dict) and isinstance(spec.get("values"), dict) and bool(spec["values"])
    if recorded and not own.is_file():
        what = f"{findings}: no such folder" if not findings.is_dir() else f"{own}: no such file"
        raise DataNotFoundError(f"{what}; the run's run.json records the report's own evaluation, whose per-sequence "
                                f"table is {FIRST_TABLE} (the notebooks' tables hold other settings): a run copied in "
                                "part? Copy the whole run folder, or make the run again")  # fmt: skip
    if own.is_file():  # the run's table: read as a bare table is, refused as one is (a row repeated, a column
        # lacking: named with the file and lines, never "a report run without a per-sequence table")
        run_file(folder, own)
        parts.append(with_trials(read_table(own)).assign(table=FIRST_TABLE))
    for csv in [] if own.is_file() else sorted(folder.rglob("*.csv")):
        if any(part.startswith(".") for part in csv.relative_to(folder).parts):
            continue
        run_file(folder, csv)  # a link leading out of the run: refused, never read
        try:
            head = pd.read_csv(csv, nrows=0)
        except (ValueError, OSError):
            continue
        if all(c in head.columns for c in [*REQUIRED, *NEEDED]):
            t = with_trials(_table_rows(csv))
            if t.duplicated(KEYS).any():
                notes.append(f"{csv}: several rows per sequence (a sweep?); left out")
                continue
            mixed = mixed_setting(t)
            if mixed is not None:  # rows of one algorithm's scene scored two ways
                notes.append(f"{csv}: holds two settings for {mixed[2]}; left out")
                continue
            parts.append(t.assign(table=csv.relative_to(folder).as_posix()))
    if not parts:
        raise DataNotFoundError(f"{folder}: a report run (run.json) without a per-sequence CSV table "
                                f"(columns {', '.join(dict.fromkeys([*REQUIRED, *NEEDED]))})")  # fmt: skip
    return pd.concat(parts, ignore_index=True).drop_duplicates(KEYS).reset_index(drop=True)


def load_run(path: str | os.PathLike[str]) -> Run:
    """A report run folder or a table (see the module docstring)."""
    p = Path(path)
    if not p.exists():
        raise DataNotFoundError(f"{p}: no such file or folder")
    if is_report_run(p):
        meta = read_run_json(p)  # its spec values and time checked there, as for verify and render
        created, source = created_of(meta, p / RUN_JSON), "run.json"
        if created is None:
            created, source = modified(p / RUN_JSON), "modification time of run.json"
        notes: list[str] = []
        table = _report_tables(p, notes, meta.get("spec"))
        notes += _trial_folder_notes(p, table)
        return Run(p, "report", table, meta, created, source, notes, unscored_inputs(p), _durations(p))
    if is_table(p):
        table, notes = read_table(p), []
        notes += _trial_folder_notes(p, table)
        return Run(p, "table", table, {}, modified(p), "modification time", notes,
                   expected=table_expected(table, p, notes))  # fmt: skip
    held = held_results(p)
    if held:  # a result folder: what history reads instead, and how to make it of these files
        raise ValidationError(f"{p}: {held}, not a run: history and --baseline read runs, report run folders "
                              f"({RUN_JSON}) and per-sequence tables; make one of it (lorisnb evaluate {p} --csv "
                              f"RUN.csv, or lorisnb report --results {p} --out RUN), or judge it with lorisnb diff "
                              "BASE_RUN " + f"{p} (diff evaluates a result folder given as CAND)")  # fmt: skip
    raise ValidationError(f"{p}: not a report run (no {RUN_JSON}) and not a CSV/Parquet table")


def held_results(path: Path) -> str | None:
    """What ``path`` holds that lorisnb evaluates, in words (``a result folder (42 result files, such as
    orb/cafe-1.txt)``, ``a result file``), where it is neither a report run nor a table but holds
    a file of pose estimates in a format lorisnb recognises (:func:`lorisnb.io.readers.registry.recognise`;
    the first 50 files are looked at); None otherwise. ``history`` passed such a folder over as "no
    run" and judged the night before it (exit 0): tonight's results, never judged."""
    import warnings

    from lorisnb.errors import LorisError
    from lorisnb.io.readers.registry import FORMATS, recognise, sample
    from lorisnb.tools.evaluation.inputs import find_inputs

    suffixes = tuple(dict.fromkeys(x for f in FORMATS.values() for x in f.suffixes))
    try:
        with warnings.catch_warnings():  # what a folder lacks is said when it is evaluated, not here
            warnings.simplefilter("ignore")
            files = [f for f, _ in find_inputs([path], suffixes).files]
    except (LorisError, OSError, ValueError):
        return None
    for f in files[:50]:
        if recognise(sample(f)):
            if not path.is_dir():
                return "a result file"
            return f"a result folder ({len(files)} result file(s), such as {f.relative_to(path).as_posix()})"
    return None


def _trial_folder_notes(path: Path, table: pd.DataFrame) -> list[str]:
    """Which folders of the run's result files were read as trials of one name
    (:func:`lorisnb.core.stats.trials.trial_folders`: ``slam_run1/`` and ``slam_run2/`` as trials 1
    and 2 of ``slam``), each note led by the run's path."""
    from lorisnb.core.stats.trials import trial_folders

    if "file" not in table.columns or not len(table):
        return []
    return [f"{path}: {n}" for n in trial_folders(table["file"].dropna().astype(str))]


#: A report run's table of every ground-truth sequence of the scenes its findings evaluated.
DURATIONS = "findings/durations.csv"


def table_expected(table: pd.DataFrame, path: Path, notes: list[str] | None = None) -> pd.DataFrame | None:
    """Every ground-truth sequence of the OpenLORIS scenes of a table ``lorisnb evaluate --csv`` wrote
    (``scene``, ``seq``, ``gt_duration``...), from the data root lorisnb finds, so that a scene value
    read from the table counts a sequence without a row as failed, as the evaluation of the results
    folder does (a table held only its sequences: scene CR 0.9996 from the table, 0.6120 from the
    folder). Used only where the table's own ground-truth durations are those of the data root (a
    pair's scene named ``cafe`` is not OpenLORIS' cafe); otherwise None, with a note in ``notes``."""
    from lorisnb.core.trajectory.frames import SCENES
    from lorisnb.io.datasets.paths import ENV_VAR, find_data, scene_durations

    if not len(table) or "gt_duration" not in table.columns:
        return None
    scenes = sorted({str(x) for x in table["scene"]})
    if not set(scenes) <= set(SCENES):
        return None

    def note(text: str) -> None:
        if notes is not None:
            notes.append(f"{path}: {text}")

    try:
        root = find_data()
    except DataNotFoundError:
        env = os.environ.get(ENV_VAR)
        if env:  # set, to a folder that is no data root: said (it read "set LORISNB_DATA to one" as if unset)
            where = Path(env).expanduser()
            state = "is not a data root" if where.is_dir() else "is a file" if where.exists() else "does not exist"
            note(f"scene values count only the sequences the table holds: {ENV_VAR} is set to {env}, which {state}, "
                 f"so no data root lists the others (the OpenLORIS ground truth); set {ENV_VAR} to the data root "
                 "(the folder holding openloris-scene/), or compare the result folders")  # fmt: skip
        else:
            note("scene values count only the sequences the table holds: no data root was found to list the others "
                 f"(the OpenLORIS ground truth); set {ENV_VAR} to one, or compare the result folders")  # fmt: skip
        return None
    have, lacking = [], []
    for scene in scenes:
        try:
            root.groundtruth(scene)
            have.append(scene)
        except DataNotFoundError:
            lacking.append(scene)
    if lacking:  # why, by the facts: office's is not public; another scene's is not in this data root
        office = ["office"] if "office" in lacking else []
        others = [x for x in lacking if x != "office"]
        why = (["the office ground truth (motion capture) is not public"] if office else []) + (
            [f"the data root {root.root} has no ground truth of {', '.join(others)}"] if others else [])  # fmt: skip
        note(f"scene values of {', '.join(lacking)} count only the sequences the table holds ({'; '.join(why)})")
    if not have:
        return None
    try:
        expected = scene_durations(have, root)
    except (DataNotFoundError, OSError, ValueError) as exc:
        note(f"scene values count only the sequences the table holds: the ground truth of {', '.join(have)} in "
             f"{root.root} could not be read ({exc})")  # fmt: skip
        return None
    known = expected.set_index(["scene", "seq"])["gt_duration"]
    rows = table.assign(scene=table["scene"].astype(str), seq=table["seq"].astype("int64"))
    rows = rows[rows["scene"].isin(have).to_numpy()]
    mine = rows.drop_duplicates(["scene", "seq"]).set_index(["scene", "seq"])["gt_duration"].astype(float)
    here = known.reindex(mine.index)
    if here.isna().any() or not np.allclose(here.to_numpy(), mine.to_numpy(), rtol=0, atol=1e-6):
        if notes is not None:
            notes.append(f"{path}: its sequences' ground-truth durations are not those of the data root's scenes "
                         "of the same names; scene values count only the sequences the table holds")  # fmt: skip
        return None
    return expected


def _durations(run_dir: Path) -> pd.DataFrame | None:
    """:data:`DURATIONS` of a report run (None for a run without it)."""
    f = run_dir / DURATIONS
    if not f.is_file():
        return None
    run_file(run_dir, f)
    expected = "the report's own table of ground-truth sequences"
    try:
        t = read_csv(f, expected)
    except ParseError:
        raise
    except (ValueError, pd.errors.ParserError) as exc:
        raise ParseError(f, None, f"not a durations table ({exc}); expected the report's own") from None
    if not {"scene", "seq", "gt_duration"} <= set(t.columns):
        raise ParseError(f, None, "expected the columns scene, seq, gt_duration (the report's own table)")
    return check_values(t, f, expected).astype({"scene": str})


#: What a report run's ``findings/input_errors.csv`` says of an input that was not scored.
NOT_SCORED = ("failed", "not scored")


def unscored_inputs(run_dir: Path) -> dict[str, str]:
    """The inputs of a report run's own evaluation (``findings/input_errors.csv``) that failed or
    were not scored, file -> reason (skipped ones, such as a scene without ground truth, are not)."""
    f = run_dir / "findings" / INPUT_ERRORS_CSV
    if not f.is_file():
        return {}
    run_file(run_dir, f)
    try:
        t = read_csv(f, "the report's own table of input errors", dtype=str, keep_default_na=False)
    except ParseError:
        raise
    except (ValueError, pd.errors.ParserError) as exc:
        raise ParseError(f, None, f"not a table of input errors ({exc}); expected the report's own") from None
    if not {"file", "status", "error"} <= set(t.columns):
        raise ParseError(f, None, "expected the columns file, status, error (the report's own table)")
    bad = t[t["status"].isin(NOT_SCORED).to_numpy()]
    return dict(zip(bad["file"], bad["error"], strict=True))


def modified(p: Path) -> datetime:
    return datetime.fromtimestamp(p.stat().st_mtime, tz=timezone.utc)


def spec_values(spec: Any) -> dict[str, Any]:
    """What of a run.json ``spec`` changes the numbers: its ``values`` (the whole spec when it has
    none), without :data:`NOT_NUMBERS`; the ``description`` is these values in words. Each value in
    its one form (:func:`recorded_value`): a run made before report parameters were recorded so
    (``-p scale on`` kept as ``"on"``) compares with one that records ``true``."""
    values = spec.get("values", spec) if isinstance(spec, dict) else {"spec": spec}
    if not isinstance(values, dict):
        values = {"values": values}
    return {k: recorded_value(k, v) for k, v in values.items()
            if k not in NOT_NUMBERS and (values is not spec or k != "description")}  # fmt: skip


def recorded_value(key: str, value: Any) -> Any:
    """A value of run.json's ``spec`` in the one form ``lorisnb report`` now records it
    (:func:`lorisnb.tools.notebook.params.canonical`: ``scale`` ``"on"``, ``"Yes"`` and ``true`` are
    True, ``rpe_unit`` ``"M"`` is ``"m"``, a threshold ``"1"`` is 1.0, ...), for every key a report's
    parameters can carry; a path (a folder of the machine that made the run) and a value no rule
    takes (a run of another version) as recorded, so that the comparison names it."""
    from lorisnb.tools.notebook.params import PATHS, canonical

    if key in PATHS or value is None:
        return value
    try:
        return canonical(key, value)
    except (ValidationError, DataNotFoundError, ValueError, TypeError, OverflowError):
        return value


def spec_differences(a: Run, b: Run) -> list[str]:
    """What makes two runs not comparable: a key of their run.json specs that changes the numbers
    differs (:func:`spec_values`; each such key named, with both values whole), or the thresholds
    recorded in their tables differ for a scene both have. Empty when they agree. A key one side
    lacks is no difference where the other side holds its default (:func:`unset_defaults`)."""
    out = []
    if a.spec is not None and b.spec is not None:
        va, vb = unset_defaults(spec_values(a.spec), spec_values(b.spec))
        missing = object()
        for k in sorted(set(va) | set(vb)):
            x, y = va.get(k, missing), vb.get(k, missing)
            if x != y:
                out.append(f"spec {k}: {_json(x, missing)} in {a.path} against {_json(y, missing)} in {b.path}")
    return out + setting_differences(a.table, b.table, str(a.path), str(b.path))


@lru_cache(maxsize=None)
def _defaults(preset: str | None) -> dict[str, Any]:
    """Every key of an evaluation spec with its default, as run records write it
    (:meth:`~lorisnb.core.spec.evalspec.EvalSpec.to_dict`): the named preset's, else the spec's own."""
    spec = PRESETS.get(preset) if isinstance(preset, str) else None
    return (spec if spec is not None else EvalSpec()).to_dict()


def _plain_value(v: Any) -> Any:
    if isinstance(v, float) and math.isinf(v):
        return "inf"
    if isinstance(v, tuple):
        return [_plain_value(x) for x in v]
    return v


def is_default(key: str, value: Any, preset: Any = None) -> bool:
    """Whether ``value`` is ``key``'s default in the evaluation spec (of ``preset`` where it names
    one; :class:`~lorisnb.core.spec.evalspec.EvalSpec`'s otherwise): False for a key no spec has."""
    d = _defaults(preset if isinstance(preset, str) else None)
    return key in d and _plain_value(value) == _plain_value(d[key])


def unset_defaults(x: dict[str, Any], y: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """Two recorded specs without the keys one of them lacks where the other holds that key's
    default (:func:`is_default`, under the preset of the side that lacks it): a run recorded before a
    key existed was made at its default, so a new key made every archived run "not comparable"
    (exit 2) with one whose spec holds it at its default. A value other than the default against a
    key not set still differs."""
    px, py = x.get("preset"), y.get("preset")
    return (
        {k: v for k, v in x.items() if k in y or not is_default(k, v, py)},
        {k: v for k, v in y.items() if k in x or not is_default(k, v, px)},
    )


def _same_spec_text(x: str, y: str) -> tuple[str, str]:
    """Two tables' ``spec`` cells (JSON) with the keys one lacks at their default left out of the
    other (:func:`unset_defaults`), each written back the same way; as they are where either is no
    JSON object."""
    try:
        a, b = json.loads(x), json.loads(y)
    except (ValueError, RecursionError):
        return x, y
    if not isinstance(a, dict) or not isinstance(b, dict):
        return x, y
    a, b = unset_defaults(a, b)
    return json.dumps(a, sort_keys=True), json.dumps(b, sort_keys=True)


def setting_differences(a: pd.DataFrame, b: pd.DataFrame, name_a: str = "BASE", name_b: str = "CAND") -> list[str]:
    """What makes two per-sequence tables not comparable: the settings (:data:`SPEC_COLUMNS`)
    differ for a scene both have; each difference said once, with the scenes it is found in. A key
    of the ``spec`` (JSON) one table lacks, or a setting column it lacks, is no difference where the
    other table holds that key's default (:func:`unset_defaults`); where the spec differs, only the
    keys that differ are named, with both values."""
    sa, sb = table_settings(a), table_settings(b)
    both = sorted(set(sa["scene"]) & set(sb["scene"]))
    said: dict[str, list[str]] = {}  # what differs -> the scenes it differs in (said once for all of them)
    for col in (c for c in SPEC_COLUMNS if (c in a.columns) != (c in b.columns)):  # recorded on one side only
        has, lacks = (name_a, name_b) if col in a.columns else (name_b, name_a)
        held = sa if col in a.columns else sb
        values = set(held.loc[held["scene"].isin(both), col])
        if col != "spec" and all(v == str(_defaults(None).get(col, object())) for v in values):
            continue  # written before the column existed: at its default, as the other table
        said.setdefault(f"{col} recorded in {has}, not in {lacks} (a table edited, or written by another lorisnb): "
                        f"how {lacks} was scored cannot be checked", []).extend(both)  # fmt: skip
    for scene in both:
        x = sa[sa["scene"] == scene].drop(columns=["table"], errors="ignore").drop_duplicates()
        y = sb[sb["scene"] == scene].drop(columns=["table"], errors="ignore").drop_duplicates()
        if "spec" in x.columns and "spec" in y.columns and x["spec"].nunique() == 1 and y["spec"].nunique() == 1:
            sx, sy = _same_spec_text(x["spec"].iloc[0], y["spec"].iloc[0])
            x, y = x.assign(spec=sx), y.assign(spec=sy)
        cols = [c for c in x.columns if c in y.columns and c != "scene"]
        xs = sorted(map(tuple, x[cols].to_numpy().tolist()))
        ys = sorted(map(tuple, y[cols].to_numpy().tolist()))
        if xs != ys:  # only the columns whose values differ (all of them if only their combination does)
            keep = [i for i in range(len(cols)) if {r[i] for r in xs} != {r[i] for r in ys}] or list(range(len(cols)))
            xk, yk = (sorted({tuple(spec_excerpt(r[i]) if cols[i] == "spec" else r[i] for i in keep) for r in rows})
                      for rows in (xs, ys))  # a spec that is no JSON object: its beginning, never whole  # fmt: skip
            text = f"{', '.join(cols[i] for i in keep)} = {_rows(xk)} in {name_a} against {_rows(yk)} in {name_b}"
            if "spec" in [cols[i] for i in keep]:  # the spec's keys that differ, not both specs whole
                si = cols.index("spec")
                keys = _spec_keys(sorted({(r[si],) for r in xs}), sorted({(r[si],) for r in ys}), name_a, name_b)
                rest = [i for i in keep if cols[i] != "spec" and f"spec {cols[i]}:" not in (keys or "")]
                if keys and len(keep) > 1 and not rest:
                    text = keys  # a setting column the spec holds too (official_interpolation): said once
                elif keys:
                    xr, yr = (sorted({tuple(r[i] for i in rest) for r in rows}) for rows in (xs, ys))
                    text = "; ".join(
                        [keys]
                        + (
                            [
                                f"{', '.join(cols[i] for i in rest)} = {_rows(xr)} in {name_a} against "
                                f"{_rows(yr)} in {name_b}"
                            ]
                            if xr != yr
                            else []
                        )  # fmt: skip
                    )
            said.setdefault(text, []).append(scene)
    return [f"{', '.join(scenes)}: {text}" for text, scenes in said.items()]


def _spec_keys(a: list[tuple], b: list[tuple], name_a: str = "", name_b: str = "") -> str | None:
    """The keys that differ between the specs (a table's ``spec`` column, JSON) of each side, with
    their values (``spec align: "se3" in A against "auto" in B``; a side holding several specs gives
    each value it holds, ``"se3"/"sim3"``), instead of the specs whole; None when a spec is no JSON
    object or no key's values differ."""
    try:
        xs, ys = ([json.loads(str(r[0])) for r in side] for side in (a, b))
    except (ValueError, RecursionError):
        return None
    if not xs or not ys or not all(isinstance(v, dict) for v in [*xs, *ys]):
        return None
    missing = object()

    def held(specs: list[dict], k: str) -> str:
        texts = dict.fromkeys(_json(s.get(k, missing), missing) for s in specs)
        return "/".join(sorted(texts))

    def named(name: str) -> str:
        return f" in {name}" if name else ""

    keys = sorted({k for s in [*xs, *ys] for k in s})
    said = [f"spec {k}: {held(xs, k)}{named(name_a)} against {held(ys, k)}{named(name_b)}" for k in keys
            if held(xs, k) != held(ys, k)]  # fmt: skip
    return "; ".join(said) or None


def _json(value: Any, missing: object) -> str:
    return "(not set)" if value is missing else json.dumps(value, sort_keys=True, default=str)


def _rows(rows: list[tuple]) -> str:
    return "; ".join("/".join(map(str, r)) for r in rows[:3]) + (" ..." if len(rows) > 3 else "")
