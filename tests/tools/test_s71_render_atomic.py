"""lorisnb render (tester s71): a second render of a run, started while the first one's staged pages
were there, was refused naming them as files "its run did not write ... move them out of it" (which
broke the first); one render at a time now holds a lock in the run folder, and another is told a
render is at work (or that a stopped one left its lock), nothing touched. A render failing while it
moved its pages into place (report.html replaced by a folder) left the run half-rendered (a page
replaced, the marker not: "edited" for ever), naming its temporary file: every place is checked
before anything is written, and a move that still fails puts back what was replaced, naming the
page. A run folder that cannot be written is said, with what to do. A renamed run's pages named the
folder it was written as: render names it as it is named now, its marker listing the page."""

from __future__ import annotations

import errno
import hashlib
import json
import os
import shutil
import socket
import stat
import subprocess
from pathlib import Path
from typing import Any

import pytest
from report_fixtures import fake_notebook

import lorisnb.tools.report.build as report
from lorisnb.cli import main
from lorisnb.errors import LorisError, OutputError
from lorisnb.tools.report.build import RENDER_LOCK, RUN_MARKER, _files, not_as_written, render_run

ORB = "cafe_1_1_orbslam2-original.txt"
ODOM = "cafe-1-2-odom.txt"
NB = "compare_algorithms"


@pytest.fixture(scope="module")
def made(tmp_path_factory, data, icra20):
    """A report run (the real ground truth and two real result files), made once; each test renders
    a copy of it."""
    here = tmp_path_factory.mktemp("lab")
    for alg, src, name in (("orb", "orbslam2_rgbd", ORB), ("odom", "odom", ODOM)):
        (here / "res" / alg).mkdir(parents=True)
        shutil.copy(icra20 / "per-seq" / src / name, here / "res" / alg / name)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(report, "run_notebook", fake_notebook)
        out, _ = report.run_report(here / "runs" / "r1", {"data_root": str(data.root)}, [NB], progress=False,
                                   results=here / "res")  # fmt: skip
    assert not_as_written(out) == []
    return out


@pytest.fixture
def run_dir(made, tmp_path):
    """A copy of the run under its own name, rendered once (its pages as render writes them here)."""
    copy = tmp_path / "r1"
    shutil.copytree(made, copy, symlinks=True)
    render_run(copy)
    assert not_as_written(copy) == []
    return copy


def contents(folder: Path) -> dict[str, str]:
    """Every file and folder below ``folder``, the marker and hidden files too -> its SHA-256."""
    out = {}
    for p in sorted(folder.rglob("*")):
        rel = p.relative_to(folder).as_posix()
        out[rel] = "folder" if p.is_dir() else hashlib.sha256(p.read_bytes()).hexdigest()
    return out


def resign(run: Path) -> None:
    """The marker listing the run's files as they are now (a sender who made the run so)."""
    marker = json.loads((run / RUN_MARKER).read_text())
    marker["files"] = _files(run)
    (run / RUN_MARKER).write_text(json.dumps(marker))


def cli(capsys, *args):
    rc = main([*map(str, args)])
    out = capsys.readouterr()
    return rc, out.out, out.err


def test_a_render_started_while_another_is_at_work_is_told_so_and_breaks_nothing(run_dir, monkeypatch):
    """The second render is started while the first has staged its notebook's page and writes
    report.html (deterministically: from inside the first one's writing)."""
    real = report.single_file
    seen: dict[str, Any] = {}

    def second_render_meanwhile(index, out):
        seen["staged"] = sorted(p.name for p in run_dir.rglob(".*.tmp-*"))
        seen["before"] = contents(run_dir)
        with pytest.raises(LorisError) as second:
            render_run(run_dir)
        seen["error"], seen["after"] = str(second.value), contents(run_dir)
        return real(index, out)

    monkeypatch.setattr(report, "single_file", second_render_meanwhile)
    pages = render_run(run_dir)  # the first render completes
    assert seen["staged"] == [f".{NB}.html.tmp-{os.getpid()}"], seen  # the first one's page, staged
    assert f"another render (pid {os.getpid()}) is at work on it" in str(seen["error"]), seen["error"]
    assert "wait for it to end, then render again" in str(seen["error"])
    assert "move them out" not in str(seen["error"])
    assert seen["after"] == seen["before"]  # nothing touched: its staged page and its lock kept
    assert RENDER_LOCK in seen["before"]
    assert [p.name for p in pages] == [f"{NB}.html", "report.html"]
    assert not_as_written(run_dir) == []  # the first one's pages, listed by its marker
    assert not list(run_dir.rglob(".*.tmp-*")) and not (run_dir / RENDER_LOCK).exists()


def test_a_lock_of_a_running_or_a_stopped_render_is_said_and_kept(run_dir, capsys):
    lock = run_dir / RENDER_LOCK
    sleeper = subprocess.Popen(["sleep", "60"])  # a render at work, by its pid
    try:
        lock.write_text(json.dumps({"pid": sleeper.pid, "host": socket.gethostname()}))
        before = contents(run_dir)
        rc, out, err = cli(capsys, "render", run_dir)
        assert rc == 2 and out == "", err
        assert f"another render (pid {sleeper.pid}) is at work on it; nothing was touched" in err, err
        assert contents(run_dir) == before
    finally:
        sleeper.kill()
        sleeper.wait()
    with pytest.raises(OutputError, match=f"a render \\(pid {sleeper.pid}\\) that is no longer running left its lock"):
        render_run(run_dir)  # said, not removed: it is not this render's
    assert contents(run_dir) == before
    lock.unlink()  # as the message says, once no render is at work
    assert render_run(run_dir) and not_as_written(run_dir) == []


def test_a_page_whose_place_is_a_folder_is_refused_before_any_page_is_replaced(run_dir, capsys):
    (run_dir / "report.html").unlink()
    (run_dir / "report.html").mkdir()
    resign(run_dir)
    before = contents(run_dir)
    rc, _, err = cli(capsys, "render", run_dir)
    assert rc == 2, err
    assert f"error: {run_dir / 'report.html'}: a folder, where render writes the run's report.html" in err, err
    assert ".tmp-" not in err
    assert contents(run_dir) == before and not_as_written(run_dir) == []  # the run as it was, not half rendered
    (run_dir / "report.html").rmdir()  # the folder moved out (the marker as before it was made): rendered
    resign(run_dir)
    assert run_dir / "report.html" in render_run(run_dir) and not_as_written(run_dir) == []


def test_a_move_that_fails_midway_puts_back_the_pages_already_replaced(run_dir, monkeypatch):
    page = run_dir / NB / f"{NB}.html"
    page.write_text("<p>a page of an older nbconvert</p>")  # so that render writes another one
    resign(run_dir)
    before = contents(run_dir)
    real = os.replace

    def failing(src, dst, **kw):
        if Path(dst) == run_dir / "report.html" and ".tmp-" in str(src):
            raise OSError(errno.EIO, os.strerror(errno.EIO), str(src), None, str(dst))
        return real(src, dst, **kw)

    monkeypatch.setattr(os, "replace", failing)
    with pytest.raises(OSError) as failed:
        render_run(run_dir)
    assert failed.value.filename == str(run_dir / "report.html")  # the page, not its temporary file
    assert contents(run_dir) == before  # the notebook's page put back, the marker untouched, nothing left over
    assert not_as_written(run_dir) == []
    monkeypatch.setattr(os, "replace", real)
    render_run(run_dir)
    assert not_as_written(run_dir) == [] and page.read_text() != "<p>a page of an older nbconvert</p>"


def test_a_run_folder_that_cannot_be_written_is_said_with_what_to_do(run_dir, capsys, monkeypatch):
    places = (run_dir, run_dir / NB)
    for where in places:
        where.chmod(0o555)
    if os.geteuid() == 0:  # root writes anywhere: answer as the permissions do for anyone else (a read-only disk)
        real = os.access
        monkeypatch.setattr(os, "access", lambda p, mode, **kw: (not mode & os.W_OK or bool(os.stat(p).st_mode & stat.S_IWUSR)) and real(p, mode, **kw))  # fmt: skip
    try:
        before = contents(run_dir)
        rc, _, err = cli(capsys, "render", run_dir)
        assert rc == 2, err
        assert f"{run_dir} will not be rendered again: the run folder is not writable" in err, err
        assert f"render a copy of it in a writable place (cp -r {run_dir} COPY && lorisnb render COPY)" in err
        assert contents(run_dir) == before
        run_dir.chmod(0o755)  # the run folder writable, its notebook's folder not: named
        with pytest.raises(OutputError, match=f"the run folder cannot be written \\({run_dir / NB}: not writable\\)"):
            render_run(run_dir)
    finally:
        for where in places:
            where.chmod(0o755)


@pytest.mark.parametrize("name", ["renamed", "a <b> & c"])
def test_a_renamed_run_is_named_as_it_is_now_and_stays_as_written(made, tmp_path, name):
    import html

    run = tmp_path / name
    shutil.copytree(made, run, symlinks=True)
    assert "Run folder <code>r1</code>" in (run / "index.html").read_text()
    pages = render_run(run)
    assert run / "index.html" in pages
    for page in ("index.html", "report.html"):
        text = (run / page).read_text()
        assert f"Run folder <code>{html.escape(name)}</code>, written " in text and "<code>r1</code>" not in text
    assert not_as_written(run) == []  # the marker lists the page as render wrote it: verify says nothing
    assert run / "index.html" not in render_run(run)  # named so already: not written again
    assert not_as_written(run) == []


def test_a_run_that_took_another_name_keeps_its_note_until_it_is_renamed(made, tmp_path):
    """A run moved to r1-2 because r1 appeared meanwhile says so; rendered under that name, its page is
    kept as written; renamed, it is named as it is now, the note (moot) gone."""
    run = tmp_path / "r1-2"
    shutil.copytree(made, run, symlinks=True)
    index = run / "index.html"
    note = ("Run folder <code>r1-2</code> (<code>r1</code> appeared while this report ran, another run's: this run "
            "is <code>r1-2</code>), written ")  # fmt: skip
    index.write_text(index.read_text().replace("Run folder <code>r1</code>, written ", note))
    resign(run)
    assert run / "index.html" not in render_run(run) and note in index.read_text()
    assert note in (run / "report.html").read_text()
    moved = run.rename(tmp_path / "kept")
    assert moved / "index.html" in render_run(moved)
    text = (moved / "index.html").read_text()
    assert "Run folder <code>kept</code>, written " in text and "appeared while" not in text
    assert not_as_written(moved) == []
