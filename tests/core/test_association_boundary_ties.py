"""Stamps one bracket (``max_diff``) apart, as files written with a few decimals make them: every
association pairs them as its peer does, run on the same input (tests/peers.py). The difference of
two such stamps rounds to just below or just above ``max_diff`` (1000.02 - 1000.00 is
0.0199999999999818), and ``t - max_diff`` rounds too: a rule must compare the difference itself,
as its peer writes it.

- ``ov_eval`` (``lorisnb consistency``): ov_eval's ``ResultTrajectory`` compiled here; lorisnb
  skipped a ground-truth row 0.0199999999999818 s early (it compared ``t - 0.02``, which rounds to
  1000.0, with it) and paired 41 of 48 poses, each with the wrong row, where ov_eval pairs 48.
- ``nearest`` (TUM's ``associate.py``, rpg_trajectory_evaluation's ``associate``, the same code):
  rpg's ``associate`` itself.
- ``evo-nearest``: evo's ``matching_time_indices`` itself.

On real poses (TUM RGB-D fr1/xyz) whose stamps are written with two decimals, the ground truth at
25 Hz."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import synthetic_covariances, write_ov_eval_file
from peers import build_ov_eval, peer, run_ov_eval

from lorisnb.core.conventions.choices import associate_nearest
from lorisnb.core.conventions.evo_sync import evo_match_indices
from lorisnb.core.metrics.consistency import associate_sequential, ov_eval_errors
from lorisnb.io.readers.covariance import read_covariances
from lorisnb.io.readers.plain import read_tum

GT, EST = "freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"


def two_decimals(stamps: np.ndarray) -> np.ndarray:
    return np.unique(np.array([float(f"{t:.2f}") for t in stamps]))


@pytest.fixture(scope="module")
def grid(data) -> tuple[np.ndarray, np.ndarray]:
    """Ground-truth stamps at 25 Hz and the estimate's, both with two decimals (real fr1/xyz stamps)."""
    gt = read_tum(data.tum / GT, warn=False)
    est = read_tum(data.tum / EST, warn=False)
    return two_decimals(gt.stamps[::4]), two_decimals(est.stamps)


def shifted_grid(n: int = 50, shift: float = 0.02) -> tuple[np.ndarray, np.ndarray]:
    """The finding's case: 25 Hz ground truth ``1000.00 + 0.04 i`` and an estimate ``shift`` later."""
    g = np.array([float(f"{1000 + 0.04 * i:.2f}") for i in range(n)])
    return g, np.array([float(f"{1000 + shift + 0.04 * i:.2f}") for i in range(n)])


@pytest.fixture(scope="module")
def ov(tmp_path_factory) -> Path:
    return build_ov_eval(tmp_path_factory.mktemp("ov_eval"))


def write_pair(data, tmp_path: Path, g: np.ndarray, e: np.ndarray) -> tuple[Path, Path]:
    """Real fr1/xyz poses (the ground truth's, the estimate's with covariances) at the stamps ``g``, ``e``."""
    gt = read_tum(data.tum / GT, warn=False)
    est = read_tum(data.tum / EST, warn=False)
    gt_rows = np.column_stack([g, gt.positions[: g.size], gt.quaternions[: g.size]])
    gt_path = tmp_path / "gt.txt"
    gt_path.write_text("".join(f"{g[k]:.2f} " + " ".join(repr(float(v)) for v in r[1:]) + "\n"
                               for k, r in enumerate(gt_rows)))  # fmt: skip
    sub = est.subset(np.arange(e.size))
    sub = type(sub).from_checked(e, sub.positions, sub.quaternions, None, {})
    est_path = write_ov_eval_file(tmp_path / "est.txt", sub, *synthetic_covariances(e))
    return est_path, gt_path


@pytest.mark.slow  # builds ov_eval from source
@pytest.mark.parametrize("case", ["finding", "fr1_xyz"])
def test_ov_eval_pairs_stamps_one_bracket_apart_as_ov_eval(ov, data, grid, tmp_path, case):
    g, e = shifted_grid() if case == "finding" else grid
    est_path, gt_path = write_pair(data, tmp_path, g, e)
    stats, rows = run_ov_eval(ov, est_path, gt_path, "se3")
    est, cov = read_covariances(est_path, required=False)
    res = ov_eval_errors(est, read_tum(gt_path, warn=False), cov, align="se3")
    want = {"finding": 48, "fr1_xyz": 658}[case]  # lorisnb paired 41 and 649
    assert len(res.poses) == stats["ate_pos"][-1] == want
    np.testing.assert_array_equal(res.poses["t"].to_numpy(), rows["ate_pos"][:, 0])
    for name in ("ate_pos", "ate_ori", "nees_pos", "nees_ori"):
        s = res.summary.set_index("series").loc[name, ["rmse", "mean", "count"]].to_numpy(float)
        np.testing.assert_allclose(s, stats[name][[0, 1, 6]], rtol=1e-9, err_msg=name)


def test_ov_eval_association_of_the_finding():
    """Where ov_eval cannot be built: its pairs of the finding's case (as ov_eval pairs them above):
    (0, 0) .. (13, 13), then the differences round the other way: (15, 14) .. (26, 25), estimate 26
    unpaired, (27, 27) .. (38, 38), (40, 39) .. (49, 48), estimate 49 unpaired."""
    gi, ei = associate_sequential(*shifted_grid())
    k = np.arange(50)
    want_e = k[(k != 26) & (k != 49)]
    want_g = np.where((want_e >= 14) & (want_e <= 25) | (want_e >= 39), want_e + 1, want_e)
    np.testing.assert_array_equal(ei, want_e)
    np.testing.assert_array_equal(gi, want_g)  # lorisnb: 41 pairs (1, 0), (3, 2), ...


@pytest.fixture(scope="module")
def rpg_associate():
    folder = peer("rpg_trajectory_evaluation") / "src" / "rpg_trajectory_evaluation"
    sys.path.insert(0, str(folder))
    try:
        return importlib.import_module("associate_timestamps").associate
    finally:
        sys.path.remove(str(folder))


@pytest.mark.parametrize("max_diff", [0.02, 0.01, 0.04])
@pytest.mark.parametrize("case", ["finding", "fr1_xyz"])
def test_nearest_pairs_stamps_one_bracket_apart_as_rpg_and_tum(rpg_associate, grid, case, max_diff):
    g, e = shifted_grid(shift=max_diff) if case == "finding" else grid
    theirs = rpg_associate(e.tolist(), g.tolist(), 0.0, max_diff)  # rpg: (estimate, ground truth)
    gi, ej = associate_nearest(g, e, max_diff)
    assert list(zip(ej.tolist(), gi.tolist(), strict=True)) == theirs
    assert len(theirs) > 0


@pytest.mark.parametrize("max_diff", [0.02, 0.01, 0.04])
@pytest.mark.parametrize("case", ["finding", "fr1_xyz"])
def test_evo_nearest_pairs_stamps_one_bracket_apart_as_evo(grid, case, max_diff):
    from evo.core.sync import matching_time_indices

    g, e = shifted_grid(shift=max_diff) if case == "finding" else grid
    for s1, s2 in ((e, g), (g, e)):
        theirs = matching_time_indices(s1.copy(), s2.copy(), max_diff)
        ours = evo_match_indices(s1, s2, max_diff)
        assert [list(map(int, x)) for x in theirs] == [x.tolist() for x in ours]
        assert len(theirs[0]) > 0
