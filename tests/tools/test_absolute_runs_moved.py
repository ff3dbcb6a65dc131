"""A run made with ``--absolute-paths`` names its inputs by absolute paths of the machine it was
made on, and records in run.json's ``roots`` each root's folder there: verify reads a key below a
recorded root below the folder given here for that root (``--data``, ``--results``, ``--root
NAME``), so the run verifies once moved; a key below no recorded root is refused saying why."""

from __future__ import annotations

import json
import shutil

from helpers import run_cli as run

ORB = "cafe_1_1_orbslam2-original.txt"
ODOM = "cafe-1-1-odom.txt"


def fake_notebook(name, out_dir, params, **kw):
    """A notebook run standing for papermill's (fast)."""
    from lorisnb.tools.report.notebooks import NotebookRun

    (out_dir / name).mkdir()
    (out_dir / name / f"{name}.ipynb").write_text(json.dumps({"cells": [], "metadata": {}, "nbformat": 4}))
    (out_dir / name / f"{name}.html").write_text(f"<pre>{params.get('results_dir')}</pre>")
    return NotebookRun(name)


def test_a_moved_absolute_paths_run_verifies_below_the_folders_given_for_its_recorded_roots(
    tmp_path, data, icra20, monkeypatch, capsys
):
    import lorisnb.tools.report.build as report

    first = tmp_path / "made-here"
    for alg, src, name in (("orb", "orbslam2_rgbd", ORB), ("odom", "odom", ODOM)):
        (first / "res" / alg).mkdir(parents=True)
        shutil.copy(icra20 / "per-seq" / src / name, first / "res" / alg / name)
    shutil.copytree(data.root / "openloris-scene", first / "data" / "openloris-scene")
    monkeypatch.setattr(report, "run_notebook", fake_notebook)
    rc, _, err = run(capsys, "report", "--results", first / "res", "--data", first / "data", "--out", first / "r",
                     "--notebooks", "compare_algorithms", "--no-progress", "--absolute-paths")  # fmt: skip
    assert rc == 0, err
    record = json.loads((first / "r" / "run.json").read_text())
    was = first.resolve()
    assert record["roots"] == {"data": str(was / "data"), "results": str(was / "res")}
    orb_key = str(was / "res" / "orb" / ORB)
    assert orb_key in record["inputs"] and str(was / "res") in record["input_roots"]
    assert len(record["inputs"]) == 7

    second = tmp_path / "elsewhere" / "moved-there"
    second.parent.mkdir()
    shutil.move(first, second)
    r = second / "r"
    roots = ["--data", second / "data", "--results", second / "res"]
    for given in (r, r / "run.json"):
        rc, out, err = run(capsys, "verify", given, *roots)
        assert (rc, out) == (0, "") and "all 7 input file(s) unchanged" in err, err

    orb = second / "res" / "orb" / ORB
    text = orb.read_text()
    orb.write_text(text.replace(text.splitlines()[-1], text.splitlines()[-1] + "0", 1))
    rc, out, _ = run(capsys, "verify", r, *roots)
    assert rc == 1 and out == f"changed: {orb_key}\n"  # named as run.json names it
    orb.write_text(text)
    shutil.copy(orb, second / "res" / "orb" / "again.txt")  # a file added to a folder the run read
    rc, out, err = run(capsys, "verify", r, *roots)
    assert rc == 1 and out == f"added: {was / 'res' / 'orb' / 'again.txt'}\n", err
    (second / "res" / "orb" / "again.txt").unlink()

    rc, _, err = run(capsys, "verify", r, "--data", second / "data")  # the results folder not given
    assert rc == 2
    assert "by an absolute path of the machine the run was made on (a run made with --absolute-paths)" in err
    assert f"below its root {{results}} ({was / 'res'}); say where that root is here with --results DIR" in err

    record["inputs"]["/elsewhere/entirely/x.txt"] = record["inputs"][orb_key]  # below no root it records
    (r / "run.json").write_text(json.dumps(record))
    rc, _, err = run(capsys, "verify", r, *roots)
    assert rc == 2 and "error: /elsewhere/entirely/x.txt: run.json names a file outside the run folder" in err
    assert "below none of the roots it records" in err and "without --absolute-paths" in err
