"""``lorisnb consistency`` on inputs ov_eval reads, ov_eval's ``ResultTrajectory`` compiled here
(tests/peers.py) on the same files, real TUM RGB-D poses (fr1/xyz, RGBD-SLAM's estimate with
:func:`helpers.synthetic_covariances`):

- a ground truth in ov_eval's own layout of 20 numbers a line (its covariances ov_eval reads and its
  metrics leave: they use the estimate's): lorisnb refused it ("has 20 fields; expected 8 numbers");
- covariance blocks of rank 2 (singular to rounding, yet Eigen inverts them): the NEES is ov_eval's
  (1e12 and more) and now a note names how many poses, the first one's stamp and its NEES, as it did
  for blocks that are not positive definite."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers import synthetic_covariances, write_ov_eval_file
from peers import build_ov_eval, run_ov_eval

from lorisnb.cli import main
from lorisnb.io.readers.plain import read_tum

GT, EST = "freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"


@pytest.fixture(scope="module")
def ov(tmp_path_factory) -> Path:
    return build_ov_eval(tmp_path_factory.mktemp("ov_eval"))


@pytest.fixture(scope="module")
def files(data, tmp_path_factory) -> dict[str, Path]:
    out = tmp_path_factory.mktemp("ov_inputs")
    est = read_tum(data.tum / EST, warn=False)
    gt = read_tum(data.tum / GT, warn=False)
    co, cp = synthetic_covariances(est.stamps)
    rank2 = cp.copy()
    u, v = np.random.default_rng(5).normal(size=(2, len(est), 3)) * 0.01
    rank2[::50] = (np.einsum("ni,nj->nij", u, u) + np.einsum("ni,nj->nij", v, v))[::50]  # 16 blocks of rank 2
    return {
        "est": write_ov_eval_file(out / "est.txt", est, co, cp),
        "rank2": write_ov_eval_file(out / "rank2.txt", est, co, rank2),
        "gt20": write_ov_eval_file(out / "gt20.txt", gt, *synthetic_covariances(gt.stamps)),
    }


def consistency(est: Path, gt: Path, tmp_path: Path, capsys) -> tuple[dict[str, np.ndarray], str]:
    """``lorisnb consistency``'s summary (series -> rmse, mean, median, std, min, max, count) and stderr."""
    import pandas as pd

    out = tmp_path / f"s{len(list(tmp_path.glob('s*.csv')))}.csv"
    assert main(["consistency", str(est), str(gt), "--align", "se3", "--summary-csv", str(out)]) == 0
    s = pd.read_csv(out).set_index("series")[["rmse", "mean", "median", "std", "min", "max", "count"]]
    return {k: s.loc[k].to_numpy(float) for k in s.index}, capsys.readouterr().err


@pytest.mark.slow  # builds ov_eval from source
def test_a_ground_truth_in_ov_evals_layout_is_read_as_ov_eval_reads_it(ov, files, data, tmp_path, capsys):
    theirs, _ = run_ov_eval(ov, files["est"], files["gt20"], "se3")
    ours, _ = consistency(files["est"], files["gt20"], tmp_path, capsys)  # lorisnb: exit 1, 'has 20 fields'
    plain, _ = consistency(files["est"], data.tum / GT, tmp_path, capsys)
    assert theirs["ate_pos"][-1] == 786
    for name, want in theirs.items():
        np.testing.assert_allclose(ours[name], want, rtol=1e-9, atol=1e-15, err_msg=name)
        np.testing.assert_allclose(plain[name], want, rtol=1e-9, atol=1e-15, err_msg=name)  # covariances left


def test_a_ground_truth_in_ov_evals_layout_is_accepted(files, data, tmp_path, capsys):
    """Everywhere the data is: the same numbers as the ground truth's TUM file."""
    ours, _ = consistency(files["est"], files["gt20"], tmp_path, capsys)
    plain, _ = consistency(files["est"], data.tum / GT, tmp_path, capsys)
    assert ours["ate_pos"][-1] == 786
    for name in ours:
        np.testing.assert_array_equal(ours[name], plain[name], err_msg=name)


@pytest.mark.slow
def test_rank_two_covariances_give_ov_evals_nees_and_a_note(ov, files, tmp_path, capsys):
    theirs, _ = run_ov_eval(ov, files["rank2"], files["gt20"], "se3")
    ours, err = consistency(files["rank2"], files["gt20"], tmp_path, capsys)
    np.testing.assert_allclose(ours["nees_pos"], theirs["nees_pos"], rtol=1e-6, err_msg="nees_pos")
    assert theirs["nees_pos"][1] > 1e6  # the mean: rounding divided by rounding


def test_rank_two_covariances_are_said(files, data, tmp_path, capsys):
    ours, err = consistency(files["rank2"], data.tum / GT, tmp_path, capsys)
    said = " ".join(err.split())
    # rounding makes the smallest eigenvalue of half of them a hair negative: those are said as not positive definite
    singular = said.split(" matched poses have a position covariance that is singular to rounding")[0].split()[-3]
    indefinite = said.split(" matched poses have a position covariance that is not positive definite")[0].split()[-3]
    assert int(singular) + int(indefinite) == 16 and int(singular) > 0
    gt, est = read_tum(data.tum / GT, warn=False), read_tum(data.tum / EST, warn=False)
    rank2_stamps = {f"{gt.stamps[np.argmin(np.abs(gt.stamps - t))]:.6f}" for t in est.stamps[::50]}
    first = said.split("singular to rounding (smallest eigenvalue below 1e-12 of the largest; the first at ")[1]
    assert first.split(" s,")[0] in rank2_stamps and ", NEES " in first
    assert ours["nees_pos"][1] > 1e6 and ours["nees_pos"][-1] == 785  # one block inverts to NaN: left out, as ov_eval
