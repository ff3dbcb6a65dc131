"""Where lorisnb and evo read a file differently: each file read by lorisnb (its default, and
keeping repeated stamps as evo does) and by evo's own readers (``evo.tools.file_interface``: TUM,
KITTI, EuRoC CSV, ROS 1 and ROS 2 bags, lone ``.mcap`` / ``.db3`` files), compared pose by pose.

Rows have the columns of :data:`~lorisnb.tools.peers.evo_bridge.CROSSCHECK_COLUMNS` (``alignment`` is
``none``: nothing is aligned); ``note`` says why a difference exists (repeated stamps, KITTI rotation blocks printed
to 7 digits, ...).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd

from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.errors import MissingDependencyError, ParseError
from lorisnb.io.readers.bags import read_bag
from lorisnb.io.readers.plain import read_euroc, read_kitti, read_tum
from lorisnb.tools._extras import require
from lorisnb.tools.peers.evo_bridge import CROSSCHECK_COLUMNS, agreement_row, evo_errors

READING_FORMATS = ("tum", "kitti", "euroc", "bag")


def evo_read(path: str | os.PathLike, fmt: str, topic: str | None = None):
    """The trajectory as evo's own reader gives it (``PoseTrajectory3D``, or ``PosePath3D`` for
    KITTI). ``topic``: a bag's topic or evo's TF id ``/tf:parent.child``. A file evo refuses is a
    ParseError naming it, with evo's reason."""
    with evo_errors(f"cannot read this file as {fmt}", "lorisnb's readers are more lenient (lorisnb evaluate reads it)",
                    path):  # fmt: skip
        return _evo_read(path, fmt, topic)


def _evo_read(path: str | os.PathLike, fmt: str, topic: str | None):
    fi = require("evo.tools.file_interface")
    p = Path(path)
    if fmt == "tum":
        return fi.read_tum_trajectory_file(p)
    if fmt == "kitti":
        return fi.read_kitti_poses_file(p)
    if fmt == "euroc":
        return fi.read_euroc_csv_trajectory(p)
    if fmt != "bag":
        raise ParseError(str(path), None, f"format {fmt!r}: evo reads {', '.join(READING_FORMATS)}")
    if topic is None:
        raise ParseError(str(path), None, "evo reads a bag's topic only when named: give the topic")
    if p.suffix == ".bag":
        from rosbags.rosbag1 import Reader
    else:
        from rosbags.rosbag2 import Reader  # type: ignore[assignment]
    reader = Reader(p)
    reader.open()
    try:
        return fi.read_bag_trajectory(reader, topic)
    except ImportError as exc:  # evo's TF reading imports ROS's tf2_py, which pip does not install
        raise MissingDependencyError(
            f"{path}: evo reads the TF chain {topic} only with ROS's {exc.name or 'tf2_py'} (a ROS install, not "
            "pip), which is not here: crosscheck a pose topic of the bag (--topic /pose), or evaluate the chain "
            "with lorisnb evaluate --tf parent:child, which reads TF itself"
        ) from None
    finally:
        reader.close()


def _lorisnb_read(path, fmt: str, repeated: str, topic: str | None) -> Trajectory:
    if fmt == "tum":
        return read_tum(path, warn=False, repeated=repeated)
    if fmt == "kitti":
        return read_kitti(path, repeated=repeated)
    if fmt == "euroc":
        return read_euroc(path, warn=False, repeated=repeated)
    return read_bag(path, topic=topic, repeated=repeated)


def _rotations_deg(q_ours: np.ndarray, evo_traj) -> np.ndarray:
    """Angle between lorisnb's orientations and evo's (its rotation matrices, as evo uses them)."""
    from scipy.spatial.transform import Rotation

    mats = np.array(evo_traj.poses_se3)[:, :3, :3]
    theirs = Rotation.from_matrix(mats)  # scipy makes the nearest rotation of a 7-digit block
    return np.degrees((Rotation.from_quat(q_ours).inv() * theirs).magnitude())


#: The rotation block's entries in a KITTI row of 12 numbers (row-major 3x4 ``[R | t]``).
_BLOCK = (0, 1, 2, 4, 5, 6, 8, 9, 10)


def written_digits(path: str | os.PathLike) -> int | None:
    """The most significant digits a KITTI file writes a rotation block's entry with (``9.999999e-01``,
    ``0.1234567``: 7; leading zeros and the exponent not counted), or None where no entry is written
    with a fractional digit. The most of any entry: writers that drop trailing zeros write fewer."""
    best = 0
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            tokens = line.split()
            if len(tokens) != 12:
                continue
            for k in _BLOCK:
                mantissa = tokens[k].lower().split("e")[0].lstrip("+-")
                if "." not in mantissa:
                    continue
                digits = mantissa.replace(".", "").lstrip("0")
                best = max(best, len(digits) if digits.isdigit() else 0)
    return best or None


def rounding_tolerance_deg(digits: int) -> float:
    """The largest angle (degrees) between two readings of one rotation block written with ``digits``
    significant digits, each reading turning the rounded block into a rotation its own way: each entry
    (at most 1 in size) is within h = 0.5e-(digits-1) of the true one, so the block within 3h
    (Frobenius), and each reading's rotation within 3h rad of the true rotation: 6h rad apart at most
    (7 digits: 1.7e-4 deg)."""
    return float(np.degrees(6 * 0.5 * 10.0 ** (1 - digits)))


def crosscheck_reading(path: str | os.PathLike, fmt: str = "tum", topic: str | None = None) -> pd.DataFrame:
    """One file read by lorisnb and by evo (see the module docstring): rows ``poses`` (lorisnb's
    default against evo), ``poses (repeated kept)``, ``stamps``, ``positions`` (metres) and
    ``orientations`` (degrees) as the largest difference between lorisnb keeping repeated stamps
    and evo, and for KITTI ``rotation block`` (evo uses the printed 3x3 block as it is); a KITTI
    file's ``orientations`` agree within the rounding of its written digits (:func:`rounding_tolerance_deg`)."""
    ours = _lorisnb_read(path, fmt, "drop", topic)
    kept = _lorisnb_read(path, fmt, "keep", topic)
    try:
        theirs = evo_read(path, fmt, topic)
    except ParseError as exc:  # lorisnb reads it, evo does not (a comma-separated or empty TUM file, ...)
        return pd.DataFrame([agreement_row("poses", "none", len(ours), np.nan, 0, f"evo refuses the file: {exc.reason}")],
                            columns=CROSSCHECK_COLUMNS)  # fmt: skip
    n_evo = int(theirs.num_poses)
    rows = []
    dropped = n_evo - len(ours)
    rows.append(agreement_row(
        "poses", "none", len(ours), n_evo, n_evo,
        "same poses" if dropped == 0 else
        f"definitions differ: lorisnb keeps the last pose of a repeated stamp (the official tool's rule), evo keeps "
        f"all ({dropped} more); read with repeated='keep' (--keep-repeated, or --conventions evo) to read as evo",
    ))  # fmt: skip
    rows.append(agreement_row("poses (repeated kept)", "none", len(kept), n_evo, n_evo, "repeated='keep'"))
    if len(kept) != n_evo:
        return pd.DataFrame(rows, columns=CROSSCHECK_COLUMNS)
    stamps = getattr(theirs, "timestamps", None)
    if stamps is not None:
        d = float(np.max(np.abs(kept.stamps - stamps))) if n_evo else 0.0
        order = "" if np.all(np.diff(stamps) >= 0) else "; evo keeps the file's order of unsorted stamps, lorisnb sorts"
        rows.append(agreement_row("stamps", "none", d, 0.0, n_evo, "largest difference, seconds" + order))
    d = float(np.max(np.abs(kept.positions - theirs.positions_xyz))) if n_evo else 0.0
    rows.append(agreement_row("positions", "none", d, 0.0, n_evo, "largest difference, metres"))
    ang = _rotations_deg(kept.quaternions, theirs) if n_evo else np.zeros(0)
    digits = written_digits(path) if fmt == "kitti" else None
    if digits is None:
        rows.append(agreement_row("orientations", "none", float(ang.max(initial=0.0)), 0.0, n_evo,
                                  "largest angle between the two readings' rotations, degrees"))  # fmt: skip
    else:  # the blocks are rounded: each reading makes its rotation of the rounded block its own way
        tol = rounding_tolerance_deg(digits)
        rows.append(agreement_row(
            "orientations", "none", float(ang.max(initial=0.0)), 0.0, n_evo,
            f"largest angle between the two readings' rotations, degrees; agrees within {tol:.2g} deg, the "
            f"rounding of the rotation blocks' {digits} written significant digits",
            tol=tol,
        ))  # fmt: skip
    if fmt == "kitti" and n_evo:
        mats = np.array(theirs.poses_se3)[:, :3, :3]
        ortho = float(np.abs(np.einsum("nij,nkj->nik", mats, mats) - np.eye(3)).max())
        rows.append(agreement_row(
            "rotation block", "none", ortho, 0.0, n_evo,
            "largest |R R^T - I| of the printed blocks: evo computes with them as they are, lorisnb with the nearest "
            "rotation; errors then differ by about this much (1e-5 for 7 printed digits)",
            tol=1e-4,
        ))  # fmt: skip
    return pd.DataFrame(rows, columns=CROSSCHECK_COLUMNS)
