"""The one registry of trajectory formats: for each its name, file suffixes, column layout, reader,
how to recognise a file of it from its first bytes, and the option that reads it. Readers, the
command line's choices and the error messages all take their knowledge from here, so a file that is
plainly in another format is answered with the option that would read it::

    data.csv, line 2: '1403636579763555584,4.68,-1.78,...' has 17 fields; expected 8 numbers ...;
    this looks like a EuRoC CSV file ('timestamp_ns,p_x,p_y,p_z,q_w,q_x,q_y,q_z,...'): read it with
    --format euroc (--gt-format euroc for the ground truth; fmt='euroc' in Python)
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

from lorisnb.errors import ParseError
from lorisnb.io.parsing.scanner import regular_file

#: Bytes of a file's beginning that :func:`sample` looks at.
SAMPLE_BYTES = 64 * 1024
#: Data lines of that beginning that the recognisers look at.
SAMPLE_LINES = 20


@dataclass(frozen=True)
class Sample:
    """The beginning of a file: its first bytes, its ``#`` comment lines before the first data line
    (and a CSV header line without ``#``), its first data lines split into tokens (at spaces, tabs
    and commas), and whether commas separate the values."""

    head: bytes
    comments: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    commas: bool
    folder: bool = False

    @cached_property
    def numbers(self) -> tuple[list[float] | None, ...]:
        """Each row's values, or None for a row with a token that is not a plain number (worked out
        once for all the recognisers)."""
        return tuple(_numbers(r) for r in self.rows)


_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_ROW_OF_NUMBERS = re.compile(rf"(?:{_NUMBER} )*{_NUMBER}")  # tokens joined by one space (one match a row)


def _numbers(row: tuple[str, ...]) -> list[float] | None:
    return [float(t) for t in row] if _ROW_OF_NUMBERS.fullmatch(" ".join(row)) else None


def _is_bag(s: Sample) -> bool:
    return s.folder or s.head.startswith((b"#ROSBAG", b"SQLite format 3", b"\x89MCAP"))


def _is_openloris(s: Sample) -> bool:
    # a header or seq line as the reader takes it: any spacing around the colon ('scene:cafe', VINS-Mono's)
    return any(r and " ".join(r).partition(":")[0].strip().lower() in ("scene", "frame", "seq") for r in s.rows)


#: Names a header gives the stamp column alone (``#timestamp``): the stamps' unit unsaid.
_STAMP_NAMES = ("timestamp", "time", "stamp", "t")
#: The smallest stamp that can only be nanoseconds since 1970 (as seconds: 31 million years).
_NANOSECONDS_SINCE_1970 = 1e15


@dataclass(frozen=True)
class _Header:
    """What the column header nearest a file's first data line says (:func:`_header`): the order of
    the quaternion named in the fifth to eighth columns (``"wxyz"``: ``q_w``, ``q_RS_w``, ``qw``
    fifth; ``"xyzw"``: ``qx`` fifth, TUM's ``tx ty tz qx qy qz qw``), whether the stamps are said to
    be nanoseconds (``[ns]``, ``(ns)``, ``timestamp_ns``), and whether it names the stamp column alone."""

    order: str | None = None
    nanoseconds: bool = False
    bare: bool = False


def _header(s: Sample) -> _Header:
    """:class:`_Header` of the last comment line before the first data line (or the CSV header line
    without ``#``) that names columns: one stamp name alone, or at least 8 names with a quaternion
    component fifth. Units in brackets (``p_x [m]``, ``timestamp(s)``) are not names."""
    for c in reversed(s.comments):
        text = c.lstrip("#").strip().lower()
        names = re.sub(r"\[[^\]]*\]|\([^)]*\)", " ", text).replace(",", " ").split()
        ns = bool(re.search(r"\[ns\]|\(ns\)|[a-z]_ns\b", text))
        if len(names) >= 8 and re.fullmatch(r"q\w*[wx]", names[4]):
            return _Header("wxyz" if names[4].endswith("w") else "xyzw", ns)
        if len(names) == 1 and names[0] in _STAMP_NAMES + tuple(f"{n}_ns" for n in _STAMP_NAMES):
            return _Header(None, ns, bare=True)
    return _Header()


def _is_euroc(s: Sample) -> bool:
    """Comma-separated rows of at least 8 numbers whose quaternion a header names ``w`` first; or,
    where no header names the order, stamps that are nanoseconds since 1970 (1e15 or more, in any
    notation: ``1403636579763555584``, ``1.4036e+18``) or said to be nanoseconds by the header, or
    integers under a header naming the stamp column alone (a comma-separated TUM file's stamps are
    seconds with a fraction: ``1.0``, ``1305031102.175304``). A header naming ``qx`` fifth (TUM's)
    is never EuRoC's, whatever the stamps."""
    rows = [(r, v) for r, v in zip(s.rows, s.numbers, strict=True) if v is not None]
    if not s.commas or not rows or not all(len(r) >= 8 for r, _ in rows):
        return False
    header = _header(s)
    if header.order is not None:
        return header.order == "wxyz"
    if header.nanoseconds or all(v[0] >= _NANOSECONDS_SINCE_1970 for _, v in rows):
        return True
    return header.bare and all(r[0].isdigit() for r, _ in rows)


def _is_kitti(s: Sample) -> bool:
    rows = s.numbers
    if not rows or any(v is None or len(v) != 12 for v in rows):
        return False
    return all(abs(sum(x * x for x in v[0:3]) - 1) < 1e-2 for v in rows if v is not None)  # rotation rows


def _is_tum(s: Sample) -> bool:
    rows = s.numbers
    if not rows or any(v is None or len(v) != 8 for v in rows):
        return False
    return all(abs(sum(x * x for x in v[4:8]) - 1) < 1e-2 for v in rows if v is not None) and not _is_euroc(s)


@dataclass(frozen=True)
class Format:
    """One trajectory format: ``name`` (the ``--format`` value), ``suffixes`` of its files,
    ``title`` and ``columns`` (its layout, in words), ``reader`` (the :mod:`lorisnb.io` function),
    ``recognise`` (whether a :class:`Sample` is plainly of this format), and ``quaternions``: the
    order its files write a quaternion in (``"xyzw"``, ``"wxyz"``), ``""`` where no order can be
    mistaken (KITTI's matrices, a bag's named fields), None where a file's header decides (EuRoC's
    ``q_w`` or ``q_x`` first). The pipeline's orientation check names an order mistake only where
    the format allows one (:func:`lorisnb.core.pipeline.sessions.evaluate_sessions`' ``quaternions``)."""

    name: str
    title: str
    suffixes: tuple[str, ...]
    columns: str
    reader: str
    recognise: Callable[[Sample], bool]
    quaternions: str | None = "xyzw"

    def looks(self) -> str:
        """``"this looks like a KITTI pose file (12 numbers ...)"``."""
        article = "an" if self.title.startswith(("A", "I", "O")) else "a"
        return f"this looks like {article} {self.title} ({self.columns})"

    def hint(self) -> str:
        """What a file of this format looks like and how to read it, on every surface."""
        return (
            f"{self.looks()}: read it with --format {self.name} "
            f"(--gt-format {self.name} for the ground truth; fmt={self.name!r} or lorisnb.{self.reader} in Python)"
        )


#: Every format lorisnb reads, in the order files are tried for recognition (most specific first).
FORMATS: dict[str, Format] = {
    f.name: f
    for f in (
        Format("bag", "ROS bag", (".bag", ".db3", ".mcap"), "ROS 1 .bag or ROS 2 bag (a pose topic or TF chain)",
               "read_bag", _is_bag, ""),
        Format("openloris", "OpenLORIS file", (".txt",),
               "'scene:' and 'frame:' headers, 'seq: N' blocks of 'stamp x y z qx qy qz qw'", "read_openloris",
               _is_openloris),
        Format("euroc", "EuRoC CSV file", (".csv",), "'timestamp_ns,p_x,p_y,p_z,q_w,q_x,q_y,q_z,...'",
               "read_euroc", _is_euroc, None),
        Format("kitti", "KITTI pose file", (".txt",), "12 numbers per line, a 3x4 pose matrix row-major",
               "read_kitti", _is_kitti, ""),
        Format("tum", "TUM trajectory file", (".txt", ".csv"), "'stamp tx ty tz qx qy qz qw', seconds",
               "read_tum", _is_tum),
    )
}  # fmt: skip

#: The format names, for option choices and messages.
FORMAT_NAMES: tuple[str, ...] = ("tum", "kitti", "euroc", "openloris", "bag")
#: Formats of plain text files (``crosscheck`` reads these).
TEXT_FORMATS: tuple[str, ...] = ("tum", "kitti", "euroc", "openloris")


def suffixes(fmt: str) -> tuple[str, ...]:
    """File suffixes of a format (the first is the one its files are usually given)."""
    return FORMATS[fmt].suffixes


def sample(path: str | os.PathLike[str]) -> Sample | None:
    """The beginning of a regular file (None if it cannot be read, or is a pipe); a folder holding ``metadata.yaml`` is
    a ROS 2 bag."""
    p = Path(path)
    try:
        if p.is_dir():
            return Sample(b"", (), (), False, folder=(p / "metadata.yaml").is_file())
        if not regular_file(p):  # a pipe: its bytes are the reader's (a peek would take them)
            return None
        with open(p, "rb") as f:
            head = f.read(_FIRST_LOOK)
            first = _sample(head, len(head) == _FIRST_LOOK)
            if len(head) < _FIRST_LOOK or len(first.rows) >= SAMPLE_LINES:
                return first
            head += f.read(SAMPLE_BYTES - _FIRST_LOOK)  # too few lines there: the whole sample
    except OSError:
        return None
    return sample_bytes(head)


def sample_bytes(head: bytes) -> Sample:
    """A :class:`Sample` of a file's first bytes (at most :data:`SAMPLE_BYTES` are looked at)."""
    if len(head) > _FIRST_LOOK:  # most files give their lines in the first 4 KB: look there first
        first = _sample(head[:_FIRST_LOOK], True)
        if len(first.rows) >= SAMPLE_LINES:
            return first
    return _sample(head[:SAMPLE_BYTES], len(head) >= SAMPLE_BYTES)


#: Bytes :func:`sample_bytes` looks at first (all of the sample when they hold too few lines).
_FIRST_LOOK = 4096


def _sample(head: bytes, cut: bool) -> Sample:
    """The :class:`Sample` of the beginning of a file (``cut``: its last line may be cut short, and
    is left out): its comment lines, first data lines in tokens and whether commas separate them."""
    if b"\0" in head[:512]:
        return Sample(head, (), (), False)
    text = head.decode("utf-8", "replace").lstrip("\ufeff")
    lines = text.splitlines()[:-1] if cut else text.splitlines()
    comments: list[str] = []
    rows: list[tuple[str, ...]] = []
    commas, first = False, ""
    for line in lines:
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            if not rows:  # a comment before the data: perhaps its header
                comments.append(stripped)
            continue
        first = first or stripped
        commas = commas or "," in stripped
        rows.append(tuple(stripped.replace(",", " ").split()))  # at whitespace (as re's \s) and commas
        if len(rows) >= SAMPLE_LINES:
            break
    if rows and _numbers(rows[0]) is None and len(rows) > 1 and _numbers(rows[1]) is not None and "," in first:
        comments.append(first)  # a CSV header line without '#': the header, as a comment's
        rows = rows[1:]
    return Sample(head, tuple(comments), tuple(rows), commas)


def recognise(s: Sample | None) -> list[str]:
    """The formats a sample is plainly in (usually one; none for text of no known layout)."""
    if s is None:
        return []
    return [name for name, f in FORMATS.items() if f.recognise(s)]


def hint(path: str | os.PathLike[str], fmt: str) -> str:
    """``"; this looks like a KITTI pose file (...): read it with --format kitti ..."`` when the
    file is plainly in another format than ``fmt``, else ``""``."""
    s = sample(path)
    return "" if s is None else hint_of_sample(s, fmt)


def line_hint(text: str, fmt: str) -> str:
    """The same as :func:`hint` for one offending line of a file (the readers' width errors)."""
    return hint_of_sample(sample_bytes(text.encode("utf-8", "replace")), fmt)


def with_hint(e: ParseError, path: object, fmt: str) -> ParseError:
    """A reader of ``fmt``'s error ``e`` on the file at ``path``, with the hint of the format the
    file is plainly in (:func:`hint_of_sample`) where it is another and ``e`` does not give it yet;
    else ``e`` itself. A pipe or a path that cannot be read gives no hint."""
    if not isinstance(path, (str, os.PathLike)):
        return e
    s = sample(path)
    extra = "" if s is None else hint_of_sample(s, fmt)
    if not extra or extra.removeprefix("; ") in e.reason:
        return e
    return ParseError(e.path, e.line, e.reason + extra)


def hint_of_sample(s: Sample, fmt: str) -> str:
    """:func:`hint` of a sample already taken."""
    found = recognise(s)
    if not found or fmt in found:
        return ""
    return "; " + FORMATS[found[0]].hint()


def times_hint(path: str | os.PathLike[str], text: str) -> str:
    """For a times file (one stamp per line) that is plainly a pose file of some format: the
    mistake, a pose file given where its times were asked for (else ``""``)."""
    s = sample(path)
    found = recognise(s) or recognise(sample_bytes(text.encode("utf-8", "replace")))
    if not found:
        return ""
    return (
        f"; {FORMATS[found[0]].looks()}, not a times file: a pose file was given where its times were asked for "
        "(--est-times, --gt-times or --times; stamps= in Python). Give the file of the poses' stamps there, one "
        "per line (KITTI's times.txt), and the pose file itself as the estimate or --gt"
    )
