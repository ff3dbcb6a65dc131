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
    from lorisnb.core.timeline import timeline_table
    from lorisnb.tools.plotting import plot_timeline, plot_trajectories

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
    from lorisnb.core.timeline import timeline_table

    with pytest.raises(ln.ValidationError, match="delta=0: expected a number of seconds > 0"):
        timeline_table(orbslam2.errors, eps=1, phi=30, delta=0)
    segments, firsts = timeline_table(orbslam2.errors, eps="1", phi="30", delta="1")  # number strings, as score takes
    paper = orbslam2.sequences(eps=1, phi=30, delta=1)
    assert len(firsts) == int((paper["matched"] > 0).sum())
