"""One rule decides whether two runs are comparable, for ``diff``, ``history`` and ``diff --baseline
last-comparable`` (:func:`lorisnb.tools.decisions.history.comparability`): a lorisnb version change
between two report runs made ``history`` exit 2 while ``diff`` of the same runs noted it and exited
0. A result folder ``diff`` scores records the running lorisnb's version and its ground truth's
checksums, so ``--baseline last-comparable`` checks them (it said "not checked ... a table holds
neither" of a result folder)."""

from __future__ import annotations

import json
import shutil
from functools import partial

import pytest
from helpers import run_cli

import lorisnb
from lorisnb.io.writers import write_csv
from lorisnb.tools.decisions.runs import DURATIONS, FIRST_TABLE
from lorisnb.tools.report.provenance import KEYS, sha256

run = partial(run_cli, joined=True)

ODOM = ("cafe-1-1-odom.txt", "cafe-1-2-odom.txt", "home-1-1-odom.txt")  # as conftest.ODOM


@pytest.fixture(scope="module")
def table(odom_sequences):
    return odom_sequences.copy()


def night(folder, table, created, version=lorisnb.__version__, inputs=None):
    """A report run as lorisnb report writes it, made at ``created`` by lorisnb ``version``."""
    (folder / "findings").mkdir(parents=True)
    write_csv(table, folder / FIRST_TABLE)
    write_csv(table[["scene", "seq", "gt_duration"]], folder / DURATIONS)
    values = {**json.loads(table["spec"].iloc[0]), "eps": "inf", "phi": "inf", "delta": 1.0, "tau": 60.0}
    meta = {k: None for k in KEYS} | {"command": ["lorisnb", "report"], "lorisnb_version": version,
                                      "created": created, "inputs": inputs or {}, "notebooks": {},
                                      "spec": {"description": "d", "values": {**values, "source": "{results}"}}}  # fmt: skip
    (folder / "run.json").write_text(json.dumps(meta))
    return folder


def test_diff_refuses_runs_of_two_lorisnb_versions_as_history_does(tmp_path, table, capsys):
    old = night(tmp_path / "old", table, "2026-12-01T03:00:00+00:00", version="0.1.0")
    new = night(tmp_path / "new", table, "2026-12-02T03:00:00+00:00")
    rc, out, err = run(capsys, "history", old, new)
    assert rc == 2 and f"(lorisnb_version 0.1.0 -> {lorisnb.__version__})" in out
    rc, out, err = run(capsys, "diff", old, new)
    assert rc == 2, err  # it was 0, with "note: lorisnb 0.1.0 made BASE, 0.3.0 CAND"
    assert ("BASE and CAND are not comparable (made by another lorisnb version or against another ground truth): "
            f"lorisnb_version 0.1.0 -> {lorisnb.__version__}. Compare runs made with the same spec, lorisnb version "
            "and ground truth") in err  # fmt: skip
    assert "verdict" not in out
    # the same version: compared
    same = night(tmp_path / "same", table, "2026-12-01T03:00:00+00:00")
    rc, out, err = run(capsys, "diff", same, new)
    assert rc == 0, err


def test_a_result_folder_cand_records_its_version_and_ground_truth(tmp_path, table, icra20, data, capsys):
    res = tmp_path / "res" / "odom"
    res.mkdir(parents=True)
    for f in ODOM:
        shutil.copy(icra20 / "per-seq" / "odom" / f, res / f)
    gt = {f"{{data}}/openloris-scene/groundtruth/gt_{s}_1.txt": sha256(data.groundtruth(s)) for s in ("cafe", "home")}
    folder = tmp_path / "nightly"
    folder.mkdir()
    night(folder / "a", table, "2000-01-01T03:00:00+00:00", inputs=gt)
    rc, out, err = run(capsys, "diff", "--baseline", "last-comparable", folder, res.parent, "--no-progress")
    assert rc == 0, err
    assert "comparable with CAND: checked: the spec and thresholds their tables record, lorisnb version, " \
           "ground-truth checksums)" in err  # fmt: skip
    assert "a table holds neither" not in err
    # another lorisnb made the only earlier run: none is comparable (exit 2), the version named
    shutil.rmtree(folder / "a")
    night(folder / "a", table, "2000-01-01T03:00:00+00:00", version="0.1.0", inputs=gt)
    rc, out, err = run(capsys, "diff", "--baseline", "last-comparable", folder, res.parent, "--no-progress")
    assert rc == 2 and f"lorisnb_version 0.1.0 -> {lorisnb.__version__}" in err
    # another ground truth: named
    shutil.rmtree(folder / "a")
    night(folder / "a", table, "2000-01-01T03:00:00+00:00", inputs={k: "0" * 64 for k in gt})
    rc, out, err = run(capsys, "diff", "--baseline", "last-comparable", folder, res.parent, "--no-progress")
    assert rc == 2 and "ground truth changed: gt_cafe_1.txt, gt_home_1.txt" in err
    # a run that records no checksum: said of it, with why (not "a table")
    shutil.rmtree(folder / "a")
    night(folder / "a", table, "2000-01-01T03:00:00+00:00")
    rc, out, err = run(capsys, "diff", "--baseline", "last-comparable", folder, res.parent, "--no-progress")
    assert rc == 0, err
    assert "not checked: ground-truth checksums (not recorded by a: its run.json records none)" in err


def test_a_table_baseline_says_a_table_records_neither(tmp_path, table, icra20, capsys):
    res = tmp_path / "res" / "odom"
    res.mkdir(parents=True)
    for f in ODOM:
        shutil.copy(icra20 / "per-seq" / "odom" / f, res / f)
    folder = tmp_path / "nightly"
    folder.mkdir()
    write_csv(table, folder / "2000-01-01.csv")
    import os

    os.utime(folder / "2000-01-01.csv", (9.5e8, 9.5e8))
    rc, out, err = run(capsys, "diff", "--baseline", "last-comparable", folder, res.parent, "--no-progress")
    assert rc == 0, err
    assert ("not checked: lorisnb version and ground-truth checksums (not recorded by 2000-01-01.csv: a table records "
            "no lorisnb version and no ground-truth checksum)") in err  # fmt: skip
