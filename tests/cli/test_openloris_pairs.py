"""OpenLORIS files given as a pair (``evaluate --gt FILE --format openloris``, ``evaluate_pairs(...,
fmt="openloris")``) are scored as the native route (``evaluate FILE --data DIR``) scores them: every
``seq:`` block with its own number, against the same-numbered ground-truth block moved to the
file's sensor frame; where a plain file on the other side makes that impossible, refused."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.io.readers.plain import read_trajectory

DSS = "lifelong/ds-slam/cafe-1.txt"  # two blocks, seq 1 and 2, frame d400_color
ORB_2 = "per-seq/orbslam2_rgbd/cafe_1_2_orbslam2-original.txt"  # one block, seq: 2, frame d400_color
NUMBERS = ["seq", "poses", "matched", "ate_rmse", "aoe_rmse", "cr", "cr_t", "cs_r", "rpe_trans_rmse", "rpe_rot_rmse"]


def _numbers(ev) -> pd.DataFrame:
    assert not ev.failures, ev.failures
    return ev.sequences()[NUMBERS].reset_index(drop=True)


@pytest.mark.parametrize("name", [DSS, ORB_2])
@pytest.mark.parametrize("preset", [None, "evo"])
def test_pair_route_equals_the_native_route(icra20, data, name, preset):
    est = icra20 / name
    assert ln.read_openloris(est).frame == "d400_color"
    pair = ln.evaluate_pairs(est, data.groundtruth("cafe"), preset, fmt="openloris", jobs=1)
    native = ln.evaluate(est, preset, data_root=data, jobs=1)
    pd.testing.assert_frame_equal(_numbers(pair), _numbers(native))
    assert [e.mode for e in pair.errors] == [e.mode for e in native.errors]
    assert [e.frame for e in pair.errors] == ["d400_color"]
    assert list(_numbers(pair)["seq"]) == ([1, 2] if name == DSS else [2])


def test_pair_route_gives_evos_numbers_on_converted_files(icra20, data, tmp_path):
    """The tester's numbers (evo 1.38.1 on each sequence converted to TUM, ground truth moved to
    d400_color: /tmp/trial_evo findings item 2); the block-1-in-base_link result was 35.230666."""
    args = ["evaluate", str(icra20 / DSS), "--gt", str(data.groundtruth("cafe")), "--format", "openloris",
            "--conventions", "evo", "--csv", str(tmp_path / "t.csv")]  # fmt: skip
    assert main([*args, "--jobs", "1"]) == 0
    table = pd.read_csv(tmp_path / "t.csv")
    assert list(table["seq"]) == [1, 2]
    np.testing.assert_allclose(table["ate_rmse"], [35.118323, 35.841266], atol=5e-7)
    np.testing.assert_allclose(table["rpe_rot_rmse"], [0.340735, 0.358278], atol=5e-7)


def _tum(path, traj) -> str:
    rows = np.column_stack([traj.stamps, traj.positions, traj.quaternions])
    np.savetxt(path, rows, fmt="%.9f")
    return str(path)


def test_a_plain_ground_truth_against_several_blocks_or_a_sensor_frame_is_refused(icra20, data, tmp_path):
    gt_file = ln.read_openloris(data.groundtruth("cafe"))
    tum_gt = _tum(tmp_path / "gt2.txt", gt_file.sequences[2])
    several = ln.evaluate_pairs(icra20 / DSS, tum_gt, fmt="openloris", gt_fmt="tum", jobs=1)
    assert not several.errors and "2 sequences (seq: 1, 2)" in several.failures[0].error
    assert "lorisnb evaluate FILE --data DIR" in several.failures[0].error
    framed = ln.evaluate_pairs(icra20 / ORB_2, tum_gt, fmt="openloris", gt_fmt="tum", jobs=1)
    assert not framed.errors and "frame d400_color" in framed.failures[0].error
    tum_est = _tum(tmp_path / "est.txt", gt_file.sequences[1])  # a TUM estimate: which of 2 blocks?
    unnamed = ln.evaluate_pairs(tum_est, data.groundtruth("cafe"), gt_fmt="openloris", jobs=1)
    assert not unnamed.errors and "against 2 ground-truth sequences" in unnamed.failures[0].error
    assert main(["evaluate", str(icra20 / DSS), "--gt", tum_gt, "--format", "openloris", "--gt-format", "tum",
                 "--jobs", "1"]) == 1  # fmt: skip
    with pytest.raises(ln.ValidationError, match=r"name their scene in their header"):
        ln.evaluate_pairs(icra20 / DSS, data.groundtruth("cafe"), fmt="openloris", scene="cafe")
    with pytest.raises(ln.ParseError, match="sequences 1, 2: expected one, or the sequence"):
        read_trajectory(icra20 / DSS, "openloris")


def test_one_base_link_block_against_a_plain_ground_truth_keeps_its_number(data, tmp_path):
    gt2 = ln.read_openloris(data.groundtruth("cafe")).sequences[2]
    lines = [f"{t:.9f} {p[0]:.6f} {p[1]:.6f} {p[2]:.6f} {q[0]:.6f} {q[1]:.6f} {q[2]:.6f} {q[3]:.6f}"
             for t, p, q in zip(gt2.stamps, gt2.positions, gt2.quaternions, strict=True)]  # fmt: skip
    est = tmp_path / "est.txt"
    est.write_text("scene: cafe\nframe: base_link\nseq: 2\n" + "\n".join(lines) + "\n")
    ev = ln.evaluate_pairs(est, _tum(tmp_path / "gt.txt", gt2), fmt="openloris", gt_fmt="tum", jobs=1)
    table = _numbers(ev)
    assert list(table["seq"]) == [2] and table["matched"][0] == len(gt2.stamps)
    assert table["ate_rmse"][0] < 1e-5


def test_crosscheck_evo_of_openloris_files_says_why(icra20, data, capsys):
    code = main(["crosscheck", str(data.groundtruth("cafe")), str(icra20 / DSS), "--format", "openloris",
                 "--conventions", "evo"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and "evo reads no OpenLORIS files" in err and "ROS bag" not in err


def test_a_declared_failure_as_a_pair_is_scored_as_the_native_route_scores_it(icra20, data, tmp_path):
    """``*-failed.txt``: ``seq:`` blocks without poses, the official data's declared failed runs."""
    failed = icra20 / "per-seq/vins_mono_color_imu_with_loop/corridor-1-failed.txt"
    pair = ln.evaluate_pairs(failed, data.groundtruth("corridor"), fmt="openloris", jobs=1)
    native = ln.evaluate(failed, data_root=data, jobs=1)
    pd.testing.assert_frame_equal(_numbers(pair), _numbers(native))
    assert list(_numbers(pair)["seq"]) == [2, 3]
    args = [str(failed), "--gt", str(data.groundtruth("corridor")), "--format", "openloris", "--jobs", "1"]
    assert main(["evaluate", *args]) == 0  # a declared failure is scored, as with --data
