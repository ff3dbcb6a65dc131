"""What the stamps of an input are, and what is refused when they cannot be right, on the real
TUM and OpenLORIS data of ../shared/data: two KITTI files without times pair by index on every
preset (evo's numbers with ``--conventions evo``; files of different lengths refused as evo_ape
refuses them); stamps in milliseconds, microseconds or nanoseconds, in one file or both, in every
format that carries stamps; the output time of OpenLORIS' 9-number lines; a pose file given as a
times file."""

from __future__ import annotations

import copy

import numpy as np
import pandas as pd
import pytest
from evo.core import metrics as em
from evo.main_ape import ape
from evo.tools import file_interface as fi
from helpers import write

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.conventions.choices import associate_nearest
from lorisnb.core.spec.evalspec import PRESETS
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.core.trajectory.units import diagnose
from lorisnb.tools.evaluation.runner import evaluate_pairs

GT, EST = "freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"
ORB_CAFE = "per-seq/orbslam2_rgbd/cafe_1_1_orbslam2-original.txt"
MASLAM = "lifelong/maslam/home.txt"  # a real file of 9-number lines (output times 65 to 100 days late)


@pytest.fixture(scope="module")
def pair(data):
    return ln.read_tum(data.tum / GT), ln.read_tum(data.tum / EST)


def _tum(traj: Trajectory, stamps: np.ndarray | None = None) -> str:
    t = traj.stamps if stamps is None else stamps
    return "".join(" ".join(f"{v:.17g}" for v in (s, *p, *q)) + "\n"
                   for s, p, q in zip(t, traj.positions, traj.quaternions, strict=True))  # fmt: skip


def _kitti(traj: Trajectory) -> str:
    m = np.concatenate([traj.rotations().as_matrix(), traj.positions[:, :, None]], axis=2).reshape(-1, 12)
    return "".join(" ".join(f"{v:.17g}" for v in row) + "\n" for row in m)


def _euroc(traj: Trajectory, stamps: np.ndarray) -> str:
    rows = [f"{int(s)}," + ",".join(f"{v:.17g}" for v in (*p, q[3], q[0], q[1], q[2]))
            for s, p, q in zip(stamps, traj.positions, traj.quaternions, strict=True)]  # fmt: skip
    return "#timestamp [ns],p_x,p_y,p_z,q_w,q_x,q_y,q_z\n" + "\n".join(rows) + "\n"


def _run(tmp_path, args: list[str], capsys) -> tuple[int, str, pd.DataFrame | None]:
    out = tmp_path / "out.csv"
    out.unlink(missing_ok=True)
    rc = main(["evaluate", *args, "--no-progress", "--csv", str(out)])
    table = pd.read_csv(out) if out.exists() and out.stat().st_size else None
    return rc, capsys.readouterr().err, table


@pytest.fixture(scope="module")
def matched(pair):
    """The estimate's poses and the ground-truth poses of the same stamps (TUM's association)."""
    gt, est = pair
    gi, ej = associate_nearest(gt.stamps, est.stamps, 0.02)
    order = np.argsort(ej)
    g, e = gt.subset(gi[order]), est.subset(ej[order])
    return Trajectory(e.stamps, g.positions, g.quaternions), e  # the ground truth on the estimate's stamps


# --- 1. KITTI files without times: pose i with pose i ----------------------------------------------


@pytest.mark.parametrize("preset", list(PRESETS))
@pytest.mark.thorough
def test_two_kitti_files_without_times_pair_by_index_on_every_preset(matched, tmp_path, capsys, preset):
    g, e = matched
    gk, ek = write(tmp_path, "gt.kitti", _kitti(g)), write(tmp_path, "est.kitti", _kitti(e))
    rc, err, table = _run(tmp_path, [str(ek), "--gt", str(gk), "--format", "kitti", "--conventions", preset], capsys)
    assert rc == 0, err
    assert "association: by index, pose i with pose i" in err and "gap(s)" not in err
    assert table is not None and table["matched"].iloc[0] == len(e) == 786
    assert '"association":"index"' in table["spec"].iloc[0]
    # the same poses as TUM files on the same stamps, matched in time under the same preset
    gt_t, est_t = write(tmp_path, "gt.txt", _tum(g)), write(tmp_path, "est.txt", _tum(e))
    rc, err, ref = _run(tmp_path, [str(est_t), "--gt", str(gt_t), "--conventions", preset], capsys)
    assert rc == 0 and ref is not None and ref["matched"].iloc[0] == len(e), err
    for col in ("ate_rmse", "aoe_rmse"):
        assert table[col].iloc[0] == pytest.approx(ref[col].iloc[0], rel=1e-9, abs=1e-9), col
    if preset == "evo":  # evo_ape kitti on the same files (evo 1.38's Python API)
        r = ape(copy.deepcopy(fi.read_kitti_poses_file(gk)), fi.read_kitti_poses_file(ek),
                em.PoseRelation.translation_part)  # fmt: skip
        assert table["ate_rmse"].iloc[0] == pytest.approx(r.stats["rmse"], rel=1e-9)
        assert table["ate_max"].iloc[0] == pytest.approx(r.stats["max"], rel=1e-9)
    if preset == "openloris":  # se3 on all pairs: evo_ape kitti --align on the same files (13.5 mm)
        r = ape(fi.read_kitti_poses_file(gk), fi.read_kitti_poses_file(ek), em.PoseRelation.translation_part,
                align=True)  # fmt: skip
        assert table["ate_rmse"].iloc[0] == pytest.approx(r.stats["rmse"], rel=1e-9)
        assert 0.013 < r.stats["rmse"] < 0.014


def test_kitti_files_of_different_lengths_or_time_options_are_refused(pair, tmp_path, capsys):
    gt, est = pair
    gk, ek = write(tmp_path, "gt.kitti", _kitti(gt)), write(tmp_path, "est.kitti", _kitti(est))
    for preset in PRESETS:  # 3000 against 788 poses: pose i of one is not pose i of the other
        rc, err, table = _run(
            tmp_path, [str(ek), "--gt", str(gk), "--format", "kitti", "--conventions", preset], capsys
        )
        assert rc == 1 and table is None or table is not None and table.empty, preset
        assert "needs files of the same length, but the estimate has 788 poses and the ground truth 3000" in err
        assert "evo_ape refuses" in err and "--est-times and --gt-times" in err
    ev = evaluate_pairs(ek, gk, fmt="kitti", spec="evo")  # in Python the same
    assert ev.exit_status() == 1 and "same length" in ev.failures[0].error
    # an option of matching in time cannot apply to pose indices: refused, naming it
    with pytest.raises(ln.ValidationError, match=r"max_gap \(--max-gap\).*paired by index"):
        evaluate_pairs(ek, gk, fmt="kitti", max_gap=1.0)
    assert main(["evaluate", str(ek), "--gt", str(gk), "--format", "kitti", "--max-diff", "0.1", "--conventions",
                 "tum", "--no-progress"]) == 2  # fmt: skip
    assert "--max-diff" in capsys.readouterr().err
    # with their times both are matched in time as before (index pairing is for files without times)
    gtt = write(tmp_path, "gt.times", "".join(f"{t:.9f}\n" for t in gt.stamps))
    estt = write(tmp_path, "est.times", "".join(f"{t:.9f}\n" for t in est.stamps))
    rc, err, table = _run(tmp_path, [str(ek), "--gt", str(gk), "--format", "kitti", "--est-times", str(estt),
                                     "--gt-times", str(gtt)], capsys)  # fmt: skip
    assert rc == 0 and "interpolated ground truth" in err and table is not None and table["matched"].iloc[0] > 700


# --- 2. stamps not in seconds ------------------------------------------------------------------------


@pytest.mark.parametrize("opts", [["--motion-filter", "0.1", "5"], ["--t-start", "3"], ["--t-end", "100"]])
def test_kitti_index_pairs_refuse_filters_and_windows(matched, tmp_path, capsys, opts):
    """A motion filter (each file keeps other poses) or a time window (in pose indices) cannot
    apply to pose i with pose i: refused naming the option, not blamed on the files' lengths."""
    g, e = write(tmp_path, "gt.kitti", _kitti(matched[0])), write(tmp_path, "est.kitti", _kitti(matched[1]))
    rc, err, _ = _run(tmp_path, [str(e), "--gt", str(g), "--format", "kitti", *opts], capsys)
    assert rc == 2 and opts[0] in err and "pose indices" in err and "same length" not in err, err


@pytest.mark.parametrize(("unit", "factor"), [("milliseconds", 1e3), ("microseconds", 1e6), ("nanoseconds", 1e9)])
@pytest.mark.thorough
def test_stamps_in_other_units_are_refused_in_one_file_or_both(pair, tmp_path, capsys, unit, factor):
    gt, est = pair
    g, e = write(tmp_path, "gt.txt", _tum(gt)), write(tmp_path, "est.txt", _tum(est))
    gu = write(tmp_path, "gt_u.txt", _tum(gt, gt.stamps * factor))
    eu = write(tmp_path, "est_u.txt", _tum(est, est.stamps * factor))
    relative = write(tmp_path, "est_r.txt", _tum(est, (est.stamps - gt.stamps[0]) * factor))
    relative_gt = write(tmp_path, "gt_r.txt", _tum(gt, (gt.stamps - gt.stamps[0]) * factor))
    for preset in ("openloris", "tum", "evo"):
        rc, err, table = _run(tmp_path, [str(eu), "--gt", str(gu), "--conventions", preset], capsys)
        assert rc == 1 and f"the stamps of both files look like {unit}" in err and "Nothing was compared" in err
        assert table is None or table.empty
    # stamps from 0 (no Unix time to tell by their size): told by the spacing of the poses
    rc, err, _ = _run(tmp_path, [str(relative), "--gt", str(relative_gt), "--conventions", "tum"], capsys)
    assert rc == 1 and f"the stamps of both files look like {unit}" in err and "apart" in err
    for est_path, gt_path, role in ((eu, g, "estimate"), (e, gu, "ground truth")):  # one file only
        rc, err, _ = _run(tmp_path, [str(est_path), "--gt", str(gt_path)], capsys)
        assert rc == 1 and "stamps in different units" in err and f"the {role}'s stamps look like {unit}" in err
    # KITTI with times files in that unit
    gk, ek = write(tmp_path, "gt.kitti", _kitti(gt)), write(tmp_path, "est.kitti", _kitti(est))
    gt_times = write(tmp_path, "gt.times", "".join(f"{t * factor:.17g}\n" for t in gt.stamps))
    est_times = write(tmp_path, "est.times", "".join(f"{t * factor:.17g}\n" for t in est.stamps))
    rc, err, _ = _run(tmp_path, [str(ek), "--gt", str(gk), "--format", "kitti", "--est-times", str(est_times),
                                 "--gt-times", str(gt_times)], capsys)  # fmt: skip
    assert rc == 1 and f"the stamps of both files look like {unit}" in err
    # in Python, the unit and its evidence
    assert diagnose(Trajectory(est.stamps * factor, est.positions, est.quaternions))[0] == unit
    assert diagnose(est) == ("seconds", "")


def test_sparse_poses_in_the_other_files_span_are_seconds(data, tmp_path, capsys):
    """Poses 6 s apart (a keyframe-only or re-localization output) in seconds inside the ground
    truth's span are not "milliseconds by their spacing": they are scored; the same spacing counted
    from 0 beside a ground truth in Unix seconds is refused as another unit (fr2_desk: 99 s)."""
    gt, est = ln.read_tum(data.tum / "fr2_desk_groundtruth.txt"), ln.read_tum(data.tum / "fr2_desk_ORB.txt")
    keep = [0]
    for k in range(1, len(est)):
        if est.stamps[k] - est.stamps[keep[-1]] >= 6.0:
            keep.append(k)
    sparse = est.subset(np.array(keep))
    assert diagnose(sparse)[0] == "milliseconds"  # alone, the spacing says so
    ln.core.units.check_stamp_units(sparse, gt)  # beside the ground truth it is seconds
    path, gt_path = write(tmp_path, "sparse.txt", _tum(sparse)), write(tmp_path, "gt.txt", _tum(gt))
    rc, err, table = _run(tmp_path, [str(path), "--gt", str(gt_path), "--conventions", "tum"], capsys)
    assert rc == 0 and table is not None and table["matched"].iloc[0] >= 10, err  # 13 of 17 within 0.02 s
    from_zero = Trajectory(sparse.stamps - sparse.stamps[0], sparse.positions, sparse.quaternions)
    with pytest.raises(ln.EvaluationError, match="look like milliseconds"):
        ln.core.units.check_stamp_units(from_zero, gt)


@pytest.mark.parametrize(("unit", "per_ns"), [("milliseconds", 1e-6), ("microseconds", 1e-3)])
def test_euroc_files_written_in_other_units_are_refused(pair, tmp_path, capsys, unit, per_ns):
    """EuRoC CSV stamps are nanoseconds; written in ms or us they are read 1e6 or 1e3 times too
    small: poses far faster than any sensor (5 kHz)."""
    gt, est = pair
    gu = write(tmp_path, "gt.csv", _euroc(gt, np.round(gt.stamps * 1e9 * per_ns)))
    eu = write(tmp_path, "est.csv", _euroc(est, np.round(est.stamps * 1e9 * per_ns)))
    rc, err, _ = _run(tmp_path, [str(eu), "--gt", str(gu), "--format", "euroc"], capsys)
    assert rc == 1 and "the stamps of both files look like a unit read too small" in err
    assert "EuRoC CSV stamps written in milliseconds or microseconds" in err
    g = write(tmp_path, "gt_tum.txt", _tum(gt))  # the estimate alone
    rc, err, _ = _run(tmp_path, [str(eu), "--gt", str(g), "--format", "euroc", "--gt-format", "tum"], capsys)
    assert rc == 1 and "the estimate's stamps look read in too small a unit" in err


def test_every_real_file_is_in_seconds(data):
    for f in sorted(data.tum.glob("*.txt")):
        assert diagnose(ln.read_tum(f)) == ("seconds", ""), f
    for f in sorted(data.icra20.rglob("*.txt"))[::7]:
        for s, t in ln.read_openloris(f, warn=False).sequences.items():
            assert diagnose(t)[0] == "seconds", (f, s)


# --- 3. OpenLORIS: the output time of 9-number lines -------------------------------------------------


def test_nine_numbers_whose_second_is_not_an_output_time_are_refused(icra20, tmp_path, capsys, data):
    lines = (icra20 / ORB_CAFE).read_text().splitlines()
    moved = [f"{ln_} {ln_.split()[0]}" if len(ln_.split()) == 8 and not ln_.startswith("#") else ln_
             for ln_ in lines]  # the stamp appended at the end: the second number is x  # fmt: skip
    f = write(tmp_path, "cafe_moved.txt", "\n".join(moved) + "\n")
    first = next(i for i, t in enumerate(moved, 1) if len(t.split()) == 9)
    with pytest.raises(ln.ParseError, match=rf"line {first}: 9 numbers.*expected the pose's output time"):
        ln.read_openloris(f, warn=False)
    assert main(["evaluate", str(f), "--data", str(data.root), "--no-progress"]) == 1
    err = capsys.readouterr().err
    assert f"cafe_moved.txt, line {first}" in err and "Are the columns out of place" in err
    # an output time before its stamp, in a file of mixed 8 and 9 numbers: refused at its line
    t = float(lines[first - 1].split()[0])
    early = [*lines]
    early[first + 5] = f"{early[first + 5].split()[0]} {t - 10:.6f} " + " ".join(early[first + 5].split()[1:])
    g = write(tmp_path, "cafe_early.txt", "\n".join(early) + "\n")
    with pytest.raises(ln.ParseError, match=rf"line {first + 6}: 9 numbers.*is -1\d\.\d+ s from the stamp"):
        ln.read_openloris(g, warn=False)
    # the real 9-number files read as before: output times 65 to 100 days after the stamps
    real = ln.read_openloris(icra20 / MASLAM, warn=False)
    assert sum(len(s) for s in real.sequences.values()) > 500
    # and the official file with a real-like output time added is the same poses
    late = [f"{s.split()[0]} {float(s.split()[0]) + 8.6e6:.6f} " + " ".join(s.split()[1:])
            if len(s.split()) == 8 and not s.startswith("#") else s for s in lines]  # fmt: skip
    h = write(tmp_path, "cafe_late.txt", "\n".join(late) + "\n")
    a, b = ln.read_openloris(icra20 / ORB_CAFE, warn=False), ln.read_openloris(h, warn=False)
    for s in a.sequences:
        np.testing.assert_array_equal(a.sequences[s].positions, b.sequences[s].positions)


# --- 4. a pose file given as a times file -----------------------------------------------------------


def test_a_pose_file_given_as_times_says_so(pair, tmp_path, capsys):
    gt, est = pair
    gk, ek = write(tmp_path, "gt.kitti", _kitti(gt)), write(tmp_path, "est.kitti", _kitti(est))
    gtt = write(tmp_path, "gt.times", "".join(f"{t:.9f}\n" for t in gt.stamps))
    tum = write(tmp_path, "est.txt", _tum(est))
    rc, err, _ = _run(tmp_path, [str(ek), "--gt", str(gk), "--format", "kitti", "--est-times", str(ek),
                                 "--gt-times", str(gtt)], capsys)  # fmt: skip
    assert rc == 1 and "also given as its own times file" in err and "read it with --format kitti" not in err
    other = write(tmp_path, "other.kitti", _kitti(est))
    rc, err, _ = _run(tmp_path, [str(ek), "--gt", str(gk), "--format", "kitti", "--est-times", str(other),
                                 "--gt-times", str(gtt)], capsys)  # fmt: skip
    assert rc == 1 and "this looks like a KITTI pose file" in err and "not a times file" in err
    assert "--est-times" in err and "read it with --format kitti" not in err
    rc, err, _ = _run(tmp_path, [str(ek), "--gt", str(gk), "--format", "kitti", "--est-times", str(tum),
                                 "--gt-times", str(gtt)], capsys)  # fmt: skip
    assert rc == 1 and "TUM trajectory file" in err and "not a times file" in err


def test_a_manifest_of_kitti_files_pairs_by_index(matched, tmp_path):
    g, e = matched
    write(tmp_path, "gt/xyz.kitti", _kitti(g))
    write(tmp_path, "res/slam/xyz.txt", _kitti(e))
    text = (f'name = "kitti"\nscene = "xyz"\nroot = "{tmp_path / "gt"}"\ngroundtruth_format = "kitti"\n'
            'estimate_format = "kitti"\n[[session]]\nname = "xyz"\ngroundtruth = "xyz.kitti"\n')  # fmt: skip
    m = write(tmp_path, "k.toml", text)
    ev = ln.evaluate_manifest(m, tmp_path / "res" / "slam")
    assert ev.exit_status() == 0 and "association: by index" in ev.conventions
    fe = ev.errors[0].sequences[0]
    assert fe.matched == len(e) == 786
    ref = ln.sequence_errors(g, e, association="nearest", max_diff=1e-6)  # the same pairs, matched by stamps
    np.testing.assert_allclose(fe.ate, ref.ate, atol=1e-9)
    write(tmp_path, "res/slam/xyz.txt", _kitti(e.subset(np.arange(700))))  # 700 poses against 786: refused
    ev = ln.evaluate_manifest(m, tmp_path / "res" / "slam")
    assert ev.exit_status() == 1 and "needs files of the same length" in ev.failures[0].error


def test_association_index_chosen_for_files_with_stamps(matched, pair, tmp_path, capsys):
    g, e = matched
    gt_t, est_t = write(tmp_path, "gt.txt", _tum(g)), write(tmp_path, "est.txt", _tum(e))
    rc, err, table = _run(tmp_path, [str(est_t), "--gt", str(gt_t), "--association", "index"], capsys)
    assert rc == 0 and "association: by index" in err and table is not None
    rc, err, ref = _run(tmp_path, [str(est_t), "--gt", str(gt_t), "--association", "nearest"], capsys)
    assert table["ate_rmse"].iloc[0] == pytest.approx(ref["ate_rmse"].iloc[0], rel=1e-12)
    assert main(["evaluate", str(est_t), "--gt", str(gt_t), "--association", "index", "--t-offset", "0.5",
                 "--no-progress"]) == 2  # fmt: skip
    assert "--t-offset: poses paired by index" in capsys.readouterr().err
    full = write(tmp_path, "gt_full.txt", _tum(pair[0]))  # 3000 poses against 786
    rc, err, _ = _run(tmp_path, [str(est_t), "--gt", str(full), "--association", "index"], capsys)
    assert rc == 1 and "same length" in err and "Choose the association interpolate or nearest" in err
