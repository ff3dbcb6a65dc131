"""ORDSLAM reader, layout detection, catalog, normalized measures, published tables (issue #6).

All ORDSLAM files here are synthetic, written by the tests from bundled OpenLORIS ground truth
(the real 27 GB dataset is not bundled)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from evo.core import metrics as em
from scipy.spatial.transform import Rotation

import lorisnb as ln
from lorisnb.core import sequence_errors
from lorisnb.core.metrics.difficulty import difficulty_measures, trajectory_stats
from lorisnb.errors import ParseError, ValidationError
from lorisnb.io import load_groundtruth
from lorisnb.io.datasets.published import ordslam_table3, ordslam_table4_tum, published_ate
from lorisnb.io.readers.ordslam import SCENARIOS, describe_sequence, find_ordslam, light_period, read_ordslam, scenario
from lorisnb.tools.notebook.indoor_outdoor import TUM_PAIRS
from lorisnb.tools.peers.evo_bridge import to_evo


@pytest.fixture(scope="module")
def segment():
    """60 s of the cafe-1 ground truth, as a synthetic ORDSLAM-like camera trajectory."""
    gt = load_groundtruth("cafe").sequences[1]
    sel = np.flatnonzero(gt.stamps - gt.stamps[0] < 60)[::3]
    return gt.subset(sel)


def _write(path, rows, header=None, sep=" "):
    text = "" if header is None else header + "\n"
    text += "\n".join(sep.join(f"{v:.17g}" for v in r) for r in rows) + "\n"
    path.write_text(text)
    return path


def test_layouts_are_detected(tmp_path, segment):
    t0 = segment.stamps - segment.stamps[0]
    frames = np.round(t0 * 30).astype(int)
    q = segment.quaternions / np.linalg.norm(segment.quaternions, axis=1, keepdims=True)
    mats = np.concatenate([segment.rotations().as_matrix(), segment.positions[:, :, None]], axis=2).reshape(-1, 12)
    files = {
        "tum": _write(tmp_path / "a.txt", np.column_stack([segment.stamps, segment.positions, q])),
        "index": _write(
            tmp_path / "b.txt",
            np.column_stack([frames, segment.positions, q]),
            header="frame,x,y,z,qx,qy,qz,qw",
            sep=",",
        ),
        "pose": _write(tmp_path / "c.txt", np.column_stack([segment.positions, q]), sep="\t"),
        "kitti": _write(tmp_path / "d.txt", mats),
        "index-kitti": _write(tmp_path / "e.txt", np.column_stack([frames, mats]), sep=";"),
    }
    for layout, f in files.items():
        t = read_ordslam(f, fps=30.0)
        assert t.meta["layout"] == layout and t.meta["dataset"] == "ORDSLAM"
        assert len(t) == len(segment)
        np.testing.assert_allclose(t.positions, segment.positions, atol=1e-8)
    np.testing.assert_allclose(read_ordslam(files["index"], fps=30.0).stamps, frames / 30.0)
    np.testing.assert_allclose(read_ordslam(files["tum"]).stamps, segment.stamps, atol=1e-6)


def test_layout_errors(tmp_path, segment):
    frames_file = _write(
        tmp_path / "f.txt", np.column_stack([np.arange(5), np.zeros((5, 3)), np.tile([0, 0, 0, 1], (5, 1))])
    )
    with pytest.raises(ParseError, match="pass fps=") as caught:
        read_ordslam(frames_file)
    # the notebook's and the report's spelling too: "pass fps=..." alone sent a notebook's user nowhere
    assert "ordslam_fps" in str(caught.value) and "catalog.csv" in str(caught.value)
    with pytest.raises(ParseError, match=r"10 numbers per line; expected an ORDSLAM trajectory layout"):
        read_ordslam(_write(tmp_path / "g.txt", np.zeros((3, 10))))
    bad = _write(tmp_path / "h.txt", [[1, 0, 0, 0, 0, 0, 0, 1], [2, 0, 0, 0, 0, 0, 1]])
    with pytest.raises(ParseError, match=r"h.txt, line 2: 7 numbers, but the first line has 8"):
        read_ordslam(bad)
    scaled = _write(tmp_path / "i.txt", [[2, 0, 0, 1, 0, 2, 0, 2, 0, 0, 2, 3]])
    with pytest.raises(ParseError, match="determinant"):
        read_ordslam(scaled, fps=30)
    sheared = _write(tmp_path / "j.txt", [[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0], [1, 0.1, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0]])
    with pytest.raises(ParseError, match=r"j.txt, line 2: 3x4 matrix has a rotation block 0.1\d* from orthonormal"):
        read_ordslam(sheared, fps=30)  # determinant 1, but no rotation: refused as the KITTI reader refuses it


def test_catalog_lookups():
    assert scenario(5).difficulty == "difficult" and scenario(6).difficulty == "very difficult"
    assert scenario(4, numbering="paper") == SCENARIOS[5]  # the paper's 'difficult' is the page's scenario 5
    with pytest.raises(ValidationError, match="no ORDSLAM scenario 6 in the paper numbering"):
        scenario(6, numbering="paper")
    assert scenario(3, numbering="Paper") == SCENARIOS[4]  # any case, as other words (it read the page's 3)
    with pytest.raises(ValidationError, match="numbering='papers': expected 'page'"):
        scenario(3, numbering="papers")
    assert [light_period(t) for t in ("13h", "13-00", "20h30", float("nan"), np.float32("nan"), None)] == [
        "day", "day", "night", "unknown", "unknown", "unknown"]  # fmt: skip
    for bad in ("24:00", 25, "noon", -1):  # 24:00 and 25 were 'night'; '13h' a ValueError
        with pytest.raises(ValidationError, match="time="):
            light_period(bad)
    assert [light_period(t) for t in ("08:30", "13:00", "17:00", "20:00", "22:30", 7)] == [
        "day",
        "day",
        "dusk",
        "night",
        "night",
        "day",
    ]
    d = describe_sequence("ordslam/s6_22-30_fill.txt")
    assert (d["scenario"], d["difficulty"], d["time"], d["light"], d["depth_mode"]) == (
        6,
        "very difficult",
        "22:30",
        "night",
        "fill",
    )
    d = describe_sequence("scenario2/13h/standard.txt")
    assert (d["scenario"], d["time"], d["depth_mode"]) == (2, "13:00", "standard")
    cat = pd.DataFrame([dict(file="x.txt", scenario=4, time="16:30", depth_mode="standard")])
    assert describe_sequence("x.txt", cat)["difficulty"] == "medium"


def test_reader_values_are_validated(tmp_path, segment):
    mats = np.concatenate([segment.rotations().as_matrix(), segment.positions[:, :, None]], axis=2).reshape(-1, 12)
    kitti = _write(tmp_path / "k.txt", mats[:5])
    with pytest.raises(ln.ValidationError, match="layout=kiti: expected one of tum, index, pose, kitti, index-kitti"):
        read_ordslam(kitti, fps=30, layout="kiti")
    for fps in (0, -30, float("nan"), float("inf")):
        with pytest.raises(ln.ValidationError, match=r"fps=.*: expected a positive number of frames per second"):
            read_ordslam(kitti, fps=fps)
    with pytest.raises(ln.ValidationError, match=r"^fps=abc is not a number; expected a number$"):
        read_ordslam(kitti, fps="abc")
    q = segment.quaternions[:5] / np.linalg.norm(segment.quaternions[:5], axis=1, keepdims=True)
    tum = _write(tmp_path / "t.txt", np.column_stack([np.arange(5) * 0.25, segment.positions[:5], q]))
    assert read_ordslam(tum).meta["layout"] == "tum"
    with pytest.raises(ParseError, match=r"t.txt, line 2: frame number 0.25 is not a whole number; layout 'index'"):
        read_ordslam(tum, fps=30, layout="index")
    frac = _write(tmp_path / "u.txt", np.column_stack([[0, 1, 2.5, 3, 4], mats[:5]]))
    with pytest.raises(
        ParseError, match=r"u.txt, line 3: frame number 2.5 is not a whole number; layout 'index-kitti'"
    ):
        read_ordslam(frac, fps=30)


def test_reader_warns_like_read_tum(tmp_path, segment):
    """Repeated frame numbers and NaN rows: the same notes, with the same rule, as read_tum."""
    q = segment.quaternions[:10] / np.linalg.norm(segment.quaternions[:10], axis=1, keepdims=True)
    frames = np.array([0, 1, 2, 3, 3, 4, 5, 5, 6, 7])
    rows = np.column_stack([frames, segment.positions[:10], q])
    rows[1, 1] = np.nan
    f = _write(tmp_path / "r.txt", rows)
    with pytest.warns(ln.LorisWarning) as rec:
        t = read_ordslam(f, fps=10)
    notes = [str(w.message) for w in rec]
    assert any("r.txt: 1 pose(s) with NaN values skipped (first at line 2)" in n for n in notes)
    assert any(
        "r.txt: timestamps are not increasing (2 times; first at line 5: 0.300000000 repeats" in n
        and "kept the last pose of each repeated stamp" in n
        for n in notes
    )
    assert len(t) == 7  # 10 lines - 1 NaN - 2 repeats; the last pose of a repeated frame is kept
    np.testing.assert_allclose(t.positions[t.stamps == 0.3], segment.positions[4:5])
    tum = tmp_path / "r_tum.txt"
    tum.write_text(f.read_text())
    with pytest.warns(ln.LorisWarning) as rec_tum:
        ln.read_tum(tum)
    tum_note = next(str(w.message) for w in rec_tum if "not increasing" in str(w.message))
    ord_note = next(n for n in notes if "not increasing" in n)
    assert ord_note.split("); ")[1] == tum_note.split("); ")[1]  # the same rule in the same words
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(read_ordslam(f, fps=10, warn=False)) == 7


def test_find_ordslam_errors(tmp_path):
    assert find_ordslam(None) is None
    with pytest.raises(ln.DataNotFoundError, match="does not exist"):
        find_ordslam(tmp_path / "nope")
    with pytest.raises(ln.DataNotFoundError, match="no ground-truth .txt file"):
        find_ordslam(tmp_path)


def test_published_tables_are_labelled(data):
    t3 = ordslam_table3()
    assert t3["source"].str.startswith("published").all()
    orb = t3[(t3["algorithm"] == "ORB-SLAM2") & (t3["scenario"] == 5)].iloc[0]
    assert orb["ate_rmse_m"] == pytest.approx(0.091) and orb["ate_pct_length"] == pytest.approx(100 * 0.091 / 12)
    t4 = ordslam_table4_tum()
    assert t4["path_length_m"].notna().all()
    assert len(published_ate()) == len(t3) + len(t4)


@pytest.mark.parametrize("pair", TUM_PAIRS, ids=[p[0] for p in TUM_PAIRS])
def test_normalized_measures_on_tum_against_independent_values(data, pair):
    name, g, e, _ = pair
    gt, est = ln.read_tum(data.tum / g), ln.read_tum(data.tum / e)
    m = difficulty_measures(sequence_errors(gt, est), gt, eps_fraction=0.01, rpe_metres=1.0)
    # independent: path length and extent with plain numpy; ATE with evo on lorisnb's pairs
    length = float(np.sum(np.sqrt(np.sum(np.diff(gt.positions, axis=0) ** 2, axis=1))))
    extent = float(np.linalg.norm(gt.positions.max(0) - gt.positions.min(0)))
    assert m["length_m"] == pytest.approx(length) and m["extent_m"] == pytest.approx(extent)
    se = sequence_errors(gt, est)
    ref = to_evo(ln.Trajectory.from_rotations(se.stamps, se.gt_positions, se.gt_rotations))
    est_e = to_evo(est.subset(np.searchsorted(est.stamps, se.stamps)))
    est_e.align(ref)
    ape = em.APE(em.PoseRelation.translation_part)
    ape.process_data((ref, est_e))
    assert m["ate_pct_length"] == pytest.approx(100 * ape.get_statistic(em.StatisticsType.rmse) / length, rel=1e-9)
    # scaled CR by a plain loop (Eq. 2 with eps = 1 % of the extent)
    ok = ape.error <= 0.01 * extent
    t = se.stamps
    nxt = np.append(t[1:], se.gt_end)
    held = sum(min(b - a, 1.0) for a, b, c in zip(t, nxt, ok, strict=True) if c)
    assert m["cr_scaled"] == pytest.approx(held / (se.gt_end - se.gt_start), abs=1e-9)


def test_trajectory_stats_on_openloris_groundtruth():
    gt = load_groundtruth("home").sequences[2]
    st = trajectory_stats(gt)
    assert st["duration_s"] == pytest.approx(gt.stamps[-1] - gt.stamps[0])
    assert st["speed_mps"] == pytest.approx(st["length_m"] / st["duration_s"])
    turns = np.degrees(np.abs(np.diff(np.unwrap(gt.rotations().as_euler("xyz")[:, 2]))))  # planar robot: yaw only
    assert st["angular_speed_dps"] == pytest.approx(turns.sum() / st["duration_s"], rel=1e-6)


def make_synthetic_ordslam(root, segment):
    """A small folder in lorisnb's documented ORDSLAM layout, derived from bundled ground truth:
    two scenarios x two times, TUM-style files, and one 'algorithm' whose estimates are the ground
    truth moved rigidly, with noise growing with difficulty."""
    rng = np.random.default_rng(0)
    root.mkdir(parents=True, exist_ok=True)
    q = segment.rotations().as_quat()
    motion = Rotation.from_euler("z", 25, degrees=True)
    for sc, noise in ((5, 0.05), (6, 0.15)):
        for time in ("13-00", "22-30"):
            name = f"s{sc}_{time}_fill.txt"
            _write(root / name, np.column_stack([segment.stamps, segment.positions, q]))
            est_p = motion.apply(segment.positions + rng.normal(scale=noise, size=segment.positions.shape)) + 2.0
            est_q = (motion * segment.rotations()).as_quat()
            (root / "estimates" / "synthetic_slam").mkdir(parents=True, exist_ok=True)
            _write(root / "estimates" / "synthetic_slam" / name, np.column_stack([segment.stamps, est_p, est_q]))
    return root


def test_ordslam_folder_measures(tmp_path, segment):
    from lorisnb.tools.notebook.indoor_outdoor import ordslam_difficulty, ordslam_stats

    folder = find_ordslam(make_synthetic_ordslam(tmp_path, segment))
    assert len(folder.groundtruth) == 4 and list(folder.estimates) == ["synthetic_slam"]
    stats = ordslam_stats(folder)
    assert set(stats["group"]) == {"difficult", "very difficult"} and set(stats["light"]) == {"day", "night"}
    assert stats["length_m"].iloc[0] == pytest.approx(segment.path_length)
    table, problems = ordslam_difficulty(folder)
    assert problems.empty and len(table) == 4
    by = table.groupby("group")["ate_rmse_m"].median()
    assert by["very difficult"] > by["difficult"]


def test_headline_numbers(data):
    from lorisnb.tools.notebook.indoor_outdoor import headline, tum_difficulty

    meas = tum_difficulty(data)
    h = headline(meas, published_ate())
    assert h["computed_ate_pct"]["TUM RGB-D"] == pytest.approx(meas["ate_pct_length"].median())
    lo, hi = h["published_ate_pct_range"]["ORDSLAM"]
    assert lo == pytest.approx(100 * 0.091 / 12) and hi == pytest.approx(100 * 0.132 / 12)
    assert 0 < h["tracked_share"]["TUM RGB-D"] <= 1


def test_a_file_given_as_the_ordslam_folder_is_said_to_be_a_file(tmp_path):
    """``-p ordslam_dir FILE``: said 'does not exist' (and 'no such folder') of a file that exists."""
    from lorisnb.tools.notebook.params import existing

    f = tmp_path / "s1.txt"
    f.write_text("1 0 0 0 0 0 0 1\n")
    with pytest.raises(ln.DataNotFoundError, match="s1.txt is a file, not a folder"):
        find_ordslam(f)
    with pytest.raises(ln.ValidationError, match="ordslam_dir=.*s1.txt: a file, not a folder; expected an existing"):
        existing("ordslam_dir", f, folder=True)
