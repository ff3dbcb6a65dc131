"""Old evo results next to new ones: :func:`evo_results_table` turns evo ``--save_results`` zip
files (:func:`lorisnb.io.readers.evo_results.read_evo_result`) into rows with lorisnb's sequence-table
column names, so that they can be ranked and reported with lorisnb's own rows.

Columns: ``algorithm`` (the estimate's file stem or topic), ``file`` (evo's est_name),
``reference`` (ref_name), ``alignment`` (what evo's title says), ``matched`` (APE poses),
``rpe_pairs``, ``rpe_delta`` (evo's delta text), ``t_first`` and ``t_last`` (the first and last
stamp of the poses the run used, NaN where its file has no stamps), then evo's seven statistics as ``ate_*`` (APE
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

import numpy as np
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


def _fingerprint(r: EvoResult) -> dict[str, Any]:
    """What an evo run's file says about the poses it used: ``t_first`` (the first synced pose's
    stamp: evo's ``timestamps`` minus ``seconds_from_start``), ``stamps`` (APE: every synced pose's
    estimate stamp; RPE: each pair's end), ``alignment_matrix`` (evo's fitted Sim(3), when aligned).
    Missing arrays (a run without stamps, KITTI) give None."""
    t = r.arrays.get("timestamps")
    since = r.arrays.get("seconds_from_start")
    first = float(t[0] - since[0]) if t is not None and since is not None and len(t) and len(since) else None
    return dict(t_first=first, stamps=None if t is None else np.asarray(t, float),
                alignment_matrix=r.arrays.get("alignment_transformation_sim3"))  # fmt: skip


def _compatible(ape: dict[str, Any], rpe: dict[str, Any]) -> bool:
    """Whether an APE run and an RPE run used the same synced poses and the same alignment (the same
    settings, as far as their files tell): the same first pose, every RPE pair end among the APE's
    poses, the same fitted alignment. What a file does not record is not held against the join."""
    if ape["t_first"] is not None and rpe["t_first"] is not None and ape["t_first"] != rpe["t_first"]:
        return False
    if ape["stamps"] is not None and rpe["stamps"] is not None and not np.isin(rpe["stamps"], ape["stamps"]).all():
        return False
    a, b = ape["alignment_matrix"], rpe["alignment_matrix"]
    if (a is None) != (b is None):
        return False
    return a is None or bool(np.allclose(a, b, rtol=1e-12, atol=1e-12))


def _same_run(slot: dict[str, Any], fp: dict[str, Any]) -> bool:
    """Whether a result belongs to a slot's settings (one APE run's relations, one RPE run's)."""
    mine = slot["_fp"]
    if mine["t_first"] != fp["t_first"]:
        return False
    if (mine["stamps"] is None) != (fp["stamps"] is None) or (
        mine["stamps"] is not None and not np.array_equal(mine["stamps"], fp["stamps"])
    ):
        return False
    a, b = mine["alignment_matrix"], fp["alignment_matrix"]
    return (a is None) == (b is None) and (a is None or bool(np.array_equal(a, b)))


def evo_results_table(paths: Iterable[str | os.PathLike]) -> pd.DataFrame:
    """One row per evo run of the result files ``paths`` (see the module docstring; a folder stands
    for the ``.zip`` files in it), with its settings: ``alignment``, ``rpe_delta``, ``t_first`` and
    ``t_last`` (the stamps of the first and last pose it used), ``sources``. Results of one run
    (the same poses and alignment: an APE's translation and its angle) share a row; an APE run and an
    RPE run are joined in one row only when they are the same pair under the same settings as far as
    the files tell (the same first synced pose, every RPE pair end among the APE's poses, the same
    fitted alignment): an APE of a ``--t_start`` run is not put next to a full-range RPE, and no RPE is
    copied into two rows (an APE run may head several RPE rows: RPE at two deltas of the same run).
    Results that would fill the same columns with other numbers make more rows. Statistics are in
    metres and degrees, whatever ``--change_unit`` evo was given."""
    files: list[Path] = []
    for p in paths:
        p = Path(p)
        files.extend(sorted(p.glob("*.zip")) if p.is_dir() else [p])
    groups: dict[tuple[str, str, str], dict[str, list[dict]]] = {}
    for f in files:  # one per result file
        r = read_evo_result(f)
        key = (r.ref_name, r.est_name, _alignment(r))
        stats: dict[str, Any] = _columns(r)
        fp = _fingerprint(r)
        if r.metric == "ape":
            stats["matched"] = int(r.errors.size)
        slots = groups.setdefault(key, {"ape": [], "rpe": []})[r.metric]
        delta = next((ln.strip() for ln in r.title.splitlines() if ln.startswith("for delta")), "")
        slot = next((x for x in slots if _same_run(x, fp) and x.get("_delta", delta) == delta
                     and all(_same(x.get(k, v), v) for k, v in stats.items())), None)  # fmt: skip
        if slot is None:
            slot = {"_src": [], "_fp": fp}
            slots.append(slot)
        slot["_src"].append(str(f))
        if r.metric == "rpe":
            slot["_delta"] = delta
            if "rpe_pairs" not in slot or r.relation == "trans_part":
                slot["rpe_pairs"] = int(r.errors.size)
                slot["rpe_delta"] = delta
        slot.update(stats)
    rows = []

    def row(ref: str, est: str, alignment: str, a: dict, b: dict) -> dict[str, Any]:
        src = a.get("_src", []) + b.get("_src", [])
        stamps = [x["_fp"]["stamps"] for x in (a, b) if "_fp" in x and x["_fp"]["stamps"] is not None]
        firsts = [x["_fp"]["t_first"] for x in (a, b) if "_fp" in x and x["_fp"]["t_first"] is not None]
        return dict(algorithm=Path(est).stem if est else Path(src[0]).stem, file=est, reference=ref, alignment=alignment,
                    t_first=firsts[0] if firsts else math.nan,
                    t_last=max(float(s[-1]) for s in stamps) if any(len(s) for s in stamps) else math.nan,
                    **{c: v for c, v in (a | b).items() if not c.startswith("_")}, sources=";".join(src))  # fmt: skip

    for (ref, est, alignment), metrics in groups.items():
        used: set[int] = set()
        for b in metrics["rpe"]:
            k = next((k for k, a in enumerate(metrics["ape"]) if _compatible(a["_fp"], b["_fp"])), None)
            if k is not None:
                used.add(k)
            rows.append(row(ref, est, alignment, metrics["ape"][k] if k is not None else {}, b))
        rows += [row(ref, est, alignment, a, {}) for k, a in enumerate(metrics["ape"]) if k not in used]
    return pd.DataFrame(rows)
