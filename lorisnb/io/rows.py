"""The numeric lines of a file as read in chunks (:mod:`lorisnb.io.chunks`): column blocks, one
per chunk, joined into one array, or split into the row-major arrays a reader keeps, with one copy
either way (on threads for a large file).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from .ranges import PARSE_THREADS


@dataclass
class Rows:
    """The numeric lines of a file.

    Attributes:
        blocks: the numbers of consecutive runs of lines (one per chunk read), in file order, each
            (k_i, m_i) float64 column-major: row i holds each line's i-th token (NaN past its last
            token). See :attr:`columns` (all of them joined) and :meth:`split`.
        ntok: (n,) tokens per line (int8: a line has at most the largest width).
        lines: (n,) 1-based line numbers (int32 where they fit, see :func:`line_dtype`).
        specials: ``(line, text)`` of the lines holding a colon (``key: value``), when asked for.
        parsed_in_c: how many of the lines pandas' C parser read (the others: the numpy scanner).
    """

    blocks: list[np.ndarray]
    ntok: np.ndarray
    lines: np.ndarray
    specials: list[tuple[int, str]]
    parsed_in_c: int = 0

    @property
    def columns(self) -> np.ndarray:
        """(k, n) float64, k the most tokens of any line (at most the largest width): column i of
        the file's lines, a contiguous array (the blocks joined once, on threads when many)."""
        if len(self.blocks) != 1:
            self.blocks = [_join_blocks(self.blocks)]
        return self.blocks[0]

    @property
    def values(self) -> np.ndarray:
        """(n, k) view of :attr:`columns`."""
        return self.columns.T

    def split(self, groups: Sequence[slice]) -> list[np.ndarray]:
        """Row-major (n, stop - start) arrays of the column ``groups`` (slices of token positions
        with a stop), copied once from the blocks (on threads when many), which are let go as
        they are copied: afterwards this Rows holds no numbers. Tokens a line lacks are NaN."""
        blocks, self.blocks = self.blocks, []
        sizes = [b.shape[1] for b in blocks]
        outs = [np.empty((sum(sizes), len(range(g.stop)[g]))) for g in groups]
        offsets = np.cumsum([0] + sizes)

        def copy(i: int) -> None:
            b, at, m = blocks[i], int(offsets[i]), sizes[i]
            for g, out in zip(groups, outs, strict=True):
                got = b[g]  # a view: the tokens of the group this block has
                out[at : at + m, : len(got)] = got.T
                out[at : at + m, len(got) :] = np.nan
            blocks[i] = _NO_ROWS  # the block's numbers go as soon as they are copied

        _each(copy, len(blocks))
        return outs


_NO_ROWS = np.zeros((0, 0))


def line_dtype(last: int) -> type[np.signedinteger]:
    """The integer type of line numbers up to ``last``: 4 bytes where they fit (40 MB less per
    10 million lines), else 8."""
    return np.int32 if last < 2**31 else np.int64


def _each(fn: Callable[[int], None], n: int) -> None:
    """``fn(i)`` for ``i`` in ``range(n)``, on threads when there are many (numpy's copies release
    the GIL)."""
    if n > 2 * PARSE_THREADS:
        with ThreadPoolExecutor(max_workers=PARSE_THREADS) as pool:
            list(pool.map(fn, range(n)))
    else:
        for i in range(n):
            fn(i)


def _join_blocks(blocks: list[np.ndarray]) -> np.ndarray:
    """One (k, n) array of column blocks, k the most tokens of any line (NaN past a line's last
    token); each block is let go as soon as it is copied."""
    used = max((len(b) for b in blocks if b.shape[1]), default=max((len(b) for b in blocks), default=0))
    sizes = [b.shape[1] for b in blocks]
    columns = np.empty((used, sum(sizes)))
    offsets = np.cumsum([0] + sizes)

    def copy(i: int) -> None:
        b, at, m = blocks[i], int(offsets[i]), sizes[i]
        columns[: len(b), at : at + m] = b[:used]
        columns[len(b) :, at : at + m] = np.nan
        blocks[i] = _NO_ROWS

    _each(copy, len(blocks))
    return columns
