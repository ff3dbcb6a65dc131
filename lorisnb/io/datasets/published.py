"""Published numbers transcribed from the two source papers (``../shared/data/published/``), as
tidy DataFrames with a ``source`` column that says they are published values, not computed ones."""

from __future__ import annotations

import pandas as pd

from lorisnb.io.datasets.paths import DataPaths, DataRoot, find_data

#: Mean trajectory length of the ORDSLAM difficult and very difficult sequences, metres (ORDSLAM
#: paper, discussion of Table 3: "средняя длина траектории ... составила 12 м").
ORDSLAM_MEAN_LENGTH_M = 12.0

#: Trajectory lengths of the two TUM RGB-D sequences of ORDSLAM's Table 4, metres, from the TUM
#: RGB-D benchmark's sequence list (Sturm et al., IROS 2012; vision.in.tum.de dataset page).
TUM_LENGTH_M = {"fr1/desk": 9.263, "fr2/xyz": 7.029}


def _read(name: str, data_root: DataRoot | DataPaths | None) -> pd.DataFrame:
    return pd.read_csv(find_data(data_root).published / name)


def ordslam_table3(data_root: DataRoot | DataPaths | None = None) -> pd.DataFrame:
    """ORDSLAM paper, Table 3: ATE RMSE of three RGB-D SLAM systems on the difficult (scenario 5)
    and very difficult (scenario 6) sequences, with the error as a share of the 12 m mean path."""
    df = _read("ordslam_table3_ate_rmse_cm.csv", data_root)
    df["scenario"] = df["scenario_difficulty"].map({"difficult": 5, "very_difficult": 6})
    df["difficulty"] = df["scenario_difficulty"].str.replace("_", " ")
    df["ate_rmse_m"] = df["ate_rmse_cm"] / 100.0
    df["path_length_m"] = ORDSLAM_MEAN_LENGTH_M
    df["ate_pct_length"] = 100.0 * df["ate_rmse_m"] / df["path_length_m"]
    df["source"] = "published: ORDSLAM paper, Table 3 (path length: the paper's 12 m mean)"
    return df


def ordslam_table4_tum(data_root: DataRoot | DataPaths | None = None) -> pd.DataFrame:
    """ORDSLAM paper, Table 4: the same systems on TUM RGB-D fr1/desk and fr2/xyz (the indoor
    reference), with the error as a share of each sequence's published length."""
    df = _read("ordslam_table4_tum_ate_rmse_cm.csv", data_root)
    df["ate_rmse_m"] = df["ate_rmse_cm"] / 100.0
    df["path_length_m"] = df["sequence"].map(TUM_LENGTH_M)
    df["ate_pct_length"] = 100.0 * df["ate_rmse_m"] / df["path_length_m"]
    df["source"] = "published: ORDSLAM paper, Table 4 (lengths: TUM RGB-D sequence list)"
    return df


def published_ate(data_root: DataRoot | DataPaths | None = None) -> pd.DataFrame:
    """Both ATE tables of the ORDSLAM paper in one table: dataset, group (scenario difficulty or
    TUM sequence), algorithm, ATE RMSE (m), path length (m), ATE as % of the path, source."""
    a = ordslam_table3(data_root).rename(columns={"difficulty": "group"})
    b = ordslam_table4_tum(data_root).rename(columns={"sequence": "group"})
    cols = ["dataset", "group", "algorithm", "ate_rmse_m", "path_length_m", "ate_pct_length", "source"]
    return pd.concat([a[cols], b[cols]], ignore_index=True)
