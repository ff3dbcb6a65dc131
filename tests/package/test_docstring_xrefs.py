"""Every Sphinx cross-reference in lorisnb's docstrings (``:func:``, ``:mod:``, ``:class:``, ``:meth:``,
``:data:``, ``:attr:``, ``:exc:``, ``:obj:``; also in ``#:`` comments, which autodoc reads) and every
MyST one in the manual's pages (``{func}`lorisnb...```) names a real object: its module imports and
the rest of the name is an attribute. A dotted ``lorisnb.*`` name must resolve as written; a
relative one (``:mod:`.runs```) from the docstring's package or module, a bare one (``:func:`score```)
from the module, its class, or builtins. A renamed function or a moved module left a reference to
nothing (``lorisnb.plotting``, ``streaming.sweep_to_dataset``)."""

from __future__ import annotations

import ast
import importlib
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
ROLES = "mod|func|class|meth|data|attr|exc|obj"
#: ``:role:`target```, ``:role:`~target```, ``:role:`title <target>```
RST = re.compile(rf":({ROLES}):`~?([^`<]*?)(?:\s*<([^>`]+)>)?`")
MYST = re.compile(rf"\{{({ROLES})\}}`~?([^`<]*?)(?:\s*<([^>`]+)>)?`")
#: Instance attributes set in ``__init__`` or a method (``self.x = ...``), which no class holds until
#: an instance exists: named bare, in the module where they are set.
INSTANCE_ATTRIBUTES = {
    ("lorisnb.tools.notebook.start", "adopting"),
    ("lorisnb.tools.notebook.widgets", "scenes"),
    ("lorisnb.tools.teaching.sandbox", "stray"),
    ("lorisnb.tools.teaching.sandbox", "findings"),
}


def module_name(path: Path) -> str:
    return ".".join(path.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__")


def resolves(name: str) -> bool:
    """Whether ``name`` (``package.module.Class.member``) is a module, or an attribute of one (a
    dataclass field or an annotated class attribute counts)."""
    parts = name.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ModuleNotFoundError as exc:
            if exc.name is None or not ".".join(parts[:k]).startswith(exc.name):
                raise  # a module that does not import, for another reason than its name
            continue
        for attr in parts[k:]:
            if isinstance(obj, type) and (
                attr in getattr(obj, "__dataclass_fields__", {}) or attr in getattr(obj, "__annotations__", {})
            ):
                return attr == parts[-1]  # a field's value is known on an instance only
            if not hasattr(obj, attr):
                return False
            obj = getattr(obj, attr)
        return True
    return False


def candidates(target: str, module: str, package: str, cls: str | None) -> list[str]:
    """Where Sphinx looks for a reference from a docstring of ``module`` (in ``cls``)."""
    target = target.strip().removesuffix("()")
    if target.startswith("lorisnb.") or target == "lorisnb":
        return [target]
    if target.startswith("."):
        rest = target.lstrip(".")
        return [f"{package}.{rest}", f"{module}.{rest}"] + ([f"{module}.{cls}.{rest}"] if cls else [])
    local = [f"{module}.{target}"] + ([f"{module}.{cls}.{target}"] if cls else [])
    return local + [f"lorisnb.{target}", f"builtins.{target}"] + ([target] if "." in target else [])


def docstrings(node: ast.AST, cls: str | None):
    """``(docstring, line, class it is in)`` of every class and function below ``node``."""
    for child in ast.iter_child_nodes(node):
        inner = child.name if isinstance(child, ast.ClassDef) else cls
        if isinstance(child, ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            yield ast.get_docstring(child) or "", child.lineno, inner
        yield from docstrings(child, inner)


def references():
    """``(where, role, target, module, package, class)`` of every reference in lorisnb's docstrings and
    ``#:`` comments."""
    for path in sorted((ROOT / "lorisnb").rglob("*.py")):
        module = module_name(path)
        package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
        source = path.read_text()
        tree = ast.parse(source)
        texts = [(ast.get_docstring(tree) or "", 1, None), *docstrings(tree, None)]
        texts += [(line, i, None) for i, line in enumerate(source.splitlines(), 1) if line.strip().startswith("#:")]
        for text, line, cls in texts:
            for role, title, target in RST.findall(text):
                yield f"{path.relative_to(ROOT)}:{line}", role, target or title, module, package, cls


def test_every_docstring_reference_names_a_real_object():
    found = list(references())
    assert len(found) > 1000  # the references are read
    assert any(t.startswith("lorisnb.core.lifelong.scoring.") for _, _, t, *_ in found)
    wrong = []
    for where, role, target, module, package, cls in found:
        if role == "attr" and (module, target.strip()) in INSTANCE_ATTRIBUTES:
            continue
        if not any(resolves(c) for c in candidates(target, module, package, cls)):
            wrong.append(f"{where}: :{role}:`{target}`")
    assert not wrong, "references to nothing:\n" + "\n".join(sorted(set(wrong)))


def test_the_instance_attributes_left_out_are_still_set_where_they_are_named():
    """The few references that cannot resolve statically are instance attributes their module sets
    (``self.<name> =``); one no longer set there is a reference to nothing."""
    for module, name in INSTANCE_ATTRIBUTES:
        source = (ROOT / Path(*module.split("."))).with_suffix(".py").read_text()
        assert re.search(rf"\bself\.{name}\b\s*(:[^=]+)?=", source), f"{module} sets no self.{name}"


def test_every_lorisnb_reference_of_the_manual_names_a_real_object():
    pages = sorted((ROOT / "docs").rglob("*.md"))
    wrong, seen = [], 0
    for page in pages:
        for role, title, target in MYST.findall(page.read_text()):
            name = (target or title).strip().removesuffix("()")
            if name.startswith("lorisnb"):
                seen += 1
                if not resolves(name):
                    wrong.append(f"{page.relative_to(ROOT)}: {{{role}}}`{name}`")
    assert seen > 10
    assert not wrong, "references to nothing:\n" + "\n".join(wrong)


@pytest.mark.parametrize(
    "name", ["lorisnb.plotting", "lorisnb.tools.evaluation.streaming.sweep_to_dataset", "lorisnb.core.nothing"]
)
def test_a_reference_to_nothing_is_found(name):
    assert not resolves(name)
    assert resolves("lorisnb.tools.figures.plotting") and resolves("lorisnb.core.spec.evalspec.EvalSpec.eps")
