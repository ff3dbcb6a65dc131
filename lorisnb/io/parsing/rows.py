"""The numeric lines of a file as read in chunks (:mod:`lorisnb.io.parsing.chunks`): column blocks, one
per chunk, joined into one array, or split into the row-major arrays a reader keeps, with one copy
either way (on threads for a large file).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from lorisnb.io.parsing.ranges import PARSE_THREADS


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
        filled: the column groups and their arrays when the numbers were copied into them as they
            were read (:class:`RowSink`; then ``blocks`` is empty and :meth:`split` returns them).
        converted: a reader's :data:`Convert` and what it gave, when it was applied to ranges of
            rows as they were read (:func:`~lorisnb.io.parsing.whole.read_whole`; see :meth:`convert`).
    """

    blocks: list[np.ndarray]
    ntok: np.ndarray
    lines: np.ndarray
    specials: list[tuple[int, str]]
    parsed_in_c: int = 0
    filled: tuple[tuple[Group, ...], Sequence[Part]] | None = None
    converted: tuple[Convert, list[Part]] | None = None

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

    def convert(self, groups: Sequence[Group], fn: Convert) -> list[Part]:
        """``fn`` of the :meth:`split` groups' arrays: what it gave on ranges of rows as they were
        read, or its result on all of them (the same arrays: it works row by row)."""
        if self.converted is not None and self.converted[0] is fn:
            arrays = self.converted[1]
            self.converted = None
            return arrays
        return list(fn(*self._parts(groups)))

    def split(self, groups: Sequence[Group]) -> list[np.ndarray]:
        """Row-major (n, stop - start) arrays of the column ``groups`` (slices of token positions
        with a stop), copied once from the blocks (on threads when many), which are let go as
        they are copied: afterwards this Rows holds no numbers. Tokens a line lacks are NaN. Rows
        read by :func:`~lorisnb.io.parsing.whole.read_whole` come as filled."""
        return [np.column_stack(p) if isinstance(p, list) else p for p in self._parts(groups)]

    def _parts(self, groups: Sequence[Group]) -> Sequence[Part]:
        """:meth:`split`'s numbers as they are held: a group of a small file read in one piece
        where the reader asked ``row_major=False`` is the parser's own columns (:data:`Part`)."""
        if self.filled is not None:
            filled, arrays = self.filled
            if tuple(groups) != filled:
                raise ValueError(f"the rows were read into the groups {filled}, not {tuple(groups)}")
            self.filled = None
            return arrays
        blocks, self.blocks = self.blocks, []
        sizes = [b.shape[1] for b in blocks]
        outs = [np.empty((sum(sizes), width(g))) for g in groups]
        offsets = np.cumsum([0] + sizes)

        def copy(i: int) -> None:
            b, at, m = blocks[i], int(offsets[i]), sizes[i]
            for g, out in zip(groups, outs, strict=True):
                got = b[g] if isinstance(g, slice) else b[[k for k in g if k < len(b)]]  # the tokens it has
                out[at : at + m, : len(got)] = got.T
                out[at : at + m, len(got) :] = np.nan
            blocks[i] = _NO_ROWS  # the block's numbers go as soon as they are copied

        each(copy, len(blocks))
        return outs


_NO_ROWS = np.zeros((0, 0))

#: A group of columns: a slice of token positions with a stop, or token positions in the order
#: wanted (EuRoC's ``q_w`` last).
Group = slice | list[int]
#: A group's numbers: an (m, width) array (any memory order), or its ``width`` columns of m
#: numbers each (a parser's columns as it read them, no copy).
Part = np.ndarray | list[np.ndarray]
#: What a reader computes from its groups' numbers (one :data:`Part` per group), row by row:
#: arrays of m rows each (or a group's :data:`Part` as given), the same whichever rows it is given
#: at once.
Convert = Callable[..., Sequence[Part]]


def width(group: Group) -> int:
    """How many columns a group has."""
    return len(group) if isinstance(group, list) else len(range(group.stop)[group])


def line_dtype(last: int) -> type[np.signedinteger]:
    """The integer type of line numbers up to ``last``: 4 bytes where they fit (40 MB less per
    10 million lines), else 8."""
    return np.int32 if last < 2**31 else np.int64


def each(fn: Callable[[int], None], n: int) -> None:
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

    each(copy, len(blocks))
    return columns


class RowSink:
    """Rows copied into row-major arrays of column groups as a file's chunks arrive in order, each
    chunk's block let go at once: a large file never holds its numbers twice. ``layout(ntok)``
    gives the groups for lines of ``ntok`` tokens; ``capacity`` is a guess of the rows (the arrays
    grow when it is short; pages past the rows are never touched)."""

    def __init__(self, layout: Callable[[int], Sequence[Group]], capacity: int) -> None:
        self.layout, self.capacity, self.n = layout, max(int(capacity), 1), 0
        self.ntok: int | None = None
        self.groups: tuple[Group, ...] = ()
        self.outs: list[np.ndarray] = []

    def add(self, part: Rows) -> bool:
        """Copy a chunk's numbers in (its blocks are emptied). False when its lines' token counts
        differ from the first lines': then the file needs the general reading."""
        m = len(part.ntok)
        if m == 0:  # no numbers (its empty block stays)
            return True
        lo, hi = int(part.ntok.min()), int(part.ntok.max())
        if self.ntok is None:
            self.ntok, self.groups = lo, tuple(self.layout(lo))
            self.outs = [np.empty((self.capacity, width(g))) for g in self.groups]
        if lo != hi or lo != self.ntok:
            return False
        if self.n + m > self.capacity:
            self.capacity = max(2 * self.capacity, self.n + m)
            self.outs = [self._moved(o) for o in self.outs]
        at = self.n
        for b in part.blocks:
            k = b.shape[1]
            for g, out in zip(self.groups, self.outs, strict=True):
                out[at : at + k] = b[g].T  # every line has the group's tokens
            at += k
        part.blocks, self.n = [], at
        return True

    def _moved(self, out: np.ndarray) -> np.ndarray:
        """``out``'s rows in an array of the new capacity (only they are written: pages past them
        stay untouched, so not resident)."""
        grown = np.empty((self.capacity, out.shape[1]))
        grown[: self.n] = out[: self.n]
        return grown

    def filled(self) -> tuple[tuple[Group, ...], list[np.ndarray]]:
        """The groups and their arrays, trimmed to the rows added (views)."""
        return self.groups, [o[: self.n] for o in self.outs]


#: Rows copied at a time from columns into a row-major array (see :func:`copy_rows`).
COPY_ROWS = 8192


def group_columns(columns: list[np.ndarray], g: Group) -> list[np.ndarray]:
    """The columns of group ``g``."""
    return columns[g] if isinstance(g, slice) else [columns[k] for k in g]


def rows_of(columns: list[np.ndarray]) -> np.ndarray:
    """(n, k) row-major array of k columns (pandas' are read-only), copied in blocks of rows on
    threads when many (numpy's copies release the GIL)."""
    if len(columns) == 1:
        return columns[0].reshape(-1, 1).copy()
    n = len(columns[0])
    out = np.empty((n, len(columns)))
    each(lambda b: copy_rows(columns, out, (b * COPY_ROWS,)), -(-n // COPY_ROWS))
    return out


def copy_rows(columns: list[np.ndarray], out: np.ndarray, starts: Iterable[int] | None = None) -> None:
    """Rows of ``columns`` into the row-major ``out`` (as many rows), :data:`COPY_ROWS` at a time
    from each of ``starts`` (all of them: every block): each block of rows stays in the CPU's
    cache while all its columns are written (a few hundred blocks, never a loop over rows)."""
    for lo in range(0, len(out), COPY_ROWS) if starts is None else starts:
        block = out[lo : lo + COPY_ROWS]
        for j, c in enumerate(columns):
            block[:, j] = c[lo : lo + COPY_ROWS]
