"""What the teaching scripts (book.py, slides.py, offline_feedback.py) share to keep their HTML
offline: where MathJax 3's files are, and which ``<script src>`` of a page would load from the network."""

from __future__ import annotations

import re
import sys
from pathlib import Path

BUILD_MARKER = ".lorisnb-teaching"  # in every folder book.py / slides.py built: only those are replaced
REMOTE_SCRIPT = re.compile(r"<script[^>]*\ssrc=\"((?:https?:)?//[^\"]+)\"")


def mathjax_dir() -> Path:
    """MathJax 3's browser files (``tex-chtml.js`` and its fonts), from the django-static-mathjax
    package that the Makefile installs into .venv-teach."""
    import mathjax  # the django-static-mathjax distribution's package

    d = Path(mathjax.__file__).parent / "static" / "mathjax" / "es5"
    if not (d / "tex-chtml.js").is_file():
        sys.exit(f"MathJax not found in {d}: install django-static-mathjax (the Makefile's .venv-teach does)")
    return d


def remote_scripts(pages: list[Path]) -> list[str]:
    """``page: url`` for every script of these HTML pages that is not a local file."""
    return [f"{p}: {src}" for p in pages for src in REMOTE_SCRIPT.findall(p.read_text(errors="replace"))]


def refuse_remote(pages: list[Path]) -> int:
    """0 when no page loads a script from the network; else list them on stderr and return 1."""
    bad = remote_scripts(pages)
    if bad:
        print("scripts loaded from the network:\n  " + "\n  ".join(bad), file=sys.stderr)
        return 1
    return 0
