"""Lazy packages (PEP 562): a package's public names are imported from their modules when first
used, so that ``import lorisnb`` or the command line's ``--help`` does not import pandas, scipy or
every module of the package.

A package lists its names once, as ordinary imports under ``if TYPE_CHECKING:`` (what type
checkers and editors read); :func:`attach` reads that block from the package's source and returns
the module's ``__getattr__`` and ``__dir__``.
"""

from __future__ import annotations

import ast
import importlib
import sys
from collections.abc import Callable
from types import ModuleType
from typing import Any


def attach(package: str) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` for the package ``package`` (its ``__name__``): each name
    imported under its ``if TYPE_CHECKING:`` block is imported from its module on first use (and
    kept in the package), and each submodule on first attribute access. A name that is also a
    submodule's (``lorisnb.core.lifelong.sweep``, the function, and ``lorisnb/core/lifelong/sweep.py``) stays the
    name when the submodule is imported, as with eager imports."""
    module = sys.modules[package]
    source = module.__spec__.loader.get_source(package)  # type: ignore[union-attr]
    where: dict[str, tuple[str, str]] = {}  # name -> (module, name in that module)
    for node in ast.parse(source).body:
        if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING":
            for imp in node.body:
                if isinstance(imp, ast.ImportFrom):
                    for alias in imp.names:
                        where[alias.asname or alias.name] = ("." * imp.level + (imp.module or ""), alias.name)

    def __getattr__(name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        if name in where:
            source_module, attr = where[name]
            value = getattr(importlib.import_module(source_module, package), attr)
        else:
            try:
                value = importlib.import_module(f"{package}.{name}")
            except ModuleNotFoundError as exc:
                if exc.name != f"{package}.{name}":
                    raise
                raise AttributeError(f"module {package!r} has no attribute {name!r}") from None
        setattr(module, name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(module)) | set(where))

    class Package(ModuleType):
        def __setattr__(self, name: str, value: Any) -> None:
            if isinstance(value, ModuleType) and name in where:  # the import system binding a submodule
                source_module, attr = where[name]
                value = getattr(importlib.import_module(source_module, package), attr)
            super().__setattr__(name, value)

    module.__class__ = Package

    return __getattr__, __dir__
