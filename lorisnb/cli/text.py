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

from lorisnb.tools.decisions.escape import clean, message_line  # the escaping rules (clean re-exported here)

__all__ = [
    "MAX_ROWS",
    "clean",
    "display_width",
    "format_table",
    "frame_columns",
    "message_line",
    "say",
    "warning_lines",
]

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
    escaped (:func:`~lorisnb.tools.decisions.escape.message_line`: as :func:`clean`, but a backslash
    shown as itself): a message quoting a file name, a label or a value read from a file (an escape
    sequence, a newline) stays one line, and the terminal interprets nothing in it."""
    print(message_line(line), file=sys.stderr)


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


#: The readers' advice on a file plainly in another format (:meth:`lorisnb.io.readers.registry.Format.hint`):
#: it names the options of ``evaluate``, ``sweep``, ``compare`` and ``diff`` on pairs.
_FORMAT_ADVICE = re.compile(
    r"read it with --format (?P<fmt>[\w-]+) \(--gt-format (?P=fmt) for the ground truth; (?P<py>fmt=[^()]*? in Python)\)"
)


def format_advice(message: str, est: str | None, gt: str | None, gt_files: Sequence[str] = ()) -> str:
    """``message`` with the readers' advice on a file in another format said in the words of the
    command that prints it: ``est`` and ``gt`` are how it chooses the format of an estimate and of a
    ground truth (an option, ``--est-format``, or a manifest's key; ``{fmt}`` stands for the format;
    None: it has no such choice). The file is a ground truth when it is one of ``gt_files`` (as
    given or resolved), an estimate when ``gt_files`` are given and it is none of them, else both
    ways are said. ``consistency --gt-format openloris`` advised ``--format tum``, which it has not."""

    def said(m: re.Match[str]) -> str:
        fmt, py = m.group("fmt"), m.group("py")
        before = message[: m.start()]
        names = {str(g) for g in gt_files} | {str(Path(g).resolve()) for g in gt_files}
        is_gt = any(re.search(rf"(^|\s){re.escape(g)}(: |, line \d+: )", before) for g in names) if names else None
        if is_gt is None:  # which file it is: not told; both ways, the estimate's first
            ways = [w for w in (est and est.format(fmt=fmt), gt and f"{gt.format(fmt=fmt)} for the ground truth") if w]
            if not ways:
                return f"convert it ({py})"
            return (
                f"read it with {ways[0]}" + "".join(f" ({w}; {py})" for w in ways[1:]) + f" ({py})" * (len(ways) == 1)
            )
        way = gt if is_gt else est
        if way is None:  # no choice of this file's format here
            return f"convert it: this command has no option for the format of {'a ground truth' if is_gt else 'an estimate'} ({py})"
        return f"read it with {way.format(fmt=fmt)} ({py})"

    return _FORMAT_ADVICE.sub(said, message)
