"""A plain file parsed by pandas' C parser in pieces of whole lines on threads, each piece's
numbers grouped (or converted) on its thread and copied into the reader's arrays in file order.

Where the installed pandas has it (3.1 and later), each piece is tokenised from its bytes with no
GIL held (``TextReader.load_buffer``: the buffer route of pandas' own threaded ``read_csv``), so
the pieces are parsed side by side on every core (what is computed from them too, as far as
numpy's operations hand the GIL back and forth); otherwise each piece is read by
``pandas.read_csv`` on its bytes. Both give the numbers of one ``read_csv`` call on the whole
file: the same C tokenizer and float conversion, with the same options (:func:`c_options`). A
piece whose rows are not its lines (a line the parser reads otherwise) makes the whole read
return None: the caller's chunked reader then names the line.

The buffer route is pandas' private API (``engine._reader``), kept for the large-file reading rows
of ``make bench`` ("read TUM/KITTI/EuRoC 1M" within 1.2x of pandas: 0.90x, 1.04x, 0.96x in the
guide's last run, docs/guide/many-files.md); replacing it by a public reader (pyarrow.csv, measured side by side on the
bundled workload and the large files) is issue 47's open work. A pandas without it takes the
public ``read_csv`` route above, with the same numbers.
"""

from __future__ import annotations

import csv
import functools
import io
import os
import threading
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor, wait
from typing import Any

import numpy as np

from lorisnb.io.parsing.ranges import GIVE_BACK_BYTES, PARSE_THREADS, give_back_memory, line_ranges, newlines
from lorisnb.io.parsing.rows import Convert, Group, Part, copy_rows, group_columns, rows_of

#: Bytes of a piece at most (as pandas' own threaded read): numpy's work on a piece's rows runs in
#: few operations on long arrays (on 256 KB pieces a million KITTI poses took twice as long).
PIECE_BYTES = 4 << 20
#: A thread's parser is kept for the next file when its pieces were at most this long (it keeps
#: buffers of about four times a piece).
KEEP_PIECE_BYTES = 1 << 20
#: Files from this size are parsed in at least :data:`PARSE_THREADS` pieces side by side.
SPLIT_MIN_BYTES = 128 << 10
#: Pieces parsed ahead of the first not yet placed, per thread (memory holds about this many).
AHEAD = 2


def c_options(sep: str) -> dict:
    """pandas' C parser as lorisnb reads a plain file: numbers only, one separator, ``\\n`` lines."""
    return dict(
        sep=sep, header=None, dtype=np.float64, quoting=csv.QUOTE_NONE, na_filter=False, engine="c",
        index_col=False, skip_blank_lines=False, lineterminator="\n",
    )  # fmt: skip


def parser_errors() -> tuple[type[BaseException], ...]:
    """What pandas' C parser raises for text that is not plain numbers."""
    from pandas import errors

    return ValueError, OverflowError, UnicodeDecodeError, errors.ParserError, errors.EmptyDataError


class _Parser:
    """One thread's parser of pieces of ``ntok`` numbers per line: pandas' buffer route where
    ``buffers`` (one reader kept for every piece), else ``read_csv`` on each piece's bytes."""

    def __init__(self, sep: str, ntok: int, buffers: bool) -> None:
        self.sep, self.ntok, self.reader = sep, ntok, None
        if buffers:
            self.reader = self._reader()

    def _reader(self) -> Any:
        """A pandas reader of buffers of lines of ``ntok`` numbers."""
        import pandas as pd

        options = c_options(self.sep) | {"names": list(range(self.ntok)), "low_memory": False}
        reader = pd.read_csv(io.BytesIO(b""), iterator=True, **options)
        reader._engine._reader.trim_after_read = False  # its buffers kept for the next piece
        return reader

    def columns(self, data: bytes) -> list[np.ndarray] | None:
        """The ``ntok`` float64 columns of ``data``'s lines (whole lines), or None when they are not
        plain numbers, one row per line."""
        try:
            if self.reader is not None:
                engine = self.reader._engine
                engine._reader.load_buffer(data)
                engine._first_chunk = True  # a reused reader reads a new piece from its start
                _, _, by_name = engine.read()
                columns = [by_name[k] for k in range(self.ntok)]
            else:
                import pandas as pd

                frame = pd.read_csv(io.BytesIO(data), **c_options(self.sep))
                columns = [c.to_numpy() for _, c in frame.items()]
        except parser_errors():
            columns = []
        rows = newlines(data) + (not data.endswith(b"\n"))
        if len(columns) == self.ntok and all(c.dtype == np.float64 and len(c) == rows for c in columns):
            return columns
        if self.reader is not None:  # a reader that refused text refuses everything after it: a new one
            self.reader = self._reader()
        return None


#: Each parsing thread's parser, kept for its next piece (a new reader costs about half as much
#: again on its first megabyte as one that has read before); let go after a file of pieces longer
#: than :data:`KEEP_PIECE_BYTES`.
_parsers: dict[int, _Parser] = {}


def _parser(sep: str, ntok: int) -> _Parser:
    """This parsing thread's parser of lines of ``ntok`` numbers (see :data:`_parsers`)."""
    buffers, me = buffers_work(), threading.get_ident()
    got = _parsers.get(me)
    if got is None or (got.sep, got.ntok, got.reader is not None) != (sep, ntok, buffers):
        got = _parsers[me] = _Parser(sep, ntok, buffers)
    return got


_pool: ThreadPoolExecutor | None = None
_pool_lock = threading.Lock()


def _threads() -> ThreadPoolExecutor:
    """The threads that parse pieces, started once (each keeps its parser)."""
    global _pool
    with _pool_lock:  # one pool, whichever threads read files at once
        if _pool is None:
            _pool = ThreadPoolExecutor(max_workers=PARSE_THREADS, thread_name_prefix="lorisnb-pieces")
        return _pool


def _forget_threads() -> None:
    """In a forked child: the parent's threads are not there (new ones start when needed)."""
    global _pool
    _pool = None
    _parsers.clear()


os.register_at_fork(after_in_child=_forget_threads)


@functools.cache
def buffers_work() -> bool:
    """Whether the installed pandas parses a buffer as its threaded reader does (checked once, on a
    two-line text): else each piece is read by ``read_csv``."""
    try:
        got = _Parser(" ", 2, True).columns(b"1 2.5\n3 4\n")
    except Exception:  # noqa: BLE001 - another pandas (no buffer route, or other internals)
        return False
    return got is not None and [c.tolist() for c in got] == [[1.0, 3.0], [2.5, 4.0]]


def piece_rows(
    path: str | os.PathLike, sep: str, start: int, size: int, ntok: int, groups: tuple[Group, ...],
    convert: Convert | None = None, row_major: bool = True,
) -> tuple[int, list[Part]] | None:  # fmt: skip
    """The rows of a plain file's lines from byte ``start`` (``size`` bytes in all) of ``ntok``
    numbers each: their count and the row-major arrays of ``groups`` (``convert``: what it gives
    on them, computed piece by piece), or None when they are not plain numbers. A file read in one
    piece with ``row_major=False`` and no ``convert`` gives the parser's own columns of groups
    that are slices (read-only, no copy). Arrays of several pieces hold as many rows as the file
    could (each line at least a digit and a separator per number) and are trimmed views (pages
    past the rows are never touched, so not resident)."""
    total = size - start
    count = -(-total // PIECE_BYTES)
    if total >= SPLIT_MIN_BYTES:  # as many pieces on each thread
        count = -(-count // PARSE_THREADS) * PARSE_THREADS
    fd = os.open(path, os.O_RDONLY)
    try:
        pieces = list(line_ranges(fd, start, size, -(-total // count)))
        if any(overlong for _, _, overlong in pieces):
            return None
        if len(pieces) == 1:
            return _one_piece(fd, *pieces[0][:2], sep, ntok, groups, convert, row_major)
        keep = total <= count * KEEP_PIECE_BYTES
        got = _on_threads(
            fd, [(lo, hi) for lo, hi, _ in pieces], sep, ntok, groups, convert, total // (2 * ntok) + 1, keep
        )
    finally:
        os.close(fd)
    if not keep:
        _parsers.clear()  # their buffers (up to 16 MB each), not kept through what the caller does next
    if size >= GIVE_BACK_BYTES:
        give_back_memory()
    return got


def _arrays(parts: Sequence[Part], capacity: int) -> list[np.ndarray]:
    """The arrays of a file's rows, ``capacity`` rows each (as many as it could hold; pages past
    the rows read are never written, so never resident), shaped as a piece's ``parts``."""
    return [
        np.empty((capacity, len(p))) if isinstance(p, list) else np.empty((capacity, *p.shape[1:]), p.dtype)
        for p in parts
    ]


def _read(fd: int, lo: int, hi: int) -> bytes | None:
    """Bytes ``[lo, hi)`` of a file (None when it is shorter now)."""
    data = os.pread(fd, hi - lo, lo)
    return data if len(data) == hi - lo else None


def _one_piece(
    fd: int, lo: int, hi: int, sep: str, ntok: int, groups: tuple[Group, ...], convert: Convert | None,
    row_major: bool,
) -> tuple[int, list[Part]] | None:  # fmt: skip
    """:func:`piece_rows` of a file read in one piece, on the calling thread."""
    data = _read(fd, lo, hi)
    columns = None if data is None else _Parser(sep, ntok, buffers_work()).columns(data)  # a small file
    if columns is None:
        return None
    del data
    parts: Sequence[Part] = [group_columns(columns, g) for g in groups]
    if convert is not None:
        return len(columns[0]), list(convert(*parts))
    keep = not row_major and all(isinstance(g, slice) for g in groups)
    return len(columns[0]), [p if keep else rows_of(p) if isinstance(p, list) else p for p in parts]


def _on_threads(
    fd: int, pieces: list[tuple[int, int]], sep: str, ntok: int, groups: tuple[Group, ...],
    convert: Convert | None, capacity: int, keep: bool = True,
) -> tuple[int, list[Part]] | None:  # fmt: skip
    """:func:`piece_rows` of several pieces on :data:`PARSE_THREADS` threads: each takes the next
    piece in file order, parses (and converts) it, and copies every piece whose rows' place is now
    known (all pieces before it done) into the arrays, made by the first such copy. Unless
    ``keep``, each thread lets its parser go when it has no piece left (its buffers freed there,
    while the other threads still parse, not after the file on the caller's thread)."""
    turn = threading.Condition()
    state: dict[str, Any] = {"taken": 0, "placed": 0, "at": 0, "failed": False}
    done: dict[int, tuple[int, Sequence[Part]]] = {}
    outs: list[np.ndarray] = []
    threads = min(PARSE_THREADS, len(pieces))

    def fail() -> None:
        with turn:
            state["failed"] = True
            turn.notify_all()

    def work() -> None:
        parser = _parser(sep, ntok)
        while True:
            with turn:
                turn.wait_for(lambda: state["failed"] or len(done) < AHEAD * threads)
                if state["failed"] or state["taken"] == len(pieces):
                    if not keep:
                        _parsers.pop(threading.get_ident(), None)
                    return
                i = state["taken"]
                state["taken"] += 1
            try:
                data = _read(fd, *pieces[i])
                columns = None if data is None else parser.columns(data)
                del data
                if columns is None:
                    fail()
                    return
                parts: Sequence[Part] = [group_columns(columns, g) for g in groups]
                if convert is not None:
                    parts = convert(*parts)
                placed = _place(i, len(columns[0]), parts)
                for at, m, ready in placed:
                    for part, out in zip(ready, outs, strict=True):
                        if isinstance(part, list):
                            copy_rows(part, out[at : at + m])
                        else:
                            out[at : at + m] = part
            except BaseException:
                fail()
                raise

    def _place(i: int, m: int, parts: Sequence[Part]) -> list[tuple[int, int, Sequence[Part]]]:
        """Piece ``i``'s rows noted; the pieces now placed (row, rows, numbers), in file order."""
        placed = []
        with turn:
            done[i] = (m, parts)
            while state["placed"] in done:
                rows, ready = done.pop(state["placed"])
                placed.append((state["at"], rows, ready))
                state["at"] += rows
                state["placed"] += 1
            if state["at"] > capacity:
                state["failed"] = True
                placed = []
            elif placed and not outs:
                try:
                    outs.extend(_arrays(placed[0][2], capacity))
                except MemoryError:  # the system refuses to reserve that much: the chunked reader then
                    state["failed"] = True
                    placed = []
            turn.notify_all()
        return placed

    pool = _threads()
    futures = [pool.submit(work) for _ in range(threads)]
    try:
        for future in futures:
            future.result()
    except BaseException:  # an interrupt here, or a thread's error: the others stop at their next piece
        fail()
        wait(futures)  # and none reads the file after the caller closes it
        raise
    if state["failed"]:
        return None
    n = state["at"]
    return n, [out[:n] for out in outs]
