"""A report's kernels keep their connection files (each holds its kernel's key) and ipc sockets in
one private folder that the report removes when it ends, also when it is interrupted and the
kernels could not remove their own (Ctrl-C, SIGTERM)."""

from __future__ import annotations

import asyncio
import os
import shutil
import tempfile
import time
from pathlib import Path

import pytest

from lorisnb.cli import main
from lorisnb.tools.report import build as report
from lorisnb.tools.report import notebooks as report_notebooks


@pytest.mark.skipif(os.name != "posix", reason="ipc sockets: POSIX")
def test_interrupted_report_leaves_no_kernel_files(tmp_path, monkeypatch, capsys):
    # a short temporary folder of its own (a test runner's deep tmp_path would be too long for the
    # kernels' ipc sockets, which then go to /tmp: test_a_deep_temporary_folder_puts_sockets_in_tmp)
    tmp = Path(tempfile.mkdtemp(prefix="lk-", dir="/tmp" if os.name == "posix" else None))
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))  # Jupyter's and lorisnb's temporary files go here
    seen: dict[str, list[str]] = {}
    managers = []

    def run(name, out_dir, parameters, timeout=1800, notebooks_dir=None):
        km = report_notebooks.kernel_manager_class()(kernel_name="python3")
        managers.append(km)
        asyncio.run(km.start_kernel(extra_arguments=report_notebooks.KERNEL_ARGS))
        deadline = time.monotonic() + 60  # the kernel binds its sockets (seconds on a loaded machine: a fixed
        while True:  # second was too short there, and sockets bound after the interrupt's clean-up stayed)
            seen["files"] = sorted(str(p.relative_to(tmp)) for p in tmp.rglob("*"))
            if (
                sum("kernel-" in f and not f.endswith(".json") for f in seen["files"]) >= 5
                or time.monotonic() > deadline
            ):
                break
            time.sleep(0.1)
        raise KeyboardInterrupt  # Ctrl-C while the notebook runs: its kernel is not shut down

    monkeypatch.setattr(report, "run_notebook", run)
    try:
        rc = main(["report", "--out", str(tmp_path / "run"), "--notebooks", "metrics_primer", "--no-progress"])
    finally:
        for km in managers:
            if km.provisioner is not None and km.provisioner.process is not None:
                km.provisioner.process.kill()
            km.context.destroy(linger=0)
    assert rc == 130
    assert any(f.endswith(".json") for f in seen["files"]), seen  # the connection file was there ...
    assert sum("kernel-" in f and not f.endswith(".json") for f in seen["files"]) >= 5, seen  # ... sockets
    try:
        assert list(tmp.iterdir()) == []  # ... and nothing is left
        assert [p.name for p in tmp_path.iterdir()] == []
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def test_a_deep_temporary_folder_puts_sockets_in_tmp(tmp_path, monkeypatch):
    """A TMPDIR too deep for an ipc socket's path (108 bytes): the kernels' files go to /tmp, and a
    kernel starts (it failed with "File name too long")."""
    deep = tmp_path / ("d" * 60) / ("e" * 40)
    deep.mkdir(parents=True)
    monkeypatch.setattr(tempfile, "tempdir", str(deep))
    with report_notebooks.kernel_files() as folder:
        assert os.path.dirname(folder) == ("/tmp" if os.name == "posix" else str(deep))
        km = report_notebooks.kernel_manager_class()(kernel_name="python3")
        asyncio.run(km.start_kernel(extra_arguments=report_notebooks.KERNEL_ARGS))
        try:
            assert asyncio.run(km.is_alive())
        finally:
            asyncio.run(km.shutdown_kernel(now=True))
    assert not os.path.exists(folder)


def test_kernel_files_go_to_the_report_folder_and_only_there(tmp_path, monkeypatch):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    km = report_notebooks.kernel_manager_class()(kernel_name="python3")
    assert km.connection_file == ""  # outside a report: Jupyter's own temporary file
    with report_notebooks.kernel_files() as folder:
        km = report_notebooks.kernel_manager_class()(kernel_name="python3")
        assert os.path.dirname(km.connection_file) == folder
        if os.name == "posix":
            assert os.path.dirname(km.ip) == folder
        assert oct(os.stat(folder).st_mode & 0o777) == "0o700"
        mine = tmp_path / "mine.json"
        mine.write_text("not the report's")
    assert not os.path.exists(folder) and mine.read_text() == "not the report's"
