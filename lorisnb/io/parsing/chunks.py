"""Streamed reading of numeric line files: the file is read in chunks of whole lines, each chunk's
numbers parsed by a C parser (pyarrow's CSV reader where pyarrow is installed, else pandas'), so
memory grows only with the numbers kept and speed is the C parser's.

A chunk that is not plain numbers (blank or indented lines, ``nan`` tokens, short or long rows,
separators other than whitespace, anything the C parser refuses) is read again by the exact numpy
byte scanner (:mod:`lorisnb.io.parsing.scanner`), which accepts what Python's ``float`` accepts and names
the line and the token of any error. Both paths give the same numbers: pyarrow's and pandas'
float conversions and Python's ``float`` are all correctly rounded.

Most files users have are small (the bundled icra20 tree: 223 files of about 110 KB): pyarrow's
reader, public and cheap to import (about 0.1 s against pandas' 0.6 s), reads them at about twice
the scanner's speed (``make bench``'s "parse only" row).
"""

from __future__ import annotations

import csv
import io
import os
import stat
from collections.abc import Callable, Generator, Sequence

import numpy as np

from lorisnb.errors import ParseError
from lorisnb.io.parsing.pieces import piece_batches, pyarrow_installed
from lorisnb.io.parsing.ranges import LINE_LIMIT, give_back_memory, in_order, line_ranges, newlines, read_range
from lorisnb.io.parsing.rows import Convert, Group, Rows, RowSink, copy_rows, line_dtype
from lorisnb.io.parsing.scanner import BOM, SNIFF_BYTES, binary_reason, open_input, scan, stamp_fractions
from lorisnb.io.parsing.whole import pandas_loaded, read_whole

CHUNK_BYTES = 8 << 20  # bytes of whole lines per chunk
FAST_MIN_BYTES = 32 << 10
#: With pyarrow, chunks from this size take its reader (a call costs 0.12-0.15 ms, and the lines it
#: must skip are found first), smaller ones the numpy scanner: on 2026-12-01 the bundled icra20
#: files under 8 KB were read in 0.43-0.59 ms of CPU each by the scanner, 0.63-0.68 ms by pyarrow
#: (in a pool's worker; 0.55-0.82 and 0.93-1.07 ms in a process whose pyarrow uses threads), those
#: of 8-16 KB in 0.62-0.63 against 0.78-0.90 ms, those of 16-32 KB about the same either way and
#: those of 32-64 KB in 1.4-1.8 ms by pyarrow, 1.9-2.7 ms by the scanner (3 runs each). A folder of
#: 3,000 files of 4.7 KB (50 poses) was evaluated in 6.9 s, 7.5 s with 2 KB here (until then), and
#: its workers took 10.9 s of CPU, 11.5 s with 2 KB (medians of 6 alternating runs).
ARROW_MIN_BYTES = 16 << 10
#: Without pandas imported (and without pyarrow installed), chunks below this are read by the numpy
#: scanner (importing pandas for them would cost more than it saves: a small OpenLORIS file is
#: evaluated without pandas).
PANDAS_MIN_BYTES = 4 << 20


def _chunks(path: str | os.PathLike, what: str, size: int) -> Generator[tuple[bytes, int, int, int], None, None]:
    """Chunks of whole lines, the 0-based line number each starts at, its number of lines and the
    byte offset in the file where the next chunk starts. A UTF-8 BOM is dropped; NUL bytes
    (binary data) are refused in the chunk where they appear, before reading on."""
    spath = str(path)
    with open_input(path, what) as fh:
        line0, rest, first, seen_text, offset = 0, b"", True, False, 0  # offset: bytes read (a pipe has no tell)
        while True:
            try:
                block = fh.read(SNIFF_BYTES if first else size)
                offset += len(block)
                if first and block.startswith(BOM):
                    block = block[len(BOM) :]
                nul = block.find(b"\0")
                if first and nul < 0 and len(block) >= SNIFF_BYTES - len(BOM):  # text so far: the rest of a chunk
                    more = fh.read(max(size - SNIFF_BYTES, 0))
                    block, offset = block + more, offset + len(more)
                    nul = block.find(b"\0", SNIFF_BYTES - len(BOM))
            except OSError as exc:
                raise ParseError(spath, None, f"cannot be read ({exc.strerror})") from None
            first = False
            if nul >= 0:
                line = line0 + rest.count(b"\n") + block.count(b"\n", 0, nul) + 1
                raise ParseError(spath, line, binary_reason(block, what))
            data = rest + block if rest else block
            if not block:
                if data:
                    seen_text = seen_text or bool(data.strip())
                    yield data + b"\n", line0, newlines(data) + 1, offset
                break
            cut = data.rfind(b"\n") + 1
            if cut == 0:
                if len(data) > LINE_LIMIT:
                    raise ParseError(spath, line0 + 1, f"a line longer than {LINE_LIMIT} bytes; expected {what} (text)")
                rest = data
                continue
            piece, rest = data[:cut], data[cut:]
            seen_text = seen_text or bool(piece.strip())
            n = newlines(piece)
            yield piece, line0, n, offset - len(rest)
            line0 += n
        if not seen_text:
            raise ParseError(spath, None, f"empty file; expected {what}")


def _layout(
    chunk: bytes, line0: int, nlines: int, specials_ok: bool
) -> tuple[np.ndarray, list[tuple[int, str]], int, int] | None:
    """Lines of a chunk the C parser must skip (comments, ``key: value`` lines, blank lines), the
    special lines' text, the first line it reads and the bytes of the chunk's first lines that hold
    every skipped line (the lines after them are all read); None if special lines are not allowed.
    Only those first lines are scanned where no blank line follows them: a result file's header
    (its ``key: value`` lines) is a few hundred bytes of a chunk of numbers (the whole of a small
    file was scanned three times: 0.2 ms of an icra20 file's 1.8 ms read)."""
    last = max(chunk.rfind(b"#"), chunk.rfind(b":"))
    scanned = chunk.find(b"\n", last) + 1 if last >= 0 else 0  # the end of the line holding the last one
    rest = chunk[scanned:]
    if scanned <= 0 or rest[:1] in (b"\n", b"\r") or b"\n\n" in rest or b"\n\r\n" in rest:
        scanned = len(chunk)  # a blank line further on (or no '#' or ':'): every line is scanned
    elif scanned < len(chunk):
        chunk, nlines = chunk[:scanned], chunk.count(b"\n", 0, scanned)
    buf = np.frombuffer(chunk, np.uint8)
    nl = np.flatnonzero(buf == 10)
    starts = np.concatenate(([0], nl[:-1] + 1))
    length = nl - starts
    head = buf[np.minimum(starts, buf.size - 1)]
    blank = (length == 0) | ((length == 1) & (head == 13))
    comment = head == ord("#")
    colon = np.zeros(nlines, bool)
    colon[np.searchsorted(nl, np.flatnonzero(buf == 58))] = True
    colon &= ~comment
    if colon.any() and not specials_ok:
        return None
    specials = [
        (line0 + int(i) + 1, chunk[starts[i] : nl[i]].decode("utf-8", "replace").strip()) for i in np.flatnonzero(colon)
    ]  # a handful per file
    skipped = comment | colon | blank
    first = nlines if skipped.all() else int(np.argmin(skipped))  # (all of a scanned head: the line after it)
    return np.flatnonzero(skipped), specials, first, scanned


def _kept_lines(chunk: bytes, skip: np.ndarray, head: int | None = None) -> bytes:
    """The lines of ``chunk`` (whole lines, each ending in a line feed) other than the 0-based
    lines ``skip``, joined in order: one slice per run of kept lines. ``head``: the bytes of the
    chunk's first lines that hold every line of ``skip`` (:func:`_layout`'s); only they are scanned."""
    if not skip.size:
        return chunk
    if head is not None and head < len(chunk):
        return _kept_lines(chunk[:head], skip) + chunk[head:]
    nl = np.flatnonzero(np.frombuffer(chunk, np.uint8) == 10)
    starts = np.concatenate(([0], nl[:-1] + 1))
    kept = np.ones(nl.size, bool)
    kept[skip] = False
    edges = np.flatnonzero(np.diff(np.concatenate(([False], kept, [False])).astype(np.int8)))
    firsts, lasts = edges[::2], edges[1::2] - 1  # each run of kept lines: its first and last line
    return b"".join(chunk[starts[a] : nl[b] + 1] for a, b in zip(firsts.tolist(), lasts.tolist(), strict=True))


def single_spaced(text: bytes) -> bytes:
    """``text`` with each run of spaces made one space and the spaces a line starts or ends with
    removed (a space is dropped where the byte before it is a space or a line feed, or it starts
    the text; then one left before a line end, CR LF or LF, or at the end), by numpy masks:
    ``re.sub`` made the runs one in about 12x the time (0.20 s an 8 MB chunk of a right-aligned
    lifelong file, holding the GIL: a 10M-pose file took 21 s to read, 3.3 s before pyarrow's
    reader replaced pandas' whitespace split), and lines ending in a space went to the exact
    scanner (a million TUM poses 5.5 s, 0.55 s without the spaces)."""
    buf = np.frombuffer(text, np.uint8)
    drop = buf == 32
    drop[1:] &= drop[:-1] | (buf[:-1] == 10)
    buf = buf[~drop]
    drop = buf == 32  # at most one space before a line end now
    drop[:-1] &= (buf[1:] == 10) | (buf[1:] == 13)
    return buf[~drop].tobytes()


def _read_arrow(
    chunk: bytes, ntok: int, skip: np.ndarray, runs: bool, sep: str = " ", head: int | None = None
) -> np.ndarray:
    """:func:`_read_c` by pyarrow's CSV reader (:func:`~lorisnb.io.parsing.pieces.piece_batches`):
    the kept lines' fields one ``sep`` apart (with ``runs``, tabs made spaces and runs of spaces
    made one, those a line starts or ends with dropped, first: :func:`single_spaced`); ValueError
    where they are not plain numbers. ``head``: :func:`_kept_lines`'."""
    body = _kept_lines(chunk, skip, head)
    if runs:
        body = single_spaced(body.replace(b"\t", b" ") if b"\t" in body else body)
    batches = piece_batches(body, sep, ntok, threads=True)
    if batches is None:
        raise ValueError("not plain numbers one space apart")
    out = np.empty((sum(len(cols[0]) for cols in batches), ntok))
    at = 0
    for cols in batches:
        copy_rows(cols, out[at : at + len(cols[0])])
        at += len(cols[0])
    return out


def _read_c(
    chunk: bytes, ntok: int, skip: np.ndarray, sep: str, runs: bool = False, head: int | None = None
) -> np.ndarray:
    """(rows, ntok) numbers of a chunk by a C parser, skipping the lines ``skip``: pyarrow's where
    installed and ``sep=" "``, else pandas'. With ``sep=" "``: fields one space apart, runs of
    spaces too with ``runs`` (a third slower); a tab, a trailing space, a line of spaces (or a run
    of spaces without ``runs``) raise (an empty field)."""
    if sep in (" ", "\t") and pyarrow_installed():
        return _read_arrow(chunk, ntok, skip, runs and sep == " ", sep, head)
    import pandas as pd  # here: reading a small file needs no pandas

    return pd.read_csv(
        io.BytesIO(chunk),
        sep=sep,
        skipinitialspace=runs,
        header=None,
        names=range(ntok),
        dtype=np.float64,
        quoting=csv.QUOTE_NONE,
        na_filter=False,
        engine="c",
        index_col=False,
        skiprows=skip.tolist() if skip.size else None,
    ).to_numpy()  # (nrows, ntok), a transposed view of pandas' column block


def _fast(chunk: bytes, line0: int, nlines: int, width: int, specials_ok: bool) -> Rows | None:
    """The C-parser path for one chunk, or None when the chunk needs the exact scanner."""
    if b"\r" in chunk and chunk.count(b"\r") != chunk.count(b"\r\n"):  # a lone CR: pandas ends a line there
        return None  # (its row count can come out right all the same, and a pose be dropped): the scanner says where

    skip = np.zeros(0, np.int64)
    specials: list[tuple[int, str]] = []
    first_row = 0
    head: int | None = None  # the first lines holding every skipped one (_layout's)
    # comments, key: value lines, blank lines (pyarrow refuses an empty line: found first, not after a failed parse,
    # which sent every chunk with a blank line to the exact scanner, 17x the time)
    structured = b"#" in chunk or b":" in chunk or chunk[:1] in (b"\n", b"\r") or b"\n\n" in chunk or b"\n\r\n" in chunk
    for attempt in range(2):  # plain numbers first; blank lines are found if the row count says so
        if structured:
            layout = _layout(chunk, line0, nlines, specials_ok)
            if layout is None:
                return None
            skip, specials, first_row, head = layout
        nrows = nlines - len(skip)
        if nrows == 0:
            return Rows([np.zeros((width, 0))], np.zeros(0, np.int64), np.zeros(0, np.int64), specials)
        try:
            at = 0
            for _ in range(first_row):
                at = chunk.index(b"\n", at) + 1
            line = chunk[at : chunk.index(b"\n", at)].rstrip(b"\r")
            ntok = len(line.split())
            if ntok > width or ntok == 0:
                return None
            # spaces only (any number): the C parser's one-character split, skipping repeated spaces, is
            # faster than its whitespace split; tabs or trailing spaces further on raise, then read as below
            runs = b"  " in line or line.startswith(b" ") or line.endswith(b" ")
            if b"\t" not in line:
                tries = [(" ", runs)] + ([(" ", True)] if not runs else [])
            elif b" " not in line and b"\t\t" not in line and line[:1] != b"\t" and line[-1:] != b"\t":
                # one tab between fields (a TSV file): the C parser on tabs (the exact scanner read a
                # million such poses in 5.9 s, 12x the time of the same file with spaces)
                tries = [("\t", False), (" ", True)]
            else:  # tabs and spaces: made single spaces first (see _read_arrow)
                tries = [(" ", True)]
            if pandas_loaded() or not pyarrow_installed():
                tries.append((r"\s+", False))  # other spacing further on (pandas' whitespace split)
            if not tries:
                return None
            for k, (sep, skip_runs) in enumerate(tries):
                try:
                    values = _read_c(chunk, ntok, skip, sep, skip_runs, head)
                    break
                except ValueError:  # pandas' ParserError and pyarrow's ArrowInvalid are ValueErrors
                    if k == len(tries) - 1:
                        raise
        except (ValueError, IndexError, UnicodeDecodeError):
            return None
        if len(values) == nrows:
            break
        if structured or attempt:  # whitespace-only lines were skipped: line numbers unknown
            return None
        structured = True  # blank lines: find them, and read again with their numbers known
    columns = values.T  # (ntok, nrows): read_rows pads short rows' columns with NaN when it joins chunks
    if skip.size:
        keep = np.ones(nlines, bool)
        keep[skip] = False
        lines = (line0 + 1 + np.flatnonzero(keep)).astype(line_dtype(line0 + nlines))
    else:
        lines = np.arange(line0 + 1, line0 + 1 + nlines, dtype=line_dtype(line0 + nlines))
    return Rows([columns], np.full(nrows, ntok, np.int8), lines, specials, nrows)


def _exact(
    chunk: bytes,
    line0: int,
    path: str,
    widths: tuple[int, ...],
    specials_ok: bool,
    bad_width: Callable[[str, int], str],
    numbers: str,
) -> Rows:
    """The numpy byte-scanner path for one chunk (any whitespace, ``nan``, exact error lines). A
    carriage return without a line feed (CR is whitespace here, a line end to the official tool and
    Python's universal newlines) is named where it is, unless a problem comes before it."""
    lone = chunk.find(b"\r", 0, len(chunk) - 1)
    while lone >= 0 and chunk[lone + 1 : lone + 2] == b"\n":  # CRLF: a line end
        lone = chunk.find(b"\r", lone + 2, len(chunk) - 1)
    if lone < 0:
        return _scanned(chunk, line0, path, widths, specials_ok, bad_width, numbers)
    cr_line = line0 + chunk.count(b"\n", 0, lone) + 1
    cr = ParseError(path, cr_line, "a carriage return (CR) without a line feed: do the file's lines end with CR alone "
                    "(classic Mac OS)? Expected lines ending with LF or CRLF; convert with tr '\\r' '\\n' < FILE > NEW")  # fmt: skip
    try:
        _scanned(chunk, line0, path, widths, specials_ok, bad_width, numbers)
    except ParseError as exc:
        if exc.line is not None and exc.line < cr_line:
            raise
    raise cr


def _scanned(
    chunk: bytes,
    line0: int,
    path: str,
    widths: tuple[int, ...],
    specials_ok: bool,
    bad_width: Callable[[str, int], str],
    numbers: str,
) -> Rows:
    """:func:`_exact` of a chunk without a lone carriage return."""
    lines = scan(chunk)
    comment = lines.first == ord("#")
    blank = lines.first < 0
    colon = lines.has_colon & ~comment & ~blank if specials_ok else np.zeros_like(blank)
    specials = [(line0 + int(i) + 1, lines.text(int(i))) for i in np.flatnonzero(colon)]
    rows = np.flatnonzero(~comment & ~blank & ~colon)
    ntok = lines.ntok[rows]
    bad = ntok != widths[0]  # (np.isin's set-up took 30 us a chunk: a file's, for a small file)
    for w in widths[1:]:
        bad &= ntok != w
    first_bad = int(np.flatnonzero(bad)[0]) if bad.any() else rows.size
    try:  # the first problem in file order, whatever the chunks: a token before a line of another width
        flat = lines.numbers(rows[:first_bad], path, numbers)
    except ParseError as exc:
        if exc.line is not None:
            raise ParseError(path, line0 + exc.line, exc.reason) from None
        raise
    if first_bad < rows.size:
        i = int(rows[first_bad])
        raise ParseError(path, line0 + i + 1, bad_width(lines.text(i), int(lines.ntok[i])))
    width = max(widths)
    columns = np.full((width, rows.size), np.nan)
    offs = np.cumsum(ntok) - ntok
    col = np.arange(flat.size) - np.repeat(offs, ntok)
    columns[col, np.repeat(np.arange(rows.size), ntok)] = flat
    return Rows([columns], ntok.astype(np.int8), line0 + rows + 1, specials)


def read_rows(
    path: str | os.PathLike,
    widths: tuple[int, ...],
    *,
    what: str,
    numbers: str,
    bad_width: Callable[[str, int], str],
    specials: bool = False,
    separators: bytes = b"",
    chunk_bytes: int | None = None,
    fast_min_bytes: int | None = None,
    progress: Callable[[int], object] | None = None,
    layout: Callable[[int], Sequence[Group]] | None = None,
    skip_lines: int = 0,
    row_major: bool = True,
    convert: Convert | None = None,
) -> Rows:
    """Read the numeric lines of a text file in chunks (a plain file of at most
    :data:`~lorisnb.io.parsing.whole.WHOLE_MAX_BYTES` with a ``layout``: by pandas' parser in pieces on
    threads, :func:`~lorisnb.io.parsing.whole.read_whole`).

    Blank lines and ``#`` comments are skipped. Each other line must hold a number of
    whitespace-separated tokens in ``widths``, all numbers; otherwise a ParseError names the
    line, using ``bad_width(text, ntok)`` or ``numbers`` (what was expected) for the message.

    Args:
        path: the file.
        widths: allowed token counts per line.
        what: what the file should be, for messages ("a TUM trajectory file").
        numbers: the numbers expected on a line, for messages.
        bad_width: message for a line of ``ntok`` tokens.
        specials: return lines holding a colon (``key: value``) in ``Rows.specials`` instead of
            reading them as numbers.
        separators: bytes read as whitespace too (``b","``).
        chunk_bytes: chunk size (default :data:`CHUNK_BYTES`).
        fast_min_bytes: chunks smaller than this skip the C parser (0: always try it first; default
            :data:`ARROW_MIN_BYTES` with pyarrow, else :data:`FAST_MIN_BYTES`).
        progress: called with the bytes of each chunk read.
        layout: the column groups the caller will :meth:`~lorisnb.io.parsing.rows.Rows.split` the rows
            into, given the lines' token count: a large file whose lines all have the same count
            is then copied into them as its chunks are parsed (:class:`~lorisnb.io.parsing.rows.RowSink`).
        skip_lines: line ``skip_lines`` (1-based; 0: none) is skipped as a comment (a header line
            without ``#``; the lines before it must be blank or comments).
        row_major: False for a reader that only computes from the groups' arrays and keeps none of
            them: a small plain file read in one piece then gives views of the parser's own numbers
            (column-major, read-only; no copy), chunked reading row-major arrays as always.
        convert: what the reader computes from the groups (:meth:`Rows.convert`): a plain file
            read in pieces computes it on each piece as it is read.
    """
    if layout is not None and not specials and chunk_bytes is None:  # a plain file: pandas' parse in pieces
        whole = read_whole(path, widths, layout, separators, skip_lines, progress, row_major, convert)
        if whole is not None:
            return whole
    spath = str(path)
    width = max(widths)
    chunk_bytes = chunk_bytes or CHUNK_BYTES
    parts: list[Rows] = []

    def parse(chunk: bytes, line0: int, nlines: int) -> Rows:
        if separators and any(s in chunk for s in separators):
            chunk = chunk.translate(bytes.maketrans(separators, b" " * len(separators)))
        least = (
            fast_min_bytes if fast_min_bytes is not None else ARROW_MIN_BYTES if pyarrow_installed() else FAST_MIN_BYTES
        )
        c_parser = len(chunk) >= least and (len(chunk) >= PANDAS_MIN_BYTES or pandas_loaded() or pyarrow_installed())
        part = _fast(chunk, line0, nlines, width, specials) if c_parser else None
        if part is None or (part.ntok.size and int(part.ntok[0]) not in widths):  # (np.isin: 20 us a file)
            part = _exact(chunk, line0, spath, widths, specials, bad_width, numbers)
        return part

    chunks = _chunks(path, what, chunk_bytes)
    first, _, first_lines, at = next(chunks)
    parts.append(parse(_commented(first, skip_lines), 0, first_lines))
    if progress is not None:
        progress(len(first))
    try:
        st = os.stat(path)
        regular, total = stat.S_ISREG(st.st_mode), st.st_size
    except OSError:
        regular, total = False, 0
    if not regular or at >= total or skip_lines > first_lines:  # a pipe or a device (or no more chunks: the
        # end checks for an empty file; or the line to skip further on): chunks one after another
        parts += in_order(
            (((parse, _commented(c, skip_lines - l0), l0, n), len(c)) for c, l0, n, _ in chunks), progress
        )
        return _join(parts)
    chunks.close()
    sink, again = None, False
    if layout is not None:  # the rows of the whole file, guessed from the first chunk's lines per byte
        sink = RowSink(layout, int(total * (first_lines + 1) / max(len(first), 1) * 1.05) + 1024)
        if not sink.add(parts[0]):
            sink = None  # lines of several token counts at once: nothing copied yet, read on as usual
    fd = os.open(path, os.O_RDONLY)
    try:
        tasks = (
            ((read_range, fd, lo, hi, overlong, parse, spath, what), hi - lo)
            for lo, hi, overlong in line_ranges(fd, at, total, chunk_bytes)
        )
        line0 = first_lines
        for part, nlines in in_order(tasks, progress):  # chunks read and parsed on threads, joined in order
            if isinstance(part, ParseError):
                raise ParseError(spath, None if part.line is None else part.line + line0, part.reason)
            if part.lines.dtype == np.int64 or line_dtype(line0 + nlines) == np.int32:
                part.lines += line0
            else:
                part.lines = part.lines + np.int64(line0)
            part.specials = [(k + line0, text) for k, text in part.specials]
            if sink is not None and not sink.add(part):
                again = True  # lines of another token count: read the file again without the sink
                break
            parts.append(part)
            line0 += nlines
    finally:
        os.close(fd)
    if again:
        del parts
        return read_rows(path, widths, what=what, numbers=numbers, bad_width=bad_width, specials=specials,
                         separators=separators, chunk_bytes=chunk_bytes, fast_min_bytes=fast_min_bytes,
                         skip_lines=skip_lines)  # fmt: skip
    rows = _join(parts)
    del parts
    if sink is not None and sink.ntok is not None:
        rows.filled = sink.filled()
    give_back_memory()
    return rows


def _commented(chunk: bytes, line: int) -> bytes:
    """``chunk`` with ``#`` put before its ``line``-th line (1-based), if the chunk holds it."""
    parts = chunk.split(b"\n", line - 1) if line >= 1 else []
    if len(parts) < line or line < 1 or not parts[-1]:  # not in this chunk (an empty rest: the next one's)
        return chunk
    return b"\n".join(parts[:-1] + [b"#" + parts[-1]])


def _join(parts: list[Rows]) -> Rows:
    """One Rows of all chunks (their blocks kept as they are: joined when :attr:`Rows.columns` is
    asked for, or copied once by :meth:`Rows.split`)."""
    if len(parts) == 1:
        return parts[0]
    return Rows(
        [b for p in parts for b in p.blocks],
        np.concatenate([p.ntok for p in parts]),
        np.concatenate([p.lines for p in parts]),
        [s for p in parts for s in p.specials],
        sum(p.parsed_in_c for p in parts),
    )


def stamp_digits(
    path: str | os.PathLike, lines: np.ndarray, chunk_bytes: int = CHUNK_BYTES
) -> tuple[np.ndarray, np.ndarray]:
    """For the given 1-based ``lines`` (increasing) of a file: the digits after the decimal point
    of each line's first token (-1 if none) and those digits as an integer, read exactly from the
    bytes (nanosecond digits included). Streams the file again; used only when needed."""
    ndig = np.full(lines.size, -1, np.int64)
    frac = np.zeros(lines.size, np.int64)
    for chunk, line0, n, _ in _chunks(path, "a text file", chunk_bytes):
        lo, hi = np.searchsorted(lines, [line0 + 1, line0 + n + 1])
        if hi > lo:
            scanned = scan(chunk)
            ndig[lo:hi], frac[lo:hi] = stamp_fractions(scanned, lines[lo:hi] - line0 - 1)
    return ndig, frac
