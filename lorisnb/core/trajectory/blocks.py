"""Row blocks: long per-pose computations (millions of poses in a lifelong run) done a block of
rows at a time, so that each chain of numpy operations works on arrays that stay in the CPU's
cache instead of streaming every temporary through memory, and blocks run on threads (numpy
releases the GIL inside its loops). Every row's result is the same whatever the block size.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from typing import TypeVar

import numpy as np

#: Rows per block: about a megabyte per (N, 4) float64 temporary.
BLOCK_ROWS = 16384

#: Threads for the blocks of one computation, per thread: 1 unless that thread lends its cores
#: (:func:`threads`; the evaluation does when it runs files in this process rather than in a pool
#: of processes). Other threads (a file's parsing threads, the blocks' own) run theirs one after
#: another: they are the lent cores already.
_lent = threading.local()


def _threads() -> int:
    """The threads this thread lent (:func:`threads`), else 1."""
    return getattr(_lent, "n", 1)


@contextmanager
def threads(n: int) -> Iterator[None]:
    """Within the block, :func:`blockwise` and :func:`each` called on this thread run on ``n``
    threads (1: one after another)."""
    before, _lent.n = _threads(), max(1, int(n))
    try:
        yield
    finally:
        _lent.n = before


def blockwise(fn: Callable[[int, int], None], n: int, block: int | None = None) -> None:
    """Call ``fn(lo, hi)`` for consecutive blocks ``[lo, hi)`` covering ``range(n)`` (of
    :data:`BLOCK_ROWS` rows unless ``block`` is given), on threads when there are several blocks.
    ``fn`` writes its rows of preallocated outputs."""
    block = block or BLOCK_ROWS
    starts = range(0, n, block)
    lent = _threads()
    if len(starts) <= 1 or lent == 1:
        for lo in starts:
            fn(lo, min(lo + block, n))
        return
    with ThreadPoolExecutor(max_workers=lent) as pool:
        for _ in pool.map(lambda lo: fn(lo, min(lo + block, n)), starts):
            pass  # re-raises a block's exception


R = TypeVar("R")


def each(*fns: Callable[[], R], rows: int) -> list[R]:
    """``[fn() for fn in fns]``, on threads when the caller lends them (:func:`threads`) and each
    works on ``rows`` of at least :data:`BLOCK_ROWS` (on fewer, starting threads costs more than
    it saves): for independent whole-array computations that each hold no GIL for long (a
    median's partition, a mean), so that they run side by side. Each result is the one computed
    alone."""
    lent = _threads()
    if len(fns) <= 1 or lent == 1 or rows < BLOCK_ROWS:
        return [fn() for fn in fns]
    with ThreadPoolExecutor(max_workers=min(lent, len(fns))) as pool:
        return list(pool.map(lambda fn: fn(), fns))


def ordinary_pages(on: bool = True) -> bool:
    """Have numpy put new large arrays in ordinary pages (``on``) or ask the kernel for huge pages
    (numpy's default); returns the previous setting (True: ordinary pages). Where the kernel
    compacts memory to find huge pages when they are first written (``transparent_hugepage/defrag``
    = ``madvise``, the usual default), arrays written once in order wait for it: a first call of
    :func:`lorisnb.core.cr_surfaces` took about four times as long on a busy machine, and a
    3-million-pose pair about a sixth more CPU time. The command line sets it for its process."""
    multiarray = getattr(getattr(np, "_core", None), "multiarray", None)
    toggle = getattr(multiarray, "_set_madvise_hugepage", None)  # numpy >= 1.20; else nothing to do
    return not toggle(not on) if toggle is not None else on
