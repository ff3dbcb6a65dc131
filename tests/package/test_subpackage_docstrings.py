"""Every sub-package's docstring (``lorisnb/<layer>/<idea>/__init__.py``; the manual's layers table,
docs/architecture.md, is generated from them) names each of its modules, and its ``May import:``
paragraph names exactly the lorisnb modules its modules import, at the top of a module or inside a
function (read from the source, by AST): none more, none fewer. Sub-packages that import each other
are the ones docs/architecture.md lists, with what imports what. Fast, and independent of
../shared/data."""

from __future__ import annotations

import ast
import re
from collections import defaultdict
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "lorisnb"

#: Imported by (almost) every package's ``__init__`` and never a dependency on an idea: the helper
#: that imports a package's names when first used.
ALWAYS = {"lorisnb._lazy"}
#: The ``:mod:`` references of a docstring (``~`` shortens the shown name, not the target).
MOD = re.compile(r":mod:`~?([\w.]+)`")


def module_name(path: Path) -> str:
    return ".".join(path.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__")


def is_module(name: str) -> bool:
    """Whether ``name`` (``lorisnb.x.y``) is a module or package of the source tree."""
    path = ROOT.joinpath(*name.split("."))
    return path.with_suffix(".py").is_file() or (path / "__init__.py").is_file()


def reexported(package: str, name: str) -> str | None:
    """The module a package's ``name`` comes from, where its ``__init__`` re-exports it under ``if
    TYPE_CHECKING:`` (:func:`lorisnb._lazy.attach`: ``from lorisnb.tools import require`` imports
    :mod:`lorisnb.tools._extras`)."""
    init = ROOT.joinpath(*package.split(".")) / "__init__.py"
    if not init.is_file():
        return None
    for node in ast.walk(ast.parse(init.read_text())):
        if isinstance(node, ast.ImportFrom) and any((a.asname or a.name) == name for a in node.names):
            base = package.split(".")[: len(package.split(".")) - node.level + 1] if node.level else []
            return ".".join([*base, node.module] if node.module else base)
    return None


def imported(path: Path) -> list[tuple[str, int]]:
    """The lorisnb modules a module imports (anywhere in it), with the line: ``from X import n``
    imports the module ``X.n`` where there is one, else the module that defines ``n`` where ``X``
    re-exports it, else ``X``."""
    module = module_name(path)
    here = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
    out = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out += [(a.name, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = (
                ".".join(here[: len(here) - node.level + 1] + ([node.module] if node.module else []))
                if node.level
                else node.module
            )
            assert base
            for a in node.names:
                name = f"{base}.{a.name}"
                out.append((name if is_module(name) else reexported(base, a.name) or base, node.lineno))
    return [(m, line) for m, line in out if m == "lorisnb" or m.startswith("lorisnb.")]


def covers(target: str, module: str) -> bool:
    """Whether naming ``target`` allows importing ``module``: a package stands for its modules, but
    :mod:`lorisnb` itself stands for itself only (not for every module of lorisnb)."""
    return module == target or (target != "lorisnb" and module.startswith(target + "."))


def may_import(doc: str) -> list[str]:
    """The lorisnb modules a docstring's ``May import:`` paragraph allows: those it names before its
    first semicolon (what follows it says what the package must not import, or who imports it)."""
    paragraph = re.search(r"May import:(.*?)(?:\n\s*\n|\Z)", doc, re.S)
    assert paragraph, "no 'May import:' paragraph"
    return MOD.findall(paragraph.group(1).split(";")[0])


SUB_PACKAGES = sorted(p.parent for p in PACKAGE.glob("*/*/__init__.py"))


def test_every_sub_package_is_checked():
    names = [module_name(p) for p in SUB_PACKAGES]
    assert {"lorisnb.core.stats", "lorisnb.io.readers", "lorisnb.tools.decisions", "lorisnb.tools.teaching"} <= set(
        names
    )
    assert len(names) >= 19


@pytest.mark.parametrize("package", SUB_PACKAGES, ids=module_name)
def test_a_sub_package_docstring_names_its_modules_and_what_it_imports(package: Path):
    name = module_name(package)
    doc = ast.get_docstring(ast.parse((package / "__init__.py").read_text())) or ""
    # every module named (``:mod:`.x``` or in full), and every module named exists
    modules = {p.stem for p in package.glob("*.py") if p.stem != "__init__"}
    named = {m.removeprefix(".").removeprefix(name + ".") for m in MOD.findall(doc) if m.startswith((".", name + "."))}
    assert not modules - named, f"{name}'s docstring does not name its modules {sorted(modules - named)}"
    assert not named - modules, f"{name}'s docstring names modules it does not hold: {sorted(named - modules)}"
    # "May import:": what its modules import, exactly
    allowed = may_import(doc)
    assert allowed, f"{name}'s 'May import:' names no module"
    assert all(is_module(t) for t in allowed), f"{name}'s 'May import:' names no such module: {allowed}"
    used: set[str] = set()
    wrong = []
    for path in sorted(package.rglob("*.py")):
        for module, line in imported(path):
            if covers(name, module) or module in ALWAYS:
                continue
            targets = [t for t in allowed if covers(t, module)]
            used.update(targets)
            if not targets:
                wrong.append(f"{path.relative_to(ROOT)}:{line} imports {module}")
    wrong = sorted(set(wrong), key=wrong.index)  # one line per import statement and module
    assert not wrong, f"{name}'s docstring says 'May import: {', '.join(allowed)}', but:\n" + "\n".join(wrong)
    unused = [t for t in allowed if t not in used]
    assert not unused, f"{name}'s 'May import:' names {unused}, which none of its modules imports"


def mutual_imports() -> dict[frozenset[str], set[str]]:
    """Pairs of sub-packages each of which imports the other, with the imports (``a -> b.module``)."""
    edges: dict[tuple[str, str], set[str]] = defaultdict(set)
    names = {module_name(p) for p in SUB_PACKAGES}
    for package in SUB_PACKAGES:
        a = module_name(package)
        for path in package.rglob("*.py"):
            for module, _ in imported(path):
                b = ".".join(module.split(".")[:3])
                if b in names and b != a:
                    edges[a, b].add(module)
    return {frozenset((a, b)): edges[a, b] | edges[b, a] for a, b in edges if (b, a) in edges}


def test_sub_packages_that_import_each_other_are_the_ones_architecture_md_lists():
    """docs/architecture.md lists each pair of sub-packages that import each other (a line
    ``- `core.metrics` <-> `core.pipeline`: ...``), and only those: a new cycle is said, not hidden."""
    text = (ROOT / "docs" / "architecture.md").read_text()
    listed = {
        frozenset(("lorisnb." + a, "lorisnb." + b)) for a, b in re.findall(r"^- `([\w.]+)` <-> `([\w.]+)`", text, re.M)
    }
    found = mutual_imports()
    assert frozenset(("lorisnb.tools.decisions", "lorisnb.tools.report")) in found  # the ones issue 47 found
    assert frozenset(("lorisnb.tools.decisions", "lorisnb.tools.figures")) in found
    missing = sorted(" <-> ".join(sorted(p)) for p in set(found) - listed)
    gone = sorted(" <-> ".join(sorted(p)) for p in listed - set(found))
    assert not missing, f"docs/architecture.md does not list these sub-packages importing each other: {missing}"
    assert not gone, f"docs/architecture.md lists sub-packages that no longer import each other: {gone}"
