"""evo's result files (``evo_ape/evo_rpe --save_results FILE.zip``, evo's ``save_res_file``):
a zip holding ``info.json`` (title, label, ref_name, est_name), ``stats.json`` (rmse, mean,
median, std, min, max, sse), one ``NAME.npy`` per array (``error_array``, ``timestamps``, ...)
and optionally the trajectories (``NAME.tum`` / ``NAME.kitti``, not read here). Read without evo.
"""

from __future__ import annotations

import io
import json
import math
import os
import re
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from lorisnb.errors import ParseError

#: evo's pose relation names (``PoseRelation`` values, in titles) -> the ``-r`` spelling.
EVO_RELATION_NAMES = {
    "translation part": "trans_part", "rotation part": "rot_part", "full transformation": "full",
    "rotation angle in degrees": "angle_deg", "rotation angle in radians": "angle_rad",
    "point distance": "point_distance", "point distance error ratio": "point_distance_error_ratio",
}  # fmt: skip


@dataclass(frozen=True)
class EvoResult:
    """One evo result file.

    Attributes:
        path: the zip file.
        metric: ``ape`` or ``rpe``.
        relation: the pose relation, as evo's ``-r`` option spells it (``trans_part``, ``angle_deg``...).
        unit: the unit of the errors (``m``, ``deg``, ``rad``, ``%`` or ``""``).
        title: evo's title (metric, relation, alignment, delta).
        ref_name, est_name: the reference and estimate names evo recorded (file names or topics).
        stats: rmse, mean, median, std, min, max, sse.
        arrays: every array of the file (``error_array``, ``timestamps``, ``seconds_from_start``...).
    """

    path: Path
    metric: str
    relation: str
    unit: str
    title: str
    ref_name: str
    est_name: str
    stats: dict[str, float]
    arrays: dict[str, np.ndarray] = field(default_factory=dict, repr=False)

    @property
    def errors(self) -> np.ndarray:
        """The per-pose (APE) or per-pair (RPE) errors."""
        return self.arrays.get("error_array", np.zeros(0))


def read_evo_result(path: str | os.PathLike) -> EvoResult:
    """Read an evo ``--save_results`` zip (see the module docstring); ParseError if it is not one."""
    spath = str(path)
    try:
        archive = zipfile.ZipFile(path)
    except (OSError, zipfile.BadZipFile) as exc:
        raise ParseError(spath, None, f"not a readable zip file ({exc}); expected an evo --save_results file") from None
    with archive:
        names = archive.namelist()
        if not {"info.json", "stats.json"} <= set(names):
            raise ParseError(spath, None, "no info.json and stats.json inside; expected an evo --save_results zip")
        try:
            info = json.loads(archive.read("info.json").decode("utf-8"))
            stats = {k: float(v) for k, v in json.loads(archive.read("stats.json").decode("utf-8")).items()}
            arrays = {}
            for name in names:
                if name.endswith((".npy", ".npz")):
                    arrays[Path(name).stem] = np.load(io.BytesIO(archive.read(name)), allow_pickle=False)
        except (ValueError, UnicodeDecodeError, TypeError) as exc:
            raise ParseError(spath, None, f"unreadable evo result content ({exc})") from None
    title = str(info.get("title", ""))
    label = str(info.get("label", ""))
    metric = label.split(" ")[0].lower() if label else title.split(" ")[0].lower()
    if metric not in ("ape", "rpe"):
        raise ParseError(spath, None, f"evo result of {label or title!r}: expected an APE or RPE result")
    m = re.search(r"w\.r\.t\. (.+?) \(", title.splitlines()[0] if title else "")
    relation_text = m.group(1) if m else ""
    unit_match = re.search(r"\(([^)]*)\)\s*$", label)
    return EvoResult(
        path=Path(path), metric=metric, relation=EVO_RELATION_NAMES.get(relation_text, relation_text),
        unit=unit_match.group(1) if unit_match else "", title=title, ref_name=str(info.get("ref_name", "")),
        est_name=str(info.get("est_name", "")), stats=stats, arrays=arrays,
    )  # fmt: skip


def degrees_statistics(stats: dict[str, float]) -> dict[str, float]:
    """Statistics of an error array in radians, converted to degrees (sse by the square)."""
    f = 180.0 / math.pi
    return {k: v * f * f if k == "sse" else v * f for k, v in stats.items()}
