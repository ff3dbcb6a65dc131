"""Pairs, sessions, bags and manifests: lorisnb reproduces TUM's evaluate_ate.py and
rpg_trajectory_evaluation on the same files (values and provenance in reference_tools.py), and
every input kind evaluates from the command line and from Python with every metric."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from helpers import write, write_bag
from reference_tools import REFERENCE

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.conventions.choices import Conventions, associate_nearest
from lorisnb.core.metrics.openloris import rmse
from lorisnb.core.metrics.relative import rpg_relative_errors
from lorisnb.core.pipeline.sessions import match, session_errors
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.io import read_tum
from lorisnb.tools.evaluation.runner import evaluate_manifest, evaluate_pairs

PAIRS = {
    "fr2_desk": ("fr2_desk_groundtruth.txt", "fr2_desk_ORB.txt"),
    "fr1_xyz": ("freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"),
}
REL = 1e-9
METRICS = [
    "ate_rmse",
    "aoe_rmse",
    "cr",
    "cr_t",
    "cs_r",
    "c_ate_rmse",
    "c_aoe_rmse",
    "rpe_trans_rmse",
    "c_rpe_trans_rmse",
]


@pytest.fixture(scope="module")
def tum_pairs(data):
    with pytest.warns(ln.LorisWarning):  # fr2_desk's ground truth repeats one stamp
        return {k: (read_tum(data.tum / g), read_tum(data.tum / e)) for k, (g, e) in PAIRS.items()}


@pytest.mark.parametrize("name", PAIRS)
def test_tum_evaluate_ate_is_reproduced(tum_pairs, name):
    gt, est = tum_pairs[name]
    for key, values in REFERENCE[name].items():
        if not key.startswith("tum_ate"):
            continue
        pairs, ate = values
        offset, max_diff = (float(part.split("=")[1]) for part in key.split()[1:])
        conv = Conventions.preset("tum", max_diff=max_diff, t_offset=offset)
        e = session_errors({1: gt}, {1: est}, conv).sequences[0]
        assert e.matched == pairs, key
        assert rmse(e.ate) == pytest.approx(ate, rel=REL), key


@pytest.mark.parametrize("name", PAIRS)
def test_rpg_absolute_errors_are_reproduced(tum_pairs, name):
    gt, est = tum_pairs[name]
    for key, values in REFERENCE[name].items():
        if not key.startswith("rpg_abs"):
            continue
        pairs, ate, aoe, scale = values
        method, n = key.split()[1], int(key.split()[2].split("=")[1])
        conv = Conventions(association="nearest", align=method, align_frames=None if n == -1 else n)
        e = session_errors({1: gt}, {1: est}, conv).sequences[0]
        assert e.matched == pairs, key
        assert rmse(e.ate) == pytest.approx(ate, rel=REL), key
        assert rmse(e.aoe) == pytest.approx(aoe, rel=REL), key
        assert e.scale == pytest.approx(scale, rel=REL), key


@pytest.mark.parametrize("name", PAIRS)
def test_rpg_relative_errors_are_reproduced(tum_pairs, name):
    gt, est = tum_pairs[name]
    conv = Conventions.preset("rpg")
    scale = session_errors({1: gt}, {1: est}, conv).sequences[0].scale
    a = match(gt, est, conv)
    rel = rpg_relative_errors(
        a.gt_positions, a.gt_rotations.as_quat(), est.positions[a.est_index], est.quaternions[a.est_index], scale=scale
    )
    for key, values in REFERENCE[name].items():
        if not key.startswith("rpg_rel"):
            continue
        length, samples, trans_perc, deg_per_m = values
        sub = rel[rel["length"] == length]
        assert len(sub) == samples, key
        assert sub["trans_perc"].mean() == pytest.approx(trans_perc, rel=REL), key
        assert sub["rot_deg_per_m"].mean() == pytest.approx(deg_per_m, rel=REL), key


def _greedy(g, e, max_diff):
    """TUM's associate.py, literally (for comparison only)."""
    cand = sorted((abs(a - b), a, b) for a in g for b in e if abs(a - b) < max_diff)
    fg, fe, out = set(g), set(e), []
    for _, a, b in cand:
        if a in fg and b in fe:
            fg.remove(a)
            fe.remove(b)
            out.append((a, b))
    return sorted(out, key=lambda p: p[1])


@pytest.mark.parametrize("seed", range(20))
def test_nearest_association_equals_tum_greedy(seed):
    rng = np.random.default_rng(seed)
    g = np.unique(np.round(np.cumsum(rng.uniform(0.001, 0.05, 200)), 3))
    e = np.unique(np.round(np.cumsum(rng.uniform(0.001, 0.06, 150)), 3))
    gi, ej = associate_nearest(g, e, 0.02)
    assert list(zip(g[gi].tolist(), e[ej].tolist(), strict=True)) == _greedy(g.tolist(), e.tolist(), 0.02)


def _check_table(table: pd.DataFrame) -> None:
    assert len(table) >= 1
    row = table.iloc[0]
    for m in METRICS:
        assert np.isfinite(row[m]), m
    assert 0 < row["cr"] <= 1 and row["matched"] > 100


def _tum(traj) -> str:
    return "".join(
        " ".join(f"{v:.17g}" for v in (t, *p, *q)) + "\n"
        for t, p, q in zip(traj.stamps, traj.positions, traj.quaternions, strict=True)
    )


def _euroc(path, traj):
    rows = [
        f"{int(round(t * 1e9))},{p[0]:.17g},{p[1]:.17g},{p[2]:.17g},{q[3]:.17g},{q[0]:.17g},{q[1]:.17g},{q[2]:.17g},0,0,0"
        for t, p, q in zip(traj.stamps, traj.positions, traj.quaternions, strict=True)
    ]
    return write(
        path.parent, path.name, "#timestamp,p_x,p_y,p_z,q_w,q_x,q_y,q_z,v_x,v_y,v_z\n" + "\n".join(rows) + "\n"
    )


def _kitti(folder, name, traj):
    mats = np.concatenate([traj.rotations().as_matrix(), traj.positions[:, :, None]], axis=2).reshape(-1, 12)
    write(folder, f"{name}.txt", "\n".join(" ".join(f"{v:.17g}" for v in m) for m in mats) + "\n")
    write(folder, f"{name}_times.txt", "\n".join(f"{t:.17g}" for t in traj.stamps) + "\n")
    return folder / f"{name}.txt", folder / f"{name}_times.txt"


@pytest.mark.thorough
def test_every_input_kind_from_the_command_line_and_python(tum_pairs, tmp_path, capsys):
    gt, est = tum_pairs["fr2_desk"]
    sub = slice(0, 1500)
    gt_s = Trajectory(gt.stamps[:6000], gt.positions[:6000], gt.quaternions[:6000])
    est_s = Trajectory(est.stamps[sub], est.positions[sub], est.quaternions[sub])
    d = tmp_path
    tum_gt, tum_est = write(d, "tum/gt.txt", _tum(gt_s)), write(d, "tum/orb.txt", _tum(est_s))
    euroc_gt = _euroc(d / "euroc" / "data.csv", gt_s)
    k_gt, k_gt_t = _kitti(d / "kitti", "gt", gt_s)
    k_est, k_est_t = _kitti(d / "kitti", "est", est_s)
    bag1_gt, bag1_est = (
        write_bag(d / "gt1.bag", gt_s, 1),
        write_bag(d / "est1.bag", est_s, 1, "nav_msgs/msg/Odometry", "/odom"),
    )
    bag2_gt = write_bag(d / "gt2", gt_s, 2, tf=("world", "odom", "base"))
    bag2_est = write_bag(d / "est2", est_s, 2, "geometry_msgs/msg/PoseWithCovarianceStamped", "/amcl_pose")
    kinds = {
        "tum": ([str(tum_est)], ["--gt", str(tum_gt)], dict(fmt="tum")),
        "euroc": ([str(tum_est)], ["--gt", str(euroc_gt), "--gt-format", "euroc"], dict(fmt="tum", gt_fmt="euroc")),
        "kitti": (
            [str(k_est)],
            ["--gt", str(k_gt), "--format", "kitti", "--gt-times", str(k_gt_t), "--est-times", str(k_est_t)],
            dict(fmt="kitti", gt_times=k_gt_t, est_times=k_est_t),
        ),  # fmt: skip
        "ros1": ([str(bag1_est)], ["--gt", str(bag1_gt), "--format", "bag"], dict(fmt="bag")),
        "ros2": (
            [str(bag2_est)],
            ["--gt", str(bag2_gt), "--format", "bag", "--gt-tf", "world:base"],
            dict(fmt="bag", gt_tf="world:base"),
        ),  # fmt: skip
    }
    reference = None
    for kind, (ests, opts, kw) in kinds.items():
        out_csv = d / f"{kind}.csv"
        argv = [
            "evaluate",
            *ests,
            *opts,
            "--conventions",
            "tum",
            "--eps",
            "0.05",
            "--phi",
            "5",
            "--csv",
            str(out_csv),
            "--no-progress",
        ]
        assert main(argv) == 0, (kind, capsys.readouterr().err)
        table = pd.read_csv(out_csv)
        _check_table(table)
        ev = evaluate_pairs(ests[0], opts[1], conventions="tum", **kw)
        py = ev.sequences(eps=0.05, phi=5)
        _check_table(py)
        np.testing.assert_allclose(py[METRICS].to_numpy(float), table[METRICS].to_numpy(float), rtol=1e-9)
        if reference is None:
            reference = py[METRICS].to_numpy(float)
        else:  # the same poses in every format: the same numbers (KITTI and bags keep ~1e-12)
            np.testing.assert_allclose(py[METRICS].to_numpy(float), reference, rtol=1e-6)
    assert "conventions: association: nearest stamps within 0.02 s" in capsys.readouterr().err


def test_manifest_sessions_lifelong_and_per_session(tum_pairs, tmp_path, capsys):
    gt, est = tum_pairs["fr2_desk"]
    halves = {1: slice(0, len(gt) // 2), 2: slice(len(gt) // 2, None)}
    d = tmp_path
    for k, s in halves.items():
        g = Trajectory(gt.stamps[s], gt.positions[s], gt.quaternions[s])
        write(d, f"data/s{k}-gt.txt", _tum(g))
        keep = (est.stamps >= g.stamps[0]) & (est.stamps <= g.stamps[-1])
        write(
            d, f"results/orb/s{k}.txt", _tum(Trajectory(est.stamps[keep], est.positions[keep], est.quaternions[keep]))
        )
    manifest = write(
        d,
        "room.toml",
        """
name = "desk room"
scene = "desk-room"
root = "${DESK_ROOT}"
lifelong = true
eps = 0.05
phi = 5
[conventions]
association = "nearest"
align = "se3"
[[session]]
name = "s1"
groundtruth = "s1-gt.txt"
[[session]]
name = "s2"
groundtruth = "s2-gt.txt"
""",
    )
    with pytest.raises(ln.ParseError, match=r"root = '\$\{DESK_ROOT\}': environment variable not set"):
        evaluate_manifest(manifest, d / "results")
    import os

    os.environ["DESK_ROOT"] = str(d / "data")
    try:
        life = evaluate_manifest(manifest, d / "results")
        per = evaluate_manifest(manifest, d / "results", lifelong=False)
        assert [f.mode for f in life.errors] == ["lifelong"] and life.errors[0].aligned_on == 1
        a, b = life.sequences(eps=0.05, phi=5), per.sequences(eps=0.05, phi=5)
        assert list(a["seq"]) == [1, 2] and list(a["algorithm"]) == ["orb", "orb"]
        assert a["ate_rmse"].iloc[0] == pytest.approx(b["ate_rmse"].iloc[0], rel=1e-12)  # session 1: same alignment
        assert a["ate_rmse"].iloc[1] >= b["ate_rmse"].iloc[1] - 1e-12  # session 2 keeps session 1's alignment
        scenes = life.scenes(eps=0.05, phi=5)
        assert scenes["scene"].tolist() == ["desk-room"] and 0 < scenes["cr"].iloc[0] <= 1
        assert main(["evaluate", str(d / "results"), "--manifest", str(manifest), "--eps", "0.05", "--phi", "5",
                     "--csv", str(d / "m.csv"), "--no-progress"]) == 0  # fmt: skip
        pd.testing.assert_frame_equal(pd.read_csv(d / "m.csv")[["seq", "cr", "ate_rmse"]],
                                      a[["seq", "cr", "ate_rmse"]].reset_index(drop=True), check_dtype=False)  # fmt: skip
        # without --eps / --phi the manifest's thresholds are used
        assert main(["evaluate", str(d / "results"), "--manifest", str(manifest), "--csv", str(d / "m2.csv"),
                     "--no-progress"]) == 0  # fmt: skip
        m2 = pd.read_csv(d / "m2.csv")
        assert m2["eps"].tolist() == [0.05, 0.05] and m2["phi"].tolist() == [5.0, 5.0]
        assert m2["cr"].tolist() == pytest.approx(a["cr"].tolist(), abs=0)
    finally:
        del os.environ["DESK_ROOT"]


def test_openloris_is_a_built_in_manifest_with_unchanged_numbers(icra20, capsys):
    src = icra20 / "lifelong" / "maslam"
    direct = ln.evaluate(src).sequences(eps="paper", phi=30)
    via = evaluate_manifest("openloris", src).sequences(eps="paper", phi=30)
    pd.testing.assert_frame_equal(direct, via)
    assert main(["evaluate", str(src), "--manifest", "openloris", "--no-progress"]) == 0


def test_clear_errors_for_bad_pairs_bags_and_manifests(tum_pairs, tmp_path, capsys):
    gt, est = tum_pairs["fr1_xyz"]
    bag = write_bag(tmp_path / "two.bag", Trajectory(gt.stamps[:50], gt.positions[:50], gt.quaternions[:50]), 1)
    with pytest.raises(ln.ParseError, match=r"no pose topic '/odom'; pose topics in this bag: /pose \(PoseStamped\)"):
        ln.read_trajectory(bag, "bag", topic="/odom")
    with pytest.raises(ln.ParseError, match=r"no TF chain from 'map' to 'base'; frames in /tf and /tf_static: none"):
        ln.read_trajectory(bag, "bag", tf="map:base")
    bad = write(tmp_path, "bad.toml", "name = 'x'\ncolour = 'red'\n[[session]]\ngroundtruth = 'a.txt'\n")
    with pytest.raises(ln.ParseError, match=r"bad.toml, line 2: unknown key 'colour'"):
        evaluate_manifest(bad, tmp_path)
    nogt = write(tmp_path, "nogt.toml", "[[session]]\nname = 'a'\ngroundtruth = 'missing.txt'\n")
    with pytest.raises(ln.ParseError, match=r"missing.txt: ground truth of session 'a' not found"):
        evaluate_manifest(nogt, tmp_path)
    with pytest.raises(ln.ValidationError, match=r"align=\s*'?rotate'?: expected one of se3, sim3, posyaw, none"):
        Conventions(align="rotate")
    with pytest.raises(ln.ValidationError, match="align_frames=1 with align='sim3'"):
        Conventions(align="sim3", align_frames=1)
    tum = str(tmp_path / "x.txt")
    assert main(["evaluate", tum, "--gt", tum, "--manifest", "openloris"]) == 2
    assert "--gt and --manifest" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exit_info:
        main(["evaluate", tum, "--gt", tum, "--t-offset", "nan"])
    assert exit_info.value.code == 2
    assert "--t-offset=nan: expected a finite number of seconds" in capsys.readouterr().err
    # an estimate of another sequence: evaluated, nothing matched, and said so
    other, _ = tum_pairs["fr2_desk"]
    fe = session_errors({1: other}, {1: est}, Conventions.preset("tum"), path="est.txt")
    assert fe.sequences[0].matched == 0
    assert any("no estimate stamp" in w and "ground truth" in w for w in fe.warnings)
    assert ln.score(fe, eps=0.1, phi=10)["cr"].iloc[0] == 0


def test_relative_eps_is_a_fraction_of_the_extent(tum_pairs):
    gt, est = tum_pairs["fr1_xyz"]
    fe = session_errors({1: gt}, {1: est}, Conventions.preset("tum"))
    e = fe.sequences[0]
    size = float(np.linalg.norm(e.gt_positions.max(0) - e.gt_positions.min(0)))
    a = ln.score(fe, eps="relative:0.05", phi=10)
    b = ln.score(fe, eps=0.05 * size, phi=10)
    assert a["eps"].iloc[0] == pytest.approx(0.05 * size)
    assert a["cr"].iloc[0] == b["cr"].iloc[0]
    with pytest.raises(ln.ValidationError, match="eps"):
        ln.score(fe, eps="relative:-1")


def test_relative_table_equals_rpg_from_the_command_line_path(data):
    ev = evaluate_pairs(data.tum / "freiburg1_xyz-rgbdslam.txt", data.tum / "freiburg1_xyz-groundtruth.txt",
                        conventions="rpg")  # fmt: skip
    table = ev.relative()  # lengths from the whole ground truth, as rpg's Trajectory class takes them
    for key, (length, samples, trans_perc, deg_per_m) in (
        (k, v) for k, v in REFERENCE["fr1_xyz"].items() if k.startswith("whole_rpg_rel")
    ):
        row = table[table["length"] == length].iloc[0]
        assert row["samples"] == samples, key
        assert row["trans_perc_mean"] == pytest.approx(trans_perc, rel=REL), key  # aligned poses: the same numbers
        assert row["rot_deg_per_m_mean"] == pytest.approx(deg_per_m, rel=REL), key


def test_transform_between_estimate_and_ground_truth_body_frames(tum_pairs):
    from scipy.spatial.transform import Rotation

    from lorisnb.core.alignment.geometry import Sim3

    gt, _ = tum_pairs["fr1_xyz"]
    t_gt_est = Sim3(Rotation.from_euler("zyx", [30, -10, 5], degrees=True).as_matrix(), np.array([0.1, -0.05, 0.2]))
    # the estimate tracks a camera mounted at T_gt_est on the ground-truth body: pose_est = pose_gt @ T_gt_est
    r = gt.rotations() * Rotation.from_matrix(t_gt_est.rotation)
    est = Trajectory.from_rotations(gt.stamps, gt.positions + gt.rotations().apply(t_gt_est.translation), r)
    inverse = Sim3(t_gt_est.rotation.T, -t_gt_est.rotation.T @ t_gt_est.translation)
    conv = Conventions(association="nearest", align="none")
    wrong = session_errors({1: gt}, {1: est}, conv).sequences[0]
    right = session_errors({1: gt}, {1: est}, conv, transform=inverse).sequences[0]
    assert rmse(wrong.ate) > 0.05 and rmse(wrong.aoe) > 10
    assert rmse(right.ate) < 1e-9 and rmse(right.aoe) < 1e-6


def test_session_formats_and_pair_only_options(tum_pairs, tmp_path, icra20, capsys):
    gt, est = tum_pairs["fr1_xyz"]
    n = len(gt) // 2
    g1 = Trajectory(gt.stamps[:n], gt.positions[:n], gt.quaternions[:n])
    g2 = Trajectory(gt.stamps[n:], gt.positions[n:], gt.quaternions[n:])
    write(tmp_path, "data/a.txt", _tum(g1))
    _euroc(tmp_path / "data" / "b.csv", g2)
    for name, g in (("a", g1), ("b", g2)):
        keep = (est.stamps >= g.stamps[0]) & (est.stamps <= g.stamps[-1])
        write(
            tmp_path,
            f"res/slam/{name}.txt",
            _tum(Trajectory(est.stamps[keep], est.positions[keep], est.quaternions[keep])),
        )
    m = write(tmp_path, "two.toml", "root = 'data'\nlifelong = true\n[[session]]\nname = 'a'\ngroundtruth = 'a.txt'\n"
                                    "[[session]]\nname = 'b'\ngroundtruth = 'b.csv'\ngroundtruth_format = 'euroc'\n")  # fmt: skip
    ev = evaluate_manifest(m, tmp_path / "res")
    table = ev.sequences(eps=0.05, phi=5)
    assert table["matched"].tolist()[1] > 100 and table["cr"].gt(0).all()
    # one spec: an alignment choice takes effect on OpenLORIS result files too; reading options of
    # pairs are refused there, not silently ignored
    src = str(icra20 / "lifelong" / "maslam")
    assert main(["evaluate", src, "--align", "posyaw", "--no-progress", "--csv", str(tmp_path / "yaw.csv")]) == 0
    assert main(["evaluate", src, "--no-progress", "--csv", str(tmp_path / "se3.csv")]) == 0
    yaw, se3 = pd.read_csv(tmp_path / "yaw.csv"), pd.read_csv(tmp_path / "se3.csv")
    assert (yaw["ate_rmse"] - se3["ate_rmse"]).abs().max() > 1e-3 and '"align":"posyaw"' in yaw["spec"].iloc[0]
    capsys.readouterr()
    assert main(["evaluate", src, "--format", "kitti", "--no-progress"]) == 2
    assert "--format: for estimates scored against --gt" in capsys.readouterr().err
    assert (
        main(["evaluate", str(icra20 / "per-seq" / "odom" / "cafe-1-1-odom.txt"), "--max-gap", "0.2", "--no-progress"])
        == 0
    )


def test_openloris_manifest_takes_lifelong_and_refuses_conventions(icra20):
    src = icra20 / "lifelong" / "maslam"
    per = evaluate_manifest("openloris", src, lifelong=False)
    assert {f.mode for f in per.errors} == {"per-seq"}
    with pytest.raises(ln.ValidationError, match="official conventions"):
        evaluate_manifest("openloris", src, conventions="tum")


@pytest.mark.parametrize(("rows", "says"), [(0, "no pose"), (1, "one pose")])
def test_a_ground_truth_of_fewer_than_two_poses_fails_the_pair_cleanly(tum_pairs, tmp_path, capsys, rows, says):
    """A ground truth of only comments crashed every table (a traceback from the scene lookup);
    one of a single pose was taken for a clock offset. Both fail the pair with what is wrong, the
    same from Python and the command line, and the scene table stays the pair's own (the data
    root's ``cafe`` is not looked up for a pair labelled cafe)."""
    gt, est = tum_pairs["fr1_xyz"]
    lines = "".join(
        f"{t:.4f} {p[0]} {p[1]} {p[2]} 0 0 0 1\n" for t, p in zip(gt.stamps[:rows], gt.positions[:rows], strict=True)
    )
    bad = write(tmp_path, "gt_bad.txt", "# ground truth\n" + lines)
    good = write(tmp_path, "est.txt", "".join(f"{t:.4f} 1 2 3 0 0 0 1\n" for t in est.stamps[:50]))
    ev = evaluate_pairs([good], bad, scene="cafe", progress=False)
    assert [f.error for f in ev.failures] == [
        f"{good}: {bad}: the ground truth has {says} (comments, blank lines and skipped poses aside); expected at least two "
        "poses spanning the estimate's time"
    ]
    assert ev.spans() == {} and ev.scenes().empty
    assert main(["evaluate", str(good), "--gt", str(bad), "--scene", "cafe", "--no-progress"]) == 1
    err = capsys.readouterr().err
    assert f"the ground truth has {says}" in err and "Traceback" not in err and "clock offset" not in err


def test_a_folder_as_a_text_ground_truth_is_refused_before_any_estimate(tum_pairs, tmp_path, capsys):
    """``--gt FOLDER`` failed each estimate in turn (exit 1, the failure recorded against the
    estimate) while a missing ground truth was refused at once (exit 2): both are refused at once."""
    _, est = tum_pairs["fr1_xyz"]
    good = write(tmp_path, "est.txt", "".join(f"{t:.4f} 1 2 3 0 0 0 1\n" for t in est.stamps[:50]))
    folder = tmp_path / "gt_folder"
    folder.mkdir()
    with pytest.raises(
        ln.ParseError, match=r"gt_folder: is a folder; expected the ground truth as a TUM trajectory file"
    ):
        evaluate_pairs([good], folder, progress=False)
    assert main(["evaluate", str(good), "--gt", str(folder), "--no-progress"]) == 2
    assert "is a folder; expected the ground truth as a TUM trajectory file" in capsys.readouterr().err
