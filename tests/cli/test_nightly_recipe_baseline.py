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
