"""Make nbgrader's feedback pages open offline: nbgrader's feedback template loads MathJax 2 from a
CDN (its ``mathjax()`` call takes no URL), so after ``nbgrader generate_feedback`` this copies
MathJax 3 (django-static-mathjax) into ``feedback/mathjax/`` and points each page's MathJax script
there, with a MathJax 3 configuration for ``$...$``. Only the pages under ``feedback/`` (written by
``make grade`` just before) are touched, and only that one script tag.

    python offline_feedback.py [FEEDBACK]   # default teaching/feedback; `make grade`: COURSE/feedback
"""

from __future__ import annotations

import os
import re
import shutil
import sys
from pathlib import Path

from offline import mathjax_dir, refuse_remote

HERE = Path(__file__).resolve().parent
CDN = re.compile(r'<script src="https://cdnjs\.cloudflare\.com/ajax/libs/mathjax/[^"]+">\s*</script>')
CONFIG = '<script>window.MathJax = {tex: {inlineMath: [["$", "$"], ["\\\\(", "\\\\)"]]}};</script>'


def main(feedback: Path) -> int:
    pages = sorted(feedback.rglob("*.html"))
    if not pages:
        return 0
    local = feedback / "mathjax"
    if not local.exists():
        shutil.copytree(mathjax_dir(), local)
    for page in pages:
        html = page.read_text()
        src = Path(os.path.relpath(local / "tex-chtml.js", page.parent)).as_posix()
        html = CDN.sub(lambda _m, s=src: f'{CONFIG}\n<script defer src="{s}"></script>', html)
        page.write_text(html)
    if refuse_remote(pages):
        return 1
    print(f"{len(pages)} feedback page(s) use the local MathJax in {local}")
    return 0


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1]).resolve() if len(sys.argv) > 1 else HERE / "feedback"))
