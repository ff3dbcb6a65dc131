"""Leaner imports in lorisnb's own processes: an optional module hidden while one other package
imports itself, where that package would import it only for what lorisnb never uses and the
import alone costs a large share of a run. The hidden module stays importable afterwards, and
nothing changes in a process that has already imported the package (a Python session).

- pandas without pyarrow (:func:`pandas_without_pyarrow`): pandas imports pyarrow whenever it is
  installed (lorisnb's ``[parquet]`` extra), about a fifth of a small evaluation's time and 60 MB;
  without it pandas keeps strings as Python objects (the same tables, the same output).
- jsonschema without ``rfc3987_syntax`` (:func:`jsonschema_without_iri_grammars`): nbformat, and
  so papermill and nbconvert, import jsonschema, whose format module imports ``rfc3987_syntax``
  where installed (jsonschema's ``format-nongpl`` extra, which JupyterLab's packages ask for);
  that package compiles 38 grammars at import, about 2 s of CPU (jsonschema issue #1392), only
  to check strings of format ``iri``, which no notebook schema uses and which jsonschema checks
  only when asked to check formats. A report pays it in every process that runs notebooks.
"""

from __future__ import annotations

import importlib.util
import sys
from typing import Any


def hide_while_importing(package: str, hidden: str) -> None:
    """Have ``package``, when next imported, import as if ``hidden`` were not installed. Nothing
    is imported here; nothing happens if ``package`` is already imported or already set so."""
    if package in sys.modules or any(
        isinstance(f, _Hiding) and f.package == package and f.hidden == hidden for f in sys.meta_path
    ):
        return
    sys.meta_path.insert(0, _Hiding(package, hidden))


def pandas_without_pyarrow() -> None:
    """pandas, if imported at all, imported without pyarrow (see the module docstring)."""
    hide_while_importing("pandas", "pyarrow")


def jsonschema_without_iri_grammars() -> None:
    """jsonschema, if imported at all, imported without ``rfc3987_syntax`` (see the module docstring)."""
    hide_while_importing("jsonschema._format", "rfc3987_syntax")


class _Hiding:
    """An import finder (``sys.meta_path``): finds ``package`` (once) with a loader that hides
    ``hidden`` while the package's own import runs."""

    def __init__(self, package: str, hidden: str) -> None:
        self.package, self.hidden = package, hidden

    def find_spec(self, name: str, path: Any = None, target: Any = None) -> Any:
        if name != self.package:
            return None
        sys.meta_path.remove(self)
        spec = importlib.util.find_spec(name)
        if spec is not None and spec.loader is not None:
            spec.loader = _HidingLoader(spec.loader, self.hidden)  # type: ignore[assignment]  # the loader protocol
        return spec


class _HidingLoader:
    """A package's own loader, with ``hidden`` unimportable while it runs (``importlib``'s loader protocol)."""

    def __init__(self, real: Any, hidden: str) -> None:
        self.real, self.hidden = real, hidden

    def create_module(self, spec: Any) -> Any:
        return self.real.create_module(spec)

    def exec_module(self, module: Any) -> None:
        before = sys.modules.get(self.hidden, _ABSENT)
        sys.modules[self.hidden] = None  # type: ignore[assignment]  # importing it raises ImportError
        try:
            self.real.exec_module(module)
        finally:
            if before is _ABSENT:
                del sys.modules[self.hidden]
            else:
                sys.modules[self.hidden] = before  # type: ignore[assignment]

    def __getattr__(self, name: str) -> Any:  # resources and the rest: the real loader's
        return getattr(self.real, name)


_ABSENT = object()
