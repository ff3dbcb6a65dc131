"""A report's kernels forked from a zygote (lorisnb.tools.report.kernels) are the kernels Jupyter
would have launched: the same facts seen from inside (argv, folder, path, environment, process
group, pandas' display width, tqdm's bar, matplotlib's backend, warnings filters), a fresh random
state each, interrupts, shutdown, the end of the kernel with its manager; and kernels are
launched as usual where the zygote cannot fork them. The facts are compared once the kernel has
imported what the zygote preloads (every lorisnb notebook does, through seaborn): before that, a
forked kernel differs only in having those modules, and their warnings filters, already."""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import signal
import socket
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

pytest.importorskip("ipykernel")
pytest.importorskip("jupyter_client")

from lorisnb.tools.report import kernels as warm_kernels
from lorisnb.tools.report.notebooks import KERNEL_ARGS, kernel_manager_class, warm_kernels_for_report  # noqa: E402

pytestmark = pytest.mark.skipif(not warm_kernels.supported(), reason="forking kernels needs Linux")

FACTS = textwrap.dedent(
    """
    import json, os, sys, threading, warnings
    import numpy as np, pandas as pd, matplotlib, scipy.stats, tqdm.auto  # what lorisnb's notebooks import
    import matplotlib.pyplot as plt
    plt.close(plt.figure())  # pyplot chooses its backend and display hook at its first figure
    print(json.dumps({
        "argv": [os.path.basename(sys.argv[0])] + [a for a in sys.argv[1:] if not a.endswith(".json")],
        "executable": sys.executable, "flags": list(sys.flags),
        "cwd": os.getcwd(), "path": sys.path[:3],
        "env": {k: v for k, v in os.environ.items() if not k.startswith("JPY_")},
        "parent_pid_set": "JPY_PARENT_PID" in os.environ,
        "own_group": os.getpgid(0) == os.getpid() == os.getsid(0),
        "max_columns": pd.get_option("display.max_columns"),
        "tqdm": tqdm.auto.tqdm.__module__,
        "backend": matplotlib.get_backend(),
        "interactive": matplotlib.is_interactive(),
        "rcparams": {k: repr(v) for k, v in matplotlib.rcParams.items()},
        "displayhook": plt._REPL_DISPLAYHOOK.name,
        "post_execute": sorted(getattr(f, "__qualname__", repr(f)) for f in get_ipython().events.callbacks["post_execute"]),
        "warnings": sorted(map(str, warnings.filters)),
        "main": type(sys.modules["__main__"]).__name__,
        "threads": sorted(type(t).__name__ if t.name.startswith("Thread-") else t.name for t in threading.enumerate()),
        "random": float(np.random.random()),
        "pid": os.getpid(),
    }))
    """
)


@contextlib.asynccontextmanager
async def _kernel(cwd: Path, now: bool = False):
    """A kernel started by the report's kernel manager in ``cwd``, ready: (manager, client)."""
    km = kernel_manager_class()(kernel_name="python3")
    await km.start_kernel(extra_arguments=KERNEL_ARGS, cwd=str(cwd))
    kc = km.client()
    kc.start_channels()
    try:
        await kc.wait_for_ready(timeout=60)
        yield km, kc
    finally:
        kc.stop_channels()
        await km.shutdown_kernel(now=now)


async def _facts(cwd: Path) -> tuple[dict, object]:
    """What a kernel started by the report's kernel manager says about itself, and its process handle."""
    async with _kernel(cwd) as (km, kc):
        out: list[str] = []
        reply = await kc.execute_interactive(
            FACTS, timeout=60, output_hook=lambda m: out.append(m["content"].get("text", ""))
        )
        assert reply["content"]["status"] == "ok", reply["content"]
        return json.loads("".join(out)), km.provisioner.process


def _kernels(cwd: Path, zygote) -> list[tuple[dict, object]]:
    warm_kernels.use(zygote)
    try:
        return [asyncio.run(_facts(cwd)) for _ in range(2)]
    finally:
        warm_kernels.use(None)


@pytest.mark.thorough
def test_a_forked_kernel_is_the_kernel_jupyter_launches(tmp_path):
    from lorisnb.tools.report.notebooks import kernel_env

    kernel_env()
    (launched, launched_proc), _ = _kernels(tmp_path, None)
    assert isinstance(launched_proc, subprocess.Popen)
    with warm_kernels_for_report() as zygote:
        assert zygote is not None
        forked = _kernels(tmp_path, zygote)
    for facts, proc in forked:
        assert isinstance(proc, warm_kernels.Forked)
        assert proc.returncode == 0  # shut down, status reported by the zygote
        for key in launched:
            if key not in ("random", "pid", "threads"):
                assert facts[key] == launched[key], key
        # the launched kernel's parent poller watches its manager; the forked one's watcher does
        assert set(facts["threads"]) - {"lorisnb-manager-watch"} == set(launched["threads"]) - {"ParentPollerUnix"}
        assert "lorisnb-manager-watch" in facts["threads"] and "ParentPollerUnix" in launched["threads"]
    assert launched["parent_pid_set"] and launched["own_group"] and launched["cwd"] == str(tmp_path)
    assert forked[0][0]["random"] != forked[1][0]["random"]  # each kernel seeded afresh
    assert forked[0][0]["pid"] != forked[1][0]["pid"]


@pytest.mark.thorough
def test_interrupt_and_shutdown_of_a_forked_kernel(tmp_path):
    from lorisnb.tools.report.notebooks import kernel_env

    kernel_env()  # this process's environment as a report's (the zygote is started in it): as the test above

    async def run(zygote):
        warm_kernels.use(zygote)
        try:
            async with _kernel(tmp_path, now=True) as (km, kc):  # now: SIGKILL to its process group
                assert isinstance(km.provisioner.process, warm_kernels.Forked), (zygote, warm_kernels.refusal())
                pid = km.provisioner.process.pid
                kc.execute("import time; time.sleep(120)")
                await asyncio.sleep(1.0)
                t = time.monotonic()
                await km.interrupt_kernel()
                reply = await kc.get_shell_msg(timeout=20)
                assert reply["content"]["ename"] == "KeyboardInterrupt" and time.monotonic() - t < 20
                assert await km.is_alive()
        finally:
            warm_kernels.use(None)
        assert not await km.is_alive()
        assert km.provisioner is None or km.provisioner.process is None
        return pid

    with warm_kernels_for_report() as zygote:
        pid = asyncio.run(run(zygote))
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)


MANAGER = textwrap.dedent(
    """
    import asyncio, json, os, sys, time
    from lorisnb.tools.report import kernels as warm_kernels
    from lorisnb.tools.report.notebooks import KERNEL_ARGS, kernel_files, kernel_manager_class
    z = json.loads(sys.argv[1])
    warm_kernels.use(warm_kernels.Zygote(z["address"], tuple(z["interpreter"]), tuple(map(tuple, z["env"]))))
    async def main(folder):
        km = kernel_manager_class()(kernel_name="python3")
        await km.start_kernel(extra_arguments=KERNEL_ARGS)
        assert isinstance(km.provisioner.process, warm_kernels.Forked)
        kc = km.client()
        kc.start_channels()
        await kc.wait_for_ready(timeout=120)  # its sockets bound
        print(json.dumps({"pid": km.provisioner.process.pid, "folder": folder, "files": os.listdir(folder)}), flush=True)
        time.sleep(600)
    with kernel_files() as folder:  # as a report's kernels
        asyncio.run(main(folder))
    """
)


@pytest.mark.thorough
def test_a_forked_kernel_ends_with_the_process_managing_it(tmp_path):
    """A launched kernel's parent poller ends it when its manager dies; a forked one's watcher does,
    and first removes its connection file and sockets, and the report's kernel folder (kill -9 left
    them in the temporary folder: nothing else would remove them)."""
    from lorisnb.tools.report.notebooks import kernel_environ

    with warm_kernels_for_report() as zygote:
        assert zygote is not None
        arg = json.dumps({"address": zygote.address, "interpreter": zygote.interpreter, "env": zygote.env})
        manager = subprocess.Popen([sys.executable, "-c", MANAGER, arg], stdout=subprocess.PIPE, text=True,
                                   env=kernel_environ(os.environ), cwd=tmp_path)  # fmt: skip
        try:
            started = json.loads(manager.stdout.readline())
            pid, folder = started["pid"], started["folder"]
            assert sum(f.endswith(".json") for f in started["files"]) == 1 and len(started["files"]) == 6, started
            os.kill(pid, 0)  # the kernel runs
            manager.send_signal(signal.SIGKILL)
            manager.wait()
            deadline = time.monotonic() + 15
            while time.monotonic() < deadline:
                try:
                    os.kill(pid, 0)
                except ProcessLookupError:
                    break
                time.sleep(0.1)
            else:
                pytest.fail(f"kernel {pid} outlived its manager")
            assert not os.path.exists(folder), os.listdir(folder)
        finally:
            manager.kill()


@pytest.mark.thorough
def test_the_zygote_ends_with_the_report(tmp_path):
    """Killed with the report (kill -9, no clean-up), the zygote ends by itself within seconds."""
    code = textwrap.dedent(
        """
        import os, sys, time
        from lorisnb.tools.report.notebooks import warm_kernels_for_report
        with warm_kernels_for_report() as z:
            print(z.address, flush=True)
            time.sleep(600)
        """
    )
    report = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True, cwd=tmp_path)
    address = report.stdout.readline().strip()
    deadline = time.monotonic() + 60
    while not os.path.exists(address) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert os.path.exists(address)
    report.send_signal(signal.SIGKILL)
    report.wait()
    deadline = time.monotonic() + 20
    while os.path.exists(address) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not os.path.exists(address), "the zygote outlived the report"
    assert not os.path.exists(os.path.dirname(address))  # nor its folder


def test_what_the_zygote_forks():
    env = {"PATH": os.path.dirname(sys.executable), "HOME": "/root"}
    z = warm_kernels.Zygote("/nowhere", (sys.executable,), warm_kernels._own(env))
    argv = [sys.executable, "-m", "ipykernel_launcher", "-f", "k.json"]
    assert z.forks(argv, {**env, "JPY_PARENT_PID": "1", "JPY_SESSION_NAME": "x"})
    assert z.forks(["python" if os.path.basename(sys.executable) == "python" else sys.executable, *argv[1:]], env)
    assert not z.forks(argv, {**env, "OMP_NUM_THREADS": "1"})  # another environment: launched as usual
    assert not z.forks([sys.executable, "-X", "dev", *argv[1:]], env)  # other interpreter flags
    assert not z.forks([sys.executable, "-m", "other_kernel", "-f", "k.json"], env)
    assert not z.forks(["/usr/bin/env", "python", "-c", "1"], env)


def test_a_zygote_that_does_not_fork_lets_the_kernel_launch_as_usual(tmp_path):
    """No zygote at the address, or one that answers 'cold' (its preload failed or warned):
    :func:`warm_kernels._fork` says so (None), and the provisioner launches the kernel itself."""
    address = str(tmp_path / "zygote")
    assert warm_kernels._fork(address, ["-f", "k.json"], str(tmp_path), {}) is None
    server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    server.bind(address)
    server.listen(1)

    def answer():
        conn, _ = server.accept()
        conn.makefile("rb").readline()
        conn.sendall(b'{"cold": "importing numpy warned: ..."}\n')
        conn.close()

    import threading

    t = threading.Thread(target=answer)
    t.start()
    assert warm_kernels._fork(address, ["-f", "k.json"], str(tmp_path), {}) is None
    t.join()
    server.close()


def test_a_preload_that_warns_or_fails_keeps_kernels_cold(tmp_path):
    (tmp_path / "warns_at_import.py").write_text("import warnings\nwarnings.warn('deprecated thing', UserWarning)\n")
    (tmp_path / "fails_at_import.py").write_text("raise RuntimeError('broken install')\n")
    code = textwrap.dedent(
        """
        import sys
        from lorisnb.tools.report import kernels as w
        w.PRELOAD = (sys.argv[1],)
        print(w._preload())
        """
    )
    env = {**os.environ, "PYTHONPATH": str(tmp_path)}

    def why(module: str) -> str:
        return subprocess.run([sys.executable, "-c", code, module], capture_output=True, text=True, env=env,
                              check=True).stdout.strip()  # fmt: skip

    assert why("warns_at_import") == "importing warns_at_import warned: deprecated thing"
    assert why("fails_at_import") == "importing fails_at_import failed: RuntimeError: broken install"
    assert why("not_installed_anywhere") == "None"  # left to the kernel, whose import fails the same way


def _cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return ""


def _status(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/status").read_text().lower()
    except OSError:
        return "zombie"  # gone meanwhile


def _descendants(pid: int) -> set[int]:
    """Every process below ``pid`` (from /proc)."""
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                stat = Path(f"/proc/{entry}/stat").read_text()
            except OSError:
                continue
            children.setdefault(int(stat.rsplit(")", 1)[1].split()[1]), []).append(int(entry))
    out, todo = set(), [pid]
    while todo:
        for c in children.get(todo.pop(), []):
            out.add(c)
            todo.append(c)
    return out


@pytest.mark.slow
@pytest.mark.parametrize("how", ["SIGTERM", "SIGINT"])
def test_a_report_stopped_midway_leaves_nothing_running_or_half_written(tmp_path, how):
    """`lorisnb report` ended by SIGTERM (a CI time-out) or Ctrl-C while its notebooks run: exit
    status 143 or 130 at once, its workers, zygote and kernels gone, no run folder, whole or partial."""
    out = tmp_path / "run"
    cmd = [str(Path(sys.executable).with_name("lorisnb")), "report", "--out", str(out), "--no-progress"]
    report = subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        deadline = time.monotonic() + 60  # its workers, zygote and first kernels start
        while time.monotonic() < deadline and len(_descendants(report.pid)) < 5:
            time.sleep(0.2)
        time.sleep(3)  # notebooks running in kernels
        below = _descendants(report.pid)
        assert len(below) >= 5  # resource tracker, workers, zygote, kernels
        commands = [_cmdline(p) for p in below]
        assert sum("lorisnb.tools.report.kernels" in c for c in commands) >= 2  # the zygote and kernels forked from it
        assert not any("ipykernel_launcher" in c for c in commands)  # no kernel fell back to a launch
        assert not any("multiprocessing.spawn" in c for c in commands)  # workers forked from the report
        if how == "SIGTERM":
            report.send_signal(signal.SIGTERM)
        else:
            os.killpg(report.pid, signal.SIGINT)  # Ctrl-C in a terminal: the whole foreground group
        assert report.wait(30) == (143 if how == "SIGTERM" else 130)
        assert ("terminated" if how == "SIGTERM" else "interrupted") in report.stderr.read()
        deadline = time.monotonic() + 15
        while time.monotonic() < deadline and any(os.path.exists(f"/proc/{p}") for p in below):
            time.sleep(0.2)
        alive = [
            p
            for p in below
            if os.path.exists(f"/proc/{p}") and "zombie" not in Path(f"/proc/{p}/status").read_text().lower()
        ]
        assert not alive, f"left running: {alive}"
        assert list(tmp_path.iterdir()) == []  # no run folder, no partial one
    finally:
        report.kill()


def test_no_zygote_without_a_kernel_to_fork(monkeypatch):
    """No Jupyter client or no ``python3`` kernel: no zygote (each notebook then fails in its own
    entry, as before); a kernel command that is not ipykernel's launcher: no zygote either."""
    from jupyter_client.kernelspec import NoSuchKernel

    from lorisnb.tools.report import notebooks as report_notebooks

    def missing():
        raise NoSuchKernel("python3")

    monkeypatch.setattr(report_notebooks, "kernel_manager_class", missing)
    with warm_kernels_for_report() as zygote:
        assert zygote is None
    with warm_kernels.zygote(["/usr/bin/env", "R", "--slave", "-f", "{connection_file}"], dict(os.environ)) as z:
        assert z is None


def test_a_forked_kernels_exit_status_comes_from_the_zygote():
    """Liveness from the pidfd; the status from the zygote's line, read with the pid when the kernel
    ended at once (both in one message) or later on the connection; 1 when the zygote cannot say."""
    for received, later, expected in (
        (b'{"returncode": 3}\n', b"", 3),
        (b"", b'{"returncode": 0}\n', 0),
        (b"", b"", 1),
    ):
        ended = subprocess.Popen(["true"])
        pidfd = os.pidfd_open(ended.pid)
        ended.wait()
        ours, zygote_end = socket.socketpair()
        zygote_end.sendall(later)
        zygote_end.close()
        handle = warm_kernels.Forked(ours, ended.pid, pidfd, received)
        assert handle.poll() == expected and handle.wait() == expected
    running = subprocess.Popen(["sleep", "30"])
    try:
        ours, zygote_end = socket.socketpair()
        handle = warm_kernels.Forked(ours, running.pid, os.pidfd_open(running.pid))
        assert handle.poll() is None
        with pytest.raises(subprocess.TimeoutExpired):
            handle.wait(0.1)
        handle.kill()
        assert running.wait(10) == -signal.SIGKILL
    finally:
        running.kill()
        zygote_end.close()
