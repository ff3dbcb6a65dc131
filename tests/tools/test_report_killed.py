"""A report killed outright (``kill -9``: it cannot stop its workers) leaves no process behind: its
notebook workers end once their parent is gone (they finished their notebooks, then waited on the
pool's queue for ever), and their kernels with them."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

psutil = pytest.importorskip("psutil")

pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("notebooks")]


def test_a_report_killed_outright_leaves_no_worker_running(tmp_path, data):
    env = {**os.environ, "LORISNB_DATA": str(data.root)}
    p = subprocess.Popen(
        [sys.executable, "-m", "lorisnb.cli", "report", "--notebooks", "per_sequence_benchmark", "metrics_primer",
         "--jobs", "2", "--out", str(tmp_path / "run"), "--no-progress"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env,
    )  # fmt: skip
    parent = psutil.Process(p.pid)
    try:
        end = time.monotonic() + 120
        while time.monotonic() < end and len(parent.children()) < 3:  # the zygote and two workers
            time.sleep(0.2)
        time.sleep(2)  # the workers' kernels started
        family = parent.children(recursive=True)
        assert len(family) >= 3, family
    finally:
        os.kill(p.pid, signal.SIGKILL)
        p.wait()
    end = time.monotonic() + 30
    alive = family
    while alive and time.monotonic() < end:
        alive = [k for k in alive if running(k)]
        time.sleep(0.2)
    for k in alive:  # never left running by the test itself
        k.kill()
    assert alive == [], [" ".join(k.cmdline())[:100] for k in alive]


def running(process) -> bool:
    try:
        return process.is_running() and process.status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False
