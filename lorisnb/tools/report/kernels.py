"""Warm notebook kernels: a report's kernels forked from one process that has already imported
the heavy modules every notebook kernel imports.

Every notebook of a report runs in a fresh kernel, and each fresh kernel spends seconds of CPU
importing the same modules before its first cell's own work. A *zygote* process imports
:data:`PRELOAD` once (nothing else: no figure, no data, no state of its own) and forks one child
per kernel; each child becomes the kernel ``python -m ipykernel_launcher ARGS`` would have been:
in the notebook's folder, with that command's environment, argv and ``sys.path``, its own
process group, numpy's global generator seeded afresh and an empty user namespace. The notebook's
``import`` lines then find those modules loaded.

Only modules whose import does not look at where it runs are preloaded: pandas chooses its
display width, ``tqdm.auto`` its progress bar and pyplot its display hook when first imported,
depending on whether they run in a Jupyter kernel, so the kernel imports those itself. The zygote
forks only when every preload imported without an error or a warning (a warning at import would
otherwise not reach the notebook that would have shown it), and a kernel is forked only when its
command is the zygote's interpreter running ``ipykernel_launcher`` and its environment is the
zygote's (apart from Jupyter's ``JPY_*`` variables); any other kernel is launched as usual. The
kernels of one report share the zygote's string-hash seed.

Jupyter's kernel manager drives a forked kernel as any local kernel (:func:`provisioner_class`:
signals to its process group, liveness from a pidfd, the exit status from the zygote), and the
kernel exits when the process managing it exits, as a launched kernel does; a forked kernel first
removes what that manager's clean-up would have (its connection file and ipc sockets, and the
report's kernel folder once empty), so that a report killed outright leaves none in the temporary
folder. Forking needs Linux (``os.pidfd_open``, fd passing); elsewhere kernels are launched as usual.

Kept after measuring the plain route (issue 47): ``lorisnb report`` on the bundled data, 8
notebooks, on 2 cores shared with other work (load about 14), took 96 s and 103 s of user CPU
with forked kernels against 132 s with every kernel launched by jupyter_client as usual (this
module bypassed, nothing else changed); wall 308 s and 210 s against 370 s.
"""

from __future__ import annotations

import asyncio
import contextlib
import importlib
import json
import os
import select
import selectors
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

#: What the zygote imports: the kernel itself and the heavy modules notebooks import through
#: pandas, seaborn and lorisnb, none of which looks at whether it runs in a kernel or starts a
#: thread a fork would lose (pyarrow, which pandas imports where installed, starts jemalloc's).
#: pyplot chooses its backend and display hook at its first figure, in the kernel.
PRELOAD = ("ipykernel.kernelapp", "numpy", "scipy.stats", "matplotlib", "matplotlib.pyplot")

#: The module a kernel command must run (``python [flags] -m ipykernel_launcher ARGS``).
LAUNCHER = "ipykernel_launcher"

#: How the private folders of a report's kernel files are named (``lorisnb.tools.report.notebooks.kernel_files``).
KERNEL_FOLDER_PREFIX = "lorisnb-k-"


@dataclass(frozen=True)
class Zygote:
    """A running zygote: its socket, the interpreter and flags it runs, and its environment."""

    address: str
    interpreter: tuple[str, ...]
    env: tuple[tuple[str, str], ...]

    def forks(self, argv: Sequence[str], env: Mapping[str, str]) -> bool:
        """Whether a kernel launched by ``argv`` in ``env`` is the one this zygote would fork."""
        return _interpreter(argv, env) == self.interpreter and _own(env) == self.env


_current: Zygote | None = None
_refused: str | None = None


def refusal() -> str | None:
    """Why this process's last kernel was launched as usual rather than forked from the zygote in
    use (None: it was forked, or no zygote is in use); for messages and tests."""
    return _refused


def _own(env: Mapping[str, str]) -> tuple[tuple[str, str], ...]:
    """``env`` without the variables Jupyter sets for each kernel."""
    return tuple(sorted((k, v) for k, v in env.items() if not k.startswith("JPY_")))


def supported() -> bool:
    """Whether kernels can be forked here (Linux: ``fork``, ``pidfd_open``, fd passing)."""
    return sys.platform == "linux" and hasattr(os, "pidfd_open") and hasattr(socket, "send_fds")


def use(zygote: Zygote | None) -> None:
    """Make this process's kernel managers fork their kernels from ``zygote`` (a report's worker
    processes get it from their initializer), or launch them as usual again (None)."""
    global _current
    _current = zygote


def current() -> Zygote | None:
    """The zygote this process's kernels are forked from, or None."""
    return _current


def _interpreter(argv: Sequence[str], env: Mapping[str, str]) -> tuple[str, ...] | None:
    """``argv``'s interpreter (resolved on ``env``'s PATH, as the kernel's launch would) and its
    flags, when ``argv`` runs :data:`LAUNCHER`; else None."""
    argv = list(argv)
    if "-m" not in argv or argv.index("-m") + 1 >= len(argv) or argv[argv.index("-m") + 1] != LAUNCHER:
        return None
    i = argv.index("-m")
    exe = shutil.which(argv[0], path=env.get("PATH")) if os.sep not in argv[0] else argv[0]
    if exe is None:
        return None
    return (os.path.abspath(exe), *argv[1:i])


@contextlib.contextmanager
def zygote(kernel_argv: Sequence[str], env: Mapping[str, str]) -> Iterator[Zygote | None]:
    """Start a zygote for kernels launched by ``kernel_argv`` (a kernelspec's argv) in ``env``,
    and stop it on leaving; yields what :func:`use` takes, or None where kernels cannot be forked
    (they are then launched as usual). The zygote ends by itself if this process ends first."""
    prefix = _interpreter(kernel_argv, env) if supported() else None
    if prefix is None:
        yield None
        return
    folder = tempfile.mkdtemp(prefix="lorisnb-kernels-")
    address = os.path.join(folder, "zygote")
    proc = subprocess.Popen(
        [*prefix, "-m", __name__, address, str(os.getpid())], env=dict(env), stdin=subprocess.DEVNULL,
        start_new_session=True,  # Ctrl-C in a terminal reaches the report, which stops it
    )  # fmt: skip
    try:
        deadline = time.monotonic() + 30  # it listens once its interpreter has started (a fraction of a second)
        while not os.path.exists(address) and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)
        yield Zygote(address, prefix, _own(env)) if os.path.exists(address) else None
    finally:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        shutil.rmtree(folder, ignore_errors=True)


class Forked:
    """A kernel forked by the zygote, with the part of :class:`subprocess.Popen` Jupyter's
    provisioner uses: ``pid``, ``poll``, ``wait``, ``send_signal``, ``terminate``, ``kill``."""

    stdin = stdout = stderr = None

    def __init__(self, conn: socket.socket, pid: int, pidfd: int, received: bytes = b"") -> None:
        self.pid, self._conn, self._pidfd, self._received = pid, conn, pidfd, received
        self.returncode: int | None = None

    def _gone(self, timeout: float | None) -> bool:
        return bool(select.select([self._pidfd], [], [], timeout)[0])

    def _finish(self) -> int:
        """The exit status the zygote reports once it has reaped the kernel (1 when it cannot)."""
        code = 1
        try:
            line = self._received
            if not line.endswith(b"\n"):
                self._conn.settimeout(10)
                line += self._conn.makefile("rb").readline()
            code = int(json.loads(line)["returncode"]) if line.strip() else 1
        except (OSError, ValueError, KeyError):
            pass
        self._conn.close()
        os.close(self._pidfd)
        return code

    def poll(self) -> int | None:
        if self.returncode is None and self._gone(0):
            self.returncode = self._finish()
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        if self.returncode is None:
            if not self._gone(timeout):
                raise subprocess.TimeoutExpired(f"kernel {self.pid}", timeout or 0)
            self.returncode = self._finish()
        return self.returncode

    def send_signal(self, signum: int) -> None:
        if self.returncode is None:
            signal.pidfd_send_signal(self._pidfd, signum)

    def terminate(self) -> None:
        self.send_signal(signal.SIGTERM)

    def kill(self) -> None:
        self.send_signal(signal.SIGKILL)


def _fork(address: str, argv: list[str], cwd: str, env: Mapping[str, str]) -> Forked | None:
    """Ask the zygote at ``address`` for a kernel; None when no zygote answers there or it does not fork."""
    global _refused
    conn = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        conn.connect(address)
    except OSError as exc:
        conn.close()
        _refused = f"no zygote answers at {address}: {exc}"
        return None
    conn.settimeout(300)  # the zygote answers once it has imported PRELOAD (seconds)
    conn.sendall(json.dumps({"argv": argv, "cwd": cwd, "env": dict(env)}).encode() + b"\n")
    msg, fds, _, _ = socket.recv_fds(conn, 4096, 1)
    if not fds:  # the zygote does not fork (its preload failed or warned): launch as usual
        conn.close()
        try:
            _refused = str(json.loads(msg.partition(b"\n")[0])["cold"])
        except (ValueError, KeyError, TypeError):
            _refused = f"the zygote answered {msg[:200]!r}"
        return None
    first, _, rest = msg.partition(b"\n")  # rest: the exit status, if the kernel ended at once
    return Forked(conn, int(json.loads(first)["pid"]), fds[0], rest)


def provisioner_class() -> Any:
    """Jupyter's local provisioner, forking its kernel from :func:`current`'s zygote when that
    zygote :meth:`~Zygote.forks` the kernel's command and environment."""
    from jupyter_client.provisioning import LocalProvisioner

    class WarmProvisioner(LocalProvisioner):
        async def launch_kernel(self, cmd: list[str], **kwargs: Any) -> Any:
            global _refused
            zyg, env = current(), dict(kwargs.get("env") or os.environ)
            _refused = None
            if zyg is None:
                return await super().launch_kernel(cmd, **kwargs)
            if not zyg.forks(cmd, env):
                own, theirs = dict(_own(env)), dict(zyg.env)
                _refused = "the kernel's command or environment is not the zygote's" + (
                    f" (variables that differ: {', '.join(sorted(k for k in own.keys() | theirs.keys() if own.get(k) != theirs.get(k)))})"
                    if own != theirs else f" (command {cmd[:3]})"
                )  # fmt: skip
                return await super().launch_kernel(cmd, **kwargs)
            if not kwargs.get("independent"):
                env["JPY_PARENT_PID"] = str(os.getpid())  # as jupyter_client's launch_kernel sets it
            cwd = str(kwargs.get("cwd") or os.getcwd())
            args = [os.path.expanduser(a) for a in cmd[cmd.index("-m") + 2 :]]
            proc = await asyncio.to_thread(_fork, zyg.address, args, cwd, env)
            if proc is None:
                return await super().launch_kernel(cmd, **kwargs)
            self.process = proc  # type: ignore[assignment]  # Popen's interface, see Forked
            self.pid, self.pgid, self.cwd = proc.pid, proc.pid, cwd
            return self.connection_info

    return WarmProvisioner


# ---- the zygote (``python -m lorisnb.tools.report.kernels ADDRESS PARENT_PID``) ----


def _preload() -> str | None:
    """Import :data:`PRELOAD`; why the zygote may not fork kernels (an import failed, warned or
    started a thread), or None. The warnings filters the imports add stay, as in a kernel that
    imports them; a warning they let through is caught on its way to the screen."""
    import gc
    import warnings

    shown: list[str] = []
    show = warnings.showwarning
    warnings.showwarning = lambda message, *_, **__: shown.append(str(message))
    try:
        for name in PRELOAD:
            try:
                importlib.import_module(name)
            except ImportError as exc:
                if exc.name != name:  # a module that is not installed is left out, like its import
                    return f"importing {name} failed: {exc}"
            except Exception as exc:  # noqa: BLE001 - the kernel would meet it itself
                return f"importing {name} failed: {type(exc).__name__}: {exc}"
            if shown:
                return f"importing {name} warned: {shown[0]}"
    finally:
        warnings.showwarning = show
    if threading.active_count() > 1:  # forking would leave a thread behind
        return "a preloaded module started a thread"
    gc.collect()
    gc.freeze()  # what the zygote holds stays shared with the kernels (no copy-on-write by gc)
    return None


def _serve(address: str, parent: int) -> dict[str, Any] | None:
    """Fork a kernel for each request until ``parent`` ends or a signal stops the zygote. Returns
    the request in each child (which then becomes the kernel), None in the zygote at its end."""
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    listener.bind(address)
    listener.listen(64)
    cold = _preload()
    wake_r, wake_w = os.pipe()
    os.set_blocking(wake_w, False)
    signal.set_wakeup_fd(wake_w)
    signal.signal(signal.SIGCHLD, lambda *_: None)
    sel = selectors.DefaultSelector()
    sel.register(listener, selectors.EVENT_READ)
    sel.register(wake_r, selectors.EVENT_READ)
    kernels: dict[int, socket.socket] = {}
    me = os.getpid()
    try:
        while os.getppid() == parent:
            for key, _ in sel.select(timeout=1.0):
                if key.fileobj is wake_r:
                    os.read(wake_r, 4096)
                    continue
                conn, _ = listener.accept()
                why = cold
                try:
                    conn.settimeout(60)
                    request = json.loads(conn.makefile("rb").readline())
                except (OSError, ValueError) as exc:
                    why = why or f"bad request: {exc}"
                if why is not None:  # no kernel from here: the manager launches it as usual
                    with contextlib.suppress(OSError):
                        conn.sendall(json.dumps({"cold": why}).encode() + b"\n")
                    conn.close()
                    continue
                pid = os.fork()
                if pid == 0:  # the child: drop the zygote's sockets, signals and pipes
                    signal.set_wakeup_fd(-1)
                    signal.signal(signal.SIGCHLD, signal.SIG_DFL)
                    for fd in (wake_r, wake_w):
                        os.close(fd)
                    for c in (listener, conn, *kernels.values()):
                        c.close()
                    sel.close()
                    return dict(request)
                pidfd = os.pidfd_open(pid)
                try:
                    socket.send_fds(conn, [json.dumps({"pid": pid}).encode() + b"\n"], [pidfd])
                    kernels[pid] = conn
                except OSError:  # the manager is gone: so is the kernel it asked for
                    os.kill(pid, signal.SIGKILL)
                    conn.close()
                finally:
                    os.close(pidfd)
            while True:  # reap every child that ended, and report the status of each kernel
                try:
                    pid, status = os.waitpid(-1, os.WNOHANG)
                except ChildProcessError:
                    break
                if pid == 0:
                    break
                if pid not in kernels:  # a kernel whose manager was gone
                    continue
                conn = kernels.pop(pid)
                with contextlib.suppress(OSError):
                    conn.sendall(json.dumps({"returncode": os.waitstatus_to_exitcode(status)}).encode() + b"\n")
                conn.close()
    finally:
        if os.getpid() == me:  # the zygote itself, not a child returning its request
            with contextlib.suppress(OSError):
                os.unlink(address)
                os.rmdir(os.path.dirname(address))  # its folder, if the report could not remove it
    return None


def _connection_file(args: Sequence[str]) -> str | None:
    """The connection file a kernel's arguments name (``-f FILE``, as a kernelspec's argv gives it)."""
    for i, a in enumerate(args):
        if a in ("-f", "--f") and i + 1 < len(args):
            return os.path.abspath(args[i + 1])
        if a.startswith(("--f=", "--IPKernelApp.connection_file=")):
            return os.path.abspath(a.partition("=")[2])
    return None


def _remove_kernel_files(connection_file: str | None) -> None:
    """Remove what a kernel's manager removes when the kernel ends (``cleanup_resources``): the
    connection file and, over ipc, the sockets it names; then the report's kernel folder
    (:data:`KERNEL_FOLDER_PREFIX`) if nothing else is left in it. For a kernel whose manager is gone."""
    if not connection_file:
        return
    try:
        with open(connection_file) as f:
            info = json.load(f)
    except (OSError, ValueError):
        info = {}
    if isinstance(info, dict) and info.get("transport") == "ipc" and info.get("ip"):
        for key in ("shell_port", "iopub_port", "stdin_port", "control_port", "hb_port"):
            if info.get(key):
                with contextlib.suppress(OSError):
                    os.unlink(f"{info['ip']}-{info[key]}")
    with contextlib.suppress(OSError):
        os.unlink(connection_file)
    folder = os.path.dirname(connection_file)
    if os.path.basename(folder).startswith(KERNEL_FOLDER_PREFIX):
        with contextlib.suppress(OSError):  # another kernel's files still there: not empty, kept
            os.rmdir(folder)


def _watch(manager: int, connection_file: str | None = None) -> None:
    """End this kernel when the process managing it ends (a launched kernel's parent poller), first
    removing the files its manager can no longer remove (a report killed with ``kill -9`` left its
    kernels' sockets and connection files, which hold each kernel's key, in the temporary folder)."""
    try:
        fd = os.pidfd_open(manager)
    except OSError:
        _remove_kernel_files(connection_file)
        os._exit(1)
    select.select([fd], [], [])
    _remove_kernel_files(connection_file)
    os._exit(1)


def _become_kernel(request: Mapping[str, Any]) -> None:
    """Turn this forked child into ``python -m ipykernel_launcher ARGV`` run in ``cwd`` with ``env``."""
    os.setsid()  # its own process group, as Jupyter launches kernels
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    cwd, env, args = str(request["cwd"]), dict(request["env"]), [str(a) for a in request["argv"]]
    os.chdir(cwd)
    os.environ.clear()
    os.environ.update(env)
    devnull = os.open(os.devnull, os.O_RDONLY)
    os.dup2(devnull, 0)
    os.close(devnull)
    import ipykernel_launcher  # type: ignore[import-untyped]

    sys.argv = [ipykernel_launcher.__file__, *args]
    if not sys.flags.safe_path:  # `python -m` put the folder it started in first; the launcher removes it
        del sys.path[0]
    if "numpy" in sys.modules:
        sys.modules["numpy"].random.seed()  # a fresh process seeds numpy's global generator afresh
    # ipykernel's own poller sees that its parent (the zygote) is not JPY_PARENT_PID and then only
    # watches for being orphaned; this thread watches the manager, as that poller would have
    manager = int(env.get("JPY_PARENT_PID", "0") or 0)
    if manager:
        watch = threading.Thread(target=_watch, args=(manager, _connection_file(args)), daemon=True,
                                 name="lorisnb-manager-watch")  # fmt: skip
        watch.start()
    from ipykernel.kernelapp import IPKernelApp

    IPKernelApp.launch_instance(argv=args)


def main(argv: Sequence[str]) -> None:
    address, parent = argv[0], int(argv[1])
    request = _serve(address, parent)
    if request is not None:
        _become_kernel(request)


if __name__ == "__main__":
    main(sys.argv[1:])
