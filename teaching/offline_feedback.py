"""Make nbgrader's feedback pages open offline, each on its own: nbgrader's feedback template loads
MathJax 2 from a CDN (its ``mathjax()`` call takes no URL), and ``nbgrader release_feedback`` hands
out the .html files only, so after ``nbgrader generate_feedback`` each page gets MathJax 3 (SVG
output: no font files) inlined, with a configuration for ``$...$`` and no menu (whose speech
options would fetch more). Only the pages under ``feedback/`` (written by ``make grade`` just
before) are touched, and only that one script tag.

    python offline_feedback.py [FEEDBACK]   # default teaching/feedback; `make grade`: COURSE/feedback
"""

from __future__ import annotations

import re
import shutil
import sys
from pathlib import Path

from offline import REMOTE_PREFIX, mathjax_dir, refuse_remote

HERE = Path(__file__).resolve().parent
CDN = re.compile(r'<script src="https://cdnjs\.cloudflare\.com/ajax/libs/mathjax/[^"]+">\s*</script>')
OLD_LOCAL = re.compile(
    r'<script>window\.MathJax = [^<]*</script>\s*<script defer src="[^"]*mathjax/tex-chtml\.js"></script>'
)
MARK = '<script id="lorisnb-mathjax">'
CONFIG = (
    '<script>window.MathJax = {tex: {inlineMath: [["$", "$"], ["\\\\(", "\\\\)"]]}, '
    "options: {enableMenu: false}, loader: {load: []}};</script>"
)


def inline_mathjax() -> str:
    """MathJax 3 (TeX input, SVG output, every TeX extension) as one inline script."""
    js = (mathjax_dir() / "tex-svg-full.js").read_text()
    js = js.replace(REMOTE_PREFIX, "./offline-npm/")  # its CDN fallbacks, never used here: kept on the machine
    js = re.sub(r"</(script)", r"<\\/\1", js, flags=re.I).replace("<!--", "<\\!--")
    return f"{CONFIG}\n{MARK}{js}</script>"


def main(feedback: Path) -> int:
    pages = sorted(feedback.rglob("*.html"))
    if not pages:
        return 0
    script = inline_mathjax()
    done = 0
    for page in pages:
        html = page.read_text()
        if MARK in html:
            continue
        new = CDN.sub(lambda _m: script, html, count=1)
        if new == html:  # a page made offline by an earlier version (MathJax in ../../mathjax)
            new = OLD_LOCAL.sub(lambda _m: script, html, count=1)
        page.write_text(new)
        done += new != html
    old = feedback / "mathjax"  # the shared copy earlier versions made: release_feedback never handed it out
    if (old / "tex-chtml.js").is_file():
        shutil.rmtree(old)
    if refuse_remote(pages):
        return 1
    print(f"{done} feedback page(s) of {len(pages)} given MathJax inline (they open offline, each on its own)")
    return 0


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1]).resolve() if len(sys.argv) > 1 else HERE / "feedback"))
