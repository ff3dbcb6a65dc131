"""Build the offline book of the primer and the labs (Jupyter Book 1 + sphinx-exercise).

    python teaching/book.py OUT          # `make book`: OUT = build/book

The sources are staged in a fresh temporary folder: the primer as it is, and each lab's instructor notebook with
every exercise in a sphinx-exercise ``exercise`` block and its solution in a ``solution`` dropdown
(hidden tests removed). Jupyter Book executes them (on the sample data shipped with lorisnb when no
data root is found) and writes HTML into ``OUT/``. MathJax 3 is served from the book's own
``_static/mathjax/`` (copied from the django-static-mathjax package), never from a CDN, and no
widget JavaScript is loaded from the network; sphinx-thebe's scripts (thebe is off) are removed, and the
build fails if a page, style sheet or script references anything on the network. A notebook that
fails to execute fails the build (exit 1, naming it), and ``OUT`` is then left as it was.
``OUT`` is replaced only when the kit created it (it holds ``offline.BUILD_MARKER``); any other
existing folder is refused before the build, and left as it is.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tempfile
from datetime import date
from pathlib import Path

import nbformat
from offline import BUILD_MARKER, mathjax_dir, offline_mathjax, publish

from lorisnb.errors import OutputError
from lorisnb.io.writers import check_owned_folder

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

CONFIG = """\
title: "Lifelong SLAM evaluation: the OpenLORIS-Scene metrics"
author: lorisnb
copyright: "{year}"
only_build_toc_files: true
execute:
  execute_notebooks: force
  timeout: 900
  allow_errors: false
html:
  use_repository_button: false
  use_issues_button: false
  use_edit_page_button: false
  use_multitoc_numbering: false
launch_buttons:
  notebook_interface: none
  binderhub_url: ""
  jupyterhub_url: ""
  thebe: false
  colab_url: ""
sphinx:
  extra_extensions:
    - sphinx_exercise
  config:
    mathjax_path: mathjax/tex-chtml.js
    html_static_path: ["mathjax_static"]
    nb_ipywidgets_js: {}
    html_theme_options:
      navigation_with_keys: false
"""

TOC = """\
format: jb-book
root: intro
chapters:
  - file: metrics_primer
{labs}
"""

INTRO = """\
# Lifelong SLAM evaluation

The primer and the labs of lorisnb's teaching kit, executed: **the instructor's copy**. Each lab
has exercises with their solutions in dropdowns, and its checks show the answers; hand it to
students after the lab, not before. The labs themselves, with their checks, are in `teaching/` of
the lorisnb repository (`make student` gives the student version).

```{tableofcontents}
```
"""

# sphinx-thebe's scripts, added to every page although thebe is off (launch_buttons.thebe: false):
# a CDN URL, declared twice (a JavaScript error), for a button the book does not have
THEBE = re.compile(
    r'[ \t]*<script>const THEBE_JS_URL = [^<]*</script>\n?|[ \t]*<script[^>]*src="[^"]*sphinx-thebe\.js[^"]*"[^>]*></script>\n?'
)
SOLUTION_MARKERS = re.compile(r"^[ \t]*### (BEGIN|END) SOLUTION[ \t]*\n?", re.M)
HIDDEN = re.compile(r"^[ \t]*### BEGIN HIDDEN TESTS.*?### END HIDDEN TESTS[ \t]*\n?", re.S | re.M)


def exercise_title(grade_id: str, prompt: str) -> str:
    """The lab's own label of an exercise (A1, B2, F1 and F2, ...): from the bold "Exercise A1" /
    "Question F1" names in its text, else from its grade_id (``A1_correctness`` -> A1)."""
    names = re.findall(r"\*\*(?:Exercise|Question)?\s*([A-G][0-9])\b", prompt)
    if names:
        return " and ".join(dict.fromkeys(names))
    return grade_id.split("_", 1)[0]


STATIC_EXPLORER = (
    "# In the book the page is static: the explorer's figure and table at its starting values (no fault) stand in\n"
    "# for its sliders (open the notebook in Jupyter to move them).\n"
)


def book_primer(source: Path) -> nbformat.NotebookNode:
    """The primer for the book: the sliders ("Play with the faults"), which a static page cannot move
    (and which would render blank), replaced by the explorer's figure and table at its starting values,
    with a note saying so."""
    nb = nbformat.read(source, as_version=4)
    for k, cell in enumerate(list(nb.cells)):
        if cell.cell_type == "code" and "session.interactive(explorer.widget)" in cell.source:
            nb.cells.insert(k, _md("*In the book the sliders cannot move (the page is static): below, the explorer's "
                                   "figure and table at its starting values, with no fault. Open the notebook in "
                                   "Jupyter to play with the faults.*"))  # fmt: skip
            head = cell.source.split("session.interactive(explorer.widget)")[0]
            cell.source = (STATIC_EXPLORER + head + "explorer_table, explorer_figure = explorer.results()\n"
                           + 'out.figure(explorer_figure, "primer_fault_explorer")\nexplorer_table')  # fmt: skip
    return nb


def _md(text: str) -> nbformat.NotebookNode:
    return nbformat.v4.new_markdown_cell(text)


def _is_prompt(cell: nbformat.NotebookNode) -> bool:
    return cell.cell_type == "markdown" or "question" in cell.get("metadata", {}).get("tags", [])


def book_notebook(source: Path) -> nbformat.NotebookNode:
    """An instructor notebook for the book: exercises and dropdown solutions, no hidden tests."""
    nb = nbformat.read(source, as_version=4)
    cells: list[nbformat.NotebookNode] = []
    for cell in nb.cells:
        meta = cell.get("metadata", {}).get("nbgrader", {})
        cell.metadata.pop("nbgrader", None)
        if cell.cell_type == "code":
            cell.source = HIDDEN.sub("", cell.source).rstrip()
        if meta.get("solution") and cell.cell_type == "code":
            label = f"ex-{meta['grade_id'].lower().replace('_', '-')}"
            # the question: the last markdown cell, or a code cell tagged "question" (its text computed)
            prompt = next((k for k in range(len(cells) - 1, -1, -1) if _is_prompt(cells[k])), None)
            if prompt is not None and "{exercise-" not in cells[prompt].source:
                text = cells[prompt].source
                at = min((i for i in (text.find("**Exercise"), text.find("**Question")) if i >= 0), default=0)
                if at > 0:  # the section's text and heading stay outside the exercise block
                    cells[prompt].source = text[:at].rstrip()
                    prompt += 1
                    cells.insert(prompt, _md(text[at:]))
                title = exercise_title(meta["grade_id"], cells[prompt].source)
                cells.insert(prompt, _md(f"```{{exercise-start}} {title}\n:label: {label}\n:nonumber:\n```"))
                cells.insert(prompt + 2, _md("```{exercise-end}\n```"))
            else:  # a second answer cell under the same text: a block of its own
                title = exercise_title(meta["grade_id"], "")
                cells.append(_md(f"```{{exercise-start}} {title}\n:label: {label}\n:nonumber:\n```"))
                cells.append(_md("Complete the cell below.\n\n```{exercise-end}\n```"))
            cells.append(_md(f"```{{solution-start}} {label}\n:class: dropdown\n```"))
            cell.source = SOLUTION_MARKERS.sub("", cell.source)
            cell.source = re.sub(r"^\w+ = \.\.\.\n", "", cell.source, flags=re.M)
            cells.append(cell)
            cells.append(_md("```{solution-end}\n```"))
            continue
        cells.append(cell)
    nb.cells = cells
    return nb


def without_thebe(html: Path) -> None:
    """Remove sphinx-thebe's scripts from every page of ``html`` (the book's thebe is off)."""
    for page in html.rglob("*.html"):
        text = page.read_text()
        if THEBE.search(text):
            page.write_text(THEBE.sub("", text))


def build_problems(html: Path, returncode: int) -> str | None:
    """What went wrong in a Jupyter Book build (None: nothing): the notebooks that failed to
    execute, with the end of their tracebacks, else jupyter-book's own failure."""
    failed = sorted((html / "reports").glob("*.err.log"))
    if failed:
        tails = "".join(
            f"\n--- {log.name.removesuffix('.err.log')}.ipynb:\n" + "\n".join(log.read_text().splitlines()[-12:])
            for log in failed
        )
        names = ", ".join(log.name.removesuffix(".err.log") + ".ipynb" for log in failed)
        return f"the book did not build: {names} failed to execute (fix it and run `make book` again){tails}"
    if returncode != 0:
        return f"the book did not build: jupyter-book exited with {returncode} (its warnings, above, are errors here)"
    if not (html / "index.html").is_file():
        return "the book did not build: jupyter-book wrote no index.html (see its output above)"
    return None


def main(out: Path) -> int:
    try:
        check_owned_folder(out, BUILD_MARKER)  # before the build: a folder the kit did not make is refused
    except OutputError as exc:
        print(f"book: {exc}", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory(prefix="lorisnb-book-") as tmp:
        src = Path(tmp) / "src"  # not in _static/: Jupyter Book would load every .js file found there
        shutil.copytree(mathjax_dir(), src / "mathjax_static" / "mathjax")
        offline_mathjax(src / "mathjax_static" / "mathjax")
        nbformat.write(book_primer(ROOT / "notebooks" / "metrics_primer.ipynb"), src / "metrics_primer.ipynb")
        labs = sorted(p for p in (HERE / "source").iterdir() if p.is_dir())
        for lab in labs:
            nbformat.write(book_notebook(lab / f"{lab.name}.ipynb"), src / f"{lab.name}.ipynb")
        (src / "_config.yml").write_text(
            CONFIG.replace("{year}", str(date.today().year))
        )  # the footer's year: this one
        (src / "_toc.yml").write_text(TOC.format(labs="\n".join(f"  - file: {lab.name}" for lab in labs)))
        (src / "intro.md").write_text(INTRO)
        kernel_tmp = Path(tmp) / "tmp"  # what the notebooks write to a temporary folder goes with this one
        kernel_tmp.mkdir()
        r = subprocess.run(
            ["jupyter-book", "build", str(src), "--path-output", str(src), "-W", "-n", "--keep-going"],
            check=False,
            env={**os.environ, "TMPDIR": str(kernel_tmp)},
        )
        html = src / "_build" / "html"
        problem = build_problems(html, r.returncode)
        if problem:
            print(f"book: {problem}\nbook: {out} is left as it was", file=sys.stderr)
            return 1
        without_thebe(html)
        published = publish(html, out, "book")
        if published:
            return published
    print(f"book: {out / 'index.html'}")
    return 0


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1] if len(sys.argv) > 1 else "build/book").resolve()))
