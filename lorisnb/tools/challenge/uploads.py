"""An upload, checked before anything is kept: OpenLORIS result files (``.txt``, text) or one
``.zip`` of them. Refused, each with a message naming the file and what was expected: archive
members with a path that leaves the folder (``../``, absolute, drive letters), links, encrypted
members, archives nested in archives, zip bombs (declared or actual unpacked size over the limit,
or a compression ratio no result file has), too many files, binary or empty files, two files of
the same name. Nothing from an upload is ever executed: the files are only read by the scorer.
"""

from __future__ import annotations

import os
import re
import shutil
import stat
import zipfile
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import IO

from lorisnb.errors import LorisError

#: A member more compressed than this is a bomb, not a result file (text of poses compresses ~3-5x).
MAX_RATIO = 100
#: Bytes read at a time.
CHUNK = 1 << 16
_SAFE_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9 _.,+=@()-]{0,199}$")


class UploadRefused(LorisError):
    """An upload refused: ``status`` is the HTTP status, the message says why and what is expected."""

    def __init__(self, message: str, status: int = 400):
        super().__init__(message)
        self.status = status


@dataclass(frozen=True)
class Limits:
    files: int
    unpacked_bytes: int


def safe_name(name: str, where: str) -> str:
    """The file name ``name`` (a member path of an archive or an uploaded file's name) as kept:
    its last part; refused if any part climbs out, is absolute or hidden, or has odd characters."""
    if not name or "\x00" in name or any(ord(c) < 32 for c in name):
        raise UploadRefused(f"{where}: {name!r}: a file name with control characters; expected a plain name")
    if "\\" in name or re.match(r"^[A-Za-z]:", name):
        raise UploadRefused(f"{where}: {name!r}: a Windows path; expected names with '/' and no drive letter")
    if name.startswith("/"):
        raise UploadRefused(f"{where}: {name!r}: an absolute path; expected a path inside the archive")
    parts = [p for p in name.split("/") if p not in ("", ".")]
    if ".." in parts:
        raise UploadRefused(f"{where}: {name!r}: a path that climbs out of the folder ('..'); refused")
    if not parts:
        raise UploadRefused(f"{where}: {name!r}: no file name")
    base = parts[-1]
    if not _SAFE_NAME.match(base):
        raise UploadRefused(f"{where}: {base!r}: expected a name of letters, digits, '-', '_' and '.', not starting "
                            "with '.'")  # fmt: skip
    return base


def _check_text(head: bytes, name: str) -> None:
    if not head.strip():
        raise UploadRefused(f"{name}: empty; expected an OpenLORIS result file (header lines, then 'seq: N' blocks "
                            "of 'timestamp x y z qx qy qz qw')")  # fmt: skip
    if b"\x00" in head:
        raise UploadRefused(f"{name}: a binary file; expected an OpenLORIS result file (text)")
    try:
        head.decode("utf-8")
    except UnicodeDecodeError as exc:
        if exc.start < len(head) - 4:  # not just a character cut at the end of the head
            raise UploadRefused(
                f"{name}: not UTF-8 text (byte {exc.start}); expected an OpenLORIS result file"
            ) from None


def _suffix(name: str, where: str, allow_zip: bool) -> str:
    suffix = Path(name).suffix.lower()
    if suffix == ".txt" or (allow_zip and suffix == ".zip"):
        return suffix
    what = "OpenLORIS result files (.txt) or one .zip of them" if allow_zip else "OpenLORIS result files (.txt)"
    raise UploadRefused(f"{where}: {name!r}: a {suffix or 'file without suffix'}; expected {what}", 415)


def _copy(src: IO[bytes], dest: Path, name: str, budget: int) -> int:
    """Copy ``src`` to ``dest`` reading at most ``budget`` bytes (refused beyond); bytes copied."""
    n = 0
    with open(dest, "xb") as out:
        head = src.read(CHUNK)
        _check_text(head, name)
        while head:
            n += len(head)
            if n > budget:
                raise UploadRefused(f"{name}: unpacks to more than the challenge's limit of {budget_mb(budget)}", 413)
            out.write(head)
            head = src.read(CHUNK)
        out.flush()
        os.fsync(out.fileno())
    return n


def budget_mb(n: int) -> str:
    return f"{n / 1e6:g} MB"


def _unzip(src: IO[bytes], label: str, dest: Path, limits: Limits, taken: set[str], budget: int) -> int:
    try:
        archive = zipfile.ZipFile(src)
    except (zipfile.BadZipFile, OSError, EOFError, ValueError) as exc:
        raise UploadRefused(f"{label}: not a readable zip archive ({exc}); expected a .zip of result files") from None
    with archive:
        members = [m for m in archive.infolist() if not m.is_dir()]
        if len(members) + len(taken) > limits.files:
            raise UploadRefused(f"{label}: {len(members)} files; the challenge takes at most {limits.files}", 413)
        declared = sum(m.file_size for m in members)
        if declared > budget:
            raise UploadRefused(f"{label}: unpacks to {budget_mb(declared)}, over the challenge's limit of "
                                f"{budget_mb(budget)}", 413)  # fmt: skip
        used = 0
        for m in members:
            where = f"{label}: {m.filename}"
            mode = m.external_attr >> 16
            if stat.S_ISLNK(mode):
                raise UploadRefused(f"{where}: a symbolic link; expected regular files")
            if stat.S_IFMT(mode) and not stat.S_ISREG(mode):  # no type bits (writestr's): a file
                raise UploadRefused(f"{where}: not a regular file; expected regular files")
            if m.flag_bits & 0x1:
                raise UploadRefused(f"{where}: encrypted; expected an archive without a password")
            name = safe_name(m.filename, label)
            _suffix(name, where, allow_zip=False)
            if m.compress_size and m.file_size / m.compress_size > MAX_RATIO:
                raise UploadRefused(f"{where}: compressed {m.file_size / m.compress_size:.0f} times (a zip bomb?); "
                                    f"result files compress at most {MAX_RATIO} times", 413)  # fmt: skip
            if name in taken:
                raise UploadRefused(f"{where}: a second file named {name!r}; expected distinct file names")
            taken.add(name)
            try:
                with archive.open(m) as f:
                    used += _copy(f, dest / name, f"{label}: {m.filename}", budget - used)
            except (zipfile.BadZipFile, OSError, EOFError, NotImplementedError, RuntimeError) as exc:
                raise UploadRefused(f"{where}: cannot be unpacked ({exc}); expected a plain zip (stored or "
                                    "deflated)") from None  # fmt: skip
        return used


def unpack(files: Iterable[tuple[str, IO[bytes]]], dest: Path, limits: Limits) -> list[str]:
    """Check and write the uploaded ``files`` ((name as sent, readable binary file) each) into the
    new folder ``dest``; the names kept. On any refusal ``dest`` is removed and
    :class:`UploadRefused` says why."""
    dest.mkdir(parents=True)
    taken: set[str] = set()
    used = 0
    items = list(files)
    try:
        if not items:
            raise UploadRefused("no file in the upload; expected OpenLORIS result files (.txt) or one .zip of them")
        if len(items) > limits.files:
            raise UploadRefused(f"{len(items)} files; the challenge takes at most {limits.files}", 413)
        for sent, f in items:
            name = safe_name(sent, "upload")
            if _suffix(name, "upload", allow_zip=True) == ".zip":
                used += _unzip(f, name, dest, limits, taken, limits.unpacked_bytes - used)
                continue
            if name in taken:
                raise UploadRefused(f"upload: a second file named {name!r}; expected distinct file names")
            taken.add(name)
            used += _copy(f, dest / name, name, limits.unpacked_bytes - used)
        if not taken:
            raise UploadRefused("the archive holds no file; expected OpenLORIS result files (.txt)")
        fd = os.open(dest, os.O_RDONLY)
        try:
            os.fsync(fd)  # the folder's entries too: on disk before the database says accepted
        finally:
            os.close(fd)
    except BaseException:
        shutil.rmtree(dest, ignore_errors=True)
        raise
    return sorted(taken)
