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

File names are not documented either. :func:`describe_sequence` reads the scenario number, time of
day and depth mode from tokens in a name such as ``s5_13-00_fill.txt`` or
``scenario6/20h/standard.txt``; a ``catalog.csv`` (``file,scenario,time,depth_mode``) next to the
files overrides what the names say.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from ..core.matrices import rotation_blocks
from ..core.trajectory import Trajectory
from ..errors import DataNotFoundError, ParseError
from .formats import ROTATION_TOLERANCE
from .scanner import check_rows, finish, read_bytes, scan

LAYOUTS = ("tum", "index", "pose", "kitti", "index-kitti")


@dataclass(frozen=True)
class Scenario:
    number: int
    difficulty: str
    motion: str


#: Motion scenarios as listed on the dataset page (six; ``ordslam-facts.md``). The published
#: Table 3 calls 5 "difficult" and 6 "very difficult" (``../shared/data/published/README.md``).
SCENARIOS: dict[int, Scenario] = {
    1: Scenario(1, "simple", "smooth rotation in a circle without translation"),
    2: Scenario(2, "simple", "vertical or horizontal translation without rotation"),
    3: Scenario(3, "simple", "vertical or horizontal translation, returning to the start position"),
    4: Scenario(4, "medium", "moving towards / away from the scene without rotation"),
    5: Scenario(5, "difficult", "smooth free motion (translation and rotation)"),
    6: Scenario(6, "very difficult", "free motion with shaking or strong wind"),
}
#: The paper's own list has five scenarios (no separate "returning" one): paper number -> page number.
PAPER_TO_PAGE = {1: 1, 2: 2, 3: 4, 4: 5, 5: 6}


def scenario(number: int, numbering: str = "page") -> Scenario:
    """The scenario with this number, in the dataset page's numbering (1-6) or the paper's (1-5)."""
    n = PAPER_TO_PAGE.get(number) if numbering == "paper" else number
    if n not in SCENARIOS:
        valid = sorted(PAPER_TO_PAGE) if numbering == "paper" else sorted(SCENARIOS)
        raise KeyError(f"no ORDSLAM scenario {number} in the {numbering} numbering; expected one of {valid}")
    return SCENARIOS[n]


def light_period(time: str | float | None) -> str:
    """Illumination class of a capture time (``"13:00"`` or hours as a number): ``day`` (07-17 h),
    ``dusk`` (17-20 h, low sun) or ``night`` (20 h and later, before 07 h)."""
    if time is None or (isinstance(time, float) and np.isnan(time)):
        return "unknown"
    if isinstance(time, str):
        h, _, m = time.partition(":")
        hours = int(h) + (int(m) / 60 if m else 0)
    else:
        hours = float(time)
    if 7 <= hours < 17:
        return "day"
    if 17 <= hours < 20:
        return "dusk"
    return "night"


_SCEN = re.compile(r"(?:scenario|scen|sc|s)[ _-]?([1-6])(?![0-9])", re.I)
_TIME = re.compile(r"(?<![0-9])([01]?[0-9]|2[0-3])(?:[:_.-]?([0-5][0-9]))?\s*h?(?![0-9])", re.I)
_DEPTH = re.compile(r"(fill(?:ed)?|standard|std)", re.I)


def describe_sequence(name: str | os.PathLike, catalog: pd.DataFrame | None = None) -> dict:
    """Scenario, difficulty, motion, capture time, light period and depth mode of a sequence, from
    the catalog if it lists the file, else from tokens of its path (see the module docstring)."""
    p = Path(name)
    info = dict(
        file=p.name, scenario=np.nan, difficulty="unknown", motion="", time=None, light="unknown", depth_mode="unknown"
    )
    if catalog is not None and p.name in set(catalog["file"]):
        row = catalog[catalog["file"] == p.name].iloc[0]
        time: str | None
        depth: str | None
        sc = int(row["scenario"]) if pd.notna(row.get("scenario")) else None
        time = str(row["time"]) if pd.notna(row.get("time")) else None
        depth = str(row["depth_mode"]) if pd.notna(row.get("depth_mode")) else "unknown"
    else:
        text = "/".join(p.with_suffix("").parts[-3:])
        m = _SCEN.search(text)
        sc = int(m.group(1)) if m else None
        rest = _SCEN.sub(" ", text)
        t = _TIME.search(rest)
        time = f"{int(t.group(1)):02d}:{t.group(2) or '00'}" if t else None
        d = _DEPTH.search(rest)
        depth = None if d is None else ("fill" if d.group(1).lower().startswith("fill") else "standard")
        depth = depth or "unknown"
    if sc is not None and sc in SCENARIOS:
        info.update(scenario=sc, difficulty=SCENARIOS[sc].difficulty, motion=SCENARIOS[sc].motion)
    info.update(time=time, light=light_period(time), depth_mode=depth)
    return info


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


def read_ordslam(path: str | os.PathLike, fps: float | None = None, layout: str | None = None) -> Trajectory:
    """Read an ORDSLAM ground-truth (or estimate) trajectory, detecting its layout.

    Args:
        path: the ``.txt`` file.
        fps: frame rate, needed when the file has frame numbers or no stamps (layouts ``index``,
            ``pose``, ``kitti``, ``index-kitti``): stamp = frame / fps, seconds.
        layout: force one of :data:`LAYOUTS` instead of detecting it.

    Returns a :class:`~lorisnb.core.trajectory.Trajectory` with ``meta = {"dataset": "ORDSLAM",
    "layout": ..., "fps": ...}``.
    """
    spath = str(path)
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
    if found not in LAYOUTS:
        raise ValueError(f"unknown layout {layout!r}; expected one of {LAYOUTS}")
    expected = {"tum": 8, "index": 8, "pose": 7, "kitti": 12, "index-kitti": 13}[found]
    if ncol != expected:
        raise ParseError(spath, int(rows[0]) + 1, f"layout {found!r} needs {expected} numbers per line, found {ncol}")
    if found != "tum" and fps is None:
        raise ParseError(
            spath,
            int(rows[0]) + 1,
            f"the file uses the {found!r} layout (frame numbers or no "
            "stamps); pass fps=... (frames per second) to turn frames into seconds",
        )
    line_no = rows + 1
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

    Layout lorisnb expects (documented in the README): ground-truth ``.txt`` files anywhere below
    ``root`` except under ``estimates/``; estimates in ``root/estimates/<algorithm>/`` with the same
    file names as the ground truth they belong to; an optional ``root/catalog.csv``.
    """

    root: Path
    groundtruth: list[Path]
    estimates: dict[str, list[Path]]
    catalog: pd.DataFrame | None

    def sequences(self) -> pd.DataFrame:
        """One row per ground-truth file with its scenario, difficulty, time, light and depth mode."""
        rows = [
            dict(path=str(p), **describe_sequence(p.relative_to(self.root), self.catalog)) for p in self.groundtruth
        ]
        return pd.DataFrame(rows)


def find_ordslam(root: str | os.PathLike | None) -> OrdslamFolder | None:
    """The ORDSLAM folder at ``root``, or None when ``root`` is None. Raises DataNotFoundError
    (naming the folder) when it is given but holds no trajectory file."""
    if root is None:
        return None
    root = Path(root).expanduser()
    if not root.is_dir():
        raise DataNotFoundError(
            f"ORDSLAM folder {root} does not exist; download the dataset (svponomarev.github.io) "
            "and pass the folder holding its ground-truth .txt files"
        )
    est_dir = root / "estimates"
    gt = sorted(p for p in root.rglob("*.txt") if est_dir not in p.parents)
    if not gt:
        raise DataNotFoundError(f"no ground-truth .txt file below {root}; expected one trajectory file per sequence")
    estimates: dict[str, list[Path]] = {}
    if est_dir.is_dir():
        for alg in sorted(d for d in est_dir.iterdir() if d.is_dir()):
            estimates[alg.name] = sorted(alg.rglob("*.txt"))
    catalog = pd.read_csv(root / "catalog.csv") if (root / "catalog.csv").exists() else None
    return OrdslamFolder(root, gt, estimates, catalog)
