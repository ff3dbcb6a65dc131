"""Readers of plain trajectory formats: TUM RGB-D text, KITTI poses, EuRoC CSV, times files, and
:func:`read_trajectory` for any of them (OpenLORIS files: :mod:`lorisnb.io.readers.openloris`).

All scan the file as bytes with numpy (:mod:`lorisnb.io.parsing.scanner`) and raise
:class:`~lorisnb.errors.ParseError` naming the file, the line and what was expected.
"""

from __future__ import annotations

import itertools
import os
import warnings
from collections.abc import Callable
from typing import cast

import numpy as np

from lorisnb.core.spec.validate import choice, flag
from lorisnb.core.trajectory.poses import Trajectory, keep_written_blocks
from lorisnb.core.trajectory.rotations import rotation_entries
from lorisnb.errors import LorisWarning, ParseError, ValidationError
from lorisnb.io.parsing.chunks import read_rows
from lorisnb.io.parsing.ranges import LINE_LIMIT
from lorisnb.io.parsing.rows import Group, Part, Rows, rows_of
from lorisnb.io.parsing.scanner import (
    BOM,
    REPEATED,
    Lines,
    check_rows,
    finish,
    read_bytes,
    regular_file,
    rows_fit,
    scan,
)
from lorisnb.io.readers.openloris import read_openloris
from lorisnb.io.readers.registry import FORMAT_NAMES, FORMATS, hint, line_hint, recognise, sample, with_hint
from lorisnb.io.readers.times import check_times, read_times, times_lines  # noqa: F401 (read_times: still lorisnb.io.readers.plain.read_times)

#: Formats :func:`read_trajectory` reads (the names of :data:`lorisnb.io.readers.registry.FORMATS`).
TRAJECTORY_FORMATS = FORMAT_NAMES
ROTATION_TOLERANCE = 1e-3  # KITTI/EuRoC rotation blocks: |R R^T - I| and |det R - 1| below this


def _warn(notes: list[str], warn: bool, stacklevel: int = 4) -> None:
    """Issue a reader's notes, attributed to the code that called the public reader (``stacklevel``
    counts this function, the reader's body and its public wrapper)."""
    if warn:
        for note in notes:
            warnings.warn(note, LorisWarning, stacklevel=stacklevel)


def _data_rows(lines: Lines) -> np.ndarray:
    """Lines that are neither blank nor ``#`` comments."""
    return np.flatnonzero((lines.first >= 0) & (lines.first != ord("#")))


def _width_message(text: str, ntok: int, expected: str, fmt: str = "", path: str | os.PathLike | None = None) -> str:
    """A line of the wrong width, with the option that would read it when the file (or else the
    line) plainly belongs to another format (:mod:`lorisnb.io.readers.registry`)."""
    more = (hint(path, fmt) if path is not None else "") or line_hint(text, fmt)
    return f"{text[:80]!r} has {ntok} fields; expected {expected}{more}"


def _check_width(lines: Lines, rows: np.ndarray, spath: str, ok: np.ndarray, expected: str, fmt: str = "") -> None:
    if not ok.all():
        i = rows[np.flatnonzero(~ok)[0]]
        raise ParseError(spath, int(i) + 1, _width_message(lines.text(i), int(lines.ntok[i]), expected, fmt))


def refuse_other_format(path: str | os.PathLike, fmt: str, read: Callable[[], object] | None = None) -> None:
    """A ParseError when the file at ``path`` is plainly in another format than ``fmt`` (its first
    lines recognised by :mod:`lorisnb.io.readers.registry`), saying which and the option that reads
    it: every reader of a format checks this, so a EuRoC CSV given to :func:`read_tum` (whose 8
    comma-separated numbers it would take as seconds and ``x y z w``) is refused as
    :func:`read_trajectory` refuses it. ``read``: the reader of ``fmt`` over the file, without its
    warnings; where it refuses the file too, its own error (naming the line, with the same hint) is
    raised. A pipe, a path that is not there or a file of no known layout is left to the reader."""
    if not isinstance(path, (str, os.PathLike)):
        return  # the reader says what it expected
    found = recognise(sample(path))
    if found and fmt not in found:
        if read is not None:
            try:
                read()
            except ParseError as e:  # its own error, on the line; with the hint where it did not give it
                raise with_hint(e, path, fmt) from e.__cause__
        want = FORMATS[fmt]
        raise ParseError(path, None, f"expected the {want.name} format ({want.columns}); {FORMATS[found[0]].hint()}")


def read_tum(
    path: str | os.PathLike,
    warn: bool = True,
    progress: Callable[[int], object] | None = None,
    repeated: str = "drop",
) -> Trajectory:
    """Read a TUM RGB-D trajectory: lines ``stamp tx ty tz qx qy qz qw`` (seconds, metres,
    quaternion xyzw), ``#`` comments; spaces, tabs or commas separate the values.

    Non-finite poses are skipped and unsorted or repeated stamps sorted (keeping the last, or with
    ``repeated="keep"`` every pose of a repeated stamp, as evo does), with a warning. Raises ParseError for a malformed line or a zero-norm quaternion. The file is read
    in chunks (:func:`lorisnb.io.parsing.chunks.read_rows`); ``progress`` is called with each chunk's bytes.
    A file plainly in another format (a EuRoC CSV, ...) is refused with a ParseError naming it
    (:func:`refuse_other_format`).
    """
    refuse_other_format(path, "tum", lambda: _read_tum(path, False, None, repeated))
    return _read_tum(path, warn, progress, repeated)


def _read_tum(
    path: str | os.PathLike,
    warn: bool = True,
    progress: Callable[[int], object] | None = None,
    repeated: str = "drop",
) -> Trajectory:
    """:func:`read_tum` of a file whose format is already checked."""
    spath = str(path)
    expected = "8 numbers 'stamp tx ty tz qx qy qz qw' (TUM format) or a '#' comment"
    rows = read_rows(
        path,
        (8,),
        what="a TUM trajectory file",
        numbers="numbers 'stamp tx ty tz qx qy qz qw'",
        bad_width=lambda text, n: _width_message(text, n, expected, "tum", path),
        separators=b",",
        progress=progress,
        layout=_pose_groups,
        convert=rows_fit,
    )
    first, positions, quaternions, unsure = _fit_groups(rows, _pose_groups(8))  # row-major, filled as read
    return _poses(spath, first[:, 0], positions, quaternions, rows.lines, warn, repeated, unsure)


def _pose_groups(ntok: int) -> tuple[slice, slice, slice]:
    """The columns of a TUM line (``ntok`` is 8): stamp, position, quaternion."""
    return slice(0, 1), slice(1, 4), slice(4, 8)


def _fit_groups(rows: Rows, groups: tuple[Group, ...]) -> list[np.ndarray]:
    """The row-major stamp, position and quaternion arrays of ``rows`` and :func:`rows_fit`'s
    flags (computed on each piece as it was read, else on all rows now)."""
    *parts, unsure = rows.convert(groups, rows_fit)
    return [rows_of(p) if isinstance(p, list) else p for p in parts] + [cast(np.ndarray, unsure)]


def _poses(
    spath: str, stamps: np.ndarray, positions: np.ndarray, quaternions: np.ndarray, line_no: np.ndarray, warn: bool,
    repeated: str, unsure: np.ndarray | None = None,
) -> Trajectory:  # fmt: skip
    """A Trajectory of rows as read: checked (:func:`~lorisnb.io.parsing.scanner.check_rows`, unless
    ``unsure`` (:func:`rows_fit`) says it has nothing to say; NaN poses skipped with a note),
    sorted (:func:`~lorisnb.io.parsing.scanner.finish`), notes issued if ``warn``."""
    notes: list[str] = []
    keep = check_rows(spath, stamps, positions, quaternions, line_no, notes) if unsure is None or unsure.any() else None
    if keep is not None and not keep.all():
        stamps, positions, quaternions, line_no = stamps[keep], positions[keep], quaternions[keep], line_no[keep]
    traj = finish(spath, stamps, positions, quaternions, line_no, "", notes, repeated)
    _warn(notes, warn, 5)  # _poses, _read_tum, read_tum
    return traj


def _pose_blocks(flat: Part) -> tuple[list[np.ndarray], np.ndarray, np.ndarray, list[np.ndarray]]:
    """Positions (their 3 columns), quaternions, refusals and the rotation blocks as written (their
    9 columns, row-major order) of m rows of ``[R | t]`` blocks, row-major (an (m, 12) array, or
    the parser's 12 columns as read), row by row (a :data:`~lorisnb.io.parsing.rows.Convert`: a
    large file computes it on each range as it is read and copies the columns straight into its
    row-major arrays, without an (m, 9) array between: 8 % less CPU for a 1M-pose file): a row is
    refused unless finite and its block a proper rotation within :data:`ROTATION_TOLERANCE`; the
    quaternions are those of the rotations nearest to the blocks (scipy's ``Rotation.from_matrix``
    quaternions of exact rotations: :func:`lorisnb.core.trajectory.rotations.rotation_entries`, on
    the columns with no copy)."""
    cols = list(flat) if isinstance(flat, list) else [flat[:, k] for k in range(12)]
    with np.errstate(all="ignore"):
        finite = all(np.isfinite(c.sum()) for c in cols) or all(np.isfinite(c).all() for c in cols)
    n = len(cols[0])
    bad = np.zeros(n, bool)
    if not finite:
        for c in cols:
            bad |= ~np.isfinite(c)
        cols = [np.where(bad, 0.0, c) for c in cols]
    q, off = rotation_entries([cols[4 * i : 4 * i + 3] for i in range(3)])
    bad |= ~(off <= ROTATION_TOLERANCE)
    return [cols[3], cols[7], cols[11]], q, bad, [cols[4 * i + j] for i in range(3) for j in range(3)]


#: Decimals a KITTI rotation block may be written with and still stand for a rotation when it is
#: off by more than :data:`ROTATION_TOLERANCE` (:func:`rounded_rotations`): with 3 its nearest
#: rotation stays within :data:`~lorisnb.core.trajectory.poses.WRITTEN_TOLERANCE` of it (by which a
#: pose turned since reading is told from its block as written); 2 leave each entry 0.005 of play.
ROUNDED_DECIMALS = (3, 6)


def rounded_rotations(blocks: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Which of the (k, 9) rotation blocks (row-major, as written) are rotations rounded to the
    decimals written, and those decimals: each block's numbers are whole multiples of ``10**-d``
    (``d`` the fewest decimals they fit, from 3 to 6: ``%.3f`` writes 3), and the rotation nearest to
    it (``q``, ``xyzw``) is within 1.75 half-units of ``10**-d`` of each entry. Rounding a rotation
    to ``d`` decimals leaves its nearest rotation within 1.68 half-units of every entry (200,000
    random rotations at each of 1 to 4 decimals; and its Frobenius distance below 3 half-units, as
    it must be), while a block scaled by ``1 + 10**-d`` (one half-unit more than rounding can give:
    an entry of ``1.01`` in a 2-decimal block) is 2 half-units off. Such files (3 decimals:
    ``np.savetxt(fmt='%.3f')``) are off by up to about 1.4e-3, past :data:`ROTATION_TOLERANCE`;
    the KITTI devkit, kitti-odom-eval and evo compose them as written."""
    from lorisnb.core.alignment.geometry import quat_to_matrix

    b = np.asarray(blocks, float).reshape(-1, 9)
    decimals = np.zeros(len(b), int)
    for d in range(ROUNDED_DECIMALS[1], ROUNDED_DECIMALS[0] - 1, -1):  # the fewest decimals that fit, last
        scaled = b * 10.0**d
        fits = (np.abs(scaled - np.rint(scaled)) <= 1e-6).all(axis=1)
        decimals[fits] = d
    half = 0.5 * 10.0 ** -decimals.astype(float)
    nearest = quat_to_matrix(np.asarray(q, float)).reshape(-1, 9)
    ok = (decimals > 0) & (np.abs(nearest - b).max(axis=1) <= 1.75 * half) & (np.linalg.det(b.reshape(-1, 3, 3)) > 0)
    return ok, decimals


def _from_matrices(spath: str, stamps: np.ndarray, poses: list[np.ndarray], line_no: np.ndarray) -> Trajectory:
    """The trajectory of :func:`_pose_blocks`' ``poses``, or a ParseError naming the first line
    refused. The rotation blocks as written are kept beside the quaternions of their nearest
    rotations (:func:`lorisnb.core.trajectory.poses.keep_written_blocks`), for the conventions
    that compose the matrices as written (the KITTI devkit's)."""
    positions, q, bad, written = poses
    if bad.any():  # a block rounded to the few decimals written is a rotation all the same
        rows = np.flatnonzero(bad)
        blocks = np.asarray(written)[rows]
        ok, decimals = rounded_rotations(blocks, q[rows])
        if not ok.all():
            k = int(rows[np.argmin(ok)])
            b = np.asarray(written)[k].reshape(3, 3)
            off = max(float(np.abs(b @ b.T - np.eye(3)).max()), abs(float(np.linalg.det(b)) - 1))
            said = (f": off by {off:.2g}, more than rounding to the decimals written explains (3 at least: "
                    "write 6 or more)") if b.any() else ""  # fmt: skip
            raise ParseError(
                spath,
                int(line_no[k]),
                "not a rotation (non-finite values, or a rotation block that is not orthonormal with determinant "
                f"1{said}); expected a pose",
            )
        _warn(
            [f"{spath}: {len(rows)} rotation block(s) written with {int(decimals.max())} decimals are rotations only "
             f"to within that rounding (first at line {int(line_no[rows[0]])}, off by more than "
             f"{ROTATION_TOLERANCE:g}): their nearest rotations are used, the blocks as written under the KITTI "
             "devkit's conventions; write 6 or more decimals to keep the rotations as computed"],
            True,
            5,  # _warn, _from_matrices, _read_kitti, read_kitti
        )  # fmt: skip
    traj = Trajectory.from_checked(np.asarray(stamps, float), positions, q, line_no, {"source": spath})
    return keep_written_blocks(traj, written)


def read_kitti(
    path: str | os.PathLike, stamps: np.ndarray | str | os.PathLike | None = None, repeated: str = "drop"
) -> Trajectory:
    """Read a KITTI pose file: one 3x4 matrix ``[R | t]`` per line, row-major (12 numbers, metres).

    KITTI files carry no stamps: pass ``stamps`` (an array, or a times file with one stamp per
    line as KITTI's ``times.txt``); without them the pose index is used as the stamp (and
    ``meta["stamps"] == "index"``). Given stamps must increase (``repeated="keep"``: or repeat).
    A file plainly in another format is refused with a ParseError naming it (:func:`refuse_other_format`).
    """
    refuse_other_format(path, "kitti", lambda: _read_kitti(path, stamps, repeated))
    return _read_kitti(path, stamps, repeated)


def _read_kitti(
    path: str | os.PathLike, stamps: np.ndarray | str | os.PathLike | None = None, repeated: str = "drop"
) -> Trajectory:
    """:func:`read_kitti` of a file whose format is already checked."""
    keep_all = choice("repeated", repeated, REPEATED) == "keep"
    spath = str(path)
    rows = read_rows(
        path,
        (12,),
        what="a KITTI pose file",
        numbers="12 numbers of a 3x4 pose matrix",
        bad_width=lambda text, n: _width_message(
            text, n, "12 numbers per line, a 3x4 pose matrix row-major (KITTI)", "kitti", path
        ),
        separators=b",",
        layout=_matrix_groups,
        row_major=False,
        convert=_pose_blocks,
    )
    poses = [rows_of(p) if isinstance(p, list) else p for p in rows.convert(_matrix_groups(12), _pose_blocks)]
    n = len(poses[0])
    if stamps is None:
        t = np.arange(n, dtype=float)
    elif isinstance(stamps, (str, os.PathLike)):
        if os.path.exists(stamps) and os.path.samefile(stamps, path):  # the pose file as its own times
            raise ParseError(spath, None, "this KITTI pose file is also given as its own times file (--est-times or "
                             "--gt-times; stamps= in Python); a times file holds one stamp per line (KITTI's "
                             "times.txt): give that, or no times for either file to pair two KITTI files by index")  # fmt: skip
        t, t_lines = times_lines(stamps)
        check_times(str(stamps), t, t_lines, keep_all)  # the times file and its line named
    else:
        t = np.asarray(stamps, dtype=float).reshape(-1)
    if len(t) != n:  # a times file: named, it may be the one at fault (another sequence's, swapped)
        given = f"the times file {stamps}" if isinstance(stamps, (str, os.PathLike)) else "the stamps given"
        raise ParseError(spath, None, f"{n} poses but {len(t)} stamps in {given}; expected one stamp per pose "
                         "(is it this sequence's times file?)")  # fmt: skip
    if not np.isfinite(t).all():
        raise ParseError(spath, None, f"stamp {int(np.flatnonzero(~np.isfinite(t))[0]) + 1} given for this KITTI "
                         "file is not finite; expected seconds")  # fmt: skip
    if stamps is not None and len(t) > 1 and not np.all(np.diff(t) >= 0 if keep_all else np.diff(t) > 0):
        raise ParseError(spath, None, "the stamps given for this KITTI file are not strictly increasing")
    out = _from_matrices(spath, t, poses, rows.lines)
    out.meta["stamps"] = "index" if stamps is None else "given"
    return out


def _matrix_groups(ntok: int) -> tuple[slice]:
    """The columns of a KITTI line (``ntok`` is 12): the 3x4 matrix, row-major."""
    return (slice(0, 12),)


EUROC_ROWS = (
    "the same number (8 or more) of comma-separated numbers on every row: "
    "'timestamp_ns,p_x,p_y,p_z,q_w,q_x,q_y,q_z,...' (EuRoC CSV)"
)
EUROC_NUMBERS = "numbers 'timestamp_ns,p_x,p_y,p_z,q_w,q_x,q_y,q_z'"


def _euroc_head(path: str | os.PathLike) -> tuple[int, int]:
    """The lines before a EuRoC CSV's rows (a header line without '#' and what precedes it; 0 if
    none) and the number of fields of its first row (8 if there is none). Reads the first lines
    only; anything unreadable is left to :func:`~lorisnb.io.parsing.chunks.read_rows` to report."""
    skip, seen = 0, 0
    try:
        with open(path, "rb") as fh:
            for k in itertools.count(1):
                line = fh.readline(LINE_LIMIT)
                if k == 1 and line.startswith(BOM):
                    line = line[len(BOM) :]
                if not line or b"\0" in line or not line.endswith(b"\n") and len(line) >= LINE_LIMIT:
                    break
                tokens = line.replace(b",", b" ").split()
                if not tokens or tokens[0].startswith(b"#"):
                    continue
                seen += 1
                if seen == 1 and len(tokens) >= 8:
                    try:
                        float(tokens[0].decode("utf-8", "replace"))
                    except ValueError:
                        skip = k  # a header line without '#'
                        continue
                return skip, len(tokens)
    except (OSError, TypeError, ValueError):
        pass
    return skip, 8


def read_euroc(path: str | os.PathLike, warn: bool = True, repeated: str = "drop") -> Trajectory:
    """Read a EuRoC ground-truth CSV (``state_groundtruth_estimate0/data.csv``): rows
    ``stamp_ns, p_x, p_y, p_z, q_w, q_x, q_y, q_z[, ...]`` after a ``#timestamp,...`` header;
    stamps become seconds (nanoseconds / 1e9, as evo), quaternions ``xyzw``. Further columns
    (velocities, biases) are ignored. ``repeated``: as :func:`read_tum`. Read in chunks as
    :func:`read_tum` (the rows straight into the arrays kept). A file plainly in another format (a
    TUM file whose stamps happen to be whole numbers, ...) is refused with a ParseError naming it
    (:func:`refuse_other_format`)."""
    refuse_other_format(path, "euroc", lambda: _read_euroc(path, False, repeated))
    return _read_euroc(path, warn, repeated)


def _read_euroc(path: str | os.PathLike, warn: bool = True, repeated: str = "drop") -> Trajectory:
    """:func:`read_euroc` of a file whose format is already checked."""
    spath = str(path)
    if not regular_file(path):  # a pipe is read once: by the byte scanner, not after a look at its head
        return _read_euroc_whole(path, warn, repeated)
    skip, width = _euroc_head(path)
    try:
        rows = read_rows(
            path,
            (width if width >= 8 else 8,),  # every row as wide as the first
            what="a trajectory file",
            numbers=EUROC_NUMBERS,
            bad_width=lambda text, n: _width_message(text, n, EUROC_ROWS),
            separators=b",",
            layout=_euroc_groups,
            skip_lines=skip,
            convert=rows_fit,
        )
    except ParseError:
        return _read_euroc_whole(path, warn, repeated)  # the first problem of the whole file, as it always was reported
    first, positions, quaternions, unsure = _fit_groups(rows, _euroc_groups(width))  # quaternions read as x y z w
    notes: list[str] = []
    line_no = rows.lines
    stamps = first[:, 0]
    if (stamps != np.round(stamps)).any():  # not whole nanoseconds: reported as the whole-file reader does
        return _read_euroc_whole(path, warn, repeated)
    keep = check_rows(spath, stamps, positions, quaternions, line_no, notes) if unsure.any() else None
    if keep is not None and not keep.all():
        stamps, positions, quaternions, line_no = stamps[keep], positions[keep], quaternions[keep], line_no[keep]
    stamps /= 1e9
    traj = finish(spath, stamps, positions, quaternions, line_no, "", notes, repeated)
    _warn(notes, warn)
    return traj


def _read_euroc_whole(path: str | os.PathLike, warn: bool, repeated: str = "drop") -> Trajectory:
    """:func:`read_euroc` by the byte scanner over the whole file: widths checked on every row
    before any number is read (a file with several problems reports the same first one)."""
    spath = str(path)
    lines = scan(read_bytes(path), separators=b",")
    rows = _data_rows(lines)
    if rows.size and lines.ntok[rows[0]] >= 8:
        first = lines.text(rows[0]).split()[0] if lines.text(rows[0]).split() else ""
        try:
            float(first)
        except ValueError:
            rows = rows[1:]  # a header line without '#'
    width = lines.ntok[rows]
    _check_width(lines, rows, spath, (width >= 8) & (width == (width[0] if width.size else 8)), EUROC_ROWS, "euroc")
    ncol = int(width[0]) if width.size else 8
    values = lines.numbers(rows, spath, EUROC_NUMBERS).reshape(-1, ncol)
    fraction = np.flatnonzero(values[:, 0] != np.round(values[:, 0]))  # NaN too (inf: by check_rows)
    if fraction.size and np.isnan(values[fraction[0], 0]):
        k = int(fraction[0])
        raise ParseError(spath, int(rows[k]) + 1, "timestamp nan is not finite; expected whole nanoseconds")
    if fraction.size:  # EuRoC stamps are whole nanoseconds: these are seconds (or no stamps at all)
        k = int(fraction[0])
        raise ParseError(
            spath, int(rows[k]) + 1,
            f"stamp {lines.text(rows[k]).split(',')[0].split()[0]} has a fraction; expected whole nanoseconds "
            f"(EuRoC CSV){hint(path, 'euroc') or '; a TUM file (stamps in seconds): read it with --format tum'}",
        )  # fmt: skip
    poses = np.column_stack([values[:, 1:4], values[:, 5:8], values[:, 4]])  # x y z qx qy qz qw
    notes: list[str] = []
    line_no = rows + 1
    keep = check_rows(spath, values[:, 0], poses[:, :3], poses[:, 3:], line_no, notes)
    traj = finish(spath, values[keep, 0] / 1e9, poses[keep, :3], poses[keep, 3:], line_no[keep], "", notes, repeated)
    _warn(notes, warn, 5)  # the whole-file reader, _read_euroc, read_euroc
    return traj


def _euroc_groups(ntok: int) -> tuple[slice, slice, list[int]]:
    """The columns of a EuRoC row: stamp (ns), position, quaternion (its ``w x y z`` columns taken
    as ``x y z w``)."""
    return slice(0, 1), slice(1, 4), [5, 6, 7, 4]


def read_trajectory(
    path: str | os.PathLike,
    fmt: str = "tum",
    seq: int | None = None,
    stamps: np.ndarray | str | os.PathLike | None = None,
    topic: str | None = None,
    tf: str | None = None,
    repeated: str = "drop",
    repair_stamps: bool = False,
) -> Trajectory:
    """Read one trajectory in any supported format.

    Args:
        fmt: ``tum``, ``kitti``, ``euroc``, ``openloris`` (``seq`` picks the sequence; needed
            when the file has several) or ``bag`` (ROS 1 or ROS 2; ``topic`` or ``tf``, see
            :func:`lorisnb.io.readers.bags.read_bag`).
        stamps: KITTI only: stamps or a times file (see :func:`read_kitti`).
        repeated: poses of a repeated stamp: ``drop`` all but the last, or ``keep`` them all (evo's
            rule); for OpenLORIS files ``drop`` is the official tool's rule (a pose repeating the
            previous one is dropped) and ``keep`` keeps such poses.
        repair_stamps: OpenLORIS files only: read nanoseconds written without zero padding as such
            (see :func:`lorisnb.io.read_openloris`); refused for other formats.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise ValidationError(f"path={path!r}: expected the path of a trajectory file (str or pathlib.Path)")
    fmt = choice("format", fmt, TRAJECTORY_FORMATS)
    if flag("repair_stamps", repair_stamps) and fmt != "openloris":
        raise ValidationError(f"repair_stamps: only OpenLORIS result files are read with it, not {fmt} files")
    for name, value, fmts in (("seq", seq, ("openloris",)), ("stamps", stamps, ("kitti",)), ("topic", topic, ("bag",)),
                              ("tf", tf, ("bag",))):  # fmt: skip
        if value is not None and fmt not in fmts:  # an argument that cannot apply: refused, never dropped
            raise ValidationError(f"{name}: only for {' and '.join(fmts)} files, not {fmt} files")
    if seq is not None and (isinstance(seq, (bool, np.bool_)) or not isinstance(seq, (int, np.integer)) or seq < 0):
        raise ValidationError(f"seq={seq!r}: expected the whole number of a 'seq: N' block")
    refuse_other_format(path, fmt)  # plainly another format: say which option reads it
    return _read(path, fmt, seq, stamps, topic, tf, repeated, repair_stamps)


def _read(
    path: str | os.PathLike,
    fmt: str,
    seq: int | None,
    stamps: np.ndarray | str | os.PathLike | None,
    topic: str | None,
    tf: str | None,
    repeated: str,
    repair_stamps: bool = False,
) -> Trajectory:
    if fmt == "bag":
        from lorisnb.io.readers.bags import read_bag

        return read_bag(path, topic=topic, tf=tf, repeated=repeated)
    if fmt == "tum":  # the format checked by read_trajectory: the file's head is looked at once
        return _read_tum(path, repeated=repeated)
    if fmt == "kitti":
        return _read_kitti(path, stamps, repeated=repeated)
    if fmt == "euroc":
        return _read_euroc(path, repeated=repeated)
    if fmt == "openloris":
        f = read_openloris(path, remove_repeated=choice("repeated", repeated, ("drop", "keep")) == "drop",
                           repair_stamps=repair_stamps)  # fmt: skip
        if not f.sequences:
            raise ParseError(path, None, "no 'seq: N' block; expected at least one sequence")
        if seq is None and len(f.sequences) > 1:  # never one block of several, silently
            raise ParseError(path, None, f"sequences {', '.join(map(str, sorted(f.sequences)))}: expected one, or "
                             "the sequence to read (seq=N); read_openloris reads them all")  # fmt: skip
        key = min(f.sequences) if seq is None else seq
        if key not in f.sequences:
            raise ParseError(path, None, f"no sequence {key}; the file has {sorted(f.sequences)}")
        return f.sequences[key]
    raise ValidationError(f"format={fmt!r}: expected one of {', '.join(TRAJECTORY_FORMATS)}")  # pragma: no cover
