"""Slides for projecting: the primer and the labs (instructor versions, executed) as reveal.js
slides that open offline.

    python teaching/slides.py OUT        # `make slides`: OUT = build/slides

Each notebook is executed (on the sample data shipped with lorisnb when no data root is found),
a new slide starts at every heading, and the slides are exported with nbconvert's reveal.js
exporter through ``teaching/slides_template/offline`` (no jQuery, require.js, mermaid or widget
scripts). reveal.js (from the sphinx-revealjs package) and MathJax 3 (django-static-mathjax) are
copied into ``OUT/reveal.js`` and ``OUT/mathjax``; the build fails if a page loads a script from the
network. ``OUT`` is replaced only when the kit created it (it holds ``offline.BUILD_MARKER``); any
other existing folder is refused before the build, and left as it is.
"""

from __future__ import annotations

import re
import shutil
import sys
import tempfile
from pathlib import Path

import nbformat
from nbclient import NotebookClient
from nbconvert import SlidesExporter
from offline import BUILD_MARKER, mathjax_dir, refuse_remote

from lorisnb.errors import OutputError
from lorisnb.io.writers import check_owned_folder, replace_folder

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
HIDDEN = re.compile(r"^[ \t]*### BEGIN HIDDEN TESTS.*?### END HIDDEN TESTS[ \t]*\n?", re.S | re.M)
MARKERS = re.compile(r"^[ \t]*### (BEGIN|END) SOLUTION[ \t]*\n?", re.M)


def slide_notebook(path: Path) -> nbformat.NotebookNode:
    """The notebook without nbgrader's markers and hidden tests, a slide per heading."""
    nb = nbformat.read(path, as_version=4)
    for cell in nb.cells:
        cell.metadata.pop("nbgrader", None)
        if cell.cell_type == "code":
            cell.source = MARKERS.sub("", HIDDEN.sub("", cell.source)).rstrip()
            cell.source = re.sub(r"^\w+ = \.\.\.\n", "", cell.source, flags=re.M)
        heading = cell.cell_type == "markdown" and re.match(r"#{1,3} ", cell.source)
        cell.metadata["slideshow"] = {"slide_type": "slide" if heading else "-"}
    return nb


def assets(out: Path) -> None:
    import sphinx_revealjs

    shutil.copytree(Path(sphinx_revealjs.__file__).parent / "_static" / "revealjs", out / "reveal.js")
    shutil.copytree(mathjax_dir(), out / "mathjax")


def main(out: Path) -> int:
    try:
        check_owned_folder(out, BUILD_MARKER)  # before the build: a folder the kit did not make is refused
    except OutputError as exc:
        print(f"slides: {exc}", file=sys.stderr)
        return 2
    notebooks = [ROOT / "notebooks" / "metrics_primer.ipynb"]
    notebooks += [p / f"{p.name}.ipynb" for p in sorted((HERE / "source").iterdir()) if p.is_dir()]
    exporter = SlidesExporter(
        extra_template_basedirs=[str(HERE / "slides_template")],
        template_name="offline",
        reveal_url_prefix="reveal.js",
        reveal_scroll=True,
        mathjax_url="mathjax/tex-chtml.js",
    )
    with tempfile.TemporaryDirectory(prefix="lorisnb-slides-") as tmp:
        built = Path(tmp) / "slides"
        built.mkdir()
        assets(built)
        pages = []
        for path in notebooks:
            nb = slide_notebook(path)
            NotebookClient(nb, timeout=900, kernel_name="python3", resources={"metadata": {"path": tmp}}).execute()
            html, _ = exporter.from_notebook_node(nb)
            page = built / f"{path.stem}.slides.html"
            page.write_text(html)
            pages.append(page)
        if refuse_remote(pages):
            return 1
        try:
            replace_folder(built, out, BUILD_MARKER)
        except OutputError as exc:
            print(f"slides: {exc}", file=sys.stderr)
            return 2
    for path in notebooks:
        print(f"slides: {out / f'{path.stem}.slides.html'}")
    return 0

if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1] if len(sys.argv) > 1 else "build/slides").resolve()))
