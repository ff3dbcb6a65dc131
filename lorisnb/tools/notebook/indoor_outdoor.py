"""Indoor (OpenLORIS-Scene, TUM RGB-D) against outdoor (ORDSLAM): tables of trajectory statistics
and normalized difficulty measures (:mod:`lorisnb.core.metrics.difficulty`) for every dataset at hand, with the
same columns so they can be stacked and grouped."""

from __future__ import annotations

import warnings
from typing import Iterable

import numpy as np
import pandas as pd

from lorisnb.core.alignment.association import groundtruth_in_frame
from lorisnb.core.metrics.difficulty import difficulty_measures, trajectory_stats
from lorisnb.core.pipeline.plausibility import time_overlap
from lorisnb.core.pipeline.sessions import sequence_errors
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.errors import LorisError, LorisWarning
from lorisnb.io.datasets.paths import DataPaths, load_groundtruth
from lorisnb.io.datasets.published import ORDSLAM_MEAN_LENGTH_M
from lorisnb.io.readers.ordslam import OrdslamFolder, read_ordslam
from lorisnb.io.readers.plain import read_tum
from lorisnb.tools.evaluation.result import Evaluation

#: The bundled TUM RGB-D pairs: (sequence, ground truth, estimate, algorithm).
TUM_PAIRS = (
    ("fr2/desk", "fr2_desk_groundtruth.txt", "fr2_desk_ORB.txt", "ORB-SLAM2"),
    ("fr1/xyz", "freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt", "RGBD-SLAM"),
)


def openloris_stats(data: DataPaths, scenes: Iterable[str] | None = None) -> pd.DataFrame:
    """Trajectory statistics of every OpenLORIS ground-truth sequence (base_link)."""
    rows = []
    for scene in scenes or data.scenes_with_groundtruth():
        for seq, t in load_groundtruth(scene, data).sequences.items():
            rows.append(dict(dataset="OpenLORIS-Scene", group=scene, sequence=f"{scene}-{seq}", **trajectory_stats(t)))
    return pd.DataFrame(rows)


def tum_stats(data: DataPaths) -> pd.DataFrame:
    rows = [
        dict(dataset="TUM RGB-D", group=name, sequence=name, **trajectory_stats(read_tum(data.tum / g)))
        for name, g, _, _ in TUM_PAIRS
    ]
    return pd.DataFrame(rows)


def ordslam_stats(folder: OrdslamFolder, fps: float | None = None, problems: list[dict] | None = None) -> pd.DataFrame:
    """Trajectory statistics of every ORDSLAM ground-truth file, with its scenario, time, light,
    depth mode and the fps it was read with (the catalog's, else ``fps``). A file that cannot be
    read raises, or, when a ``problems`` list is given, is appended to it (``file, status, kind,
    error``, as :func:`ordslam_difficulty`'s) and left out."""
    rows = []
    for p in folder.groundtruth:
        info = folder.describe(p)
        try:
            traj = read_ordslam(p, info["fps"] or fps)
        except LorisError as exc:
            if problems is None:
                raise
            problems.append(dict(file=str(p), status="failed", kind="ORDSLAM ground truth", error=str(exc)))
            continue
        rows.append(
            dict(
                dataset="ORDSLAM",
                group=info["difficulty"],
                sequence=folder.relative(p),
                scenario=info["scenario"],
                time=info["time"],
                light=info["light"],
                depth_mode=info["depth_mode"],
                fps=info["fps"] or fps,
                **trajectory_stats(traj),
            )
        )
    return pd.DataFrame(rows)


def openloris_difficulty(
    ev: Evaluation, data: DataPaths, eps_fraction: float = 0.1, rpe_metres: float = 1.0, relative_to: str = "extent"
) -> pd.DataFrame:
    """Normalized measures of every evaluated OpenLORIS sequence (ground truth in the estimate's frame)."""
    rows = []
    for f in ev.errors:
        gt_file = load_groundtruth(f.scene, data)
        for e in f.sequences:
            gt = groundtruth_in_frame(gt_file.sequences[e.seq], f.scene, f.frame)
            rows.append(
                dict(
                    dataset="OpenLORIS-Scene",
                    group=f.scene,
                    sequence=f"{f.scene}-{e.seq}",
                    algorithm=f.algorithm,
                    **difficulty_measures(e, gt, eps_fraction, rpe_metres, relative_to=relative_to),
                )
            )
    return pd.DataFrame(rows)


def tum_difficulty(
    data: DataPaths, eps_fraction: float = 0.1, rpe_metres: float = 1.0, relative_to: str = "extent"
) -> pd.DataFrame:
    rows = []
    for name, g, e, alg in TUM_PAIRS:
        gt, est = read_tum(data.tum / g), read_tum(data.tum / e)
        rows.append(
            dict(
                dataset="TUM RGB-D",
                group=name,
                sequence=name,
                algorithm=alg,
                **difficulty_measures(sequence_errors(gt, est), gt, eps_fraction, rpe_metres, relative_to=relative_to),
            )
        )
    return pd.DataFrame(rows)


def ordslam_difficulty(
    folder: OrdslamFolder,
    fps: float | None = None,
    max_gap: float = 0.5,
    scale: bool = False,
    eps_fraction: float = 0.1,
    rpe_metres: float = 1.0,
    relative_to: str = "extent",
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Measures of every ORDSLAM estimate (``estimates/<algorithm>/<path of its ground truth>``,
    :meth:`~lorisnb.io.readers.ordslam.OrdslamFolder.pairs`). Returns (table, problems): an estimate
    without exactly one ground truth, or unreadable, is a row of ``problems`` (columns ``file,
    status, kind, error``, as :meth:`~lorisnb.tools.evaluation.result.Evaluation.failures_table`), not fatal;
    so is ("not scored", :func:`unmatched_reason`) one of which no pose could be matched: its stamps
    outside the ground truth's time span or the ground truth sparser than ``max_gap``."""
    pairs, unmatched = folder.pairs()
    rows = []
    problems = [dict(file=str(p), status="failed", kind="ORDSLAM estimate", error=why) for p, why in unmatched]
    for alg, est_path, gt_path in pairs:
        info = folder.describe(gt_path)
        rate = info["fps"] or fps  # the catalog's fps of this sequence, else the folder's
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", LorisWarning)
                gt, est = read_ordslam(gt_path, rate), read_ordslam(est_path, rate)
        except LorisError as exc:
            problems.append(dict(file=str(est_path), status="failed", kind="ORDSLAM estimate", error=str(exc)))
            continue
        e = sequence_errors(gt, est, scale=scale, max_gap=max_gap)
        if e.matched == 0:  # a time base or max_gap that does not fit, not an algorithm lost all along
            why = unmatched_reason(str(est_path), gt, est, max_gap)
            problems.append(dict(file=str(est_path), status="not scored", kind="ORDSLAM estimate", error=why))
            continue
        rows.append(
            dict(
                dataset="ORDSLAM",
                group=info["difficulty"],
                sequence=folder.relative(gt_path),
                algorithm=alg,
                scenario=info["scenario"],
                time=info["time"],
                light=info["light"],
                depth_mode=info["depth_mode"],
                **difficulty_measures(e, gt, eps_fraction, rpe_metres, relative_to=relative_to),
            )
        )
    return pd.DataFrame(rows), pd.DataFrame(problems, columns=["file", "status", "kind", "error"])


def unmatched_reason(label: str, gt: Trajectory, est: Trajectory, max_gap: float) -> str:
    """Why no estimate pose of an ORDSLAM pair was matched: stamps outside the ground truth's time
    span (another time base: seconds against frame numbers, a clock offset), or ground-truth poses
    further apart than ``max_gap`` (sparse key frames)."""
    outside = time_overlap(label, est.stamps, float(gt.stamps[0]), float(gt.stamps[-1]))
    if outside is not None:
        return (
            outside + " (ORDSLAM: the ground truth and the estimate need the same time base; a file of frame "
            "numbers is turned into seconds with fps)"
        )
    spacing = float(np.median(np.diff(gt.stamps))) if len(gt) > 1 else float("nan")
    return (
        f"{label}: no estimate pose matched a ground-truth pose within max_gap={max_gap:g} s; the ground truth's "
        f"poses are {spacing:.3g} s apart (median): raise max_gap (ordslam_max_gap) above that spacing"
    )


def length_contrast(stats: pd.DataFrame, scenes: Iterable[str] = ("market", "corridor")) -> str:
    """The sentence on path lengths the notebook's reading rests on, computed: the median ground-truth
    path length (metres) of OpenLORIS' ``scenes`` against ORDSLAM's (the sequences of ``stats`` where
    it holds any, else the paper's 12 m mean of its difficult scenarios), and how many times as
    long, longer or shorter as the numbers say."""
    med = stats.groupby(["dataset", "group"], sort=False)["length_m"].median()
    loris = {g: float(med[("OpenLORIS-Scene", g)]) for g in scenes if ("OpenLORIS-Scene", g) in med.index}
    if not loris:
        return "No OpenLORIS sequence of " + " or ".join(scenes) + " here: no path length to compare."
    ords = stats.loc[stats["dataset"] == "ORDSLAM", "length_m"]
    if len(ords):
        other, source = (
            float(ords.median()),
            f"ORDSLAM {float(ords.median()):.0f} m (median of your folder's {len(ords)} sequences)",
        )
    else:
        other, source = (
            ORDSLAM_MEAN_LENGTH_M,
            f"ORDSLAM {ORDSLAM_MEAN_LENGTH_M:.0f} m (the paper's mean of its difficult scenarios)",
        )
    ratios = [v / other for v in loris.values()]
    lo, hi = min(ratios), max(ratios)
    if lo > 1:
        how = f"{lo:.1f} to {hi:.1f} times as long" if hi - lo >= 0.05 else f"{lo:.1f} times as long"
    elif hi < 1:
        how = f"shorter ({lo:.2f} to {hi:.2f} of its length)"
    else:
        how = f"from {lo:.2f} to {hi:.2f} times its length"
    shown = " and ".join(f"{g} {v:.0f} m" for g, v in loris.items())
    return f"Median path length: OpenLORIS {shown}; {source}: the OpenLORIS paths are {how}."


def headline(measures: pd.DataFrame, published_ate: pd.DataFrame) -> dict[str, dict]:
    """The numbers the comparison's conclusions rest on: median ATE as % of path per computed
    dataset, the range of the published ORDSLAM and TUM values, median share of time tracked."""
    pub = published_ate.groupby("dataset")["ate_pct_length"]
    return dict(
        computed_ate_pct=measures.groupby("dataset")["ate_pct_length"].median().to_dict(),
        published_ate_pct_range={k: (float(v.min()), float(v.max())) for k, v in pub},
        tracked_share=measures.groupby("dataset")["tracked_share"].median().to_dict(),
    )
