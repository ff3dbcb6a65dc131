"""Threshold sweeps and CR surfaces at the grid's edges, on the real icra20 results, per sequence and
lifelong: every grid point against a direct single evaluation and against the paper's Eq. 2-4 by
hand; monotone where the definitions make them so; the sweep's helpers (``eps_at_cr``,
``cr_surfaces``) score each trial alone, take the values ``score`` takes and refuse what it refuses.
"""

from __future__ import annotations

import itertools
import shutil

import numpy as np
import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core import aggregate_scenes, score
from lorisnb.core.lifelong.surfaces import cr_surfaces
from lorisnb.core.lifelong.sweep import eps_at_cr, sweep, sweep_scenes

EPS = [np.inf, 0.3, 0.0, "paper", "relative:0.05"]  # unsorted on purpose
PHI = [180.0, 0.0, 30.0, np.inf]
DELTA = [np.inf, 1e-6, 1.0, 86400.0]
TAU = [86400.0, 1e-6, 60.0, np.inf]


@pytest.fixture(scope="module")
def ev(icra20):
    paths = [icra20 / "lifelong" / "maslam", icra20 / "per-seq" / "orbslam2_t265",
             icra20 / "per-seq" / "vins_mono_color_imu_with_loop" / "corridor-1-failed.txt"]  # fmt: skip
    return ln.evaluate(paths, jobs=1, progress=False)


@pytest.fixture(scope="module")
def grid(ev):
    return sweep(ev.errors, EPS, PHI, DELTA, TAU, columns="all")


def _maslam(ev, scene: str):
    return next(f for f in ev.errors if f.algorithm == "maslam" and f.scene == scene)


def _at(grid: pd.DataFrame, e, p, d, t) -> pd.DataFrame:
    label = e if isinstance(e, str) else str(float(e))
    sel = (grid["eps_value"].astype(str) == label) & (grid["phi"] == p) & (grid["delta"] == d) & (grid["tau"] == t)
    return grid[sel].reset_index(drop=True)


def _points():
    yield from ((e, p, np.inf, 1e-6) for e, p in itertools.product(EPS, PHI))
    yield from (("paper", 30.0, d, t) for d, t in itertools.product(DELTA, TAU))


@pytest.mark.thorough
def test_every_edge_of_the_grid_equals_a_single_evaluation(ev, grid):
    assert {f.mode for f in ev.errors} == {"lifelong", "per-seq"} and (
        grid["matched"] == 0
    ).any()  # both modes, and a run without output
    for e, p, d, t in _points():
        direct = score(ev.errors, e, p, d, t)
        swept = _at(grid, e, p, d, t)
        assert len(swept) == len(direct) == sum(len(f.sequences) for f in ev.errors), (e, p, d, t)
        for c in ("cs_r", "c_matched", "reloc_time", "first_correct", "eps", "matched"):  # no sums: bit for bit
            np.testing.assert_array_equal(swept[c].to_numpy(), direct[c].to_numpy(), err_msg=f"{c} at {(e, p, d, t)}")
        for c in ("correct_time", "cr", "cr_t", "c_ate_rmse", "c_aoe_rmse"):
            np.testing.assert_allclose(swept[c], direct[c], rtol=1e-13, atol=0, equal_nan=True, err_msg=f"{c} at {(e, p, d, t)}")  # fmt: skip
    # at eps = 0 no pose of the real results is correct; at eps = phi = inf every matched pose is
    none, every = _at(grid, 0.0, np.inf, np.inf, 1e-6), _at(grid, np.inf, np.inf, np.inf, 1e-6)
    assert (none["cr"] == 0).all() and (none["cs_r"] == 0).all()
    np.testing.assert_array_equal(every["c_matched"], every["matched"])


def test_rates_follow_the_papers_equations_by_hand(ev, grid):
    """Eq. 2-4 of the paper, written out for each sequence of maslam's lifelong corridor (re-localized
    sequences: t0 > t_min), at eps 'paper' (5 m), phi 30 deg, over delta and tau."""
    f = _maslam(ev, "corridor")
    rows = grid[(grid["file"] == f.file) & (grid["algorithm"] == "maslam")]
    assert len(f.sequences) == 5
    for e in f.sequences:
        if e.matched == 0:
            continue
        c = (e.ate <= 5.0) & (e.aoe <= 30.0)  # Eq. 1
        t_next = np.append(e.stamps[1:], e.gt_end)  # t_{N+1} = t_max
        t_min, t_max, t0 = e.gt_start, e.gt_end, e.stamps[0]
        for d, t in itertools.product(DELTA, TAU):
            held = np.sum(np.minimum(t_next - e.stamps, d) * c)
            r = _at(rows[rows["seq"] == e.seq], "paper", 30.0, d, t).iloc[0]
            assert r["cr"] == pytest.approx(held / (t_max - t_min), rel=1e-12)  # Eq. 2
            assert r["cr_t"] == pytest.approx(held / (t_max - t0), rel=1e-12)  # Eq. 3
            assert r["cs_r"] == pytest.approx(np.exp(-(t0 - t_min) / t) * c[0], rel=1e-12)  # Eq. 4
    assert rows["cs_r"].max() > 0 and (rows.groupby("seq")["reloc_time"].first() > 0).any()


def test_rates_grow_with_every_threshold_that_admits_more(grid):
    """CR, CR-T and the correct poses never drop as eps, phi or delta grow; CS-R never drops as
    eps, phi or tau grow; delta leaves CS-R alone and tau CR (up to the sums' last bits)."""
    order = {"eps": grid["eps"], "phi": grid["phi"], "delta": grid["delta"], "tau": grid["tau"]}
    table = grid[grid["eps_value"].astype(str) != "relative:0.05"]  # its metres differ per sequence
    for axis, metrics in (("eps", ("cr", "cr_t", "c_matched", "cs_r")), ("phi", ("cr", "cr_t", "c_matched", "cs_r")),
                          ("delta", ("cr", "cr_t")), ("tau", ("cs_r",))):  # fmt: skip
        rest = ["file", "seq"] + [k for k in order if k != axis]
        s = table.sort_values([*rest, axis])
        for m in metrics:
            step = s.groupby(rest, observed=True)[m].diff().dropna()
            assert step.min() >= -1e-12 * max(1.0, s[m].abs().max()), (axis, m)
    for m in ("cr", "cr_t", "cs_r"):
        assert grid[m].between(0, 1).all(), m


def test_a_command_line_sweep_at_the_edges_equals_evaluate(icra20, tmp_path, capsys):
    f = str(icra20 / "lifelong" / "maslam" / "home.txt")
    args = ["--no-progress", "--csv"]
    assert main(["sweep", f, "--eps", "paper,0", "--phi", "180,inf", "--delta", "inf,1e-6", "--tau", "86400",
                 *args, str(tmp_path / "s.csv")]) == 0  # fmt: skip
    assert main(["evaluate", f, "--eps", "paper", "--phi", "180", "--delta", "inf", "--tau", "86400",
                 *args, str(tmp_path / "e.csv")]) == 0  # fmt: skip
    capsys.readouterr()
    s, e = pd.read_csv(tmp_path / "s.csv"), pd.read_csv(tmp_path / "e.csv")
    sub = s[(s["eps_value"] == "paper") & (s["phi"] == 180) & np.isinf(s["delta"])].reset_index(drop=True)
    assert len(sub) == len(e) == 5
    for c in ("cr", "cr_t", "cs_r", "c_matched", "correct_time", "c_ate_rmse"):
        np.testing.assert_allclose(sub[c], e[c], rtol=1e-13, equal_nan=True, err_msg=c)
    assert sub["cs_r"].tolist() == e["cs_r"].tolist()


def test_correct_time_is_the_same_sum_in_a_sweep_as_alone(ev):
    """A BLAS product summed a row of a large grid in another order than a one-row product: sweeps
    and scores differed in the last bits, and a superset of correct poses could sum to less
    (maslam corridor at delta 0.01: 25.93351482391359 s at eps 10, ...351 s at eps inf)."""
    f = _maslam(ev, "corridor")
    eps, phi = [0.0, 0.05, 0.3, 1.0, 3.0, 10.0, np.inf], [0.0, 5.0, 30.0, 90.0, 180.0, np.inf]
    grid = sweep(f, eps, phi, [0.01, 1.0])
    for e in eps:
        for p in phi:
            for d in (0.01, 1.0):
                direct = score(f, e, p, d)
                at = grid[(grid["eps"] == e) & (grid["phi"] == p) & (grid["delta"] == d)]
                for col in ("correct_time", "cr", "cr_t", "c_ate_rmse", "c_aoe_rmse", "c_matched"):
                    np.testing.assert_array_equal(at[col].to_numpy(), direct[col].to_numpy(), err_msg=col)
    ct = grid.set_index(["seq", "delta", "phi", "eps"])["correct_time"].sort_index()
    assert (ct.groupby(level=["seq", "delta", "phi"]).diff().dropna() >= 0).all()  # non-decreasing in eps


@pytest.fixture
def trials(icra20, tmp_path):
    for k in (1, 2, 3):  # the same run three times: each trial's answer is the run's own
        (tmp_path / "maslam").mkdir(exist_ok=True)
        shutil.copy(icra20 / "lifelong" / "maslam" / "cafe.txt", tmp_path / "maslam" / f"cafe_seed{k}.txt")
    return ln.evaluate(tmp_path, trials_by=r"seed(\d+)", jobs=1, progress=False)


def test_eps_at_cr_scores_each_trial_alone(trials, icra20):
    """Three trials of one run were pooled into one row whose CR reached 2.1 (max_cr) and whose
    eps for CR 0.5 was 0.30 m, where each trial's CR is 0.17."""
    res = eps_at_cr(trials.errors, 0.5, trials.durations(), phi=30.0)
    assert res["trial"].tolist() == [1, 2, 3] and (res["max_cr"] <= 1).all()
    alone = eps_at_cr(ln.evaluate(icra20 / "lifelong" / "maslam" / "cafe.txt", jobs=1).errors, 0.5,
                      trials.durations(), phi=30.0)  # fmt: skip
    assert res["eps"].tolist() == [alone["eps"].iloc[0]] * 3
    assert alone["eps"].iloc[0] == pytest.approx(0.588663, abs=1e-6)
    assert alone["max_cr"].iloc[0] == pytest.approx(0.700958, abs=1e-6)
    scenes = trials.scenes(eps=float(res["eps"].iloc[0]), phi=30.0)
    assert (scenes["cr"] >= 0.5).all()
    below = trials.scenes(eps=float(np.nextafter(res["eps"].iloc[0], 0)), phi=30.0)
    assert (below["cr"] < 0.5).all()


def test_eps_at_cr_target_is_a_rate(ev):
    files = [_maslam(ev, "cafe")]
    durations = ev.durations()
    for bad in (0, -0.1, 1.5, 50, np.nan, np.inf, None, True, "half"):
        with pytest.raises(ln.ValidationError, match=r"expected a correct rate above 0 and at most 1"):
            eps_at_cr(files, bad, durations)
    assert eps_at_cr(files, "0.5", durations)["eps"].tolist() == eps_at_cr(files, 0.5, durations)["eps"].tolist()
    assert np.isnan(eps_at_cr(files, 1.0, durations)["eps"].iloc[0])  # never reached: NaN, with its max_cr


def test_eps_at_cr_lists_a_run_without_matches(ev):
    res = eps_at_cr(ev.errors, 0.5, ev.durations())
    failed = res[res["algorithm"] == "vins_mono_color_imu_with_loop"]
    assert len(failed) == 1 and np.isnan(failed["eps"].iloc[0]) and failed["max_cr"].iloc[0] == 0.0


def test_missing_durations_are_refused_alike(ev):
    files = [_maslam(ev, "cafe")]
    durations = ev.durations()
    without = durations[durations["scene"] != "cafe"]
    msg = "no ground-truth durations for scene(s) cafe; pass their durations"
    for call in (lambda: sweep_scenes(sweep(files, [1.0], [30.0]), without),
                 lambda: cr_surfaces(files, [1.0, 3.0], [30.0], without),  # was a surface of NaN
                 lambda: eps_at_cr(files, 0.5, without)):  # was a KeyError  # fmt: skip
        with pytest.raises(ln.EvaluationError) as info:
            call()
        assert str(info.value) == msg


def test_a_sweep_takes_the_eps_values_score_takes(ev):
    """A scene mapping (accepted by score) was a TypeError in sweep; a 0-d numpy array (a
    reduction's result) was a TypeError in sweep and cr_surfaces."""
    files = [f for f in ev.errors if f.mode == "lifelong"]
    mapping = {"cafe": 1.0, "corridor": 5.0, "home": 2.0, "market": 4.0}
    swept = sweep(files, [mapping, "paper"], [30.0])
    direct = score(files, mapping, 30.0)
    at = swept[swept["eps_value"] == "cafe:1,corridor:5,home:2,market:4"].reset_index(drop=True)
    np.testing.assert_allclose(at["cr"], direct["cr"], rtol=1e-13)
    np.testing.assert_array_equal(at["eps"], direct["eps"])
    assert set(at["eps"]) == {1.0, 5.0, 2.0, 4.0}
    with pytest.raises(ln.ValidationError) as swept_error:  # refused as score refuses it (model.scene_eps)
        sweep(files, [{"cafe": 1.0}], [30.0])
    with pytest.raises(ln.ValidationError) as direct_error:
        score(files, {"cafe": 1.0}, 30.0)
    assert str(swept_error.value) == str(direct_error.value) and "gives no threshold for scene" in str(
        swept_error.value
    )
    zero_d = np.asarray([0.3, 1.0]).max()[()]  # a numpy scalar ...
    assert sweep(files, np.array(1.0))["cr"].tolist() == sweep(files, 1.0)["cr"].tolist() == sweep(files, zero_d)["cr"].tolist()  # fmt: skip
    s = cr_surfaces(files, np.array(1.0), np.array(30.0), ev.durations())
    assert s.cr.shape == (len(s.groups), 1, 1)
    with pytest.raises(ln.ValidationError, match="expected at most 180 degrees"):
        cr_surfaces(files, [1.0], np.array(200.0), ev.durations())


def test_a_fine_grid_is_scored_in_chunks_within_bounded_memory(ev):
    """The kernel's (eps, phi, pose) arrays made a fine sweep need E x P x poses x 9 bytes (a
    1000 x 1000 sweep of maslam's cafe: 14.5 GiB, refused with advice to stream to Parquet, which
    needs the same); the grid is now scored in chunks of :data:`CHUNK_BYTES`."""
    from lorisnb.core.lifelong.sweep import sweep_bytes

    f = _maslam(ev, "cafe")
    eps, phi = np.geomspace(0.05, 20, 300), np.linspace(0, 180, 100)
    assert 300 * 100 * max(e.matched for e in f.sequences) * 9 > 2**28  # more than one chunk (CHUNK_BYTES)
    table = sweep(f, eps, phi, max_bytes=400 * 2**20)
    assert sweep_bytes([f], (300, 100, 1, 1)) < 400 * 2**20 and len(table) == 2 * 300 * 100
    for i, j in ((0, 0), (123, 17), (299, 99), (250, 40)):
        direct = score(f, eps[i], phi[j])
        at = table[(table["eps"] == eps[i]) & (table["phi"] == phi[j])]
        np.testing.assert_array_equal(at["c_matched"], direct["c_matched"])
        np.testing.assert_allclose(at["cr"], direct["cr"], rtol=1e-13)
    with pytest.raises(ln.ValidationError, match=r"about 0\.3 GiB .* stream the table to Parquet"):
        sweep(f, eps, phi, max_bytes=100 * 2**20)


def test_ranking_and_surface_lookups_refuse_what_they_cannot_answer(ev):
    """rank_stability on a sweep's own table (one row per sequence) ranked the sequences averaged,
    with exit status 0; a metric's typo was a KeyError; Surfaces.at found nothing for an evaluation
    of icra20_results (suite 'lifelong') unless given the suite, and said so with a KeyError."""
    from lorisnb.core.lifelong.sweep import rank_stability, rank_swaps

    files = [f for f in ev.errors if f.algorithm == "maslam"]
    table = sweep(files, [1.0, 3.0, 5.0], [30.0])
    with pytest.raises(ln.ValidationError, match=r"expected scene rows \(sweep_scenes\(table, durations\)\)"):
        rank_stability(table)
    scenes = sweep_scenes(table, ev.durations())
    for rank in (rank_stability, rank_swaps):
        with pytest.raises(ln.ValidationError, match=r"metric='CR' is no numeric column .* expected one of cr, cr_t"):
            rank(scenes, metric="CR")
    s = cr_surfaces(files, [1.0, 3.0], [30.0], ev.durations())
    lookup = aggregate_scenes(score(files, 3.0, 30.0), ev.durations()).set_index("scene")
    assert s.at("maslam", "cafe")[1, 0] == pytest.approx(lookup.loc["cafe", "cr"], abs=1e-12)
    with pytest.raises(ln.ValidationError, match=r"no surface for 'masla' in 'cafe' .* algorithms 'maslam'; scenes"):
        s.at("masla", "cafe")


def test_a_sweep_carries_evos_pose_relation_columns_as_evaluate_does(icra20):
    """``sweep --relation R`` said 'pose relation R (ape_*, rpe_* columns)' and wrote none:
    sweep(relation=R) now adds them (threshold-free, per sequence), so a row equals evaluate's.
    (The command line must pass ``relation=ev.spec.relation``: see the report.)"""
    from lorisnb.core.metrics.relation_table import RELATION_COLUMNS

    ev = ln.evaluate(icra20 / "lifelong" / "maslam" / "cafe.txt", relation="angle_deg", jobs=1)
    direct = ev.sequences(eps=1.0, phi=30.0)
    swept = sweep(ev.errors, [3.0, 1.0], [30.0], columns="all", relation="angle_deg")
    at = swept[swept["eps"] == 1.0].reset_index(drop=True)
    assert [c for c in at.columns if c != "eps_value"] == [c for c in direct.columns if c != "spec"]
    for c in RELATION_COLUMNS[1:]:
        np.testing.assert_array_equal(at[c], direct[c], err_msg=c)
    assert (at["relation"] == "angle_deg").all() and at["ape_max"].between(0, 180).all()
    np.testing.assert_allclose(at["cr"], direct["cr"], rtol=1e-13)
    with pytest.raises(ln.ValidationError, match="pose relation 'angle': expected one of trans_part, angle_deg"):
        sweep(ev.errors, [1.0], relation="angle")
