"""``lorisnb evaluate --conventions kitti`` (issue 45): the KITTI odometry devkit's numbers in the
sequence table, its leaderboard summary over all sequences and its per-length errors, against the
devkit's evaluate_odometry.cpp compiled here (tests/peers.py) on real KITTI poses; the matrices as
written for KITTI files, the rotations of the quaternions for stamped inputs."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from peers import KITTI_SEQUENCES, build_devkit, kitti_pair, run_devkit

import lorisnb
from lorisnb.cli import main
from lorisnb.core.metrics.kitti import KITTI_LENGTHS
from lorisnb.core.metrics.kitti_table import kitti_totals
from lorisnb.errors import ValidationError
from lorisnb.io.readers.plain import read_kitti


@pytest.fixture(scope="module")
def devkit(tmp_path_factory) -> Path:
    return build_devkit(tmp_path_factory.mktemp("devkit"))


def lengths_file(out: Path, kind: str) -> dict[float, float]:
    rows = np.loadtxt(out / f"seq_{kind}.txt", ndmin=2)
    return dict(zip(rows[:, 0], rows[:, 1], strict=True))


@pytest.mark.parametrize("seq", KITTI_SEQUENCES)
@pytest.mark.thorough
def test_evaluate_prints_and_writes_the_devkits_numbers(devkit, tmp_path, capsys, seq):
    gt, est = kitti_pair(seq)
    _, (t, r) = run_devkit(devkit, gt, est, tmp_path / "devkit")
    out = tmp_path / "k.csv"
    plot = tmp_path / "lengths.png"
    args = ["evaluate", str(est), "--gt", str(gt), "--format", "kitti", "--conventions", "kitti", "--csv", str(out),
            "--kitti-plot", str(plot), "--no-progress"]  # fmt: skip
    assert main(args) == 0
    printed = capsys.readouterr()
    assert "KITTI matrices as written" in printed.err and "kitti_t_err" in printed.out
    row = pd.read_csv(out).iloc[0]
    assert row["kitti_matrices"] == "as written"
    assert row["kitti_t_err"] == pytest.approx(100 * t, rel=1e-6)
    assert row["kitti_r_err"] == pytest.approx(np.degrees(r) * 100, rel=1e-6)
    tl, rl = lengths_file(tmp_path / "devkit", "tl"), lengths_file(tmp_path / "devkit", "rl")
    for n in KITTI_LENGTHS:  # the devkit's files: %f
        assert row[f"kitti_t_err_{int(n)}"] / 100 == pytest.approx(tl[n], abs=5e-7)
        assert np.radians(row[f"kitti_r_err_{int(n)}"] / 100) == pytest.approx(rl[n], abs=5e-7)
    assert plot.stat().st_size > 10_000


@pytest.mark.thorough
def test_leaderboard_total_over_all_sequences(devkit, tmp_path):
    """The devkit's summary is over every segment of every sequence (its total_err): one devkit run
    on the sequences' files end to end would mix their poses, so its segments of each are pooled."""
    segments, evaluations = [], []
    for seq in KITTI_SEQUENCES:
        gt, est = kitti_pair(seq)
        rows, _ = run_devkit(devkit, gt, est, tmp_path / seq)
        segments.append(rows)
        evaluations.append(lorisnb.evaluate_pairs(est, gt, "kitti", fmt="kitti"))
    pooled = np.concatenate(segments)
    t = float(np.cumsum(pooled[:, 2].astype(np.float32), dtype=np.float32)[-1] / np.float32(len(pooled)))
    total = kitti_totals([replace(f, algorithm="vo") for ev in evaluations for f in ev.errors])  # one algorithm
    assert len(total) == 1 and total.loc[0, "sequences"] == 2
    assert total.loc[0, "kitti_segments"] == len(pooled)
    assert total.loc[0, "kitti_t_err"] == pytest.approx(100 * t, rel=1e-6)


@pytest.mark.thorough  # the devkit compiled and run, as above (5 s of CPU); its recorded numbers: test_kitti_recorded.py
def test_stamped_inputs_use_their_rotations(devkit, tmp_path):
    """A TUM pair (stamps, quaternions) under kitti: paired by nearest stamps, each pose's rotation
    from its quaternion; equal to the devkit on KITTI files holding those rotations in full."""
    gt_file, est_file = kitti_pair("10")
    files = []
    for name, path in (("gt", gt_file), ("est", est_file)):
        t = read_kitti(path)
        stamps = 0.1 * np.arange(len(t))
        tum = tmp_path / f"{name}.tum"
        tum.write_text("".join(f"{s:.2f} " + " ".join(f"{v:.17g}" for v in (*p, *q)) + "\n"
                               for s, p, q in zip(stamps, t.positions, t.quaternions, strict=True)))  # fmt: skip
        mats = np.concatenate([t.rotations().as_matrix(), t.positions[:, :, None]], axis=2).reshape(-1, 12)
        full = tmp_path / f"{name}.kitti"
        full.write_text("\n".join(" ".join(f"{v:.17g}" for v in m) for m in mats) + "\n")
        files.append((tum, full))
    _, (t_err, r_err) = run_devkit(devkit, files[0][1], files[1][1], tmp_path / "devkit")
    ev = lorisnb.evaluate_pairs(files[1][0], files[0][0], "kitti")
    row = ev.sequences().iloc[0]
    assert row["matched"] == len(read_kitti(gt_file)) and row["kitti_matrices"] == "rotations"
    assert row["kitti_t_err"] == pytest.approx(100 * t_err, rel=1e-6)
    assert row["kitti_r_err"] == pytest.approx(np.degrees(r_err) * 100, rel=1e-6)
    # a repeated stamp (every 50th, an earlier pose 3 cm off before it) is read as TUM's associate.py
    # keeps it, the last pose: each was kept and paired with the next ground-truth stamp, one more
    # devkit frame each (the estimate's); of the ground truth's the first was used
    for tum, _ in files:
        lines = tum.read_text().splitlines(keepends=True)
        off = [f"{x.split()[0]} " + " ".join(f"{float(v) + 0.03:.17g}" for v in x.split()[1:4]) + " "
               + " ".join(x.split()[4:]) + "\n" for x in lines]  # fmt: skip
        tum.write_text("".join(o + x if k % 50 == 7 else x for k, (o, x) in enumerate(zip(off, lines, strict=True))))
    dup = lorisnb.evaluate_pairs(files[1][0], files[0][0], "kitti").sequences().iloc[0]
    assert dup["matched"] == row["matched"] and dup["kitti_segments"] == row["kitti_segments"]
    assert dup["kitti_t_err"] == pytest.approx(100 * t_err, rel=1e-6)
    assert dup["kitti_r_err"] == pytest.approx(np.degrees(r_err) * 100, rel=1e-6)


def test_double_precision_on_request_and_refused_elsewhere(tmp_path):
    gt, est = kitti_pair("09")
    single = lorisnb.evaluate_pairs(est, gt, "kitti", fmt="kitti").sequences().iloc[0]
    double = lorisnb.evaluate_pairs(est, gt, "kitti", fmt="kitti", kitti_precision="double")
    assert "double precision" in double.conventions
    d = double.sequences().iloc[0]
    assert d["kitti_r_err"] == pytest.approx(single["kitti_r_err"], rel=1e-3)
    assert d["kitti_r_err"] != single["kitti_r_err"]
    with pytest.raises(ValidationError, match="only for the KITTI metric"):
        lorisnb.evaluate_pairs(est, gt, "evo", fmt="kitti", kitti_precision="double")
    assert (
        main(["evaluate", str(est), "--gt", str(gt), "--format", "kitti", "--kitti-plot", str(tmp_path / "p.png")]) == 2
    )
    assert not (tmp_path / "p.png").exists()


def test_blocks_as_written_follow_their_poses():
    """A KITTI file's blocks as written stay with their poses through any subset, and are let go when
    the orientations change (a body transform): then the rotations are used, and said."""
    from lorisnb.core.pipeline.steps import with_transform
    from lorisnb.core.trajectory.poses import written_blocks

    gt, _ = kitti_pair("10")
    t = read_kitti(gt)
    written = np.loadtxt(gt).reshape(-1, 3, 4)[:, :, :3]
    assert np.array_equal(written_blocks(t), written)
    pick = np.arange(3, len(t), 7)
    assert np.array_equal(written_blocks(t.subset(pick)), written[pick])
    turned = np.eye(4)
    turned[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    assert written_blocks(with_transform(t, turned)) is None
    shifted = np.eye(4)
    shifted[:3, 3] = [0.1, 0.0, 0.0]
    assert np.array_equal(written_blocks(with_transform(t, shifted)), written)  # orientations unchanged


def test_a_sequence_shorter_than_the_shortest_segment_is_said(data, capsys):
    """fr2_desk travels about 18 m: no 100 m segment, so kitti_t_err and kitti_r_err are NaN with
    0 segments, which the command printed without a word (a missing RPE pair gets one)."""
    est, gt = data.tum / "fr2_desk_ORB.txt", data.tum / "fr2_desk_groundtruth.txt"
    assert main(["evaluate", str(est), "--gt", str(gt), "--conventions", "kitti", "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert "note: 1 sequence(s) hold no KITTI segment (fr2_desk_ORB.txt, seq 1)" in err, err
    row = lorisnb.evaluate_pairs(est, gt, conventions="kitti").kitti_totals().iloc[0]
    assert row["kitti_segments"] == 0 and np.isnan(row["kitti_t_err"])


def test_a_refused_input_prints_no_empty_kitti_tables(tmp_path, capsys):
    """Every input refused (13 numbers a line): the error says why, and no empty 'KITTI odometry' or
    'per segment length' table (header rows only) comes before it on stdout; --kitti-plot writes no
    figure of nothing (it was an AttributeError traceback) and says so."""
    gt = tmp_path / "gt.txt"
    gt.write_text("".join(f"1 0 0 {i} 0 1 0 0 0 0 1 0\n" for i in range(5)))
    est = tmp_path / "est.txt"
    est.write_text("".join(f"{i} 1 0 0 {i} 0 1 0 0 0 0 1 0\n" for i in range(5)))
    plot = tmp_path / "lengths.png"
    assert main(["evaluate", str(est), "--gt", str(gt), "--format", "kitti", "--conventions", "kitti",
                 "--no-progress", "--kitti-plot", str(plot)]) == 1  # fmt: skip
    out, err = capsys.readouterr()
    assert "KITTI odometry" not in out and "per segment length" not in out and "kitti_t_err" not in out
    assert "has 13 fields" in err and "no plot was written" in err and not plot.exists()
