"""Trials numbered from 0 (``trial0/``, ``run_0/``, which the default trial tokens read): a missing
trial is caught as with trials numbered from 1, in ``diff`` and ``history``, from the CLI and from
Python. Trial 0 was read as "a file without a trial token" wherever numbered trials existed, so a
CAND of 0-based trials that lost trial 2 everywhere had its trial 0 relabelled as trial 2: "ok",
exit 0 (the same tables renumbered 1 to 3: "missing trial 3", exit 1); with CAND's other trials
byte-equal to BASE's, the lost trial was named "trial 2 a copy". The unnumbered stand-in (a run
numbering some sequences' trials and not others') is pinned by tests/tools/test_verdicts.py. Real
data: the bundled icra20 results, evaluated and perturbed as reruns."""

from __future__ import annotations

import os

import numpy as np
import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.stats.regression import changes


@pytest.fixture(scope="module")
def runs(icra20):
    """Three reruns (trials 0, 1, 2) of the odom and orbslam2_rgbd per-seq results at the paper's
    thresholds, each sequence's values varied by a rerun-sized spread, seeded."""
    table = ln.evaluate([icra20 / "per-seq" / "odom", icra20 / "per-seq" / "orbslam2_rgbd"]).sequences(
        eps="paper", phi=30
    )
    rng = np.random.default_rng(11)
    parts = []
    for k in range(3):
        t = table.assign(trial=k)
        t["cr"] = np.clip(t["cr"] + rng.normal(0, 0.01, len(t)), 0, 1)
        t["ate_rmse"] = t["ate_rmse"] * np.exp(rng.normal(0, 0.05, len(t)))
        parts.append(t)
    return pd.concat(parts, ignore_index=True)


def _lost(seqs: pd.DataFrame) -> pd.DataFrame:
    return seqs[seqs["status"].isin(["missing", "failed"])]


@pytest.mark.parametrize("first", [0, 1])
def test_a_lost_trial_is_missing_whatever_the_first_number(runs, first):
    """0-based and 1-based numbering alike: CAND losing its last trial everywhere, its first trial
    everywhere, or one sequence's middle trial is "missing trial N" on exactly those sequences."""
    base = runs.assign(trial=runs["trial"] + first)
    last, mid = first + 2, first + 1
    n = base.groupby(["algorithm", "scene", "seq"]).ngroups
    for gone in (last, first):
        seqs, scenes = changes(base, base[base["trial"] != gone])
        lost = _lost(seqs)
        assert len(lost) == n and (lost["cand"] == f"missing trial {gone}").all(), (gone, lost["cand"].tolist())
        assert (scenes["metric"] == "coverage").any()
    one = (base["algorithm"] == "odom") & (base["scene"] == "cafe") & (base["seq"] == 1)
    seqs, _ = changes(base, base[~(one & (base["trial"] == mid))])
    assert _lost(seqs)[["algorithm", "scene", "seq", "cand"]].values.tolist() == [
        ["odom", "cafe", 1, f"missing trial {mid}"]
    ]
    seqs, _ = changes(base, base)  # nothing lost: nothing missing
    assert _lost(seqs).empty


def test_a_lost_trial_beside_byte_equal_trials_is_named_missing_not_a_copy(runs):
    """CAND holding BASE's own trials 0 and 1 and no trial 2 lacks trial 2: named missing (it was
    "trial 2 a copy", BASE's trial 0 relabelled)."""
    seqs, _ = changes(runs, runs[runs["trial"] != 2].copy())
    lost = _lost(seqs)
    assert not lost.empty and (lost["cand"] == "missing trial 2").all()
    assert not seqs["cand"].astype(str).str.contains("a copy").any()


def test_unnumbered_stand_in_and_zero_based_runs_keep_their_counts(runs):
    """Where no sequence holds trial 0 beside another, trial 0 is the unnumbered stand-in: a single
    unnumbered run against 0-based trials 0 to 2 lacks two of them; 0-based trials against 1-based
    ones of the same count lack nothing, both ways."""
    single = runs[runs["trial"] == 1].assign(trial=0)
    seqs, _ = changes(runs, single)
    lost = _lost(seqs)
    assert len(lost) == len(single) and (lost["cand"] == "missing trial 1, 2").all()
    one_based = runs.assign(trial=runs["trial"] + 1)
    for b, c in ((runs, one_based), (one_based, runs)):
        seqs, _ = changes(b, c)
        assert _lost(seqs).empty


def test_diff_and_history_cli_catch_a_lost_trial_numbered_from_zero(runs, tmp_path, capsys):
    """The CLI, on tables: ``diff`` of a 0-based BASE and a CAND without trial 2 exits 1 naming
    "missing trial 2" (it said "ok", exit 0); ``history`` of the two nights does the same."""
    folder = tmp_path / "nightly"
    folder.mkdir()
    base, cand = folder / "2026-01-01.csv", folder / "2026-01-02.csv"
    runs.to_csv(base, index=False)
    runs[runs["trial"] != 2].to_csv(cand, index=False)
    os.utime(base, (1767236400, 1767236400))
    os.utime(cand, (1767322800, 1767322800))
    rc = main(["diff", str(base), str(cand), "--no-progress"])
    out = capsys.readouterr().out
    assert rc == 1 and "missing trial 2" in out and "a copy" not in out
    rc = main(["history", str(base), str(cand), "--metric", "cr"])
    out = capsys.readouterr().out
    assert rc == 1, out
    assert "newest run 2026-01-02.csv against 2026-01-01.csv: regression" in out and "missing trial 2" in out
