"""One trajectory, every benchmark's number: the same estimate and ground truth scored under each
preset (``openloris``, ``tum``, ``rpg``, ``evo``, ``kitti``, ``tartanair``), each number beside the
rule that makes it differ from the others: for teaching, and for the README's conventions table.
Every number is computed here (:func:`lorisnb.evaluate_pairs` under each preset); none is quoted.
"""

from __future__ import annotations

import math
import os
from typing import Any

import pandas as pd

#: Why each preset's numbers differ: how it pairs, aligns and steps the RPE (its source tool).
WHY = {
    "openloris": "OpenLORIS-Scene tool: ground truth interpolated within 0.5 s, SE(3) on all matched poses, "
                 "RPE over 1 s, repeated poses dropped",
    "tum": "TUM evaluate_ate.py: nearest stamps within 0.02 s (greedy), SE(3); lorisnb's RPE over 1 s",
    "rpg": "rpg_trajectory_evaluation: nearest stamps within 0.02 s, Sim(3) (its scale), every row kept",
    "evo": "evo_ape / evo_rpe defaults: evo's nearest stamps within 0.01 s, no alignment, RPE between consecutive "
           "poses (1 frame); KITTI matrices as written",
    "kitti": "KITTI devkit evaluate_odometry.cpp: no alignment, segments of 100..800 m every 10 frames, single "
             "precision, matrices as written; t_err in %, r_err in deg/100 m",
    "tartanair": "tartanair_tools: Horn alignment inside its ATE, RPE over 10000 random pairs (seed 0), KITTI score "
                 "over 5..40 m from every frame",
}  # fmt: skip
PRESETS = tuple(WHY)
#: (column of the sequence table, quantity, unit) reported for every preset, then each preset's own.
COMMON = [("matched", "matched poses", ""), ("ate_rmse", "ATE RMSE", "m"), ("aoe_rmse", "AOE RMSE", "deg"),
          ("rpe_trans_rmse", "RPE translation RMSE", "m"), ("rpe_rot_rmse", "RPE rotation RMSE", "deg")]  # fmt: skip
OWN = {
    "kitti": [("kitti_t_err", "KITTI translational error", "%"), ("kitti_r_err", "KITTI rotational error", "deg/100 m"),
              ("kitti_segments", "KITTI segments", "")],
    "tartanair": [("tartanair_ate", "TartanAir ATE", "m"), ("tartanair_rpe_trans", "TartanAir RPE translation", "m"),
                  ("tartanair_rpe_rot", "TartanAir RPE rotation", "rad"),
                  ("tartanair_kitti_t", "TartanAir KITTI translation", "m/m"),
                  ("tartanair_kitti_r", "TartanAir KITTI rotation", "deg/m")],
}  # fmt: skip


def every_number(
    estimate: str | os.PathLike[str], groundtruth: str | os.PathLike[str], fmt: str = "tum",
    gt_fmt: str | None = None, presets: tuple[str, ...] = PRESETS, **options: Any,
) -> pd.DataFrame:  # fmt: skip
    """Long table of one pair under every preset: ``preset``, ``quantity``, ``value``, ``unit``,
    ``why`` (the preset's rule, :data:`WHY`). ``options`` go to :func:`lorisnb.evaluate_pairs` (times
    files, topics). A preset whose pairing fails (an estimate not matching in time) gives NaN values
    and the reason in ``why``."""
    from lorisnb.core.spec.validate import choice
    from lorisnb.errors import LorisError
    from lorisnb.tools.evaluation.runner import evaluate_pairs

    rows = []
    for preset in presets:
        choice("preset", preset, PRESETS)
        wanted = COMMON + OWN.get(preset, [])
        why = WHY[preset]
        try:
            ev = evaluate_pairs(estimate, groundtruth, preset, fmt=fmt, gt_fmt=gt_fmt, **options)
            table = ev.sequences()
            row = table.iloc[0] if len(table) else None
            if row is None or not row["matched"]:
                reasons = [f.error for f in (*ev.failures, *ev.unscored)]
                why += f" (not scored: {reasons[0] if reasons else 'no pose matched'})"
        except LorisError as exc:
            row, why = None, f"{why} (not scored: {exc})"
        for col, quantity, unit in wanted:
            value = float(row[col]) if row is not None and col in row.index else math.nan
            rows.append(dict(preset=preset, quantity=quantity, value=value, unit=unit, why=why))
    return pd.DataFrame(rows, columns=["preset", "quantity", "value", "unit", "why"])


def side_by_side(table: pd.DataFrame) -> pd.DataFrame:
    """:func:`every_number`'s table with one column per preset (quantities as rows, units kept)."""
    keys = list(dict.fromkeys(zip(table["quantity"], table["unit"], strict=True)))
    wide = table.set_index(["quantity", "unit", "preset"])["value"].unstack("preset")
    wide = wide.reindex(pd.MultiIndex.from_tuples(keys, names=["quantity", "unit"]))
    return wide[[p for p in PRESETS if p in wide.columns]]
