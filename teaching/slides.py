"""Slides for projecting: the primer and the labs (instructor versions, executed) as reveal.js
slides that open offline, and for each lab a deck without its solutions (``<lab>.projector.slides.html``:
the answer cells as students have them, only the figures of the outputs) to project during the lab.

    python teaching/slides.py OUT        # `make slides`: OUT = build/slides

Each notebook is executed (on the sample data shipped with lorisnb when no data root is found),
a new slide starts at every heading, and the slides are exported with nbconvert's reveal.js
exporter through ``teaching/slides_template/offline`` (no jQuery, require.js, mermaid or widget
scripts) with reveal.js's ``white`` theme (its fonts are local). reveal.js (from the sphinx-revealjs
package, the Google Fonts imports of its other themes removed) and MathJax 3 (django-static-mathjax)
are copied into ``OUT/reveal.js`` and ``OUT/mathjax``; the build fails if a page, style sheet or
script references anything on the network. What the notebooks write to a temporary folder is removed
with the build's own. ``OUT`` is replaced only when the kit created it (it holds ``offline.BUILD_MARKER``); any
other existing folder is refused before the build, and left as it is.
"""

from __future__ import annotations

import copy
import os
import re
import shutil
import sys
import tempfile
from pathlib import Path

import nbformat
from nbclient import NotebookClient
from nbconvert import SlidesExporter
from offline import BUILD_MARKER, mathjax_dir, offline_mathjax, publish

from lorisnb.errors import OutputError
from lorisnb.io.writers import check_owned_folder

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


SOLUTION = re.compile(r"^([ \t]*)### BEGIN SOLUTION.*?### END SOLUTION[ \t]*\n?", re.S | re.M)


def projector_notebook(executed: nbformat.NotebookNode, source: Path) -> nbformat.NotebookNode:
    """The lab's deck to project during the lab: each answer cell as the students have it (the
    stub, no solution, no output), and after the first answer only the figures of the outputs
    kept (the tables, the checks' lines and the explanations give the answers away)."""
    src = nbformat.read(source, as_version=4)
    nb = copy.deepcopy(executed)
    started = False
    for cell, orig in zip(nb.cells, src.cells, strict=True):
        if cell.cell_type != "code":
            continue
        meta = orig.get("metadata", {}).get("nbgrader", {})
        if meta.get("solution"):
            started = True
            stub = SOLUTION.sub(lambda m: f"{m.group(1)}# YOUR CODE HERE\n{m.group(1)}raise NotImplementedError()\n",
                                HIDDEN.sub("", orig.source))  # fmt: skip
            cell.source, cell.outputs, cell.execution_count = stub.rstrip(), [], None
        elif started or meta.get("grade"):
            cell.outputs = [o for o in cell.get("outputs", []) if "image/png" in o.get("data", {})]
    return nb


REMOTE_IMPORT = re.compile(r"^[ \t]*@import url\((?:https?:)?//[^)]*\);?[ \t]*\n?", re.M)
THEME = "white"  # reveal.js's theme with its fonts beside it (simple, the default, imports Google Fonts)


def assets(out: Path) -> None:
    """reveal.js and MathJax beside the slides, with no reference to the network: the themes that
    import Google Fonts fall back to the browser's fonts (the slides use ``THEME``, whose fonts are local)."""
    import sphinx_revealjs

    shutil.copytree(Path(sphinx_revealjs.__file__).parent / "_static" / "revealjs", out / "reveal.js")
    shutil.rmtree(out / "reveal.js" / "plugin" / "math")  # unused (MathJax is beside it), it loads from a CDN
    for css in (out / "reveal.js").rglob("*.css"):
        text = css.read_text()
        if REMOTE_IMPORT.search(text):
            css.write_text(REMOTE_IMPORT.sub("", text))
    shutil.copytree(mathjax_dir(), out / "mathjax")
    offline_mathjax(out / "mathjax")


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
        reveal_theme=THEME,
        reveal_scroll=True,
        mathjax_url="mathjax/tex-chtml.js",
    )
    with tempfile.TemporaryDirectory(prefix="lorisnb-slides-") as tmp:
        built = Path(tmp) / "slides"
        built.mkdir()
        assets(built)
        kernel_tmp = Path(tmp) / "tmp"  # what the notebooks write to a temporary folder goes with this one
        kernel_tmp.mkdir()
        before = os.environ.get("TMPDIR")
        os.environ["TMPDIR"] = str(kernel_tmp)  # the kernels inherit it
        try:
            for path in notebooks:
                nb = slide_notebook(path)
                NotebookClient(nb, timeout=900, kernel_name="python3", resources={"metadata": {"path": tmp}}).execute()
                html, _ = exporter.from_notebook_node(nb)
                (built / f"{path.stem}.slides.html").write_text(html)
                if path.parent.parent == HERE / "source":  # a lab: its deck without solutions, to project
                    html, _ = exporter.from_notebook_node(projector_notebook(nb, path))
                    (built / f"{path.stem}.projector.slides.html").write_text(html)
        finally:
            if before is None:
                os.environ.pop("TMPDIR", None)
            else:
                os.environ["TMPDIR"] = before
        published = publish(built, out, "slides")
        if published:
            return published
    for path in notebooks:
        print(f"slides: {out / f'{path.stem}.slides.html'}")
        if path.parent.parent == HERE / "source":
            print(f"slides: {out / f'{path.stem}.projector.slides.html'} (no solutions: for projecting during the lab)")
    return 0


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1] if len(sys.argv) > 1 else "build/slides").resolve()))
