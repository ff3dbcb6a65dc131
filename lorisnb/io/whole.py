"""The fast path of a plain numeric file: pandas' C parser over the whole file in one call (its
fastest exact parse), the numbers copied once into the arrays a reader keeps; a large
file by the same parser on ranges of its lines on threads, each range copied straight into those
arrays (as fast, in a third of the memory); a small file, while pandas is not imported, by
numpy's C reader (importing pandas would cost more).

A file is plain when its lines after a leading block of ``#`` comments, blank lines and a header
line are numbers one separator apart (a space, or a comma), the same count on every line, and it
ends with one line end at most. Anything else (a comment or blank line further on, tabs or runs
of spaces, ``nan`` tokens, a line of another width, a byte order mark) makes the C parser refuse
the file or is seen in its first or last bytes: then :func:`read_whole` returns None and the
chunked reader (:func:`lorisnb.io.chunks.read_rows`) reads it, with the exact line of any error.
Both give the same numbers (the same C parser; it rounds as Python's ``float`` does).
"""

from __future__ import annotations

import csv
import io
import os
import stat
import sys
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np

from .ranges import GIVE_BACK_BYTES, PARSE_THREADS, give_back_memory, line_ranges
from .rows import Convert, Group, Part, Rows, copy_rows, group_columns, line_dtype, rows_of
from .scanner import BOM, SNIFF_BYTES

#: Files up to this size are read in one call; larger ones in chunks, in bounded memory (the C
#: parser holds about three times the numbers while it reads a whole file).
WHOLE_MAX_BYTES = 256 << 20
#: Without pandas imported, files up to this size are read by numpy (faster than importing pandas).
NUMPY_MAX_BYTES = 8 << 20
#: Files from this size whose numbers are copied into row-major groups (or converted) are parsed
#: in ranges of whole lines on threads, each range's numbers copied straight into the reader's
#: arrays (:func:`_ranged_rows`): about as fast as pandas' own read of the whole file,
#: in a third of its memory (it maps the file and holds its numbers twice before the copy: about
#: 210 MiB for an 85 MB file of a million TUM poses, against about 80 MiB), and a matrix file's
#: quaternions computed on the threads as the ranges are read. Below this size the threads' chunk
#: buffers (about 20 MB each) would cost more memory than pandas' one call.
RANGED_MIN_BYTES = 32 << 20
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
    (:meth:`Rows.convert`), done on each range of a file read on threads, as it is read."""
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
    if not pandas_loaded() and st.st_size <= NUMPY_MAX_BYTES:  # no pandas to import for a small file
        values = _numpy_rows(path, sep, skip, ntok)
        if values is None:
            return None
        n = len(values)
        outs = [
            np.take(values, g, axis=1) if not isinstance(g, slice) else
            np.ascontiguousarray(values[:, g]) if row_major else values[:, g]
            for g in groups
        ]  # fmt: skip
    elif (row_major or convert is not None) and st.st_size >= RANGED_MIN_BYTES and PARSE_THREADS > 1:
        parsed = _ranged_rows(path, sep, _line_start(head, skip), st.st_size, ntok, groups, convert)
        if parsed is None:
            return None
        n, outs = parsed
        if convert is not None:
            return _rows(n, ntok, skip, (), [], (convert, outs), progress, st.st_size)
    else:
        whole = _pandas_rows(path, sep, skip, ntok, groups, row_major)
        if whole is None:
            return None
        n, outs = whole
    return _rows(n, ntok, skip, groups, outs, None, progress, st.st_size)


def _rows(
    n: int, ntok: int, skip: int, groups: tuple[Group, ...], outs: Sequence[Part],
    converted: tuple[Convert, list[np.ndarray]] | None, progress: Callable[[int], object] | None, size: int,
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


def _pandas_rows(
    path: str | os.PathLike, sep: str, skip: int, ntok: int, groups: tuple[Group, ...], row_major: bool = True
) -> tuple[int, list[Part]] | None:
    """The number of rows and their numbers copied into ``groups`` (row-major) by pandas' C
    parser in one call, or None when the file is not plain after all. ``row_major=False``: groups
    that are slices are the parser's own columns (a :data:`~lorisnb.io.rows.Part`), not copies."""
    import pandas as pd  # here: a small file read by numpy needs no pandas

    try:
        frame = pd.read_csv(path, **_c_options(sep, skip))
    except _parser_errors():
        return None  # not plain after all: the chunked reader finds what and where
    if frame.shape[1] != ntok or not all(dt == np.float64 for dt in frame.dtypes):
        return None
    columns = _columns(frame)
    del frame
    n = len(columns[0])
    copy = row_major or not all(isinstance(g, slice) for g in groups)  # else the parser's own columns
    outs: list[Part] = [rows_of(group_columns(columns, g)) if copy else group_columns(columns, g) for g in groups]
    del columns
    if os.stat(path).st_size >= GIVE_BACK_BYTES:
        give_back_memory()  # the parser's buffers of a large file: not kept as the process's memory
    return n, outs


def _line_start(head: bytes, skip: int) -> int:
    """The byte offset of line ``skip + 1`` (the lines skipped are in the file's first bytes)."""
    at = 0
    for _ in range(skip):
        at = head.index(b"\n", at) + 1
    return at


def _ranged_rows(
    path: str | os.PathLike, sep: str, start: int, size: int, ntok: int, groups: tuple[Group, ...],
    convert: Convert | None = None,
) -> tuple[int, list[np.ndarray]] | None:  # fmt: skip
    """:func:`_pandas_rows` of a large file (the same C parser and options), in bounded memory:
    the lines from byte ``start`` are shared among :data:`PARSE_THREADS` threads, one range of
    whole lines each, which its thread reads with one parser in chunks of :data:`CHUNK_ROWS` rows
    (as fast as one call on the file), copying each chunk into row-major arrays of the groups
    (``convert``: of what it computes from them) at its rows: a range starts after the lines of
    the ranges before it, each counted by the thread of the range after it while its own thread
    reads it. The arrays hold as many rows as the file could (each line at least a digit and a
    separator per number) and are returned trimmed (views; pages past the rows are never touched,
    so not resident). None when a range is not plain numbers after all."""
    fd = os.open(path, os.O_RDONLY)
    try:
        ranges = _shares(fd, start, size, PARSE_THREADS)
        if any(overlong for _, _, overlong in ranges):
            return None
        capacity = (size - start) // (2 * ntok) + 1
        outs: list[np.ndarray] = []
        counts: list[int | None] = [None] * len(ranges)
        failed = False
        turn = threading.Condition()

        def count_then_parse(i: int) -> int | None:
            nonlocal failed
            lo, hi, _ = ranges[i]
            if i:  # the lines of the range before, counted while its own thread reads them
                try:
                    lines = _line_count(fd, *ranges[i - 1][:2])
                except BaseException:
                    with turn:  # no range waits for this count in vain
                        failed = True
                        turn.notify_all()
                    raise
                with turn:
                    counts[i - 1] = lines
                    turn.notify_all()
                    turn.wait_for(lambda: failed or all(c is not None for c in counts[:i]))
            at = sum(c for c in counts[:i] if c is not None)
            try:
                end = _parse_range(fd, lo, hi, sep, ntok, groups, convert, outs, at, capacity, turn)
            except BaseException:
                failed = True
                raise
            with turn:  # the lines read are the lines counted (the last range's: nobody counts them)
                turn.wait_for(lambda: failed or i == len(ranges) - 1 or counts[i] is not None)
                if end is None or (i < len(ranges) - 1 and end - at != counts[i]):
                    failed = True
                    turn.notify_all()
            return None if failed else end

        with ThreadPoolExecutor(max_workers=len(ranges)) as pool:
            ends = list(pool.map(count_then_parse, range(len(ranges))))
    finally:
        os.close(fd)
    if failed or not ends or ends[-1] is None:
        return None
    if size >= GIVE_BACK_BYTES:
        give_back_memory()  # the parser's buffers, freed on the threads
    return ends[-1], [out[: ends[-1]] for out in outs]


#: A thread counts the lines of the range before its own at about this many times the speed it
#: parses them: the first range, whose thread counts none, is that much longer than the others.
COUNT_SPEED = 13.0


def _shares(fd: int, start: int, size: int, threads: int) -> list[tuple[int, int, bool]]:
    """Ranges of whole lines from byte ``start``, one per thread, all ending together: the first
    (no lines to count before it) longer by :data:`COUNT_SPEED`'s share (see :func:`line_ranges`)."""
    total = size - start
    first = int(total * (1 + 1 / COUNT_SPEED) / (threads + 1 / COUNT_SPEED)) + 1
    head = next(line_ranges(fd, start, size, first))
    if threads == 1 or head[1] >= size or head[2]:
        return [head]
    return [head, *line_ranges(fd, head[1], size, -(-(size - head[1]) // (threads - 1)))]


#: Rows a range's parser reads at a time (about 5 MB of a TUM file's text).
CHUNK_ROWS = 1 << 16


def _parse_range(
    fd: int, lo: int, hi: int, sep: str, ntok: int, groups: tuple[Group, ...], convert: Convert | None,
    outs: list[np.ndarray], at: int, capacity: int, turn: threading.Condition,
) -> int | None:  # fmt: skip
    """Bytes ``[lo, hi)`` of a file parsed in chunks of :data:`CHUNK_ROWS` rows, each copied into
    ``outs`` from row ``at`` (the arrays made, under ``turn``, by the first chunk of any range):
    the row after the last, or None when they are not plain numbers."""
    import pandas as pd

    text = io.BufferedReader(_Span(fd, lo, hi), 1 << 20)
    try:
        with pd.read_csv(text, chunksize=CHUNK_ROWS, **_c_options(sep, 0)) as chunks:
            for frame in chunks:
                if frame.shape[1] != ntok or not all(dt == np.float64 for dt in frame.dtypes):
                    return None
                columns = _columns(frame)
                del frame
                parts: Sequence[Part] = [group_columns(columns, g) for g in groups]
                if convert is not None:
                    parts = convert(*parts)
                m = len(columns[0])
                if at + m > capacity:
                    return None
                with turn:
                    if not outs:
                        outs.extend(
                            np.empty((capacity, len(p))) if isinstance(p, list) else np.empty((capacity, *p.shape[1:]), p.dtype)
                            for p in parts
                        )  # fmt: skip
                for part, out in zip(parts, outs, strict=True):
                    if isinstance(part, list):
                        copy_rows(part, out[at : at + m])
                    else:
                        out[at : at + m] = part
                at += m
    except _parser_errors():
        return None
    return at


class _Span(io.RawIOBase):
    """Bytes ``[lo, hi)`` of an open file as a file of their own (``os.pread``: the threads share
    the descriptor, not a position)."""

    def __init__(self, fd: int, lo: int, hi: int) -> None:
        super().__init__()
        self.fd, self.at, self.hi = fd, lo, hi

    def readable(self) -> bool:
        return True

    def readinto(self, buffer: Any) -> int:
        n = min(len(buffer), self.hi - self.at)
        if n <= 0:
            return 0
        data = os.pread(self.fd, n, self.at)
        buffer[: len(data)] = data
        self.at += len(data)
        return len(data)


def _line_count(fd: int, lo: int, hi: int, piece: int = 1 << 20) -> int:
    """Line feeds in bytes ``[lo, hi)`` of a file, read a megabyte at a time into one buffer."""
    buffer = bytearray(piece)
    found = np.empty(piece, bool)
    n = 0
    for a in range(lo, hi, piece):
        got = os.preadv(fd, [memoryview(buffer)[: min(piece, hi - a)]], a)
        n += int(np.count_nonzero(np.equal(np.frombuffer(buffer, np.uint8, got), 10, out=found[:got])))
    return n


def _c_options(sep: str, skip: int) -> dict:
    """pandas' C parser as lorisnb reads a plain file: numbers only, one separator, ``\\n`` lines."""
    return dict(
        sep=sep, header=None, skiprows=skip, dtype=np.float64, quoting=csv.QUOTE_NONE, na_filter=False,
        engine="c", index_col=False, skip_blank_lines=False, lineterminator="\n",
    )  # fmt: skip


def _parser_errors() -> tuple[type[BaseException], ...]:
    """What pandas' C parser raises for text that is not plain numbers."""
    from pandas import errors

    return ValueError, OverflowError, UnicodeDecodeError, errors.ParserError, errors.EmptyDataError


def _columns(frame: Any) -> list[np.ndarray]:
    """A parsed frame's columns as pandas holds them (read-only views: no copy)."""
    return [c.to_numpy() for _, c in frame.items()]


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
