"""Portable runs: a report writes every path into its run folder relative to a *named root*
(``{results}``: the results folder, ``{data}``: the data root, ``{run}``: the run folder itself,
and one per path parameter, e.g. ``{groundtruth}``), never as the absolute path of the machine it
ran on (unless asked, ``lorisnb report --absolute-paths``). A run folder copied to a web server or
another laptop then leaks none of its author's paths, and is verified there against the roots
found there (``lorisnb verify RUN --data DIR --results DIR``).

Two steps make it so: the keys of ``run.json`` are written as ``{name}/path/inside``
(:func:`root_key`), and once the run is complete every file of it (pages, notebooks, tables,
figures) has each root's absolute path replaced by its name (:func:`make_portable`), whatever
wrote it: lorisnb, a notebook's printout, papermill's parameters cell.
"""

from __future__ import annotations

import html
import json
import os
import re
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from lorisnb.errors import OutputError, ValidationError

#: The notebook parameters naming an input file or folder besides the results and the data root.
PATH_PARAMETERS = ("path", "groundtruth", "ordslam_dir")

#: The name of a root as written into a run: ``{data}``, ``{results}``.
MARK = "{{{}}}"
_NAMED = re.compile(r"^\{([A-Za-z_][A-Za-z0-9_]*)\}(?:/(.*))?$")


def mark(name: str) -> str:
    """How the root ``name`` is written into a run: ``{name}``."""
    return MARK.format(name)


def split_key(key: str) -> tuple[str, str] | None:
    """``("results", "orb/x.txt")`` for the key ``{results}/orb/x.txt``; None for a key that
    names no root (an absolute path, or a path relative to the data root as runs before named
    roots wrote it)."""
    m = _NAMED.match(key)
    return (m.group(1), m.group(2) or "") if m else None


def root_key(path: Path, roots: Mapping[str, Path]) -> str:
    """``path`` as ``{name}/inside`` below the innermost of ``roots`` holding it (both resolved);
    the absolute path if none holds it. A link is written where it is, not where it leads."""
    p = path.parent.resolve() / path.name if path.is_symlink() else path.resolve()
    best: tuple[int, str] | None = None
    for name, root in roots.items():
        r = root.resolve()
        if p == r or r in p.parents:
            depth = len(r.parts)
            if best is None or depth > best[0]:
                rel = p.relative_to(r).as_posix()
                best = (depth, mark(name) + ("" if rel == "." else f"/{rel}"))
    return best[1] if best else str(p)


def resolve_key(key: str, roots: Mapping[str, Path]) -> Path | None:
    """The file a ``{name}/inside`` key stands for below ``roots[name]`` (where it is: a link in it
    is not followed, as :func:`root_key` writes it); None if ``name`` is not among ``roots``. A key
    that leaves its root as written (``{data}/../..``, ``{data}//etc``) is refused."""
    named = split_key(key)
    if named is None:
        return Path(key)
    name, inside = named
    if name not in roots:
        return None
    root = roots[name].resolve()
    p = Path(os.path.normpath(root / inside)) if inside else root
    if p != root and root not in p.parents:
        raise ValidationError(f"run.json: the input {key!r} leaves its root {mark(name)}; a run lorisnb wrote "
                              "never does (an edited run.json?)")  # fmt: skip
    return p


def spellings(path: Path) -> list[str]:
    """The ways a folder's absolute path can be written: as given and resolved (a link on the
    way), each also as HTML and JSON escape it."""
    forms = {os.path.abspath(path), str(path.resolve())}
    out = set()
    for f in forms:
        out |= {f, html.escape(f, quote=True), json.dumps(f)[1:-1], html.escape(json.dumps(f)[1:-1], quote=True)}
    return sorted((s for s in out if len(s) > 1), key=len, reverse=True)


def named_roots(
    params: Mapping[str, Any], data_root: Path | None, results: Any, notebooks: Path | None
) -> dict[str, Path]:
    """A report's named roots: ``data`` (the data root), ``results`` (the results folder, given
    as ``--results`` or the ``results_dir`` parameter), one per other path parameter (``path``,
    ``groundtruth``, ``ordslam_dir``) and ``notebooks`` (a folder of one's own notebooks)."""
    named: dict[str, Path] = {}
    if data_root is not None:
        named["data"] = Path(data_root)
    if results:
        named["results"] = Path(str(results))
    for k in PATH_PARAMETERS:
        if params.get(k):
            named[k] = Path(str(params[k]))
    if notebooks is not None:
        named["notebooks"] = Path(notebooks)
    return {k: Path(os.path.abspath(v)) for k, v in named.items()}


def _pattern(roots: Iterable[tuple[str, Path]]) -> tuple[re.Pattern[bytes], dict[bytes, bytes]]:
    by_text: dict[bytes, bytes] = {}
    for name, root in roots:
        for s in spellings(root):
            by_text.setdefault(s.encode(), mark(name).encode())
    alternatives = sorted(by_text, key=len, reverse=True)  # the longest (innermost) root first
    # a root ends where a path part ends: "/a/res" is not replaced inside "/a/results"
    pattern = re.compile(b"(?:" + b"|".join(map(re.escape, alternatives)) + rb")(?![^/\\\s\"'<>&,;:)\]}|`])")
    return pattern, by_text


def make_portable(folder: Path, roots: Iterable[tuple[str, Path]]) -> list[Path]:
    """Replace, in every file below ``folder``, each root's absolute path (:func:`spellings`) by
    its name (:func:`mark`); returns the files changed. A file that holds one where it cannot be
    replaced (a compressed or binary file, where the bytes' length or a checksum matters) is an
    :class:`~lorisnb.errors.OutputError` naming it: the run would not be portable."""
    roots = list(roots)
    if not roots:
        return []
    pattern, by_text = _pattern(roots)
    changed = []
    for p in sorted(x for x in folder.rglob("*") if x.is_file() and not x.is_symlink()):
        data = p.read_bytes()
        if not pattern.search(data):
            continue
        try:
            data.decode("utf-8")
        except UnicodeDecodeError:
            raise OutputError(f"{p}: a binary file holds an absolute path of the machine the run was made on, which "
                              "cannot be replaced by its root's name; report it, or pass --absolute-paths") from None  # fmt: skip
        p.write_bytes(pattern.sub(lambda m: by_text[m.group(0)], data))
        changed.append(p)
    return changed


def held_paths(folder: Path, roots: Iterable[Path]) -> list[tuple[Path, str]]:
    """(file, absolute path) for each file below ``folder`` that still holds one of ``roots``'
    absolute paths (:func:`spellings`): empty for a portable run."""
    texts = sorted({s for r in roots for s in spellings(r)}, key=len, reverse=True)
    found = []
    for p in sorted(x for x in folder.rglob("*") if x.is_file()):
        data = p.read_bytes()
        found += [(p, s) for s in texts if s.encode() in data]
    return found
