"""compare made statistically sound (issue 25 point 6, issue 24 points 3 and 7): one exact or
permutation test behind ranks, summary, bold marks and the CSV; the smallest attainable p-value
stated; missing sequences counted as evaluate counts them; duplicate files and an unmatched
--trials-by refused."""

from __future__ import annotations

import re
import shutil

import numpy as np
import pandas as pd
import pytest
from helpers import write
from scipy import stats as sps

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.stats.permutation import min_p, permutation_test, runs_needed

HOME = {"odom": "home-1-{}-odom.txt", "orbslam2_rgbd": "home_1_{}_orbslam2-original.txt"}


def rerun_copy(src, dst, seed: int) -> None:
    """A rerun of the system behind a result file (:func:`lorisnb.core.stats.reruns.rerun`: another
    start delay, other dropouts, other jitter), written as a result file: trials that differ as
    reruns do, not copies of one run."""
    from lorisnb.core.stats.reruns import RerunNoise, rerun

    rf = ln.read_openloris(src, warn=False)
    dst.parent.mkdir(parents=True, exist_ok=True)
    again = {q: rerun(tr, RerunNoise(), seed + q) for q, tr in rf.sequences.items()}
    ln.write_openloris(dst, again, scene=rf.header["scene"], frame=rf.header["frame"])


def compare(capsys, *args) -> tuple[int, str, str]:
    rc = main(["compare", *map(str, args), "--no-progress"])
    out = capsys.readouterr()
    return rc, out.out, out.err


@pytest.mark.thorough
def test_ranks_summary_bold_and_csv_agree(tmp_path, icra20, capsys):
    """Five reruns of odom, of a twin of odom (other seeds) and of ORB-SLAM2 on the five home
    sequences: the test separates ORB-SLAM2 from both, not the twins; the printed ranks, the
    summary sentence, the CSV ranks and p-values, and the bold cells of LaTeX and Markdown agree.
    (Noisy copies of one file are pseudo-replicates, which compare warns about instead of testing:
    the trials here are reruns.)"""
    res = tmp_path / "results"
    for alg, src_alg, base_seed in (("odom", "odom", 0), ("odom_twin", "odom", 1000), ("orb", "orbslam2_rgbd", 0)):
        for seq in range(1, 6):
            for trial in range(1, 6):
                src = icra20 / "per-seq" / src_alg / HOME[src_alg].format(seq)
                rerun_copy(src, res / alg / f"trial{trial}" / src.name, base_seed + 10 * seq + trial)
    csv, pairs_csv, md, tex = (tmp_path / n for n in ("c.csv", "p.csv", "t.md", "t.tex"))
    rc, out, _ = compare(capsys, res, "--csv", csv, "--pairs-csv", pairs_csv, "--markdown", md, "--latex", tex)
    assert rc == 0
    assert "(5 trial(s) per sequence)" in out
    algs, pairs = pd.read_csv(csv), pd.read_csv(pairs_csv)
    assert set(pairs["test"]) == {"permutation of trials within sequences"}
    k = int(pairs["significant"].sum())
    assert f"{k} of {len(pairs)} pairs differ significantly" in out
    rank = algs.set_index("algorithm")["rank"]
    assert rank["orb"] == 3 and rank["odom"] == rank["odom_twin"] == 1 and k == 2
    for line in out.splitlines():  # the printed ranking is the CSV's
        m = re.match(r"\s+home\s+(\S+)\s.*\s(\d+)\s+\S*$", line)
        if m and m.group(1) in rank.index:
            assert int(m.group(2)) == rank[m.group(1)]
    sig = pairs[pairs["significant"]]
    assert set(sig["better"]) == {"odom", "odom_twin"} and (sig["p_holm"] <= 0.05).all()
    assert (algs.loc[algs["algorithm"] == "orb", "p_holm_vs_top"] <= 0.05).all()
    assert algs["cliffs_delta_vs_top"].dropna().between(-1, 1).all()
    holds_zero = (pairs["difference_low"] <= 0) & (pairs["difference_high"] >= 0)  # the inverted test's interval
    assert (holds_zero == ~pairs["significant"]).all()
    others = algs[algs["algorithm"] != algs["top"]]
    zero = (others["difference_low_vs_top"] <= 0) & (others["difference_high_vs_top"] >= 0)
    assert (zero == (others["p_holm_vs_top"] > 0.05)).all() and not zero[others["algorithm"] == "orb"].any()
    bold = {line.split("|")[1].strip() for line in md.read_text().splitlines() if "**" in line}
    assert bold == {"odom", "odom_twin"}  # rank 1 where the test separates someone
    assert tex.read_text().count(r"\textbf") == 2


@pytest.mark.thorough
def test_no_significant_pair_no_bold_and_equal_ranks(tmp_path, icra20, capsys):
    """One run each (the bundled results): ranks 1 and 1, '0 of 1 pairs', no bold, the smallest
    possible p-value stated (2/2^5 on five home sequences)."""
    md, csv = tmp_path / "t.md", tmp_path / "c.csv"
    args = [icra20 / "per-seq" / "odom", icra20 / "per-seq" / "orbslam2_rgbd", "--markdown", md, "--csv", csv]
    rc, out, _ = compare(capsys, *args, "--power", "0.1")
    assert rc == 0 and "0 of 4 pairs differ significantly" in out
    assert "home (smallest possible p 0.0625" in out
    assert "**" not in md.read_text()
    algs = pd.read_csv(csv)
    assert (algs["rank"] == 1).all() and (algs["coverage"] == 1).all()
    assert algs.loc[algs["scene"] == "home", "min_p_vs_top"].dropna().eq(0.0625).all()
    unbounded = algs.dropna(subset=["p_vs_top"])  # no design here can reach 0.05: the test's interval is unbounded
    assert np.isinf(unbounded["difference_low_vs_top"]).all() and np.isinf(unbounded["difference_high_vs_top"]).all()
    assert "(power 0.8, each pair at alpha 0.05 / 4 pairs = 0.0125," in out  # the level each pair is sized at
    assert "runs needed to detect a difference of 0.1" in out and re.search(
        r"home\s+odom\s+orbslam2_rgbd\s+sequences\s+5\s+\d+", out
    )


def test_exact_test_on_three_against_three_with_ties(tmp_path, icra20, capsys):
    """3 vs 3 trials of one sequence, identical within each algorithm (ties): the exact test's
    smallest possible p is 0.1, and compare says no pair can reach 0.05; the trials are copies of
    one run, so no p-value is reported for the pair at all."""
    res = tmp_path / "results"
    for alg in HOME:
        for trial in (1, 2, 3):
            src = icra20 / "per-seq" / alg / HOME[alg].format(2)
            write(res, f"{alg}/{src.stem}_trial{trial}.txt", src.read_bytes())
    pairs_csv = tmp_path / "p.csv"
    rc, out, err = compare(capsys, res, "--pairs-csv", pairs_csv, "--power", "0.05")
    p = pd.read_csv(pairs_csv).iloc[0]
    assert rc == 0 and np.isnan(p["p"]) and p["test"] == "none: trials are copies of one run"
    # no test was made: no design of one is described (it said exact, 20 relabellings, min_p 0.1, reachable)
    assert np.isnan(p["relabellings"]) and np.isnan(p["min_p"]) and np.isnan(p["exact"]) and not p["reachable"]
    assert not p["significant"]
    assert p["difference_low"] == -np.inf and p["difference_high"] == np.inf  # no shift can be rejected either
    # copies: no test is made, so no count of trials helps (it said "smallest possible p 0.1 ... run more trials
    # (--power DELTA says how many)", and --power then sized nothing)
    assert "no pair can reach alpha 0.05 in home (the trials are copies of one run: no pair is tested" in out, out
    assert "--power DELTA says how many" not in out
    assert runs_needed(0.05, paired=False) == 4  # 4 vs 4: 2/70 < 0.05
    assert np.isnan(p["needed"]) and "--power: no number of runs for the pairs of" in err  # copies: none sized
    assert "has no output for home sequence(s) 1, 3, 4, 5" in err  # only seq 2 given: coverage stated
    # stdout says why no pair was sized (it said "every pair of algorithms differs, or no scene has two"), and
    # the header counts the copies as the one run they are (it said "3 trial(s) per sequence")
    assert ("--power 0.05: no pair sized: 1 of 1 pair(s) not sized: the trials of odom, orbslam2_rgbd are copies "
            "of one run") in out, out  # fmt: skip
    assert "every pair of algorithms differs" not in out and "3 trial(s) per sequence" not in out
    assert "(odom, orbslam2_rgbd: 3 file(s) per sequence, 1 distinct run (the trials are copies of one run" in out


def test_permutation_test_matches_scipy():
    """The exact test equals scipy.stats.permutation_test (exact, two-sided) on tied data: two
    independent samples, and paired samples (sign flips)."""
    a, b = np.array([0.5, 0.5, 0.7]), np.array([0.5, 0.6, 0.6])
    ref = sps.permutation_test((a, b), lambda x, y, axis: x.mean(axis) - y.mean(axis), permutation_type="independent",
                               vectorized=True, n_resamples=np.inf, alternative="two-sided")  # fmt: skip
    ours = permutation_test([a], [b])
    assert ours.exact and ours.pvalue == pytest.approx(ref.pvalue) and ours.min_p == pytest.approx(0.1)
    x = np.array([0.9, 0.8, 0.85, 0.7, 0.7, 0.95])
    y = np.array([0.6, 0.8, 0.65, 0.5, 0.71, 0.9])
    ref = sps.permutation_test((x, y), lambda u, v, axis: (u - v).mean(axis), permutation_type="samples",
                               vectorized=True, n_resamples=np.inf, alternative="two-sided")  # fmt: skip
    ours = permutation_test([np.array([u]) for u in x], [np.array([v]) for v in y])
    assert ours.pvalue == pytest.approx(ref.pvalue) and ours.min_p == pytest.approx(2 / 2**5)  # one tie: 5 flips
    assert min_p([(1, 1)] * 5) == pytest.approx(0.0625) and min_p([(3, 3)]) == pytest.approx(0.1)


def test_missing_sequences_count_as_evaluate_counts_them(tmp_path, icra20, capsys):
    """An algorithm without two home sequences is ranked on CR over all five (as evaluate's scene
    CR), not on what it has, and a warning names the sequences."""
    res = tmp_path / "results"
    shutil.copytree(icra20 / "per-seq" / "odom", res / "odom")
    shutil.copytree(icra20 / "per-seq" / "orbslam2_rgbd", res / "orb")
    for n in (4, 5):
        (res / "orb" / HOME["orbslam2_rgbd"].format(n)).unlink()
    csv = tmp_path / "c.csv"
    rc, out, err = compare(capsys, res, "--csv", csv)
    assert rc == 0 and "orb has no output for home sequence(s) 4, 5 (output for 3 of its 5 sequences)" in err
    row = pd.read_csv(csv).set_index(["algorithm", "scene"]).loc[("orb", "home")]
    assert row["coverage"] == pytest.approx(0.6) and row["missing_seqs"] == "4, 5"
    ev = ln.evaluate(res / "orb", scenes=["home"])
    scene = ev.scenes(eps="paper", phi=30).iloc[0]  # evaluate's CR: correct time over all five sequences
    assert scene["sequences"] == 3 and row["value"] == pytest.approx(scene["cr"], rel=1e-12)
    assert "3/5" in out


def test_duplicate_files_and_unmatched_trials_by_are_errors(tmp_path, icra20, data, capsys):
    src = (icra20 / "per-seq" / "orbslam2_rgbd" / "cafe_1_1_orbslam2-original.txt").read_bytes()
    write(tmp_path, "res/orb/cafe_a.txt", src)
    write(tmp_path, "res/orb/cafe_b.txt", src)
    rc, out, err = compare(capsys, tmp_path / "res")
    assert rc == 2 and "cafe_a.txt and" in err and "cafe_b.txt both hold orb cafe-1" in err and "--trials-by" in err
    with pytest.raises(ln.ValidationError, match="no trial number"):
        ln.evaluate(tmp_path / "res")
    rc, out, err = compare(capsys, tmp_path / "res", "--trials-by", r"cafe_([ab])")
    assert rc == 2 and "not a whole number" in err
    rc, out, err = compare(capsys, tmp_path / "res", "--trials-by", r"seed(\d+)")
    assert rc == 2 and r"trials_by=seed(\d+): matches none of the file or folder names of the 2 result file" in err
    with pytest.raises(ln.ValidationError, match="matches none"):
        ln.evaluate(tmp_path / "res", trials_by=r"seed(\d+)")
    tum = data.tum  # estimates against a --gt: the same rule
    rc = main(["evaluate", str(tum / "freiburg1_xyz-rgbdslam.txt"),
               "--gt", str(tum / "freiburg1_xyz-groundtruth.txt"), "--trials-by", r"seed(\d+)", "--no-progress"])  # fmt: skip
    assert rc == 2 and "matches none of the file or folder names of the 1 result file" in capsys.readouterr().err
    # searched in one name at a time: a '/' never matches (a path that visibly matches was refused)
    with pytest.raises(ln.ValidationError, match="one file or folder name at a time, so '/' never matches"):
        ln.evaluate(tmp_path / "res", trials_by=r"orb/cafe_seed(\d)")
    (tmp_path / "res" / "orb" / "cafe_b.txt").rename(tmp_path / "res" / "orb" / "cafe_seed2.txt")
    (tmp_path / "res" / "orb" / "cafe_a.txt").rename(tmp_path / "res" / "orb" / "cafe_seed1.txt")
    ev = ln.evaluate(tmp_path / "res", trials_by=r"seed(\d+)")
    assert sorted(f.trial for f in ev.errors) == [1, 2]


def test_options_compare_and_diff_cannot_apply_are_refused(tmp_path, icra20, capsys):
    odom = icra20 / "per-seq" / "odom"
    rc, _, err = compare(capsys, odom, "--parquet", tmp_path / "x")
    assert rc == 2 and "--parquet: not used by lorisnb compare" in err and not (tmp_path / "x").exists()
    rc, _, err = compare(capsys, odom, "--relative")
    assert rc == 2 and "--relative: not used" in err
    rc, _, err = compare(capsys, odom, "--latex", tmp_path / "t.txt")
    assert rc == 2 and "expected a .tex" in err
    rc, _, err = compare(capsys, odom, "--csv", tmp_path / "same.csv", "--pairs-csv", tmp_path / "same.csv")
    assert rc == 2 and "its own file" in err and not (tmp_path / "same.csv").exists()
    for bad in ("--alpha", "--level"):
        with pytest.raises(SystemExit):
            main(["compare", str(odom), bad, "1.5"])
    assert main(["diff", str(odom), str(odom), "--relative"]) == 2
    assert main(["diff", str(odom), "--no-progress"]) == 2  # one run only
    capsys.readouterr()
    # a threshold the metric does not depend on: ignored, though the header said "tau 5 s"
    for option, metric in (("--tau", "cr"), ("--tau", "c_ate_rmse"), ("--delta", "cs_r"), ("--delta", "c_ate_rmse")):
        rc, _, err = compare(capsys, odom, option, "5", "--metric", metric)
        assert rc == 2 and f"{option}: changes no value of --metric {metric}" in err, err


def test_difference_interval_inverts_the_test():
    """Paired, eight sequences (256 sign flips): the interval holds the shifts the exact test accepts;
    just inside a bound p > alpha, just outside p <= alpha; 0 is outside as the test rejects."""
    from lorisnb.core.stats.permutation import difference_interval, holm_levels

    x = np.array([0.9, 0.8, 0.85, 0.7, 0.75, 0.95, 0.6, 0.88])
    y = x - np.array([0.2, 0.1, 0.25, 0.15, 0.3, 0.12, 0.18, 0.22])
    a, b = [np.array([v]) for v in x], [np.array([v]) for v in y]
    res = permutation_test(a, b)
    assert res.exact and res.pvalue == pytest.approx(2 / 256)
    low, high = difference_interval(a, b, None, 0.05)
    assert 0 < low < res.statistic < high
    shift = lambda d: permutation_test([v - d for v in a], b).pvalue  # noqa: E731
    assert shift(low + 1e-6) > 0.05 >= shift(low - 1e-3) and shift(high - 1e-6) > 0.05 >= shift(high + 1e-3)
    assert difference_interval(a[:4], b[:4], None, 0.05) == (-np.inf, np.inf)  # 2/16 > 0.05: nothing rejected
    np.testing.assert_allclose(holm_levels(np.array([0.01, 0.04, 0.03]), 0.05), [0.05 / 3, 0.025, 0.025])


def test_tables_keep_suites_apart(tmp_path, icra20, capsys):
    """The same algorithm in two suites (folders above it): two rows, not one."""
    for suite in ("v1", "v2"):
        for seq in (1, 2):
            src = icra20 / "per-seq" / "odom" / HOME["odom"].format(seq)
            write(tmp_path, f"res/{suite}/odom/{src.name}", src.read_bytes())
    md = tmp_path / "t.md"
    rc, _, _ = compare(capsys, tmp_path / "res", "--markdown", md)
    rows = [line.split("|")[1].strip() for line in md.read_text().splitlines()[2:] if line.startswith("|")]
    assert rc == 0 and rows == ["odom (v1)", "odom (v2)"]


@pytest.mark.thorough
def test_power_with_one_algorithm_and_a_difference_a_rate_cannot_show(icra20, capsys):
    """``compare`` of one algorithm with ``--power`` crashed with a KeyError: the pairs not found
    different were picked from an empty table by an object-dtype column, which pandas took for
    column labels. A difference above 1 of a rate (CR) is refused, from Python too."""
    odom = icra20 / "per-seq" / "odom"
    rc, out, err = compare(capsys, odom, "--power", "0.1")
    assert rc == 0 and "Traceback" not in err
    assert "--power 0.1: no pair sized: no scene has two algorithms with a value to compare" in out
    rc, out, err = compare(capsys, odom, "--power", "2")
    assert rc == 2 and "power delta=2: cr is a rate between 0 and 1" in err
    from lorisnb.tools.decisions.comparison import compare_table

    ev = ln.evaluate(odom, progress=False)
    with pytest.raises(ln.ValidationError, match="a difference above 1 cannot happen"):
        compare_table(ev.sequences(), ev.durations(), "cr_t", power_delta=1.5)
    res = compare_table(ev.sequences(), ev.durations(), "cr", power_delta=0.1)
    assert res.power is not None and res.power.empty and {"scene", "a", "b", "needed"} <= set(res.power.columns)


def test_identical_algorithms_are_said_to_be_identical_not_short_of_trials(tmp_path, icra20, capsys):
    """Two copies of one algorithm: no test can separate them, and the output says so instead of
    "run more trials" (no number of trials would help); their difference prints as +0.000, never
    -0.000."""
    res = tmp_path / "results"
    shutil.copytree(icra20 / "per-seq" / "orbslam2_rgbd", res / "orb")
    shutil.copytree(icra20 / "per-seq" / "orbslam2_rgbd", res / "orb_copy")
    rc, out, err = compare(capsys, res)
    assert rc == 0
    assert "every pair's results are the same on every sequence: no test can separate them" in out + err
    assert "run more trials" not in out + err and "-0.000" not in out


def test_an_rpe_option_for_a_metric_without_rpe_is_named_as_typed(icra20, capsys):
    """``compare --rpe-consecutive`` (stored as rpe_all_pairs=False) was refused as '--rpe-all-pairs'."""
    for typed in ("--rpe-consecutive", "--rpe-all-pairs"):
        rc, _, err = compare(capsys, icra20 / "per-seq" / "odom", typed)
        assert rc == 2 and f"{typed}: the RPE step changes no value of --metric cr" in err, err


def _tester_trials(icra20, root, algorithms=("orbslam2_rgbd", "vins_mono_color_imu_with_loop"), seed=1) -> None:
    """The tester's ``tri/`` folder (mktrials.py): the first four home sequences of each algorithm (of
    five), three trials each with noise on the positions, so each algorithm lacks home-1-5."""
    rng = np.random.default_rng(seed)
    for alg in algorithms:
        for src in sorted((icra20 / "per-seq" / alg).glob("home*"))[:4]:
            for k in (1, 2, 3):
                dst = root / alg / f"run_{k}" / src.name.strip()
                dst.parent.mkdir(parents=True, exist_ok=True)
                lines = []
                for line in src.read_text().splitlines():
                    p = line.split()
                    if len(p) >= 8 and re.fullmatch(r"[0-9.]+", p[0]):
                        for i in range(len(p) - 7, len(p) - 4):
                            p[i] = f"{float(p[i]) + rng.normal(0, 0.02 * k):.6f}"
                        line = " ".join(p)
                    lines.append(line)
                dst.write_text("\n".join(lines) + "\n")


def test_the_notebooks_scene_values_are_compares(tmp_path, icra20, capsys):
    """compare_algorithms (and so a report's compare page) scored only the sequences with output: on the
    tester's tri/ folder (four of five home sequences) orbslam2's CR was 0.0819 in the notebook, 0.077 in
    ``lorisnb compare`` (coverage 4/5). The notebook's function gives compare's numbers: value,
    interval, coverage, rank and the pairwise test."""
    from lorisnb.tools.notebook.comparison import scene_comparison

    res = tmp_path / "tri"
    _tester_trials(icra20, res)
    csv, pairs_csv = tmp_path / "c.csv", tmp_path / "p.csv"
    rc, out, err = compare(capsys, res, "--eps", 0.1, "--phi", 30, "--csv", csv, "--pairs-csv", pairs_csv)
    assert rc == 0 and "4/5" in out and "no output for home sequence(s) 5" in err
    cli = pd.read_csv(csv).set_index(["scene", "algorithm"])
    ev = ln.evaluate(res, ln.make_spec(eps=0.1, phi=30.0), progress=False)
    nb = scene_comparison(ev.sequences(0.1, 30.0, 1.0, 60.0), ev.durations(), "cr")
    mine = nb.ranking.set_index(["scene", "algorithm"]).loc[cli.index]
    for column in ("value", "low", "high", "rank", "sequences_with_output", "scene_sequences"):
        np.testing.assert_allclose(mine[column].to_numpy(float), cli[column].to_numpy(float), rtol=1e-12)
    assert set(mine["covered"]) == {"4/5"}
    assert mine.loc[("home", "orbslam2_rgbd"), "value"] == pytest.approx(0.0771, abs=5e-5)
    pairs = pd.read_csv(pairs_csv)
    np.testing.assert_allclose(nb.pairs["difference"].to_numpy(float), pairs["difference"].to_numpy(float))
    assert any("no output for home sequence(s) 5" in n for n in nb.notes)
    ci = nb.ci[nb.ci["metric"] == "cr"].set_index(["scene", "algorithm"]).loc[cli.index]
    np.testing.assert_allclose(ci["value"].to_numpy(float), cli["value"].to_numpy(float), rtol=1e-12)
