"""``compare --power`` printed ``-1`` runs needed where the spread is unknown, with no word of why
(a user reads "-1 runs" as nonsense); the command line refused ``--gt`` with ``--manifest`` by a
check of its own, beside the registry of exclusive inputs the notebooks and the report read."""

from __future__ import annotations

import re
import shutil

import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.spec import exclusive
from lorisnb.core.stats.reruns import RerunNoise, rerun
from lorisnb.tools.notebook.params import EXCLUSIVE, check_values

ODOM, ORB = "odom/home-1-{}-odom.txt", "orbslam2_rgbd/home_1_{}_orbslam2-original.txt"


def compare(capsys, *args) -> tuple[int, str, str]:
    rc = main(["compare", *map(str, args), "--no-progress"])
    out = capsys.readouterr()
    return rc, out.out, out.err


def test_power_says_why_no_runs_are_named_for_one_sequence_with_values(tmp_path, icra20, capsys):
    """odom and ORB-SLAM2 on home sequence 2 only, compared by c_ate_rmse: the other four
    sequences count as failed runs, which have no ATE, so one difference is left and its spread is
    unknown. The table said ``needed -1``; it says ``unknown``, a line under it says why, and the
    pairs CSV leaves ``needed`` empty with the reason in ``needed_note``."""
    res = tmp_path / "results"
    for alg, name in (("odom", ODOM), ("orb", ORB)):
        (res / alg).mkdir(parents=True)
        shutil.copy(icra20 / "per-seq" / name.format(2), res / alg)
    pairs_csv = tmp_path / "p.csv"
    rc, out, _ = compare(capsys, res, "--metric", "c_ate_rmse", "--power", "0.05", "--pairs-csv", pairs_csv)
    assert rc == 0
    table = out.split("runs needed to detect a difference of 0.05 in c_ate_rmse")[1]
    assert re.search(r"home\s+odom\s+orb\s+sequences\s+5\s+unknown\n", table), table
    assert not re.search(r"\s-1\b", table), table  # "-1 runs needed"
    # why no pair can be significant: one sequence with values (they differ), not results the same everywhere
    assert ("no pair can reach alpha 0.05 in home (only 1 sequence where two algorithms both have a value of "
            "c_ate_rmse: a test needs two or more)") in out and "the same on every sequence" not in out  # fmt: skip
    assert ("needed unknown for home odom vs orb: the spread is unknown, as 1 of 5 sequence(s) have a value of "
            "c_ate_rmse for both algorithms (a failed or missing run has none) and the spread of the differences "
            "needs two; evaluate more sequences") in table  # fmt: skip
    p = pd.read_csv(pairs_csv, keep_default_na=False).iloc[0]
    assert p["needed"] == "" and p["needed_note"].startswith("the spread is unknown, as 1 of 5 sequence(s)")
    # Python keeps its value (-1: the spread is unknown) and gains the reason
    ev = ln.evaluate(res, progress=False)
    from lorisnb.tools.decisions.comparison import compare_table

    power = compare_table(ev.sequences(), ev.durations(), "c_ate_rmse", power_delta=0.05).power
    assert power is not None and power["needed"].tolist() == [-1]
    assert power["needed_note"].iloc[0] == p["needed_note"]


def test_power_says_which_algorithm_has_one_trial(tmp_path, icra20, capsys):
    """Three reruns of odom against odom's one run, home sequence 2: the trials' spread of the
    single run is unknown. The table said ``needed -1``; it names the algorithm with one trial and
    asks for two; sized pairs beside it keep their numbers (the CSV writes them as whole numbers)."""
    res = tmp_path / "results"
    src = icra20 / "per-seq" / ODOM.format(2)
    rf = ln.read_openloris(src, warn=False)
    for trial in (1, 2, 3):
        dst = res / "odom" / f"trial{trial}" / src.name
        dst.parent.mkdir(parents=True)
        again = {q: rerun(tr, RerunNoise(), 20 + trial + q) for q, tr in rf.sequences.items()}
        ln.write_openloris(dst, again, scene=rf.header["scene"], frame=rf.header["frame"])
    (res / "single").mkdir()
    shutil.copy(src, res / "single")
    pairs_csv = tmp_path / "p.csv"
    rc, out, _ = compare(capsys, res, "--power", "0.05", "--pairs-csv", pairs_csv)
    assert rc == 0
    table = out.split("runs needed to detect a difference of 0.05 in cr")[1]
    assert re.search(r"home\s+odom\s+single\s+trials per sequence\s+1\s+unknown\n", table), table
    assert ("needed unknown for home odom vs single: the spread is unknown, as single has one trial (with a value "
            "of cr) per sequence, which says nothing of how reruns vary; run it at least twice per sequence") in table  # fmt: skip
    p = pd.read_csv(pairs_csv, keep_default_na=False).iloc[0]
    assert p["needed"] == "" and "single has one trial" in p["needed_note"]


def test_power_csv_says_why_pairs_that_differ_are_not_sized(icra20, tmp_path, capsys):
    """Three reruns of odom and of a twin of odom (other seeds) on the five home sequences, beside
    ORB-SLAM2's one run of each: the twins' pair is sized (a whole number, no note; the CSV wrote
    ``12.0`` beside empty cells), the pairs with ORB-SLAM2 differ already (empty ``needed``, the
    note ``differs already``, where the CSV left the empty cell unexplained)."""
    res = tmp_path / "results"
    for seq in range(1, 6):
        src = icra20 / "per-seq" / ODOM.format(seq)
        rf = ln.read_openloris(src, warn=False)
        for alg, base in (("odom", 0), ("twin", 1000)):
            for trial in (1, 2, 3):
                dst = res / alg / f"trial{trial}" / src.name
                dst.parent.mkdir(parents=True, exist_ok=True)
                again = {q: rerun(tr, RerunNoise(), base + 10 * seq + trial + q) for q, tr in rf.sequences.items()}
                ln.write_openloris(dst, again, scene=rf.header["scene"], frame=rf.header["frame"])
        (res / "orb").mkdir(exist_ok=True)
        shutil.copy(icra20 / "per-seq" / ORB.format(seq), res / "orb")
    pairs_csv = tmp_path / "p.csv"
    rc, out, _ = compare(capsys, res, "--power", "0.05", "--pairs-csv", pairs_csv)
    assert rc == 0 and "unknown" not in out.split("runs needed")[1]
    p = pd.read_csv(pairs_csv, keep_default_na=False, dtype=str).set_index(["a", "b"])
    assert p.loc[("odom", "twin"), "significant"] == "False"
    assert p.loc[("odom", "twin"), "needed"].isdigit() and p.loc[("odom", "twin"), "needed_note"] == ""
    for pair in (("odom", "orb"), ("orb", "twin")):
        assert p.loc[pair, "significant"] == "True"
        assert p.loc[pair, "needed"] == "" and p.loc[pair, "needed_note"] == "differs already"


def test_command_line_refuses_exclusive_options_from_the_one_registry(tmp_path, tum_folder, capsys, monkeypatch):
    """The command line's refusal of --gt with --manifest is the registry's entry, as the
    notebooks' is; a pair added to the registry is refused by the command line too (before any
    input is read: exit 2)."""
    est, gt = tum_folder / "fr2_desk_ORB.txt", tum_folder / "fr2_desk_groundtruth.txt"
    assert main(["evaluate", str(est), "--gt", str(gt), "--manifest", "tum-fr1-office"]) == 2
    assert ("--gt and --manifest: give one (a manifest names the ground truth of each session)"
            in capsys.readouterr().err)  # fmt: skip
    # the notebooks' parameters are the registry's, with its options named
    assert EXCLUSIVE == [(*e.names, f"{e.options[0]} and {e.options[1]} on the command line; {e.why}")
                         for e in exclusive.EXCLUSIVE_INPUTS]  # fmt: skip
    with pytest.raises(ln.ValidationError, match=r"give one \(--gt and --manifest on the command line; a manifest"):
        check_values({"groundtruth": str(gt), "manifest": "tum-fr1-office"}, ["evaluate_my_results"])
    added = exclusive.Exclusive(("groundtruth", "t_offset"), ("--gt", "--t-offset"), "a test's pair")
    monkeypatch.setattr(exclusive, "EXCLUSIVE_INPUTS", (*exclusive.EXCLUSIVE_INPUTS, added))
    assert main(["evaluate", str(est), "--gt", str(gt), "--t-offset", "0.5"]) == 2
    assert "--gt and --t-offset: give one (a test's pair)" in capsys.readouterr().err
    monkeypatch.undo()
    assert main(["evaluate", str(est), "--gt", str(gt), "--t-offset", "0.5", "--no-progress"]) == 0
