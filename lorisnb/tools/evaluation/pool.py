"""Running one task per input file here, on all local cores, or on any ``concurrent.futures``
executor (a Dask cluster's): largest inputs first, small ones together in one task, results in
the order of the inputs, one progress bar."""

from __future__ import annotations

import contextlib
import importlib
import os
import re
import socket
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor, as_completed, wait
from functools import partial
from multiprocessing import get_all_start_methods, get_context
from pathlib import Path
from typing import Any, TypeVar

from lorisnb.core.spec.validate import flag
from lorisnb.core.trajectory.blocks import threads
from lorisnb.errors import EvaluationError, ValidationError

T = TypeVar("T")
R = TypeVar("R")

#: A task sent to a pool holds inputs of about this many bytes at most (small files travel
#: together: one task per file costs more than evaluating a small file), and there are at least
#: this many tasks per worker, so that the work stays balanced.
BATCH_BYTES = 8 * 2**20
TASKS_PER_WORKER = 4

#: Inputs smaller than this (bytes) are handled in this process when worker processes are costly
#: to start (a fork server or spawned interpreters import numpy and pandas: about a second).
PARALLEL_MIN_BYTES = 100 * 2**20


def size_of(path: Path) -> int:
    """Bytes of a file (0 if it cannot be read: the task reports why)."""
    try:
        return path.stat().st_size
    except OSError:
        return 0


def default_jobs() -> int:
    """All local cores (``os.cpu_count()``)."""
    return max(1, os.cpu_count() or 1)


def batches(sizes: Sequence[int], n_jobs: int) -> list[list[int]]:
    """Indices of inputs grouped into tasks: largest first (no worker is left with a big one at the
    end), each task at most :data:`BATCH_BYTES` or an even share of the whole, whichever is smaller."""
    order = sorted(range(len(sizes)), key=lambda k: -sizes[k])
    limit = min(BATCH_BYTES, sum(sizes) / max(1, TASKS_PER_WORKER * n_jobs))
    out: list[list[int]] = []
    load = 0.0
    for k in order:
        if not out or load + sizes[k] > limit:
            out.append([])
            load = 0.0
        out[-1].append(k)
        load += sizes[k]
    return out


def can_fork() -> bool:
    """Whether worker processes can be forked from this one: the platform forks, and this process
    runs a single thread (forking a threaded process is unsafe)."""
    return "fork" in get_all_start_methods() and threading.active_count() == 1


def start_context(preload: Sequence[str] = ("lorisnb.tools.evaluation.runner",), fallback: str = "forkserver") -> Any:
    """How worker processes start: forked when this process runs a single thread (the command
    line, scripts: cheapest), else from a fork server (a Jupyter kernel runs threads, and forking
    a threaded process is unsafe) or spawned, as ``fallback`` says (spawned where neither is
    available). Workers start with the modules ``preload`` names imported: forked ones inherit
    them (they are imported here first), a fork server imports them once for all its workers."""
    methods = get_all_start_methods()
    if can_fork():
        for name in preload:
            with contextlib.suppress(ImportError):  # as a fork server does: the task says what is missing
                importlib.import_module(name)
        return get_context("fork")
    if fallback == "forkserver" and "forkserver" in methods:
        ctx = get_context("forkserver")
        ctx.set_forkserver_preload(list(preload))
        return ctx
    return get_context("spawn")


def worth_processes(sizes: Sequence[int], n_jobs: int) -> bool:
    """Whether a local process pool pays: several processes, at least two inputs each, and forked
    workers (cheap) or enough input to outweigh starting interpreters."""
    if n_jobs <= 1 or len(sizes) < 2 * n_jobs:
        return False
    if can_fork():
        return True
    return sum(sizes) >= PARALLEL_MIN_BYTES


class WatchedExecutor(Executor):
    """An executor of a cluster (a Dask client's) with a count of its workers: :func:`run_tasks`
    waiting on it gives up with an error when the cluster has had no worker for
    :data:`SCHEDULER_TIMEOUT` seconds (every worker killed mid-run left the command waiting for
    ever, its bar frozen, nothing said). ``where``: the scheduler, as the message names it."""

    def __init__(self, executor: Executor, workers: Callable[[], int], where: str) -> None:
        self.executor, self.workers, self.where = executor, workers, where

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future:
        return self.executor.submit(fn, *args, **kwargs)

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        self.executor.shutdown(wait=wait, cancel_futures=cancel_futures)


def _completed(futures: Any, executor: Executor | None) -> Any:
    """``as_completed(futures)``, or, on a :class:`WatchedExecutor`, the same while its cluster keeps a
    worker (polled each second once nothing completes); an EvaluationError once it has had none
    for :data:`SCHEDULER_TIMEOUT` seconds."""
    if not isinstance(executor, WatchedExecutor):
        yield from as_completed(futures)
        return
    import time

    pending, since = set(futures), None
    while pending:
        done, pending = wait(pending, timeout=1.0, return_when=FIRST_COMPLETED)
        yield from done
        if done or executor.workers() > 0:
            since = None
            continue
        since = time.monotonic() if since is None else since
        if time.monotonic() - since >= SCHEDULER_TIMEOUT:
            for f in pending:
                f.cancel()
            raise EvaluationError(f"{executor.where}: the cluster has had no worker for {SCHEDULER_TIMEOUT:g} s, "
                                  f"{len(pending)} task(s) of {len(futures)} left waiting (its workers stopped?); "
                                  "start a worker and run again")  # fmt: skip


def apply_all(fn: Callable[[T], R], items: list[T]) -> list[R]:
    """``fn`` on each item: one task of a pool."""
    return [fn(item) for item in items]


def run_tasks(
    fn: Callable[..., R],
    items: Sequence[T],
    sizes: Sequence[int],
    n_jobs: int,
    executor: Executor | None = None,
    progress: bool = False,
    *,
    desc: str,
    unit: str,
    meanwhile: Callable[[], object] | None = None,
) -> list[R]:
    """``fn(item)`` for every item, in the order of ``items``: here one at a time (``fn`` then gets
    ``progress=`` too, for bars of its own, and long computations run on ``n_jobs`` threads,
    :mod:`lorisnb.core.trajectory.blocks`), in a local pool of ``n_jobs`` processes, or on
    ``executor``. ``fn`` must be a module-level function (it is pickled by name). ``sizes`` are
    the items' bytes, for scheduling. ``progress`` is a yes/no value (:func:`lorisnb.core.spec.validate.flag`:
    ``progress="no"`` is refused, not truth-tested). ``meanwhile``: work of this process called
    once every task is sent to a pool (the workers started), before their results are awaited
    (not called when the items are done here)."""
    progress = flag("progress", progress)

    def new_bar() -> Any:
        if not progress:
            return None
        from tqdm.auto import tqdm

        return tqdm(total=len(items), desc=desc, unit=unit)

    if executor is None and not worth_processes(sizes, n_jobs):
        out = []
        bar = new_bar()
        try:
            with threads(n_jobs):  # one input at a time: its long computations use the cores
                for item in items:
                    out.append(fn(item, progress=progress))
                    if bar is not None:
                        bar.update()
        finally:
            if bar is not None:
                bar.close()
        return out
    own = executor is None
    pool = executor or ProcessPoolExecutor(max_workers=n_jobs, mp_context=start_context())
    bar = None
    try:
        task = partial(apply_all, fn)
        futures = {pool.submit(task, [items[k] for k in batch]): batch for batch in batches(sizes, n_jobs)}
        bar = new_bar()  # after the workers are forked: the bar may start a monitor thread
        if meanwhile is not None:
            meanwhile()
        results: list[Any] = [None] * len(items)
        for fut in _completed(futures, executor):
            for k, result in zip(futures[fut], fut.result(), strict=True):
                results[k] = result
            if bar is not None:
                bar.update(len(futures[fut]))
        return results
    finally:
        if bar is not None:
            bar.close()
        if own:
            pool.shutdown(cancel_futures=True)


#: Seconds a Dask scheduler gets to accept a connection and answer the handshake.
SCHEDULER_TIMEOUT = 10.0
#: Schemes :func:`connect_scheduler` accepts (``host:port`` alone means ``tcp://``).
SCHEDULER_SCHEMES = ("tcp", "tls", "inproc")
_HOST_PORT = re.compile(r"(?P<host>\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+):(?P<port>[0-9]{1,5})")  # fullmatch


def scheduler_address(address: object) -> tuple[str, str, int]:
    """``(scheme, host, port)`` of a Dask scheduler address (``tcp://HOST:PORT``, ``tls://HOST:PORT``,
    ``HOST:PORT``, or ``inproc://...`` with host the rest and port 0); ValidationError naming
    the address and the expected form otherwise."""
    expected = "expected tcp://HOST:PORT (the scheduler's port, 8786 by default), tls://HOST:PORT or inproc://..."
    if not isinstance(address, str) or not address.strip():
        raise ValidationError(f"--scheduler {address!r}: {expected}")
    text = address.strip()
    scheme, sep, rest = text.partition("://")
    if not sep:
        scheme, rest = "tcp", text
    scheme = scheme.lower()
    if scheme not in SCHEDULER_SCHEMES:
        raise ValidationError(f"--scheduler {text}: unknown scheme {scheme!r}; {expected}")
    if scheme == "inproc":
        if not rest:
            raise ValidationError(f"--scheduler {text}: {expected}")
        return scheme, rest, 0
    m = _HOST_PORT.fullmatch(rest.rstrip("/"))
    if m is None or not 0 < int(m["port"]) < 65536:
        raise ValidationError(f"--scheduler {text}: not a HOST:PORT address; {expected}")
    return scheme, m["host"].strip("[]"), int(m["port"])


def probe_scheduler(address: str, timeout: float | None = None) -> None:
    """Check, within ``timeout`` seconds, that ``address`` accepts a TCP connection and (plain
    ``tcp``) speaks first as a Dask scheduler does (it sends its handshake on every connection):
    a closed port, a silent server, or an HTTP server (the dashboard's port, 8787, is the usual
    mistake) is an EvaluationError of one line naming the address. ``inproc`` is not probed.
    ``timeout`` defaults to :data:`SCHEDULER_TIMEOUT`."""
    timeout = SCHEDULER_TIMEOUT if timeout is None else float(timeout)
    scheme, host, port = scheduler_address(address)
    if scheme == "inproc":
        return
    try:
        sock = socket.create_connection((host, port), timeout=timeout)
    except TimeoutError:
        raise EvaluationError(
            f"--scheduler {address}: no answer within {timeout:g} s; is the scheduler running?"
        ) from None
    except OSError as exc:
        reason = exc.strerror or str(exc)
        raise EvaluationError(
            f"--scheduler {address}: cannot reach the Dask scheduler ({reason}); is it running there?"
        ) from None
    with sock:
        if scheme != "tcp":
            return
        sock.settimeout(timeout)
        try:
            head = sock.recv(8)
        except TimeoutError:
            head = None
        except OSError as exc:
            raise EvaluationError(f"--scheduler {address}: the connection failed ({exc.strerror or exc})") from None
    hint = "the scheduler's address is printed by `dask scheduler` ('Scheduler at: tcp://HOST:8786')"
    if head is None:
        raise EvaluationError(
            f"--scheduler {address}: the server there did not answer as a Dask scheduler within {timeout:g} s "
            f"(a web server, e.g. the dashboard's port 8787?); {hint}"
        )
    if head.startswith(b"HTTP") or head[:1] == b"<":
        raise EvaluationError(
            f"--scheduler {address}: that is a web server (the dashboard?), not a Dask scheduler; {hint}"
        )
    frames = int.from_bytes(head.ljust(8, b"\0"), "little")
    if len(head) < 8 or not 0 < frames < 1024:
        raise EvaluationError(f"--scheduler {address}: the server there does not speak Dask's protocol; {hint}")


def connect_scheduler(address: str, timeout: float | None = None) -> Any:
    """A ``distributed.Client`` of the Dask scheduler at ``address``, after
    :func:`scheduler_address` checked its form and :func:`probe_scheduler` its answer; every
    failure is one lorisnb error naming the address, within about ``timeout`` seconds."""
    from lorisnb.tools import require

    timeout = SCHEDULER_TIMEOUT if timeout is None else float(timeout)
    distributed = require("distributed")
    probe_scheduler(address, timeout)
    scheme, host, port = scheduler_address(address)
    normal = f"{scheme}://{host}" if scheme == "inproc" else f"{scheme}://[{host}]:{port}" if ":" in host else (
        f"{scheme}://{host}:{port}")  # fmt: skip  # the form checked (a trailing "/" failed in distributed)
    try:
        return distributed.Client(normal, timeout=timeout)
    except TypeError as exc:  # tls:// without a TLS configuration: distributed's own TypeError
        if scheduler_address(address)[0] != "tls":
            raise
        line = str(exc).splitlines()[0]
        raise EvaluationError(f"--scheduler {address}: tls:// needs Dask's TLS settings (distributed.comm.tls in "
                              f"the Dask configuration: ca-file, client cert and key), none found ({line})") from None  # fmt: skip
    except (OSError, TimeoutError, ValueError) as exc:
        line = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise EvaluationError(f"--scheduler {address}: cannot reach the Dask scheduler ({line})") from None
