"""A trial that crashed after writing its result file's header (``scene:``, ``frame:``, ``seq: 5`` and
no pose) is a failed run, as a missing trial is: ``diff`` regresses on it (it passed, verdict ok,
exit 0, CR 0.87 -> 0.28 on the t-test's spread), unless BASE failed as often there. And every row
says one trial count: the trials of each side, then how many values the test took (it said "5 vs 1
trials" beside trials_cand 5, and called values holding failed runs "copies of one run"). Real
data: reruns of the icra20 ORB-SLAM2 outputs of the home scene."""

from __future__ import annotations

import json
import re
import shutil

import numpy as np
import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.stats.regression import changes
from lorisnb.tools.decisions.diff import diff_tables

ALG = "orbslam2_rgbd"
NAME = "home_1_{}_orbslam2-original"


def _rerun(src, dst, seed: int) -> None:
    """A rerun of the system behind a result file (:func:`lorisnb.core.stats.reruns.rerun`), written."""
    from lorisnb.core.stats.reruns import RerunNoise, rerun

    rf = ln.read_openloris(src, warn=False)
    dst.parent.mkdir(parents=True, exist_ok=True)
    again = {q: rerun(tr, RerunNoise(), seed + q) for q, tr in rf.sequences.items()}
    ln.write_openloris(dst, again, scene=rf.header["scene"], frame=rf.header["frame"])


@pytest.fixture(scope="module")
def runs(icra20, tmp_path_factory):
    """BASE and CAND: three reruns each of ORB-SLAM2 on the five home sequences."""
    root = tmp_path_factory.mktemp("runs")
    for side, offset in (("base", 0), ("cand", 500)):
        for seq in range(1, 6):
            for trial in (1, 2, 3):
                src = icra20 / "per-seq" / ALG / f"{NAME.format(seq)}.txt"
                _rerun(src, root / side / ALG / f"{NAME.format(seq)}_trial{trial}.txt", offset + 10 * seq + trial)
    return root


def _crashed(runs, tmp_path, side: str, cuts: dict[int, int], name: str):
    """A copy of a run whose home-5 trials (keys) are cut to their first lines (values): 3 keeps the
    header only, 4 the header and one pose."""
    out = tmp_path / name
    shutil.copytree(runs / side, out)
    for trial, keep in cuts.items():
        f = out / ALG / f"{NAME.format(5)}_trial{trial}.txt"
        f.write_text("".join(f.read_text().splitlines(keepends=True)[:keep]))
    return out


def _diff(capsys, base, cand, tmp_path):
    rc = main(["diff", str(base), str(cand), "--json", str(tmp_path / "v.json"), "--force", "--no-progress"])
    out = capsys.readouterr().out
    return rc, json.loads((tmp_path / "v.json").read_text()), out


def test_what_a_header_only_and_a_one_pose_block_hold(runs, tmp_path):
    """A header-only block is a row without output (poses 0, matched 0, CR 0, no ATE); a block of
    one pose matched it (poses 1, matched 1): output, judged by its values."""
    cand = _crashed(runs, tmp_path, "cand", {2: 3, 3: 4}, "c")
    with pytest.warns(ln.LorisWarning):
        t = ln.evaluate([cand]).sequences()
    five = t[(t["scene"] == "home") & (t["seq"] == 5)].set_index("trial")
    assert five.loc[2, ["poses", "matched", "cr"]].tolist() == [0, 0, 0.0] and np.isnan(five.loc[2, "ate_rmse"])
    assert five.loc[3, ["poses", "matched"]].tolist() == [1, 1] and five.loc[3, "cr"] < 0.05
    assert five.loc[1, "matched"] > 500


@pytest.mark.thorough
def test_trials_written_without_a_pose_regress_through_the_cli(runs, tmp_path, capsys):
    """CAND's home-5 trials 2 and 3 crashed after their header: regression, exit 1, the trials named
    as a missing trial's are; at scene level too. One such trial of three is within rerun noise
    (reruns that never initialise): no failed-trial row, as on a noise-only night."""
    cand = _crashed(runs, tmp_path, "cand", {2: 3, 3: 3}, "c_hdr2")
    rc, v, out = _diff(capsys, runs / "base", cand, tmp_path)
    assert rc == 1 and v["verdict"] == "regression"
    lost = [r for r in v["regressions"] if r["level"] == "sequence" and r["metric"] == "trial"]
    assert [(r["scene"], r["seq"], r["cand"], r["status"]) for r in lost] == [
        ("home", 5, "trial 2, 3 no pose matched", "failed")
    ]
    assert "BASE failed in none of its 3 trial(s), CAND in 2 of its 3" in lost[0]["decided_by"]
    scene = [r for r in v["regressions"] if r["level"] == "scene" and r["metric"] == "coverage"]
    assert [r["cand"] for r in scene] == ["home-5: trial 2, 3 no pose matched"]
    assert "verdict: regression (1 sequence(s) regressed: orbslam2_rgbd home-5 trial 2, 3 no pose matched)" in out
    cr = [r for r in v["regressions"] + v["improvements"] if r["metric"] == "cr" and r["seq"] == 5]
    assert not cr  # the t-test alone does not see it: the coverage rule does
    cand1 = _crashed(runs, tmp_path, "cand", {3: 3}, "c_hdr1")
    rc, v, _ = _diff(capsys, runs / "base", cand1, tmp_path)
    assert v["counts"]["failed"] == 0 and not [r for r in v["regressions"] if r["metric"] in ("trial", "coverage")]


@pytest.mark.thorough
def test_failed_trials_are_counted_against_the_base(runs, tmp_path, capsys):
    """A system that fails home-5 in one trial of three on both sides passes (equal failures, no
    false alarm); CAND failing two of three where BASE failed one regresses."""
    base = _crashed(runs, tmp_path, "base", {3: 3}, "b_hdr1")
    rc, v, _ = _diff(capsys, base, _crashed(runs, tmp_path, "cand", {1: 3}, "c_hdr1"), tmp_path)
    assert rc == 0 and v["verdict"] == "ok" and v["counts"]["failed"] == 0
    rc, v, _ = _diff(capsys, base, _crashed(runs, tmp_path, "cand", {1: 3, 2: 3}, "c_hdr12"), tmp_path)
    lost = [r for r in v["regressions"] if r["metric"] == "trial"]
    assert rc == 1 and [r["cand"] for r in lost] == ["trial 1, 2 no pose matched"]
    assert "BASE failed in 1 of its 3 trial(s) (3), CAND in 2 of its 3" in lost[0]["decided_by"]


@pytest.mark.thorough
def test_a_single_run_without_a_pose_regresses(icra20, tmp_path, capsys):
    """One run a side (no trial token): CAND's home-5 file holds its header only, BASE's tracked."""
    base, cand = tmp_path / "b", tmp_path / "c"
    for seq in (4, 5):
        for side, seed in ((base, 0), (cand, 500)):
            _rerun(icra20 / "per-seq" / ALG / f"{NAME.format(seq)}.txt", side / ALG / f"{NAME.format(seq)}.txt", seed)
    f = cand / ALG / f"{NAME.format(5)}.txt"
    f.write_text("".join(f.read_text().splitlines(keepends=True)[:3]))
    assert f.read_text().splitlines()[-1] == "seq: 5"
    rc, v, _ = _diff(capsys, base, cand, tmp_path)
    lost = [r for r in v["regressions"] if r["level"] == "sequence" and r["status"] == "failed"]
    assert rc == 1 and [(r["seq"], r["cand"]) for r in lost] == [(5, "nothing matched")]


def test_a_python_diff_of_tables_with_failed_trials(runs, tmp_path):
    """The same rule in Python, on the evaluated tables: CR 0.87 -> 0.28 with two of three trials
    empty regresses; the ATE row counts 3 vs 3 trials and says it tested 3 vs 1 values, why."""
    base = ln.evaluate([runs / "base"]).sequences()
    cand = ln.evaluate([_crashed(runs, tmp_path, "cand", {2: 3, 3: 3}, "c_hdr2")]).sequences()
    d = diff_tables(base, cand)
    assert d.regressed
    s = d.sequences[(d.sequences["scene"] == "home") & (d.sequences["seq"] == 5)].set_index("metric")
    assert s.loc["trial", "cand"] == "trial 2, 3 no pose matched" and s.loc["trial", "status"] == "failed"
    ate = s.loc["ate_rmse"]
    assert (ate["trials_base"], ate["trials_cand"]) == (3, 3)
    assert "(3 vs 3 trials, tested on 3 vs 1 values" in ate["decided_by"]
    assert "2 of CAND's trials have no ate_rmse (no pose to take it over)" in ate["decided_by"]


def test_every_row_says_the_trial_count_of_its_columns(icra20):
    """BASE five reruns, CAND three near-identical copies of one run (its trials 4 and 5 missing:
    failed runs): the rows said "5 vs 1 trials" beside trials_cand 5 and called CAND's values, two
    failed runs among them, "near-identical copies of one run". Now each t-test row begins with its
    columns' counts; the copies are CAND's trials with output, its failed runs count each."""
    table = ln.evaluate([icra20 / "per-seq" / ALG]).sequences(eps="paper", phi=30)
    rng = np.random.default_rng(3)

    def trials(ks, spread):
        parts = []
        for k in ks:
            t = table.assign(trial=k)
            t["cr"] = np.clip(t["cr"] + rng.normal(0, spread[0], len(t)), 0, 1)
            t["ate_rmse"] = t["ate_rmse"] * np.exp(rng.normal(0, spread[1], len(t)))
            parts.append(t)
        return pd.concat(parts, ignore_index=True)

    base, cand = trials(range(1, 6), (0.02, 0.19)), trials(range(1, 4), (1e-4, 0.005))
    seqs, scenes = changes(base, cand)
    assert (seqs.loc[seqs["metric"] == "trial", "cand"] == "missing trial 4, 5").all()
    tested = pd.concat([seqs, scenes])
    tested = tested[tested["decided_by"].str.startswith("t-test", na=False)]
    assert len(tested)
    said = tested["decided_by"].str.extract(r"\((\d+) vs (\d+) trials").astype(float)
    assert (said[0].to_numpy() == tested["trials_base"].to_numpy()).all()
    assert (said[1].to_numpy() == tested["trials_cand"].to_numpy()).all()
    copies = tested[tested["decided_by"].str.contains("near-identical copies")]
    assert len(copies) and not copies["decided_by"].str.contains("CAND's trials are near-identical").any()
    assert copies["decided_by"].str.contains("CAND's 3 trial\\(s\\) with output are near-identical copies").any()
    assert copies["decided_by"].str.contains("its 2 failed run\\(s\\) \\(no pose matched\\) count each").any()
    cr = tested[(tested["metric"] == "cr") & tested["seq"].notna()]
    assert cr["decided_by"].str.contains(re.escape("(5 vs 5 trials, tested on 5 vs 3 values")).all()
