"""ORDSLAM (Ponomarev & Drozdov, J. Opt. Technol. 87(12), 2020): outdoor, hand-held RGB-D
sequences (ZED stereo camera, 1280x720) with motion scenarios of graded difficulty, each recorded at
several times of day and in two depth modes. ``../shared/papers/ordslam-2020-ru.md``, English
summary ``ordslam-facts.md``.

What is assumed, and why
------------------------
The paper does not document the column layout of its ground-truth ``.txt`` files (one per
sequence; the 27 GB download is not bundled). :func:`read_ordslam` therefore accepts the layouts
that are plausible for such files and detects which one a file uses:

* ``tum``: ``stamp x y z qx qy qz qw`` (8 numbers, stamps in seconds, not all whole numbers): the
  TUM RGB-D convention, which the paper follows for its metric (ATE after Horn alignment);
* ``index``: ``frame x y z qx qy qz qw`` (8 numbers, the first a whole-number frame index): the
  ground truth is computed on selected frames of the video, so a frame number is natural; the
  stamp is ``frame / fps`` and needs ``fps``;
* ``pose``: ``x y z qx qy qz qw`` (7 numbers, one line per selected frame): stamp = line / fps;
* ``kitti``: 12 numbers, a 3x4 matrix ``[R | t]`` row-major as in KITTI (stamp = line / fps);
* ``index-kitti``: a frame index followed by the 12 matrix numbers.

Values may be separated by spaces, tabs, commas or semicolons; ``#`` comments and one header line of
column names are skipped. Anything else raises :class:`~lorisnb.errors.ParseError` naming the file
and what was expected. Every returned trajectory records its layout in ``meta["layout"]``.

File names are not documented either. :func:`~lorisnb.io.datasets.ordslam_catalog.describe_sequence` reads
the scenario number, time of day and depth mode from tokens of a path such as
``s5_13-00_fill.txt`` or ``scenario6/20h/standard.txt`` (the accepted tokens are listed in
:mod:`lorisnb.io.datasets.ordslam_catalog`); a ``catalog.csv`` (``file,scenario,time,depth_mode``) in the
folder overrides what the names say.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from lorisnb.core.spec.validate import choice, positive
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.core.trajectory.rotations import rotation_blocks
from lorisnb.errors import DataNotFoundError, LorisWarning, ParseError
from lorisnb.io.datasets.ordslam_catalog import (
    PAPER_TO_PAGE,
    SCENARIOS,
    Scenario,
    describe_sequence,
    light_period,
    read_catalog,
    scenario,
)
from lorisnb.io.parsing.scanner import check_rows, finish, read_bytes, scan
from lorisnb.io.readers.plain import ROTATION_TOLERANCE

__all__ = [
    "LAYOUTS", "PAPER_TO_PAGE", "SCENARIOS", "OrdslamFolder", "Scenario", "describe_sequence", "find_ordslam",
    "light_period", "read_ordslam", "scenario",
]  # fmt: skip

LAYOUTS = ("tum", "index", "pose", "kitti", "index-kitti")


def _detect(values: np.ndarray, ncol: int, path: str) -> str:
    if ncol == 8:
        first = values[:, 0]
        whole = np.all(np.abs(first - np.round(first)) < 1e-9)
        return "index" if whole and first.max() < 1e7 else "tum"
    if ncol == 7:
        return "pose"
    if ncol == 12:
        return "kitti"
    if ncol == 13:
        return "index-kitti"
    raise ParseError(
        path,
        None,
        f"{ncol} numbers per line; expected an ORDSLAM trajectory layout: 8 "
        "('stamp x y z qx qy qz qw' or 'frame x y z qx qy qz qw'), 7 ('x y z qx qy qz qw'), "
        "12 (3x4 matrix, KITTI) or 13 (frame + 3x4 matrix)",
    )


def read_ordslam(
    path: str | os.PathLike, fps: float | None = None, layout: str | None = None, warn: bool = True
) -> Trajectory:
    """Read an ORDSLAM ground-truth (or estimate) trajectory, detecting its layout.

    Args:
        path: the ``.txt`` file.
        fps: frame rate, needed when the file has frame numbers or no stamps (layouts ``index``,
            ``pose``, ``kitti``, ``index-kitti``): stamp = frame / fps, seconds.
        layout: force one of :data:`LAYOUTS` instead of detecting it (``index`` and
            ``index-kitti`` need whole frame numbers).
        warn: issue the notes about the file as :class:`~lorisnb.errors.LorisWarning` (as
            :func:`~lorisnb.io.readers.plain.read_tum` does): poses with NaN or infinite values skipped,
            frame numbers or stamps not increasing (sorted; the last pose of a repeated one kept).

    Raises ValidationError for a bad ``fps`` or ``layout``, ParseError (file and line) for a file
    that does not fit the layout.

    Returns a :class:`~lorisnb.core.trajectory.poses.Trajectory` with ``meta = {"dataset": "ORDSLAM",
    "layout": ..., "fps": ...}``.
    """
    spath = str(path)
    if layout is not None:
        layout = choice("layout", layout, LAYOUTS)
    if fps is not None:
        fps = positive("fps", fps, "frames per second")
    lines = scan(read_bytes(path), separators=b",;")
    rows = np.flatnonzero((lines.first >= 0) & (lines.first != ord("#")))
    if rows.size and not (chr(lines.first[rows[0]]).isdigit() or chr(lines.first[rows[0]]) in "+-."):
        rows = rows[1:]  # one header line of column names
    if rows.size == 0:
        raise ParseError(spath, None, "no trajectory lines; expected one pose per line")
    counts = lines.ntok[rows]
    ncol = int(counts[0])
    bad = counts != ncol
    if bad.any():
        i = rows[np.flatnonzero(bad)[0]]
        raise ParseError(
            spath,
            int(i) + 1,
            f"{lines.ntok[i]} numbers, but the first line has {ncol}; expected the same layout on every line",
        )
    values = lines.numbers(rows, spath, f"{ncol} numbers per line").reshape(-1, ncol)
    found = _detect(values, ncol, spath) if layout is None else layout
    expected = {"tum": 8, "index": 8, "pose": 7, "kitti": 12, "index-kitti": 13}[found]
    if ncol != expected:
        raise ParseError(spath, int(rows[0]) + 1, f"layout {found!r} needs {expected} numbers per line, found {ncol}")
    if found != "tum" and fps is None:
        raise ParseError(
            spath,
            int(rows[0]) + 1,
            f"the file uses the {found!r} layout (frame numbers or no "
            "stamps); pass fps=... (frames per second) to turn frames into seconds (read_ordslam's and "
            "find_ordslam's fps; ordslam_fps in the indoor_vs_outdoor notebook and lorisnb report -p ordslam_fps; "
            "an fps column in catalog.csv for this file alone)",
        )
    line_no = rows + 1
    if found in ("index", "index-kitti"):
        frac = np.flatnonzero(~(np.abs(values[:, 0] - np.round(values[:, 0])) < 1e-9))
        if frac.size:
            i = int(frac[0])
            raise ParseError(
                spath,
                int(line_no[i]),
                f"frame number {float(values[i, 0])!r} is not a whole number; layout {found!r} expects a frame "
                "index first (stamps in seconds: layout 'tum')",
            )
    rate = float(fps) if fps is not None else np.nan  # fps is required for every layout but tum
    if found == "tum":
        stamps, pose = values[:, 0], values[:, 1:8]
    elif found == "index":
        stamps, pose = values[:, 0] / rate, values[:, 1:8]
    elif found == "pose":
        stamps, pose = np.arange(len(values)) / rate, values
    else:
        mats = values[:, -12:].reshape(-1, 3, 4)
        frames = values[:, 0] if found == "index-kitti" else np.arange(len(values))
        stamps = frames / rate
        det = np.linalg.det(mats[:, :, :3])
        if np.any(np.abs(det - 1) > 1e-3):
            i = int(np.flatnonzero(np.abs(det - 1) > 1e-3)[0])
            raise ParseError(
                spath,
                int(line_no[i]),
                f"3x4 matrix has a rotation block of determinant {det[i]:.4f}; expected a rotation (determinant 1)",
            )
        finite = np.isfinite(mats).all(axis=(1, 2))  # other rows are skipped below, with a note
        quat, off = rotation_blocks(np.where(finite[:, None, None], mats[:, :, :3], np.eye(3)))
        if np.any(off > ROTATION_TOLERANCE):
            i = int(np.flatnonzero(off > ROTATION_TOLERANCE)[0])
            raise ParseError(
                spath,
                int(line_no[i]),
                f"3x4 matrix has a rotation block {off[i]:.4f} from orthonormal; expected a rotation (R R^T = I)",
            )
        quat[~finite] = np.nan
        pose = np.concatenate([mats[:, :, 3], quat], axis=1)
    notes: list[str] = []
    keep = check_rows(spath, stamps, pose[:, :3], pose[:, 3:7], line_no, notes)
    traj = finish(spath, stamps[keep], pose[keep, :3], pose[keep, 3:7], line_no[keep], "", notes)
    if warn:
        for note in notes:
            warnings.warn(note, LorisWarning, stacklevel=2)
    return Trajectory.from_checked(  # checked and sorted by check_rows and finish
        traj.stamps,
        traj.positions,
        traj.quaternions,
        traj.lines,
        {"dataset": "ORDSLAM", "layout": found, "fps": fps, "source": spath},
    )


@dataclass
class OrdslamFolder:
    """An ORDSLAM folder: ground-truth files and, optionally, estimates of algorithms.

    Layout lorisnb expects (documented in docs/guide/ordslam.md): ground-truth ``.txt`` files anywhere below
    ``root`` except under ``estimates/``; the estimate of ground truth ``root/REL`` is
    ``root/estimates/<algorithm>/REL`` (the same path relative to the folder; a bare file name is
    enough when only one ground-truth file has that name); an optional ``root/catalog.csv``
    (:func:`~lorisnb.io.datasets.ordslam_catalog.read_catalog`).
    """

    root: Path
    groundtruth: list[Path]
    estimates: dict[str, list[Path]]
    catalog: pd.DataFrame | None

    def relative(self, path: Path) -> str:
        """The ground-truth file's path relative to the folder, ``/``-separated (its key)."""
        return path.relative_to(self.root).as_posix()

    def describe(self, path: Path) -> dict:
        """:func:`describe_sequence` of a ground-truth file of this folder."""
        return describe_sequence(self.relative(path), self.catalog)

    def sequences(self) -> pd.DataFrame:
        """One row per ground-truth file with its scenario, difficulty, time, light and depth mode."""
        return pd.DataFrame([dict(path=str(p), **self.describe(p)) for p in self.groundtruth])

    def pairs(self) -> tuple[list[tuple[str, Path, Path]], list[tuple[Path, str]]]:
        """(algorithm, estimate, ground truth) for every estimate, and (estimate, why) for those
        without exactly one ground truth: none at the same relative path, or a bare name that
        several ground-truth files share (all of them named). Never matched by name alone when
        the estimate sits in sub-folders."""
        by_rel = {self.relative(p): p for p in self.groundtruth}
        by_name: dict[str, list[Path]] = {}
        for p in self.groundtruth:
            by_name.setdefault(p.name, []).append(p)
        pairs, problems = [], []
        for alg, files in self.estimates.items():
            base = self.root / "estimates" / alg
            for est in files:
                rel = est.relative_to(base).as_posix()
                gt = by_rel.get(rel)
                if gt is None and "/" not in rel and len(by_name.get(rel, [])) == 1:
                    gt = by_name[rel][0]
                if gt is not None:
                    pairs.append((alg, est, gt))
                    continue
                same = sorted(self.relative(p) for p in by_name.get(est.name, []))
                if "/" not in rel and len(same) > 1:
                    why = (
                        f"ambiguous: ground-truth files {', '.join(same)} are all named {est.name}; put the "
                        f"estimate at estimates/{alg}/<the same relative path>"
                    )
                else:
                    why = f"no ground-truth file {rel} (expected estimates/{alg}/<path of the ground truth>)"
                    if same:
                        why += f"; ground truth with that name: {', '.join(same)}"
                problems.append((est, why))
        return pairs, problems


def _text_files(folder: Path) -> list[Path]:
    """The ``.txt`` files below ``folder`` (any case: ``S5_13-00_FILL.TXT`` was passed over without
    a word), hidden files and folders left out (``.ipynb_checkpoints``, which JupyterLab writes
    beside a file it opens, ``.x.txt``, ``~x.txt``: they were read as sequences), sorted."""
    out = []
    for p in folder.rglob("*"):
        hidden = any(part.startswith((".", "~")) for part in p.relative_to(folder).parts)
        if not hidden and p.suffix.lower() == ".txt" and p.is_file():
            out.append(p)
    return sorted(out)


def find_ordslam(root: str | os.PathLike | None) -> OrdslamFolder | None:
    """The ORDSLAM folder at ``root``, or None when ``root`` is None. Raises DataNotFoundError
    (naming the folder) when it is given but holds no trajectory file, ParseError when its
    ``catalog.csv`` has a bad row."""
    if root is None:
        return None
    root = Path(root).expanduser()
    if not root.is_dir():
        raise DataNotFoundError(
            f"ORDSLAM folder {root} {'is a file, not a folder' if root.exists() else 'does not exist'}; download the "
            "dataset (svponomarev.github.io) and pass the folder holding its ground-truth .txt files"
        )
    est_dir = root / "estimates"
    gt = [p for p in _text_files(root) if est_dir not in p.parents]
    if not gt:
        raise DataNotFoundError(f"no ground-truth .txt file below {root}; expected one trajectory file per sequence")
    estimates: dict[str, list[Path]] = {}
    if est_dir.is_dir():
        for alg in sorted(d for d in est_dir.iterdir() if d.is_dir()):
            estimates[alg.name] = _text_files(alg)
    cat = root / "catalog.csv"
    catalog = read_catalog(cat, [p.relative_to(root).as_posix() for p in gt]) if cat.is_file() else None
    return OrdslamFolder(root, gt, estimates, catalog)
