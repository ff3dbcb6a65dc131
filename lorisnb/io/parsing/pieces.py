"""A plain file parsed in pieces of whole lines on threads, each piece's numbers grouped (or
converted) on its thread and copied into the reader's arrays in file order.

Each piece is parsed by a public reader: ``pyarrow.csv.read_csv`` on its bytes where pyarrow is
installed (it holds no GIL while it parses, so the pieces are parsed side by side on every core),
else ``pandas.read_csv`` (C engine) on its bytes. Both round as Python's ``float`` does, so both
give the numbers of the exact byte scanner. A piece whose rows are not its lines (a line the
parser reads otherwise) makes the whole read return None: the caller's chunked reader then names
the line. (The route through pandas' private parser internals that this replaced is gone: issue
47; the figures of both are in ``make bench``'s reading rows.)

The pieces' own threads (rather than pyarrow's threaded read of the whole file) keep memory at
the arrays a reader keeps: each piece is converted and copied into place as soon as it is parsed,
while a whole-file table would hold every column once more. Measured on 1M-pose files (2 shared
cores, both in one process, in alternation, medians): lorisnb's whole read (pieces, grouping,
KITTI's rotations, the pose checks) took 0.90x, 0.78x and 1.02x (TUM, KITTI, EuRoC; 5 runs) and
0.91x, 0.88x and 0.74x (3 runs, a busier machine) of ``pyarrow.csv.read_csv`` with its own threads
and the columns to numpy, which does none of that work.

A file under :data:`SPLIT_MIN_BYTES` is one piece, parsed from the calling thread: by pyarrow in
blocks on its own threads (one block a core) where the process may use them (:func:`arrow_threads`:
not a pool's worker), each block's rows grouped (converted) and copied into place as the pieces'
are. pyarrow's threads also convert a block's columns side by side, which two pieces on lorisnb's
threads, each parsed on one, do not: a 10,000-pose file took 0.52-0.56x the time (:func:`piece_batches`).
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
#: Files from this size are parsed in at least :data:`PARSE_THREADS` pieces side by side; smaller
#: ones in one piece (in blocks on pyarrow's threads: :func:`piece_batches`). Two pyarrow parses
#: side by side on 2 cores each run slower than one alone, and handing pieces to threads costs
#: about 0.1 ms: split in two, TUM files of 0.25-2 MB took 1.02-1.28x the time of one piece, 3 MB
#: about the same, 4 MB 0.82x and 6 MB (KITTI) 0.59x (warm threads, in alternation, medians;
#: 2026-11-29; each piece parsed on one thread).
SPLIT_MIN_BYTES = 3 << 20
#: Pieces parsed ahead of the first not yet placed, per thread (memory holds about this many).
AHEAD = 2
#: Bytes of a block of pyarrow's threaded parse at least (:func:`piece_batches`): a 100 KB file
#: took 0.49 ms in 64 KB blocks, 0.62 ms in 32 KB or 128 KB ones.
ARROW_BLOCK_MIN = 64 << 10


def c_options(sep: str) -> dict:
    """pandas' C parser as lorisnb reads a plain file: numbers only, one separator, ``\\n`` lines."""
    return dict(
        sep=sep, header=None, dtype=np.float64, quoting=csv.QUOTE_NONE, na_filter=False, engine="c",
        index_col=False, skip_blank_lines=False, lineterminator="\n",
    )  # fmt: skip


def parser_errors() -> tuple[type[BaseException], ...]:
    """What the piece parser (:func:`piece_columns`) raises for text that is not plain numbers
    (pyarrow's ``ArrowInvalid`` and pandas' ``ParserError`` and ``EmptyDataError`` are ValueErrors)."""
    return ValueError, OverflowError, UnicodeDecodeError


@functools.cache
def pyarrow_installed() -> bool:
    """Whether pyarrow (the ``parquet`` extra) is installed: its CSV reader then parses the pieces."""
    try:
        import pyarrow.csv  # noqa: F401
    except ImportError:
        return False
    return True


@functools.cache
def _arrow_options(sep: str, ntok: int) -> tuple[Any, Any]:
    """pyarrow's CSV options as lorisnb reads a plain file: ``ntok`` float64 columns, one separator,
    no quoting, no header, no null value (``nan`` is read as a number, as ``float`` reads it), and
    an empty line refused, not skipped (the row count then shows it)."""
    import pyarrow as pa
    import pyarrow.csv as pc

    names = [str(k) for k in range(ntok)]
    return (
        pc.ParseOptions(delimiter=sep, quote_char=False, double_quote=False, escape_char=False,
                        ignore_empty_lines=False),
        pc.ConvertOptions(column_types=dict.fromkeys(names, pa.float64()), null_values=[], true_values=[],
                          false_values=[], strings_can_be_null=False, quoted_strings_can_be_null=False),
    )  # fmt: skip


def _floats(array: Any) -> np.ndarray:
    """A float64 pyarrow array without nulls as a numpy array (read-only, no copy), from its data
    buffer (``ChunkedArray.to_numpy`` imports pandas: 0.6 s)."""
    return np.frombuffer(array.buffers()[1], np.float64, len(array), array.offset * 8)


def piece_batches(data: bytes, sep: str, ntok: int, threads: bool = False) -> list[list[np.ndarray]] | None:
    """The ``ntok`` float64 columns of ``data``'s lines (whole lines), one row per line, as one or
    more batches of consecutive rows (each a list of columns), or None when they are not plain
    numbers: by ``pyarrow.csv.read_csv`` where pyarrow is installed (with no GIL held: pieces on
    threads are parsed side by side), else ``pandas.read_csv`` (C engine). Both round as Python's
    ``float`` does. A token ``float`` refuses is refused here too: pyarrow's ``nan(...)`` (C's
    form) is not plain, nor a line pyarrow ends at a lone CR (the row count differs from the line
    count).

    ``threads``: pyarrow parses the text in blocks on its own threads (:func:`arrow_threads` says
    whether this process may), a batch each; else in one block on the calling thread. A 10,000-pose
    file took 0.52-0.56x the time in two blocks on 2 cores, 0.66-0.72x in one (its columns were
    converted side by side), and a 100 KB icra20 file 0.56-0.58x (TUM, KITTI and EuRoC files, 200
    runs each, warm, in alternation, medians; 2026-11-30)."""
    try:
        if pyarrow_installed():
            if b"(" in data:
                return None
            import pyarrow as pa
            import pyarrow.csv as pc

            names = [str(k) for k in range(ntok)]
            if threads and arrow_threads():
                read = pc.ReadOptions(column_names=names, use_threads=True, block_size=arrow_block_bytes(len(data)))
            else:  # one block (one array per column), on this thread
                read = pc.ReadOptions(column_names=names, use_threads=False, block_size=max(len(data) + 1, 1 << 16))
            table = pc.read_csv(pa.py_buffer(data), read, *_arrow_options(sep, ntok))
            batches = [[_floats(a) for a in batch.columns] for batch in table.to_batches() if batch.num_rows]
            rows = table.num_rows
        else:
            import pandas as pd

            frame = pd.read_csv(io.BytesIO(data), **c_options(sep))
            batches = [[c.to_numpy() for _, c in frame.items()]]
            rows = len(frame)
    except parser_errors():
        return None
    if not pyarrow_installed() or b"\r" in data:  # pyarrow ends a line at LF (or CR) only and refuses an
        # empty one: without a CR its rows are the lines (counting the lines of a 1M-pose file took 16 ms)
        if rows != newlines(data) + (not data.endswith(b"\n")):
            return None
    if rows and all(len(cols) == ntok and all(c.dtype == np.float64 for c in cols) for cols in batches):
        return batches
    return None


def piece_columns(data: bytes, sep: str, ntok: int) -> list[np.ndarray] | None:
    """:func:`piece_batches` in one block: the ``ntok`` columns of all of ``data``'s lines."""
    batches = piece_batches(data, sep, ntok)
    return None if batches is None else batches[0]


def arrow_block_bytes(size: int) -> int:
    """Bytes of a block of pyarrow's threaded parse of ``size`` bytes: a block for each of its
    threads, :data:`ARROW_BLOCK_MIN` at least (a line straddling blocks is pyarrow's to join)."""
    import pyarrow as pa

    return max(-(-size // pa.cpu_count()) + 1, ARROW_BLOCK_MIN)


def arrow_threads() -> bool:
    """Whether pyarrow may parse on its threads in this process: not in a process that
    ``multiprocessing`` started (a pool's worker, beside others using the cores) and not where
    pyarrow has one thread."""
    import multiprocessing

    import pyarrow as pa

    return multiprocessing.parent_process() is None and pa.cpu_count() > 1


_pool: ThreadPoolExecutor | None = None
_pool_lock = threading.Lock()


def _threads() -> ThreadPoolExecutor:
    """The threads that parse pieces, started once."""
    global _pool
    with _pool_lock:  # one pool, whichever threads read files at once
        if _pool is None:
            _pool = ThreadPoolExecutor(max_workers=PARSE_THREADS, thread_name_prefix="lorisnb-pieces")
        return _pool


def _forget_threads() -> None:
    """In a forked child: the parent's threads are not there (new ones start when needed)."""
    global _pool
    _pool = None


os.register_at_fork(after_in_child=_forget_threads)


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
        got = _on_threads(fd, [(lo, hi) for lo, hi, _ in pieces], sep, ntok, groups, convert, total // (2 * ntok) + 1)
    finally:
        os.close(fd)
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
    """:func:`piece_rows` of a file read in one piece, parsed from the calling thread (in blocks
    on pyarrow's threads: :func:`piece_batches`), each block's rows grouped (converted) and copied
    into place."""
    data = _read(fd, lo, hi)
    batches = None if data is None else piece_batches(data, sep, ntok, threads=True)
    if batches is None:
        return None
    del data
    if len(batches) == 1:
        columns = batches[0]
        parts: Sequence[Part] = [group_columns(columns, g) for g in groups]
        if convert is not None:
            return len(columns[0]), list(convert(*parts))
        keep = not row_major and all(isinstance(g, slice) for g in groups)
        return len(columns[0]), [p if keep else rows_of(p) if isinstance(p, list) else p for p in parts]
    n = sum(len(cols[0]) for cols in batches)
    outs: list[np.ndarray] = []
    at = 0
    for cols in batches:
        parts = [group_columns(cols, g) for g in groups]
        if convert is not None:
            parts = convert(*parts)
        outs = outs or _arrays(parts, n)
        m = len(cols[0])
        for part, out in zip(parts, outs, strict=True):
            if isinstance(part, list):
                copy_rows(part, out[at : at + m])
            else:
                out[at : at + m] = part
        at += m
    return n, list(outs)


def _on_threads(
    fd: int, pieces: list[tuple[int, int]], sep: str, ntok: int, groups: tuple[Group, ...],
    convert: Convert | None, capacity: int,
) -> tuple[int, list[Part]] | None:  # fmt: skip
    """:func:`piece_rows` of several pieces on :data:`PARSE_THREADS` threads: each takes the next
    piece in file order, parses (and converts) it, and copies every piece whose rows' place is now
    known (all pieces before it done) into the arrays, made by the first such copy."""
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
        while True:
            with turn:
                turn.wait_for(lambda: state["failed"] or len(done) < AHEAD * threads)
                if state["failed"] or state["taken"] == len(pieces):
                    return
                i = state["taken"]
                state["taken"] += 1
            try:
                data = _read(fd, *pieces[i])
                columns = None if data is None else piece_columns(data, sep, ntok)
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
