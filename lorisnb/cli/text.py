"""Tables as text for the terminal, from columns (no pandas needed): every command prints its
tables through :func:`format_table`."""

from __future__ import annotations

import math
import os
import re
import sys
import unicodedata
import warnings
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from lorisnb.tools.decisions.escape import clean  # the one escaping rule, for every output (re-exported here)

__all__ = ["MAX_ROWS", "clean", "display_width", "format_table", "frame_columns", "say", "warning_lines"]

MAX_ROWS = 500  # more rows: the first and last half of these, with a line saying how many were left out


def format_table(columns: Mapping[str, Sequence[Any] | np.ndarray], digits: int = 4, max_rows: int = MAX_ROWS) -> str:
    """Columns right-aligned under their names, two spaces apart; floats with ``digits``
    decimals (NaN as ``NaN``), integers, booleans and text as they are, control characters in
    names and cells escaped (:func:`clean`: a newline in a folder name keeps its row on one line)."""
    names = list(columns)
    n = len(next(iter(columns.values()))) if names else 0
    rows = list(range(n))
    if n > max_rows:
        rows = rows[: max_rows // 2] + [-1] + rows[n - max_rows // 2 :]
    cells = []
    for name in names:
        values = columns[name]
        cells.append([clean(name)] + ["..." if i < 0 else _cell(values[i], digits) for i in rows])
    shown = [[display_width(c) for c in col] for col in cells]
    widths = [max(col) for col in shown]
    lines = [
        "  ".join(" " * (w - cw[k]) + col[k] for col, cw, w in zip(cells, shown, widths, strict=True))
        for k in range(len(rows) + 1)
    ]
    if n > max_rows:
        lines.append(f"[{n} rows, {n - 2 * (max_rows // 2)} not shown]")
    return "\n".join(lines)


def display_width(text: str) -> int:
    """Columns ``text`` takes in a terminal: two for a wide or full-width character (CJK, by the
    Unicode East Asian Width property), none for a combining mark or a format character, one for
    others (``len`` counted a Chinese algorithm name at half its width and shifted its row)."""
    if text.isascii():
        return len(text)
    return sum(
        0 if unicodedata.combining(c) or unicodedata.category(c) in ("Mn", "Me", "Cf")
        else 2 if unicodedata.east_asian_width(c) in ("W", "F") else 1
        for c in text
    )  # fmt: skip


def _cell(value: Any, digits: int) -> str:
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value))
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        return "NaN" if math.isnan(value) else f"{float(value):.{digits}f}"
    return clean(value)


def frame_columns(df: Any) -> dict[str, np.ndarray]:
    """A DataFrame's columns as numpy arrays (for :func:`format_table`)."""
    return {str(c): df[c].to_numpy() for c in df.columns}


def say(line: object) -> None:
    """One message line on stderr (``error: ...``, ``warning: ...``, ``note: ...``), control characters
    escaped (:func:`clean`): a message quoting a file name, a label or a value read from a file
    (an escape sequence, a newline) stays one line, and the terminal interprets nothing in it."""
    print(clean(line), file=sys.stderr)


def _named(text: str, roots: Mapping[str, str | os.PathLike[str] | None]) -> str:
    """``text`` with each root's absolute path (as given made absolute, and links resolved) written by its
    name, ``{results}``, ``{data}`` (as run.json and the run's pages name them)."""
    forms: dict[str, str] = {}
    for name, folder in roots.items():
        if folder:
            for form in (os.path.abspath(folder), str(Path(folder).resolve())):
                if len(form) > 1:  # (not "/")
                    forms.setdefault(form.rstrip(os.sep), "{" + name + "}")
    for form in sorted(forms, key=len, reverse=True):  # a root inside another: the longer first
        whole = r"(?<![^\s'\"(=:,;])" + re.escape(form) + r"(?=[/\\\s;,:)'\"]|$)"  # a whole path, not part of one
        text = re.sub(whole, forms[form].replace("\\", "\\\\"), text)
    return text


@contextmanager
def warning_lines(roots: Mapping[str, str | os.PathLike[str] | None] | None = None) -> Iterator[None]:
    """Every warning issued while a command runs, a LorisWarning or another library's, printed as one
    ``warning: ...`` line (:func:`say`: control characters escaped), never Python's two lines with a
    source line of lorisnb; ``roots``: folders (name -> path) whose paths the line names ``{name}``."""
    from lorisnb.errors import LorisWarning

    show = warnings.showwarning

    def one_line(message: Warning | str, category: type[Warning], *_: Any, **__: Any) -> None:
        text = str(message) if issubclass(category, LorisWarning) else f"{category.__name__}: {message}"
        say(f"warning: {_named(text, roots or {})}")

    warnings.showwarning = one_line
    try:
        yield
    finally:
        warnings.showwarning = show
