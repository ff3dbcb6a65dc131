"""Old evo results next to new ones: :func:`evo_results_table` turns evo ``--save_results`` zip
files (:func:`lorisnb.io.readers.evo_results.read_evo_result`) into rows with lorisnb's sequence-table
column names, so that they can be ranked and reported with lorisnb's own rows.

Columns: ``algorithm`` (the estimate's file stem or topic), ``file`` (evo's est_name),
``reference`` (ref_name), ``alignment`` (what evo's title says), ``matched`` (APE poses),
``rpe_pairs``, ``rpe_delta`` (evo's delta text), then evo's seven statistics as ``ate_*`` (APE
translation part, m), ``aoe_*`` (APE rotation angle, deg), ``rpe_trans_*`` (m), ``rpe_rot_*``
(deg): angles saved in radians are converted to degrees. Results of other pose relations go to
``ape_RELATION_*`` / ``rpe_RELATION_*`` columns; ``sources`` lists the zip files of each row.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import pandas as pd

from lorisnb.errors import ParseError
from lorisnb.io.readers.evo_results import EvoResult, degrees_statistics, read_evo_result

_PREFIX = {("ape", "trans_part"): "ate", ("ape", "point_distance"): "ate", ("ape", "angle_deg"): "aoe",
           ("ape", "angle_rad"): "aoe", ("rpe", "trans_part"): "rpe_trans", ("rpe", "angle_deg"): "rpe_rot",
           ("rpe", "angle_rad"): "rpe_rot"}  # fmt: skip


#: evo's output units (``--change_unit``) in metres or degrees, lorisnb's units for the columns.
_TO_BASE = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "km": 1e3, "deg": 1.0, "rad": 180.0 / math.pi}
_ANGLE_UNITS = ("deg", "rad")


def _alignment(r: EvoResult) -> str:
    return " ".join(line.strip("() ") for line in r.title.splitlines()[1:] if line.startswith("("))


def _columns(r: EvoResult) -> dict[str, float]:
    """The statistic columns of one result, in metres (lengths) or degrees (angles) whatever unit
    evo wrote them in (``--change_unit mm``, ``-r angle_deg --change_unit rad``); the relations
    without a unit (``full``, ``rot_part``, ``point_distance_error_ratio``) keep evo's numbers."""
    prefix = _PREFIX.get((r.metric, r.relation), f"{r.metric}_{r.relation}")
    factor = 1.0
    if r.relation in ("trans_part", "point_distance", "angle_deg", "angle_rad"):
        angle = r.relation.startswith("angle")
        if r.unit not in _TO_BASE or (r.unit in _ANGLE_UNITS) != angle:  # evo converts none else
            raise ParseError(str(r.path), None, f"{r.metric} {r.relation} in {r.unit or 'no unit'}: expected "
                             f"{'deg or rad' if angle else 'm, mm, cm or km'}")  # fmt: skip
        factor = _TO_BASE[r.unit]
    stats = degrees_statistics(r.stats) if factor == _TO_BASE["rad"] else {
        k: v * factor * factor if k == "sse" else v * factor for k, v in r.stats.items()}  # fmt: skip
    return {f"{prefix}_{k}": v for k, v in stats.items()}


def _same(a: object, b: object) -> bool:
    """Two values of one column equal (numbers to 1e-12 relative: one zip in mm, one in m)."""
    if isinstance(a, float) and isinstance(b, float):
        return math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-300) or (math.isnan(a) and math.isnan(b))
    return a == b


def evo_results_table(paths: Iterable[str | os.PathLike]) -> pd.DataFrame:
    """One row per (reference, estimate, alignment) of the evo result files ``paths`` (see the
    module docstring); a folder stands for the ``.zip`` files in it. Results that would fill the
    same columns with other numbers (RPE at two deltas, APE after two sync settings, which evo's
    title does not record) make more rows for that estimate, row k holding the k-th set of each
    metric (or its only one): no number is overwritten. ``rpe_delta`` and ``rpe_pairs`` are those
    of the row's translation RPE (else of its first RPE). Statistics are in metres and degrees,
    whatever ``--change_unit`` evo was given."""
    files: list[Path] = []
    for p in paths:
        p = Path(p)
        files.extend(sorted(p.glob("*.zip")) if p.is_dir() else [p])
    groups: dict[tuple[str, str, str], dict[str, list[dict]]] = {}
    for f in files:  # one per result file
        r = read_evo_result(f)
        key = (r.ref_name, r.est_name, _alignment(r))
        stats: dict[str, Any] = _columns(r)
        if r.metric == "ape":
            stats["matched"] = int(r.errors.size)
        slots = groups.setdefault(key, {"ape": [], "rpe": []})[r.metric]
        slot = next((x for x in slots if all(_same(x.get(k, v), v) for k, v in stats.items())), None)
        if slot is None:
            slot = {"_src": []}
            slots.append(slot)
        slot["_src"].append(str(f))
        if r.metric == "rpe" and ("rpe_pairs" not in slot or r.relation == "trans_part"):
            lines = r.title.splitlines()
            slot["rpe_pairs"] = int(r.errors.size)
            slot["rpe_delta"] = next((ln.strip() for ln in lines if ln.startswith("for delta")), "")
        slot.update(stats)
    rows = []
    for (ref, est, alignment), metrics in groups.items():
        ape, rpe = metrics["ape"] or [{"_src": []}], metrics["rpe"] or [{"_src": []}]
        for k in range(max(len(ape), len(rpe))):
            a, b = ape[min(k, len(ape) - 1)], rpe[min(k, len(rpe) - 1)]
            rows.append(dict(algorithm=Path(est).stem if est else Path((a["_src"] or b["_src"])[0]).stem, file=est,
                             reference=ref, alignment=alignment,
                             **{c: v for c, v in (a | b).items() if c != "_src"},
                             sources=";".join(a["_src"] + b["_src"])))  # fmt: skip
    return pd.DataFrame(rows)
