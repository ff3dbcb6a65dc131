"""Provenance of a report run: ``run.json`` (the command line, lorisnb's version and git commit,
the evaluation spec, the data root, when, a SHA-256 of every input file, and each notebook's
status), and :func:`verify_run`, which re-checks the inputs' checksums.

``run.json`` keys (read by ``lorisnb diff`` and ``lorisnb history`` too; keep them):
``command`` (argv list), ``lorisnb_version``, ``commit`` (git commit of the lorisnb checkout, or
null when lorisnb is installed from a wheel), ``spec`` (``description``: the evaluation's
conventions in words; ``values``: thresholds eps, phi, delta, tau, the scale mode, the
conventions, the metric and test settings of the leaderboard), ``data_root``, ``created`` (ISO
8601, UTC), ``inputs`` (path -> sha256; relative paths are below ``data_root``), ``notebooks``
(name -> status).
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import os
import subprocess
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from .._version import __version__
from ..errors import LorisError

RUN_JSON = "run.json"
KEYS = ("command", "lorisnb_version", "commit", "spec", "data_root", "created", "inputs", "notebooks")


def sha256(path: Path, chunk: int = 1 << 20) -> str:
    """The SHA-256 of a file's bytes, hex."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        while block := f.read(chunk):
            h.update(block)
    return h.hexdigest()


def git_commit(start: Path | None = None) -> str | None:
    """The commit of the git checkout lorisnb runs from (None when it is not one, or git is missing)."""
    here = start or Path(__file__).resolve().parents[2]
    if not (here / ".git").exists():
        return None
    try:
        out = subprocess.run(
            ["git", "-C", str(here), "rev-parse", "HEAD"], capture_output=True, text=True, timeout=10, check=False
        )
    except (OSError, subprocess.TimeoutExpired):
        return None
    commit = out.stdout.strip()
    return commit if out.returncode == 0 and len(commit) == 40 else None


def input_files(roots: Iterable[Path]) -> list[Path]:
    """Every regular file of ``roots`` (files, or folders walked recursively), hidden files
    left out, sorted, each once."""
    found: dict[Path, None] = {}
    for root in roots:
        if root.is_file():
            found[root.resolve()] = None
        elif root.is_dir():
            for p in sorted(root.rglob("*")):
                rel = p.relative_to(root).parts
                if p.is_file() and not any(part.startswith(".") for part in rel):
                    found[p.resolve()] = None
    return sorted(found)


def _key(path: Path, data_root: Path | None) -> str:
    if data_root is not None:
        try:
            return path.relative_to(data_root.resolve()).as_posix()
        except ValueError:
            pass
    return str(path)


def checksums(files: Iterable[Path], data_root: Path | None) -> dict[str, str]:
    """path -> sha256; paths below ``data_root`` relative to it, others absolute."""
    return {_key(p, data_root): sha256(p) for p in files}


def run_record(
    command: list[str],
    spec: Mapping[str, Any],
    data_root: Path | None,
    inputs: Mapping[str, str],
    notebooks: Mapping[str, str],
) -> dict[str, Any]:
    """The content of ``run.json`` (see the module docstring)."""
    return {
        "command": list(command),
        "lorisnb_version": __version__,
        "commit": git_commit(),
        "spec": dict(spec),
        "data_root": str(data_root) if data_root is not None else None,
        "created": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "inputs": dict(inputs),
        "notebooks": dict(notebooks),
    }


def write_run_json(run_dir: Path, record: Mapping[str, Any]) -> Path:
    out = run_dir / RUN_JSON
    out.write_text(json.dumps(record, indent=2, default=str) + "\n", encoding="utf-8")
    return out


def read_run_json(run: str | os.PathLike[str]) -> dict[str, Any]:
    """``run.json`` of a run folder (or the file itself); a clear error if it is not one."""
    p = Path(run)
    f = p / RUN_JSON if p.is_dir() else p
    if not f.is_file():
        raise LorisError(f"{p}: no {RUN_JSON} here; expected a run folder written by lorisnb report")
    try:
        record = json.loads(f.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise LorisError(f"{f}: not valid JSON ({exc}); expected the run.json lorisnb report writes") from None
    missing = [k for k in KEYS if not isinstance(record, dict) or k not in record]
    if missing:
        raise LorisError(f"{f}: lacks key(s) {', '.join(missing)}; expected the run.json lorisnb report writes")
    return record


def verify_run(run: str | os.PathLike[str]) -> list[tuple[str, str]]:
    """Re-check every input of a run: a list of (path, 'changed' or 'missing'); empty if all
    inputs still have their recorded SHA-256. Relative paths are read below the run's data root."""
    record = read_run_json(run)
    root = Path(record["data_root"]) if record.get("data_root") else None
    problems = []
    for key, digest in sorted(record["inputs"].items()):
        p = Path(key)
        if not p.is_absolute():
            p = (root / p) if root is not None else p
        if not p.is_file():
            problems.append((key, "missing"))
        elif sha256(p) != digest:
            problems.append((key, "changed"))
    return problems
