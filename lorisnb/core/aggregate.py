"""Per-scene aggregates of per-sequence tables, as in the paper's Fig. 2 and Fig. 3 and the
official ``evaluate_all.py``. Pure: the ground-truth durations are an argument
(:func:`durations_table` builds them from ground-truth files already read)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd

from ..errors import EvaluationError
from .frames import SCENES
from .model import SCENE_COLUMNS, ResultFile

DURATION_COLUMNS = ["scene", "seq", "gt_start", "gt_end", "gt_duration"]


def durations_table(groundtruths: Mapping[str, ResultFile]) -> pd.DataFrame:
    """Ground-truth span of every sequence of each scene: first and last stamp and duration,
    seconds. ``groundtruths`` maps scene -> its ground-truth file."""
    return spans_table(
        {
            scene: {s: (float(t.stamps[0]), float(t.stamps[-1])) for s, t in gt.sequences.items() if len(t)}
            for scene, gt in groundtruths.items()
        }
    )


def spans_table(spans: Mapping[str, Mapping[int, tuple[float, float]]]) -> pd.DataFrame:
    """:func:`durations_table` from the spans alone: scene -> sequence -> (first, last stamp, seconds)."""
    rows = [
        dict(scene=scene, seq=s, gt_start=start, gt_end=end, gt_duration=end - start)
        for scene, by_seq in spans.items()
        for s, (start, end) in by_seq.items()
    ]
    return pd.DataFrame(rows, columns=DURATION_COLUMNS)


def aggregate_scenes(sequences: pd.DataFrame, durations: pd.DataFrame) -> pd.DataFrame:
    """Per algorithm and scene, as in the paper's Fig. 2 and Fig. 3:

    - ``cr``: sum of correct time / sum of the ground-truth durations of *all* the scene's
      sequences (a sequence the algorithm has no result for counts as not tracked);
    - ``cr_t``: sum of correct time / sum of tracked time (t_max - t0);
    - ``c_ate_rmse``: mean of per-sequence C-ATE RMSE weighted by their correct-pose counts (the
      paper's figure value); ``c_ate_rmse_pooled``: RMSE over all correct poses of the scene;
    - ``ate_rmse``: the same weighted mean of ATE RMSE over matched poses (Fig. 2's value);
    - ``cs_r_mean``: mean CS-R over the sequences evaluated.

    Args:
        sequences: a per-sequence table (:func:`lorisnb.core.scoring.score` or a sweep).
        durations: :func:`durations_table` of the scenes in ``sequences``.

    Rows are grouped by ``suite``, ``algorithm``, ``scene`` and the thresholds.
    """
    if sequences.empty:
        return pd.DataFrame(columns=SCENE_COLUMNS)
    missing = sorted(set(sequences["scene"].astype(str)) - set(durations["scene"].astype(str)))
    if missing:
        raise EvaluationError(f"no ground-truth durations for scene(s) {', '.join(missing)}; pass their durations")
    total = durations.groupby("scene")["gt_duration"].sum()
    nseq = durations.groupby("scene")["seq"].count()
    keys = ["suite", "algorithm", "scene", "eps", "phi", "delta", "tau"]
    keys += [c for c in ("eps_value", "trial") if c in sequences.columns]  # a sweep: eps as given; trials
    dup = sequences.duplicated(subset=keys + ["seq"], keep=False)
    if dup.any():
        d = sequences[dup].iloc[0]
        same_seq = (sequences["algorithm"] == d["algorithm"]) & (sequences["scene"] == d["scene"])
        same = sequences[dup & same_seq & (sequences["seq"] == d["seq"])]["file"].astype(str).unique()
        raise EvaluationError(
            f"several results for {d['algorithm']} {d['scene']}-{d['seq']} ({', '.join(same[:3])}); "
            "evaluate them in separate folders (suites)"
        )
    df = sequences.copy()
    df["_c_sq"] = np.where(df["c_matched"] > 0, df["c_ate_rmse"] ** 2 * df["c_matched"], 0.0)
    df["_c_w"] = np.where(df["c_matched"] > 0, df["c_ate_rmse"] * df["c_matched"], 0.0)
    df["_a_w"] = np.where(df["matched"] > 0, df["ate_rmse"] * df["matched"], 0.0)
    g = df.groupby(keys, sort=False, dropna=False, observed=True)
    out = g.agg(
        sequences=("seq", "count"), matched=("matched", "sum"), c_matched=("c_matched", "sum"),
        correct_time=("correct_time", "sum"), track_time=("track_time", "sum"), cs_r_mean=("cs_r", "mean"),
        _c_sq=("_c_sq", "sum"), _c_w=("_c_w", "sum"), _a_w=("_a_w", "sum"),
    ).reset_index()  # fmt: skip
    out["scene_sequences"] = out["scene"].astype(str).map(nseq).astype(int)
    out["scene_duration"] = out["scene"].astype(str).map(total)
    with np.errstate(invalid="ignore", divide="ignore"):
        out["cr"] = out["correct_time"] / out["scene_duration"]
        out["cr_t"] = np.where(out["track_time"] > 0, out["correct_time"] / out["track_time"], np.nan)
        out["c_ate_rmse"] = np.where(out["c_matched"] > 0, out["_c_w"] / out["c_matched"], np.nan)
        out["c_ate_rmse_pooled"] = np.where(out["c_matched"] > 0, np.sqrt(out["_c_sq"] / out["c_matched"]), np.nan)
        out["ate_rmse"] = np.where(out["matched"] > 0, out["_a_w"] / out["matched"], np.nan)
    order = {s: i for i, s in enumerate(SCENES)}
    out = out.drop(columns=["_c_sq", "_c_w", "_a_w"])[SCENE_COLUMNS + keys[7:]]
    out = out.sort_values(
        ["suite", "algorithm", "scene"] + (["trial"] if "trial" in out.columns else []),
        key=lambda c: c.map(order) if c.name == "scene" else (c if c.name == "trial" else c.astype(str)),
    )
    return out.reset_index(drop=True)
