"""Run a student's code in a sandbox: its own folder, an unprivileged user, no network, a time
limit per cell and a memory limit, with the instructor's files out of reach.

:class:`Sandbox` starts one child process (:mod:`._sandbox_child`) and talks to it over pipes, a
request per cell. When the grader runs as root on Linux with ``unshare`` and ``setpriv`` (CI, a
course server), the child gets (``isolation == "full"``):

- its own network namespace (no interface but a loopback that is down: no network at all);
- its own mount namespace in which the whole file system is read-only except its working folder
  (and a fresh 64 MB ``/dev/shm`` for multiprocessing's locks),
  the folders named ``hidden`` (the course folder, the labs' sources, the checkout lorisnb runs
  from) are replaced by empty, unreadable folders, and the temporary folders (``/tmp``, ``/var/tmp``,
  ``$TMPDIR``) and those named ``private`` by empty ones, its working folder alone kept in them (and,
  read-only, what it needs to run that lies there: a Python environment in ``/tmp/x/venv``): it
  sees no other grader's folder, nor another sandbox's of the same submission;
- its own PID namespace (it sees and signals no other process) and IPC namespace (no System V or POSIX
  message queue, semaphore or shared memory reaches another sandbox);
- a user id of its own (``uid``, owning nothing else), no capabilities, ``no_new_privs``;
- limits: address space (``memory_bytes``), file size, number of processes, CPU time.

Otherwise (not root, or no ``unshare``) the child runs as the grader's user in its working folder
with the same limits and time-outs but none of the isolation (``isolation == "limits"``); the
grader says so. The time limit is enforced by the parent, which kills the child's whole process
group; the sandbox can then be restarted (:meth:`Sandbox.restart`).
"""

from __future__ import annotations

import contextlib
import json
import os
import resource
import secrets
import select
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

CHILD = Path(__file__).with_name("_sandbox_child.py")
_CHILD_SOURCE: list[str] = []


def _child_source() -> str:
    """The child's code (read once, by the grader, from lorisnb's own folder)."""
    if not _CHILD_SOURCE:
        _CHILD_SOURCE.append(CHILD.read_text(encoding="utf-8"))
    return _CHILD_SOURCE[0]


def stat_is_link_or_plain(st: os.stat_result) -> bool:
    """Whether an entry of a folder is a link (its own inode: changing its owner changes nothing
    else), a folder, or a file with no other name (``st_nlink`` 1): a hard link to a file elsewhere
    is neither."""
    import stat as _stat

    return _stat.S_ISLNK(st.st_mode) or _stat.S_ISDIR(st.st_mode) or st.st_nlink <= 1


@dataclass(frozen=True)
class Limits:
    """The sandbox's limits: seconds per answer cell or call (``cell_timeout_s``), seconds per
    instructor cell (``locked_timeout_s``: the lab's own cells, its imports and data; at least
    ``cell_timeout_s``), bytes of address space (``memory_bytes``, RLIMIT_AS), bytes per written file,
    processes of its user, CPU seconds. ``budget_s``: seconds of wall clock for a whole submission
    (from its first answer cell on: the cells, their replays, its functions' sandboxes and the checks'
    calls; default ``BUDGET_CELLS`` times ``cell_timeout_s``, at least ``BUDGET_MIN_S``): the grader
    stops running its code when it is spent."""

    cell_timeout_s: float = 60.0
    locked_timeout_s: float = 120.0
    budget_s: float | None = None
    memory_bytes: int = 3 * 1024**3
    file_bytes: int = 64 * 1024**2
    processes: int = 64
    cpu_s: int = 1800

    def __post_init__(self) -> None:
        if not self.cell_timeout_s > 0:
            raise ValueError(f"cell_timeout_s must be > 0 seconds, got {self.cell_timeout_s!r}")
        if self.budget_s is not None and not self.budget_s > 0:
            raise ValueError(f"budget_s must be > 0 seconds, got {self.budget_s!r}")
        if self.memory_bytes < 256 * 1024**2:
            raise ValueError(f"memory_bytes must be at least 256 MiB, got {self.memory_bytes!r}")

    @property
    def submission_s(self) -> float:
        """The wall-clock budget of one submission, in seconds."""
        return self.budget_s if self.budget_s is not None else max(BUDGET_CELLS * self.cell_timeout_s, BUDGET_MIN_S)


# a submission's default budget: 5 per-cell limits (5 min at the default 60 s), at least 2 minutes
# (the lab's own cells after the first answer are charged too: about 10 to 20 s on a busy 2-core machine)
BUDGET_CELLS, BUDGET_MIN_S = 5, 120.0


REPLY_BYTES = 64 * 1024**2  # the most the grader buffers of the child's pipe without a line end
SYNC_S = 5.0  # at least this long for the child to answer the grader's sync after a reply (it runs no code then)


class SandboxError(RuntimeError):
    """The child died or broke the protocol (a time-out, the memory limit, ``os._exit``...)."""


class SandboxTimeout(SandboxError):
    """The child was stopped at its time limit (or no time was left to run it)."""


def error_of(exc: SandboxError) -> str:
    """The error an answer gets when its sandbox stopped: ``TimeoutError: ...`` for a time limit
    (:class:`SandboxTimeout`), else ``RuntimeError: ...`` (the sandbox ended: its code ended its
    process, the memory limit...): never a time-out that was none."""
    return f"{'TimeoutError' if isinstance(exc, SandboxTimeout) else 'RuntimeError'}: {exc}"


def can_isolate() -> bool:
    """Whether :class:`Sandbox` can isolate (root on Linux, with unshare and setpriv)."""
    return (
        sys.platform == "linux"
        and os.geteuid() == 0
        and shutil.which("unshare") is not None
        and shutil.which("setpriv") is not None
    )


def _temporary_folders() -> list[Path]:
    import tempfile

    return [Path(d).resolve() for d in dict.fromkeys((tempfile.gettempdir(), "/tmp", "/var/tmp"))]


def _as_needed(needed: Sequence[Path]) -> list[Path]:
    # each needed path as written and as resolved: an interpreter reached through a link in a temporary
    # folder (a clone's .venv linking to a checkout's) is started by the path through the link
    return list(dict.fromkeys(q for n in needed for q in (Path(os.path.abspath(n)), Path(n).resolve())))


_WARNED: set[Path] = set()


def private_folders(work: Path, private: Sequence[Path], needed: Sequence[Path], tmp: bool = True) -> list[Path]:
    """The folders a sandbox working in ``work`` sees empty (but for ``work`` itself and the paths of
    ``needed`` inside them, :func:`kept_paths`): the temporary folders (unless not ``tmp``) and
    ``private``, less the root and less those inside another of them (emptied with it). A folder that
    is one of ``needed`` (the Python environment, lorisnb), or lies inside one, cannot be emptied: it
    is left as it is, and a warning on stderr names it and what to do."""
    found = [Path(p).resolve() for p in (*(_temporary_folders() if tmp else []), *private)]
    need = _as_needed(needed)
    out = []
    for p in dict.fromkeys(found):
        if not p.is_dir() or p == p.parent:
            continue
        inside = next((n for n in need if p.is_relative_to(n)), None)
        if inside is not None:
            if p not in _WARNED:
                _WARNED.add(p)
                print(
                    f"warning: the grading sandbox cannot hide {p} from a submission's code: it is, or lies in, "
                    f"{inside}, which the sandbox needs to run (the Python environment, lorisnb); a submission "
                    f"can list and read what {p} holds. Install the environment elsewhere, or set TMPDIR to a "
                    "folder outside it",
                    file=sys.stderr,
                )
            continue
        out.append(p)
    del work
    return [p for p in out if not any(p != q and p.is_relative_to(q) for q in out)]


def kept_paths(private: Sequence[Path], needed: Sequence[Path]) -> list[Path]:
    """The folders of ``needed`` (as written and as resolved) that lie inside one of ``private``, the
    outermost ones: a sandbox sees them, read-only, in the emptied folder (a Python environment in
    ``/tmp/x/venv`` is bound back there, and nothing else of ``/tmp`` shows)."""
    found = [n for n in _as_needed(needed) if n.is_dir() and any(n != p and n.is_relative_to(p) for p in private)]
    return [n for n in found if not any(n != q and n.is_relative_to(q) for q in found)]


def closed_to_others(paths: Sequence[Path]) -> list[Path]:
    """The first folder (or file) on the way to each of ``paths`` that a user other than its owner
    cannot pass (a folder without ``o+x``, or the path itself without ``o+r``): the sandbox's own
    user could not read what lies behind it. Empty when every path is reachable."""
    closed: list[Path] = []
    for path in paths:
        p = Path(path).resolve()
        for q in (*reversed(p.parents), p):
            mode = q.stat().st_mode
            need = 0o005 if q.is_dir() else 0o004
            if mode & need != need:
                closed.append(q)
                break
    return list(dict.fromkeys(closed))


_CLAIMED: dict[tuple[int, int, int], int] = {}  # (pid, base, count) -> first uid (its lock's fd stays open)


def claim_uids(base: int, count: int = 2, span: int = 4000) -> int:
    """The first of ``count`` consecutive user ids, from ``base`` up in steps of ``count`` within
    ``span``, that no other process on this machine holds and no account uses: held (an exclusive
    ``flock`` on ``lorisnb-sandbox-uid-<uid>.lock`` in /run/lock or the temporary folder) until this
    process ends, so concurrent graders (workers of one class, or two instructors' graders) never
    share a sandbox user, which could read the other's working folder. The same ids for every call
    of one process."""
    import fcntl
    import pwd
    import tempfile

    key = (os.getpid(), base, count)  # a forked worker claims its own (the parent's lock is not its)
    if key in _CLAIMED:
        return _CLAIMED[key]
    lock_dir = Path("/run/lock") if os.access("/run/lock", os.W_OK) else Path(tempfile.gettempdir())
    for first in range(base, base + span, count):
        ids = range(first, first + count)
        if any(_account_exists(u, pwd) for u in ids):
            continue
        try:
            fd = os.open(lock_dir / f"lorisnb-sandbox-uid-{first}.lock", os.O_RDWR | os.O_CREAT, 0o600)
        except OSError:  # another user's lock file: not ours to take
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            continue
        _CLAIMED[key] = first
        return first
    raise SandboxError(f"no free sandbox user id in {base}..{base + span - 1}: {span // count} graders already run")


def _account_exists(uid: int, pwd: Any) -> bool:
    try:
        pwd.getpwuid(uid)
    except KeyError:
        return False
    return True


# the child's mount namespace, as root before dropping to the student's uid: everything read-only,
# the private folders (the temporary folders: other graders' and other sandboxes' folders) replaced by
# empty ones, in which the kept paths (what the child needs to run that lies there: a Python
# environment in /tmp) are bound back read-only, then the hidden folders emptied (also inside a kept
# path), only the working folder writable
_SETUP = r"""set -e
work="$1"; uid="$2"; shift 2
mount --make-rprivate /
for m in $(awk '{print $5}' /proc/self/mountinfo | sort -u); do
  case "$m" in /proc|/proc/*|/sys|/sys/*|/dev|/dev/pts) continue;; esac
  mount -o remount,bind,ro "$m" 2>/dev/null || true
done
mount -t tmpfs -o size=64m,mode=1777,nosuid,nodev lorisnb-shm /dev/shm  # its own (multiprocessing's locks)
stage=/dev/shm/.lorisnb-work  # the working folder, kept aside while the hidden and private folders are emptied
mkdir "$stage"
mount --bind "$work" "$stage"
kept=0  # the kept paths, kept aside the same way (each one's path in a file beside it: no arrays in sh)
while [ "$1" != "--" ]; do
  kept=$((kept + 1))
  mkdir "/dev/shm/.lorisnb-keep-$kept"
  mount --bind "$1" "/dev/shm/.lorisnb-keep-$kept"
  printf '%s' "$1" > "/dev/shm/.lorisnb-keep-$kept.path"
  shift
done
shift
private=""
while [ "$1" != "--" ]; do
  if [ -d "$1" ]; then mount -t tmpfs -o size=1m,mode=1777,nosuid,nodev lorisnb-private "$1"; private="$private $1"; fi
  shift
done
shift
i=0
while [ "$i" -lt "$kept" ]; do
  i=$((i + 1))
  dest=$(cat "/dev/shm/.lorisnb-keep-$i.path")
  mkdir -p "$dest"
  mount -n --move "/dev/shm/.lorisnb-keep-$i" "$dest"
  mount -o remount,bind,ro "$dest"
  rmdir "/dev/shm/.lorisnb-keep-$i"
  rm "/dev/shm/.lorisnb-keep-$i.path"
done
while [ "$1" != "--" ]; do
  if [ -d "$1" ]; then mount -t tmpfs -o size=4k,mode=0700,ro lorisnb-hidden "$1"; fi
  shift
done
shift
mkdir -p "$work"
mount -n --move "$stage" "$work"
rmdir "$stage"
mount -o remount,bind,rw "$work"
for d in $private; do mount -o remount,bind,ro "$d"; done
mount -t proc proc /proc
cd "$work"
exec setpriv --reuid="$uid" --regid="$uid" --clear-groups --no-new-privs --inh-caps=-all --bounding-set=-all -- "$@"
"""


class Sandbox:
    """One child process running a student's cells in ``work`` (a folder the grader made: it is
    given to ``uid`` and is the only place the child can write).

    ``no_lorisnb``: lorisnb cannot be imported (and, isolated, its folder is hidden): for formula
    answers, which must be written with numpy. ``hidden``: folders the child must not read.
    ``private``: folders it sees empty but for its own folder, as it sees the temporary folders
    (``private_tmp=False``: those as they are, for a test that puts there what the child must reach)."""

    def __init__(
        self,
        work: Path,
        *,
        limits: Limits = Limits(),
        hidden: Sequence[Path] = (),
        uid: int = 62000,
        no_lorisnb: bool = False,
        python_path: Sequence[Path] = (),
        private: Sequence[Path] = (),
        private_tmp: bool = True,
    ) -> None:
        self.work = Path(work).resolve()
        self.limits = limits
        self.hidden = [Path(h).resolve() for h in hidden]
        self.uid = uid
        self.no_lorisnb = no_lorisnb
        self.python_path = [str(p) for p in python_path]
        self.isolation = "full" if can_isolate() else "limits"
        self.private = private_folders(self.work, private, self._needed(), private_tmp)
        self.kept = kept_paths(self.private, self._needed())  # bound back, read-only, in the emptied folders
        self._proc: subprocess.Popen[bytes] | None = None
        self._buffer = bytearray()
        self._scanned = 0  # bytes of the buffer known to hold no line end
        self._given = False  # the working folder was given to the sandbox's user (once, before its first start)
        self.stray = 0  # lines in the reply pipe that were no reply of the child's (tampering)
        # the requests whose reply the code could have written: a second reply to the request (forged with its
        # id), a reply holding other names than those asked for; one text each (a line that is no reply: stray)
        self.tampered: list[str] = []
        # a reply to a request whose reply was read already, found later (the code forged the reply and answered
        # the grader's sync itself: the child's own reply comes after them): (the request's name, what was found)
        self.late: list[tuple[str, str]] = []
        self._answered: dict[str, str] = {}  # id -> name of every request whose reply was read
        self.findings: list[str] = []  # what the guard of a no-lorisnb child refused or found (lorisnb used)
        self.start()

    # --- life cycle ------------------------------------------------------------------------------

    def _needed(self) -> list[Path]:
        """What the child reads to run: the Python environment, numpy, lorisnb, ``python_path``."""
        import lorisnb

        return [
            Path(sys.prefix), Path(sys.base_prefix), Path(sys.executable).parent, Path(sys.executable).resolve().parent,
            Path(np.__file__).resolve().parents[1], Path(lorisnb.__file__).resolve().parent,
            *(Path(p) for p in self.python_path),
        ]  # fmt: skip

    def _command(self) -> list[str]:
        # without lorisnb: no site (an editable install's path hook would find it), numpy's folder only
        # the child's code is given on its command line (``-c``), never as a file in the working folder: the
        # student owns that folder, and a file the grader (root) wrote or read there by its name could be a
        # link a student's cell put in its place (to any file of the machine, which root would overwrite)
        child = [
            sys.executable,
            *(["-S"] if self.no_lorisnb else []),
            "-B",
            "-c",
            _child_source(),
            "lorisnb-sandbox",
            f"--output-bytes={self.limits.file_bytes}",  # the student's prints, kept up to the file size limit
        ] + (["--no-lorisnb"] if self.no_lorisnb else [])
        if self.isolation != "full":
            return child
        hidden = [str(h) for h in self.hidden if not self.work.is_relative_to(h)]
        if self.no_lorisnb:
            import lorisnb

            hidden.append(str(Path(lorisnb.__file__).resolve().parent))
        return [
            "unshare", "--mount", "--net", "--pid", "--ipc", "--fork", "--kill-child", "--",
            "sh", "-c", _SETUP, "sh", str(self.work), str(self.uid), *map(str, self.kept), "--",
            *map(str, self.private), "--", *hidden, "--",
            *child,
        ]  # fmt: skip

    def _limit(self) -> None:  # runs in the child before exec
        os.setsid()
        lim = self.limits
        for which, value in (
            (resource.RLIMIT_AS, lim.memory_bytes),
            (resource.RLIMIT_FSIZE, lim.file_bytes),
            (resource.RLIMIT_NPROC, lim.processes),
            (resource.RLIMIT_CPU, lim.cpu_s),
            (resource.RLIMIT_CORE, 0),
        ):
            if which == resource.RLIMIT_NPROC and self.isolation != "full":
                continue  # counted per user: the grader's own user has other processes
            resource.setrlimit(which, (value, value))

    def _give_folder(self) -> None:
        """Give the working folder (as the grader made it: no student code ran in it yet) to the
        sandbox's user, once, before its first start. Never again: from then on the student's code
        owns what lies in it, and the grader (root) does nothing in it by name (a restart neither
        copies, nor changes the owner of, anything there), since any name could be a link, a hard
        link or a folder swapped for a link by then (a process of the student's still dying)."""
        closed = [p for p in self.work.parents
                  if not p.stat().st_mode & 0o001 and not any(p.is_relative_to(q) for q in self.private)]  # fmt: skip
        if closed:
            raise OSError(f"the sandbox's folder {self.work} is under {closed[0]}, which its user cannot enter "
                          "(mode without o+x): make the folder elsewhere (the grader uses $TMPDIR)")  # fmt: skip
        fd = os.open(self.work, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW)
        try:
            for top, dirs, files, top_fd in os.fwalk(".", dir_fd=fd, follow_symlinks=False):
                del top
                for name in [*dirs, *files]:
                    st = os.stat(name, dir_fd=top_fd, follow_symlinks=False)
                    if not stat_is_link_or_plain(st):
                        continue  # a file with another name elsewhere (a hard link): not the folder's to give
                    os.chown(name, self.uid, self.uid, dir_fd=top_fd, follow_symlinks=False)
            os.fchown(fd, self.uid, self.uid)
            os.fchmod(fd, 0o700)
        finally:
            os.close(fd)

    def start(self) -> None:
        if self.isolation == "full" and not self._given:
            self._give_folder()
            self._given = True
        env = {
            "PATH": os.environ.get("PATH", "/usr/bin:/bin"),
            "HOME": str(self.work),
            "TMPDIR": str(self.work),
            "MPLBACKEND": "Agg",
            "MPLCONFIGDIR": str(self.work / ".matplotlib"),
            "OPENBLAS_NUM_THREADS": "1",
            "OMP_NUM_THREADS": "1",
            "MKL_NUM_THREADS": "1",
            "PYTHONHASHSEED": "0",
            "PYTHONDONTWRITEBYTECODE": "1",
            "LANG": "C.UTF-8",
        }
        if self.no_lorisnb:
            env["PYTHONPATH"] = str(Path(np.__file__).resolve().parents[1])
        elif self.python_path:
            env["PYTHONPATH"] = os.pathsep.join(self.python_path)
        self._proc = subprocess.Popen(  # noqa: S603 (our own child, its command built above)
            self._command(),
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            cwd=self.work,
            env=env,
            preexec_fn=self._limit,  # noqa: PLW1509 (the limits must be set between fork and exec)
        )
        self._buffer = bytearray()
        self._scanned = 0

    def close(self, settle: bool = True) -> None:
        """Kill the child and everything it started (its process group); ``settle``: once what it
        wrote up to the grader's last request is read (:meth:`settle`: a reply to a request answered
        earlier is found even when it came after the grader's last request), unless the child is
        stopped for a limit or an error (it may be running code then, and answers nothing)."""
        if settle and self._proc is not None and self._answered:
            with contextlib.suppress(SandboxError, OSError, ValueError):
                self.settle()
        proc, self._proc = self._proc, None
        if proc is None:
            return
        if proc.poll() is None:
            try:
                os.killpg(proc.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        proc.wait()
        for f in (proc.stdin, proc.stdout):
            if f is not None:
                f.close()

    def restart(self) -> None:
        self.close(settle=False)
        self.start()

    def __enter__(self) -> Sandbox:
        return self

    def __exit__(self, exc_type: object, *_exc: object) -> None:
        self.close(settle=exc_type is None)

    # --- requests --------------------------------------------------------------------------------

    def _ask(self, request: dict[str, Any], timeout_s: float, name: str = "<request>") -> dict[str, Any]:
        """Send a request and wait for its reply (the first line carrying its id), then for the reply to
        a second request of the grader's own (``sync``, whose id no code has seen yet): the child writes
        its one reply to a request after the request's code ran, and nothing until it reads the next, so
        every other line up to the sync's reply is the code writing into the grader's channel: a second
        reply to the request (the code forged one with its id: the first is returned, so either may be
        the code's) names the request in ``self.tampered`` (``name``); a line that is no reply to it is
        not read as one, only counted in :attr:`stray`. Code that forged a reply and also answered the
        sync itself (it read the sync from the request pipe) is found later: the child's own reply to
        the request comes after them, and a reply to a request answered earlier, read at any later
        request or at :meth:`settle`, is put in ``late`` under that request's name."""
        proc = self._proc
        if proc is None or proc.poll() is not None or proc.stdin is None or proc.stdout is None:
            raise SandboxError("the sandbox is not running (it ended earlier)")
        if timeout_s <= 0:
            raise SandboxTimeout("time limit: no time left for it")
        fd = proc.stdout.fileno()
        self._drain(fd)
        replies = 0
        request_id = secrets.token_hex(8)
        self._send({**request, "id": request_id})
        deadline = time.monotonic() + timeout_s
        while True:
            line = self._next(fd, deadline, timeout_s)
            if line is not None and line.get("id") == request_id:
                reply, replies = line, 1
                break
            if line is not None:
                self._unasked(line)  # not the reply to this request: written by the code into the pipe
        sync_id = secrets.token_hex(8)
        self._send({"op": "sync", "id": sync_id})
        sync_deadline = max(deadline, time.monotonic() + SYNC_S)
        while True:
            line = self._next(fd, sync_deadline, max(sync_deadline - time.monotonic(), 0.0))
            if line is not None and line.get("id") == sync_id:
                break
            if line is not None and line.get("id") == request_id:
                replies += 1
            elif line is not None:
                self._unasked(line)
        self._answered[request_id] = name
        if replies > 1:
            self.tampered.append(f"{name}: {replies} replies to one request")
        return checked_reply(reply)

    def _unasked(self, line: dict[str, Any]) -> None:
        """A line that is no reply to the request pending: a reply to one answered earlier (the
        code forged that reply and answered the grader's sync itself, so the child's own reply came
        later) goes in ``late`` under that request's name; any other is counted in :attr:`stray`."""
        earlier = self._answered.get(str(line.get("id")))
        if earlier is None:
            self.stray += 1
            return
        self.late.append((earlier, f"{earlier}: a second reply to one request, written after the grader had read "
                                   "a first one and its own check of the channel had been answered (the code "
                                   "answered it)"))  # fmt: skip

    def settle(self, timeout_s: float = SYNC_S) -> None:
        """Read everything the child wrote up to now: a sync request of the grader's and every line
        before its answer (a reply to a request answered earlier goes in ``late``): the child
        answers the sync once the code that ran for the last request has returned. A child whose
        process ended on its own after the last reply was read (the loop never ends by itself: the
        code ended it, as code that forged its reply and left before the child's own could follow
        does) puts that request in ``late`` too. Detection is best effort: code in the child can
        also keep the child's own reply from being written, and is then not found; what it can
        report is only what it computed itself."""
        proc = self._proc
        if proc is None or proc.stdout is None:
            return
        if proc.poll() is not None:
            self._ended_after_reply()
            return
        fd = proc.stdout.fileno()
        try:
            self._drain(fd)
            sync_id = secrets.token_hex(8)
            self._send({"op": "sync", "id": sync_id})
            deadline = time.monotonic() + timeout_s
            while True:
                line = self._next(fd, deadline, timeout_s)
                if line is not None and line.get("id") == sync_id:
                    return
                if line is not None:
                    self._unasked(line)
        except SandboxTimeout:
            raise
        except SandboxError:
            self._ended_after_reply()
            raise

    def _ended_after_reply(self) -> None:
        """The child's process ended with no request pending: the last request answered goes in
        ``late`` (once)."""
        if not self._answered:
            return
        name = list(self._answered.values())[-1]
        found = (f"{name}: the sandbox's process ended on its own after its reply was read (the code ended it, "
                 "as code that forged its reply and left before the child's own reply does)")  # fmt: skip
        if (name, found) not in self.late:
            self.late.append((name, found))

    def _send(self, request: dict[str, Any]) -> None:
        proc = self._proc
        assert proc is not None and proc.stdin is not None
        try:
            proc.stdin.write((json.dumps(request) + "\n").encode())
            proc.stdin.flush()
        except BrokenPipeError:
            raise SandboxError(self._ended()) from None

    def _next(self, fd: int, deadline: float, timeout_s: float) -> dict[str, Any] | None:
        """The next line from the pipe as :meth:`_line` reads it (None: a line that is no reply)."""
        while (end := self._line_end()) < 0:
            left = deadline - time.monotonic()
            if left <= 0:
                self.close(settle=False)
                raise SandboxTimeout(f"time limit: the cell ran for more than {timeout_s:g} s and was stopped")
            ready, _, _ = select.select([fd], [], [], left)
            if ready:
                chunk = os.read(fd, 1 << 16)
                if not chunk:
                    raise SandboxError(self._ended())
                self._take(chunk)
        line = bytes(self._buffer[:end])
        del self._buffer[: end + 1]
        self._scanned = 0
        return self._line(line)

    def _ended(self) -> str:
        """Close the child, which ended on its own (its pipe closed), and say how: its exit status
        (``os._exit``, ``sys.exit`` past the cell, a signal: SIGKILL is the memory limit or a kill)."""
        proc = self._proc
        code = None
        if proc is not None:
            try:
                code = proc.wait(timeout=2)
            except subprocess.TimeoutExpired:
                code = None
        self.close(settle=False)
        if code is None:
            return "the sandbox ended (its process closed the grader's pipe: the code ended it, or the memory limit)"
        if code >= 0:
            return (f"the sandbox ended: the code ended its process (exit status {code}: os._exit, or the like); "
                    "an answer's code must not end the process it runs in")  # fmt: skip
        try:
            name = signal.Signals(-code).name
        except ValueError:
            name = f"signal {-code}"
        why = {"SIGKILL": "the memory limit, or the code killed it", "SIGXCPU": "the CPU time limit",
               "SIGSEGV": "a crash in compiled code, or the memory limit", "SIGABRT": "an abort (often out of memory)",
               "SIGXFSZ": "the file size limit"}.get(name, "the code, or a limit")  # fmt: skip
        return f"the sandbox ended: its process was stopped by {name} ({why})"

    def _line_end(self) -> int:
        """Where the buffer's first line ends (-1: no line end yet); each byte is looked at once."""
        end = self._buffer.find(b"\n", self._scanned)
        self._scanned = len(self._buffer) if end < 0 else end
        return end

    def _take(self, chunk: bytes) -> None:
        """Add what came through the pipe to the buffer, which holds no line end yet (in place: no copy
        of what it holds), and stop a child whose pipe holds more than :data:`REPLY_BYTES` without a
        line end: no reply is that long (a cell's code writing into the pipe would otherwise fill the
        grader's memory)."""
        self._buffer += chunk
        if len(self._buffer) > REPLY_BYTES and b"\n" not in chunk:
            self._buffer = bytearray()
            self._scanned = 0
            self.stray += 1
            self.close(settle=False)
            raise SandboxError(
                f"the code wrote more than {REPLY_BYTES // 1024**2} MiB into the grader's reply pipe without a line "
                "end (no reply is that long): the sandbox was stopped and the cell counts as failed"
            )

    def _line(self, line: bytes) -> dict[str, Any] | None:
        """A line from the pipe: a finding of the guard (``{"lorisnb": what}``: kept in
        :attr:`findings`; the code could write one too, which only tells on itself), an empty line
        (the guard starts its own with one), else what it parses to (None for an empty line or a
        finding; a line that is no JSON object is counted in :attr:`stray`)."""
        if not line.strip():
            return None
        try:
            parsed = json.loads(line)
        except ValueError:
            parsed = None
        if isinstance(parsed, dict) and set(parsed) == {"lorisnb"} and self.no_lorisnb:
            if len(self.findings) < 100:
                self.findings.append(str(parsed["lorisnb"])[:600])
            return None
        if not isinstance(parsed, dict):
            self.stray += 1
            return None
        return parsed

    def _drain(self, fd: int) -> None:
        """Read what came through the pipe while no request was pending: the guard's findings are
        kept; anything else counts as stray (the code wrote it, or a reply came after one the code
        forged): nothing is waiting then."""
        read = 0
        while read < REPLY_BYTES and select.select([fd], [], [], 0)[0]:  # bounded: the code may write on and on
            chunk = os.read(fd, 1 << 16)
            if not chunk:
                break
            read += len(chunk)
            self._take(chunk)
            while (end := self._line_end()) >= 0:
                line = bytes(self._buffer[:end])
                del self._buffer[: end + 1]
                self._scanned = 0
                if (parsed := self._line(line)) is not None:
                    self._unasked(parsed)
        if (parsed := self._line(bytes(self._buffer))) is not None:
            self._unasked(parsed)
        self._buffer = bytearray()
        self._scanned = 0

    def run(
        self,
        source: str,
        capture: Sequence[str] = (),
        name: str = "<cell>",
        locked: bool = False,
        timeout_s: float | None = None,
    ) -> dict[str, Any]:
        """Run one cell (``locked``: the instructor's, with its own time limit; ``timeout_s``: a
        shorter limit, what is left of a budget); the reply: ``ok``, ``error`` (the cell's
        exception), ``values`` (captured)."""
        lim = self.limits
        timeout = max(lim.cell_timeout_s, lim.locked_timeout_s) if locked else lim.cell_timeout_s
        if timeout_s is not None:
            timeout = min(timeout, timeout_s)
        reply = self._ask({"op": "exec", "source": source, "capture": list(capture), "name": name}, timeout, name)
        # the names asked for, and only them: a reply holding others (the cell's code added names to the request
        # it was run by, or forged the reply) is the code tampering with the grader's channel
        got = reply.get("values")
        asked = list(dict.fromkeys(capture))
        if not isinstance(got, dict) or set(got) != set(asked):
            extra = sorted(set(got or ()) - set(asked))
            self.tampered.append(
                f"{name}: its reply held names the grader did not ask for ({', '.join(extra[:5])})" if extra
                else f"{name}: its reply lacked names the grader asked for"
            )  # fmt: skip
            got = got if isinstance(got, dict) else {}
        reply["values"] = {n: got.get(n, {"missing": True}) for n in asked}
        return reply

    def bind(self, values: dict[str, Any], timeout_s: float | None = None) -> None:
        """Bind ``values`` (name -> a value as :func:`._sandbox_child.given` describes it) in the
        notebook's namespace, running nothing."""
        timeout = self.limits.cell_timeout_s if timeout_s is None else min(self.limits.cell_timeout_s, timeout_s)
        reply = self._ask({"op": "set", "values": values}, timeout, "<the lab's values>")
        if not reply.get("ok"):
            raise SandboxError(f"the sandbox could not take the lab's values: {reply.get('error')}")

    def call(self, name: str, args: dict[str, Any], timeout_s: float | None = None) -> dict[str, Any]:
        """Call the function ``name`` the cells defined with these (numpy or plain) arguments."""
        encoded = {k: _encode(v) for k, v in args.items()}
        timeout = self.limits.cell_timeout_s if timeout_s is None else min(self.limits.cell_timeout_s, timeout_s)
        return self._ask({"op": "call", "name": name, "args": encoded}, timeout, f"<a call of {name}>")


#: what a reply's value is told as when it is none of :func:`._sandbox_child._plain`'s forms
_UNRECOGNISED = {"not_plain": "unrecognised-reply"}  # told "<a unrecognised-reply object, not a plain value>"


def checked_plain(plain: Any) -> dict[str, Any]:
    """A value of a reply as :func:`._sandbox_child._plain` describes it, checked: ``{"missing":
    True}``, ``{"value": a bool, int, float, str or None}``, ``{"array": numbers (nested lists, or one
    number: a 0-d array), "dtype": a numeric dtype}`` (it must make that array), ``{"not_plain": a type's name}``; anything else (the
    student's code can write a reply of its own into the pipe) is ``{"not_plain": ...}``, never
    passed on to the checks."""
    if not isinstance(plain, dict):
        return dict(_UNRECOGNISED)
    keys = set(plain)
    if keys == {"missing"} and plain["missing"] is True:
        return {"missing": True}
    if keys == {"value"} and (plain["value"] is None or type(plain["value"]) in (bool, int, float, str)):
        return {"value": plain["value"]}
    if keys == {"not_plain"} and isinstance(plain["not_plain"], str):
        return {"not_plain": plain["not_plain"][:200]}
    # a 0-d array's ``tolist()`` is its one number
    if (
        keys == {"array", "dtype"}
        and type(plain["array"]) in (list, int, float, bool)
        and isinstance(plain["dtype"], str)
    ):
        try:
            dtype = np.dtype(plain["dtype"])
            if dtype.kind not in "biuf":
                return dict(_UNRECOGNISED)
            np.array(plain["array"], dtype=dtype)
        except (TypeError, ValueError, OverflowError):
            return dict(_UNRECOGNISED)
        return {"array": plain["array"], "dtype": plain["dtype"]}
    return dict(_UNRECOGNISED)


def checked_reply(reply: dict[str, Any]) -> dict[str, Any]:
    """A reply to the grader (its ``id`` matched) with every part checked, whatever wrote it (the
    child, or the student's code writing into the pipe): ``ok`` a bool, ``error`` a text, ``line`` a
    positive int, ``values`` names to :func:`checked_plain` values, ``result`` one such value,
    ``output_truncated_mib`` a number; anything else left out."""
    out: dict[str, Any] = {"ok": reply.get("ok") is True}
    if "error" in reply or not out["ok"]:
        out["error"] = str(reply.get("error", "RuntimeError: failed"))[:2000]
    line = reply.get("line")
    if type(line) is int and line > 0:
        out["line"] = line
    if isinstance(reply.get("values"), dict):
        out["values"] = {str(n): checked_plain(v) for n, v in reply["values"].items()}
    if "result" in reply:
        out["result"] = checked_plain(reply["result"])
    mib = reply.get("output_truncated_mib")
    if type(mib) in (int, float):
        out["output_truncated_mib"] = mib
    return out


def _encode(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return {"array": value.tolist(), "dtype": value.dtype.str}
    if isinstance(value, np.generic):
        return {"scalar": value.item(), "dtype": value.dtype.str}
    return value


def decode(plain: dict[str, Any]) -> Any:
    """A value the child described (``_plain``) as the grader sees it: the number, string or array;
    ``...`` for a missing answer; :class:`NotPlain` for anything else."""
    if plain.get("missing"):
        return Ellipsis
    if "value" in plain:
        return plain["value"]
    if "array" in plain:
        return np.array(plain["array"], dtype=plain["dtype"])
    return NotPlain(str(plain.get("not_plain", "unknown")))


class NotPlain:
    """An answer that was not a plain value (a number, a string, a numpy array of numbers): a
    prediction is a value, decided before the reference exists; an object is never asked later.
    ``error``: there is no value at all, and why (the cell failed, a time limit)."""

    def __init__(self, type_name: str, error: str | None = None) -> None:
        self.type_name = type_name
        self.error = error

    def __repr__(self) -> str:
        if self.error is not None:
            return f"<no value: {self.error}>"
        return f"<a {self.type_name} object, not a plain value>"
