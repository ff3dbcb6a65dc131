"""Reading a large regular file on threads: the byte ranges of whole lines, each range read
(``os.pread``) and parsed on a thread of its own, results in file order. Line numbers inside a
range count from 1; the caller adds the lines before it."""

from __future__ import annotations

import os
import sys
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any, TypeVar

import numpy as np

from lorisnb.errors import ParseError
from lorisnb.io.parsing.scanner import SNIFF_BYTES, binary_reason

T = TypeVar("T")

#: After reading at least this many bytes, memory freed by the parse is handed back to the system.
GIVE_BACK_BYTES = 64 * 2**20

PARSE_THREADS = max(1, min(4, os.cpu_count() or 1))  # threads reading and parsing the chunks of one large file
LINE_LIMIT = 1 << 20  # a "line" longer than this (and than a chunk) is not a text line of numbers


def line_ranges(fd: int, start: int, total: int, size: int) -> Iterator[tuple[int, int, bool]]:
    """Byte ranges ``[lo, hi)`` of whole lines from ``start`` to the end of the file, about ``size``
    bytes each: each boundary is the first line end after ``lo + size``, found by reading a few KB
    there. ``True`` marks a range after which no line end follows within a chunk (or
    :data:`LINE_LIMIT`): not text, as when chunks are read one after another."""
    lo = start
    while lo < total:
        hi = lo + size
        if hi >= total:
            yield lo, total, False
            return
        probe = os.pread(fd, min(SNIFF_BYTES, total - hi), hi)
        k = probe.find(b"\n")
        if k < 0:  # a long line: look as far as reading one chunk after another would
            probe = os.pread(fd, min(max(LINE_LIMIT, size) + 1, total - hi), hi)
            k = probe.find(b"\n")
        if k > max(LINE_LIMIT, size) or (k < 0 and len(probe) > max(LINE_LIMIT, size)):
            yield lo, hi, True
            return
        if k < 0:
            yield lo, total, False
            return
        yield lo, hi + k + 1, False
        lo = hi + k + 1


def read_range(
    fd: int, lo: int, hi: int, overlong: bool, parse: Callable[[bytes, int, int], T], path: str, what: str
) -> tuple[T | ParseError, int]:
    """Bytes ``[lo, hi)`` of a file read and parsed (on a thread): the rows with line numbers from 1
    in this range, or the ParseError found (line numbers likewise), and the number of lines."""
    data = os.pread(fd, hi - lo, lo)
    if len(data) != hi - lo:
        return ParseError(path, None, "changed while being read; read it again"), 0
    nl = newlines(data)
    nul = data.find(b"\0")
    if nul >= 0:
        return ParseError(path, data.count(b"\n", 0, nul) + 1, binary_reason(data, what)), nl
    if overlong:
        return ParseError(path, nl + 1, f"a line longer than {LINE_LIMIT} bytes; expected {what} (text)"), nl
    if not data.endswith(b"\n"):
        data += b"\n"
        nl += 1
    try:
        return parse(data, 0, nl), nl
    except ParseError as exc:
        return exc, nl


def newlines(text: bytes) -> int:
    """The number of line feeds in ``text`` (numpy: several times as fast as ``bytes.count``)."""
    return int(np.count_nonzero(np.frombuffer(text, np.uint8) == 10))


def in_order(tasks: Iterable[tuple[tuple, int]], progress: Callable[[int], object] | None) -> Iterator:
    """Results of ``fn(*args)`` for ``((fn, *args), size)`` tasks, run on :data:`PARSE_THREADS`
    threads and yielded in order (a few tasks ahead at most, so memory holds a few chunks)."""
    pending: deque[tuple[Future, int]] = deque()
    with ThreadPoolExecutor(max_workers=PARSE_THREADS) as pool:
        try:
            for (fn, *args), size in tasks:
                pending.append((pool.submit(fn, *args), size))
                while len(pending) > 2 * PARSE_THREADS or (pending and pending[0][0].done()):
                    fut, done = pending.popleft()
                    yield fut.result()
                    if progress is not None:
                        progress(done)
            while pending:
                fut, done = pending.popleft()
                yield fut.result()
                if progress is not None:
                    progress(done)
        finally:
            for fut, _ in pending:
                fut.cancel()


def give_back_memory() -> None:
    """Return freed memory to the system: glibc's (``malloc_trim``) and, where pyarrow's CSV reader
    parsed the file, its memory pool's (``MemoryPool.release_unused``). Chunks parsed on threads
    are freed in per-thread heaps that glibc keeps otherwise: after a 1 GB file that is about 0.7 GB
    of a process's resident memory. pyarrow's default pool (mimalloc) kept about 50 MB after two
    million-pose TUM files, for the rest of the run: a pair of them peaked at 352-389 MB, 313-328 MB
    with it given back (the bench's row of the 1M-pose pair's bytes per pose)."""
    libc = _libc()
    if libc is not None:
        libc.malloc_trim(0)
    pa = sys.modules.get("pyarrow")
    if pa is not None and hasattr(pa, "default_memory_pool"):
        pa.default_memory_pool().release_unused()


def keep_freed_memory() -> None:
    """For a short-lived process (the command line): glibc serves blocks under 32 MB (a chunk's
    text, the parser's buffers, row blocks' temporaries) from memory freed earlier instead of new
    pages, and gives memory back only when :func:`give_back_memory` says so (after a large file).
    By default it unmaps and trims such blocks again and again, and each new page is zeroed by the
    kernel: about a third less system time on a 1 GB file (the bench figure that keeps this glibc
    tuning: ``make bench``'s rows of the 10M-pose pair, time and peak memory per pose). One heap for every thread: memory the
    parse threads free is what the main thread reuses next, and :func:`give_back_memory` can
    return it (glibc's ``malloc_trim`` leaves the free top of a thread's own heap resident: about
    55 MiB after a million-pose file, for the rest of the run). Nothing outside glibc."""
    libc = _libc()
    if libc is not None:
        libc.mallopt(_M_ARENA_MAX, 1)  # before any thread allocates (the command line calls this first)
        libc.mallopt(_M_MMAP_THRESHOLD, 32 << 20)  # glibc's largest
        libc.mallopt(_M_TRIM_THRESHOLD, 1 << 30)


_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD, _M_ARENA_MAX = -1, -3, -8  # glibc's malloc.h


def _libc() -> Any:
    """glibc, or None (another C library, another system)."""
    global _glibc
    if _glibc is None:
        try:
            import ctypes

            lib = ctypes.CDLL("libc.so.6")
            _glibc = lib if hasattr(lib, "malloc_trim") and hasattr(lib, "mallopt") else False
        except OSError:
            _glibc = False
    return _glibc or None


_glibc: Any = None
