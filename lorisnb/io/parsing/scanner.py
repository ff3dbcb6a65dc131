"""The byte scanner behind every text reader: a file's lines, their first characters, their
token counts and their numbers, computed with numpy over the whole buffer (no Python loop over
lines), plus the row checks shared by the readers.

Errors are :class:`~lorisnb.errors.ParseError` naming the file, the line and what was expected.
"""

from __future__ import annotations

import os
import re
import stat
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from typing import TYPE_CHECKING, BinaryIO

import numpy as np

from lorisnb.core.spec.validate import choice
from lorisnb.core.trajectory.poses import QUAT_EPS, Trajectory, quaternion_norms_fit
from lorisnb.errors import ParseError

if TYPE_CHECKING:
    from lorisnb.io.parsing.rows import Part

#: Rules for poses of a repeated stamp: keep the last (the official tool's), or every one (evo's).
REPEATED = ("drop", "keep")

#: Who else keeps the last pose of a repeated stamp, as the note of ``repeated="drop"`` ends: the
#: OpenLORIS tool and TUM's associate.py (a dict keyed by stamp), whose rule the kitti and tartanair
#: conventions follow too. A command whose peer reads repeated stamps otherwise says so instead
#: (:func:`repeated_peer_clause`).
DROP_PEERS = ", as the OpenLORIS tool and TUM's associate.py do"
_drop_peers: ContextVar[str] = ContextVar("drop_peers", default=DROP_PEERS)


@contextmanager
def repeated_peer_clause(clause: str) -> Iterator[None]:
    """Within the block, the note on a repeated stamp's dropped poses ends with ``clause`` (its
    separator included, e.g. ``"; ov_eval keeps every row"``) in place of :data:`DROP_PEERS`: the
    command that reads the file names its own peer's rule (the readers know no command)."""
    token = _drop_peers.set(clause)
    try:
        yield
    finally:
        _drop_peers.reset(token)


WHITESPACE = np.zeros(256, dtype=bool)
WHITESPACE[[9, 10, 11, 12, 13, 32]] = True

POSE_FIELDS = "stamp [output_time] x y z qx qy qz qw"


@dataclass
class Lines:
    """Per-line facts of a byte buffer, computed with numpy."""

    raw: bytes
    buf: np.ndarray  # uint8 view
    starts: np.ndarray  # byte offset of each line
    ends: np.ndarray  # byte offset of each line's end (its newline excluded)
    line_of: np.ndarray  # line index of each byte
    first: np.ndarray  # first non-blank byte of each line, -1 for blank lines
    first_pos: np.ndarray  # byte offset of that byte, -1 for blank lines
    has_colon: np.ndarray  # bool per line
    ntok: np.ndarray  # whitespace-separated tokens per line

    def text(self, i: int) -> str:
        return self.raw[self.starts[i] : self.ends[i]].decode("utf-8", "replace").strip()

    def numbers(self, rows: np.ndarray, path: str, expected: str) -> np.ndarray:
        """All tokens of lines ``rows`` as float64, flat; on a bad token, a ParseError for its line."""
        keep = np.zeros(len(self.starts), dtype=bool)
        keep[rows] = True
        b = self.buf.copy()
        b[~keep[self.line_of]] = 32
        data = b.tobytes()
        if b"_" not in data:  # Python's float reads '1_000' as 1000 (PEP 515); a number in a file has no '_'
            try:
                return np.array(data.split(), dtype=np.float64)
            except (ValueError, TypeError):
                pass
        for i in rows:  # error path only: find the first offending line
            for tok in self.raw[self.starts[i] : self.ends[i]].split():
                try:
                    if b"_" in tok:
                        raise ValueError(tok)
                    float(tok)
                except ValueError:
                    shown = tok.decode("utf-8", "replace")
                    header = ""
                    if i == rows[0] and not any(_number(t) for t in self.raw[self.starts[i] : self.ends[i]].split()):
                        header = " (a line of column names? start it with '#', a comment)"
                    raise ParseError(
                        path, int(i) + 1, f"{shown!r} is not a number; expected {expected}{header}"
                    ) from None
        raise ParseError(path, None, f"could not read the numbers; expected {expected}")


def _number(token: bytes) -> bool:
    """Whether ``token`` reads as a number (:meth:`Lines.numbers`' rule: no ``_``)."""
    try:
        float(token)
    except ValueError:
        return False
    return b"_" not in token


def scan(raw: bytes, separators: bytes = b"") -> Lines:
    buf = np.frombuffer(raw, dtype=np.uint8)
    if separators:
        buf = buf.copy()
        for s in separators:
            buf[buf == s] = 32
        raw = buf.tobytes()
    n = buf.size
    nl = np.flatnonzero(buf == 10)
    starts = np.concatenate(([0], nl + 1))
    ends = np.concatenate((nl, [n]))
    nlines = starts.size
    line_of = np.repeat(np.arange(nlines), ends - starts + 1)[:n]
    ws = WHITESPACE[buf]
    nonws = np.flatnonzero(~ws)
    first = np.full(nlines, -1, dtype=np.int16)
    first_pos = np.full(nlines, -1, dtype=np.int64)
    if nonws.size:
        ln = line_of[nonws]
        run = np.concatenate(([True], ln[1:] != ln[:-1]))
        first[ln[run]] = buf[nonws[run]]
        first_pos[ln[run]] = nonws[run]
    has_colon = np.bincount(line_of[buf == 58], minlength=nlines) > 0
    tok_start = ~ws & np.concatenate(([True], ws[:-1]))
    ntok = np.bincount(line_of[tok_start], minlength=nlines)
    return Lines(raw, buf, starts, ends, line_of, first, first_pos, has_colon, ntok)


def stamp_fractions(lines: Lines, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For the first token (the stamp) of each line in ``rows``: the number of digits after its
    decimal point (-1 if none) and those digits read as an integer. Vectorized over lines."""
    if rows.size == 0:
        return np.zeros(0, int), np.zeros(0, np.int64)
    buf = lines.buf
    start = lines.first_pos[rows]
    ws = np.append(np.flatnonzero(WHITESPACE[buf]), buf.size)  # sentinels: a token or fraction ends at the end
    end = ws[np.searchsorted(ws, start)]
    dots = np.append(np.flatnonzero(buf == 46), buf.size)
    dot = dots[np.searchsorted(dots, start)]
    has = dot < end
    ndig = np.where(has, end - dot - 1, -1)
    n = np.where(has, ndig, 0)
    # digit positions of every fraction, then their integer value by a segmented sum
    total = int(n.sum())
    value = np.zeros(rows.size, np.int64)
    if total:
        owner = np.repeat(np.arange(rows.size), n)
        offs = np.arange(total) - np.repeat(np.cumsum(n) - n, n)
        pos = np.repeat(dot + 1, n) + offs
        digit = buf[pos].astype(np.int64) - 48
        if ((digit < 0) | (digit > 9)).any():
            return ndig, value  # not plain digits: no repair possible; numbers() reports the line
        power = 10 ** (np.repeat(n, n) - 1 - offs)
        np.add.at(value, owner, digit * power)
    return ndig, value


def nanosecond_pattern(ndig: np.ndarray) -> np.ndarray:
    """Lines whose stamp looks like ``secs.nanosecs`` printed without zero padding: most stamps of
    the file have exactly 9 decimals and these have fewer (``1560000003.28307199`` for
    ``.028307199``). Returns a boolean mask (all False when the file does not follow the pattern)."""
    if ndig.size == 0:
        return np.zeros(0, bool)
    nine = np.mean(ndig == 9)
    short = (ndig >= 1) & (ndig < 9)
    return short if nine >= 0.5 and short.any() else np.zeros(ndig.size, bool)


BOM = b"\xef\xbb\xbf"
SNIFF_BYTES = 65536  # binary input is recognized in this many bytes, before the rest is read


def open_input(path: str | os.PathLike[str], what: str) -> BinaryIO:
    """A file opened for reading bytes; ParseError for a path that is not one (a missing file, a
    folder, an unreadable file, not a path at all), saying what was expected."""
    if not isinstance(path, (str, os.PathLike)) or str(path).strip() == "":
        raise ParseError(
            str(path), None, f"expected the path of {what} (str or pathlib.Path), got {type(path).__name__}"
        )
    try:
        return open(path, "rb")  # noqa: SIM115 (the caller closes it)
    except FileNotFoundError:
        if os.path.islink(path):  # a dangling link: where it points is what is missing
            raise ParseError(path, None, f"a link to {os.readlink(path)}, which does not exist; expected {what} "
                             "there (fix or remove the link)") from None  # fmt: skip
        raise ParseError(path, None, f"file not found; expected {what} at this path") from None
    except IsADirectoryError:
        raise ParseError(path, None, f"is a folder; expected {what}") from None
    except OSError as exc:
        raise ParseError(path, None, f"cannot be read ({exc.strerror})") from None


def regular_file(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` is a regular file, which can be read more than once: a pipe (a FIFO, the
    shell's ``<(...)``) gives its bytes once, so nothing may peek at its start before it is read."""
    try:
        return stat.S_ISREG(os.stat(path).st_mode)
    except (OSError, TypeError, ValueError):
        return False


#: Bytes from the first NUL on that :func:`wide_text` reads: a few KB tell UTF-16/32 text from binary
#: data. (It read the whole 64 KB head, or an 8 MB chunk where the NUL came later, decoded 12 ways
#: and counted in Python: a 200 MB file of random bytes was refused in 53 ms, now in 3.5 ms.)
WIDE_SNIFF_BYTES = 4096

_NOT_ASCII_TEXT = re.compile(r"[^\t\n\r -~]")


def wide_text(head: bytes) -> bool:
    """Whether bytes holding a NUL are text in UTF-16 or UTF-32: a byte-order mark of either, or
    the :data:`WIDE_SNIFF_BYTES` from the character before the first NUL read in one of them (from
    any offset) as ASCII text, 9 characters of 10 printable or line ends and no NUL among them
    (from there: PowerShell's ``>>`` appends UTF-16 to a UTF-8 file). Zeros (``head -c 1M
    /dev/zero``), or ASCII text with a stray NUL, are not: they read as NULs or as CJK signs."""
    if head[:4] in (b"\xff\xfe\0\0", b"\0\0\xfe\xff") or head[:2] in (b"\xff\xfe", b"\xfe\xff"):
        return True
    start = max(head.find(b"\0") - 1, 0)  # UTF-16-LE's first character, 'A\\0'
    window = head[start : start + WIDE_SNIFF_BYTES]
    for encoding, unit in (("utf-16-le", 2), ("utf-16-be", 2), ("utf-32-le", 4), ("utf-32-be", 4)):
        for offset in range(unit):
            body = window[offset : offset + (len(window) - offset) // unit * unit]
            if len(body) < 4 * unit:
                continue
            text = body.decode(encoding, errors="replace")
            other = len(_NOT_ASCII_TEXT.findall(text))
            if "\0" not in text and other <= 0.1 * len(text):
                return True
    return False


def binary_reason(head: bytes, what: str) -> str:
    """Why a file whose bytes ``head`` hold a NUL byte is refused: text in UTF-16 or UTF-32
    (a Windows editor's "Unicode": :func:`wide_text`) said as such, anything else as binary data."""
    if wide_text(head):
        return f"text in UTF-16 or UTF-32 (NUL bytes between the characters); expected {what} as UTF-8 or ASCII text: save it as UTF-8"
    return f"binary data (a NUL byte); expected {what} (text)"


def read_bytes(path: str | os.PathLike[str], what: str = "a trajectory file") -> bytes:
    """A text file's bytes, a UTF-8 byte-order mark removed. ParseError for a missing file, a
    folder, an unreadable file, an empty file, or binary content (NUL bytes in its first 64 KB,
    found before the rest is read)."""
    with open_input(path, what) as fh:
        try:
            head = fh.read(SNIFF_BYTES)
            nul = head.find(b"\0")
            if nul >= 0:
                raise ParseError(path, head.count(b"\n", 0, nul) + 1, binary_reason(head, what))
            raw = head + fh.read()
        except OSError as exc:
            raise ParseError(path, None, f"cannot be read ({exc.strerror})") from None
    if raw.startswith(BOM):
        raw = raw[len(BOM) :]
    if not raw.strip():
        raise ParseError(path, None, f"empty file; expected {what}")
    return raw


def finish(
    path: str,
    stamps: np.ndarray,
    positions: np.ndarray,
    quaternions: np.ndarray,
    lines: np.ndarray,
    label: str,
    notes: list[str],
    repeated: str = "drop",
) -> Trajectory:
    """A Trajectory of rows (stamps (N,) seconds, positions (N, 3), quaternions (N, 4) ``xyzw``,
    1-based source lines): sorted by stamp keeping the last pose of a repeated stamp (as a dict
    keyed by stamp would), or with ``repeated="keep"`` every pose of a repeated stamp, in file
    order (as evo reads them). Contiguous arrays are kept as they are (a reader passes arrays of
    its own), others copied. The rows must have passed :func:`check_rows` (nothing is checked
    again)."""
    keep_all = choice("repeated", repeated, REPEATED) == "keep"
    # stamps are finite (check_rows): a later stamp is greater exactly when their difference is positive
    # (compared, not subtracted: a byte a pose where np.diff's differences took eight)
    ahead = stamps[1:] >= stamps[:-1] if keep_all else stamps[1:] > stamps[:-1]
    if not ahead.all():
        back = np.flatnonzero(~ahead)
        i = back[0] + 1
        kind = "repeats" if stamps[i] == stamps[i - 1] else "goes backwards"
        rule = (
            "kept every pose of a repeated stamp in file order (repeated='keep')"
            if keep_all
            else f"kept the last pose of each repeated stamp{_drop_peers.get()}"
        )
        # sorted only if a stamp goes backwards (with "keep" every one here does; with "drop" some may only repeat)
        sorted_ = "sorted them and " if keep_all or (stamps[back + 1] < stamps[back]).any() else ""
        notes.append(
            f"{path}{label}: timestamps are not increasing ({len(back)} times; first at line "
            f"{lines[i]}: {stamps[i]:.9f} {kind} after {stamps[i - 1]:.9f}); {sorted_}{rule}"
        )
        order = np.argsort(stamps, kind="stable")
        s = stamps[order]
        if not keep_all:
            order = order[np.concatenate((s[1:] != s[:-1], [True]))]
        stamps, positions, quaternions, lines = stamps[order], positions[order], quaternions[order], lines[order]
    elif keep_all and stamps.size > 1:  # in order, but poses of one stamp kept: said as when they are dropped
        same = np.flatnonzero(stamps[1:] == stamps[:-1])
        if same.size:
            i = same[0] + 1
            notes.append(
                f"{path}{label}: timestamps are not increasing ({same.size} times; first at line {lines[i]}: "
                f"{stamps[i]:.9f} repeats after {stamps[i - 1]:.9f}); kept every pose of a repeated stamp in file "
                "order (repeated='keep')"
            )
    small = lines.size == 0 or int(lines.max()) < 2**31  # line numbers in 4 bytes: 40 MB less per 10M poses
    return Trajectory.from_checked(  # rows checked by check_rows, sorted above
        np.ascontiguousarray(stamps, float),
        np.ascontiguousarray(positions, float),
        np.ascontiguousarray(quaternions, float),
        lines.astype(np.int32, copy=False) if small else lines,
    )


def check_rows(
    path: str, stamps: np.ndarray, positions: np.ndarray, quaternions: np.ndarray, lines: np.ndarray, notes: list[str]
) -> np.ndarray:
    """Validate rows (stamps (N,), positions (N, 3), quaternions (N, 4)); return the mask of rows
    to keep: poses with NaN or infinite values are skipped, with one note in ``notes`` saying how
    many and the first line."""
    bad_stamp = ~np.isfinite(stamps)
    if bad_stamp.any():
        i = np.flatnonzero(bad_stamp)[0]
        raise ParseError(path, int(lines[i]), f"timestamp {stamps[i]} is not finite; expected seconds")
    n = len(stamps)
    with np.errstate(over="ignore", invalid="ignore"):  # a sum is inf or NaN if a value is (or if it overflows:
        all_finite = np.isfinite(positions.sum()) and np.isfinite(quaternions.sum())  # then row by row)
    if all_finite:  # the usual case: one pass, no temporaries
        finite = np.ones(n, bool)
    else:
        finite = np.isfinite(positions).all(axis=1) & np.isfinite(quaternions).all(axis=1)
    if not finite.all():  # one note for every skipped pose, whichever reader skipped it
        skipped = np.flatnonzero(~finite)
        inf_rows = int((~(np.isnan(positions[skipped]).any(axis=1) | np.isnan(quaternions[skipped]).any(axis=1))).sum())
        kinds = (
            "infinite"
            if inf_rows == skipped.size
            else "NaN"
            if inf_rows == 0
            else f"NaN or infinite ({inf_rows} infinite)"
        )
        notes.append(f"{path}: {skipped.size} pose(s) with {kinds} values skipped (first at line {lines[skipped[0]]})")
    if quaternion_norms_fit(quaternions):
        return finite
    with np.errstate(over="ignore"):
        nq = np.einsum("ij,ij->i", quaternions, quaternions)
    zero = finite & (nq < QUAT_EPS)
    if zero.any():
        i = np.flatnonzero(zero)[0]
        raise ParseError(path, int(lines[i]), "quaternion has zero norm; expected a rotation qx qy qz qw of unit norm")
    huge = finite & ~np.isfinite(nq)
    if huge.any():
        i = np.flatnonzero(huge)[0]
        raise ParseError(
            path, int(lines[i]), "quaternion is too large to normalize; expected a rotation qx qy qz qw of unit norm"
        )
    return finite


def rows_fit(first: Part, positions: Part, quaternions: Part) -> list[Part]:
    """A :data:`~lorisnb.io.parsing.rows.Convert` of a pose file's groups (stamp, position, quaternion
    ``xyzw``), computed on each piece of a plain file on its thread as it is parsed: the groups as
    given, and a flag for each row, set on all rows given together unless every number is finite
    and every quaternion's squared norm finite and clearly (by 1e-9 of it) at least
    :data:`~lorisnb.core.trajectory.poses.QUAT_EPS`, so that :func:`check_rows` would pass them all as
    they are. A reader looks at the rows with it only where a row is flagged (then check_rows
    decides, with its notes and errors, as without this)."""
    cols = [c for p in (first, positions, quaternions) for c in (p if isinstance(p, list) else p.T)]
    n = len(cols[0])
    with np.errstate(all="ignore"):
        fine = all(np.isfinite(c.sum()) for c in cols)  # an overflowing sum: flagged, check_rows decides
        if fine and n:
            x, y, z, w = cols[-4:]
            nq = x * x
            for c in (y, z, w):
                nq += c * c
            fine = bool(nq.min() >= QUAT_EPS * (1 + 1e-9)) and bool(np.isfinite(nq.max()))
    return [first, positions, quaternions, np.full(n, not fine)]
