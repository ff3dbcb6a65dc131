"""Old evo results next to new ones: :func:`evo_results_table` turns evo ``--save_results`` zip
files (:func:`lorisnb.io.evo_results.read_evo_result`) into rows with lorisnb's sequence-table
column names, so that they can be ranked and reported with lorisnb's own rows.

Columns: ``algorithm`` (the estimate's file stem or topic), ``file`` (evo's est_name),
``reference`` (ref_name), ``alignment`` (what evo's title says), ``matched`` (APE poses),
``rpe_pairs``, ``rpe_delta`` (evo's delta text), then evo's seven statistics as ``ate_*`` (APE
translation part, m), ``aoe_*`` (APE rotation angle, deg), ``rpe_trans_*`` (m), ``rpe_rot_*``
(deg): angles saved in radians are converted to degrees. Results of other pose relations go to
``ape_RELATION_*`` / ``rpe_RELATION_*`` columns; ``sources`` lists the zip files of each row.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

import pandas as pd

from ..io.evo_results import EvoResult, degrees_statistics, read_evo_result

_PREFIX = {("ape", "trans_part"): "ate", ("ape", "point_distance"): "ate", ("ape", "angle_deg"): "aoe",
           ("ape", "angle_rad"): "aoe", ("rpe", "trans_part"): "rpe_trans", ("rpe", "angle_deg"): "rpe_rot",
           ("rpe", "angle_rad"): "rpe_rot"}  # fmt: skip


def _alignment(r: EvoResult) -> str:
    return " ".join(line.strip("() ") for line in r.title.splitlines()[1:] if line.startswith("("))


def evo_results_table(paths: Iterable[str | os.PathLike]) -> pd.DataFrame:
    """One row per (reference, estimate, alignment) of the evo result files ``paths`` (see the
    module docstring); a folder stands for the ``.zip`` files in it."""
    files: list[Path] = []
    for p in paths:
        p = Path(p)
        files.extend(sorted(p.glob("*.zip")) if p.is_dir() else [p])
    rows: dict[tuple[str, str, str], dict] = {}
    for f in files:  # one per result file
        r = read_evo_result(f)
        key = (r.ref_name, r.est_name, _alignment(r))
        row = rows.setdefault(
            key,
            dict(algorithm=Path(r.est_name).stem if r.est_name else f.stem, file=r.est_name, reference=r.ref_name,
                 alignment=key[2], sources=[]),
        )  # fmt: skip
        row["sources"].append(str(f))
        prefix = _PREFIX.get((r.metric, r.relation), f"{r.metric}_{r.relation}")
        stats = (
            degrees_statistics(r.stats) if r.relation == "angle_rad" and prefix != f"{r.metric}_angle_rad" else r.stats
        )
        row.update({f"{prefix}_{k}": v for k, v in stats.items()})
        if r.metric == "ape":
            row["matched"] = int(r.errors.size)
        else:
            row["rpe_pairs"] = int(r.errors.size)
            lines = r.title.splitlines()
            row["rpe_delta"] = next((ln.strip() for ln in lines if ln.startswith("for delta")), "")
    table = pd.DataFrame(list(rows.values()))
    if len(table):
        table["sources"] = table["sources"].map(";".join)
    return table
