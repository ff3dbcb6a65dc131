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

import functools
import html
import json
import os
import re
import unicodedata
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from lorisnb.errors import LorisError, OutputError, ValidationError
from lorisnb.io.datasets.manifest import BUILT_IN
from lorisnb.io.writers import naming

#: The notebook parameters naming an input file or folder besides the results and the data root.
PATH_PARAMETERS = ("path", "groundtruth", "ordslam_dir")

#: The name of a root as written into a run: ``{data}``, ``{results}``.
MARK = "{{{}}}"
#: A key below a root, matched whole (:meth:`re.Pattern.fullmatch`, any character inside, a newline too:
#: ``{results}/new\nline/x.txt`` is one, and ``{results}/alg/x.txt\n`` is not ``{results}/alg/x.txt``).
_NAMED = re.compile(r"\{([A-Za-z_][A-Za-z0-9_]*)\}(?:/(.*))?", re.DOTALL)


def mark(name: str) -> str:
    """How the root ``name`` is written into a run: ``{name}``."""
    return MARK.format(name)


def split_key(key: str) -> tuple[str, str] | None:
    """``("results", "orb/x.txt")`` for the key ``{results}/orb/x.txt``; None for a key that
    names no root (an absolute path, or a path relative to the data root as runs before named
    roots wrote it)."""
    m = _NAMED.fullmatch(key)
    return (m.group(1), m.group(2) or "") if m else None


def root_key(path: Path, roots: Mapping[str, Path]) -> str:
    """``path`` as ``{name}/inside`` below the innermost of ``roots`` holding it where it is (its
    absolute path as found, links not followed: a file of a folder linked into the results folder is
    ``{results}/linked/x.txt``, one of a data root whose ``openloris-scene`` is a link is
    ``{data}/openloris-scene/...``), else where it really is (both resolved); the absolute path if
    none holds it. A link is written where it is, not where it leads; a root given as a link
    (``--results reslink``) holds what was found below it or below where it leads (``res/odom/x.txt``,
    ``odom`` a link of its own, is ``{results}/odom/x.txt``, not the path ``odom`` leads to)."""
    real = path.parent.resolve() / path.name if path.is_symlink() else path.resolve()
    given = [(k, Path(os.path.abspath(v))) for k, v in roots.items()]
    resolved = [(k, v.resolve()) for k, v in roots.items()]
    for p, folders in ((Path(os.path.abspath(path)), given + resolved), (real, resolved)):
        best: tuple[int, str] | None = None
        for name, r in folders:
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


#: ``lorisnb report``'s options naming a root (``--data DIR``, ``--results DIR``, ``--notebooks-dir DIR``,
#: ``--baseline DIR``), and the parameters that do (``-p NAME VALUE``): recorded by the root's name
#: (:func:`command_by_root`).
ROOT_OPTIONS = ("--data", "--results", "--notebooks-dir", "--baseline")
ROOT_PARAMETERS = ("data_root", "results_dir", "notebooks_dir", "manifest", *PATH_PARAMETERS)
#: Options that are also the beginning of a root's option, not an abbreviation of it (argparse takes
#: an option by any unambiguous beginning: ``--res`` is ``--results``, ``--notebooks`` is itself).
_NOT_ROOT_OPTIONS = ("--notebooks",)
_PARAMETER_OPTIONS = ("-p", "--parameter")
#: The option naming the run folder itself: recorded as ``{run}`` (the run is that folder, wherever it
#: was asked for, ``--out runs/r1``, and wherever it is moved).
RUN_OPTIONS = ("--out",)


def _is_option(token: str, options: Iterable[str]) -> bool:
    """Whether ``token`` is one of ``options``, spelled whole or by a beginning of it as argparse
    takes one (``--res`` for ``--results``; ``--notebooks`` is an option of its own)."""
    return token in options or (
        token.startswith("--")
        and len(token) > 2
        and token not in _NOT_ROOT_OPTIONS
        and any(o.startswith(token) for o in options if o.startswith("--"))
    )


def command_by_root(command: Iterable[str], roots: Mapping[str, Path]) -> list[str]:
    """``command`` (a report's argv, as run.json records it) with the value of each option naming a
    root (:data:`ROOT_OPTIONS`: ``--data DIR``, ``--data=DIR``, ``--res DIR``, and ``-p NAME VALUE``
    for :data:`ROOT_PARAMETERS`) written by the name of the root it is, or lies below
    (:func:`root_key`: ``--data {data}``), however it was typed: relative to where the command
    ran (``--data ../data``), through a link (``--results reslink``), or absolute. A relative path
    means nothing once the run is moved, and an absolute one is this machine's. A value below no
    root, and every other argument, is kept as typed, but the run folder (:data:`RUN_OPTIONS`,
    ``--out runs/r1``), which is written ``{run}``."""

    def by_root(value: str) -> str:
        if not value or split_key(value) is not None:
            return value
        try:  # where it is, else where it leads (--data datalink: the data root is recorded resolved)
            key = root_key(Path(value), roots)
            if split_key(key) is None:
                key = root_key(Path(value).resolve(), roots)
        except (OSError, ValueError, RuntimeError):  # no path (a NUL byte), a loop of links
            return value
        return key if split_key(key) is not None else value

    out = list(command)
    i = 1
    while i < len(out):
        token = out[i]
        if token == "--":
            break
        option, eq, value = token.partition("=")
        if token.startswith("--") and eq and _is_option(option, ROOT_OPTIONS):
            out[i] = f"{option}={by_root(value)}"
        elif token.startswith("--") and eq and _is_option(option, RUN_OPTIONS):
            out[i] = f"{option}={mark('run')}"
        elif _is_option(token, ROOT_OPTIONS) and i + 1 < len(out):
            out[i + 1] = by_root(out[i + 1])
            i += 1
        elif _is_option(token, RUN_OPTIONS) and i + 1 < len(out):
            out[i + 1] = mark("run")
            i += 1
        elif _is_option(token, _PARAMETER_OPTIONS) and i + 2 < len(out):
            if out[i + 1] in ROOT_PARAMETERS:
                out[i + 2] = by_root(out[i + 2])
            i += 2
        i += 1
    return out


#: Characters every escaping below writes as they are: a path made of them has one spelling.
_PLAIN = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789/._-")


def _python(c: str) -> set[str]:
    """A character as Python source spells it inside a string literal: papermill's parameters cell
    (``unicode_escape``, then ``"`` as ``\\"``), ``repr`` (a printout of a path in a list)."""
    escaped = c.encode("unicode_escape").decode("ascii")
    out = {escaped, repr(c)[1:-1], c.replace("\\", "\\\\")}
    if c == '"':
        out.add('\\"')
    if c == "'":
        out.add("\\'")
    return out


def _json(c: str) -> set[str]:
    """A character inside a JSON string (a notebook, run.json), ASCII-only or not."""
    return {json.dumps(c)[1:-1], json.dumps(c, ensure_ascii=False)[1:-1]}


def _html(c: str) -> set[str]:
    """A character in an HTML page: ``html.escape`` with ``quote=False`` (nbconvert's highlighter: ``'`` and
    ``"`` as they are) and ``quote=True``, markupsafe's ``&#34;``/``&#39;`` (Jinja templates), a numeric
    reference."""
    out = {c, html.escape(c, quote=True), f"&#{ord(c)};", f"&#x{ord(c):x};"}
    return out if c in "&<>\"'" or ord(c) > 127 else {c}


def _url(c: str) -> set[str]:
    """A character in a link's address (``file:///caf%C3%A9``)."""
    from urllib.parse import quote

    return {quote(c, safe="/")}


_LAYERS = (_python, _json, _html, _url)


def _through(layer: Any, forms: set[str]) -> set[str]:
    """Each of ``forms`` once more escaped by ``layer``, character by character."""
    import itertools

    out = set()
    for f in forms:
        out |= {"".join(p) for p in itertools.product(*(sorted(layer(ch)) for ch in f))}
    return out


@functools.lru_cache(maxsize=4096)
def _char_forms(c: str) -> tuple[str, ...]:
    """Every spelling of the character ``c`` in the files a run holds: as it is (in NFC and NFD),
    then escaped by any of Python, JSON, HTML and URL quoting, one inside another in any order
    (a Python string in a notebook's JSON, JSON in an HTML page, a highlighted parameters cell).
    Every escaping is a character's own, so a path's spellings are its characters' spellings
    one after the other."""
    import itertools

    start = {c, unicodedata.normalize("NFC", c), unicodedata.normalize("NFD", c)}
    found = set(start)
    for n in range(1, len(_LAYERS) + 1):
        for order in itertools.permutations(_LAYERS, n):
            forms = set(start)
            for layer in order:
                forms = _through(layer, forms)
            found |= forms
    return tuple(sorted(found, key=lambda f: (-len(f), f)))


def _bases(path: Path) -> list[str]:
    """A folder's absolute path as given and resolved (a link on the way), each in NFC and NFD."""
    given = {os.path.abspath(path), str(path.resolve())}
    return sorted({unicodedata.normalize(f, g) for g in given for f in ("NFC", "NFD")} | given)


def spellings(path: Path) -> list[str]:
    """The ways a folder's absolute path is written in the files a run holds (:func:`_char_forms`):
    as given and resolved, as papermill writes it into a notebook's parameters (``caf\\xe9``,
    ``dq\\"x``), each also as HTML (with and without its quotes escaped), JSON and a link's
    address escape it, one inside another (the notebook's JSON of a Python string). The same
    escaping throughout a path; :func:`_path_regex` also matches mixtures."""
    import itertools

    encoders: list[list[Any]] = [
        [lambda s: s.encode("unicode_escape").decode("ascii"),
         lambda s: s.encode("unicode_escape").decode("ascii").replace('"', '\\"'), lambda s: repr(s)[1:-1]],
        [lambda s: json.dumps(s)[1:-1], lambda s: json.dumps(s, ensure_ascii=False)[1:-1]],
        [lambda s: html.escape(s, quote=False), lambda s: html.escape(s, quote=True),
         lambda s: html.escape(s, quote=False).replace('"', "&#34;").replace("'", "&#39;")],
    ]  # fmt: skip
    out = set()
    for base in _bases(path):
        for n in range(len(encoders) + 1):
            for order in itertools.permutations(encoders, n):
                for chain in itertools.product(*order):
                    s = base
                    for enc in chain:
                        s = enc(s)
                    out.add(s)
    return sorted((s for s in out if len(s) > 1), key=len, reverse=True)


def _path_regex(path: Path) -> bytes:
    """A regular expression matching every spelling of ``path`` (:func:`_char_forms`, each
    character escaped its own way), as bytes of UTF-8."""
    branches: set[bytes] = set()
    for base in _bases(path):
        parts: list[bytes] = []
        for c in base:
            if c in _PLAIN:
                parts.append(re.escape(c.encode()))
            else:
                parts.append(b"(?:" + b"|".join(re.escape(f.encode()) for f in _char_forms(c)) + b")")
        branches.add(b"".join(parts))
    ordered: list[bytes] = sorted(branches, key=len, reverse=True)
    return b"|".join(ordered)


def _loose_regex(path: Path) -> bytes | None:
    """A regular expression matching ``path`` whatever spells the characters that some escaping
    changes (any few characters in their place), the others as they are; None if too few are left
    to tell the path from another (``/é``)."""
    branches: set[bytes] = set()
    for base in _bases(path):
        runs = re.split(r"[^A-Za-z0-9/._-]+", base)
        if sum(map(len, runs)) < 10 or len(runs) < 2:
            continue  # a path escaping leaves alone is matched by its spellings already
        branches.add(rb"[^\n\r]{1,24}?".join(re.escape(r.encode()) for r in runs))
    ordered: list[bytes] = sorted(branches, key=len, reverse=True)
    return b"|".join(ordered) if branches else None


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


_END = rb"(?![^/\\\s\"'<>&,;:)\]}|`])"  # a root ends where a path part ends: "/a/res" is not "/a/results"


def _pattern(roots: Iterable[tuple[str, Path]]) -> tuple[re.Pattern[bytes], list[bytes]]:
    """A pattern matching each root's spellings (:func:`_path_regex`) where a path starts, and the
    names (:func:`mark`) its groups ``r0``, ``r1``... stand for."""
    unique: dict[str, tuple[str, Path]] = {}
    for name, root in roots:
        unique.setdefault(os.path.abspath(root), (name, root))
    ordered = sorted(unique.values(), key=lambda r: len(os.path.abspath(r[1])), reverse=True)  # innermost first
    names = [mark(name).encode() for name, _ in ordered]
    branches = b"|".join(b"(?P<r%d>" % i + _path_regex(root) + b")" for i, (_, root) in enumerate(ordered))
    # a root starts where a path starts, not after a letter or digit (inside base64 image data, "/data/" may
    # occur by chance) unless that is an escaped newline or tab ("...\\n/home/me") or ends a terminal colour
    # code (a traceback's "\x1b[32m/home/me/...", "\\u001b[32m..." in a notebook's JSON), kept as it is
    pattern = re.compile(rb"(?:(?<![A-Za-z0-9+])|(?<=\\[nrt])|(?P<esc>(?:\x1b|\\u001b|\\x1b|\\033)\[[0-9;]*m))(?:"
                         + branches + b")" + _END)  # fmt: skip
    return pattern, names


def _replace(pattern: re.Pattern[bytes], names: list[bytes], data: bytes) -> bytes:
    """``data`` with each of :func:`_pattern`'s matches replaced by its root's name (a colour code
    before it kept)."""

    def name(m: re.Match[bytes]) -> bytes:
        which = next(int(k[1:]) for k, v in m.groupdict().items() if k[0] == "r" and v is not None)
        return (m.group("esc") or b"") + names[which]

    return pattern.sub(name, data)


def make_portable(folder: Path, roots: Iterable[tuple[str, Path]]) -> list[Path]:
    """Replace, in every file below ``folder``, each root's absolute path (any of its spellings:
    :func:`_char_forms`) by its name (:func:`mark`); returns the files changed. A file that holds
    one where it cannot be replaced (a compressed or binary file, where the bytes' length or a
    checksum matters) is an :class:`~lorisnb.errors.OutputError` naming it: the run would not be
    portable. An error about a link leading outside the results folder says so without the path
    it leads to (:func:`hide_link_targets`)."""
    roots = list(roots)
    if not roots:
        return []
    pattern, names = _pattern(roots)
    changed = []
    for p in sorted(x for x in folder.rglob("*") if x.is_file() and not x.is_symlink()):
        data = p.read_bytes()
        hidden = hide_link_targets(data)
        if not pattern.search(hidden):
            if hidden != data:
                with naming(p):  # a full disk names the file
                    p.write_bytes(hidden)
                changed.append(p)
            continue
        try:
            data.decode("utf-8")
        except UnicodeDecodeError:
            raise OutputError(f"{p}: a binary file holds an absolute path of the machine the run was made on, which "
                              "cannot be replaced by its root's name; report it, or pass --absolute-paths") from None  # fmt: skip
        with naming(p):
            p.write_bytes(_replace(pattern, names, hidden))
        changed.append(p)
    return changed


#: How an error names the file a link leads to outside the results folder (lorisnb's evaluation).
_LINK_TARGET = re.compile(rb"\(a link to [^\n\r]{1,4096}?, outside the results folder")


def hide_link_targets(data: bytes) -> bytes:
    """``data`` with each error's ``(a link to /where/it/leads, outside the results folder`` said as
    ``(a link leading outside the results folder``: that path lies below no root of the run (its
    name would say nothing elsewhere) and is the machine's own."""
    if b"a link to " not in data:
        return data
    return _LINK_TARGET.sub(b"(a link leading outside the results folder", data)


#: Folders too generic to tell whose a run is: a root's parent among them is not looked for.
GENERIC_FOLDERS = frozenset({"/usr/local", "/opt/local", "/var/tmp", "/private/tmp", "/private/var"})


def author_folders(roots: Iterable[tuple[str, Path]]) -> list[Path]:
    """The folders holding ``roots`` (as given and links resolved), up to but not including the
    short generic ones (``/``, ``/tmp``, ``/home``, ``/Users``: fewer than three parts, and
    :data:`GENERIC_FOLDERS`): a notebook printing ``os.path.dirname(results_dir)`` shows the
    author's folder (``/home/me/lab``), which names no root and is not replaced."""
    out: dict[str, Path] = {}
    for _, root in roots:
        for base in {Path(os.path.abspath(root)), Path(root).resolve()}:
            for p in base.parents:
                if len(p.parts) >= 3 and p.as_posix() not in GENERIC_FOLDERS:
                    out.setdefault(str(p), p)
    return sorted(out.values())


def _quoted_regex(path: Path) -> bytes:
    """A folder's absolute path as URL quoting writes it whole, ``/`` quoted too
    (``urllib.parse.quote_plus``, ``quote(..., safe="")``: ``%2Fhome%2Fme``), any case of hex."""
    from urllib.parse import quote, quote_plus

    forms = {f(b) for b in _bases(path) for f in (quote_plus, lambda x: quote(x, safe=""))}
    return b"|".join(re.sub(rb"%([0-9A-F]{2})", lambda m: b"%(?i:" + m[1] + b")", re.escape(f.encode()))
                     for f in sorted(forms, key=len, reverse=True))  # fmt: skip


def unreplaced(folder: Path, roots: Iterable[tuple[str, Path]], also: Iterable[Path] = ()) -> list[Path]:
    """The files below ``folder`` that still show one of ``roots``' absolute paths where
    :func:`make_portable` did not replace it: any spelling (:func:`_path_regex`) after any
    character (it replaces a path only where a path starts), and the path with its escaped
    characters spelled any other way (:func:`_loose_regex`: an escaping it does not know), or URL
    quoted whole (:func:`_quoted_regex`), ending where a path part ends; ``also``: other folders
    of the author's looked for the same way, but for the loose spellings (the folders holding
    the roots, :func:`author_folders`). Empty for a portable run; a file listed is a place the
    replacement does not know (said, so that a run is not shared believing it clean)."""
    roots = list(roots)
    if not roots:
        return []
    others = list(also)
    exact = [_path_regex(r) for r in [*(r for _, r in roots), *others]]
    quoted = [_quoted_regex(r) for r in [*(r for _, r in roots), *others]]
    loose = [x for x in (_loose_regex(r) for _, r in roots) if x is not None]
    found = re.compile(b"(?:" + b"|".join(exact + quoted + loose) + b")" + _END)
    return [p for p in sorted(x for x in folder.rglob("*") if x.is_file() and not x.is_symlink())
            if found.search(p.read_bytes())]  # fmt: skip


def held_paths(folder: Path, roots: Iterable[Path]) -> list[tuple[Path, str]]:
    """(file, absolute path) for each file below ``folder`` that still holds one of ``roots``'
    absolute paths (:func:`spellings`): empty for a portable run."""
    texts = sorted({s for r in roots for s in spellings(r)}, key=len, reverse=True)
    found = []
    for p in sorted(x for x in folder.rglob("*") if x.is_file()):
        data = p.read_bytes()
        found += [(p, s) for s in texts if s.encode() in data]
    return found
