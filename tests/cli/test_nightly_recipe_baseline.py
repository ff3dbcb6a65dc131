"""The nightly recipe of the reports guide: tonight's run is written into the nightly folder, then
``diff --baseline last-comparable nightly results`` judges tonight's results folder. That run was
made after the results it evaluated, so it is no baseline of them; it was taken as one (its twin:
'ok', exit 0, whatever had been lost since the night before). A result folder's time is when its
content last changed (its files' and folders' modification times: a file removed changes its folder)."""

from __future__ import annotations

import os
import shutil
import time

from lorisnb.cli import main

ALGS = ("orbslam2_rgbd", "odom")


def test_tonights_run_of_the_same_results_is_passed_over(icra20, data, tmp_path, capsys):
    results, nightly = tmp_path / "results", tmp_path / "nightly"
    nightly.mkdir()
    for alg in ALGS:
        shutil.copytree(icra20 / "per-seq" / alg, results / alg)
    old = time.time() - 7200
    for p in [results, *results.rglob("*")]:
        os.utime(p, (old, old))
    common = ["--data", str(data.root), "--no-progress"]
    assert main(["evaluate", str(results), *common, "--csv", str(nightly / "2026-01-01.csv")]) == 0
    os.utime(nightly / "2026-01-01.csv", (old + 60, old + 60))  # last night's run, of last night's results
    lost = next((results / "orbslam2_rgbd").glob("market_1_3*"))
    lost.unlink()  # tonight: a sequence lost
    assert main(["evaluate", str(results), *common, "--csv", str(nightly / "2026-01-02.csv")]) == 0
    capsys.readouterr()
    rc = main(["diff", "--baseline", "last-comparable", str(nightly), str(results), *common])
    out, err = capsys.readouterr()
    assert "baseline: " + str(nightly / "2026-01-01.csv") in err, err
    assert "made at or after" in out + err and "2026-01-02.csv" in out + err
    assert rc == 1 and "market-3 missing" in out, out


def _nights(icra20, data, tmp_path):
    """Last night's table (of results with one more sequence), tonight's table of tonight's results
    (a copy of CAND in the nightly folder) and tonight's results folder."""
    results, nightly = tmp_path / "results", tmp_path / "nightly"
    nightly.mkdir()
    for alg in ALGS:
        shutil.copytree(icra20 / "per-seq" / alg, results / alg)
    common = ["--data", str(data.root), "--no-progress"]
    assert main(["evaluate", str(results), *common, "--csv", str(nightly / "2026-01-01.csv")]) == 0
    next((results / "orbslam2_rgbd").glob("market_1_3*")).unlink()
    assert main(["evaluate", str(results), *common, "--csv", str(nightly / "2026-01-02.csv")]) == 0
    old = time.time() - 7200
    os.utime(nightly / "2026-01-01.csv", (old, old))
    return results, nightly, common


def test_results_with_future_times_have_no_time_and_a_copy_is_passed_over(icra20, data, tmp_path, capsys):
    """Results copied with a clock that runs ahead (rsync -a from such a machine): their time is after
    tonight's run of them, which was then taken as the baseline ('ok', exit 0). Their time is unknown
    then, and a run holding every value of CAND is its copy (only then: a system whose reruns are
    alike is compared with its last run, tests/tools/test_nightly_gate.py)."""
    results, nightly, common = _nights(icra20, data, tmp_path)
    ahead = time.time() + 3600
    for p in [results, *results.rglob("*")]:
        os.utime(p, (ahead, ahead))
    capsys.readouterr()
    rc = main(["diff", "--baseline", "last-comparable", str(nightly), str(results), *common])
    out, err = capsys.readouterr()
    assert "is in the future" in err and "baseline: " + str(nightly / "2026-01-01.csv") in err, err
    assert "2026-01-02.csv in " in out + err and "taken as CAND's copy" in out + err
    assert rc == 1 and "market-3 missing" in out, out


def test_results_older_than_every_run_say_why_none_is_a_baseline(icra20, data, tmp_path, capsys):
    """Results restored with old times (tar -x, cp -p): every run is passed over; the error said 'none of
    the 0 run(s) ... (none left)', not that CAND's file times decided it."""
    results, nightly, common = _nights(icra20, data, tmp_path)
    older = time.time() - 10 * 86400
    for p in [results, *results.rglob("*")]:
        os.utime(p, (older, older))
    capsys.readouterr()
    assert main(["diff", "--baseline", "last-comparable", str(nightly), str(results), *common]) == 2
    err = capsys.readouterr().err
    assert "every run in" in err and "modification time of its newest result file" in err and "touch them" in err


def test_an_empty_newest_night_is_damaged_not_passed_over(icra20, data, tmp_path, capsys):
    """A failed --csv or a redirect leaves an empty file: history passed over it as 'no run' and judged
    the older nights (exit 0); a damaged newest night exits 2."""
    _, nightly, _ = _nights(icra20, data, tmp_path)
    (nightly / "2026-01-03.csv").write_bytes(b"")
    assert main(["history", *map(str, sorted(nightly.glob("*.csv")))]) == 2
    assert "2026-01-03.csv" in capsys.readouterr().err
