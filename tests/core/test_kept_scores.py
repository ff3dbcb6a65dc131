"""What a sequence's errors keep once computed (its RPE pairs, its rotation lever, its scores at a
setting): the same numbers as computed afresh, never carried into a changed copy, and the scores
at the spec's setting computed where the errors were (an evaluation's workers)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.core.lifelong import scoring
from lorisnb.core.lifelong.scoring import KEPT_SETTINGS, score, score_rows
from lorisnb.core.metrics.relative import RPG_FRACTIONS
from lorisnb.core.pipeline.model import STAT_COLUMNS


def _fresh(errors):
    """Copies of the errors that keep nothing (``replace`` with no change)."""
    return [replace(f, sequences=[replace(e) for e in f.sequences]) for f in errors]


@pytest.fixture(scope="module")
def home(icra20):
    """Scored without the statistics with the errors (as ``lorisnb evaluate`` prints its table)."""
    return ln.evaluate(icra20 / "lifelong", algorithms=["maslam", "orbslam2_t265"], scenes=["home"], progress=False,
                       statistics=False)  # fmt: skip


@pytest.fixture(scope="module")
def home_all(icra20):
    """Scored with every column with the errors (the default: a table of every column is read)."""
    return ln.evaluate(icra20 / "lifelong", algorithms=["maslam", "orbslam2_t265"], scenes=["home"], progress=False)


def test_a_changed_copy_keeps_none_of_the_old_errors_results(home):
    """``dataclasses.replace`` of a sequence's errors: its RPE, lever and scores are those of the
    new values (they were the old errors' RPE and lever: one dict shared by both)."""
    e = next(e for f in home.errors for e in f.sequences if e.matched > 100)
    _, _, trans, _ = e.rpe()
    lever = e.rotation_lever
    assert trans.max() > 0.01 and lever > 0.1
    same = replace(e, est_positions=e.gt_positions.copy(), est_quaternions=e.gt_quaternions.copy(),
                   ate=np.zeros(e.matched), aoe=np.zeros(e.matched), gt_positions=2 * e.gt_positions)  # fmt: skip
    _, _, trans2, rot2 = same.rpe()
    assert np.abs(trans2 - trans).max() > 0.01  # the RPE of the new positions, not the kept one
    assert same.rotation_lever == pytest.approx(2 * lever, rel=1e-12)
    f = next(f for f in home.errors if e in f.sequences)
    row = score([replace(f, sequences=[same])]).iloc[0]
    assert row["ate_rmse"] == 0 and row["rpe_rot_rmse"] == pytest.approx(0, abs=1e-6)
    assert score([f]).set_index("seq").loc[e.seq, "ate_rmse"] > 0.01  # the original keeps its own


def test_tables_at_the_spec_setting_are_those_scored_afresh_and_were_scored_with_the_errors(home, monkeypatch):
    """The evaluation scored the spec's setting without the statistics where it computed the
    errors: that table (``lorisnb evaluate``'s printout) is read, and the one with every column
    adds only the statistics; both equal the scores of copies that keep nothing, to the last bit,
    columns in the same order."""
    spec = home.spec
    setting = (spec.eps, spec.phi, spec.delta, spec.tau)
    afresh_lean = score_rows(_fresh(home.errors), *setting, stats=False)
    afresh = score(_fresh(home.errors), *setting)
    afresh_rows = score_rows(_fresh(home.errors), *setting)

    def no_scoring(*args, **kwargs):
        raise AssertionError("scored again")

    monkeypatch.setattr(scoring, "sequence_grid", no_scoring)
    lean = score_rows(home.errors, *setting, stats=False)
    assert [list(r) for r in lean] == [list(r) for r in afresh_lean] and not set(STAT_COLUMNS) & set(lean[0])
    assert pd.DataFrame(lean).equals(pd.DataFrame(afresh_lean))
    table = home.sequences()  # the statistics computed alone, the rest read
    pd.testing.assert_frame_equal(table.drop(columns="spec"), afresh, check_exact=True)
    assert [list(r) for r in score_rows(home.errors, *setting)] == [list(r) for r in afresh_rows]
    with pytest.raises(AssertionError, match="scored again"):  # another setting is scored
        home.sequences(eps=0.123)


def test_scores_without_statistics_are_read_from_those_with_them(home, monkeypatch):
    """Scores with every column kept (a table computed first): those without the statistics are
    read from them, the same values and columns in the same order as scored afresh."""
    setting = (0.4, 15.0, 1.0, 60.0)
    fresh = _fresh(home.errors)
    afresh = score(_fresh(home.errors), *setting, stats=False)
    score(fresh, *setting)  # every column, kept
    monkeypatch.setattr(scoring, "sequence_grid", lambda *a, **k: pytest.fail("scored again"))
    pd.testing.assert_frame_equal(score(fresh, *setting, stats=False), afresh, check_exact=True)


def test_a_sequence_keeps_the_latest_settings_only_and_each_is_the_fresh_score(home):
    f = _fresh(home.errors)[0]
    first = score([f], 0.3, 10.0)
    for eps in np.linspace(0.05, 1.0, 3 * KEPT_SETTINGS):
        score([f], float(eps), 10.0)
    assert all(len(e._scores) <= KEPT_SETTINGS for e in f.sequences)
    pd.testing.assert_frame_equal(score([f], 0.3, 10.0), first, check_exact=True)
    pd.testing.assert_frame_equal(score(_fresh([f]), 0.3, 10.0), first, check_exact=True)


def test_statistics_scored_with_the_errors_are_read_by_every_table(home_all, monkeypatch):
    """``evaluate``'s default (``statistics=True``): the workers scored every column at the spec's
    setting, so neither table computes anything (``score`` patched to fail in this process), and
    both equal the scores of copies that keep nothing, to the last bit."""
    spec = home_all.spec
    setting = (spec.eps, spec.phi, spec.delta, spec.tau)
    afresh = score(_fresh(home_all.errors), *setting)
    afresh_lean = score(_fresh(home_all.errors), *setting, stats=False)
    monkeypatch.setattr(scoring, "sequence_grid", lambda *a, **k: pytest.fail("scored again"))
    monkeypatch.setattr(scoring, "_statistics", lambda *a, **k: pytest.fail("statistics computed again"))
    pd.testing.assert_frame_equal(home_all.sequences().drop(columns="spec"), afresh, check_exact=True)
    pd.testing.assert_frame_equal(score(home_all.errors, *setting, stats=False), afresh_lean, check_exact=True)


@pytest.mark.parametrize("value", ["no", 1, None])
def test_statistics_is_a_yes_no_value(icra20, value):
    """``statistics`` is checked as every yes/no option is: a string or number is refused, naming it."""
    with pytest.raises(ln.ValidationError, match="statistics"):
        ln.evaluate(icra20 / "lifelong" / "maslam" / "home.txt", statistics=value)


@pytest.fixture(scope="module")
def home_scores(icra20):
    """Only the scores at the spec's setting sent back, each pose's errors let go (``lorisnb evaluate``)."""
    return ln.evaluate(icra20 / "lifelong", algorithms=["maslam", "orbslam2_t265"], scenes=["home"], progress=False,
                       keep_poses=False, jobs=2)  # fmt: skip


def test_tables_without_the_poses_are_those_with_them(home_scores, home_all):
    """``keep_poses=False``: the tables at the spec's setting (every column, and the rows without
    the statistics) equal those of an evaluation that kept each pose's errors, to the last bit;
    the per-scene table too; the sequences kept no per-pose array (a twentieth of the bytes here)."""
    import pickle

    pd.testing.assert_frame_equal(home_scores.sequences(), home_all.sequences(), check_exact=True)
    lean, lean_all = home_scores.sequence_rows(stats=False), home_all.sequence_rows(stats=False)
    assert [list(r) for r in lean] == [list(r) for r in lean_all] and pd.DataFrame(lean).equals(pd.DataFrame(lean_all))
    pd.testing.assert_frame_equal(home_scores.scenes(), home_all.scenes(), check_exact=True)
    assert [e.matched for f in home_scores.errors for e in f.sequences] == [
        e.matched for f in home_all.errors for e in f.sequences
    ]
    kept = sum(len(pickle.dumps(f)) for f in home_scores.errors)
    whole = sum(len(pickle.dumps(f)) for f in home_all.errors)
    assert kept < whole / 20
    assert home_scores.exit_status() == home_all.exit_status() == 0


def test_without_the_poses_anything_else_says_how_to_keep_them(home_scores):
    """Another setting, a sweep, the poses or a sequence's arrays: an EvaluationError naming
    ``keep_poses``, never a number computed from nothing."""
    e = home_scores.errors[0].sequences[0]
    for attempt in (
        lambda: home_scores.sequences(eps=0.5),
        lambda: home_scores.poses(),
        lambda: ln.sweep(home_scores.errors, eps=[1, 2], phi=[10]),
        lambda: e.ate,
        lambda: e.rpe(2.0),
    ):
        with pytest.raises(ln.EvaluationError, match="keep_poses=True"):
            attempt()
    assert "let go" in repr(e) and "keep_poses=False" in repr(home_scores)


def test_keep_poses_is_checked_and_refused_where_a_table_needs_the_poses(icra20, data):
    """``keep_poses`` is a yes/no value; False is refused for specs whose table is computed from the
    poses after the files are evaluated (KITTI's, TartanAir's, evo's relation statistics)."""
    one = icra20 / "lifelong" / "maslam" / "home.txt"
    with pytest.raises(ln.ValidationError, match="keep_poses"):
        ln.evaluate(one, keep_poses="no")
    est, gt = data.root / "tum-rgbd" / "fr2_desk_ORB.txt", data.root / "tum-rgbd" / "fr2_desk_groundtruth.txt"
    for spec, options in (("kitti", {}), ("tartanair", {}), ("evo", {"relation": "angle_deg"})):
        with pytest.raises(ln.ValidationError, match=r"keep_poses=False: .* keep them \(keep_poses=True\)"):
            ln.evaluate_pairs(est, gt, spec, keep_poses=False, **options)
    assert len(ln.evaluate_pairs(est, gt, "tum", keep_poses=False).sequences()) == 1


def test_without_statistics_and_poses_the_tables_read_and_the_statistics_refused(icra20):
    """``statistics=False, keep_poses=False``: the rows without the statistics (the command line's
    printed table) are read, and so are ``sequences()`` (without the statistics columns: it raised
    an error saying the table at that setting could be read) and ``scenes()`` (which reads no
    statistics); the statistics (``stats=True``) and another setting need the poses and say so."""
    ev = ln.evaluate(icra20 / "lifelong" / "maslam" / "home.txt", statistics=False, keep_poses=False)
    ref = ln.evaluate(icra20 / "lifelong" / "maslam" / "home.txt", statistics=False)
    assert pd.DataFrame(ev.sequence_rows(stats=False)).equals(pd.DataFrame(ref.sequence_rows(stats=False)))
    full = ref.sequences()
    lean = ev.sequences()
    assert [c for c in full.columns if c not in lean.columns] == STAT_COLUMNS
    pd.testing.assert_frame_equal(lean, full[lean.columns])
    pd.testing.assert_frame_equal(ev.scenes(), ref.scenes())
    with pytest.raises(ln.EvaluationError, match=r"statistics columns \(stats=True\) need each pose's errors"):
        ev.sequences(stats=True)
    with pytest.raises(ln.EvaluationError, match="keep_poses=True"):
        ev.sequences(eps=0.123)
    with pytest.raises(ln.EvaluationError, match="keep_poses=True"):
        ev.scenes(eps=0.123)


def test_relative_refuses_fractions_and_lengths_together(data):
    """Both given, the lengths were used and the fractions ignored without a word."""
    ev = ln.evaluate_pairs(data.tum / "fr2_desk_ORB.txt", data.tum / "fr2_desk_groundtruth.txt", "rpg")
    with pytest.raises(ln.ValidationError, match="fractions and lengths both given"):
        ev.relative(fractions=(0.1, 0.2), lengths=[1])
    assert ev.relative().equals(ev.relative(fractions=RPG_FRACTIONS))
    assert len(ev.relative(lengths=[1])) > 0
