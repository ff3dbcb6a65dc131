"""An OpenLORIS ground truth's repeated poses (a pose identical to the one before: market's ground
truth has 149, 18 and 113 in its three sequences) follow the spec's rule under every preset but
``openloris``, as the estimate's do and as the ``conventions:`` line says ("repeated poses kept in
KITTI and OpenLORIS files"); under ``openloris`` they are dropped whatever ``--keep-repeated`` says
(the official tool reads its ground truth so, with or without its ``-k``), and the line says that.
They were dropped under every preset: ``--conventions kitti`` paired 4,863, 3,983 and 1,455 poses of
MASLAM's lifelong market file, where the ground truth it claimed to read (repeated poses kept) pairs
4,933, 3,992 and 1,455 by TUM's rule."""

from __future__ import annotations

import pandas as pd
import pytest

from lorisnb.cli import main
from lorisnb.core.conventions.choices import associate_nearest
from lorisnb.io.readers.openloris import read_openloris

RESULT = ("lifelong", "maslam", "market.txt")
PER_SEQ = ("per-seq", "orbslam2_rgbd", "market_1_1_orbslam2-original.txt")  # no repeated pose of its own


def run(data, tmp_path, capsys, *options: str, result: tuple[str, ...] = RESULT) -> tuple[pd.DataFrame, str]:
    est = data.icra20.joinpath(*result)
    csv = tmp_path / f"t{len(list(tmp_path.glob('t*.csv')))}.csv"
    args = ["evaluate", str(est), "--data", str(data.root), "--csv", str(csv), "--no-progress", "--jobs", "1", *options]
    assert main(args) == 0
    line = next(x for x in capsys.readouterr().err.splitlines() if x.startswith("conventions:"))
    return pd.read_csv(csv), line


def paired_by_tum(data, drop: bool) -> list[int]:
    """How many estimate poses of each sequence TUM's nearest rule (0.02 s) pairs with the ground
    truth, both files read with their repeated poses dropped or kept."""
    gt = read_openloris(data.groundtruth("market"), remove_repeated=drop, warn=False).sequences
    est = read_openloris(data.icra20.joinpath(*RESULT), remove_repeated=drop, warn=False).sequences
    return [int(associate_nearest(gt[k].stamps, est[k].stamps, 0.02)[0].size) for k in sorted(est)]


@pytest.mark.parametrize("preset", ["kitti", "tum", "evo"])
def test_other_presets_read_the_ground_truth_by_their_rule(data, tmp_path, capsys, preset):
    """The command line (--keep-repeated) and Python (remove_repeated=True): the ground truth as the rule says."""
    import lorisnb

    kept, line = run(data, tmp_path, capsys, "--conventions", preset, "--keep-repeated")
    ev = lorisnb.evaluate(data.icra20.joinpath(*RESULT), conventions=preset, data_root=data.root, remove_repeated=True)
    dropped = ev.sequences()
    if preset != "evo":  # evo pairs by its own rule (each pose of the shorter trajectory), not TUM's
        assert list(kept["matched"]) == paired_by_tum(data, drop=False) == [4933, 3992, 1455]  # it paired 4863, 3983
        assert list(dropped["matched"]) == paired_by_tum(data, drop=True) == [4863, 3983, 1455]
    else:
        assert kept["matched"].sum() > dropped["matched"].sum()
    assert "repeated poses kept" in line and "ground truth's dropped" not in line
    assert "repeated poses dropped" in ev.spec.describe()


def test_the_kitti_preset_says_what_it_does_with_openloris_files(data, tmp_path, capsys):
    rows, line = run(data, tmp_path, capsys, "--conventions", "kitti")
    assert list(rows["matched"]) == [4933, 3992, 1455]
    assert "repeated poses kept in KITTI and OpenLORIS files" in line


def test_openloris_keeps_the_official_reading(data, tmp_path, capsys):
    plain, line = run(data, tmp_path, capsys, result=PER_SEQ)
    kept, line_kept = run(data, tmp_path, capsys, "--keep-repeated", result=PER_SEQ)
    assert "repeated poses dropped" in line
    assert "an OpenLORIS ground truth's dropped, as the official tool reads it" in line_kept
    # the estimate has no repeated pose: -k changes nothing, the ground truth is read as the official tool reads it
    assert kept["matched"].tolist() == plain["matched"].tolist() == [1313]
    assert kept["ate_rmse"].tolist() == plain["ate_rmse"].tolist()
