"""One spec per run: the report's own tables are computed with the spec the notebooks build from the
same parameters, and a threshold word reaches notebooks and widgets normalized, checked by the same
code."""

from __future__ import annotations

import math

import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.tools.notebook.params import check_parameters, evaluation_spec
from lorisnb.tools.notebook.widgets import ThresholdExplorer
from lorisnb.tools.report.leaderboard import leaderboard_spec, report_findings

ORB = "cafe_1_1_orbslam2-original.txt"


def test_the_reports_tables_use_the_notebooks_spec(icra20, data):
    """-p official_interpolation, rpe_unit, rpe_delta reach findings/ and run.json's spec as they
    reach the notebooks; the thresholds not given are compare's (the spec's: inf, inf)."""
    source = icra20 / "per-seq"
    params = {"official_interpolation": True, "rpe_unit": "m", "rpe_delta": 2, "eps": 3, "scenes": ["cafe"],
              "algorithms": ["orbslam2_rgbd"]}  # fmt: skip
    f, ev, values = report_findings(source, data, params)
    assert ev.spec == evaluation_spec({"scale": "auto", **params})  # the notebooks' function
    assert ev.spec.official_interpolation and (ev.spec.rpe_unit, ev.spec.rpe_delta) == ("m", 2.0)
    assert ev.spec.eps == 3.0 and math.isinf(ev.spec.phi) and values["scale"] == "auto"
    table = ev.sequences()
    plain = ln.evaluate(source / "orbslam2_rgbd" / ORB, scale="auto").sequences(3.0)
    nb = ln.evaluate(source / "orbslam2_rgbd" / ORB, evaluation_spec(params, mode="per-seq"), scale="auto").sequences()
    row = table[table["seq"] == 1].iloc[0]
    assert row["official_interpolation"] and row["aoe_rmse"] == pytest.approx(nb["aoe_rmse"].iloc[0], abs=1e-9)
    assert row["rpe_trans_rmse"] == pytest.approx(nb["rpe_trans_rmse"].iloc[0], abs=1e-9)
    # the official tool's slips and RPE over 2 m: not the plain numbers (1.992166 deg, RPE per second)
    assert row["aoe_rmse"] == pytest.approx(2.003032, abs=1e-6) and plain["aoe_rmse"].iloc[0] == pytest.approx(
        1.992166, abs=1e-6
    )
    assert row["rpe_trans_rmse"] != pytest.approx(plain["rpe_trans_rmse"].iloc[0], rel=1e-3)
    assert '"rpe_unit":"m"' in row["spec"] and f.board["value"].between(0, 1).all()
    # the defaults: compare's and the per-sequence notebook's (eps = phi = inf)
    spec = leaderboard_spec({})
    assert (spec.eps, spec.phi, spec.delta, spec.tau, spec.align) == (math.inf, math.inf, 1.0, 60.0, "auto")


@pytest.mark.parametrize("given, expected", [("PAPER", "paper"), (" Paper ", "paper"),
                                             (" relative:0.05", "relative:0.05"), ("3", 3.0)])  # fmt: skip
def test_threshold_words_reach_the_notebooks_normalized(given, expected):
    declared = {"eps": {"default": '"paper"'}}
    assert check_parameters({"eps": given}, declared)["eps"] == expected


def test_threshold_explorer_takes_every_eps_the_readme_names(icra20):
    ev = ln.evaluate(icra20 / "lifelong", algorithms=["vins_mono_color_imu_with_loop"], scenes=["home"])
    d = ev.durations()
    metres = ThresholdExplorer(ev.errors, d, eps=3.0).results()[0]
    for eps in ("paper", "PAPER", {"home": 3.0}):  # home's paper eps is 3 m
        ex = ThresholdExplorer(ev.errors, d, eps=eps)
        assert ex.eps == 3.0
        pd.testing.assert_frame_equal(ex.results()[0], metres)
    rel = ThresholdExplorer(ev.errors, d, eps="relative:0.05")
    assert rel.eps == "relative:0.05"
    expected = ln.aggregate_scenes(ln.score(ev.errors, "relative:0.05", 30.0, 1.0, 60.0), d)["cr"].iloc[0]
    assert rel.results()[0]["cr"].iloc[0] == pytest.approx(expected, abs=1e-12)
    slider = next(c for c in rel.widget().children[0].children[0].children if c.description == "eps (m)")
    assert slider.value == "relative:0.05" and 5.0 in [v for _, v in slider.options]
    with pytest.raises(ln.errors.ValidationError, match="relative:2"):
        ThresholdExplorer(ev.errors, d, eps="relative:2")


def test_a_relative_eps_is_refused_before_anything_runs_where_a_notebook_quotes_metres(tmp_path, data):
    """``-p eps relative:0.05`` passed the report's check and failed metrics_primer inside its kernel
    (its prose quotes eps in metres of one scene); the other notebooks take it."""
    from lorisnb.cli import main
    from lorisnb.errors import ValidationError
    from lorisnb.tools.notebook.start import setup

    declared = {"eps": {"default": "1.0"}}
    with pytest.raises(ValidationError, match="metrics_primer quotes eps in metres"):
        check_parameters({"eps": "relative:0.05"}, declared, ["metrics_primer", "threshold_sensitivity"])
    assert check_parameters({"eps": "relative:0.05"}, declared, ["threshold_sensitivity"])["eps"] == "relative:0.05"
    assert check_parameters({"eps": "PAPER"}, declared, ["metrics_primer"])["eps"] == "paper"
    with pytest.raises(ValidationError, match="metrics_primer quotes eps in metres"):
        setup("metrics_primer", data.root, tmp_path / "out", parameters={"eps": " relative:0.05"})
    out = tmp_path / "report"
    assert main(["report", "--notebooks", "metrics_primer", "-p", "eps", "relative:0.05", "--out", str(out)]) == 2
    assert not out.exists()


@pytest.mark.parametrize(
    "command",
    [["evaluate"], ["sweep", "--eps", "0.5,1", "--phi", "30"], ["compare"], ["evaluate", "--rpe-unit", "m"]],
)
def test_a_command_builds_its_spec_once_at_the_edge(command, monkeypatch, capsys):
    """The options enter once: the command line builds the spec and every layer below takes it as
    it is. ``evaluate()`` validated it again from scratch, and ``compare`` once more per table for
    the RPE options it already held (three specs for one command)."""
    from lorisnb.cli import main
    from lorisnb.core.spec.evalspec import EvalSpec
    from lorisnb.io.datasets.paths import sample_data

    built = []
    original = EvalSpec.__post_init__

    def counted(self):
        built.append(self)
        original(self)

    monkeypatch.setattr(EvalSpec, "__post_init__", counted)
    sample = sample_data()
    rc = main([*command, str(sample.icra20 / "per-seq" / "orbslam2_rgbd"), "--data", str(sample.root), "--jobs", "1"])
    capsys.readouterr()
    assert rc == 0 and len(built) == 1, (rc, len(built))
