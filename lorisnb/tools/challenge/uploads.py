"""An upload, checked before anything is kept: result files in a format lorisnb reads, or one
``.zip`` of them. OpenLORIS result files (``.txt``) name their scene and sequences in their headers;
TUM and EuRoC files (``.txt``, ``.csv``) name their sequence by their file name, as OpenLORIS names
sequences (``cafe-1-2.txt``), and their format is recognised from their content
(:mod:`lorisnb.io.readers.registry`) or given for the whole upload (:func:`upload_format`);
:func:`plan` says how each is scored. KITTI pose files (no stamps: the correct rate is taken over
time) and ROS bags are refused, saying what to send instead.

Refused, each with a message naming the file and what was expected: archive members with a path
that leaves the folder (``../``, absolute, drive letters), links, encrypted members, archives
nested in archives, zip bombs (declared or actual unpacked size over the limit, or a compression
ratio no result file has), too many files, binary or empty files, two files of the same name.
Nothing from an upload is ever executed: the files are only read by the scorer.
"""

from __future__ import annotations

import codecs
import json
import os
import re
import shutil
import stat
import string
import threading
import unicodedata
import warnings
import zipfile
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from lorisnb.core.spec.evalspec import EvalSpec
from lorisnb.core.stats.trials import names_a_trial, split_trial
from lorisnb.core.trajectory.frames import SCENES
from lorisnb.errors import LorisError
from lorisnb.io.parsing.scanner import wide_text
from lorisnb.io.readers.openloris import declared_scene
from lorisnb.io.readers.registry import FORMATS, recognise, sample

#: A member more compressed than this is a bomb, not a result file (text of poses compresses ~3-5x).
MAX_RATIO = 100
#: Bytes read at a time.
CHUNK = 1 << 16
#: What a file name kept from an upload is made of (:func:`safe_name`, :func:`name_fault`): its
#: first character one of :data:`NAME_FIRST`, the others of :data:`NAME_REST`, at most
#: :data:`NAME_MAX` characters. The check and the message that states it (:data:`NAME_RULE`) are
#: both made from these.
NAME_FIRST = string.ascii_letters + string.digits
NAME_REST = NAME_FIRST + " _.,+=@()-"
NAME_MAX = 200
#: The suffixes of result files taken (an archive's members too).
SUFFIXES = (".txt", ".csv")
#: What an upload may hold, in words (every refusal of a file's kind ends with it).
TAKEN = ("result files in a format lorisnb reads: OpenLORIS result files (.txt), or TUM (.txt, .csv) or EuRoC "
         "CSV (.csv) files named after their sequence as OpenLORIS names it (cafe-1-2.txt)")  # fmt: skip
#: The upload's ``format`` field: ``auto`` (each file's own, recognised from its content) or the
#: format every file of the upload is read in.
UPLOAD_FORMATS = ("auto", "openloris", "tum", "euroc")
#: Formats lorisnb reads that a challenge cannot score, and what to send instead.
NOT_TAKEN = {
    "kitti": "a KITTI pose file holds no stamps, and the correct rate (CR) is taken over time: write the poses "
             "with their stamps as a TUM file named after its sequence (cafe-1-2.txt, lines 'stamp tx ty tz qx qy "
             "qz qw') or as an OpenLORIS result file",
    "bag": "the challenge takes no ROS bags (a bag holds topics and TF frames to choose from, and a recording): write "
           "the estimate's poses as a TUM file named after its sequence (e.g. evo_traj bag FILE TOPIC --save_as_tum, "
           "renamed cafe-1-2.txt) or as an OpenLORIS result file",
}  # fmt: skip
#: A plain trajectory file's name naming its sequence as OpenLORIS does: ``<scene>-1-<seq>``,
#: ``-`` or ``_``, anything after a further separator (``cafe_1_2_orbslam2.txt``, ``cafe-1-2_trial2.csv``).
#: A submission's plan (:func:`plan`), beside its ``files`` folder: read by the scorer.
PLAN = "plan.json"
SEQUENCE_NAME = re.compile(r"(?P<scene>[A-Za-z]+)[-_]1[-_](?P<seq>[0-9]{1,3})(?:[-_.].*)?", re.DOTALL)  # fullmatch


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
    its last part; refused if any part climbs out, is absolute or hidden, or has odd characters,
    and an uploaded file without a name (a browser's form sent with no file chosen)."""
    if not name:
        if where == "upload":
            raise UploadRefused(f"no file chosen; choose the files to upload: {TAKEN}, or one .zip of them")
        raise UploadRefused(f"{where}: a member without a name; expected named result files")
    if "\x00" in name or any(ord(c) < 32 for c in name):
        raise UploadRefused(f"{where}: {name!r}: a file name with control characters; expected a plain name")
    if "\\" in name or re.match(r"^[A-Za-z]:", name):
        raise UploadRefused(f"{where}: {name!r}: a Windows path; expected names with '/' and no drive letter")
    if name.startswith("/"):  # what is expected, for the case at hand: an uploaded file's name, or a member's path
        inside = ("the file's name (cafe-1-1.txt), or a path relative to the upload (run_1/cafe-1-1.txt)"
                  if where == "upload" else "a path inside the archive")  # fmt: skip
        raise UploadRefused(f"{where}: {name!r}: an absolute path; expected {inside}")
    parts = [p for p in name.split("/") if p not in ("", ".")]
    if ".." in parts:
        raise UploadRefused(f"{where}: {name!r}: a path that climbs out of the folder ('..'); refused")
    if not parts:
        raise UploadRefused(f"{where}: {name!r}: no file name")
    base = parts[-1]
    fault = name_fault(base)
    if fault:
        fixed = _name_fixed(base)
        hidden = base.startswith(".")  # .DS_Store and the like: left out, not renamed
        rename = f"; rename it {fixed!r}" if fixed and not hidden and not name_fault(fixed) else ""
        raise UploadRefused(f"{where}: {base!r}: {fault}; expected {NAME_RULE}{rename}")
    return base


#: The names :func:`safe_name` takes, in words (from :data:`NAME_FIRST`, :data:`NAME_REST` and
#: :data:`NAME_MAX`, the definition it checks).
NAME_RULE = (
    f"a name of 1 to {NAME_MAX} characters: an ASCII letter or digit (A-Z, a-z, 0-9) first, then ASCII letters, "
    "digits, spaces and " + ", ".join(f"'{c}'" for c in NAME_REST if c not in NAME_FIRST and c != " ")
)


def _said(c: str) -> str:
    """A character as a message names it: a space in words, another by itself (quoted), with its
    code point where it is not plain ASCII."""
    if c == " ":
        return "a space"
    if c.isascii() and c.isprintable():
        return repr(c)
    name = unicodedata.name(c, "")
    return f"{c!r} (U+{ord(c):04X}{', ' + name if name and not c.isprintable() else ''})"


def name_fault(base: str) -> str | None:
    """What makes ``base`` a name :func:`safe_name` refuses, naming the first character at fault
    and its position (1 for the first); None for a name it takes."""
    if not base:
        return "no file name"
    if base[0] not in NAME_FIRST:
        what = " (a hidden file: leave it out of the upload)" if base[0] == "." else ""
        return f"character 1 is {_said(base[0])}{what}, which cannot start a name"
    for k, c in enumerate(base[1:], start=2):
        if c not in NAME_REST:
            return f"character {k} is {_said(c)}, which a name cannot hold"
    if len(base) > NAME_MAX:
        return f"{len(base)} characters long"
    return None


def _name_fixed(base: str) -> str:
    """``base`` as it could be renamed: each letter without its accents (Unicode NFKD, the
    combining marks dropped: ``café-1-1.txt`` as ``cafe-1-1.txt``, the name of its sequence), without
    the characters before its first letter or digit, each other character a name cannot hold as '_'."""
    plain = "".join(c for c in unicodedata.normalize("NFKD", base) if not unicodedata.combining(c))
    start = next((k for k, c in enumerate(plain) if c in NAME_FIRST), len(plain))
    return "".join(c if c in NAME_REST else "_" for c in plain[start:])


#: The largest trial number a file's name may carry (``cafe-1-1_trial3.txt``, ``run_3/``): the
#: tables scores are kept in hold it in 64 bits (a run named for its epoch time in nanoseconds fits).
MAX_TRIAL = 2**63 - 1


def kept_name(path: str, where: str) -> str:
    """The name an uploaded file (``path``: as sent, or an archive member's path) is kept and scored
    under: its last part (:func:`safe_name`), its suffix in lower case (the scorer's folder walk reads
    ``.txt`` and ``.csv`` as written: ``CAFE-1-1.TXT`` kept as ``CAFE-1-1.txt``), and a trial its
    folders name (``run_2/a.txt``, ``trial3/cafe-1-1.txt``; :func:`~lorisnb.core.stats.trials.split_trial`)
    in its name (``a_trial2.txt``), where its name names none: ``lorisnb evaluate`` reads such folders
    as trials 1, 2, ..., and so is the upload scored. A trial number over :data:`MAX_TRIAL` is refused."""
    base = safe_name(path, where)
    stem, suffix = (base[: -len(Path(base).suffix)], Path(base).suffix) if Path(base).suffix else (base, "")
    name = stem + suffix.lower()
    parts = [p for p in path.split("/") if p not in ("", ".")]
    try:  # the file name's trial, else its folders'
        trial = split_trial("/".join(parts) if not names_a_trial(base) else base)[1]
        digits = str(trial) if trial > MAX_TRIAL else ""
    except LorisError:  # a number too long to read as one (over 4300 digits): too large too
        trial, digits = MAX_TRIAL + 1, max(re.findall(r"[0-9]+", path), key=len, default="")
    if trial > MAX_TRIAL:
        number = digits if len(digits) <= 40 else f"{digits[:20]}... ({len(digits)} digits)"
        raise UploadRefused(f"{where}: {path!r}: trial number {number}, too large; expected a trial number of at most "
                            f"{MAX_TRIAL} (cafe-1-2_trial2.txt, run_2/)")  # fmt: skip
    if trial and not names_a_trial(base):  # a trial its folders name: in its name
        name = safe_name(f"{stem}_trial{trial}{suffix.lower()}", where)
    return name


def _check_text(head: bytes, name: str) -> None:
    """Refuse a file whose first chunk is blank or holds a NUL byte: text in UTF-16 or UTF-32 (the
    readers' rule, :func:`~lorisnb.io.parsing.scanner.wide_text`), else binary."""
    if not head.strip():
        raise UploadRefused(f"{name}: empty; expected poses: {TAKEN}")
    if b"\x00" in head and wide_text(head):
        raise UploadRefused(f"{name}: text in UTF-16 or UTF-32 (NUL bytes between the characters); save it as "
                            "UTF-8 and upload it again")  # fmt: skip
    if b"\x00" in head:
        raise UploadRefused(f"{name}: a binary file; expected text: {TAKEN}")


class _Utf8:
    """A file's bytes checked as UTF-8 chunk by chunk (a character cut at a chunk's end is
    decoded with the next chunk's bytes; one cut at the file's end is refused)."""

    def __init__(self, name: str):
        self.name = name
        self.decoder = codecs.getincrementaldecoder("utf-8")()
        self.seen = 0  # bytes given before this chunk

    def __call__(self, chunk: bytes, final: bool = False) -> None:
        pending = len(self.decoder.getstate()[0])
        try:
            self.decoder.decode(chunk, final)
        except UnicodeDecodeError as exc:
            at = self.seen - pending + exc.start
            raise UploadRefused(f"{self.name}: not UTF-8 text (byte {at}); expected {TAKEN}") from None
        self.seen += len(chunk)


def _suffix(name: str, where: str, allow_zip: bool) -> str:
    suffix = Path(name).suffix.lower()
    if suffix in SUFFIXES or (allow_zip and suffix == ".zip"):
        return suffix
    if suffix in FORMATS["bag"].suffixes:
        raise UploadRefused(f"{where}: {name!r}: a ROS bag; {NOT_TAKEN['bag']}", 415)
    if suffix == ".zip":
        raise UploadRefused(f"{where}: {name!r}: an archive inside the archive; expected {TAKEN}, in one .zip", 415)
    what = f"{TAKEN}, or one .zip of them" if allow_zip else TAKEN
    raise UploadRefused(f"{where}: {name!r}: a {suffix or 'file without suffix'}; expected {what}", 415)


def upload_format(value: object) -> str:
    """The upload's ``format`` field, checked: ``auto`` (also when not given) or one of
    :data:`UPLOAD_FORMATS`; a format the challenge cannot score is refused saying why."""
    if value is None or (isinstance(value, str) and not value.strip()):
        return "auto"
    if not isinstance(value, str):
        raise UploadRefused("format: a file was sent as the format; expected a format name (auto, tum, ...)")
    fmt = value.strip().lower()
    if fmt in UPLOAD_FORMATS:
        return fmt
    if fmt in NOT_TAKEN:
        raise UploadRefused(f"format {fmt}: {NOT_TAKEN[fmt]}", 415)
    raise UploadRefused(f"format {value[:40]!r}: expected auto (each file's format recognised from its content), "
                        "openloris, tum or euroc")  # fmt: skip


def sequence_of(name: str) -> tuple[str, int] | None:
    """The (scene, sequence) a file's name names as OpenLORIS names sequences (``cafe-1-2.txt``:
    cafe, 2); None if it names none."""
    m = SEQUENCE_NAME.fullmatch(Path(name).stem)
    return (m["scene"].lower(), int(m["seq"])) if m else None


def not_ours(where: str, scene: str, seq: int, have: Iterable[tuple[str, int]]) -> UploadRefused | None:
    """The refusal of a file (``where``: its name, and the line naming the sequence) that names the
    sequence ``scene``-1-``seq``, when it is not one of the challenge's sequences ``have`` (scene,
    seq); None when it is. One rule and one message for every format: a TUM or EuRoC file's name,
    an OpenLORIS file's ``scene:`` and ``seq: N`` lines (such a sequence has no ground truth to score
    it against, or none a phase shows: it would fail at scoring, and count as a submission)."""
    listed = sorted(set(have))
    if (scene, seq) in listed:
        return None
    said = ", ".join(f"{s}-1-{q}" for s, q in listed)
    return UploadRefused(f"{where}: names sequence {scene}-1-{seq}, which is not one of this challenge's; expected "
                         f"one of {said}")  # fmt: skip


def plan(folder: Path, names: list[str], fmt: str, sequences: Iterable[tuple[str, int]]) -> dict[str, dict[str, Any]]:
    """How each kept file is scored: OpenLORIS result files (recognised by their headers, or all
    files with ``fmt`` openloris) as ``lorisnb evaluate`` scores them, not listed here; TUM and
    EuRoC files listed, ``name -> {format, scene, seq}``, the sequence named by the file's name and
    one of the challenge's ``sequences`` (scene, seq). Refused (:class:`UploadRefused`): KITTI
    files and bags (:data:`NOT_TAKEN`), a file of no format lorisnb recognises (unless ``fmt``
    names one), a file plainly of another format than ``fmt``, a TUM or EuRoC file whose name
    names no sequence of the challenge, an OpenLORIS file whose ``scene:`` header names a scene
    not in the challenge (it would be scored as no output at all, and count as a submission)."""
    have = sorted(set(sequences))
    out: dict[str, dict[str, Any]] = {}
    for name in names:
        found = recognise(sample(folder / name))
        if found and found[0] in NOT_TAKEN:
            raise UploadRefused(f"{name}: {FORMATS[found[0]].looks()}; {NOT_TAKEN[found[0]]}", 415)
        if fmt != "auto" and found and fmt not in found:
            raise UploadRefused(f"{name}: {FORMATS[found[0]].looks()}, but the upload's format is {fmt}; send it "
                                f"with the format auto (each file's own is recognised) or {found[0]}", 415)  # fmt: skip
        kind = fmt if fmt != "auto" else found[0] if found else None
        if kind is None:
            raise UploadRefused(f"{name}: not recognised as any format lorisnb reads; expected {TAKEN}. A file of one "
                                "of them it does not recognise (its first lines are checked): give the upload's format "
                                "(openloris, tum or euroc: the form's format field, lorisnb submit --format) to have "
                                "every line read", 415)  # fmt: skip
        if kind == "openloris":  # its scene: at a look now (read whole, its seq: lines too, by read_upload)
            scene = declared_scene(folder / name)
            if scene is not None:
                _check_scene(name, scene, have)
            continue
        seq = sequence_of(name)
        title = FORMATS[kind].title
        if seq is None:
            example = f"{have[-1][0]}-1-{have[-1][1]}" if have else "cafe-1-2"
            raise UploadRefused(f"{name}: a {title} names no sequence; expected its name to name it as OpenLORIS "
                                f"names sequences, <scene>-1-<seq> (e.g. {example}{Path(name).suffix}), or an "
                                "OpenLORIS result file (scene:, frame: and seq: N blocks)")  # fmt: skip
        refused = not_ours(name, seq[0], seq[1], have)
        if refused is not None:
            raise refused
        out[name] = dict(format=kind, scene=seq[0], seq=seq[1])
    return out


#: The largest position coordinate (metres) and stamp (seconds) an uploaded file may hold: no
#: trajectory reaches 1e12 m, and stamps in nanoseconds are about 1.6e18 (said by the scorer: divide
#: them by 1e9); beyond, the scorer's sums of squares overflow (1e308 gave numpy's 'overflow
#: encountered' as notes, and errors of inf).
MAX_COORDINATE = 1e12
MAX_STAMP = 1e30


def read_upload(folder: Path, names: list[str], layout: Mapping[str, Mapping[str, Any]],
                spec: EvalSpec | None = None, sequences: Iterable[tuple[str, int]] | None = None) -> None:  # fmt: skip
    """Read every kept file whole with the reader the scorer reads it with (``layout``: the
    :func:`plan`; a file not in it is an OpenLORIS result file, read by
    :func:`.scoring.read_result`, the one reading :func:`.scoring.score_folder` reads it by: every
    line, its ``scene:`` and ``frame:`` values, its ``seq:`` blocks), under the rules of ``spec``
    (default: lorisnb's), so that a file the scorer would refuse is refused at upload, naming the
    file and the line (:class:`~lorisnb.errors.LorisError`, the reader's words). An OpenLORIS
    file's ``seq: N`` naming a sequence not of the challenge's ``sequences`` (scene, seq; None: not
    checked) is refused as a TUM file named for it is (:func:`not_ours`), naming its line. A
    position coordinate over :data:`MAX_COORDINATE` m or a stamp over :data:`MAX_STAMP` s is
    refused too, naming the pose by its stamp."""
    have = None if sequences is None else sorted(set(sequences))
    with READING:  # one upload read at a time: its memory is the server's, not a limited scorer's
        _read_each(folder, names, layout, spec, have)


#: Uploads read at once by :func:`read_upload` (in the server's process, outside the scorer's memory
#: limit): one, so that many teams' large files at the same moment hold one file's arrays, not all.
READING = threading.BoundedSemaphore(1)


def _read_each(folder: Path, names: list[str], layout: Mapping[str, Mapping[str, Any]], spec: EvalSpec | None,
               have: list[tuple[str, int]] | None) -> None:  # fmt: skip
    """:func:`read_upload`'s reading of each file."""
    from lorisnb.io.readers.plain import read_trajectory
    from lorisnb.tools.challenge.scoring import read_result

    for name in names:
        path = folder / name
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # notes are the scorer's to say; only refusals here
            if name in layout:
                kind = str(layout[name]["format"])
                rule = spec.repeated_for(kind) if spec is not None else "drop"
                trajectories = [read_trajectory(path, kind, repeated=rule)]
            else:
                result, blocks = read_result(path, spec)
                if have is not None:
                    _check_blocks(name, blocks, have)
                trajectories = list(result.sequences.values())
        for t in trajectories:
            _check_values(name, t.stamps, t.positions)


def _check_scene(name: str, scene: str, have: Iterable[tuple[str, int]]) -> None:
    """Refuse an OpenLORIS file whose ``scene:`` header names ``scene``, not one of the scenes of the
    challenge's sequences ``have`` (it would be scored as no output at all, and count as a submission)."""
    scenes = sorted({s for s, _ in have}, key=SCENES.index)
    if scene not in scenes:
        raise UploadRefused(f"{name}: an OpenLORIS result file of {scene} (its scene: header), which is not "
                            f"one of this challenge's scenes; expected {' or '.join(scenes)}")  # fmt: skip


def _check_blocks(name: str, blocks: Any, have: list[tuple[str, int]]) -> None:
    """Refuse an OpenLORIS file (its :class:`.scoring.Blocks`) of a scene not in the challenge, or
    with a ``seq: N`` line naming a sequence not of the challenge's ``have``, naming its line."""
    _check_scene(name, blocks.scene, have)
    for line, seq in blocks.seqs:
        refused = not_ours(f"{name}, line {line}: 'seq: {seq}'", blocks.scene, seq, have)
        if refused is not None:
            raise refused


def _check_values(name: str, stamps: Any, positions: Any) -> None:
    """Refuse poses whose position or stamp is too large to compute with (:data:`MAX_COORDINATE`,
    :data:`MAX_STAMP`), naming the first by its stamp."""
    import numpy as np

    over = np.flatnonzero((np.abs(positions) > MAX_COORDINATE).any(axis=1) | (np.abs(stamps) > MAX_STAMP))
    if over.size:
        k = int(over[0])
        big = float(np.abs(positions[k]).max())
        what = (f"a position coordinate of {big:.3g} m, over {MAX_COORDINATE:g} m" if big > MAX_COORDINATE
                else f"a stamp over {MAX_STAMP:g} s")  # fmt: skip
        raise UploadRefused(f"{name}: the pose at stamp {float(stamps[k]):.6g} ({over.size} pose(s) in all) has {what}: "
                            "too large to compute errors with; expected positions in metres and stamps in seconds")  # fmt: skip


def _copy(src: IO[bytes], dest: Path, name: str, budget: int) -> int:
    """Copy ``src`` to ``dest`` reading at most ``budget`` bytes (refused beyond); bytes copied."""
    n = 0
    with open(dest, "xb") as out:
        head = src.read(CHUNK)
        _check_text(head, name)
        utf8 = _Utf8(name)
        while head:
            n += len(head)
            if n > budget:
                raise UploadRefused(f"{name}: unpacks to more than the challenge's limit of {budget_mb(budget)}", 413)
            utf8(head)
            out.write(head)
            head = src.read(CHUNK)
        utf8(b"", final=True)
        out.flush()
        os.fsync(out.fileno())
    return n


def budget_mb(n: int) -> str:
    return f"{n / 1e6:g} MB"


def _unzip(src: IO[bytes], label: str, dest: Path, limits: Limits, taken: dict[str, tuple[str, str]],
           budget: int) -> int:  # fmt: skip
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
            _suffix(safe_name(m.filename, label), where, allow_zip=False)
            name = kept_name(m.filename, where)
            if m.compress_size and m.file_size / m.compress_size > MAX_RATIO:
                raise UploadRefused(f"{where}: compressed {m.file_size / m.compress_size:.0f} times (a zip bomb?); "
                                    f"result files compress at most {MAX_RATIO} times", 413)  # fmt: skip
            _take(taken, name, m.filename, label)
            try:
                with archive.open(m) as f:
                    used += _copy(f, dest / name, f"{label}: {m.filename}", budget - used)
            except (zipfile.BadZipFile, OSError, EOFError, NotImplementedError, RuntimeError) as exc:
                raise UploadRefused(f"{where}: cannot be unpacked ({exc}); expected a plain zip (stored or "
                                    "deflated)") from None  # fmt: skip
        return used


def _take(taken: dict[str, tuple[str, str]], name: str, path: str, where: str) -> None:
    """Keep ``path`` (as sent, in ``where``: ``upload`` or its archive) under ``name``
    (:func:`kept_name`); refused if a file before it is kept under that name, naming both as sent
    (each with its own archive, when they came in two) and why each is kept under that name."""
    if name not in taken:
        taken[name] = (path, where)
        return
    first, first_where = taken[name]
    why = [f"{p!r} is kept as {name!r} ({_renamed(p, name)})" for p in dict.fromkeys((first, path))
           if Path(p).name != name]  # fmt: skip
    both = (
        f"{where}: {first!r} and {path!r}"
        if first_where == where
        else f"{first_where}: {first!r} and {where}: {path!r}"
    )
    raise UploadRefused(f"{both}: a second file named {name!r}{': ' + '; '.join(why) if why else ''}; expected "
                        "distinct file names")  # fmt: skip


def _renamed(path: str, name: str) -> str:
    """Why ``path`` is kept as ``name`` (:func:`kept_name`), in words."""
    said = []
    if Path(path).suffix != Path(name).suffix:
        said.append("its suffix in lower case")
    if not names_a_trial(Path(path).name) and names_a_trial(name):
        said.append(f"trial {split_trial(name)[1]}, which its folder names, in its name")
    return " and ".join(said) or "its last part"


def unpack(files: Iterable[tuple[str, IO[bytes]]], dest: Path, limits: Limits) -> list[str]:
    """Check and write the uploaded ``files`` ((name as sent, readable binary file) each) into the
    new folder ``dest``; the names kept. On any refusal ``dest`` is removed and
    :class:`UploadRefused` says why."""
    dest.mkdir(parents=True)
    taken: dict[str, tuple[str, str]] = {}  # name kept -> the path it was sent as, and where (upload, its .zip)
    used = 0
    items = list(files)
    try:
        if not items:
            raise UploadRefused(f"no file in the upload; expected {TAKEN}, or one .zip of them")
        if len(items) > limits.files:
            raise UploadRefused(f"{len(items)} files; the challenge takes at most {limits.files}", 413)
        for sent, f in items:
            name = safe_name(sent, "upload")
            if _suffix(name, "upload", allow_zip=True) == ".zip":
                used += _unzip(f, name, dest, limits, taken, limits.unpacked_bytes - used)
                continue
            name = kept_name(sent, "upload")
            _take(taken, name, sent, "upload")
            used += _copy(f, dest / name, name, limits.unpacked_bytes - used)
        if not taken:
            raise UploadRefused(f"the archive holds no file; expected {TAKEN}")
        _fsync_folder(dest)
    except BaseException:
        shutil.rmtree(dest, ignore_errors=True)
        raise
    return sorted(taken)


def _fsync_folder(folder: Path) -> None:
    fd = os.open(folder, os.O_RDONLY)
    try:
        os.fsync(fd)  # the folder's entries too: on disk before the database says accepted
    finally:
        os.close(fd)


def keep_upload(files: Iterable[tuple[str, IO[bytes]]], folder: Path, limits: Limits, fmt: str,
                sequences: Iterable[tuple[str, int]], spec: EvalSpec | None = None) -> list[str]:  # fmt: skip
    """:func:`unpack` the upload into ``folder/files``, write its :func:`plan` (``folder/plan.json``,
    when some file is not an OpenLORIS result file), both on disk before it returns, and read every
    file whole as the scorer reads it with ``spec`` (:func:`read_upload`); the names kept.
    Any :class:`~lorisnb.errors.LorisError` of reading the upload is an :class:`UploadRefused` (400,
    its message naming the file and line, the server's paths taken out). On a refusal the caller
    removes ``folder``."""
    sequences = list(sequences)  # the plan's check and the reading's
    try:
        names = unpack(files, folder / "files", limits)
        layout = plan(folder / "files", names, fmt, sequences)
        read_upload(folder / "files", names, layout, spec, sequences)
    except UploadRefused:
        raise
    except LorisError as exc:  # any other refusal of reading the upload: the team's words, no server path
        text = str(exc).replace(f"{folder / 'files'}{os.sep}", "").replace(str(folder), "the upload")
        raise UploadRefused(text) from None
    if layout:
        with open(folder / PLAN, "x", encoding="utf-8") as out:
            json.dump(layout, out)
            out.flush()
            os.fsync(out.fileno())
        _fsync_folder(folder)
    return names
