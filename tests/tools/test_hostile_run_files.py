"""A run folder received from elsewhere may hold what no run lorisnb writes holds: a FIFO (tar
keeps them), a device, a marker that is a link leading out of it. verify and render refuse each,
naming it, never opened (a FIFO would block them for ever, a device read without end); and
``verify RUN/run.json`` checks the run's own files as ``verify RUN`` does."""

from __future__ import annotations

import json
import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from lorisnb.cli import main

ORB = "cafe_1_1_orbslam2-original.txt"
ODOM = "cafe-1-1-odom.txt"
NOT_REGULAR = "not a regular file (a FIFO, a device): a run folder lorisnb writes holds none"


def fake_notebook(name, out_dir, params, **kw):
    """A notebook run standing for papermill's (fast): its notebook, page and figure in its folder."""
    from lorisnb.tools.report.notebooks import NotebookRun

    folder = out_dir / name
    folder.mkdir()
    nb = {"cells": [], "metadata": {}, "nbformat": 4, "nbformat_minor": 5}
    (folder / f"{name}.ipynb").write_text(json.dumps(nb))
    (folder / f"{name}.html").write_text(f"<pre>{name}</pre>")
    (folder / f"{name}_ate.png").write_bytes(b"\x89PNG\r\n\x1a\n")
    return NotebookRun(name)


@pytest.fixture(scope="module")
def made(tmp_path_factory, data, icra20):
    """A lab (two real icra20 results, the real ground truth) and a report run of it."""
    import lorisnb.tools.report.build as report

    here = tmp_path_factory.mktemp("lab")
    for alg, src, name in (("orb", "orbslam2_rgbd", ORB), ("odom", "odom", ODOM)):
        (here / "res" / alg).mkdir(parents=True)
        shutil.copy(icra20 / "per-seq" / src / name, here / "res" / alg / name)
    shutil.copytree(data.root / "openloris-scene", here / "data" / "openloris-scene")
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(report, "run_notebook", fake_notebook)
        rc = main(["report", "--results", str(here / "res"), "--data", str(here / "data"), "--out",
                   str(here / "run"), "--notebooks", "compare_algorithms", "--no-progress"])  # fmt: skip
    assert rc == 0
    return here


def copy_run(made: Path, tmp_path: Path) -> Path:
    run = tmp_path / "received"
    shutil.copytree(made / "run", run, symlinks=True)
    return run


def roots(made: Path) -> list[str]:
    return ["--data", str(made / "data"), "--results", str(made / "res")]


def lorisnb(*args: str, timeout: float = 60) -> subprocess.CompletedProcess:
    """``lorisnb ARGS`` through :func:`lorisnb.cli.main` in a process of its own, ended if it blocks."""
    code = "import sys; from lorisnb.cli import main; sys.exit(main(sys.argv[1:]))"
    try:
        return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        pytest.fail(f"lorisnb {' '.join(args[:2])} still ran after {timeout} s: it blocked on a file of the run")


def test_verify_given_run_json_checks_the_runs_own_files_as_given_its_folder(made, tmp_path, capsys):
    run = copy_run(made, tmp_path)
    rc, out = main(["verify", str(run), *roots(made)]), capsys.readouterr()
    assert rc == 0 and "all 7 input file(s) unchanged" in out.err, out.err
    rc, out = main(["verify", str(run / "run.json"), *roots(made)]), capsys.readouterr()
    assert rc == 0 and "marker lists no files" not in out.err, out.err
    board = run / "findings" / "leaderboard.csv"
    text = board.read_text()
    assert ",cafe,1,orb,cr,0.38753386857201266," in text and ",cafe,1,odom,cr,0.38740472762085815," in text
    board.write_text(text.replace(",orb,cr,0.3875", ",orb,cr,0.9875"))  # the leaderboard's orb made better
    said = []
    for given in (run, run / "run.json"):
        rc, out = main(["verify", str(given), *roots(made)]), capsys.readouterr()
        assert rc == 1, out.err
        assert out.out.strip() == f"edited: {run / 'findings' / 'leaderboard.csv'}"
        assert "marker lists no files" not in out.err and "1 file(s) of the run itself" in out.err
        said.append((out.out, out.err))
    assert said[0] == said[1]


# what a FIFO in each place blocked for ever: verify on the marker, pages, notebooks, tables, figures;
# render on run.json (hashed with the run's files) and the same
PLACES = [
    ("verify", ".lorisnb-run"),
    ("verify", "run.json"),
    ("verify", "index.html"),
    ("verify", "compare_algorithms/compare_algorithms.ipynb"),
    ("verify", "compare_algorithms/compare_algorithms_ate.png"),
    ("verify", "findings/leaderboard.csv"),
    ("render", "run.json"),
    ("render", ".lorisnb-run"),
    ("render", "index.html"),
    ("render", "compare_algorithms/compare_algorithms.ipynb"),
    ("render", "compare_algorithms/compare_algorithms_ate.png"),
    ("render", "findings/leaderboard.csv"),
]


@pytest.mark.parametrize("command,rel", PLACES)
def test_a_fifo_in_a_received_run_is_refused_naming_it_never_waited_on(made, tmp_path, command, rel):
    run = copy_run(made, tmp_path)
    assert (run / rel).is_file()
    before = {p.relative_to(run): p.read_bytes() for p in run.rglob("*") if p.is_file() and p != run / rel}
    (run / rel).unlink()
    os.mkfifo(run / rel)
    p = lorisnb(command, str(run), *(roots(made) if command == "verify" else []))
    assert p.returncode == 2, p.stdout + p.stderr
    assert p.stderr.strip() == f"error: {run / rel}: {NOT_REGULAR} (a received run?); it was not read. Remove it, " \
                               "or copy the run again from where it came"  # fmt: skip
    assert stat.S_ISFIFO(os.lstat(run / rel).st_mode)  # left as it is, and nothing else written
    assert {p.relative_to(run): p.read_bytes() for p in run.rglob("*") if p.is_file() and p != run / rel} == before


@pytest.mark.skipif(not hasattr(os, "mknod") or os.geteuid() != 0, reason="making a device takes root")
@pytest.mark.parametrize("command", ["verify", "render"])
@pytest.mark.parametrize("rel", [".lorisnb-run", "notebook.css", "compare_algorithms/compare_algorithms_ate.png"])
def test_a_device_in_a_received_run_is_refused_never_read_without_end(made, tmp_path, command, rel):
    run = copy_run(made, tmp_path)
    (run / rel).unlink()
    os.mknod(run / rel, 0o644 | stat.S_IFCHR, os.makedev(1, 5))  # /dev/zero
    p = lorisnb(command, str(run), *(roots(made) if command == "verify" else []))
    assert p.returncode == 2 and "Traceback" not in p.stderr and "MemoryError" not in p.stderr, p.stderr
    assert p.stderr.startswith(f"error: {run / rel}: {NOT_REGULAR}"), p.stderr


@pytest.mark.parametrize("command", ["verify", "render"])
def test_a_marker_that_is_a_link_leading_out_of_the_run_is_refused_by_verify_as_by_render(
    made, tmp_path, command, capsys
):
    run = copy_run(made, tmp_path)
    secret = tmp_path / "secret.txt"
    secret.write_text(json.dumps({"files": {}, "who": "root:x:0:0:root:/root:/bin/bash"}))
    (run / ".lorisnb-run").unlink()
    (run / ".lorisnb-run").symlink_to(secret)
    rc = main([command, str(run), *(roots(made) if command == "verify" else [])])
    out = capsys.readouterr()
    assert rc == 2, out.out + out.err
    assert f"error: {run / '.lorisnb-run'}: a link leading outside the run folder" in out.err
    assert "root:x" not in out.out + out.err and str(secret) not in out.out + out.err
    assert "marker lists no files" not in out.err
