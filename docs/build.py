"""Build lorisnb's manual (Sphinx + MyST + myst-nb) offline into OUT.

    python docs/build.py OUT                  # `make docs`: OUT = build/docs, warnings are errors
    python docs/build.py OUT --no-notebooks   # while writing pages: the notebooks left out (not for CI)

The sources are staged in a fresh temporary folder: this folder's pages (``index.md``, every
``guide/*.md``, ``reference/``, ``architecture.md``), the notebooks of ``notebooks/`` with a hidden
cell that sends what they write to a temporary folder (never into the checkout's ``results/``), and
the pages generated from the code: the API reference's list of public names and sub-packages
(:func:`api_page`), the table of layers from the sub-packages' docstrings (:func:`layers_table`) and
the spec table (:func:`lorisnb.core.spec.table.spec_table`). Sphinx runs with warnings as errors;
myst-nb executes every notebook (on the data root lorisnb finds, else the sample shipped with it, as
each notebook says), and one that fails fails the build. MathJax 3 is served from the manual's own
``_static/mathjax/`` (the django-static-mathjax package, as the teaching book does), and the build
fails if a page, style sheet or script would load anything from the network.
``OUT`` is replaced only when this script created it (it holds ``BUILD_MARKER``); any other existing
folder is refused before the build, and left as it is.
"""

from __future__ import annotations

import argparse
import ast
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import nbformat

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT / "teaching"))  # the offline checks and MathJax lookup the teaching book uses

from offline import mathjax_dir, offline_mathjax, publish  # noqa: E402

import lorisnb  # noqa: E402
from lorisnb.core.spec.table import spec_table  # noqa: E402
from lorisnb.errors import OutputError  # noqa: E402
from lorisnb.io.writers import check_owned_folder  # noqa: E402

BUILD_MARKER = ".lorisnb-docs"  # in every folder this script built: only those are replaced
#: the layers, top first, as the import contract in pyproject.toml orders them
LAYERS = ["cli", "tools", "io", "core"]
#: the guide's pages in reading order (index.md's ``guide/*``); any other page follows, alphabetically
GUIDE_ORDER = [
    "installing", "command-line", "datasets", "evaluation-spec", "python", "many-files", "sweeps", "comparing",
    "regression-gating", "history", "reports", "evo", "ordslam", "errors", "teaching", "testing",
]  # fmt: skip
#: the hidden cell after a notebook's parameters: what it writes goes to the build's temporary folder
OUTPUT_CELL = "output_dir = {path!r}  # the manual's build: outputs into a temporary folder"


def docstring(init: Path) -> str:
    """The docstring of a package's ``__init__.py`` (read, not imported)."""
    return ast.get_docstring(ast.parse(init.read_text())) or ""


_ROLE = re.compile(r":(mod|func|class|data|meth|attr|exc):`(~?)([^`]+)`")


def myst_text(text: str, package: str) -> str:
    """reStructuredText roles of a docstring as MyST roles (``:mod:`.runs``` -> ``{mod}`pkg.runs```,
    relative names made absolute from ``package``)."""

    def role(m: re.Match[str]) -> str:
        name = m.group(3)
        return f"{{{m.group(1)}}}`{m.group(2)}{package + name if name.startswith('.') else name}`"

    return _ROLE.sub(role, text)


def _one_line(text: str) -> str:
    return " ".join(text.split()).replace("|", "\\|")


def layers_table() -> str:
    """The layers and their sub-packages as MyST tables: what each holds and what it may import,
    from their docstrings (the part before ``May import:``, and that part)."""
    out = []
    for layer in LAYERS:
        pkg = ROOT / "lorisnb" / layer
        out.append(f"### `lorisnb.{layer}`\n\n{myst_text(docstring(pkg / '__init__.py'), f'lorisnb.{layer}')}\n")
        subs = sorted(p for p in pkg.iterdir() if (p / "__init__.py").is_file())
        if not subs:
            continue
        out.append("| sub-package | holds | may import |\n|---|---|---|")
        for sub in subs:
            text = myst_text(docstring(sub / "__init__.py"), f"lorisnb.{layer}.{sub.name}")
            holds, _, may = text.partition("May import:")
            out.append(
                f"| {{mod}}`lorisnb.{layer}.{sub.name}` | {_one_line(holds)} | {_one_line(may) or '(not said)'} |"
            )
        out.append("")
    return "\n".join(out)


def api_page(template: str) -> str:
    """The API page with the public names (``lorisnb.__all__``)."""
    public = sorted(n for n in lorisnb.__all__ if callable(getattr(lorisnb, n)))
    constants = sorted(n for n in lorisnb.__all__ if n not in public)
    listed = "\n".join(f"- `ln.{n}`: `{getattr(lorisnb, n)!r}`" for n in constants)
    return template.replace("@PUBLIC@", "\n".join("   " + n for n in public)).replace("@CONSTANTS@", listed)


_LITERAL = re.compile(r"(``.+?``)")
#: A docutils system message printed past Sphinx's logging (``:1: (WARNING/2) Inline emphasis ...``).
DOCUTILS_MESSAGE = re.compile(r"\((WARNING|ERROR|SEVERE)/[2-4]\)")


def rst_text(text: str) -> str:
    """A docstring as safe reStructuredText: ``|x|`` (absolute values, not substitutions) escaped
    outside inline literals."""
    return "".join(part if part.startswith("``") else part.replace("|", "\\|") for part in _LITERAL.split(text))


def _title(text: str, char: str) -> str:
    return f"{text}\n{char * len(text)}\n"


def _members(tree: ast.Module) -> list[str]:
    """``name(arguments)``: first docstring line, for each public function and class of a module."""
    out = []
    for node in tree.body:
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef) and not node.name.startswith("_"):
            first = (ast.get_docstring(node) or "").strip().split("\n\n")[0]
            first = " ".join(first.split())
            kind = "class " if isinstance(node, ast.ClassDef) else ""
            out.append(f"- {kind}``{node.name}``" + (f": {first}" if first else ""))
    return out


def package_page(pkg: Path) -> str:
    """A sub-package as reStructuredText: its docstring, then each module's docstring and members
    (read from the source, not imported: every module, optional extras or not)."""
    name = ".".join(pkg.relative_to(ROOT).parts)
    out = [_title(f"``{name}``", "="), f".. py:module:: {name}\n", rst_text(docstring(pkg / "__init__.py")), ""]
    for module in sorted(pkg.glob("*.py")):
        if module.name.startswith("_"):
            continue
        tree = ast.parse(module.read_text())
        out += [_title(f"``{module.stem}``", "-"), f".. py:module:: {name}.{module.stem}\n"]
        out += [rst_text(ast.get_docstring(tree) or ""), "", *map(rst_text, _members(tree)), ""]
    return "\n".join(out)


def packages() -> list[Path]:
    """Every package of lorisnb below the layers (``lorisnb/<layer>/<sub>/``), and the layers that
    hold modules of their own (``lorisnb/cli``)."""
    out = []
    for layer in LAYERS:
        pkg = ROOT / "lorisnb" / layer
        subs = sorted(p for p in pkg.iterdir() if (p / "__init__.py").is_file())
        if [m for m in pkg.glob("*.py") if not m.name.startswith("_")]:
            out.append(pkg)
        out += subs
    return out


def stage_notebook(source: Path, dest: Path, output_dir: Path) -> None:
    """``source`` as the manual executes it: a hidden cell after its parameters sets ``output_dir``."""
    nb = nbformat.read(source, as_version=4)
    at = next((i for i, c in enumerate(nb.cells) if "parameters" in c.get("metadata", {}).get("tags", [])), None)
    if at is None:
        raise SystemExit(f"docs: {source} has no cell tagged 'parameters'")
    cell = nbformat.v4.new_code_cell(OUTPUT_CELL.format(path=str(output_dir)))
    cell.metadata["tags"] = ["remove-cell"]
    nb.cells.insert(at + 1, cell)
    nbformat.write(nb, dest)


#: Seconds a cell may take in the manual's build (the longest notebook takes about 35 s in all): a
#: cell past it is taken for a stalled kernel and the notebook is run once more in a fresh kernel. (The
#: stall seen now and then under load, an idle kernel whose reply the client left unseen until the
#: timeout, is gone: the client of :func:`~lorisnb.tools.report.notebooks.waking_client_class` looks
#: at its sockets every second.)
CELL_TIMEOUT_S = 180


def _execute(path: Path, env: dict[str, str]) -> str | None:
    """Execute one staged notebook in place in this process's own kernel client; its problem
    (``name: error``) or None. A cell that times out is retried once with the whole notebook."""
    from nbclient import NotebookClient
    from nbclient.exceptions import CellTimeoutError
    from tqdm import tqdm

    from lorisnb.tools.report.notebooks import kernel_manager_class

    os.environ.update(env)  # the kernel's environment: TMPDIR of the build, MPLBACKEND
    start = time.perf_counter()
    for attempt in (1, 2):
        nb = nbformat.read(path, as_version=4)
        try:
            NotebookClient(
                nb, timeout=CELL_TIMEOUT_S, startup_timeout=300, kernel_name="python3",
                resources={"metadata": {"path": str(path.parent)}},
                kernel_manager_class=kernel_manager_class(),  # ipc sockets: no race for a TCP port between two kernels
            ).execute()  # fmt: skip
        except CellTimeoutError as exc:
            if attempt == 1:
                tqdm.write(f"docs: {path.stem}: a cell did not answer in {CELL_TIMEOUT_S} s; running it once more")
                continue
            return f"{path.stem}: {' '.join(str(exc).split())[-1500:]}"
        except Exception as exc:  # a cell's error, a kernel that died: the build fails naming it
            return f"{path.stem}: {' '.join(str(exc).split())[-1500:]}"
        break
    nbformat.write(nb, path)
    tqdm.write(f"docs: {path.stem} executed in {time.perf_counter() - start:.0f} s")
    return None


def execute_notebooks(paths: list[Path], jobs: int, env: dict[str, str]) -> list[str]:
    """Execute the staged notebooks in place, ``jobs`` at a time, each in a process of its own
    (a kernel client per process: nbclient's clients in threads of one process stalled with an
    idle kernel now and then), with a progress bar; the problems (``name: error``), none when all
    ran. Sphinx then renders their outputs as they are (myst-nb does not execute again)."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor
    from functools import partial

    from tqdm import tqdm

    with ProcessPoolExecutor(max_workers=max(1, jobs), mp_context=multiprocessing.get_context("spawn")) as pool:
        done = list(tqdm(pool.map(partial(_execute, env=env), paths), total=len(paths), desc="notebooks", unit="nb"))
    return [d for d in done if d]


def reading_order(index: str, src: Path) -> str:
    """``index.md`` with its globs ``guide/*`` and ``notebooks/*`` written out: the pages in reading
    order (:data:`GUIDE_ORDER`, the notebooks in a report's order), then every other page of the
    folder, alphabetically (a glob alone sorts by file name; Sphinx warns on a glob that matches
    nothing after an explicit list, so the list is written here, not beside the glob)."""
    from lorisnb.tools.report.build import DEFAULT_NOTEBOOKS

    for folder, order in (("guide", GUIDE_ORDER), ("notebooks", DEFAULT_NOTEBOOKS)):
        names = {p.stem for p in (src / folder).iterdir() if p.suffix in (".md", ".ipynb", ".rst")}
        listed = [n for n in order if n in names] + sorted(names - set(order))
        index = index.replace(f"\n{folder}/*\n", "\n" + "".join(f"{folder}/{n}\n" for n in listed))
    return index


def stage(src: Path, work: Path, notebooks: bool) -> None:
    """Everything Sphinx reads, in ``src``."""
    shutil.copytree(HERE, src, ignore=shutil.ignore_patterns("build.py", "requirements.txt", "__pycache__", "_build"))
    shutil.copytree(mathjax_dir(), src / "mathjax_static" / "mathjax")
    offline_mathjax(src / "mathjax_static" / "mathjax")
    api = src / "reference" / "api.md"
    api.write_text(api_page(api.read_text()))
    (src / "reference" / "packages").mkdir()
    for pkg in packages():
        (src / "reference" / "packages" / (".".join(pkg.relative_to(ROOT).parts) + ".rst")).write_text(
            package_page(pkg)
        )
    (src / "reference" / "_spec_table.md").write_text(spec_table() + "\n")
    (src / "_layers.md").write_text(layers_table())
    (src / "notebooks").mkdir()
    if notebooks:
        for nb in sorted((ROOT / "notebooks").glob("*.ipynb")):
            out = work / "outputs" / nb.stem
            out.mkdir(parents=True)
            stage_notebook(nb, src / "notebooks" / nb.name, out)
    else:  # a page each, in their place
        for nb in sorted((ROOT / "notebooks").glob("*.ipynb")):
            (src / "notebooks" / f"{nb.stem}.md").write_text(
                f"# {nb.stem}\n\nLeft out of this draft (`--no-notebooks`).\n"
            )
    (src / "index.md").write_text(reading_order((src / "index.md").read_text(), src))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", nargs="?", default="build/docs", type=Path)
    ap.add_argument("--no-notebooks", action="store_true", help="leave the notebooks out (a quick draft)")
    ap.add_argument(
        "--jobs", type=int, default=os.cpu_count() or 1, help="notebooks executed at a time (default: the cores)"
    )
    args = ap.parse_args(argv)
    out = args.out.resolve()
    try:
        check_owned_folder(out, BUILD_MARKER)  # before the build: a folder the script did not make is refused
    except OutputError as exc:
        print(f"docs: {exc}", file=sys.stderr)
        return 2
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="lorisnb-docs-") as tmp:
        work = Path(tmp)
        src, html = work / "src", work / "html"
        stage(src, work, notebooks=not args.no_notebooks)
        kernel_tmp = work / "tmp"  # what the notebooks write to a temporary folder goes with this one
        kernel_tmp.mkdir()
        env = {"TMPDIR": str(kernel_tmp), "MPLBACKEND": "Agg"}
        failed = execute_notebooks(sorted((src / "notebooks").glob("*.ipynb")), args.jobs, env)
        if failed:
            print("docs: notebooks failed to execute (fix them and run `make docs` again):\n  " + "\n  ".join(failed)
                  + f"\ndocs: {out} is left as it was", file=sys.stderr)  # fmt: skip
            return 1
        executed = time.perf_counter()
        cmd = [
            sys.executable,
            "-m",
            "sphinx",
            "-b",
            "html",
            "-j",
            "auto",
            "-W",
            "--keep-going",
            "-q",
            "-d",
            str(work / "doctrees"),
        ]
        r = subprocess.run([*cmd, str(src), str(html)], check=False, env={**os.environ, **env}, stderr=subprocess.PIPE,
                           text=True)  # fmt: skip
        sys.stderr.write(r.stderr)
        # docutils' own messages (a help text parsed by sphinx-argparse) bypass Sphinx's -W: errors too
        if DOCUTILS_MESSAGE.search(r.stderr) and r.returncode == 0:
            r.returncode = 1
        if r.returncode != 0 or not (html / "index.html").is_file():
            print(f"docs: the manual did not build (sphinx exited with {r.returncode}; its warnings, above, "
                  f"are errors here); {out} is left as it was", file=sys.stderr)  # fmt: skip
            return 1
        published = publish(html, out, "docs", BUILD_MARKER)
        if published:
            return published
    print(f"docs: {out / 'index.html'} ({time.perf_counter() - start:.0f} s: staged and executed {executed - start:.0f} s, "
          f"Sphinx {time.perf_counter() - executed:.0f} s)")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
