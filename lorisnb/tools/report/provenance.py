"""Provenance of a report run: ``run.json`` (the command line, lorisnb's version and git commit,
the evaluation spec, the data root, when, a SHA-256 of every input file, and each notebook's
status), and :func:`verify_run`, which re-checks the inputs' checksums and the listing of the
folders they came from.

``run.json`` keys (read by ``lorisnb diff`` and ``lorisnb history`` too; keep them):
``command`` (argv list), ``lorisnb_version``, ``commit`` (git commit of the lorisnb checkout, or
null when lorisnb is installed from a wheel), ``spec`` (``description``: the evaluation's
conventions in words; ``values``: thresholds eps, phi, delta, tau, the scale mode, the
conventions, the metric and test settings of the leaderboard), ``data_root``, ``created`` (ISO
8601, UTC), ``inputs`` (path -> sha256; relative paths are below ``data_root``), ``notebooks``
(name -> status), ``input_roots`` (the files and folders whose listing gave ``inputs``, so that
:func:`verify_run` notices a file added to them; absent in runs of lorisnb 0.x before it).
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

from lorisnb._version import __version__
from lorisnb.errors import LorisError, ParseError

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
    here = start or Path(__file__).resolve().parents[3]
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
    roots: Iterable[Path] = (),
) -> dict[str, Any]:
    """The content of ``run.json`` (see the module docstring); ``roots``: the files and folders
    whose listing gave the inputs (:func:`input_files`)."""
    return {
        "command": list(command),
        "lorisnb_version": __version__,
        "commit": git_commit(),
        "spec": dict(spec),
        "data_root": str(data_root) if data_root is not None else None,
        "created": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "inputs": dict(inputs),
        "notebooks": dict(notebooks),
        "input_roots": [_key(r.resolve(), data_root) for r in roots],
    }


def write_run_json(run_dir: Path, record: Mapping[str, Any]) -> Path:
    out = run_dir / RUN_JSON
    out.write_text(json.dumps(record, indent=2, default=str) + "\n", encoding="utf-8")
    return out


def _is_str_map(v: Any) -> bool:
    return isinstance(v, dict) and all(isinstance(x, str) for x in v.values())


def _is_text_or_null(v: Any) -> bool:
    return v is None or isinstance(v, str)


#: What each key of run.json must hold: (check, what is expected in words).
SHAPES: dict[str, tuple[Any, str]] = {
    "command": (lambda v: isinstance(v, list) and all(isinstance(x, str) for x in v), "a list of strings"),
    "lorisnb_version": (_is_text_or_null, "a version string or null"),
    "commit": (_is_text_or_null, "a git commit or null"),
    "label": (_is_text_or_null, "the name of the code under test or null"),
    "spec": (
        lambda v: (
            isinstance(v, dict) and isinstance(v.get("values", {}), dict) and _is_text_or_null(v.get("description"))
        ),
        'an object {"description": text, "values": {...}}',
    ),  # fmt: skip
    "data_root": (_is_text_or_null, "a folder path or null"),
    "created": (_is_text_or_null, "an ISO 8601 time"),
    "inputs": (_is_str_map, "an object path -> SHA-256"),
    "notebooks": (_is_str_map, "an object notebook name -> status"),
    "input_roots": (lambda v: isinstance(v, list) and all(isinstance(x, str) for x in v), "a list of paths"),
}


def read_run_json(run: str | os.PathLike[str]) -> dict[str, Any]:
    """``run.json`` of a run folder (or the file itself), every key checked (:data:`SHAPES`); a
    :class:`~lorisnb.errors.ParseError` naming the file and what was expected if it is not one."""
    p = Path(run)
    f = p / RUN_JSON if p.is_dir() else p
    if not f.is_file():
        raise LorisError(f"{p}: no {RUN_JSON} here; expected a run folder written by lorisnb report")
    try:
        record = json.loads(f.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ParseError(f, None, f"not valid JSON ({exc}); expected the run.json lorisnb report writes") from None
    if not isinstance(record, dict):
        raise ParseError(f, None, f"a JSON {type(record).__name__}; expected an object with the keys {', '.join(KEYS)}")
    missing = [k for k in KEYS if k not in record]
    if missing:
        raise ParseError(f, None, f"lacks key(s) {', '.join(missing)}; expected the run.json lorisnb report writes")
    for key, (ok, expected) in SHAPES.items():
        if key in record and not ok(record[key]):
            shown = json.dumps(record[key], default=str)
            shown = shown if len(shown) <= 80 else shown[:77] + "..."
            raise ParseError(f, None, f'"{key}" is {shown}; expected {expected}')
    return record


def _path(key: str, data_root: Path | None) -> Path:
    p = Path(key)
    return (data_root / p) if not p.is_absolute() and data_root is not None else p


def verify_run(run: str | os.PathLike[str]) -> list[tuple[str, str]]:
    """Re-check every input of a run: a list of (path, 'changed', 'missing' or 'added'); empty if
    all inputs still have their recorded SHA-256 and the folders the report read
    (``input_roots``, listed as the report listed them, :func:`input_files`) hold no other file.
    Relative paths are read below the run's data root."""
    record = read_run_json(run)
    root = Path(record["data_root"]) if record.get("data_root") else None
    problems = []
    for key, digest in sorted(record["inputs"].items()):
        p = _path(key, root)
        if not p.is_file():
            problems.append((key, "missing"))
        elif sha256(p) != digest:
            problems.append((key, "changed"))
    if "input_roots" in record:
        now = {_key(p, root) for p in input_files(_path(r, root) for r in record["input_roots"])}
        problems += [(key, "added") for key in sorted(now - set(record["inputs"]))]
    return problems
