"""A folder's result files are found whatever the case of their suffix: ``CAFE_1_1.TXT`` (a file
saved on Windows) was left out silently, so a folder of them was 'nothing was evaluated', while the
same file named alone was scored."""

from __future__ import annotations

import shutil
import warnings

import lorisnb as ln


def test_a_folder_finds_upper_case_suffixes(tmp_path, data, icra20):
    src = icra20 / "per-seq" / "orbslam2_rgbd" / "cafe_1_1_orbslam2-original.txt"
    for name, suffix in (("lower", ".txt"), ("upper", ".TXT"), ("mixed", ".Txt")):
        (tmp_path / name / "orbslam2_rgbd").mkdir(parents=True)
        shutil.copy(src, tmp_path / name / "orbslam2_rgbd" / f"cafe_1_1{suffix}")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rows = {
            n: ln.evaluate(tmp_path / n, data_root=data).sequences(eps="paper", phi=30.0)
            for n in ("lower", "upper", "mixed")
        }
    assert len(rows["lower"]) == 1 and rows["lower"]["matched"].iloc[0] > 1000
    for n in ("upper", "mixed"):
        assert rows[n][["matched", "cr", "ate_rmse"]].equals(rows["lower"][["matched", "cr", "ate_rmse"]])
