"""evo parity probes on the bundled TUM pair (fr1_xyz, RGBD-SLAM), with evo's own Python API (evo
1.38: readers, sync, ``main_ape.ape``, ``main_rpe.rpe``, ``save_res_file``) on the same inputs:
``crosscheck --conventions`` runs evo with the alignment lorisnb used (``auto`` resolved) and says
where a preset is not evo's; evo result zips written with ``--change_unit`` or at several RPE deltas
become rows in metres and degrees, none overwritten; evo's time window and scale-only alignment say
what went wrong."""

from __future__ import annotations

import copy
import shutil

import pandas as pd
import pytest
from evo.core import metrics as em
from evo.core import sync
from evo.main_ape import ape
from evo.main_rpe import rpe
from evo.tools import file_interface as fi

from lorisnb.cli import main
from lorisnb.core.spec.evalspec import make_spec
from lorisnb.errors import EvaluationError, ValidationError
from lorisnb.tools.peers.crosscheck_evo import crosscheck_evo
from lorisnb.tools.peers.evo_import import evo_results_table

GT, EST = "freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"


def _evo_synced(data, max_diff=0.01):
    ref = fi.read_tum_trajectory_file(data.tum / GT)
    est = fi.read_tum_trajectory_file(data.tum / EST)
    return sync.associate_trajectories(ref, est, max_diff=max_diff)


def _evo_ate(data, max_diff=0.01, **align) -> dict[str, float]:
    ref, est = _evo_synced(data, max_diff)
    return ape(ref, est, em.PoseRelation.translation_part, **align).stats


def _stats(table: pd.DataFrame) -> pd.DataFrame:
    return table[~table["quantity"].str.contains(":")].set_index("quantity")


@pytest.mark.parametrize(("name", "align"), [("dso", dict(align=True, correct_scale=True)),
                                             ("orb_run", dict(align=True))])  # fmt: skip
@pytest.mark.thorough
def test_align_auto_runs_evo_with_the_alignment_lorisnb_chose(data, tmp_path, name, align):
    """``--align auto`` is Sim(3) for a monocular algorithm (named dso or svo), else SE(3): evo's column was
    evo without any alignment (14 of 30 statistics 'disagreed', exit status 1)."""
    est = tmp_path / f"{name}.txt"
    shutil.copy(data.tum / EST, est)
    stats = _stats(crosscheck_evo(data.tum / GT, est, make_spec("evo", align="auto")))
    assert stats["agrees"].all(), stats[~stats["agrees"]]
    theirs = _evo_ate(data, **align)
    assert stats.loc["ate_rmse", "evo"] == pytest.approx(theirs["rmse"], rel=1e-12)
    assert stats.loc["ate_max", "lorisnb"] == pytest.approx(theirs["max"], rel=1e-9)
    assert stats.loc["ate_rmse", "alignment"] == ("sim3 (auto)" if "scale" in str(align) else "se3 (auto)")
    assert main(["crosscheck", str(data.tum / GT), str(est), "--conventions", "evo", "--align", "auto"]) == 0


@pytest.mark.thorough
def test_a_preset_that_is_not_evos_says_where_the_definitions_differ(data, capsys):
    """``crosscheck --conventions vio``: evo has no posyaw; its column is its SE(3) alignment (it was
    evo unaligned, 0.0201 m against lorisnb's 0.0140 m, with nothing said), and every row says what
    differs (posyaw), and where the pairs are the same on both sides (fr1/xyz: TUM's greedy
    association and evo's sync pair the same 786 poses) it says so rather than excusing the rows."""
    g, e = str(data.tum / GT), str(data.tum / EST)
    assert main(["crosscheck", g, e, "--conventions", "vio"]) == 0  # every difference explained (issue 48)
    captured = capsys.readouterr()
    assert "explained by a stated definition" in captured.err and "DISAGREE" not in captured.err
    stats = _stats(crosscheck_evo(g, e, "vio"))
    note = stats.loc["ate_rmse", "note"]
    assert note.startswith("definitions differ") and "posyaw" in note and "repeated" not in note
    # TUM's greedy association and evo's sync pair the same poses here: said so, not excused as a difference
    same = "identical pairs (association nearest and evo's nearest-stamp sync pair the same 786 poses)"
    assert same in note and "greedy" not in note
    tum = _stats(crosscheck_evo(g, e, "tum")).loc["ate_rmse", "note"]
    assert same in tum and "repeated" not in tum
    assert stats.loc["ate_rmse", "evo"] == pytest.approx(_evo_ate(data, 0.02, align=True)["rmse"], rel=1e-12)
    assert stats.loc["ate_rmse", "lorisnb"] == pytest.approx(0.014046763, rel=1e-6)  # posyaw, lorisnb's own
    evo = _stats(crosscheck_evo(g, e, "evo"))  # evo's own preset: nothing differs
    assert not evo["note"].str.startswith("definitions differ").any() and evo["agrees"].all()


def test_no_match_says_lorisnbs_reason_not_evos(data, tmp_path):
    """An estimate 1000 s off the ground truth: lorisnb's reason (no stamp inside the span, a clock
    offset?), not evo's SyncException with advice about NaN poses."""
    lines = [ln.split() for ln in (data.tum / EST).read_text().splitlines() if not ln.startswith("#")]
    shifted = tmp_path / "shifted.txt"
    shifted.write_text("".join(f"{float(x[0]) + 1000:.6f} {' '.join(x[1:])}\n" for x in lines[:50]))
    with pytest.raises(EvaluationError, match="no estimate stamp falls inside") as info:
        crosscheck_evo(data.tum / GT, shifted)
    assert "NaN" not in str(info.value) and "clock offset" in str(info.value)


def _save(result, path, ref="groundtruth.txt", est="rgbdslam.txt"):
    result.info["ref_name"], result.info["est_name"] = ref, est
    fi.save_res_file(path, result)


def test_evo_zips_with_change_unit_are_read_in_metres_and_degrees(data, tmp_path):
    """``evo_ape --change_unit mm`` and ``-r angle_deg --change_unit rad``: the rows held the
    millimetres as metres (13.47 'm') and the radians as degrees."""
    ref, est = _evo_synced(data)
    c = copy.deepcopy
    mm = ape(c(ref), c(est), em.PoseRelation.translation_part, align=True, change_unit=em.Unit.millimeters)
    rad = ape(c(ref), c(est), em.PoseRelation.rotation_angle_deg, align=True, change_unit=em.Unit.radians)
    rpe_cm = rpe(c(ref), c(est), em.PoseRelation.translation_part, delta=1, delta_unit=em.Unit.frames, align=True,
                 change_unit=em.Unit.centimeters)  # fmt: skip
    metres = ape(c(ref), c(est), em.PoseRelation.translation_part, align=True).stats
    degrees = ape(c(ref), c(est), em.PoseRelation.rotation_angle_deg, align=True).stats
    rpe_m = rpe(c(ref), c(est), em.PoseRelation.translation_part, delta=1, delta_unit=em.Unit.frames, align=True)
    for name, res in (("mm", mm), ("rad", rad), ("rpe_cm", rpe_cm)):
        _save(res, tmp_path / f"{name}.zip")
    table = evo_results_table([tmp_path])
    assert len(table) == 1
    row = table.iloc[0]
    assert row["ate_rmse"] == pytest.approx(0.013470089, rel=1e-6)
    for k, v in metres.items():
        assert row[f"ate_{k}"] == pytest.approx(v, rel=1e-12), k
    for k, v in degrees.items():
        assert row[f"aoe_{k}"] == pytest.approx(v, rel=1e-12), k
    for k, v in rpe_m.stats.items():
        assert row[f"rpe_trans_{k}"] == pytest.approx(v, rel=1e-12), k


def test_evo_zips_at_two_rpe_deltas_are_two_rows(data, tmp_path):
    """evo_rpe at 1 frame and at 0.2 m for one estimate: the second overwrote the first in one row
    (784 pairs lost); now a row each, each with the estimate's APE."""
    ref, est = _evo_synced(data)
    c = copy.deepcopy
    a = ape(c(ref), c(est), em.PoseRelation.translation_part, align=True)
    frames = rpe(c(ref), c(est), em.PoseRelation.translation_part, delta=1, delta_unit=em.Unit.frames, align=True)
    metres = rpe(c(ref), c(est), em.PoseRelation.translation_part, delta=0.2, delta_unit=em.Unit.meters, align=True)
    for name, res in (("ape", a), ("rpe_1f", frames), ("rpe_02m", metres)):
        _save(res, tmp_path / f"{name}.zip")
    table = evo_results_table([tmp_path]).set_index("rpe_pairs")
    assert sorted(table.index) == [41, 784]
    assert table.loc[784, "rpe_trans_rmse"] == pytest.approx(frames.stats["rmse"], rel=1e-15)
    assert table.loc[41, "rpe_trans_rmse"] == pytest.approx(metres.stats["rmse"], rel=1e-15)
    assert "0.2 (m)" in table.loc[41, "rpe_delta"] and "1 (frames)" in table.loc[784, "rpe_delta"]
    assert (table["ate_rmse"] == a.stats["rmse"]).all() and (table["matched"] == 785).all()


def test_time_window_and_scale_say_what_went_wrong(data, capsys):
    """``--t-start`` after the ground truth's end was told 'is after t_end 1305031128.7555 s' (no
    t_end was given); ``--align scale --align-frames 1`` was 'needs at least 2 matched poses' with
    785 matched."""
    g, e = str(data.tum / GT), str(data.tum / EST)
    assert main(["evaluate", e, "--gt", g, "--conventions", "evo", "--t-start", "1305031200", "--no-progress"]) == 1
    err = capsys.readouterr().err
    assert "after the ground truth's last stamp 1305031128.7555001 s" in err and "t_end" not in err
    one_pose_scale = ["--conventions", "evo", "--align", "scale", "--align-frames", "1", "--no-progress"]
    assert main(["evaluate", e, "--gt", g, *one_pose_scale]) == 2  # refused before any file is read, as sim3 is
    assert "--align-frames 1 with --align scale: a scale needs 2 poses" in capsys.readouterr().err


def test_to_evo_of_an_empty_trajectory_is_lorisnbs_error(data, tmp_path):
    """A TUM file of comments only, read and handed to evo: lorisnb's ValidationError naming it
    (it was evo's TrajectoryException, 'pose data is empty'); a real one converts both ways."""
    from lorisnb.io import read_tum
    from lorisnb.tools.peers.evo_bridge import from_evo, to_evo

    empty = tmp_path / "empty.txt"
    empty.write_text("# timestamp tx ty tz qx qy qz qw\n")
    with pytest.raises(ValidationError, match="'est' has no poses"):
        to_evo(read_tum(empty), "est")
    t = read_tum(data.tum / EST)
    back = from_evo(to_evo(t, "est"))
    assert len(back) == 788 and back.positions[0, 0] == pytest.approx(1.344379, abs=1e-12)


def test_crosscheck_evo_checks_its_format_and_tolerance(data):
    """``crosscheck_evo(..., fmt="TUM")`` read the TUM files as a ROS bag ('not a readable ROS bag');
    ``tol=-1`` was taken (2 of 30 statistics 'agreed')."""
    table = crosscheck_evo(data.tum / GT, data.tum / EST, fmt="TUM", gt_fmt=" tum")
    stats = _stats(table)
    assert stats["agrees"].all() and stats.loc["matched", "evo"] == 785
    for bad in (-1, float("nan"), "1e-9"):
        with pytest.raises(ValidationError, match="expected a tolerance in"):
            crosscheck_evo(data.tum / GT, data.tum / EST, tol=bad)
    with pytest.raises(ValidationError, match="fmt=tumm: expected one of tum, kitti"):
        crosscheck_evo(data.tum / GT, data.tum / EST, fmt="tumm")


def test_classic_crosscheck_checks_its_rpe_steps_and_flags(data):
    """``crosscheck(..., rpe_deltas=[(1, "frames")])`` was scored as 1 *metre* (any unit but 'f' was
    metres: 's', 'deg' too); ``(0, 'f')`` raised ValueError and ``(1.5, 'f')`` evo's
    MetricsException; ``all_pairs="no"`` meant all pairs and ``crosscheck_openloris(scale="no")``
    Sim(3) (strings truth-tested)."""
    from lorisnb.io import read_tum
    from lorisnb.tools.peers.crosscheck import crosscheck, crosscheck_openloris

    gt, est = read_tum(data.tum / GT), read_tum(data.tum / EST)
    rows = crosscheck(gt, est, rpe_deltas=[(1, "frames")]).set_index("quantity")
    one_frame = crosscheck(gt, est, rpe_deltas=[(1, "f")]).set_index("quantity")
    assert "delta 1 frame(s)" in rows.loc["rpe_trans_rmse", "note"]
    assert rows.loc["rpe_trans_rmse", "lorisnb"] == one_frame.loc["rpe_trans_rmse", "lorisnb"]
    assert rows.loc["rpe_trans_rmse", "n_pairs"] == 787 and rows.loc["rpe_trans_rmse", "agrees"]
    for bad, words in (([(0.5, "s")], "unit 's'"), ([(5, "deg")], "unit 'deg'"), ([(0, "f")], "positive whole"),
                       ([(1.5, "f")], "positive whole"), ([(-1, "m")], "positive number of metres")):  # fmt: skip
        with pytest.raises(ValidationError, match=words):
            crosscheck(gt, est, rpe_deltas=bad)
    with pytest.raises(ValidationError, match="all_pairs='no'"):
        crosscheck(gt, est, all_pairs="no")
    dso = data.icra20 / "per-seq" / "dso" / "cafe-1-1-all.txt"
    table = crosscheck_openloris(dso, scale="no", data_root=data.root, rpe_deltas=[(1, "f")])
    assert set(table.loc[table["quantity"] == "rpe_trans_rmse", "alignment"]) == {"se3"}


def test_evo_zips_of_other_settings_are_not_joined(data, tmp_path):
    """Issue 45: an APE of a --t_start/--t_end run sat next to a full-range RPE in one row, and one RPE
    was copied into two rows. Now each run is its own row with its settings (t_first, t_last), and APE
    and RPE are joined only when the same poses and the same alignment were used."""

    ref, est = _evo_synced(data)
    c = copy.deepcopy
    t0 = float(ref.timestamps[0])
    window_ref, window_est = c(ref), c(est)
    keep = [i for i, t in enumerate(window_ref.timestamps) if t0 + 5 <= t <= t0 + 20]
    window_ref.reduce_to_ids(keep)
    window_est.reduce_to_ids(keep)
    a_window = ape(c(window_ref), c(window_est), em.PoseRelation.translation_part, align=True)
    a_full = ape(c(ref), c(est), em.PoseRelation.translation_part, align=True)
    r_full = rpe(c(ref), c(est), em.PoseRelation.translation_part, delta=1, delta_unit=em.Unit.frames, align=True)
    for name, res in (("ape_window", a_window), ("ape_full", a_full), ("rpe_full", r_full)):
        _save(res, tmp_path / f"{name}.zip")
    table = evo_results_table([tmp_path])
    assert len(table) == 2
    joined = table[table["rpe_trans_rmse"].notna()]
    assert len(joined) == 1  # the RPE once, next to the full-range APE only
    assert joined.iloc[0]["ate_rmse"] == pytest.approx(a_full.stats["rmse"], rel=1e-15)
    alone = table[table["rpe_trans_rmse"].isna()].iloc[0]
    assert alone["ate_rmse"] == pytest.approx(a_window.stats["rmse"], rel=1e-15)
    assert alone["matched"] == len(keep) and alone["t_first"] == pytest.approx(window_est.timestamps[0], abs=1e-6)
    assert joined.iloc[0]["t_first"] == pytest.approx(est.timestamps[0], abs=1e-6)
