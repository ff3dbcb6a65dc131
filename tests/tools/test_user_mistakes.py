"""Ordinary mistakes of a Python user in a notebook: each gets a message saying what to do, never
a silently empty or plausible table."""

from __future__ import annotations

import warnings

import pytest

import lorisnb as ln
from lorisnb.errors import FailedInputsWarning


@pytest.mark.parametrize(
    ("scene", "said"),
    [
        ("Home", "scene names are lower case: 'home'"),
        ("kitchen", "expected an OpenLORIS scene: office, corridor, home, cafe, market"),
        ("office", "office ground truth (motion capture) is not public"),
    ],
)
def test_a_scene_without_ground_truth_says_why_and_what_the_root_has(data, scene, said):
    with pytest.raises(ln.DataNotFoundError) as exc:
        ln.load_groundtruth(scene, data_root=data)
    have = ", ".join(data.scenes_with_groundtruth())
    assert said in str(exc.value)
    assert f"has the ground truth of {have}" in str(exc.value)


def test_a_scene_that_is_not_a_name_is_refused(data):
    with pytest.raises(ln.ValidationError, match="scene=3: expected an OpenLORIS scene name"):
        ln.load_groundtruth(3, data_root=data)  # type: ignore[arg-type]


def test_a_misspelt_results_folder_warns_at_the_call_not_only_in_the_repr(data, icra20):
    typo = icra20 / "per-seq" / "orb_slam2"  # the folder is orbslam2_rgbd
    with pytest.warns(FailedInputsWarning, match=r"1 of 1 inputs could not be evaluated.*orb_slam2: file not found"):
        ev = ln.evaluate(typo, data_root=data)
    assert ev.sequences().empty and ev.exit_status() == 1 and len(ev.failures) == 1


def test_a_pair_read_in_the_wrong_format_warns(data):
    est, gt = data.tum / "fr2_desk_ORB.txt", data.tum / "fr2_desk_groundtruth.txt"
    with pytest.warns(FailedInputsWarning, match=r"1 of 1 inputs.*looks like a TUM trajectory file"):
        ev = ln.evaluate_pairs(est, gt, fmt="kitti")
    assert ev.exit_status() == 1


def test_good_and_bad_inputs_name_the_count_and_the_good_ones_are_scored(data, icra20, tmp_path):
    bad = tmp_path / "broken.txt"
    bad.write_text("scene: cafe\nframe: base_link\nseq: 1\n1 2 3\n")
    good = icra20 / "per-seq" / "orbslam2_rgbd"
    with pytest.warns(
        FailedInputsWarning, match=rf"1 of {len(list(good.glob('*.txt'))) + 1} inputs.*broken.txt, line 4"
    ):
        ev = ln.evaluate([good, bad], data_root=data)
    scored = ev.sequences(eps="paper", phi=30)
    assert len(scored) > 0 and scored["cr"].between(0, 1).all()


def test_an_evaluation_without_failures_issues_no_such_warning(data):
    est, gt = data.tum / "fr2_desk_ORB.txt", data.tum / "fr2_desk_groundtruth.txt"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ev = ln.evaluate_pairs(est, gt)
    assert ev.exit_status() == 0
    assert not [w for w in caught if issubclass(w.category, FailedInputsWarning)]


@pytest.fixture(scope="module")
def orbslam2(data, icra20):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ln.evaluate(icra20 / "per-seq" / "orbslam2_rgbd", data_root=data, scenes=["cafe"])


@pytest.mark.parametrize(
    ("kw", "said"),
    [
        (dict(eps=1, phi=-1), "phi=-1: expected a number of degrees >= 0"),
        (dict(eps=1, phi=float("nan")), "phi=nan: expected a number of degrees, not NaN"),
        (dict(eps=-2, phi=30), "eps=-2: expected 'paper', 'relative:F', a number of metres >= 0"),
        (dict(eps="paper", phi=400), "phi=400: expected at most 180 degrees"),
    ],
)
def test_figures_validate_their_thresholds_as_the_tables_do(orbslam2, kw, said):
    from lorisnb.core.lifelong.timeline import timeline_table
    from lorisnb.tools.figures.plotting import plot_timeline, plot_trajectories

    with pytest.raises(ln.ValidationError) as table_error:
        orbslam2.sequences(**kw)
    assert said in str(table_error.value)
    for draw in (
        lambda: plot_trajectories(orbslam2.errors[0], **kw),
        lambda: timeline_table(orbslam2.errors, **kw),
        lambda: plot_timeline(orbslam2.errors, orbslam2.durations(), orbslam2.scenes(), **kw),
    ):
        with pytest.raises(ln.ValidationError) as exc:
            draw()
        assert str(exc.value) == str(table_error.value)


def test_a_zero_validity_window_is_refused_by_the_timeline_as_by_score(orbslam2):
    from lorisnb.core.lifelong.timeline import timeline_table

    with pytest.raises(ln.ValidationError, match="delta=0: expected a number of seconds > 0"):
        timeline_table(orbslam2.errors, eps=1, phi=30, delta=0)
    segments, firsts = timeline_table(orbslam2.errors, eps="1", phi="30", delta="1")  # number strings, as score takes
    paper = orbslam2.sequences(eps=1, phi=30, delta=1)
    assert len(firsts) == int((paper["matched"] > 0).sum())


def test_an_eps_mapping_without_a_scene_of_the_inputs_says_which(data, icra20):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ev = ln.evaluate(icra20 / "per-seq" / "orbslam2_rgbd", data_root=data, scenes=["cafe", "home"])
    with pytest.raises(ln.ValidationError, match="gives no threshold for scene 'home'"):
        ev.scenes(eps={"cafe": 2})
    both = ev.scenes(eps={"cafe": 2, "home": 3}).set_index("scene")
    assert both.loc["cafe", "eps"] == 2 and both.loc["home", "eps"] == 3
    assert both.loc["home", "cr"] == ev.scenes(eps=3).set_index("scene").loc["home", "cr"]


def test_the_timeline_draws_each_trial_on_its_own_row_with_its_own_numbers(tmp_path, icra20):
    """Two trials of one algorithm (the lifelong notebook's and evaluate_my_results' plot_timeline):
    one row named ``vins`` with both trials' segments and both CRs printed over each other."""
    import shutil

    from lorisnb.tools.figures.plotting import plot_timeline

    (tmp_path / "vins").mkdir()
    lifelong = icra20 / "lifelong"
    shutil.copy(lifelong / "vins_mono_color_imu_with_loop" / "cafe-1.txt", tmp_path / "vins" / "cafe_trial1.txt")
    shutil.copy(lifelong / "vins_mono_fisheye_imu_with_loop" / "cafe-1.txt", tmp_path / "vins" / "cafe_trial2.txt")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ev = ln.evaluate(tmp_path, progress=False)
    table = ev.scenes(eps="paper", phi=30)
    fig = plot_timeline(ev.errors, ev.durations(), table, "paper", 30)
    ax = fig.axes[0]
    rows = {t.get_text(): y for t, y in zip(ax.get_yticklabels(), ax.get_yticks(), strict=True)}
    assert sorted(rows) == ["vins trial 1", "vins trial 2"]
    cr_texts = {round(t.get_position()[1] - 0.12, 6): t.get_text() for t in ax.texts if t.get_text().endswith("%")}
    rmse_texts = [t.get_text() for t in ax.texts if t.get_text().endswith(" m")]
    for r in table.to_dict("records"):
        y = rows[f"vins trial {r['trial']}"]
        assert cr_texts[round(y, 6)] == f"{100 * r['cr']:.1f}%"
        assert f"{r['c_ate_rmse']:.3f} m" in rmse_texts
    segments = [c for c in ax.collections if len(c.get_segments())]
    heights = {round(s[0][1], 6) for c in segments for s in c.get_segments()}
    assert heights == {round(y, 6) for y in rows.values()}  # each trial's segments on its row


def test_a_dangling_link_in_a_results_folder_fails_saying_so(tmp_path, data, icra20, capsys):
    """A results folder holding a link to a file that is gone (a moved run): the link was left out
    of the walk (Path.is_file is False), its sequence shown as 'no output', exit status 0."""
    from lorisnb.cli import main

    (tmp_path / "orb").mkdir()
    good = icra20 / "per-seq" / "orbslam2_rgbd" / "cafe_1_1_orbslam2-original.txt"
    (tmp_path / "orb" / good.name).symlink_to(good)
    (tmp_path / "orb" / "cafe_1_2.txt").symlink_to(tmp_path / "moved" / "cafe_1_2.txt")
    with pytest.warns(FailedInputsWarning, match=r"1 of 2 inputs.*cafe_1_2.txt: a link to .*moved.*does not exist"):
        ev = ln.evaluate(tmp_path, data_root=data)
    assert len(ev.errors) == 1 and ev.exit_status() == 1
    assert main(["evaluate", str(tmp_path), "--data", str(data.root), "--no-progress"]) == 1
    assert "cafe_1_2.txt: a link to" in capsys.readouterr().err


def test_a_file_without_its_scenes_ground_truth_is_listed_once(tmp_path, icra20):
    """A data root without gt_cafe_1.txt: the cafe file is not scored (exit 1), and the failures
    table and the repr listed it twice, as skipped and as not scored."""
    import shutil

    root = tmp_path / "data"
    shutil.copytree(icra20.parents[1] / "openloris-scene" / "groundtruth", root / "openloris-scene" / "groundtruth")
    (root / "openloris-scene" / "groundtruth" / "gt_cafe_1.txt").unlink()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ev = ln.evaluate(icra20 / "per-seq" / "orbslam2_rgbd", data_root=root, scenes=["cafe", "home"])
    table = ev.failures_table()
    cafe = table[table["file"].str.contains("cafe_")]
    assert len(cafe) == 2 and set(cafe["status"]) == {"not scored"}  # cafe-1-1 and cafe-1-2, once each
    assert table["file"].is_unique and ev.exit_status() == 1
    assert "2 unscored" in repr(ev) and "skipped" not in repr(ev)


def test_a_conflicting_scale_is_told_in_the_command_lines_words(data, capsys):
    from lorisnb.cli import main

    est, gt = data.tum / "fr2_desk_ORB.txt", data.tum / "fr2_desk_groundtruth.txt"
    argv = ["evaluate", str(est), "--gt", str(gt), "--scale", "off", "--align", "sim3", "--no-progress"]
    assert main(argv) == 2
    assert "--scale off and --align sim3: give one" in capsys.readouterr().err


def test_a_zero_d_array_is_one_threshold_on_every_grid_path(tmp_path, data):
    import numpy as np

    from lorisnb.core.spec.validate import threshold_list
    from lorisnb.tools.evaluation.streaming import sweep_to_parquet

    assert threshold_list("eps", np.array(0.3)) == [0.3] and threshold_list("phi", np.float64(30)) == [30.0]
    est, gt = data.tum / "fr2_desk_ORB.txt", data.tum / "fr2_desk_groundtruth.txt"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ev = ln.evaluate_pairs(est, gt)
    pytest.importorskip("pyarrow")
    out, n = sweep_to_parquet(ev.errors, tmp_path / "sweep", eps=np.array(0.05), phi=np.array([10.0, 30.0]))
    import pandas as pd

    table = pd.read_parquet(out)
    direct = ln.sweep(ev.errors, eps=[0.05], phi=[10.0, 30.0])
    assert n == len(table) == len(direct) == 2
    assert sorted(table["cr"]) == sorted(direct["cr"])


def test_evos_align_frames_minus_one_and_a_one_pose_scale_are_refused_up_front(data, capsys, tmp_path):
    """evo's --n_to_align -1 means every pose: the message says to leave the option out. A scale
    fitted on one pose was refused up front for sim3 only; for align scale each file failed."""
    from lorisnb.cli import main

    est, gt = data.tum / "fr2_desk_ORB.txt", data.tum / "fr2_desk_groundtruth.txt"
    for surface in (lambda: ln.make_spec("evo", align_frames=-1), lambda: ln.evaluate_pairs(est, gt, align_frames=-1)):
        with pytest.raises(ln.ValidationError, match=r"align_frames=-1: .*leave it out to fit on all matched poses"):
            surface()
    base = ["evaluate", str(est), "--gt", str(gt), "--no-progress"]
    with pytest.raises(SystemExit) as stop:  # argparse's usage error
        main([*base, "--align-frames", "-1"])
    assert stop.value.code == 2 and "leave it out to fit on all matched poses: evo's -1" in capsys.readouterr().err
    assert main([*base, "--align", "scale", "--align-frames", "1"]) == 2  # usage, before any file: not 1
    err = capsys.readouterr().err
    assert "--align-frames 1 with --align scale: a scale needs 2 poses" in err and "evaluated" not in err
    with pytest.raises(ln.ValidationError, match="align_frames 1 with align scale: a scale needs 2 poses"):
        ln.EvalSpec.preset("evo", align="scale", align_frames=1)
