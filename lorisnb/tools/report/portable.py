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

from lorisnb.errors import LorisError, OutputError, ValidationError
from lorisnb.io.datasets.manifest import BUILT_IN

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
    """``path`` as ``{name}/inside`` below the innermost of ``roots`` holding it where it is (its
    absolute path as found, links not followed: a file of a folder linked into the results folder is
    ``{results}/linked/x.txt``, one of a data root whose ``openloris-scene`` is a link is
    ``{data}/openloris-scene/...``), else where it really is (both resolved); the absolute path if
    none holds it. A link is written where it is, not where it leads."""
    real = path.parent.resolve() / path.name if path.is_symlink() else path.resolve()
    for p, folders in (
        (Path(os.path.abspath(path)), {k: Path(os.path.abspath(v)) for k, v in roots.items()}),
        (real, {k: v.resolve() for k, v in roots.items()}),
    ):
        best: tuple[int, str] | None = None
        for name, r in folders.items():
            if p == r or r in p.parents:
                depth = len(r.parts)
                if best is None or depth > best[0]:
                    rel = p.relative_to(r).as_posix()
                    best = (depth, mark(name) + ("" if rel == "." else f"/{rel}"))
        if best is not None:
            return best[1]
    return str(real)


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
    way), and as papermill writes it into a notebook's parameters (Python's ``unicode_escape``:
    ``caf\\xe9``), each also as HTML and JSON escape it."""
    forms = {os.path.abspath(path), str(path.resolve())}
    forms |= {f.encode("unicode_escape").decode("ascii") for f in forms}
    out = set()
    for f in forms:
        out |= {f, html.escape(f, quote=True), json.dumps(f)[1:-1], html.escape(json.dumps(f)[1:-1], quote=True)}
    return sorted((s for s in out if len(s) > 1), key=len, reverse=True)


def install_roots() -> list[tuple[str, Path]]:
    """Where this machine keeps the code a run's pages may name (a warning's file and line, papermill's
    ``input_path`` of a bundled notebook): ``{lorisnb}``, the folder holding the lorisnb package
    (a checkout, or site-packages), and ``{python}``, the interpreter's environment and base
    installation. Replaced in a portable run like the named roots; no input lies below them."""
    import sys

    here = Path(__file__).resolve().parents[3]
    found = [("lorisnb", here), ("python", Path(sys.prefix)), ("python", Path(sys.base_prefix))]
    # a system-wide prefix names no one's folder: "/usr/bin/chromium" in a printout stays as it is
    return [(k, p) for k, p in found if len(p.parts) >= 3 and p.as_posix() not in ("/usr/local", "/opt/local")]


def text_of_html(data: bytes) -> bytes:
    """An HTML page's text with its tags taken out: a path a syntax highlighter split over several
    ``<span>`` elements (at an escape, ``\\xe9``) is whole again, for :func:`split_paths`."""
    return re.sub(rb"<[^>]*>", b"", data)


def split_paths(page: Path, roots: Iterable[tuple[str, Path]]) -> bool:
    """Whether the HTML ``page`` still shows one of ``roots``' absolute paths once its tags are
    taken out: a path :func:`make_portable` could not replace because markup splits it."""
    roots = list(roots)
    if not roots:
        return False
    pattern, _ = _pattern(roots)
    return bool(pattern.search(text_of_html(page.read_bytes())))


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
    files = manifest_files(params.get("manifest"))
    if files:  # a manifest's folder, and the folder holding its sessions' ground truth
        if str(params["manifest"]) not in BUILT_IN:
            named["manifest"] = files[0].parent
        truth = [f for f in files if f.suffix.lower() != ".toml"]
        if truth:
            named["sessions"] = Path(os.path.commonpath([os.path.abspath(f.parent) for f in truth]))
    if notebooks is not None:
        named["notebooks"] = Path(notebooks)
    return {k: Path(os.path.abspath(v)) for k, v in named.items()}


def manifest_files(manifest: Any) -> list[Path]:
    """A manifest given as a path (the ``manifest`` parameter), then the ground-truth files it names:
    inputs of a report (for a built-in manifest's name, its ground truth only: the file inside
    lorisnb is none of the user's). Nothing for no manifest, or one that cannot be read (the
    notebook says why)."""
    if not manifest:
        return []
    from lorisnb.io.datasets.manifest import read_manifest

    try:
        m = read_manifest(str(manifest))
    except (LorisError, OSError):
        return []
    own = [] if str(manifest) in BUILT_IN else [Path(os.path.abspath(m.path))]
    return own + [Path(os.path.abspath(s.groundtruth)) for s in m.sessions if s.groundtruth.exists()]


def _pattern(roots: Iterable[tuple[str, Path]]) -> tuple[re.Pattern[bytes], dict[bytes, bytes]]:
    by_text: dict[bytes, bytes] = {}
    for name, root in roots:
        for s in spellings(root):
            by_text.setdefault(s.encode(), mark(name).encode())
    alternatives = sorted(by_text, key=len, reverse=True)  # the longest (innermost) root first
    # a root ends where a path part ends: "/a/res" is not replaced inside "/a/results"; and starts where a path
    # starts, not after a letter or digit (inside base64 image data, "/data/" may occur by chance) unless that
    # is an escaped newline or tab ("...\\n/home/me") or ends a terminal colour code (a traceback's
    # "\x1b[32m/home/me/...", "\\u001b[32m..." in a notebook's JSON), kept as it is (group "esc")
    pattern = re.compile(rb"(?:(?<![A-Za-z0-9+])|(?<=\\[nrt])|(?P<esc>(?:\x1b|\\u001b|\\x1b|\\033)\[[0-9;]*m))(?P<path>"
                         + b"|".join(map(re.escape, alternatives)) + rb")(?![^/\\\s\"'<>&,;:)\]}|`])")  # fmt: skip
    return pattern, by_text


def _replace(pattern: re.Pattern[bytes], by_text: dict[bytes, bytes], data: bytes) -> bytes:
    """``data`` with each of :func:`_pattern`'s matches replaced by its root's name (a colour code
    before it kept)."""
    return pattern.sub(lambda m: (m.group("esc") or b"") + by_text[m.group("path")], data)


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
        p.write_bytes(_replace(pattern, by_text, data))
        changed.append(p)
    return changed


def unreplaced(folder: Path, roots: Iterable[tuple[str, Path]]) -> list[Path]:
    """The files below ``folder`` that still show one of ``roots``' absolute paths where
    :func:`make_portable` did not replace it: after any character (it replaces a path only where
    a path starts), ending where a path part ends. Empty for a portable run; a file listed is a
    place the replacement does not know (said, so that a run is not shared believing it clean)."""
    roots = list(roots)
    if not roots:
        return []
    texts = sorted({s.encode() for _, r in roots for s in spellings(r)}, key=len, reverse=True)
    loose = re.compile(b"(?:" + b"|".join(map(re.escape, texts)) + rb")(?![^/\\\s\"'<>&,;:)\]}|`])")
    return [p for p in sorted(x for x in folder.rglob("*") if x.is_file() and not x.is_symlink())
            if loose.search(p.read_bytes())]  # fmt: skip


def held_paths(folder: Path, roots: Iterable[Path]) -> list[tuple[Path, str]]:
    """(file, absolute path) for each file below ``folder`` that still holds one of ``roots``'
    absolute paths (:func:`spellings`): empty for a portable run."""
    texts = sorted({s for r in roots for s in spellings(r)}, key=len, reverse=True)
    found = []
    for p in sorted(x for x in folder.rglob("*") if x.is_file()):
        data = p.read_bytes()
        found += [(p, s) for s in texts if s.encode() in data]
    return found
