"""Inputs of an evaluation: paths given by the user, the result files and folders they hold, and
the labels (algorithm, file, suite, trial, scene) read from their names."""

from __future__ import annotations

import os
import re
from collections.abc import Iterable
from pathlib import Path

import pandas as pd

from ..core.trials import split_trial
from ..errors import ValidationError
from ..io.manifest import Manifest

PathArg = str | os.PathLike[str]


def is_hidden(path: Path) -> bool:
    """Hidden files and editor leftovers (``.x.txt``, ``.#x.txt``, ``~x.txt``) are not results."""
    return path.name.startswith((".", "~"))


def as_paths(paths: PathArg | Iterable[PathArg]) -> list[Path]:
    """One path or several, as Paths; an empty path or another type is a ValidationError."""
    items = [paths] if isinstance(paths, (str, os.PathLike)) else None
    if items is None:
        if isinstance(paths, (bytes, pd.DataFrame)) or not isinstance(paths, Iterable):
            raise ValidationError(
                f"paths: expected a file or folder path (str or pathlib.Path) or a list of them, "
                f"got {type(paths).__name__}"
            )
        items = list(paths)
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


def result_files(
    paths: PathArg | Iterable[PathArg], suffixes: tuple[str, ...] = (".txt",)
) -> list[tuple[Path, Path | None]]:
    """Expand files and folders into ``(file, root)`` pairs; a folder is walked for files ending in
    ``suffixes`` below it (``root/<algorithm>/*.txt``, or deeper: ``root/<suite>/<algorithm>/*.txt``),
    hidden files and folders left out. A ROS 2 bag (a folder holding ``metadata.yaml``) is one
    file when ``.bag`` is among the suffixes."""
    out: list[tuple[Path, Path | None]] = []
    bags = ".bag" in suffixes
    for p in as_paths(paths):
        if p.is_dir() and not (bags and (p / "metadata.yaml").is_file()):
            found = [f for f in p.rglob("*") if f.suffix in suffixes and f.is_file()]
            if bags:
                found += [m.parent for m in p.rglob("metadata.yaml")]
            files = sorted(f for f in found if not any(is_hidden(Path(part)) for part in f.relative_to(p).parts))
            out.extend((f, p) for f in files)
        else:
            out.append((p, None))
    return out


def names(what: str, value: object) -> list[str]:
    """A name or a list of names (algorithms, scenes), checked."""
    items = [value] if isinstance(value, str) else value
    if not isinstance(items, Iterable) or isinstance(items, (bytes, pd.DataFrame)):
        raise ValidationError(f"{what}={value!r}: expected a name or a list of names")
    names = list(items)
    bad = [n for n in names if not isinstance(n, str)]
    if bad:
        raise ValidationError(f"{what}: expected names (str), got {bad[0]!r}")
    return names


def labels(path: Path, root: Path | None, trials_by: str | None = None) -> tuple[str, str, str, int]:
    """(algorithm, file relative to the root, suite, trial) for a result file; a trial token in
    the path (:func:`lorisnb.core.trials.split_trial`) is not part of the algorithm or suite."""
    if root is None:  # a file given alone: its algorithm is its folder, or the folder above a trial folder
        base, trial = split_trial("/".join(path.parts[-3:]), trials_by)
        parts = base.split("/")
        return (parts[-2] if len(parts) >= 2 else path.parent.name), path.name, "", trial
    rel = path.relative_to(root).as_posix()
    base, trial = split_trial(rel, trials_by)
    parts = base.split("/")
    algorithm = parts[-2] if len(parts) >= 2 else root.name
    return algorithm, rel, "/".join(parts[:-2]), trial


def scene_label(gt_path: Path) -> str:
    """A scene name from a ground-truth path: ``fr2_desk_groundtruth.txt`` -> ``fr2_desk``;
    EuRoC's ``V1_01_easy/mav0/state_groundtruth_estimate0/data.csv`` -> ``V1_01_easy``."""
    generic = {"data", "groundtruth", "gt", "mav0", "state_groundtruth_estimate0", "poses", "metadata"}
    for part in [gt_path.stem, *[p.name for p in gt_path.parents]]:
        name = re.sub(r"[-_.]?(groundtruth|ground_truth|gt)$", "", part, flags=re.IGNORECASE)
        if name and name.lower() not in generic:
            return name
    return gt_path.stem


def algorithm_folders(results: PathArg | Iterable[PathArg], m: Manifest) -> list[tuple[Path, Path | None]]:
    """Folders holding estimate files of the manifest's sessions: each given folder if it holds
    one itself, else its sub-folders that do."""
    names = {s.estimate for s in m.sessions}
    out: list[tuple[Path, Path | None]] = []
    for p in as_paths(results):
        if not p.is_dir():
            raise ValidationError(f"{p}: expected a folder of estimates (one per session, named as in {m.path.name})")
        if any((p / n).exists() for n in names):
            out.append((p, None))
            continue
        subs = sorted(d for d in p.rglob("*") if d.is_dir() and any((d / n).exists() for n in names))
        out.extend((d, p) for d in subs)
        if not subs:
            raise ValidationError(f"{p}: no estimate named {', '.join(sorted(names))} in it or below it")
    return out
