"""The inputs of an evaluation, counted once: any iterable of paths as a list of Paths, and files
named more than once (the same file or folder twice, a file and its folder, a symbolic link and
its target) kept once, with a note."""

from __future__ import annotations

import os
import warnings
from collections.abc import Iterable
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import LorisWarning, ValidationError

PathArg = str | os.PathLike[str]


def as_paths(paths: PathArg | Iterable[PathArg]) -> list[Path]:
    """One path or several, as Paths: a str or Path, or any iterable of them (list, tuple,
    generator, set (sorted), numpy array of str, pandas Series or Index). An empty path or
    another type is a ValidationError."""
    if isinstance(paths, np.ndarray):
        paths = paths.ravel().tolist()
    items = [paths] if isinstance(paths, (str, os.PathLike)) else None
    if items is None:
        if isinstance(paths, (bytes, pd.DataFrame)) or not isinstance(paths, Iterable):
            raise ValidationError(
                f"paths: expected a file or folder path (str or pathlib.Path) or a list of them, "
                f"got {type(paths).__name__}"
            )
        items = list(paths)
        if isinstance(paths, (set, frozenset)):
            items = sorted(items, key=str)  # the same order every run
    out = []
    for p in items:
        if not isinstance(p, (str, os.PathLike)):
            raise ValidationError(f"paths: expected str or pathlib.Path items, got {type(p).__name__} ({p!r:.60})")
        if str(p).strip() == "":
            raise ValidationError("paths: an empty path (an unset shell variable?); expected a file or folder")
        out.append(Path(p))
    if not out:
        raise ValidationError("paths: no path given; expected at least one file or folder")
    return out


def real_path(path: Path) -> Path:
    """The file a path names (links resolved), for comparing inputs."""
    try:
        return path.resolve()
    except OSError:
        return path.absolute()


def unique_files(items: list[tuple[Path, Path | None]]) -> list[tuple[Path, Path | None]]:
    """``(file, root)`` pairs with every file kept once (compared by real path, the first naming
    kept), with a LorisWarning listing what was named more than once: an input is never scored
    twice, nor called a duplicate (a second trial) of itself."""
    seen: dict[Path, Path] = {}
    out: list[tuple[Path, Path | None]] = []
    again: list[str] = []
    for path, root in items:
        key = real_path(path)
        if key in seen:
            again.append(str(path) if str(path) == str(seen[key]) else f"{path} (= {seen[key]})")
            continue
        seen[key] = path
        out.append((path, root))
    if again:
        shown = "; ".join(again[:5]) + (f"; and {len(again) - 5} more" if len(again) > 5 else "")
        warnings.warn(
            f"{len(again)} input(s) named more than once, each counted once: {shown}",
            LorisWarning,
            stacklevel=3,
        )
    return out


def near_names(folder: Path, name: str) -> list[str]:
    """Files in ``folder`` whose names differ from ``name`` only in case, or are close to it
    (``XYZ.txt``, ``xyz.TXT``, ``xyz .txt``, ``xzy.txt`` for ``xyz.txt``): what the user meant."""
    import difflib

    try:
        names = sorted(p.name for p in folder.iterdir() if not p.name.startswith("."))
    except OSError:
        return []
    same = [n for n in names if n.lower() == name.lower() and n != name]
    return same or difflib.get_close_matches(name, names, n=3, cutoff=0.75)


def holds_any(folder: Path, names: Iterable[str]) -> bool:
    """Whether ``folder`` holds one of ``names``, or a file differing from one only in case."""
    try:
        present = {p.name.lower() for p in folder.iterdir()}
    except OSError:
        return False
    return any(n.lower() in present for n in names)


def missing_note(folder: Path, algorithm: str, absent: list[tuple[str, str]]) -> str:
    """A warning for sessions without an estimate file: ``absent`` holds (session, expected file)."""
    parts = []
    for session, name in absent:
        near = near_names(folder, name)
        hint = (
            f" (found {', '.join(near)}: names are case-sensitive; rename it or set estimate = '{near[0]}' in the manifest)"
            if near
            else ""
        )
        parts.append(f"{session}: {folder / name} not found{hint}")
    return (
        f"{algorithm}: no estimate for {len(absent)} session(s), scored as missing output (0 poses, CR 0): "
        + "; ".join(parts)
    )
