"""What the teaching scripts (book.py, slides.py, offline_feedback.py) share to keep their HTML
offline: where MathJax 3's files are, and which references of a built file would load something
from the network (scripts, style sheets, ``@import``, fonts, images, or a script's URL string of a
.js/.css/font file, such as sphinx-thebe's ``THEBE_JS_URL``)."""

from __future__ import annotations

import re
import sys
from pathlib import Path

BUILD_MARKER = ".lorisnb-teaching"  # in every folder book.py / slides.py built: only those are replaced
_URL = r"((?:https?:)?//[^\"'`\s>)]+)"
REMOTE = [
    re.compile(r"<script[^>]*\ssrc=[\"']?" + _URL, re.I),
    re.compile(r"<link[^>]*\shref=[\"']?" + _URL, re.I),
    re.compile(r"<(?:img|iframe|source|video|audio|embed|object)[^>]*\s(?:src|data)=[\"']?" + _URL, re.I),
    re.compile(r"@import\s+(?:url\()?\s*[\"']?" + _URL, re.I),
    re.compile(r"url\(\s*[\"']?" + _URL, re.I),
    re.compile(r"[\"'`]((?:https?:)?//[^\"'`\s]+\.(?:m?js|css|woff2?|ttf|otf|eot)(?:\?[^\"'`\s]*)?)[\"'`]", re.I),
]
CHECKED = (".html", ".css", ".js")  # the files a browser reads when a page opens
REMOTE_PREFIX = "https://cdn.jsdelivr.net/npm/"  # where MathJax 3 would fetch what it lacks


def mathjax_dir() -> Path:
    """MathJax 3's browser files (``tex-chtml.js`` and its fonts), from the django-static-mathjax
    package that the Makefile installs into .venv-teach."""
    import mathjax  # the django-static-mathjax distribution's package

    d = Path(mathjax.__file__).parent / "static" / "mathjax" / "es5"
    if not (d / "tex-chtml.js").is_file():
        sys.exit(f"MathJax not found in {d}: install django-static-mathjax (the Makefile's .venv-teach does)")
    return d


def offline_mathjax(folder: Path) -> None:
    """MathJax's own files in ``folder`` (a copy) with its CDN fallbacks (the speech rule engine,
    an XPath polyfill) pointed at a local path: what they would fetch fails on the machine instead
    of leaving it. Only used by the menu's speech options, which the pages do not enable."""
    for js in folder.rglob("*.js"):
        text = js.read_text(errors="surrogateescape")
        if REMOTE_PREFIX in text:
            js.write_text(text.replace(REMOTE_PREFIX, "./offline-npm/"), errors="surrogateescape")


def remote_references(files: list[Path]) -> list[str]:
    """``file: url`` for every reference of these files (.html, .css, .js) that loads from the network."""
    out = []
    for f in files:
        if f.suffix not in CHECKED:
            continue
        text = f.read_text(errors="replace")
        patterns = REMOTE[-1:] if f.suffix == ".js" else REMOTE
        out += [f"{f}: {url}" for p in patterns for url in p.findall(text)]
    return out


def remote_scripts(pages: list[Path]) -> list[str]:
    """The same as :func:`remote_references` (kept for the scripts' callers)."""
    return remote_references(pages)


def refuse_remote(files: list[Path]) -> int:
    """0 when no file loads anything from the network; else list them on stderr and return 1."""
    bad = remote_references(files)
    if bad:
        print("references to the network (nothing may load from it):\n  " + "\n  ".join(bad), file=sys.stderr)
        return 1
    return 0


def built_files(folder: Path) -> list[Path]:
    """Every file of a build a browser may read (``CHECKED``)."""
    return sorted(p for p in folder.rglob("*") if p.suffix in CHECKED and p.is_file())


def publish(built: Path, out: Path, tool: str, marker: str = BUILD_MARKER) -> int:
    """The last step of every offline build (the book, the slides, the manual): refuse a build that
    would load anything from the network, then move it to ``out`` with ``marker`` in it (an earlier
    ``out`` is replaced only if it holds ``marker``). 0, else the exit status with the reason on
    stderr: 1 (the network), 2 (an ``out`` the tool did not make)."""
    from lorisnb.errors import OutputError
    from lorisnb.io.writers import replace_folder

    if refuse_remote(built_files(built)):
        return 1
    try:
        replace_folder(built, out, marker)
    except OutputError as exc:
        print(f"{tool}: {exc}", file=sys.stderr)
        return 2
    return 0
