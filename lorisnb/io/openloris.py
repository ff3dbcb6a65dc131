"""Reader of OpenLORIS result and ground-truth files.

Format (``benchmark/README.md`` of the OpenLORIS-Scene tools)::

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
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np

from ..core.model import ResultFile
from ..core.trajectory import Trajectory
from ..errors import LorisWarning, ParseError
from .scanner import check_rows, finish, nanosecond_pattern, read_bytes, scan, stamp_fractions

POSE_FIELDS = "stamp [output_time] x y z qx qy qz qw"


def read_openloris(
    path: str | os.PathLike, remove_repeated: bool = True, warn: bool = True, repair_stamps: bool = False
) -> ResultFile:
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
    lines = scan(read_bytes(path, "an OpenLORIS trajectory file ('scene:', 'frame:', 'seq: N' blocks of poses)"))
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
    for i in map(int, special):  # header and seq lines only: a handful per file
        text = lines.text(i)
        key, _, value = text.partition(":")
        key, value = key.strip().lower(), value.strip()  # keys in any case: 'Scene: cafe'
        if key == "seq":
            try:
                current = int(value)
            except ValueError:
                raise ParseError(spath, int(i) + 1, f"{text!r}: expected 'seq: N' with an integer N") from None
            if any(s == current for _, s in seq_at):
                notes.append(
                    f"{spath}: 'seq: {current}' appears again at line {i + 1}; the poses of "
                    f"its earlier block are discarded, as the official tool does"
                )
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
        raise ParseError(
            spath,
            int(i) + 1,
            f"{lines.text(i)[:80]!r} has {lines.ntok[i]} fields; expected 8 or 9 numbers "
            f"'{POSE_FIELDS}', a 'key: value' line, a 'seq: N' line or a '#' comment",
        )
    seq_line_idx = np.array([s for s, _ in seq_at], dtype=int)
    if pose_rows.size and (seq_line_idx.size == 0 or pose_rows[0] < seq_line_idx[0]):
        raise ParseError(
            spath, int(pose_rows[0]) + 1, "pose line before any 'seq: N' line; expected 'seq: N' to open each sequence"
        )
    values = lines.numbers(pose_rows, spath, f"numbers '{POSE_FIELDS}'")
    offs = np.cumsum(ntok) - ntok
    stamps = values[offs]
    ndig, frac = stamp_fractions(lines, pose_rows)
    unpadded = nanosecond_pattern(ndig)
    if unpadded.any():
        i = int(np.flatnonzero(unpadded)[0])
        tok = lines.raw[lines.first_pos[pose_rows[i]] : lines.first_pos[pose_rows[i]] + 11 + int(ndig[i])].split()[0]
        secs = np.floor(stamps[unpadded])
        if repair_stamps:
            stamps = stamps.copy()
            stamps[unpadded] = secs + frac[unpadded] * 1e-9
            notes.append(
                f"{spath}: repaired {int(unpadded.sum())} stamps written as nanoseconds without zero "
                f"padding (line {pose_rows[i] + 1}: {tok.decode()} read as {secs[0]:.0f}.{int(frac[unpadded][0]):09d})"
            )
        else:
            notes.append(
                f"{spath}: {int(unpadded.sum())} of {len(stamps)} stamps look like nanoseconds written without zero "
                f"padding (line {pose_rows[i] + 1}: {tok.decode()} probably means {secs[0]:.0f}.{int(frac[unpadded][0]):09d}); "
                "as written they are out of order. Read with repair_stamps=True (command line --repair-stamps) to "
                "fix them; off by default so that the official tool's numbers stay reproducible"
            )
    poses = values[(offs + ntok - 7)[:, None] + np.arange(7)]
    line_no = pose_rows + 1
    keep = check_rows(spath, stamps, poses, line_no, notes)
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
        sequences[seq] = finish(spath, stamps[sel], poses[sel], line_no[sel], f", seq {seq}", notes)
    sequences = dict(sorted(sequences.items()))
    result = ResultFile(
        path=Path(path),
        header=header,
        header_lines=header_lines,
        sequences=sequences,
        seq_info={k: seq_info[k] for k in sequences},
        seq_lines=seq_lines,
        removed_repeats=removed,
        warnings=notes,
    )
    if warn:
        for note in notes:
            warnings.warn(note, LorisWarning, stacklevel=2)
    return result
