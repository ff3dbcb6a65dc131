"""Repeated trials, intervals, pairwise tests, rankings and paper-ready tables (issue 14)."""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest
from helpers import write

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.stats import inference as stats
from lorisnb.core.stats import ranking
from lorisnb.core.stats.trials import split_trial
from lorisnb.tools.report.tables import comparison_table, interval, to_latex, to_markdown

ORB = "per-seq/orbslam2_rgbd/cafe_1_1_orbslam2-original.txt"


@pytest.mark.parametrize(
    "path, base, trial",
    [
        ("orb/cafe_trial3.txt", "orb/cafe.txt", 3),
        ("orb/cafe-trial-3.txt", "orb/cafe.txt", 3),
        ("orb/trial3/cafe.txt", "orb/cafe.txt", 3),
        ("orb/run_2/cafe.txt", "orb/cafe.txt", 2),
        ("MH_01/stamped_traj_estimate3.txt", "MH_01/stamped_traj_estimate.txt", 3),
        ("orb/cafe.txt", "orb/cafe.txt", 0),
        ("orb/runner/cafe.txt", "orb/runner/cafe.txt", 0),
    ],
)
def test_trial_tokens(path, base, trial):
    assert split_trial(path) == (base, trial)


def test_trials_through_evaluate(tmp_path, icra20):
    src = (icra20 / ORB).read_bytes()
    write(tmp_path, "orb/cafe_trial1.txt", src)
    write(tmp_path, "orb/cafe_trial2.txt", src)
    write(tmp_path, "vins/run_1/cafe.txt", src)
    ev = ln.evaluate(tmp_path)
    t = ev.sequences(eps="paper", phi=30)
    assert sorted(zip(t["algorithm"], t["trial"], strict=True)) == [("orb", 1), ("orb", 2), ("vins", 1)]
    scenes = ev.scenes(eps="paper", phi=30)  # trials are not duplicates
    assert len(scenes) == 3 and scenes["cr"].nunique() == 1
    summary = stats.trial_summary(t).set_index("algorithm")
    assert summary.loc["orb", "trials"] == 2 and summary.loc["orb", "cr_std"] == 0.0
    per_seq = stats.trial_summary(t, level="sequence").set_index(["algorithm", "seq"])
    assert per_seq.loc[("orb", 1), "trials"] == 2 and per_seq.loc[("orb", 1), "cr_mean"] == t["cr"].iloc[0]
    alone = ln.evaluate(tmp_path / "vins" / "run_1" / "cafe.txt").errors[0]  # a file given alone
    assert (alone.algorithm, alone.trial) == ("vins", 1)
    custom = ln.evaluate(write(tmp_path, "x/orb/cafe_seed7.txt", src).parent.parent, trials_by=r"seed(\d+)")
    assert custom.errors[0].trial == 7
    with pytest.raises(ln.ValidationError, match="expected a group"):
        ln.evaluate(tmp_path, trials_by="seed")


def _population(rng, n_seq, n_trials, mean_shift=0.0, algorithm="a"):
    """A per-sequence table: sequence CR ~ Beta(5, 3) (population mean 0.625 + shift), each trial
    with noise of 0.03; equal durations, so the scene value is the mean."""
    base = np.clip(rng.beta(5, 3, n_seq) + mean_shift, 0, 1)
    rows = [
        dict(algorithm=algorithm, scene="s", seq=s + 1, trial=k + 1, cr=float(np.clip(base[s] + rng.normal(0, 0.03), 0, 1)),
             gt_duration=100.0, matched=100)
        for s in range(n_seq) for k in range(n_trials)
    ]  # fmt: skip
    return pd.DataFrame(rows), base


def test_single_sequence_with_trials_bootstraps_the_trials():
    table, _ = _population(np.random.default_rng(1), n_seq=1, n_trials=8)
    ci = stats.confidence_intervals(table, ["cr"]).iloc[0]
    assert ci["unit"] == "trials" and ci["units"] == 8 and ci["low"] < ci["value"] < ci["high"]


@pytest.mark.thorough
def test_intervals_cover_the_true_value_at_about_the_nominal_rate():
    """Over 300 simulated benchmarks (fixed seeds), the 95 % interval covers the population mean."""
    rng = np.random.default_rng(12345)
    hits, n = 0, 300
    for k in range(n):
        table, _ = _population(rng, n_seq=12, n_trials=3)
        ci = stats.confidence_intervals(table, ["cr"], n_resamples=400, seed=k).iloc[0]
        assert ci["unit"] == "sequences x trials" and ci["trials"] == 3
        hits += ci["low"] <= 0.625 <= ci["high"]
    assert 0.88 <= hits / n <= 0.99, hits / n


@pytest.mark.thorough
def test_pairwise_detects_a_real_difference_and_not_a_null_one():
    rng = np.random.default_rng(7)
    detected = false_alarms = 0
    n = 100
    for k in range(n):
        a, base = _population(rng, 12, 2, algorithm="a")
        b = a.assign(algorithm="b", cr=np.clip(a["cr"] - 0.08 + rng.normal(0, 0.02, len(a)), 0, 1))
        c = a.assign(algorithm="c", cr=np.clip(a["cr"] + rng.normal(0, 0.03, len(a)), 0, 1))
        p = stats.pairwise(pd.concat([a, b, c]), "cr", n_resamples=200, seed=k, intervals=False).set_index(["a", "b"])
        detected += bool(p.loc[("a", "b"), "significant"])
        false_alarms += bool(p.loc[("a", "c"), "significant"])
        assert p["correction"].iloc[0].startswith("Holm over 3 pair(s)")
    assert detected / n >= 0.8, detected
    assert false_alarms / n <= 0.08, false_alarms


def test_holm_and_minimum_p():
    np.testing.assert_allclose(stats.holm(np.array([0.01, 0.04, 0.03, np.nan])), [0.03, 0.06, 0.06, np.nan])
    a, _ = _population(np.random.default_rng(0), 5, 1)
    b = a.assign(algorithm="b", cr=a["cr"] - 0.2)
    p = stats.pairwise(pd.concat([a, b])).iloc[0]
    assert p["min_p"] == pytest.approx(0.0625) and p["p"] == pytest.approx(0.0625) and p["exact"]
    assert not p["significant"] and p["p_a_better"] == 1.0  # five sequences can never reach 0.05


def test_ranking_marks_ties():
    rng = np.random.default_rng(3)
    a, _ = _population(rng, 15, 1)
    b = a.assign(algorithm="b", cr=a["cr"] + rng.normal(0, 0.01, len(a)))
    c = a.assign(algorithm="c", cr=a["cr"] - 0.2)
    r = ranking.ranking(pd.concat([a, b, c])).set_index("algorithm")
    assert r.loc["a", "rank"] == r.loc["b", "rank"] == 1 and r.loc["c", "rank"] == 3
    assert r.loc["a", "tied_with"] == "b" and r.loc["c", "tied_with"] == ""


@pytest.mark.thorough
def test_latex_and_markdown_tables(icra20):
    ev = ln.evaluate([icra20 / "per-seq" / a for a in ("orbslam2_rgbd", "dso", "odom")], scale="auto")
    ci = stats.confidence_intervals(ev.sequences(eps="paper", phi=30), ["cr", "c_ate_rmse"], n_resamples=300)
    text, best = comparison_table(ci, "cr")
    assert not best.to_numpy().any()  # no test given: nothing in bold
    table = ev.sequences(eps="paper", phi=30)
    rank = ranking.ranking(table, "cr")
    text, best = comparison_table(ci, "cr", ranks=rank)
    tex = to_latex(text, best, caption="CR 95% intervals", label="tab:cr")
    assert tex.count("{") == tex.count("}") and tex.count("[") == tex.count("]")
    rules = [tex.index(r) for r in (r"\toprule", r"\midrule", r"\bottomrule")]
    assert rules == sorted(rules)
    body = tex[rules[1] : rules[2]].strip().splitlines()[1:]
    assert len(body) == 3 and all(line.endswith(r"\\") for line in body)  # one row per algorithm
    assert r"95\%" in tex and r"orbslam2\_rgbd" in tex
    for col in text.columns:  # bold = rank 1 where the test separates someone
        r = rank[rank["scene"] == col].set_index("algorithm")
        separated = (r["rank"] > 1).any()
        for alg in text.index:
            assert best.loc[alg, col] == (separated and r.loc[alg, "rank"] == 1)
    assert tex.count(r"\textbf") == int(best.to_numpy().sum())
    assert re.search(r"\d\.\d\d \[\d\.\d\d, \d\.\d\d\]", tex)
    md = to_markdown(text, best)
    assert md.count("\n") == 2 + 3 and md.count("**") == 2 * int(best.to_numpy().sum())
    assert interval(0.834, 0.791, 0.872) == "0.83 [0.79, 0.87]" and interval(np.nan, 0, 1) == "n/a"


@pytest.mark.thorough
def test_compare_command(tmp_path, icra20, capsys):
    tex, md, csv = tmp_path / "t.tex", tmp_path / "t.md", tmp_path / "ci.csv"
    args = ["compare", str(icra20 / "per-seq" / "orbslam2_rgbd"), str(icra20 / "per-seq" / "odom"), "--latex", str(tex)]
    rc = main(args + ["--markdown", str(md), "--csv", str(csv), "--no-progress"])
    assert rc == 0
    outp = capsys.readouterr().out
    assert "95% bootstrap intervals over sequences" in outp and "pairs differ significantly" in outp
    assert tex.read_text().count(r"\\") == 1 + 2 and md.exists()  # the header and one row per algorithm
    ci = pd.read_csv(csv)
    row = ci[(ci["algorithm"] == "odom") & (ci["scene"] == "home") & (ci["metric"] == "cr")].iloc[0]
    assert row["low"] <= row["value"] <= row["high"] and row["units"] == 5


def test_robust_ranking_counts_ties_as_first(icra20):
    ev = ln.evaluate([icra20 / "per-seq" / a for a in ("orbslam2_rgbd", "odom")], scenes=["home"])
    grid = ln.sweep(ev.errors, [0.5, 1, 100], [10, 180])
    first, region = ranking.robust_ranking(grid, ev.durations(), "cr", reference=(1.0, 180.0))
    assert set(first["cases"]) == {6}
    assert first["firsts"].sum() >= 6  # every case has a first; ties count for each
    assert region.set_index(["eps", "phi"]).loc[(1.0, 180.0), "same_ranking"]
