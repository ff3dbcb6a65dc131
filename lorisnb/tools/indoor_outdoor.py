"""Indoor (OpenLORIS-Scene, TUM RGB-D) against outdoor (ORDSLAM): tables of trajectory statistics
and normalized difficulty measures (:mod:`lorisnb.core.difficulty`) for every dataset at hand, with the
same columns so they can be stacked and grouped."""

from __future__ import annotations

import warnings
from typing import Iterable

import pandas as pd

from ..core.association import groundtruth_in_frame
from ..core.difficulty import difficulty_measures, trajectory_stats
from ..core.pipeline import sequence_errors
from ..errors import LorisError, LorisWarning
from ..io.data import DataPaths, load_groundtruth
from ..io.formats import read_tum
from ..io.ordslam import OrdslamFolder, read_ordslam
from .evaluation import Evaluation

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


def ordslam_stats(folder: OrdslamFolder, fps: float | None = None) -> pd.DataFrame:
    rows = []
    for p in folder.groundtruth:
        info = folder.describe(p)
        rows.append(
            dict(
                dataset="ORDSLAM",
                group=info["difficulty"],
                sequence=folder.relative(p),
                scenario=info["scenario"],
                time=info["time"],
                light=info["light"],
                depth_mode=info["depth_mode"],
                **trajectory_stats(read_ordslam(p, fps)),
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
    :meth:`~lorisnb.io.ordslam.OrdslamFolder.pairs`). Returns (table, problems): an estimate
    without exactly one ground truth, or unreadable, is a row of ``problems`` (columns ``file,
    status, kind, error``, as :meth:`~lorisnb.tools.evaluation.Evaluation.failures_table`), not fatal."""
    pairs, unmatched = folder.pairs()
    rows = []
    problems = [dict(file=str(p), status="failed", kind="ORDSLAM estimate", error=why) for p, why in unmatched]
    for alg, est_path, gt_path in pairs:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", LorisWarning)
                gt, est = read_ordslam(gt_path, fps), read_ordslam(est_path, fps)
        except LorisError as exc:
            problems.append(dict(file=str(est_path), status="failed", kind="ORDSLAM estimate", error=str(exc)))
            continue
        info = folder.describe(gt_path)
        e = sequence_errors(gt, est, scale=scale, max_gap=max_gap)
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


def headline(measures: pd.DataFrame, published_ate: pd.DataFrame) -> dict[str, dict]:
    """The numbers the comparison's conclusions rest on: median ATE as % of path per computed
    dataset, the range of the published ORDSLAM and TUM values, median share of time tracked."""
    pub = published_ate.groupby("dataset")["ate_pct_length"]
    return dict(
        computed_ate_pct=measures.groupby("dataset")["ate_pct_length"].median().to_dict(),
        published_ate_pct_range={k: (float(v.min()), float(v.max())) for k, v in pub},
        tracked_share=measures.groupby("dataset")["tracked_share"].median().to_dict(),
    )
