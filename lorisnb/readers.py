"""Readers: OpenLORIS result and ground-truth files, TUM files, and the formats evo reads.

OpenLORIS format (``benchmark/README.md`` of the OpenLORIS-Scene tools)::

    scene: cafe               # header lines `key: value`; keys and spacing vary
    frame: d400_color
    seq: 1                    # one block per sequence
    aided_reloc: false        # optional per-sequence `key: value` lines
    # comment
    stamp [output_time] x y z qx qy qz qw      # 8 or 9 numbers; the pose is the last 7

The reader follows the official tool where it decides numbers: NaN poses are skipped; by default a
pose identical to the previous pose line of the file is dropped, also across a ``seq:`` boundary
(lost algorithms repeat a frozen pose); repeated or backward stamps are sorted and the last pose of
a repeated stamp kept (with a warning). A ``seq:`` block without poses is kept (it scores zero).

Files are scanned as bytes with numpy (no Python loop over pose lines); a malformed file raises
:class:`~lorisnb.errors.ParseError` naming the file, the line and what was expected.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import LorisWarning, ParseError
from .frames import FRAMES, SCENES, match_scene
from .trajectory import Trajectory

_WS = np.zeros(256, dtype=bool)
_WS[[9, 10, 11, 12, 13, 32]] = True
_QUAT_EPS = np.finfo(float).eps * 4.0  # below this squared norm a quaternion has no direction

POSE_FIELDS = "stamp [output_time] x y z qx qy qz qw"


@dataclass
class _Lines:
    """Per-line facts of a byte buffer, computed with numpy."""

    raw: bytes
    buf: np.ndarray          # uint8 view
    starts: np.ndarray       # byte offset of each line
    ends: np.ndarray         # byte offset of each line's end (its newline excluded)
    line_of: np.ndarray      # line index of each byte
    first: np.ndarray        # first non-blank byte of each line, -1 for blank lines
    first_pos: np.ndarray    # byte offset of that byte, -1 for blank lines
    has_colon: np.ndarray    # bool per line
    ntok: np.ndarray         # whitespace-separated tokens per line

    def text(self, i: int) -> str:
        return self.raw[self.starts[i]:self.ends[i]].decode("utf-8", "replace").strip()

    def numbers(self, rows: np.ndarray, path: str, expected: str) -> np.ndarray:
        """All tokens of lines ``rows`` as float64, flat; on a bad token, a ParseError for its line."""
        keep = np.zeros(len(self.starts), dtype=bool)
        keep[rows] = True
        b = self.buf.copy()
        b[~keep[self.line_of]] = 32
        toks = b.tobytes().split()
        try:
            return np.array(toks, dtype=np.float64)
        except (ValueError, TypeError):
            pass
        for i in rows:  # error path only: find the first offending line
            for tok in self.raw[self.starts[i]:self.ends[i]].split():
                try:
                    float(tok)
                except ValueError:
                    shown = tok.decode("utf-8", "replace")
                    raise ParseError(path, int(i) + 1, f"{shown!r} is not a number; expected {expected}") from None
        raise ParseError(path, None, f"could not read the numbers; expected {expected}")


def _scan(raw: bytes, separators: bytes = b"") -> _Lines:
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
    ws = _WS[buf]
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
    return _Lines(raw, buf, starts, ends, line_of, first, first_pos, has_colon, ntok)


def _stamp_fractions(lines: _Lines, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For the first token (the stamp) of each line in ``rows``: the number of digits after its
    decimal point (-1 if none) and those digits read as an integer. Vectorized over lines."""
    if rows.size == 0:
        return np.zeros(0, int), np.zeros(0, np.int64)
    buf = lines.buf
    start = lines.first_pos[rows]
    ws = np.append(np.flatnonzero(_WS[buf]), buf.size)  # sentinels: a token or fraction ends at the end
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


def _nanosecond_pattern(ndig: np.ndarray) -> np.ndarray:
    """Lines whose stamp looks like ``secs.nanosecs`` printed without zero padding: most stamps of
    the file have exactly 9 decimals and these have fewer (``1560000003.28307199`` for
    ``.028307199``). Returns a boolean mask (all False when the file does not follow the pattern)."""
    if ndig.size == 0:
        return np.zeros(0, bool)
    nine = np.mean(ndig == 9)
    short = (ndig >= 1) & (ndig < 9)
    return short if nine >= 0.5 and short.any() else np.zeros(ndig.size, bool)


def _read_bytes(path: str | os.PathLike) -> bytes:
    try:
        with open(path, "rb") as fh:
            return fh.read()
    except FileNotFoundError:
        raise ParseError(path, None, "file not found; expected a trajectory file at this path") from None
    except IsADirectoryError:
        raise ParseError(path, None, "is a folder; expected a trajectory file") from None
    except OSError as exc:
        raise ParseError(path, None, f"cannot be read ({exc.strerror})") from None


def _finish(path: str, stamps: np.ndarray, poses: np.ndarray, lines: np.ndarray, label: str,
            notes: list[str]) -> Trajectory:
    """Sort by stamp keeping the last pose of a repeated stamp (as a dict keyed by stamp would)."""
    if stamps.size > 1 and not np.all(np.diff(stamps) > 0):
        back = np.flatnonzero(np.diff(stamps) <= 0)
        i = back[0] + 1
        kind = "repeats" if stamps[i] == stamps[i - 1] else "goes backwards"
        notes.append(
            f"{path}{label}: timestamps are not increasing ({len(back)} times; first at line "
            f"{lines[i]}: {stamps[i]:.9f} {kind} after {stamps[i - 1]:.9f}); sorted them and kept "
            f"the last pose of each repeated stamp, as the official tool does"
        )
        order = np.argsort(stamps, kind="stable")
        s = stamps[order]
        last = np.concatenate((s[1:] != s[:-1], [True]))
        order = order[last]
        stamps, poses, lines = stamps[order], poses[order], lines[order]
    return Trajectory(stamps, poses[:, :3].copy(), poses[:, 3:7].copy(), lines)


def _check_rows(path: str, stamps: np.ndarray, poses: np.ndarray, lines: np.ndarray,
                notes: list[str]) -> np.ndarray:
    """Validate rows; return the mask of rows to keep (NaN poses are skipped)."""
    bad_stamp = ~np.isfinite(stamps)
    if bad_stamp.any():
        i = np.flatnonzero(bad_stamp)[0]
        raise ParseError(path, int(lines[i]), f"timestamp {stamps[i]} is not finite; expected seconds")
    finite = np.isfinite(poses).all(axis=1)
    inf_rows = ~finite & ~np.isnan(poses).any(axis=1)
    if inf_rows.any():
        notes.append(f"{path}: {int(inf_rows.sum())} pose(s) with infinite values skipped "
                     f"(first at line {lines[np.flatnonzero(inf_rows)[0]]})")
    nq = np.einsum("ij,ij->i", poses[:, 3:7], poses[:, 3:7])
    zero = finite & (nq < _QUAT_EPS)
    if zero.any():
        i = np.flatnonzero(zero)[0]
        raise ParseError(path, int(lines[i]),
                         "quaternion has zero norm; expected a rotation qx qy qz qw of unit norm")
    return finite


@dataclass
class OpenLorisFile:
    """One OpenLORIS result or ground-truth file.

    Attributes:
        path: the file.
        header: ``key: value`` lines, first occurrence of each key (as the official tool).
        header_lines: 1-based line number of each header key.
        sequences: sequence number -> Trajectory, in increasing sequence order; a sequence with
            no pose maps to an empty Trajectory.
        seq_info: sequence number -> the ``key: value`` lines inside that block (``aided_reloc``,
            ``reloc``, ...).
        seq_lines: sequence number -> line of its ``seq:`` line.
        removed_repeats: sequence number -> poses dropped as repeats of the previous pose.
        warnings: what was noticed while reading (also issued as LorisWarning).
    """

    path: Path
    header: dict[str, str]
    header_lines: dict[str, int]
    sequences: dict[int, Trajectory]
    seq_info: dict[int, dict[str, str]] = field(default_factory=dict)
    seq_lines: dict[int, int] = field(default_factory=dict)
    removed_repeats: dict[int, int] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)

    @property
    def scene(self) -> str:
        """The scene matched from the ``scene:`` header (ParseError if missing or unknown)."""
        if "scene" not in self.header:
            raise ParseError(self.path, 1, "no 'scene: NAME' header line; expected one of "
                             + ", ".join(SCENES) + " (add e.g. 'scene: cafe' at the top)")
        scene = match_scene(self.header["scene"])
        if scene is None:
            raise ParseError(self.path, self.header_lines["scene"],
                             f"unknown scene {self.header['scene']!r}; expected a name containing one of "
                             + ", ".join(SCENES))
        return scene

    @property
    def frame(self) -> str:
        """The ``frame:`` header (ParseError if missing or not a known sensor frame)."""
        if "frame" not in self.header:
            raise ParseError(self.path, 1, "no 'frame: NAME' header line; expected one of "
                             + ", ".join(FRAMES))
        frame = self.header["frame"]
        if frame not in FRAMES:
            raise ParseError(self.path, self.header_lines["frame"],
                             f"unknown frame {frame!r}; expected one of " + ", ".join(FRAMES))
        return frame

    @property
    def n_poses(self) -> int:
        return sum(len(t) for t in self.sequences.values())


def read_openloris(path: str | os.PathLike, remove_repeated: bool = True,
                   warn: bool = True, repair_stamps: bool = False) -> OpenLorisFile:
    """Read an OpenLORIS result or ground-truth file (see the module docstring).

    Args:
        path: the file.
        remove_repeated: drop a pose identical (all 7 values) to the previous pose line of the
            file, also across ``seq:`` boundaries, as the official tool does by default.
        warn: issue what was noticed as LorisWarning (it is kept in ``.warnings`` either way).
        repair_stamps: read stamps that look like nanoseconds printed without zero padding
            (``1560000003.28307199`` for ``1560000003.028307199``, written by some ROS nodes) as
            such. Off by default: the official tool uses the stamps as written, and so do its
            numbers. When the pattern is seen and this is off, a warning says so.

    Raises:
        ParseError: malformed line, pose before any ``seq:``, zero-norm quaternion, ...
    """
    spath = str(path)
    lines = _scan(_read_bytes(path))
    comment = lines.first == ord("#")
    blank = lines.first < 0
    special = np.flatnonzero(lines.has_colon & ~comment & ~blank)
    pose_rows = np.flatnonzero(~comment & ~blank & ~lines.has_colon)

    header: dict[str, str] = {}
    header_lines: dict[str, int] = {}
    seq_at: list[tuple[int, int]] = []  # (line index, seq)
    seq_info: dict[int, dict[str, str]] = {}
    notes: list[str] = []
    current: int | None = None
    for i in special:  # header and seq lines only: a handful per file
        text = lines.text(i)
        key, _, value = text.partition(":")
        key, value = key.strip(), value.strip()
        if key == "seq":
            try:
                current = int(value)
            except ValueError:
                raise ParseError(spath, int(i) + 1, f"{text!r}: expected 'seq: N' with an integer N") from None
            if any(s == current for _, s in seq_at):
                notes.append(f"{spath}: 'seq: {current}' appears again at line {i + 1}; the poses of "
                             f"its earlier block are discarded, as the official tool does")
            seq_at.append((int(i), current))
            seq_info[current] = {}
            continue
        if key == "reloc" and current is None:
            raise ParseError(spath, int(i) + 1, "'reloc:' line before any 'seq: N' line; expected it inside a block")
        if not key:
            raise ParseError(spath, int(i) + 1, f"{text!r}: expected 'key: value', 'seq: N' or a pose line")
        if key not in header:
            header[key] = value
            header_lines[key] = int(i) + 1
        if current is not None:
            seq_info[current][key] = value

    # pose lines: every line that is not blank, a comment or `key: value`
    ntok = lines.ntok[pose_rows]
    bad = (ntok != 8) & (ntok != 9)
    if bad.any():
        i = pose_rows[np.flatnonzero(bad)[0]]
        raise ParseError(spath, int(i) + 1,
                         f"{lines.text(i)[:80]!r} has {lines.ntok[i]} fields; expected 8 or 9 numbers "
                         f"'{POSE_FIELDS}', a 'key: value' line, a 'seq: N' line or a '#' comment")
    seq_line_idx = np.array([s for s, _ in seq_at], dtype=int)
    if pose_rows.size and (seq_line_idx.size == 0 or pose_rows[0] < seq_line_idx[0]):
        raise ParseError(spath, int(pose_rows[0]) + 1,
                         "pose line before any 'seq: N' line; expected 'seq: N' to open each sequence")
    values = lines.numbers(pose_rows, spath, f"numbers '{POSE_FIELDS}'")
    offs = np.cumsum(ntok) - ntok
    stamps = values[offs]
    ndig, frac = _stamp_fractions(lines, pose_rows)
    unpadded = _nanosecond_pattern(ndig)
    if unpadded.any():
        i = int(np.flatnonzero(unpadded)[0])
        tok = lines.raw[lines.first_pos[pose_rows[i]]:lines.first_pos[pose_rows[i]] + 11 + int(ndig[i])].split()[0]
        secs = np.floor(stamps[unpadded])
        if repair_stamps:
            stamps = stamps.copy()
            stamps[unpadded] = secs + frac[unpadded] * 1e-9
            notes.append(f"{spath}: repaired {int(unpadded.sum())} stamps written as nanoseconds without zero "
                         f"padding (line {pose_rows[i] + 1}: {tok.decode()} read as {secs[0]:.0f}.{int(frac[unpadded][0]):09d})")
        else:
            notes.append(
                f"{spath}: {int(unpadded.sum())} of {len(stamps)} stamps look like nanoseconds written without zero "
                f"padding (line {pose_rows[i] + 1}: {tok.decode()} probably means {secs[0]:.0f}.{int(frac[unpadded][0]):09d}); "
                "as written they are out of order. Read with repair_stamps=True (command line --repair-stamps) to "
                "fix them; off by default so that the official tool's numbers stay reproducible")
    poses = values[(offs + ntok - 7)[:, None] + np.arange(7)]
    line_no = pose_rows + 1
    keep = _check_rows(spath, stamps, poses, line_no, notes)
    # block of each pose line: the last seq line above it
    block = np.searchsorted(seq_line_idx, pose_rows, side="right") - 1 if pose_rows.size else pose_rows

    stamps, poses, line_no, block = stamps[keep], poses[keep], line_no[keep], block[keep]
    repeat = np.zeros(len(stamps), dtype=bool)
    if remove_repeated and len(stamps) > 1:
        repeat[1:] = (poses[1:] == poses[:-1]).all(axis=1)

    sequences: dict[int, Trajectory] = {}
    removed: dict[int, int] = {}
    seq_lines: dict[int, int] = {}
    for b, (li, seq) in enumerate(seq_at):  # one iteration per `seq:` block
        in_block = block == b
        sel = in_block & ~repeat
        removed[seq] = int((in_block & repeat).sum())
        seq_lines[seq] = li + 1
        sequences[seq] = _finish(spath, stamps[sel], poses[sel], line_no[sel], f", seq {seq}", notes)
    sequences = dict(sorted(sequences.items()))
    result = OpenLorisFile(Path(path), header, header_lines, sequences,
                           {k: seq_info[k] for k in sequences}, seq_lines, removed, notes)
    if warn:
        for note in notes:
            warnings.warn(note, LorisWarning, stacklevel=2)
    return result


def read_tum(path: str | os.PathLike, warn: bool = True) -> Trajectory:
    """Read a TUM RGB-D trajectory: lines ``stamp tx ty tz qx qy qz qw`` (seconds, metres,
    quaternion xyzw), ``#`` comments; spaces, tabs or commas separate the values.

    Non-finite poses are skipped and unsorted or repeated stamps sorted (keeping the last), with a
    warning. Raises ParseError for a malformed line or a zero-norm quaternion.
    """
    spath = str(path)
    lines = _scan(_read_bytes(path), separators=b",")
    comment = lines.first == ord("#")
    blank = lines.first < 0
    rows = np.flatnonzero(~comment & ~blank)
    ntok = lines.ntok[rows]
    bad = ntok != 8
    if bad.any():
        i = rows[np.flatnonzero(bad)[0]]
        raise ParseError(spath, int(i) + 1, f"{lines.text(i)[:80]!r} has {lines.ntok[i]} fields; expected 8 "
                         "numbers 'stamp tx ty tz qx qy qz qw' (TUM format) or a '#' comment")
    values = lines.numbers(rows, spath, "numbers 'stamp tx ty tz qx qy qz qw'").reshape(-1, 8)
    notes: list[str] = []
    line_no = rows + 1
    keep = _check_rows(spath, values[:, 0], values[:, 1:], line_no, notes)
    nan_rows = int((~keep).sum())
    if nan_rows:
        notes.append(f"{spath}: {nan_rows} pose(s) with NaN or infinite values skipped")
    traj = _finish(spath, values[keep, 0], values[keep, 1:], line_no[keep], "", notes)
    if warn:
        for note in notes:
            warnings.warn(note, LorisWarning, stacklevel=2)
    return traj


def _from_evo(traj, path: str, first_line: int = 1) -> Trajectory:
    """A trajectory read by evo, checked: finite values and proper rotations (determinant 1);
    pose k is reported at line ``first_line + k``."""
    from scipy.spatial.transform import Rotation

    poses = np.asarray(traj.poses_se3, dtype=float).reshape(-1, 4, 4)
    stamps = np.asarray(getattr(traj, "timestamps", np.arange(len(poses), dtype=float)), dtype=float)
    with np.errstate(all="ignore"):
        det = np.linalg.det(poses[:, :3, :3]) if len(poses) else np.zeros(0)
        ortho = np.abs(np.einsum("nij,nkj->nik", poses[:, :3, :3], poses[:, :3, :3]) - np.eye(3)).max(axis=(1, 2)) \
            if len(poses) else np.zeros(0)
    bad = ~np.isfinite(poses).all(axis=(1, 2)) | ~np.isfinite(stamps) | (np.abs(det - 1) > 1e-3) | (ortho > 1e-3)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise ParseError(path, first_line + k, "not a rotation (non-finite values, or a rotation block that is not "
                         "orthonormal with determinant 1); expected a pose")
    rot = Rotation.from_matrix(poses[:, :3, :3]) if len(poses) else Rotation.identity(0)
    return Trajectory(stamps, poses[:, :3, 3].copy(), rot.as_quat() if len(poses) else np.zeros((0, 4)), None,
                      {"source": path})


def read_kitti(path: str | os.PathLike, stamps: np.ndarray | str | os.PathLike | None = None) -> Trajectory:
    """Read a KITTI pose file (one 3x4 matrix per line, row-major) through evo's file interface.

    KITTI files carry no stamps: pass ``stamps`` (an array, or a times file with one stamp per
    line as KITTI's ``times.txt``); without them the pose index is used as the stamp, and poses
    are paired by index as evo does.
    """
    from evo.tools import file_interface

    try:
        traj = file_interface.read_kitti_poses_file(str(path))
    except Exception as exc:  # evo raises its own FileInterfaceException or numpy errors
        raise ParseError(path, None, f"not a KITTI pose file (evo says: {exc}); expected 12 numbers "
                         "per line, a 3x4 matrix row-major") from None
    out = _from_evo(traj, str(path))
    if stamps is None:
        return out
    if isinstance(stamps, (str, os.PathLike)):
        t = read_times(stamps)
    else:
        t = np.asarray(stamps, dtype=float)
    if len(t) != len(out):
        raise ParseError(path, None, f"{len(out)} poses but {len(t)} stamps; expected one stamp per pose")
    return Trajectory(t, out.positions, out.quaternions, None, out.meta)


def read_times(path: str | os.PathLike) -> np.ndarray:
    """Read a times file: one stamp (seconds) per line, ``#`` comments allowed."""
    spath = str(path)
    lines = _scan(_read_bytes(path))
    rows = np.flatnonzero((lines.first >= 0) & (lines.first != ord("#")))
    bad = lines.ntok[rows] != 1
    if bad.any():
        i = rows[np.flatnonzero(bad)[0]]
        raise ParseError(spath, int(i) + 1, f"{lines.text(i)[:80]!r}: expected one stamp per line")
    return lines.numbers(rows, spath, "one stamp in seconds per line")


def read_euroc(path: str | os.PathLike) -> Trajectory:
    """Read a EuRoC ground-truth CSV (``state_groundtruth_estimate0/data.csv``: stamp in ns,
    position, quaternion ``w x y z``, ...) through evo's file interface; stamps in seconds."""
    from evo.tools import file_interface

    try:
        traj = file_interface.read_euroc_csv_trajectory(str(path))
    except Exception as exc:
        raise ParseError(path, None, f"not a EuRoC CSV (evo says: {exc}); expected "
                         "'#timestamp,p_x,p_y,p_z,q_w,q_x,q_y,q_z,...' rows") from None
    return _from_evo(traj, str(path), first_line=2)


TRAJECTORY_FORMATS = ("tum", "kitti", "euroc", "openloris")


def read_trajectory(path: str | os.PathLike, fmt: str = "tum", seq: int | None = None,
                    stamps: np.ndarray | str | os.PathLike | None = None) -> Trajectory:
    """Read one trajectory in any supported format.

    Args:
        fmt: ``tum``, ``kitti``, ``euroc`` or ``openloris`` (for OpenLORIS, ``seq`` picks the
            sequence; default the lowest-numbered one).
        stamps: KITTI only: stamps or a times file (see :func:`read_kitti`).
    """
    if fmt == "tum":
        return read_tum(path)
    if fmt == "kitti":
        return read_kitti(path, stamps)
    if fmt == "euroc":
        return read_euroc(path)
    if fmt == "openloris":
        f = read_openloris(path)
        if not f.sequences:
            raise ParseError(path, None, "no 'seq: N' block; expected at least one sequence")
        key = min(f.sequences) if seq is None else seq
        if key not in f.sequences:
            raise ParseError(path, None, f"no sequence {key}; the file has {sorted(f.sequences)}")
        return f.sequences[key]
    raise ValueError(f"unknown format {fmt!r}; expected one of {', '.join(TRAJECTORY_FORMATS)}")
