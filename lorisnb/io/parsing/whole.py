"""The fast path of a plain numeric file: a public C parser (pyarrow's CSV reader, else pandas')
on pieces of its lines on threads, each piece's numbers copied (or converted) straight into the
arrays a reader keeps (:mod:`lorisnb.io.parsing.pieces`); a small file, without pyarrow and while
pandas is not imported, by numpy's C reader (importing pandas would cost more; pyarrow's reader
took a quarter of ``np.loadtxt``'s CPU on 10,000-pose TUM, KITTI and EuRoC files: 5-9 ms against
23-32 ms).

A file is plain when its lines after a leading block of ``#`` comments, blank lines and a header
line are numbers one separator apart (a space, or a comma), the same count on every line, and it
ends with one line end at most. Anything else (a comment or blank line further on, tabs or runs
of spaces, ``nan`` tokens, a line of another width, a byte order mark) makes the C parser refuse
the file or is seen in its first or last bytes: then :func:`read_whole` returns None and the
chunked reader (:func:`lorisnb.io.parsing.chunks.read_rows`) reads it, with the exact line of any error.
Both give the same numbers (the same C parser; it rounds as Python's ``float`` does).
"""

from __future__ import annotations

import io
import os
import stat
import sys
from collections.abc import Callable, Sequence

import numpy as np

from lorisnb.io.parsing.pieces import piece_rows, pyarrow_installed
from lorisnb.io.parsing.rows import Convert, Group, Part, Rows, line_dtype
from lorisnb.io.parsing.scanner import BOM, SNIFF_BYTES

#: Files up to this size are read here; larger ones by the chunked reader (a 3M-pose KITTI file,
#: 340 MB, took twice pandas' time there; a 10M-pose TUM pair of 850 MB files, read here, took
#: 16-18 s against 19-20 s in chunks, at the same 230 bytes per pose).
WHOLE_MAX_BYTES = 1 << 30
#: Without pyarrow and pandas imported, files up to this size are read by numpy (faster than importing pandas).
NUMPY_MAX_BYTES = 8 << 20
TAIL_BYTES = 4096
BLANK = b" \t\r\x0b\x0c"
#: The bytes of a plain file's numeric lines: numbers (``nan``, ``inf``, ``infinity`` too), separators, line ends.
PLAIN_BYTES = b"0123456789+-.eE ,\r\nnaifNAIFtyTY"


def read_whole(
    path: str | os.PathLike,
    widths: tuple[int, ...],
    layout: Callable[[int], Sequence[Group]],
    separators: bytes = b"",
    skip_lines: int = 0,
    progress: Callable[[int], object] | None = None,
    row_major: bool = True,
    convert: Convert | None = None,
) -> Rows | None:
    """The numeric lines of a plain regular file (see the module docstring) as a :class:`Rows`
    whose numbers are already copied into ``layout``'s column groups (row-major), or None when
    the file is not plain or too large (read it in chunks then). ``skip_lines``: the 1-based line
    of a header without ``#`` (0: none). ``row_major=False``: groups that are slices come as
    read-only views of the parser's numbers instead (no copy; pandas' are column-major), for a
    reader that keeps none of them. ``convert``: what the reader computes from the groups
    (:meth:`Rows.convert`), done on each piece of the file as it is parsed."""
    try:
        st = os.stat(path)
        if not stat.S_ISREG(st.st_mode) or not 0 < st.st_size <= WHOLE_MAX_BYTES:
            return None
        with open(path, "rb") as fh:
            head = fh.read(SNIFF_BYTES)
            fh.seek(max(st.st_size - TAIL_BYTES, 0))
            tail = fh.read()
    except (OSError, TypeError, ValueError):
        return None
    plan = _plan(head, tail, widths, separators, skip_lines)
    if plan is None:
        return None
    skip, ntok, sep = plan
    groups = tuple(layout(ntok))
    outs: Sequence[Part]
    if not pandas_loaded() and not pyarrow_installed() and st.st_size <= NUMPY_MAX_BYTES:  # no pandas to import
        values = _numpy_rows(path, sep, skip, ntok)
        if values is None:
            return None
        n = len(values)
        outs = [
            np.take(values, g, axis=1) if not isinstance(g, slice) else
            np.ascontiguousarray(values[:, g]) if row_major else values[:, g]
            for g in groups
        ]  # fmt: skip
    else:
        parsed = piece_rows(path, sep, _line_start(head, skip), st.st_size, ntok, groups, convert, row_major)
        if parsed is None:
            return None
        n, outs = parsed
        if convert is not None:  # what it gave
            return _rows(n, ntok, skip, (), [], (convert, list(outs)), progress, st.st_size)
    return _rows(n, ntok, skip, groups, outs, None, progress, st.st_size)


def _rows(
    n: int, ntok: int, skip: int, groups: tuple[Group, ...], outs: Sequence[Part],
    converted: tuple[Convert, list[Part]] | None, progress: Callable[[int], object] | None, size: int,
) -> Rows:  # fmt: skip
    """The :class:`Rows` of ``n`` lines of ``ntok`` numbers after ``skip`` lines."""
    if progress is not None:
        progress(size)
    last = skip + n
    lines = np.arange(skip + 1, last + 1, dtype=line_dtype(last))
    filled = (groups, outs) if converted is None else None
    return Rows([], np.full(n, ntok, np.int8), lines, [], n, filled=filled, converted=converted)


def pandas_loaded() -> bool:
    """Whether pandas is imported already (then using it costs nothing more)."""
    return "pandas" in sys.modules


def _numpy_rows(path: str | os.PathLike, sep: str, skip: int, ntok: int) -> np.ndarray | None:
    """(n, ntok) numbers of a small plain file by numpy's C reader (``np.loadtxt``, which rounds
    as Python's ``float`` does), or None when it is not plain after all (it skips blank lines,
    which the line count then shows)."""
    try:
        with open(path, "rb") as fh:
            raw = fh.read()
        body = raw.split(b"\n", skip)[-1] if skip else raw
        if body.translate(None, PLAIN_BYTES) or body.count(b"\r") != body.count(b"\r\n"):  # numpy strips bytes
            return None  # Python's float refuses ('0.5\x1c') and ends a line at a lone CR: not plain after all
        values = np.loadtxt(io.BytesIO(raw), dtype=np.float64, delimiter=sep, comments=None, skiprows=skip, ndmin=2)
    except (ValueError, OSError, UnicodeDecodeError):
        return None
    total = raw.count(b"\n") + (0 if raw.endswith(b"\n") else 1)
    return values if values.shape == (total - skip, ntok) else None


def _line_start(head: bytes, skip: int) -> int:
    """The byte offset of line ``skip + 1`` (the lines skipped are in the file's first bytes)."""
    at = 0
    for _ in range(skip):
        at = head.index(b"\n", at) + 1
    return at


def _plan(
    head: bytes, tail: bytes, widths: tuple[int, ...], separators: bytes, skip_lines: int
) -> tuple[int, int, str] | None:
    """From a file's first and last bytes: the lines to skip (leading comments, blank lines, the
    header), the tokens per line and the separator, or None when the file is not plain."""
    if head.startswith(BOM) or b"\0" in head or b"\0" in tail:
        return None
    body = tail[:-1] if tail.endswith(b"\n") else tail
    body = body[:-1] if body.endswith(b"\r") else body
    if not body or body[-1:] in BLANK + b"\n":  # blank lines or spaces at the end
        return None
    skip = 0
    for k, line in enumerate(head.split(b"\n")[:-1], start=1):  # whole lines of the head
        text = line.rstrip(b"\r")
        stripped = text.strip(BLANK)
        if not stripped or stripped.startswith(b"#") or k == skip_lines:
            skip = k
            continue
        if skip_lines > k:
            return None
        seps = [s for s in (b" ", *(bytes([c]) for c in separators)) if s in text]
        if len(seps) != 1 or text != stripped or any(c in text for c in b"\t\x0b\x0c\r"):
            return None
        sep = seps[0]
        tokens = text.split(sep)
        if b"" in tokens or len(tokens) not in widths:
            return None
        return skip, len(tokens), sep.decode()
    return None
