"""The package's shape: the public API (pinned), the names the README shows, the layers, private
names kept private, notebooks stored clean. Fast, and independent of ../shared/data."""

from __future__ import annotations

import ast
import importlib
import json
import re
import subprocess
import sys
from pathlib import Path

import nbformat
import pytest

import lorisnb as ln
from lorisnb.tools.report.build import DEFAULT_NOTEBOOKS, notebook_dir

ROOT = Path(__file__).resolve().parents[2]

PUBLIC_API = [
    "DataNotFoundError", "EvaluationError", "Evaluation", "FileErrors", "FrameError", "LorisError", "LorisWarning",
    "MissingDependencyError", "OpenLorisFile", "OutputError", "PAPER_EPS", "PAPER_PHI", "ParseError",
    "ResultFile", "SCENES", "SequenceErrors", "Trajectory", "ValidationError", "__version__", "aggregate_scenes",
    "compute_errors", "evaluate", "find_data", "load_groundtruth", "pose_table", "read_euroc", "read_kitti",
    "read_openloris", "read_ordslam", "read_trajectory", "read_tum", "score", "sequence_errors", "setup", "sweep",
    "write_openloris", "Conventions", "session_errors", "evaluate_pairs", "evaluate_manifest", "read_manifest",
    "EvalSpec", "make_spec", "evaluate_sessions",
]  # fmt: skip


def test_public_api_is_pinned():
    assert sorted(ln.__all__) == sorted(PUBLIC_API)
    assert all(hasattr(ln, n) for n in ln.__all__)


def test_version_is_defined_once():
    from importlib import metadata

    assert ln.__version__ == metadata.version("lorisnb")
    assert "version =" not in (ROOT / "pyproject.toml").read_text().split("[project]")[1].split("[")[0]


def test_names_the_readme_shows_exist():
    """The names the README and the manual's pages (docs/**/*.md) show exist."""
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
    assert len(pages) > 10, pages  # the manual's pages are found
    text = "\n".join(p.read_text() for p in pages)
    for name in set(re.findall(r"\blorisnb\.([A-Za-z_][A-Za-z0-9_]*)\(", text)) | set(
        re.findall(r"\bln\.([A-Za-z_][A-Za-z0-9_]*)\b", text)
    ):
        assert hasattr(ln, name), f"the README or a page of docs/ uses lorisnb.{name}, which is not exported"
    for module in set(re.findall(r"`(lorisnb(?:\.[a-z_]+)+)`", text)):
        parts = module.split(".")
        for k in range(len(parts), 0, -1):  # a module, or a name in a module (or in lorisnb itself)
            try:
                m = __import__(".".join(parts[:k]), fromlist=["x"])
            except ImportError:
                continue
            obj = m
            for attr in parts[k:]:
                assert hasattr(obj, attr), f"the README or a page of docs/ names {module}, which does not exist"
                obj = getattr(obj, attr)
            break
        else:
            pytest.fail(f"the README or a page of docs/ names {module}, which does not exist")


def _imports(path: Path):
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            yield node, [a.name for a in node.names]


@pytest.mark.thorough
def test_no_private_names_imported_across_modules():
    for path in (ROOT / "lorisnb").rglob("*.py"):
        for node, names in _imports(path):
            private = [n for n in names if n.startswith("_") and not n.startswith("__")]
            assert not private, f"{path.relative_to(ROOT)}:{node.lineno} imports private {private} from {node.module}"


def test_layers_hold():
    """The import contracts of pyproject.toml (core < io < tools < cli) hold."""
    lint = Path(sys.executable).with_name("lint-imports")
    r = subprocess.run([str(lint)], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "broken" not in r.stdout.lower() or "0 broken" in r.stdout.lower()


def test_core_does_not_look_for_data():
    for path in (ROOT / "lorisnb" / "core").rglob("*.py"):
        text = path.read_text()
        for banned in ("find_data", "LORISNB_DATA", "os.environ", "print("):
            assert banned not in text, f"{path.name} uses {banned}"


def test_notebooks_are_stored_clean_with_one_parameters_cell():
    found = sorted(p.stem for p in notebook_dir().glob("*.ipynb"))
    assert found == sorted(DEFAULT_NOTEBOOKS)
    for path in notebook_dir().glob("*.ipynb"):
        nb = nbformat.read(str(path), as_version=4)
        code = [c for c in nb.cells if c.cell_type == "code"]
        assert all(not c.outputs and c.execution_count is None for c in code), path.name
        tagged = [c for c in code if "parameters" in c.metadata.get("tags", [])]
        assert len(tagged) == 1, path.name
        assert "output_dir = None" in tagged[0].source and "quick" in tagged[0].source, path.name
        assert sum("ln.setup(" in c.source for c in code) == 1, f"{path.name}: one setup call"
        # what JupyterLab writes on connecting to the kernel: stored as is, the notebook opens unmodified
        assert nb.metadata["kernelspec"] == {
            "display_name": "Python 3 (ipykernel)",
            "language": "python",
            "name": "python3",
        }
        assert nb.metadata["language_info"]["name"] == "python" and "codemirror_mode" in nb.metadata["language_info"]
        assert all("id" in c for c in nb.cells), f"{path.name}: cells need ids (nbformat 4.5)"


def test_every_sub_package_says_what_it_holds_and_may_import():
    for init in (ROOT / "lorisnb").rglob("__init__.py"):
        if init.parent.name in ("sample_data",) or init.parent == ROOT / "lorisnb":
            continue
        doc = ast.get_docstring(ast.parse(init.read_text()))
        assert doc, f"{init.relative_to(ROOT)} has no docstring"
        depth = len(init.relative_to(ROOT / "lorisnb").parts)
        if depth == 3:  # lorisnb/<layer>/<idea>/__init__.py
            assert "May import" in doc, f"{init.relative_to(ROOT)} does not say what it may import"


@pytest.mark.parametrize(
    ("old", "new"),
    [("lorisnb.core.scoring", "lorisnb.core.lifelong.scoring"), ("lorisnb.tools.report_index", "lorisnb.tools.report.index"),
     ("lorisnb.io.formats", "lorisnb.io.readers.plain")],
)  # fmt: skip
@pytest.mark.thorough
def test_the_former_flat_names_still_import_with_a_warning(old, new):
    code = (
        "import warnings, importlib, sys\n"
        "warnings.simplefilter('error')\n"
        f"import lorisnb\n"
        f"try:\n    importlib.import_module({old!r})\nexcept DeprecationWarning as w:\n    print('warned', w)\n"
        "warnings.simplefilter('ignore')\n"
        f"m = importlib.import_module({old!r})\n"
        f"print(m is importlib.import_module({new!r}), m.__name__, m.__spec__.name)\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, r.stderr
    assert f"warned {old} moved to {new}" in r.stdout
    assert f"True {new} {new}" in r.stdout


def test_a_former_module_that_is_now_a_package_exports_its_names():
    from lorisnb.core import spec
    from lorisnb.core.spec import evalspec
    from lorisnb.tools import report
    from lorisnb.tools.report import build

    assert spec.EvalSpec is evalspec.EvalSpec and spec.make_spec is evalspec.make_spec
    assert report.notebook_dir is build.notebook_dir and report.DEFAULT_NOTEBOOKS is build.DEFAULT_NOTEBOOKS


def test_tests_mirror_the_layout():
    """Tests live beside the layer they test (tests/core, io, tools, cli; the notebooks, the package
    as installed and the manual have folders of their own), named for what they test, not for the
    probe that found a bug; no two test files share a name (pytest imports them by name)."""
    layers = {"core", "io", "tools", "cli", "notebooks", "package", "docs"}
    files = sorted((ROOT / "tests").rglob("test_*.py"))
    assert files
    assert not [f.name for f in files if f.parent == ROOT / "tests"], "put a new test in tests/<layer>/"
    assert {f.parent.name for f in files} <= layers
    assert not [f.name for f in files if f.name.startswith("test_probe_")]
    names = [f.name for f in files]
    assert len(names) == len(set(names)), sorted({n for n in names if names.count(n) > 1})
    for layer in ("core", "io", "tools", "cli"):
        assert (ROOT / "lorisnb" / layer).is_dir() and (ROOT / "tests" / layer).is_dir()


#: What the kit gives its users to read and run: every import there of a former module path
#: (lorisnb._moved.MOVED) shows each user a DeprecationWarning. Generated course folders are left out.
SHOWN = ("notebooks", "teaching", "docs", "benchmarks")
SHOWN_FILES = (".py", ".ipynb", ".md", ".rst", ".toml", ".txt")
GENERATED = {"release", "submitted", "autograded", "feedback", "graded", "exports", "_build", "__pycache__"}
#: ``from X import a, b`` (or ``(a,\n b)``): a name imported from X is the module X.a where X.a was moved
FROM_IMPORT = re.compile(r"\bfrom\s+(lorisnb(?:\.\w+)*)\s+import\s+(\([^)]*\)|[^\n;`\"']*)")


def _former(module: str, name: str) -> str | None:
    """``from module import name`` imports the former module path ``module.name``: MOVED lists it and
    ``module`` exports no ``name`` of its own (``from lorisnb.core import sweep`` is the function)."""
    from lorisnb._moved import MOVED

    old = f"{module}.{name}"
    return old if old in MOVED and name not in getattr(importlib.import_module(module), "__all__", ()) else None


def _former_names_in_text(text: str) -> set[str]:
    """The former module paths a text imports (``from lorisnb.io import published``, on one line or in
    parentheses, in code, a string or a page's prose) or names (``lorisnb.io.published``, as in
    ``import lorisnb.io.published`` or ``importlib.import_module("lorisnb.io.published")``)."""
    from lorisnb._moved import MOVED

    named = re.compile(r"(?<![\w.])(" + "|".join(map(re.escape, sorted(MOVED, key=len, reverse=True))) + r")(?!\w)")
    found = set(named.findall(text))
    for module, names in FROM_IMPORT.findall(text):
        names = names.strip("()") if names.startswith("(") else names.split("#")[0]
        for piece in names.split(","):
            words = [w for w in piece.split() if w not in ("...", ">>>")]
            if words and (old := _former(module, words[0])):
                found.add(old)
    return found


def _former_names_imported(path: Path) -> set[str]:
    """The former module paths a Python file's import statements name (strings are not looked at: a
    test of the deprecation path imports the former names in a subprocess's code or by
    ``importlib.import_module``)."""
    from lorisnb._moved import MOVED

    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            modules = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            modules = [node.module]
            found |= {old for a in node.names if (old := _former(node.module, a.name))}
        else:
            continue
        for module in modules:
            parts = module.split(".")
            found |= {".".join(parts[:k]) for k in range(2, len(parts) + 1)} & MOVED.keys()
    return found


def test_no_notebook_doc_or_test_imports_a_former_module_path():
    """The notebooks, the teaching kit's sources, the manual, the README and the benchmarks import
    lorisnb's modules from where they live now, not by a former name that lorisnb._moved maps with a
    DeprecationWarning (shown to everyone who runs them); lorisnb's and the tests' own import
    statements too."""
    assert _former_names_in_text("from lorisnb.io import published\n") == {"lorisnb.io.published"}
    assert _former_names_in_text(">>> from lorisnb.core import (\n...     ranking as r,\n...     stats)") == {
        "lorisnb.core.ranking"
    }
    assert _former_names_in_text("x = importlib.import_module('lorisnb.tools.plotting')") == {"lorisnb.tools.plotting"}
    assert not _former_names_in_text("from lorisnb.io.datasets import published\nimport lorisnb.io.datasets.paths\n")
    pages = [ROOT / "README.md", ROOT / "environment.md"]
    for folder in SHOWN:
        pages += [
            p
            for p in (ROOT / folder).rglob("*")
            if p.suffix in SHOWN_FILES and not GENERATED & set(p.relative_to(ROOT).parts)
        ]
    assert sum(p.suffix == ".ipynb" for p in pages) >= 10 and sum(p.suffix == ".md" for p in pages) >= 20, pages
    found = []
    for page in pages:
        text = page.read_text()
        if page.suffix == ".ipynb":  # the cells' text, as the user sees it
            text = "\n".join("".join(c["source"]) for c in json.loads(text)["cells"])
        found += [f"{page.relative_to(ROOT)}: {old}" for old in sorted(_former_names_in_text(text))]
    for path in [*(ROOT / "lorisnb").rglob("*.py"), *(ROOT / "tests").rglob("*.py")]:
        found += [f"{path.relative_to(ROOT)}: {old}" for old in sorted(_former_names_imported(path))]
    assert not found, "former module paths (lorisnb._moved.MOVED; import from the new place):\n" + "\n".join(found)
