"""An estimate at ~100 Hz against ground truth at ~1 Hz (sparser than the 0.5 s interpolation
bracket): every estimate stamp equal to a ground-truth stamp is matched to that very pose, where
the bracket alone matched none ("no estimate stamp matches"). Denser ground truth keeps the
official rule (tests/test_probe_official_fuzz.py)."""

from __future__ import annotations

import numpy as np

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.alignment.association import associate, sparser_than

GT = "fr2_desk_groundtruth.txt"


def sparse_pair(tmp_path, data):
    """The recorded ground truth (300 Hz) as an estimate at 100 Hz (one pose in 3) and as ground
    truth at 1 Hz (one in 300): every ground-truth stamp is one of the estimate's."""
    lines = [x for x in (data.tum / GT).read_text().splitlines() if x and not x.startswith("#")]
    est = tmp_path / "est.txt"
    est.write_text("\n".join(lines[::3]) + "\n")
    gt = tmp_path / "gt_1hz.txt"
    gt.write_text("\n".join(lines[::300]) + "\n")
    return est, gt, lines[::300]


def test_equal_stamps_match_whatever_the_bracket_in_python(tmp_path, data):
    est_path, gt_path, gt_lines = sparse_pair(tmp_path, data)
    gt, est = ln.read_tum(gt_path), ln.read_tum(est_path)
    assert np.median(np.diff(gt.stamps)) > 0.5 and sparser_than(gt.stamps, 0.5)
    shared = np.intersect1d(est.stamps, gt.stamps)
    a = associate(gt, est.stamps)
    assert len(a) == len(shared) == len(gt_lines) > 60
    np.testing.assert_array_equal(a.stamps, shared)
    k = np.searchsorted(gt.stamps, a.stamps)
    np.testing.assert_array_equal(a.gt_positions, gt.positions[k])  # the ground-truth poses themselves
    assert len(associate(gt, est.stamps + 1e-4)) == 0  # not equal: the bracket's rule, which matches none
    dense = ln.read_tum(data.tum / GT)
    assert not sparser_than(dense.stamps, 0.5)


def test_equal_stamps_match_on_the_command_line(tmp_path, data, capsys):
    est_path, gt_path, gt_lines = sparse_pair(tmp_path, data)
    out_csv = tmp_path / "t.csv"
    rc = main(["evaluate", str(est_path), "--gt", str(gt_path), "--csv", str(out_csv), "--no-progress"])
    captured = capsys.readouterr()
    assert rc == 0 and "no estimate stamp matches" not in captured.err
    import pandas as pd

    row = pd.read_csv(out_csv).iloc[0]
    assert row["matched"] == len(gt_lines) and row["ate_rmse"] < 1e-9  # the same poses: nothing to align away
