"""Runs as ``diff`` and ``history`` read them: a report run folder (``run.json`` and the CSV tables
its notebooks wrote), or a per-sequence table as ``lorisnb evaluate --csv`` / ``--parquet`` writes it.

A run's **spec** is what its numbers depend on besides the estimates: the ``spec`` of ``run.json``
when there is one, and the thresholds recorded in the table's own columns (``eps``, ``phi``,
``delta``, ``tau`` per scene, ``official_interpolation``). Two runs are comparable when their specs
agree (:func:`spec_differences`).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import pandas as pd

from ..errors import DataNotFoundError, ParseError, ValidationError

#: Columns a per-sequence table must have to be read as one.
REQUIRED = ["algorithm", "scene", "seq", "cr", "eps", "phi", "delta", "tau"]
#: Table columns that are part of the spec (per scene).
SPEC_COLUMNS = ["eps", "phi", "delta", "tau", "official_interpolation", "spec"]
RUN_JSON = "run.json"


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

    def groundtruth_sums(self) -> dict[str, str]:
        """name -> sha256 of the ground-truth files among run.json's inputs."""
        inputs = self.meta.get("inputs") or {}
        if not isinstance(inputs, dict):
            return {}
        return {Path(p).name: str(h) for p, h in inputs.items() if "groundtruth" in str(p) or "gt_" in Path(p).name}

    def table_spec(self) -> pd.DataFrame:
        """The spec columns per scene (one row per distinct setting)."""
        cols = [c for c in SPEC_COLUMNS if c in self.table.columns]
        keys = ["table"] if "table" in self.table.columns else []
        return self.table[keys + ["scene"] + cols].astype(str).drop_duplicates().sort_values(keys + ["scene"] + cols)


def is_table(path: Path) -> bool:
    """A CSV or Parquet file, or a Parquet dataset folder (``algorithm=NAME/`` parts)."""
    if path.is_file():
        return path.suffix.lower() in (".csv", ".parquet")
    return path.is_dir() and (any(path.glob("algorithm=*")) or any(path.glob("*.parquet")))


def is_report_run(path: Path) -> bool:
    return path.is_dir() and (path / RUN_JSON).is_file()


def read_table(path: Path) -> pd.DataFrame:
    """A per-sequence table from CSV or Parquet; its columns are checked."""
    try:
        if path.is_file() and path.suffix.lower() == ".csv":
            df = pd.read_csv(path)
        else:
            df = pd.read_parquet(path)
    except ImportError:
        from ..errors import MissingDependencyError

        raise MissingDependencyError("reading Parquet needs pyarrow: pip install 'lorisnb[parquet]'") from None
    except (ValueError, OSError) as exc:
        raise ParseError(path, None, f"not a readable CSV or Parquet table ({exc})") from None
    missing = [c for c in REQUIRED if c not in df.columns]
    if missing:
        raise ParseError(path, None, f"lacks column(s) {', '.join(missing)}; expected a per-sequence table as "
                         "written by lorisnb evaluate --csv / --parquet")  # fmt: skip
    for c in ("algorithm", "scene", "suite", "file"):
        if c in df.columns:
            df[c] = df[c].astype(str).where(df[c].notna(), "")
    return df


def _report_tables(folder: Path, notes: list[str]) -> pd.DataFrame:
    """Every per-sequence CSV table of a report run, stacked, with a ``table`` column (its path in the
    run); tables that are not per-sequence (scenes, pairs, ...) are left out, and so are tables with
    several rows per sequence and trial (sweeps), with a note in ``notes``."""
    parts = []
    for csv in sorted(folder.rglob("*.csv")):
        if any(part.startswith(".") for part in csv.relative_to(folder).parts):
            continue
        try:
            head = pd.read_csv(csv, nrows=0)
        except (ValueError, OSError):
            continue
        if all(c in head.columns for c in REQUIRED):
            t = read_table(csv)
            keys = [c for c in ("suite", "algorithm", "scene", "seq", "trial") if c in t.columns]
            if t.duplicated(keys).any():
                notes.append(f"{csv}: several rows per sequence (a sweep?); left out")
                continue
            parts.append(t.assign(table=csv.relative_to(folder).as_posix()))
    if not parts:
        raise DataNotFoundError(f"{folder}: a report run (run.json) without a per-sequence CSV table "
                                f"(columns {', '.join(REQUIRED)})")  # fmt: skip
    return pd.concat(parts, ignore_index=True)


def load_run(path: str | os.PathLike[str]) -> Run:
    """A report run folder or a table (see the module docstring)."""
    p = Path(path)
    if not p.exists():
        raise DataNotFoundError(f"{p}: no such file or folder")
    if is_report_run(p):
        try:
            meta = json.loads((p / RUN_JSON).read_text(encoding="utf-8"))
        except (ValueError, UnicodeDecodeError) as exc:
            raise ParseError(p / RUN_JSON, None, f"not valid JSON ({exc})") from None
        if not isinstance(meta, dict):
            raise ParseError(p / RUN_JSON, None, "expected a JSON object (command, lorisnb_version, spec, ...)")
        created, source = _parse_time(meta.get("created")), "run.json"
        if created is None:
            created, source = _mtime(p / RUN_JSON), "modification time of run.json"
        notes: list[str] = []
        return Run(p, "report", _report_tables(p, notes), meta, created, source, notes)
    if is_table(p):
        return Run(p, "table", read_table(p), {}, _mtime(p), "modification time")
    raise ValidationError(f"{p}: not a report run (no {RUN_JSON}) and not a CSV/Parquet table")


def _parse_time(value: Any) -> datetime | None:
    if not isinstance(value, str):
        return None
    try:
        t = datetime.fromisoformat(value.replace("Z", "+00:00"))
    except ValueError:
        return None
    return t if t.tzinfo else t.replace(tzinfo=timezone.utc)


def _mtime(p: Path) -> datetime:
    return datetime.fromtimestamp(p.stat().st_mtime, tz=timezone.utc)


def spec_differences(a: Run, b: Run) -> list[str]:
    """What makes two runs not comparable: their run.json specs differ, or the thresholds recorded
    in their tables differ for a scene both have. Empty when they agree."""
    out = []
    if a.spec is not None and b.spec is not None and a.spec != b.spec:
        out.append(f"spec: {_short(a.spec)} in {a.path} against {_short(b.spec)} in {b.path}")
    sa, sb = a.table_spec(), b.table_spec()
    both = sorted(set(sa["scene"]) & set(sb["scene"]))
    for scene in both:
        x = sa[sa["scene"] == scene].drop(columns=["table"], errors="ignore").drop_duplicates()
        y = sb[sb["scene"] == scene].drop(columns=["table"], errors="ignore").drop_duplicates()
        cols = [c for c in x.columns if c in y.columns and c != "scene"]
        xs = sorted(map(tuple, x[cols].to_numpy().tolist()))
        ys = sorted(map(tuple, y[cols].to_numpy().tolist()))
        if xs != ys:
            out.append(f"{scene}: {', '.join(cols)} = {_rows(xs)} in {a.path} against {_rows(ys)} in {b.path}")
    return out


def _rows(rows: list[tuple]) -> str:
    return "; ".join("/".join(map(str, r)) for r in rows[:3]) + (" ..." if len(rows) > 3 else "")


def _short(spec: Any) -> str:
    text = json.dumps(spec, sort_keys=True, default=str) if not isinstance(spec, str) else spec
    return text if len(text) <= 120 else text[:117] + "..."
