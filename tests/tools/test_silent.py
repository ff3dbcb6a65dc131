"""Zero silent wrong results (issue 24): every class of mistake that used to give a plausible
number with exit status 0, a traceback or a hang, each tried several ways: on the command line, in
Python and through manifests, on the real TUM data of ../shared/data."""

from __future__ import annotations

import http.server
import re
import socket
import threading
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from helpers import circle, errors_of, openloris_text, write, write_bag
from scipy.spatial.transform import Rotation

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.alignment.geometry import degenerate_alignment, umeyama
from lorisnb.core.conventions.choices import fit_alignment
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.core.trajectory.units import check_stamp_units, stamp_unit
from lorisnb.io.readers import registry
from lorisnb.tools.evaluation import pool
from lorisnb.tools.evaluation.inputs import result_files
from lorisnb.tools.evaluation.runner import evaluate_manifest, evaluate_pairs

GT, EST = "freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"


@pytest.fixture(scope="module")
def pair(data):
    return ln.read_tum(data.tum / GT), ln.read_tum(data.tum / EST)


def _tum(traj: Trajectory, stamps: np.ndarray | None = None) -> str:
    t = traj.stamps if stamps is None else stamps
    return "".join(
        " ".join(f"{v:.17g}" for v in (s, *p, *q)) + "\n"
        for s, p, q in zip(t, traj.positions, traj.quaternions, strict=True)
    )


def _kitti(traj: Trajectory) -> str:
    m = np.concatenate([Rotation.from_quat(traj.quaternions).as_matrix(), traj.positions[:, :, None]], axis=2)
    return "".join(" ".join(f"{v:.17g}" for v in row) + "\n" for row in m.reshape(-1, 12))


def _euroc(traj: Trajectory, header: bool = True) -> str:
    head = "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z []\n"
    rows = [
        f"{int(round(t * 1e9))}," + ",".join(f"{v:.17g}" for v in (*p, q[3], q[0], q[1], q[2])) + "\n"
        for t, p, q in zip(traj.stamps, traj.positions, traj.quaternions, strict=True)
    ]
    return (head if header else "") + "".join(rows)


def _err(capsys) -> str:
    return capsys.readouterr().err


def _rc(args: list[str]) -> int:
    """The exit status of a command line (argparse exits for bad option values)."""
    try:
        return main(args)
    except SystemExit as exc:
        return int(exc.code or 0)


# --- 2. counted once, never dropped -----------------------------------------------------------


def test_the_same_input_named_twice_is_counted_once(data, tmp_path, capsys):
    d = tmp_path / "res" / "rgbdslam"
    est = write(d, "xyz.txt", (data.tum / EST).read_bytes())
    (tmp_path / "link.txt").symlink_to(est)
    once = evaluate_pairs(est, data.tum / GT)
    for twice in (
        [est, est],
        [tmp_path / "res", tmp_path / "res"],
        [tmp_path / "res", est],
        [est, tmp_path / "link.txt"],
    ):
        with pytest.warns(ln.LorisWarning, match=r"named more than once, each counted once"):
            ev = evaluate_pairs(twice, data.tum / GT)
        assert len(ev.errors) == 1 and ev.sequences()["ate_rmse"].tolist() == once.sequences()["ate_rmse"].tolist()
    rc = main(["evaluate", str(tmp_path / "res"), str(tmp_path / "res"), "--gt", str(data.tum / GT), "--no-progress",
               "--csv", str(tmp_path / "t.csv")])  # fmt: skip
    assert rc == 0 and len(pd.read_csv(tmp_path / "t.csv")) == 1
    assert "named more than once" in _err(capsys)


def test_a_linked_algorithm_folder_is_walked_and_a_loop_is_said(icra20, tmp_path, capsys):
    """A results folder holding a link to an algorithm's folder kept elsewhere (a lab's habit): its
    files are evaluated (they were left out without a word), labelled by the link's name; a link
    back to a folder it lies in is said and not walked again; the report's inputs are those files."""
    from lorisnb.tools.report.provenance import input_files

    res, elsewhere = tmp_path / "res", tmp_path / "elsewhere" / "runs"
    for folder, alg, name in ((res, "odom", "cafe-1-1-odom.txt"), (elsewhere, "orb", "cafe_1_1_orbslam2-original.txt")):
        (folder / alg).mkdir(parents=True)
        (folder / alg / name).write_bytes((icra20 / "per-seq" / ("odom" if alg == "odom" else "orbslam2_rgbd") / name)
                                          .read_bytes())  # fmt: skip
    (res / "orbslam2").symlink_to(elsewhere / "orb", target_is_directory=True)
    ev = ln.evaluate(res, progress=False)
    assert sorted(f.algorithm for f in ev.errors) == ["odom", "orbslam2"]
    assert [p.name for p in input_files([res], resolve=False)] == [
        "cafe-1-1-odom.txt",
        "cafe_1_1_orbslam2-original.txt",
    ]
    (res / "odom" / "back").symlink_to(res, target_is_directory=True)
    with pytest.warns(ln.LorisWarning, match=r"1 linked folder\(s\) lead back to a folder they are in, not walked again: "
                      r".*odom/back -> .*res$"):  # fmt: skip
        again = ln.evaluate(res, progress=False)
    assert sorted(f.algorithm for f in again.errors) == ["odom", "orbslam2"]
    assert main(["evaluate", str(res), "--no-progress"]) == 0
    assert "lead back to a folder they are in" in _err(capsys)


def test_the_ground_truth_is_never_scored_as_an_estimate_of_itself(data, tmp_path):
    d = tmp_path / "res"
    gt = write(d, "gt.txt", (data.tum / GT).read_bytes())
    write(d, "slam/xyz.txt", (data.tum / EST).read_bytes())
    with pytest.warns(ln.LorisWarning, match="the ground truth is among the estimates; left out"):
        ev = evaluate_pairs(d, gt)
    assert [f.algorithm for f in ev.errors] == ["slam"]
    with pytest.raises(ln.ValidationError, match="the only input is the ground truth itself"):
        evaluate_pairs(gt, gt)


def test_openloris_folder_named_twice_is_counted_once(icra20):
    folder = icra20 / "per-seq" / "dso"
    with pytest.warns(ln.LorisWarning, match="named more than once"):
        items = result_files([folder, folder, folder / "cafe-1-1-all.txt", folder.parent / ".." / "per-seq" / "dso"])
    assert len(items) == len(result_files(folder)) == len({p.resolve() for p, _ in items})


MANIFEST = """
name = "xyz twice"
scene = "xyz"
root = "{root}"
[conventions]
association = "nearest"
[[session]]
name = "xyz"
groundtruth = "{gt}"
"""


def test_a_manifest_session_listed_twice_is_an_error(data, tmp_path):
    base = MANIFEST.format(root=data.tum, gt=GT)
    cases = {
        "name": base + '[[session]]\nname = "xyz"\ngroundtruth = "other.txt"\n',
        "estimate file": base + f'[[session]]\nname = "b"\nestimate = "xyz.txt"\ngroundtruth = "{GT}"\n',
    }
    for what, text in cases.items():
        m = write(tmp_path, f"{what[:4]}.toml", text)
        with pytest.raises(ln.ParseError, match=f"have the same {what}.*a session listed twice"):
            ln.read_manifest(m)
        assert main(["evaluate", str(tmp_path), "--manifest", str(m), "--no-progress"]) == 2


def test_a_session_without_its_estimate_is_a_row_with_a_warning(data, tmp_path, capsys):
    gt = ln.read_tum(data.tum / GT)
    half = len(gt) // 2
    for k, part in ((1, slice(0, half)), (2, slice(half, None))):
        write(tmp_path, f"gt/s{k}.txt", _tum(Trajectory(gt.stamps[part], gt.positions[part], gt.quaternions[part])))
    est = (data.tum / EST).read_text().splitlines(keepends=True)
    write(tmp_path, "res/slam/s1.txt", "".join(est))
    write(tmp_path, "res/slam/S2.txt", "".join(est))  # the user meant s2.txt
    m = write(tmp_path, "two.toml", (
        f'name = "two"\nscene = "xyz"\nroot = "{tmp_path / "gt"}"\nlifelong = false\n'
        '[[session]]\nname = "s1"\ngroundtruth = "s1.txt"\n[[session]]\nname = "s2"\ngroundtruth = "s2.txt"\n'
    ))  # fmt: skip
    ev = evaluate_manifest(m, tmp_path / "res")
    table = ev.sequences(eps=0.1, phi=10)
    assert table["seq"].tolist() == [1, 2]  # the missing session never vanishes
    row = table.iloc[1]
    assert row["poses"] == 0 and row["matched"] == 0 and row["cr"] == 0 and row["cs_r"] == 0
    assert table.iloc[0]["matched"] > 0
    assert any("found S2.txt: names are case-sensitive" in w for w in ev.warnings)
    assert [f.kind for f in ev.unscored] == ["missing-estimate"] and ev.exit_status() == 1
    # scene CR counts the missing session's ground-truth time as not correct
    full = ev.scenes(eps=0.1, phi=10)
    assert full["cr"].iloc[0] < table.iloc[0]["cr"]
    out = tmp_path / "m.csv"
    assert main(["evaluate", str(tmp_path / "res"), "--manifest", str(m), "--csv", str(out), "--no-progress"]) == 1
    err = _err(capsys)
    assert "no estimate for 1 session(s)" in err and "not scored:" in err
    assert pd.read_csv(out)["seq"].tolist() == [1, 2]
    # the results folder named twice: scored once
    with pytest.warns(ln.LorisWarning, match="named more than once"):
        twice = evaluate_manifest(m, [tmp_path / "res", tmp_path / "res" / "slam"])
    assert len(twice.errors) == 1
    # no estimate of the scene at all: every session is a row
    (tmp_path / "res" / "slam" / "s1.txt").unlink()
    ev = evaluate_manifest(m, tmp_path / "res")
    assert ev.sequences()["poses"].tolist() == [0, 0] and ev.exit_status() == 1


# --- 4. formats and stamp units ---------------------------------------------------------------


def test_a_file_in_another_format_names_the_option_that_reads_it(pair, tmp_path, capsys, data):
    gt, est = pair
    kitti = write(tmp_path, "est_kitti.txt", _kitti(est))
    euroc = write(tmp_path, "gt.csv", _euroc(gt))
    euroc8 = write(tmp_path, "gt8.csv", _euroc(gt, header=False))
    cases = [
        (kitti, "tum", "--format kitti"),
        (euroc, "tum", "--gt-format euroc"),
        (euroc8, "tum", "--gt-format euroc"),
        (data.tum / EST, "euroc", "--format tum"),
        (data.tum / EST, "kitti", "--format tum"),
        (kitti, "euroc", "--format kitti"),
        (euroc, "kitti", "--format euroc"),
    ]
    for path, fmt, option in cases:
        with pytest.raises(ln.ParseError, match=option):
            ln.read_trajectory(path, fmt)
    with pytest.raises(ln.ParseError, match=r"has 12 fields.*--format kitti"):
        ln.read_tum(kitti)
    with pytest.raises(ln.ParseError, match=r"has a fraction; expected whole nanoseconds.*--format tum"):
        ln.read_euroc(data.tum / EST)
    # on the command line: a TUM file read with --format euroc is not taken as nanoseconds
    assert main(["evaluate", str(data.tum / EST), "--gt", str(data.tum / GT), "--format", "euroc",
                 "--gt-format", "tum", "--no-progress"]) == 1  # fmt: skip
    assert "--format tum" in _err(capsys)
    assert main(["evaluate", str(data.tum / EST), "--gt", str(euroc), "--no-progress"]) == 1  # nothing scored
    assert "--gt-format euroc" in _err(capsys)
    # without --gt a TUM file is read as an OpenLORIS result: the message says how to score it
    ev = ln.evaluate(data.tum / EST, jobs=1)
    assert "looks like a TUM trajectory file" in ev.failures[0].error and "--gt FILE" in ev.failures[0].error
    # and the right option reads them: the same numbers
    right = evaluate_pairs(data.tum / EST, euroc, gt_fmt="euroc", conventions="tum").sequences()
    ref = evaluate_pairs(data.tum / EST, data.tum / GT, conventions="tum").sequences()
    assert right["ate_rmse"].iloc[0] == pytest.approx(ref["ate_rmse"].iloc[0], rel=1e-9)


def test_evo_tf_spelling_is_read_as_lorisnb_spelling(pair, tmp_path):
    pytest.importorskip("rosbags")
    gt, _ = pair
    part = Trajectory(gt.stamps[:60], gt.positions[:60], gt.quaternions[:60])
    bag = write_bag(tmp_path / "tf2", part, 2, tf=("world", "odom", "base"))
    ours = ln.read_trajectory(bag, "bag", tf="world:base")
    for kw in ({"tf": "/tf:world.base"}, {"topic": "/tf:world.base"}):  # evo_ape's syntax, as tf or as topic
        theirs = ln.read_trajectory(bag, "bag", **kw)
        np.testing.assert_array_equal(theirs.positions, ours.positions)
    np.testing.assert_allclose(ours.positions, part.positions, atol=1e-9)


def test_the_registry_is_the_one_source_of_format_knowledge():
    from lorisnb.cli import build_parser
    from lorisnb.io.datasets.manifest import SUFFIX

    assert set(registry.FORMAT_NAMES) == set(registry.FORMATS) == set(ln.io.TRAJECTORY_FORMATS)
    sub = build_parser()._subparsers._group_actions[0].choices  # type: ignore[union-attr]
    fmt = next(a for a in sub["evaluate"]._actions if a.dest == "format")
    assert tuple(fmt.choices) == registry.FORMAT_NAMES
    assert all(SUFFIX[n] == registry.suffixes(n)[0] for n in registry.FORMAT_NAMES)
    assert registry.recognise(registry.sample_bytes(b"#ROSBAG V2.0\n")) == ["bag"]
    assert registry.recognise(registry.sample_bytes(b"scene: cafe\nframe: d400_color\nseq: 1\n")) == ["openloris"]
    assert registry.recognise(registry.sample_bytes(b"")) == []


def test_stamps_in_different_units_are_an_error_naming_the_cause(pair, tmp_path, capsys, data):
    gt, est = pair
    t0 = gt.stamps[0]
    g = write(tmp_path, "gt.txt", _kitti(gt))
    e = write(tmp_path, "est.txt", _kitti(est))
    gt_times = write(tmp_path, "gt_times.txt", "".join(f"{t - t0:.17g}\n" for t in gt.stamps))
    est_times = write(tmp_path, "est_times.txt", "".join(f"{t - t0:.17g}\n" for t in est.stamps))
    base = ["evaluate", str(e), "--gt", str(g), "--format", "kitti", "--no-progress"]
    assert main([*base, "--est-times", str(est_times)]) == 1
    err = _err(capsys)
    assert "stamps in different units" in err and "ground truth's stamps are pose indices" in err
    assert "--gt-times" in err
    assert main([*base, "--gt-times", str(gt_times)]) == 1
    assert "estimate's stamps are pose indices" in _err(capsys)
    assert main([*base, "--gt-times", str(gt_times), "--est-times", str(est_times), "--csv",
                 str(tmp_path / "ok.csv")]) == 0  # fmt: skip
    assert pd.read_csv(tmp_path / "ok.csv")["ate_rmse"].iloc[0] < 0.1
    # nanoseconds against seconds, in Python
    ns = Trajectory(gt.stamps * 1e9, gt.positions, gt.quaternions)
    assert (stamp_unit(ns), stamp_unit(gt)) == ("nanoseconds", "seconds")
    with pytest.raises(ln.EvaluationError, match=r"ground truth's stamps look like nanoseconds.*--gt-format euroc"):
        check_stamp_units(est, ns)
    check_stamp_units(est, gt)  # the same units: fine
    with pytest.raises(ln.EvaluationError, match="stamps of both files look like nanoseconds"):
        check_stamp_units(Trajectory(est.stamps * 1e9, est.positions, est.quaternions), ns)
    # through a manifest: KITTI estimates (no stamps) against TUM ground truth (seconds)
    write(tmp_path, "res/slam/xyz.txt", _kitti(est))
    kitti_manifest = MANIFEST.format(root=data.tum, gt=GT).replace(
        'scene = "xyz"', 'scene = "xyz"\nestimate_format = "kitti"'
    )
    m = write(tmp_path, "k.toml", kitti_manifest)
    ev = evaluate_manifest(m, tmp_path / "res" / "slam")
    assert ev.exit_status() == 1 and "estimate's stamps are pose indices" in ev.failures[0].error
    nsfile = write(tmp_path, "gt_ns.txt", _tum(gt, gt.stamps * 1e9))
    ev = evaluate_pairs(e, nsfile, fmt="kitti", est_times=est_times, gt_fmt="tum")
    assert ev.exit_status() == 1 and "stamps in different units" in ev.failures[0].error


# --- 5. exit status ---------------------------------------------------------------------------


def test_nothing_matched_is_exit_status_1_on_every_command(pair, tmp_path, capsys, data):
    gt, est = pair
    late = write(tmp_path, "late/slam.txt", _tum(est, est.stamps + 1e5))  # no stamp overlaps
    gtp = str(data.tum / GT)
    for command in (["evaluate"], ["sweep", "--eps", "0.1,1"], ["compare", "--eps", "0.1", "--phi", "10"]):
        out = tmp_path / f"{command[0]}.csv"
        rc = main([*command, str(late), "--gt", gtp, "--no-progress", "--csv", str(out)])
        assert rc == 1, command
        assert "not scored:" in _err(capsys)
        if command[0] != "compare":
            rows = pd.read_csv(out)
            assert (rows["matched"] == 0).all() and (rows["cr"] == 0).all()  # still in the table
    pytest.importorskip("evo")
    assert main(["crosscheck", gtp, str(late)]) == 1  # crosscheck: nothing to compare is 1 as well
    assert "no estimate stamp" in _err(capsys)
    ev = evaluate_pairs(late, gtp)
    assert ev.exit_status() == 1 and [f.kind for f in ev.unscored] == ["no-match"]
    assert "no estimate stamp" in ev.unscored[0].error
    assert ev.failures_table()["status"].tolist() == ["not scored"]
    good = evaluate_pairs(data.tum / EST, gtp)
    assert good.exit_status() == 0 and good.unscored == []
    # one good and one unmatched input: 1, and both rows are there
    assert main(["evaluate", str(data.tum / EST), str(late), "--gt", gtp, "--no-progress"]) == 1
    assert main(["evaluate", str(data.tum / EST), "--gt", gtp, "--no-progress"]) == 0
    assert _rc(["evaluate", str(data.tum / EST), "--gt", gtp, "--phi", "400"]) == 2  # usage


def test_an_empty_estimate_is_not_scored_but_a_declared_failure_is(tmp_path, data, icra20, capsys):
    """An estimate of a pair with no pose (a crashed run wrote nothing, or only comments) is 1 with
    a `not scored:` line; an OpenLORIS file of `seq:` blocks without poses declares failed runs
    (the official data's corridor-1-failed.txt files) and is scored as the paper scores them: 0."""
    gtp = str(data.tum / GT)
    for name, text in (("empty.txt", ""), ("comments.txt", "# only comments\n# x\n")):
        est = write(tmp_path, name, text)
        rc = main(["evaluate", str(est), "--gt", gtp, "--no-progress"])
        err = _err(capsys)
        assert rc == 1 and (f"not scored: {est}: holds no pose" in err or "empty file" in err), err
    ev = evaluate_pairs(tmp_path / "comments.txt", gtp)
    assert [f.kind for f in ev.unscored] == ["no-pose"] and ev.exit_status() == 1
    failed = sorted(icra20.glob("per-seq/*/corridor-1-failed.txt"))
    assert failed, "the official data's declared failures"
    ev = ln.evaluate(failed[0])
    assert ev.exit_status() == 0 and all(e.poses == 0 for f in ev.errors for e in f.sequences)
    assert (ev.sequences()["cr"] == 0).all()


def test_messages_name_the_real_cause(tmp_path, data, capsys):
    """What left nothing to match is named: an option that thinned both trajectories to one pose
    (not a clock offset), an empty folder (not "the ground truth itself"); a refused value's
    message is whole."""
    est, gtp = str(data.tum / EST), str(data.tum / GT)
    for opts, named in ((["--downsample", "1"], "downsample 1"), (["--motion-filter", "100", "180"], "motion filter")):
        assert main(["evaluate", est, "--gt", gtp, *opts, "--no-progress"]) == 1
        err = _err(capsys)
        assert f"after {named}" in err and "clock offset" not in err, err
    (tmp_path / "empty").mkdir()
    assert main(["evaluate", str(tmp_path / "empty"), "--gt", gtp, "--no-progress"]) == 1
    err = _err(capsys)
    assert "no input file was found" in err and "ground truth itself" not in err
    assert _rc(["evaluate", est, "--gt", gtp, "--rpe-all-pairs", "--rpe-tolerance", "-1"]) == 2
    assert re.search(r"--rpe-tolerance=-1: expected a positive number$", _err(capsys).strip(), re.M)


# --- 6. degenerate alignments -----------------------------------------------------------------


def test_degenerate_alignments_are_refused_or_warned(pair, data, tmp_path):
    gt, est = pair
    m = ln.session_errors({1: gt}, {1: est}, ln.Conventions.preset("tum")).sequences[0]
    p_e, p_g = m.est_positions, m.gt_positions
    for frames, method in ((2, "se3"), (2, "sim3")):
        with pytest.raises(ln.EvaluationError, match=r"only 2 matched positions.*--align-frames"):
            fit_alignment(p_e, p_g, method, frames)
    line = np.outer(np.arange(10.0), [1.0, 2.0, 0.5])
    with pytest.raises(ln.EvaluationError, match="determined: 10 matched positions on one line, so the rotation"):
        fit_alignment(line, line + 1, "se3")
    same = np.repeat(p_e[:1], 50, axis=0)
    with pytest.raises(ln.EvaluationError, match=r"determined: 50 matched estimate positions, all identical \(zero"):
        fit_alignment(same, p_g[:50], "sim3")
    vertical = np.column_stack([np.zeros(20), np.zeros(20), np.arange(20.0)])
    with pytest.raises(ln.EvaluationError, match="no horizontal spread"):
        fit_alignment(vertical, vertical, "posyaw")
    assert degenerate_alignment(p_e, p_g) is None
    # align_frames=1 (rpg's first-pose alignment) stays possible, and normal data is unchanged
    fit_alignment(p_e, p_g, "se3", 1, est.quaternions[:1], gt.quaternions[:1])
    np.testing.assert_array_equal(umeyama(p_e, p_g, strict=True).rotation, umeyama(p_e, p_g).rotation)
    # through the pipeline: the file fails with the reason, the exit status is 1
    ev = evaluate_pairs(data.tum / EST, data.tum / GT, conventions=ln.Conventions.preset("tum", align_frames=2))
    assert ev.exit_status() == 1 and "no SE(3) alignment can be determined" in ev.failures[0].error
    assert ev.failures[0].error.startswith(f"{data.tum / EST}: ")  # which input, among many, failed
    # through a manifest's [conventions]: the same refusal
    write(tmp_path, "res/slam/xyz.txt", (data.tum / EST).read_bytes())
    m = write(tmp_path, "m.toml", MANIFEST.format(root=data.tum, gt=GT) + "")
    text = m.read_text().replace('association = "nearest"', 'association = "nearest"\nalign_frames = 2')
    ev = evaluate_manifest(write(tmp_path, "m2.toml", text), tmp_path / "res")
    assert ev.exit_status() == 1 and "only 2 matched positions" in ev.failures[0].error
    # posyaw on an estimate tilted against gravity: a warning saying what to do
    tilt = Rotation.from_euler("x", 40, degrees=True)
    tilted = Trajectory(est.stamps, tilt.apply(est.positions), (tilt * Rotation.from_quat(est.quaternions)).as_quat())
    with pytest.warns(ln.LorisWarning, match=r"posyaw.*tilts z by 4\d\.\d deg.*--align se3"):
        ln.session_errors({1: gt}, {1: tilted}, ln.Conventions.preset("vio"))
    tilted_file = write(tmp_path, "tilted/slam.txt", _tum(tilted))
    ev = evaluate_pairs(tilted_file, data.tum / GT, conventions="vio")
    assert any("tilts z by" in w for w in ev.warnings)  # kept with the file, shown by the command line
    # an alignment on all of a handful of poses absorbs their error: said
    few = write(tmp_path, "few/slam.txt", "".join((data.tum / EST).read_text().splitlines(keepends=True)[10:200:40]))
    ev = evaluate_pairs(few, data.tum / GT, conventions="tum")
    assert any("fitted on all of only 5 matched poses" in w for w in ev.warnings)


def test_a_degenerate_lifelong_alignment_of_an_openloris_file_is_said(tmp_path):
    gt1, gt2 = circle(), circle(t0=2000.0)
    gt = write(tmp_path, "gt_cafe_1.txt", openloris_text({1: gt1, 2: gt2}))
    first = Trajectory(gt1.stamps[:2], gt1.positions[:2] + 0.1, gt1.quaternions[:2])  # 2 poses, then lost
    est = write(tmp_path, "algo/cafe.txt", openloris_text({1: first, 2: gt2}))
    ref = ln.read_openloris(gt)
    fe = errors_of(est, ref, mode="lifelong")
    assert any("seq 1: the alignment was fitted on only 2 matched positions" in w for w in fe.warnings)
    # said, not changed: the official tool aligns on those two poses all the same
    fitted = umeyama(first.positions, fe.sequences[0].gt_positions)
    np.testing.assert_allclose(fe.alignment.rotation, fitted.rotation, atol=1e-6)  # 9 digits in the file
    assert fe.aligned_on == 1 and fe.sequences[1].matched == len(gt2)
    good = errors_of(write(tmp_path, "algo2/cafe.txt", openloris_text({1: gt1, 2: gt2})), ref, mode="lifelong")
    assert not any("alignment was fitted" in w for w in good.warnings)


# --- 8. values outside their meaning ----------------------------------------------------------


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        ("--phi", "400", "at most 180 degrees"),
        ("--eps", "relative:5", r"for 5 % write 0.05"),
        ("--delta", "-1", "seconds > 0"),
        ("--tau", "3600000", "at most 86400 seconds.*milliseconds"),
        ("--delta", "5000000", "milliseconds instead of seconds"),
    ],
)
def test_values_outside_their_meaning_are_refused_everywhere(data, tmp_path, capsys, option, value, message):
    args = ["evaluate", str(data.tum / EST), "--gt", str(data.tum / GT), option, value, "--no-progress"]
    assert _rc(args) == 2
    assert re.search(message, _err(capsys).strip().splitlines()[-1])  # one line says what is wrong
    name = option.lstrip("-")
    ev = evaluate_pairs(data.tum / EST, data.tum / GT)
    with pytest.raises(ln.ValidationError, match=message):
        ev.sequences(**{name: value})
    with pytest.raises(ln.ValidationError, match=message):
        ln.sweep(ev.errors, **{name: [value]})


def test_a_degenerate_fit_is_said_in_a_sentence():
    """Each reason reads after 'the alignment was fitted on' ('fitted on the 10 matched positions lie on
    one line', 'fitted on all 5 matched estimate positions are identical' were not sentences)."""
    from lorisnb.core.pipeline.plausibility import degenerate_fit

    line = np.outer(np.arange(10.0), [1.0, 2.0, 0.5])
    said = degenerate_fit("seq 1", line, line + 1)
    assert said is not None and said.startswith(
        "seq 1: the alignment was fitted on 10 matched positions on one line, so"
    )
    same = np.zeros((5, 3))
    said = degenerate_fit("seq 1", same, np.random.default_rng(0).normal(size=(5, 3)))
    assert said is not None and said.startswith(
        "seq 1: the alignment was fitted on 5 matched estimate positions, all identical (zero spread), so its rotation"
    )


def test_manifest_and_sweep_fractions_use_the_same_limits(data, tmp_path):
    m = write(
        tmp_path, "m.toml", MANIFEST.format(root=data.tum, gt=GT).replace("[conventions]", "phi = 400\n[conventions]")
    )
    with pytest.raises(ln.ParseError, match="at most 180 degrees"):
        ln.read_manifest(m)
    ev = evaluate_pairs(data.tum / EST, data.tum / GT)
    with pytest.raises(ln.ValidationError, match="write 0.05"):
        ln.sweep(ev.errors, eps=[5], relative_to="extent")
    assert len(ln.sweep(ev.errors, eps=[0.05, np.inf], relative_to="extent")) == 2
    # relative_to with no fraction to read (eps left at inf): it changed nothing and was accepted
    with pytest.raises(ln.ValidationError, match="relative_to=extent: no eps value to read as a fraction"):
        ln.sweep(ev.errors, relative_to="extent")
    rc = main(["sweep", str(data.tum / EST), "--gt", str(data.tum / GT), "--relative-to", "length", "--no-progress"])
    assert rc == 2


# --- 9. the Dask scheduler, on loopback only ----------------------------------------------------


@pytest.fixture
def http_port():
    server = http.server.HTTPServer(("127.0.0.1", 0), http.server.SimpleHTTPRequestHandler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield server.server_port
    server.shutdown()
    server.server_close()


def _closed_port() -> int:
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def test_scheduler_addresses_are_checked_and_time_out(http_port, monkeypatch, data, capsys):
    pytest.importorskip("distributed")
    for bad in ("not-an-address", "http://127.0.0.1:8786", "tcp://127.0.0.1", "127.0.0.1:99999", ""):
        with pytest.raises(ln.ValidationError, match="expected tcp://HOST:PORT"):
            pool.connect_scheduler(bad, timeout=1)
    with pytest.raises(ln.EvaluationError, match=r"cannot reach the Dask scheduler \(Connection refused\)"):
        pool.connect_scheduler(f"tcp://127.0.0.1:{_closed_port()}", timeout=1)
    start = time.monotonic()
    with pytest.raises(ln.EvaluationError, match="did not answer as a Dask scheduler within 1 s.*dashboard"):
        pool.connect_scheduler(f"tcp://127.0.0.1:{http_port}", timeout=1)
    assert time.monotonic() - start < 5
    monkeypatch.setattr(pool, "SCHEDULER_TIMEOUT", 1.0)
    odom = str(data.icra20 / "per-seq" / "odom")
    for address in ("not-an-address", f"127.0.0.1:{http_port}", f"tcp://127.0.0.1:{_closed_port()}"):
        assert main(["evaluate", odom, "--scheduler", address, "--no-progress"]) == 2
        err = _err(capsys).strip().splitlines()
        assert len(err) == 1 and address in err[0] and "Traceback" not in err[0]
    with pytest.raises(SystemExit) as exc:  # an empty value: a usage error, as every option's
        main(["evaluate", odom, "--scheduler", "", "--no-progress"])
    assert exc.value.code == 2 and "--scheduler: an empty value" in _err(capsys)


def test_a_real_scheduler_on_loopback_connects():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=1, processes=False, protocol="tcp", host="127.0.0.1",
                                  dashboard_address=None) as cluster:  # fmt: skip
        client = pool.connect_scheduler(cluster.scheduler_address, timeout=5)
        try:
            assert client.submit(lambda x: x + 1, 1).result() == 2
        finally:
            client.close()


# --- 11. outputs checked before any work --------------------------------------------------------


@pytest.mark.parametrize(
    ("outputs", "message"),
    [
        (["--csv", "X.csv", "--latex", "X.csv"], "both name"),
        (["--csv", "X.tex"], "expected a .csv file name"),
        (["--csv", "out.txt"], "expected a .csv file name"),
        (["--latex", "table.md"], "expected a .tex file name"),
        (["--markdown", "table.tex"], "expected a .md file name"),
        (["--parquet", "pq"], "--parquet: not used by lorisnb compare"),
    ],
)
def test_outputs_are_refused_before_any_work(data, tmp_path, monkeypatch, capsys, outputs, message):
    monkeypatch.chdir(tmp_path)
    called = []
    monkeypatch.setattr("lorisnb.tools.evaluation.jobs.read_trajectory", lambda *a, **k: called.append(a))
    rc = main(["compare", str(data.tum / EST), "--gt", str(data.tum / GT), *outputs, "--no-progress"])
    assert rc == 2 and message in _err(capsys)
    assert called == [] and list(tmp_path.iterdir()) == []  # nothing read, nothing left behind


def test_folder_and_file_outputs_do_not_overlap(data, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    rc = main(["evaluate", str(data.tum / EST), "--gt", str(data.tum / GT), "--parquet", "pq", "--csv", "pq/t.csv"])
    assert rc == 2 and "lies inside the --parquet folder" in _err(capsys)
    rc = main(["sweep", str(data.tum / EST), "--gt", str(data.tum / GT), "--parquet", "t.csv"])
    assert rc == 2 and "expected a folder name" in _err(capsys)
    assert list(tmp_path.iterdir()) == []
    # a CSV among CSV estimates would be read as an estimate by the next run
    d = write(tmp_path, "res/slam/xyz.csv", "x").parent.parent
    rc = main(["evaluate", str(d), "--gt", str(data.tum / GT), "--format", "euroc", "--csv", str(d / "table.csv")])
    assert rc == 2 and "lies in the input folder" in _err(capsys)
    assert main(["evaluate", str(data.tum / EST), "--gt", str(data.tum / GT), "--csv", "t.csv.gz"]) == 2
    assert "expected a .csv file name" in _err(capsys) and not (tmp_path / "t.csv.gz").exists()


# --- 12. reprs and any iterable of paths ------------------------------------------------------


def test_objects_print_a_short_useful_repr(data, icra20, tmp_path):
    ev = evaluate_pairs([data.tum / EST, write(tmp_path, "x/late.txt", "1 0 0 0 0 0 0 1\n")], data.tum / GT)
    text = repr(ev)
    assert text == "<Evaluation: 2 inputs (2 algorithms, 1 scene), 1 unscored; EvalSpec.preset('openloris')>"
    f = ev.errors[0]
    assert repr(f).startswith(f"<FileErrors {f.algorithm} {f.file} (scene freiburg1_xyz, per-seq): 1 sequence, ")
    s = repr(f.sequences[0])
    assert s.startswith("<SequenceErrors seq 1: 788 poses, ") and "ATE RMSE" in s and "AOE RMSE" in s
    traj = ln.read_tum(data.tum / EST)
    assert repr(traj).startswith("<Trajectory: 788 poses, stamps 1305031102.") and " s (" in repr(traj)
    rf = ln.read_openloris(icra20 / "per-seq" / "dso" / "cafe-1-1-all.txt")
    assert repr(rf) == "<ResultFile cafe-1-1-all.txt: scene cafe, frame d400_color, 1 sequence, 314 poses>"
    m = ln.read_manifest(write(tmp_path, "m.toml", MANIFEST.format(root=data.tum, gt=GT)))
    assert repr(m) == "<Manifest 'xyz twice': 1 session (1 scene), per session, tum ground truth, tum estimates>"
    assert re.fullmatch(r"<Sim3: rotation [\d.]+ deg, translation \[.*\] m, scale 1>", repr(f.alignment))
    assert all(len(repr(o)) < 300 for o in (ev, f, f.sequences[0], traj, rf, m, f.alignment))


def test_any_iterable_of_paths_works(icra20):
    folder = icra20 / "per-seq" / "dso"
    files = sorted(str(p) for p in folder.glob("*.txt"))[:3]
    expected = [p for p, _ in result_files(files)]
    for given in (
        tuple(files), (f for f in files), set(files), np.array(files), pd.Series(files), pd.Index(files),
        [Path(f) for f in files],
    ):  # fmt: skip
        assert [p for p, _ in result_files(given)] == expected, type(given)
    assert [p for p, _ in result_files(np.array(files[0]))] == expected[:1]
    ev = ln.evaluate((f for f in files), jobs=1)  # a generator is read once
    assert len(ev.errors) + len(ev.skipped) == 3
    for bad in (42, pd.DataFrame({"a": files}), [files[0], 3], ""):
        with pytest.raises(ln.ValidationError):
            result_files(bad)


def test_a_missing_estimate_is_never_offered_another_sessions_file(data, tmp_path):
    """Session s2's missing ``s2.txt`` got the hint "found s1.txt: names are case-sensitive; rename
    it", naming session s1's own estimate; another session's file is never the one meant."""
    gt = ln.read_tum(data.tum / GT)
    half = len(gt) // 2
    for k, part in ((1, slice(0, half)), (2, slice(half, None))):
        write(tmp_path, f"gt/s{k}.txt", _tum(Trajectory(gt.stamps[part], gt.positions[part], gt.quaternions[part])))
    write(tmp_path, "res/slam/s1.txt", (data.tum / EST).read_text())
    m = write(tmp_path, "two.toml", (
        f'name = "two"\nscene = "xyz"\nroot = "{tmp_path / "gt"}"\nlifelong = false\n'
        '[[session]]\nname = "s1"\ngroundtruth = "s1.txt"\n[[session]]\nname = "s2"\ngroundtruth = "s2.txt"\n'
    ))  # fmt: skip
    ev = evaluate_manifest(m, tmp_path / "res")
    notes = [w for w in ev.warnings if "no estimate for 1 session" in w]
    assert notes and "s2.txt not found" in notes[0] and "found s1.txt" not in notes[0], notes


def test_a_typo_of_a_threshold_names_every_setting_and_the_one_meant(data):
    """``ev.sequences(epss=1)`` listed the RPE settings only, as if eps were not one."""
    ev = evaluate_pairs(data.tum / EST, data.tum / GT)
    with pytest.raises(ln.ValidationError, match=r"epss: not a setting of the scores \(did you mean 'eps'\?\); "
                       "expected one of eps, phi, delta, tau, rpe_delta"):  # fmt: skip
        ev.sequences(epss=1)
    with pytest.raises(ln.ValidationError, match="did you mean 'rpe_delta'"):
        ev.sequences(rpe_detla=2)


@pytest.mark.parametrize("name", ["algorithms", "scenes"])
def test_an_empty_list_of_names_is_refused_not_read_as_nothing_or_everything(icra20, name, capsys):
    """``algorithms=[]`` evaluated nothing and exited 0 (a quick notebook put its defaults in its
    place); an empty list selects nothing, so it is refused, naming the parameter."""
    from lorisnb.tools.notebook.params import check_values

    with pytest.raises(ln.ValidationError, match=rf"{name}=\[\]: an empty list selects nothing"):
        ln.evaluate(icra20 / "per-seq" / "odom", **{name: []})
    with pytest.raises(ln.ValidationError, match=rf"{name}=\[\]"):
        check_values({name: []}, ["per_sequence_benchmark"])
