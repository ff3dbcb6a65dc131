"""Threshold sweeps: every grid point equals the single-setting evaluation (issue #4)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from helpers import durations_of

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core import aggregate_scenes, score
from lorisnb.core.lifelong.sweep import eps_at_cr, rank_stability, rank_swaps, sequence_size, sweep, sweep_scenes

EPS = [0.1, 0.3, 1.0, 3.0, 10.0, np.inf]
PHI = [5.0, 30.0, np.inf]
DELTA = [0.2, 1.0, 5.0]
TAU = [10.0, 60.0]


@pytest.fixture(scope="module")
def ev(icra20):
    return ln.evaluate(icra20, scale="auto")


def _same(a: pd.DataFrame, b: pd.DataFrame, cols) -> None:
    a = a.reset_index(drop=True)
    b = b.reset_index(drop=True)
    assert len(a) == len(b) > 0
    for c in cols:
        x, y = a[c], b[c]
        if pd.api.types.is_numeric_dtype(x) and not pd.api.types.is_bool_dtype(x):
            np.testing.assert_allclose(x.astype(float), y.astype(float), rtol=0, atol=1e-12, equal_nan=True, err_msg=c)
        else:
            assert (x.astype(str).to_numpy() == y.astype(str).to_numpy()).all(), c


@pytest.fixture(scope="module")
def grid(ev):
    return sweep(ev.errors, EPS, PHI, DELTA, TAU, columns="all")


@pytest.mark.parametrize(
    "point",
    [
        (0.3, 30.0, 1.0, 60.0),
        (3.0, 5.0, 0.2, 10.0),
        (np.inf, np.inf, 5.0, 60.0),
        (10.0, 30.0, 0.2, 60.0),
        (0.1, np.inf, 1.0, 10.0),
    ],
)
@pytest.mark.thorough
def test_every_checked_grid_point_equals_direct_evaluation(ev, grid, point):
    e, p, d, t = point
    direct = score(ev.errors, e, p, d, t)
    sub = grid[(grid["eps_value"] == e) & (grid["phi"] == p) & (grid["delta"] == d) & (grid["tau"] == t)]
    _same(direct, sub, direct.columns)


def test_lean_table_has_the_same_values(ev, grid):
    lean = sweep(ev.errors, EPS, PHI, DELTA, TAU)
    _same(grid[lean.columns], lean, lean.columns)
    assert (
        len(lean) == len(grid) == sum(len(f.sequences) for f in ev.errors) * len(EPS) * len(PHI) * len(DELTA) * len(TAU)
    )


def test_paper_eps_in_a_grid(ev):
    sw = sweep(ev.errors, ["paper", 3.0], [30.0])
    _same(score(ev.errors, "paper", 30.0), sw[sw["eps_value"] == "paper"], ["cr", "cr_t", "cs_r", "c_ate_rmse", "eps"])
    assert set(sw.loc[sw["eps_value"] == "paper", "eps"]) == {3.0, 5.0}


def test_scene_aggregates_of_a_sweep_equal_direct_aggregates(ev, grid):
    scenes = sweep_scenes(grid, ev.durations())
    direct = aggregate_scenes(score(ev.errors, 3.0, 30.0, 1.0, 60.0), ev.durations())
    sub = scenes[(scenes["eps"] == 3.0) & (scenes["phi"] == 30.0) & (scenes["delta"] == 1.0) & (scenes["tau"] == 60.0)]
    _same(direct, sub, ["suite", "algorithm", "scene", "cr", "cr_t", "c_ate_rmse", "c_ate_rmse_pooled"])


def test_relative_eps_uses_each_sequence_size(ev):
    f = next(f for f in ev.errors if f.file.endswith("vins_mono_color_imu_with_loop/home-1-3.txt"))
    e = f.sequences[0]
    ext = sequence_size(e, "extent")
    p = e.gt_positions
    assert ext == pytest.approx(np.linalg.norm(p.max(0) - p.min(0)))
    sw = sweep(f, [0.05], [np.inf], relative_to="extent")
    direct = score(f, 0.05 * ext)
    assert sw["cr"].iloc[0] == pytest.approx(direct["cr"].iloc[0], abs=1e-12)
    assert sw["eps"].iloc[0] == pytest.approx(0.05 * ext)


def test_eps_at_cr_is_exact(ev):
    files = [f for f in ev.errors if f.suite == "lifelong" and f.algorithm == "vins_mono_color_imu_with_loop"]
    durations = durations_of(*files)
    res = eps_at_cr(files, 0.3, durations, phi=30.0).set_index("scene")
    for scene, row in res.iterrows():
        if not np.isfinite(row["eps"]):
            continue
        at = aggregate_scenes(score(files, row["eps"], 30.0), durations).set_index("scene").loc[scene, "cr"]
        below = (
            aggregate_scenes(score(files, np.nextafter(row["eps"], 0), 30.0), durations)
            .set_index("scene")
            .loc[scene, "cr"]
        )
        assert at >= 0.3 - 1e-12 and below < 0.3


def test_rank_stability_and_swaps(ev):
    files = [f for f in ev.errors if f.suite == "per-seq"]
    scenes = sweep_scenes(sweep(files, [0.1, 0.3, 1.0, 3.0, 5.0, 10.0, 100.0], [np.inf]), durations_of(*files))
    stab = rank_stability(scenes)
    at_ref = stab[stab["eps"] == stab["reference_eps"]]
    assert len(at_ref) > 0
    assert np.allclose(at_ref["kendall_tau"], 1.0) and (at_ref["swapped_pairs"] == 0).all()
    assert stab["kendall_tau"].between(-1, 1).all()
    swaps = rank_swaps(scenes)
    assert len(swaps) > 0 and (swaps["eps_from"] < swaps["eps_to"]).all()


def test_sweep_cli_row_equals_evaluate_cli_row(icra20, tmp_path, capsys):
    f = str(icra20 / "lifelong" / "maslam" / "cafe.txt")
    assert (
        main(
            [
                "sweep",
                f,
                "--columns",
                "all",
                "--eps",
                "0.3,1,inf",
                "--phi",
                "10,inf",
                "--delta",
                "1",
                "--tau",
                "60",
                "--csv",
                str(tmp_path / "s.csv"),
                "--no-progress",
            ]
        )
        == 0
    )
    # the conventions line says the grid swept, not the spec's default thresholds (eps inf, phi inf)
    assert "; swept eps 0.3,1,inf m, phi 10,inf deg, delta 1 s, tau 60 s; RPE" in capsys.readouterr().err
    assert main(["evaluate", f, "--eps", "0.3", "--phi", "10", "--csv", str(tmp_path / "e.csv"), "--no-progress"]) == 0
    s = pd.read_csv(tmp_path / "s.csv")
    e = pd.read_csv(tmp_path / "e.csv")
    assert list(s.columns) == list(e.columns)
    sub = s[(s["eps"] == 0.3) & (s["phi"] == 10)]
    _same(e, sub, [c for c in e.columns if c != "file"])
    # the default columns: the thresholds' metrics, the same values
    args = ["sweep", f, "--eps", "0.3,1,inf", "--phi", "10,inf", "--csv", str(tmp_path / "lean.csv"), "--no-progress"]
    assert main(args) == 0
    lean = pd.read_csv(tmp_path / "lean.csv")
    assert set(lean.columns) < set(e.columns) and {"cr", "cr_t", "cs_r", "c_ate_rmse", "spec"} <= set(lean.columns)
    _same(e, lean[(lean["eps"] == 0.3) & (lean["phi"] == 10)], [c for c in lean.columns if c != "file"])
    assert main([*args[:-3], "--rpe-delta", "2", *args[-3:]]) == 2  # no column of it depends on the RPE
    assert "--rpe-delta: the RPE is in the table of sweep --columns all" in capsys.readouterr().err
    assert sub.set_index("seq").loc[2, "cr"] == pytest.approx(0.137731, abs=1e-6)
