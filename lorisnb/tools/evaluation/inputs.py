"""Inputs of an evaluation: paths given by the user (any iterable of them), the result files and
folders they hold, each counted once (the same file or folder named twice, a file and its folder,
a link and its target: kept once, with a note), and the labels (algorithm, file, suite, trial,
scene) read from their names."""

from __future__ import annotations

import functools
import os
import re
import sys
import warnings
from collections.abc import Collection, Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from lorisnb.core.spec import validate
from lorisnb.core.stats.trials import names_a_trial, split_trial
from lorisnb.errors import LorisWarning, ParseError, ValidationError
from lorisnb.io.datasets.manifest import Manifest

PathArg = str | os.PathLike[str]


def is_hidden(path: Path) -> bool:
    """Hidden files and editor leftovers (``.x.txt``, ``.#x.txt``, ``~x.txt``) are not results."""
    return path.name.startswith((".", "~"))


#: Names (without suffix, any case) of a dataset's or a project's documents, never results: a folder
#: walked for results passes them over as it passes hidden files (the OpenLORIS-Scene folder holds
#: ``LICENSE.txt``); named as an input, such a file is read as any other.
DOCUMENT_NAMES = frozenset({"license", "licence", "copying", "readme", "notice", "changelog", "changes", "authors",
                            "contributors", "citation", "todo"})  # fmt: skip


def is_document(path: Path) -> bool:
    """A document (``LICENSE.txt``, ``README.txt``, ...: :data:`DOCUMENT_NAMES`), not a result."""
    return path.stem.strip().lower() in DOCUMENT_NAMES


def as_paths(paths: PathArg | Iterable[PathArg]) -> list[Path]:
    """One path or several, as Paths: a str or Path, or any iterable of them (list, tuple,
    generator, set (sorted), numpy array of str, pandas Series or Index). An empty path or
    another type is a ValidationError."""
    if isinstance(paths, np.ndarray):
        paths = paths.ravel().tolist()
    items = [paths] if isinstance(paths, (str, os.PathLike)) else None
    if items is None:
        if isinstance(paths, bytes) or _is_frame(paths) or not isinstance(paths, Iterable):
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


@dataclass(frozen=True)
class Found:
    """A file or folder :func:`walk` found: where it is, where it really is (links resolved), what
    it is (``folder``, ``file``, ``dangling``: a link to nothing, or ``other``) and whether it or a
    folder it is in is hidden (:func:`is_hidden`)."""

    path: Path
    real: str
    kind: str
    hidden: bool


def walk(folder: Path, inside: Iterable[Path] | None = None) -> list[Found]:
    """Every file and folder below ``folder``, linked folders followed as folders are (a lab links
    an algorithm's runs from elsewhere into its results folder: they were left out, silently). A
    link to a folder it lies in (a loop) is not walked again, with a LorisWarning naming it.
    ``inside``: folders (resolved) a linked folder must lead into to be walked (a received run's
    check reads nothing elsewhere); one leading elsewhere is listed, not walked. One ``scandir``
    per folder: an entry's real path is its folder's and its name unless it is a link."""
    out: list[Found] = []
    loops: list[str] = []
    allowed = None if inside is None else [Path(f) for f in inside]
    top = os.path.realpath(folder)
    stack = [(os.fspath(folder), top, frozenset({top}), False)]
    seen_as = {top: os.fspath(folder)}  # a folder walked (real path) -> as found, for the loops' warning
    while stack:
        here, real_here, above, hidden_here = stack.pop()
        try:
            with os.scandir(here) as it:
                entries = list(it)
        except OSError:  # an unreadable folder is passed over, as os.walk and rglob do
            continue
        for e in entries:
            link = e.is_symlink()
            real = os.path.realpath(e.path) if link else os.path.join(real_here, e.name)
            try:
                kind = (
                    "folder"
                    if e.is_dir()
                    else "file"
                    if e.is_file()
                    else "dangling"
                    if link and not os.path.exists(e.path)
                    else "other"
                )
            except OSError:
                kind = "other"
            hidden = hidden_here or e.name.startswith((".", "~"))  # is_hidden on the name (no Path: 5,000 files)
            out.append(Found(Path(e.path), real, kind, hidden))
            if kind != "folder":
                continue
            if real in above:  # named as found below the folder walked, not where it lies (a link above)
                loops.append(f"{e.path} -> {seen_as.get(real, real)}")
            elif not link or allowed is None or any(Path(real) == f or f in Path(real).parents for f in allowed):
                seen_as.setdefault(real, e.path)
                stack.append((e.path, real, above | {real}, hidden))
    if loops:
        warnings.warn(f"{len(loops)} linked folder(s) lead back to a folder they are in, not walked again: "
                      + "; ".join(sorted(loops)[:5]), LorisWarning, stacklevel=3)  # fmt: skip
    return out


@dataclass(frozen=True)
class Inputs:
    """What the paths given hold (:func:`find_inputs`): the result files as ``(file, root)`` pairs,
    and the trial folders that hold none (a trial whose run wrote nothing)."""

    files: list[tuple[Path, Path | None]]
    #: each trial folder that holds no result file (:class:`EmptyTrial`)
    empty_trials: list[EmptyTrial]

    def lost_runs(self, trials_by: str | None = None) -> list[tuple[Path, str, tuple[tuple[str, str, int], ...]]]:
        """(folder, why it is a failed input, the (suite, algorithm, trial) runs it leaves without
        output) of each empty trial folder: its trial of every algorithm whose files lie below the
        same place of the tree in the other trials (``trial3/``: every algorithm's; ``orb/run_3/``:
        orb's)."""
        out = []
        for e in self.empty_trials:
            runs: dict[tuple[str, str], None] = {}
            for p, r in self.files:
                if r != e.root:
                    continue
                algorithm, rel, suite, _ = labels(p, r, trials_by)
                if not e.below or split_trial(rel, trials_by)[0].startswith(e.below + "/"):
                    runs[(suite, algorithm)] = None
            out.append((e.folder, e.why, tuple((s, a, e.trial) for s, a in runs)))
        return out


@dataclass(frozen=True)
class EmptyTrial:
    """A trial folder that holds no result file (:func:`empty_trial_folders`): the folder, why it is
    a failed input, the folder walked (``root``), where it lies without its trial token
    (``below``: ``""`` for ``root/trial3``, ``"orb"`` for ``root/orb/run_3``) and its trial."""

    folder: Path
    why: str
    root: Path
    below: str
    trial: int


def result_files(
    paths: PathArg | Iterable[PathArg], suffixes: tuple[str, ...] = (".txt",)
) -> list[tuple[Path, Path | None]]:
    """Expand files and folders into ``(file, root)`` pairs (:func:`find_inputs`' files)."""
    return find_inputs(paths, suffixes).files


def find_inputs(
    paths: PathArg | Iterable[PathArg], suffixes: tuple[str, ...] = (".txt",), trials_by: str | None = None
) -> Inputs:
    """Expand files and folders into ``(file, root)`` pairs; a folder is walked (:func:`walk`: linked
    folders followed) for files ending in ``suffixes`` below it (``root/<algorithm>/*.txt``, or
    deeper: ``root/<suite>/<algorithm>/*.txt``), hidden files and folders and documents
    (:func:`is_document`: ``LICENSE.txt``, ``README.txt``) left out. A ROS 2 bag (a folder holding
    ``metadata.yaml``) is one file when ``.bag`` is among the suffixes. Where the files below a
    folder carry trial numbers (``trials_by``, or the default tokens), a folder named as a trial
    that holds none of them (``trial3/``, ``dso/run_2/``) is returned as an empty trial
    (:func:`empty_trial_folders`)."""
    out: list[tuple[Path, Path | None]] = []
    empty: list[EmptyTrial] = []
    reals: dict[Path, Path] = {}
    bags = ".bag" in suffixes
    for p in as_paths(paths):
        if p.is_dir() and not (bags and (p / "metadata.yaml").is_file()):
            below = [f for f in walk(p) if not f.hidden and not (f.kind != "folder" and is_document(f.path))]
            # a dangling link is an input that fails (saying so), never silently no input
            found = {
                f.path: f.real for f in below if f.path.suffix.lower() in suffixes and f.kind in ("file", "dangling")
            }
            if bags:  # a bag folder is one input: not also its .db3 / .mcap files
                folders = {f.path.parent: os.path.dirname(f.real) for f in below if f.path.name == "metadata.yaml"}
                found = {k: v for k, v in found.items() if not any(d in k.parents for d in folders)} | folders
            reals.update((k, Path(v)) for k, v in found.items())
            out.extend((f, p) for f in sorted(found))
            trials = empty_trial_folders(p, below, found, trials_by)
            asked = " or ".join(", ".join(suffixes).rsplit(", ", 1))
            empty += [EmptyTrial(d, f"{d}: a trial folder that holds no result file (no {asked} file, the format read; "
                       f"{held([d], below).replace('they hold', 'it holds', 1)}): the trial's run wrote nothing, or its "
                       "files were not copied; counted as a failed input (the tables hold the other trials only)",
                                 p, *_folder_trial(d.relative_to(p).as_posix(), trials_by))
                      for d in trials]  # fmt: skip
            _say_empty_algorithms(p, below, found, suffixes, set(trials))
        else:
            out.append((p, None))
    return Inputs(unique_files(out, reals), empty)


def _folder_trial(relpath: str, trials_by: str | None) -> tuple[str, int]:
    """(the folder's path without its trial token, the trial) of a trial folder's relative path
    (:func:`~lorisnb.core.stats.trials.split_trial` reads the last name as a file's)."""
    base, trial = split_trial(relpath + "/_", trials_by)
    return base.removesuffix("_").removesuffix("/"), trial


def _holding(root: Path, found: Iterable[Path]) -> set[str]:
    """Every folder below ``root`` that holds one of the ``found`` files, at any depth (as path
    strings, as :func:`walk` found them)."""
    top = os.fspath(root)
    holding: set[str] = set()
    for f in found:
        d = os.path.dirname(os.fspath(f))
        while d and d != top and d not in holding:  # (its folders above are in it already)
            holding.add(d)
            d, above = os.path.dirname(d), d
            if d == above:  # the file system's root
                break
    return holding


def empty_trial_folders(
    root: Path, below: list[Found], found: Mapping[Path, Any], trials_by: str | None = None
) -> list[Path]:
    """The folders below ``root`` named as a trial (``trial3/``, ``run_2/``: a trial token of
    :mod:`lorisnb.core.stats.trials`, or the ``trials_by`` expression) that hold no result file at
    any depth, at the depth where other trial folders below ``root`` do hold result files: a trial
    whose run wrote nothing (a crash, a copy cut short). Every algorithm may lack it, so no table
    could tell it is missing; the evaluation counts each as a failed input. A folder named so
    beside files that carry their trial in their own name (``dso/run_1/`` of logs beside
    ``dso/cafe_trial1.txt``) is not a trial folder."""
    named = [f.path for f in below if f.kind == "folder" and not f.hidden and names_a_trial(f.path.name, trials_by)]
    if not named:  # (a regular expression per folder, never per file, unless a folder is named as a trial)
        return []
    holding = _holding(root, found)
    depth = len(root.parts)
    used = {len(d.parts) - depth for d in named if os.fspath(d) in holding}  # where trial folders hold results
    return sorted(d for d in named if os.fspath(d) not in holding and len(d.parts) - depth in used)


def _say_empty_algorithms(
    root: Path,
    below: list[Found],
    found: Mapping[Path, Any],
    suffixes: tuple[str, ...] = (".txt",),
    trials: Collection[Path] = (),
) -> None:
    """Warn of a folder beside the algorithms' folders that holds no result file (an algorithm that
    failed on every sequence, or whose files have another suffix than the format asked: said, with
    what the folders hold): it was left out of every table without a word. Folders inside an
    algorithm's (its logs) are not algorithms; empty ``trials`` (:func:`empty_trial_folders`) are
    failed inputs, said as such."""
    # on path strings, as walk found them (pathlib's objects and hashes cost 0.2 s on 5,000 files)
    top = os.fspath(root)
    algorithms = {os.path.dirname(os.fspath(f)) for f in found}
    parents = {os.path.dirname(a) for a in algorithms if a != top}
    candidates = [f.path for f in below if f.kind == "folder" and (s := os.fspath(f.path)) not in algorithms
                  and os.path.dirname(s) in parents and f.path not in trials]  # fmt: skip
    if not candidates:
        return
    holding = _holding(root, found)  # every folder below the root that holds a result file, at any depth
    empty = sorted(c for c in candidates if os.fspath(c) not in holding)
    if empty:
        asked = " or ".join(", ".join(suffixes).rsplit(", ", 1))
        warnings.warn(f"{root}: {len(empty)} folder(s) beside the algorithms' hold no result file (no {asked} file, "
                      f"the format read; {held(empty, below)}), so they are in no table: {_shown(root, empty)}",
                      LorisWarning, stacklevel=4)  # fmt: skip


def _shown(root: Path, folders: list[Path]) -> str:
    """Up to five folders, relative to ``root``, and how many more."""
    return ", ".join(str(e.relative_to(root)) for e in folders[:5]) + (
        f" and {len(folders) - 5} more" * (len(folders) > 5)
    )


def held(folders: Iterable[Path], below: list[Found]) -> str:
    """What ``folders`` hold (``below``: :func:`walk`'s entries), by suffix: ``they hold 1 .txt
    file``, ``they hold 2 .log files and 1 file without a suffix``, ``they hold no file``."""
    inside = tuple(os.fspath(f) + os.sep for f in folders)
    counts: dict[str, int] = {}
    for f in below:
        if f.kind != "folder" and not f.hidden and os.fspath(f.path).startswith(inside):
            key = f.path.suffix.lower()
            counts[key] = counts.get(key, 0) + 1
    if not counts:
        return "they hold no file"
    parts = [f"{n} {k or 'file'}{' file' if k else ''}{'s' * (n > 1)}" + (" without a suffix" if not k else "")
             for k, n in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))]  # fmt: skip
    shown = parts[:3] + ([f"{sum(sorted(counts.values(), reverse=True)[3:])} more"] if len(parts) > 3 else [])
    return "they hold " + " and ".join(", ".join(shown).rsplit(", ", 1))


def names(what: str, value: object) -> list[str]:
    """A name or a list of names (algorithms, scenes), checked."""
    items = [value] if isinstance(value, str) else value
    if not isinstance(items, Iterable) or isinstance(items, bytes) or _is_frame(items):
        raise ValidationError(f"{what}={value!r}: expected a name or a list of names")
    names = list(items)
    if not names:  # it selected nothing: empty tables, exit 0 (or a quick run's defaults in its place)
        raise ValidationError(f"{what}=[]: an empty list selects nothing; expected at least one name (leave {what} "
                              "out, or None, for every one)")  # fmt: skip
    bad = [n for n in names if not isinstance(n, str)]
    if bad:
        raise ValidationError(f"{what}: expected names (str), got {bad[0]!r}")
    return [validate.label(n) for n in names]  # as the labels they are compared with (NFC)


def labels(path: Path, root: Path | None, trials_by: str | None = None) -> tuple[str, str, str, int]:
    """(algorithm, file relative to the root, suite, trial) for a result file; a trial token in
    the path (:func:`lorisnb.core.stats.trials.split_trial`) is not part of the algorithm or suite.
    Computed once per file and process (a run asks three times: its trial checks, then the file's
    task, which a forked worker finds computed; 5,000 files took 0.9 s of pathlib work before)."""
    return _labels(path, root, trials_by, os.getcwd())


@functools.lru_cache(maxsize=1 << 16)
def _labels(path: Path, root: Path | None, trials_by: str | None, cwd: str) -> tuple[str, str, str, int]:
    """:func:`labels`; ``cwd``: the folder relative paths are made absolute from, part of the key (a
    file given alone, or the root ``.``, is named by the folders of its absolute path)."""
    if root is None:  # a file given alone: its algorithm is its folder, or the folder above a trial folder
        # (of the absolute path: ``cafe1.txt`` typed inside ``dso/`` is dso's, as ``dso/cafe1.txt`` is)
        base, trial = split_trial("/".join(absolute(path).parts[-3:]), trials_by)
        parts = base.split("/")
        return validate.label(parts[-2] if len(parts) >= 2 else ""), validate.label(path.name), "", trial
    rel = path.relative_to(root).as_posix()
    base, trial = split_trial(rel, trials_by)
    parts = base.split("/")
    algorithm = parts[-2] if len(parts) >= 2 else absolute(root).name  # ``.`` typed inside ``dso/``: dso
    return validate.label(algorithm), validate.label(rel), validate.label("/".join(parts[:-2])), trial


def scene_label(gt_path: Path) -> str:
    """A scene name from a ground-truth path: ``fr2_desk_groundtruth.txt`` -> ``fr2_desk``;
    EuRoC's ``V1_01_easy/mav0/state_groundtruth_estimate0/data.csv`` -> ``V1_01_easy``. The folders
    are those of the absolute path: ``groundtruth.txt`` typed inside ``fr2_desk/`` is ``fr2_desk``,
    as ``fr2_desk/groundtruth.txt`` is, whatever the current directory."""
    generic = {"data", "groundtruth", "gt", "mav0", "state_groundtruth_estimate0", "poses", "metadata"}
    for part in [gt_path.stem, *[p.name for p in absolute(gt_path).parents]]:
        name = re.sub(r"[-_.]?(groundtruth|ground_truth|gt)$", "", part, flags=re.IGNORECASE)
        if name and name.lower() not in generic:
            return name
    return gt_path.stem


def algorithm_folders(results: PathArg | Iterable[PathArg], m: Manifest) -> list[tuple[Path, Path | None]]:
    """Folders holding estimate files of the manifest's sessions: each given folder if it holds
    one itself, else its sub-folders that do (an estimate may be a path below the folder,
    ``sub/x.txt``: a folder on that path is not an algorithm's). A folder beside those that holds
    none is decided as :func:`result_files` decides it: one holding a close name of an estimate
    (``fr2-desk.txt`` for ``fr2_desk.txt``) is the algorithm it looks like, its sessions scored as
    missing output with the name it holds said (:func:`missing_note`); one holding none is named in
    a LorisWarning (it is in no table). Two sessions whose estimates are one file in a folder
    (``x.txt`` and ``X.txt`` on a file system that ignores case, a link to the other) are a
    ParseError naming both: the file would be scored twice."""
    names = {s.estimate for s in m.sessions}
    out: list[tuple[Path, Path | None]] = []
    for p in as_paths(results):
        if not p.is_dir():
            raise ValidationError(f"{p}: expected a folder of estimates (one per session, named as in {m.path.name})")
        if holds_any(p, names):
            out.append((p, None))
            continue
        below = walk(p)
        subs = sorted(d.path for d in below if d.kind == "folder" and holds_any(d.path, names))
        subs = [d for d in subs if not any(_on_estimate_path(a, d, names) for a in subs if a != d)]
        if not subs:
            near = _near_misses([p, *(d.path for d in below if d.kind == "folder" and not d.hidden)], names)
            hint = f" (found {'; '.join(near[:3])}: a close name; rename it, or set estimate in {m.path.name})"
            raise ValidationError(f"{p}: no estimate named {', '.join(sorted(names))} in it or below it"
                                  + hint * bool(near))  # fmt: skip
        out.extend((d, p) for d in subs + _beside(p, below, subs, names, m))
    out = unique_files(out)  # a folder named twice is scored once
    for folder, _ in out:
        _one_file_each(folder, m)
    return out


def _beside(root: Path, below: list[Found], subs: list[Path], names: set[str], m: Manifest) -> list[Path]:
    """The folders beside the algorithms' ``subs`` that hold no estimate but a close name of one
    (kept: the algorithm they look like, its sessions scored missing with the name said); those
    holding none are named in a LorisWarning, as :func:`result_files` names them."""
    top, algorithms = os.fspath(root), {os.fspath(d) for d in subs}
    parents = {os.path.dirname(a) for a in algorithms if a != top}
    holding = {os.fspath(a) for d in subs for a in (d, *d.parents) if a != root and root in a.parents}
    candidates = sorted(
        f.path for f in below
        if f.kind == "folder" and not f.hidden and (s := os.fspath(f.path)) not in holding
        and os.path.dirname(s) in parents and not any(_on_estimate_path(a, f.path, names, itself=True) for a in subs)
    )  # fmt: skip
    kept = [c for c in candidates if _near_misses([c], names)]
    empty = [c for c in candidates if c not in kept]
    if empty:
        warnings.warn(f"{root}: {len(empty)} folder(s) beside the algorithms' hold no result file (no estimate named "
                      f"{', '.join(sorted(names))} as {m.path.name} names them, nor a close name; "
                      f"{held(empty, below)}), so they are in no table: {_shown(root, empty)}",
                      LorisWarning, stacklevel=4)  # fmt: skip
    return kept


def _near_misses(folders: Iterable[Path], names: Iterable[str]) -> list[str]:
    """``folder/file`` for each file in ``folders`` with a close name of an estimate's
    (:func:`near_names`: ``fr2-desk.txt``, ``fr2_desk.TXT`` for ``fr2_desk.txt``)."""
    out = []
    for folder in folders:
        for n in sorted(names):
            where, _, name = n.rpartition("/")
            out += [f"{folder / where / x}" for x in near_names(folder / where, name)]
    return list(dict.fromkeys(out))


def check_manifest_trials(folders: list[tuple[Path, Path | None]], m: Manifest, trials_by: str | None) -> None:
    """A ``trials_by`` that matches none of the algorithm folders' paths (:func:`algorithm_folders`;
    a manifest's estimates are named by it, so their trials are numbered by their folders) is a
    ValidationError naming the estimate files found, as they are on disk."""
    if trials_by is None or not folders:
        return
    rels = [labels(f / "x", r, trials_by)[1] if r else "/".join(absolute(f / "x").parts[-3:]) for f, r in folders]
    if any(names_a_trial(p, trials_by) for p in rels):
        return
    from lorisnb.io.datasets.paths import named_entry

    files = [str(e) for f, _ in folders for s in m.sessions if os.path.lexists(e := named_entry(f, s.estimate))]
    shown = ", ".join(files[:3]) + (f" and {len(files) - 3} more" if len(files) > 3 else "")
    raise ValidationError(
        f"trials_by={trials_by}: matches none of the folder names of the {len(folders)} algorithm folder(s) and "
        f"{len(files)} estimate file(s) ({shown}); the estimates are named by {m.path.name}, so a trial is numbered "
        "by a folder's name: expected an expression that finds the trial number in one of them, e.g. 'run(\\d+)'"
    )


def _parts(name: str) -> list[str]:
    """An estimate's path as compared: its names (no ``.`` or empty parts), NFC, lower case."""
    return [validate.label(x).lower() for x in name.split("/") if x not in ("", ".")]


def _on_estimate_path(folder: Path, sub: Path, names: Iterable[str], itself: bool = False) -> bool:
    """Whether ``sub`` is a folder on the way to one of ``folder``'s estimates (``sub/x.txt``), or
    (``itself``) the estimate (a ROS 2 bag's folder)."""
    if folder not in sub.parents:
        return False
    rel = _parts(sub.relative_to(folder).as_posix())
    return any(_parts(n)[: len(rel)] == rel and len(_parts(n)) > len(rel) - itself for n in names)


def _one_file_each(folder: Path, m: Manifest) -> None:
    """Refuse two sessions whose estimates in ``folder`` are one file (by device and inode)."""
    from lorisnb.io.datasets.paths import named_entry

    first: dict[tuple[int, int], Any] = {}
    for s in m.sessions:
        found = named_entry(folder, s.estimate)
        key = _file_id(found)
        if key is None:
            continue
        if key in first:
            t, was = first[key]
            raise ParseError(m.path, None, f"sessions {t.seq} ({t.name!r}, estimate = {t.estimate!r}) and {s.seq} "
                             f"({s.name!r}, estimate = {s.estimate!r}) name one file in {folder} ({was.name}, "
                             f"{found.name}): a session listed twice? Each session must be listed once, with its own "
                             "estimate file (it would be scored twice)")  # fmt: skip
        first[key] = (s, found)


def absolute(path: Path) -> Path:
    """``path`` made absolute without resolving links (``..`` taken away as the shell means it):
    where labels read folder names from, so that they never depend on the current directory."""
    return Path(os.path.abspath(path))


def real_path(path: Path) -> Path:
    """The file a path names (links resolved), for comparing inputs."""
    try:
        return path.resolve()
    except OSError:
        return path.absolute()


def unique_files(
    items: list[tuple[Path, Path | None]], reals: dict[Path, Path] | None = None
) -> list[tuple[Path, Path | None]]:
    """``(file, root)`` pairs with every file kept once (compared by real path, at the place of its
    first naming; ``reals``: those already known, :func:`walk`'s), with a LorisWarning listing what
    was named more than once: an input is never scored twice, nor called a duplicate (a second
    trial) of itself. Its labels do not depend on the order of the namings: a folder's naming is
    kept over the file's own (the labels a folder gives: suite, algorithm), and of two folders the
    outer one's (more of the path in the labels), the naming of that file in it. A file linked into
    several trial folders of one tree is a trial in each (copies of one run, which ``compare`` tells)."""
    seen: dict[Path, int] = {}
    out: list[tuple[Path, Path | None]] = []
    again: list[str] = []
    known = reals or {}
    for path, root in items:
        key = known.get(path) or real_path(path)
        if key in seen:
            i = seen[key]
            first = out[i][0]
            if root is not None and root == out[i][1] and _trial_of(path, root) != _trial_of(first, root):
                out.append((path, root))  # one file linked into two trial folders of a tree: a trial each (a copy
                continue  # of the other, which compare tells), never a trial without output
            again.append(str(path) if str(path) == str(first) else f"{path} (= {first})")
            if _naming_order(path, root) < _naming_order(*out[i]):
                out[i] = (path, root)
            continue
        seen[key] = len(out)
        out.append((path, root))
    if again:
        shown = "; ".join(again[:5]) + (f"; and {len(again) - 5} more" if len(again) > 5 else "")
        warnings.warn(
            f"{len(again)} input(s) named more than once, each counted once: {shown}",
            LorisWarning,
            stacklevel=3,
        )
    return out


def _trial_of(path: Path, root: Path) -> int | None:
    """The trial a file's path below ``root`` names by the default tokens (None: a path that
    names two)."""
    try:
        return split_trial(path.relative_to(root).as_posix())[1]
    except ValidationError:
        return None


def _naming_order(path: Path, root: Path | None) -> tuple[int, int, str]:
    """Which naming of a file :func:`unique_files` keeps, the least: a folder's before none, the
    outer folder's (the longest path below it) first, then the smaller path (any order of the
    inputs gives the same)."""
    if root is None:
        return (1, 0, str(path))
    return (0, -len(path.relative_to(root).parts), str(path))


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
    """Whether ``folder`` holds one of ``names`` (a file's name, or a relative path below the folder:
    ``sub/x.txt``), or a file differing from one only in case or in Unicode form (NFC and NFD
    spellings of ``café.txt``), in any of its names."""
    listed: dict[Path, dict[str, list[str]]] = {}

    def entries(here: Path) -> dict[str, list[str]]:  # compared name -> the names as on disk
        if here not in listed:
            got: dict[str, list[str]] = {}
            try:
                for e in here.iterdir():
                    got.setdefault(validate.label(e.name).lower(), []).append(e.name)
            except OSError:
                pass
            listed[here] = got
        return listed[here]

    def below(here: Path, parts: list[str]) -> bool:
        if not parts:
            return True
        if parts[0] == "..":
            return below(here / "..", parts[1:])
        last = len(parts) == 1
        return any(last or (here / e).is_dir() and below(here / e, parts[1:]) for e in entries(here).get(parts[0], []))

    return any(below(Path(folder), parts) for n in names if (parts := _parts(n)))


def outside_results(path: Path, results: Path) -> Path | None:
    """Where an estimate file really is when that lies (links resolved) outside the results folder
    it was found in (a link of the user's, or ``/etc/passwd`` linked into a received folder), else
    None. Such a file is read, as any input the user's folder links to, but an error about it
    quotes none of its content (:func:`unquoted`)."""
    real, top = real_path(path), real_path(results)
    return real if real != top and top not in real.parents else None


def unquoted(exc: ParseError, real: Path, manifest: bool = True) -> ParseError:
    """``exc`` about a file found through a link leading outside the results folder (the file
    itself, or a folder above it; ``real``: where it lies, :func:`outside_results`), without the
    text of the file it quoted: what line, not what it holds (``manifest``: with the option that
    shows it; a folder walked without a manifest has none: the user opens the file). It names the
    file as found below the results folder, and the linked folder on its path by its name, never
    where the link leads (``real`` is a folder of this machine's, not the user's results: a run
    shared keeps it out)."""
    see = "; pass --manifest-outside, or outside=True, to see it" if manifest else ""
    link = _link_on_the_way(Path(os.fspath(exc.path))) if exc.path is not None else None
    how = (
        "a link leading outside the results folder"
        if link is None or link == Path(os.fspath(exc.path))
        else f"in the folder {link.name}, a link leading outside the results folder"
    )  # its name: the path holds it
    return ParseError(exc.path, exc.line, f"not a trajectory file as expected ({how}: its content is not shown{see})")


def _link_on_the_way(path: Path) -> Path | None:
    """The nearest of ``path`` and the folders above it (as written, not resolved) that is a link:
    the one an input was found through; None if none is."""
    return next((p for p in (path, *path.parents) if os.path.islink(p)), None)


def missing_note(folder: Path, algorithm: str, absent: list[tuple[str, str]], taken: Iterable[str] = ()) -> str:
    """A warning for sessions without an estimate file: ``absent`` holds (session, expected file);
    a file of another session (``taken``) is never offered as the one meant."""
    used = set(taken)
    parts = []
    for session, name in absent:
        near = [n for n in near_names(folder, name) if n not in used]
        how = "names are case-sensitive" if near and near[0].lower() == name.lower() else "a close name"
        hint = (
            f" (found {', '.join(near)}: {how}; rename it or set estimate = '{near[0]}' in the manifest)"
            if near
            else ""
        )
        parts.append(f"{session}: {folder / name} not found{hint}")
    return (
        f"{algorithm}: no estimate for {len(absent)} session(s), scored as missing output (0 poses, CR 0): "
        + "; ".join(parts)
    )


def without_groundtruth(items: list[tuple[Path, Path | None]], groundtruth: Path) -> list[tuple[Path, Path | None]]:
    """``(file, root)`` pairs less the ground-truth file itself (a ground truth kept in the results
    folder would be scored as an estimate of itself), with a LorisWarning when it was among them;
    nothing left but the ground truth is a ValidationError (no file at all is for the exit status
    to say: nothing was evaluated)."""
    gt = real_path(groundtruth)
    kept = [(p, r) for p, r in items if real_path(p) != gt]
    if len(kept) < len(items):
        warnings.warn(f"{groundtruth}: the ground truth is among the estimates; left out", LorisWarning, stacklevel=3)
    if items and not kept:
        raise ValidationError(f"{groundtruth}: the only input is the ground truth itself; expected estimate files")
    return kept


def without_dataset_groundtruth(
    items: list[tuple[Path, Path | None]], groundtruths: Iterable[Path]
) -> list[tuple[Path, Path | None]]:
    """``(file, root)`` pairs less the data root's ground-truth files (``groundtruth/gt_<scene>_1.txt``:
    walking the dataset folder found them, and each scored as an estimate of itself, CR 1.0, under
    an algorithm ``groundtruth``), as :func:`without_groundtruth` leaves out a pair's ground truth:
    with a LorisWarning naming them; nothing left but ground truth is a ValidationError."""
    gts = {k for k in map(_file_id, groundtruths) if k is not None}
    if not gts:
        return items
    # the same file, by its device and inode (one stat each: resolving 5,000 paths took 0.2 s)
    ids = [_file_id(p) for p, _ in items]
    kept = [item for item, k in zip(items, ids, strict=True) if k is None or k not in gts]
    if len(kept) < len(items):
        left = sorted(str(p) for (p, _), k in zip(items, ids, strict=True) if k is not None and k in gts)
        warnings.warn(f"{len(left)} ground-truth file(s) of the data among the inputs, left out (a ground truth is not "
                      f"an estimate): {'; '.join(left[:5])}{'; ...' if len(left) > 5 else ''}",
                      LorisWarning, stacklevel=3)  # fmt: skip
    if items and not kept:
        raise ValidationError(f"{items[0][0]}: the inputs are only the data's ground truth; expected result files "
                              "(icra20_results/, or your own)")  # fmt: skip
    return kept


def _file_id(path: Path) -> tuple[int, int] | None:
    """The file ``path`` names (links followed), as its device and inode; None where it cannot be
    read (a dangling link: no ground truth)."""
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return None
    return st.st_dev, st.st_ino


def _is_frame(value: object) -> bool:
    """Whether ``value`` is a pandas DataFrame (iterable, but over its column names): pandas is
    not imported for the question (a DataFrame exists only where it was)."""
    pd = sys.modules.get("pandas")
    return pd is not None and isinstance(value, pd.DataFrame)
