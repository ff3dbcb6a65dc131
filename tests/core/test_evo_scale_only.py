"""evo's scale correction alone (``evo_ape -s`` without ``-a``; lorisnb ``--align scale``) on inputs
the parity tests never gave it: evo fits a whole Umeyama Sim(3) for its scale and refuses matched
positions whose cross-covariance has rank below 2 (2 poses, positions on one line). lorisnb gave a
number there (a scale from the same fit); it now refuses as evo does, and agrees with evo's numbers
where evo gives them (evo 1.38's own API run here on cuts of the bundled fr1/xyz RGBD-SLAM run)."""

from __future__ import annotations

import copy

import numpy as np
import pandas as pd
import pytest

from lorisnb.cli import main
from lorisnb.core.conventions.evo_options import evo_rank_refusal, scale_alignment
from lorisnb.errors import EvaluationError

GT, EST = "freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"


def _cut(data, tmp_path, rows: slice, line: bool = False):
    """The ground truth whole and the estimate's ``rows``; ``line``: every position of both files
    moved onto the x axis (y = z = 0)."""
    files = []
    for name, sl in ((GT, slice(None)), (EST, rows)):
        a = np.loadtxt(data.tum / name)[sl]
        if line:
            a[:, 2:4] = 0.0
        p = tmp_path / name
        np.savetxt(p, a, fmt="%.17g")
        files.append(p)
    return files


def _evo(gt, est):
    """evo_ape -s (trans_part), as its CLI runs it: evo's reader, its nearest sync (0.01 s), ape."""
    em = pytest.importorskip("evo.core.metrics")
    from evo.core import sync
    from evo.main_ape import ape
    from evo.tools import file_interface as fi

    ref, e = sync.associate_trajectories(
        fi.read_tum_trajectory_file(gt), fi.read_tum_trajectory_file(est), max_diff=0.01
    )
    return ape(copy.deepcopy(ref), copy.deepcopy(e), em.PoseRelation.translation_part, correct_scale=True).stats


def _lorisnb(gt, est, tmp_path, capsys):
    out = tmp_path / "out.csv"
    rc = main(["evaluate", str(est), "--gt", str(gt), "--conventions", "evo", "--align", "scale", "--csv", str(out),
               "--force", "--no-progress", "--jobs", "1"])  # fmt: skip
    err = capsys.readouterr().err
    return (pd.read_csv(out).iloc[0] if rc == 0 else None), err


@pytest.mark.parametrize(("rows", "line"), [(slice(100, 102), False), (slice(100, 110), True), (slice(0, None), True)])
def test_scale_only_refused_where_evo_refuses(data, tmp_path, capsys, rows, line):
    pytest.importorskip("evo")
    from evo.core.geometry import GeometryException

    gt, est = _cut(data, tmp_path, rows, line)
    with pytest.raises(GeometryException, match="Degenerate covariance rank"):
        _evo(gt, est)
    row, err = _lorisnb(gt, est, tmp_path, capsys)
    assert row is None, "lorisnb gave a scale-only number where evo refuses"
    assert "no scale correction can be determined" in err and "Degenerate covariance rank" in err


@pytest.mark.parametrize("rows", [slice(100, 103), slice(200, 210), slice(0, None)])
def test_scale_only_equals_evo_where_evo_fits_it(data, tmp_path, capsys, rows):
    gt, est = _cut(data, tmp_path, rows)
    theirs = _evo(gt, est)
    row, err = _lorisnb(gt, est, tmp_path, capsys)
    assert row is not None, err
    for k in ("rmse", "mean", "median", "std", "min", "max", "sse"):
        assert row[f"ate_{k}"] == pytest.approx(theirs[k], rel=1e-9, abs=1e-12), k


def test_rank_rule_is_evos():
    p = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0]])
    assert "rank 1" in evo_rank_refusal(p, 2 * p)
    assert "2 poses" in evo_rank_refusal(p[:2], p[:2])
    q = p + np.array([[0, 0, 0], [0, 1e-3, 0], [0, 0, 0]])
    assert evo_rank_refusal(q, q) is None
    with pytest.raises(EvaluationError, match="rank 1"):
        scale_alignment(p, 2 * p)
    assert scale_alignment(q, 2 * q).scale == pytest.approx(2.0)
