"""Times files: one stamp (seconds) per line, as KITTI's ``times.txt``; errors name the times
file and its line."""

from __future__ import annotations

import os

import numpy as np

from lorisnb.errors import ParseError
from lorisnb.io.parsing.scanner import read_bytes, scan
from lorisnb.io.readers.registry import times_hint


def read_times(path: str | os.PathLike) -> np.ndarray:
    """Read a times file: one stamp (seconds) per line, ``#`` comments allowed."""
    return times_lines(path)[0]


TIMES_FILE = "a times file, one stamp in seconds per line"


def check_times(spath: str, t: np.ndarray, lines: np.ndarray, keep_all: bool) -> None:
    """ParseError naming the line of a times file's first stamp that is not finite or does not
    increase (``keep_all``: or repeat)."""
    bad = ~np.isfinite(t)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise ParseError(spath, int(lines[k]), f"stamp {float(t[k])} is not finite; expected {TIMES_FILE}")
    back = np.flatnonzero(np.diff(t) < 0 if keep_all else np.diff(t) <= 0)
    if back.size:
        k = int(back[0]) + 1
        kind = "repeats" if t[k] == t[k - 1] else "goes backwards"
        order = "non-decreasing" if keep_all else "increasing"
        raise ParseError(spath, int(lines[k]), f"stamp {float(t[k])!r} {kind} after {float(t[k - 1])!r}; expected "
                         f"{order} stamps, one per pose (KITTI's times.txt)")  # fmt: skip


def times_lines(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """:func:`read_times`' stamps and their 1-based lines."""
    spath = str(path)
    lines = scan(read_bytes(path, TIMES_FILE))
    rows = np.flatnonzero((lines.first >= 0) & (lines.first != ord("#")))  # neither blank nor comments
    ok = lines.ntok[rows] == 1
    if not ok.all():  # a pose file given as the times file: say so, not how to read it as poses
        i = rows[np.flatnonzero(~ok)[0]]
        text = lines.text(i)
        raise ParseError(spath, int(i) + 1, f"{text[:80]!r} has {int(lines.ntok[i])} fields; expected one stamp per "
                         f"line (a times file){times_hint(path, text)}")  # fmt: skip
    return lines.numbers(rows, spath, "one stamp in seconds per line"), rows + 1
