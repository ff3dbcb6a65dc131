"""Scoring: each submission in a process of its own, forked from a server that has lorisnb's
evaluation already imported (``forkserver``), with a CPU-time and a memory limit
(``resource.setrlimit``) and a wall-clock deadline. The process scores the uploaded files with
:func:`lorisnb.tools.evaluation.runner.evaluate` (the pipeline of ``lorisnb evaluate``) against the
hidden ground truth, draws the paper's timeline figure, and writes its outcome to a JSON file
named for its claim; the server commits that outcome to the database (:func:`.store.finish`).

:class:`Scorer` is the server's loop over the persisted queue (:mod:`.store`): it puts back what a
killed server left half-scored, runs up to ``workers`` processes at a time and commits each
outcome once. With ``[challenge] scheduler`` each scoring is a task of that Dask cluster
(:func:`score_on_worker`: a fresh process on the worker, under the same limits).
"""

from __future__ import annotations

import json
import math
import multiprocessing
import os
import pickle
import resource
import signal
import subprocess
import sys
import threading
import time
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from sqlalchemy import Engine

from lorisnb.core.spec.evalspec import EvalSpec
from lorisnb.errors import LorisError, LorisWarning
from lorisnb.io.datasets.paths import DataPaths
from lorisnb.tools.challenge import store
from lorisnb.tools.challenge.config import Challenge
from lorisnb.tools.evaluation.runner import evaluate
from lorisnb.tools.evaluation.status import skipped_only

FILES = "files"  # a submission's folder: files/ (as uploaded), result-<claim>.json, timeline.png


def _plain(value: Any) -> Any:
    """A table value as JSON holds it (numpy scalars as Python ones; NaN and infinities as None)."""
    if hasattr(value, "item"):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value if isinstance(value, (int, float, str, bool)) or value is None else str(value)


def scrub(text: str, folder: Path, data: DataPaths) -> str:
    """A message with the server's paths taken out: the upload's folder (its files by name) and
    the hidden ground truth's folder (never named to a team)."""
    text = text.replace(f"{folder}{os.sep}", "").replace(str(folder), "the upload")
    return text.replace(str(data.root.resolve()), "<ground truth>").replace(str(data.root), "<ground truth>")


def score_folder(folder: Path, data: DataPaths, spec: EvalSpec, figure: Path | None = None) -> dict[str, Any]:
    """Score the result files in ``folder`` as ``lorisnb evaluate`` does: per-sequence rows (every
    column of :meth:`Evaluation.sequence_rows`), each file that failed or was not scored with its
    reason (paths scrubbed, :func:`scrub`), and the timeline figure written to ``figure``."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        ev = evaluate([folder], spec, data_root=data, jobs=1, progress=False)
        rows = ev.sequence_rows()
    problems = [("failed", f) for f in ev.failures] + [("not scored", f) for f in ev.unscored]
    problems += [("skipped", f) for f in skipped_only(ev)]
    failures = [dict(file=Path(f.path).name, status=s, error=scrub(f.error, folder, data)) for s, f in problems]
    notes = list(dict.fromkeys(scrub(str(w.message), folder, data) for w in caught
                               if "could not be evaluated" not in str(w.message)))  # fmt: skip
    out: dict[str, Any] = dict(
        rows=[{k: _plain(v) for k, v in r.items() if k != "spec"} | {"file": Path(str(r["file"])).name} for r in rows],
        failures=failures, notes=notes, conventions=ev.describe(), figure=False,
    )  # fmt: skip
    if figure is not None and ev.errors:
        try:
            import matplotlib

            matplotlib.use("Agg")
            from lorisnb.tools.figures.plotting import plot_timeline

            fig = plot_timeline(ev.errors, ev.durations(), ev.scenes(), spec.eps, spec.phi, spec.delta,
                                title="this submission")  # fmt: skip
            fig.savefig(figure, dpi=80)
            out["figure"] = True
        except (LorisError, ValueError) as exc:
            out["notes"].append(f"no timeline figure: {scrub(str(exc), folder, data)}")
    return out


def _limit(cpu_seconds: int, memory_bytes: int) -> None:
    resource.setrlimit(resource.RLIMIT_CPU, (cpu_seconds, cpu_seconds + 5))  # SIGXCPU, then SIGKILL
    resource.setrlimit(resource.RLIMIT_AS, (memory_bytes, memory_bytes))


def _write(path: Path, outcome: dict[str, Any]) -> None:
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(outcome), encoding="utf-8")
    os.replace(tmp, path)


def score_in_child(folder: str, data: DataPaths, spec: EvalSpec, out: str, cpu_seconds: int, memory_bytes: int) -> None:
    """The scoring process: limits set, then :func:`score_folder`, its outcome written to ``out``."""
    _limit(cpu_seconds, memory_bytes)
    sub = Path(folder)
    try:
        outcome = score_folder(sub / FILES, data, spec, sub / "timeline.png")
    except MemoryError:
        outcome = dict(error=f"scoring needed more than the challenge's memory limit of {memory_bytes / 1e6:g} MB")
    except LorisError as exc:
        outcome = dict(error=scrub(str(exc), sub / FILES, data))
    except Exception as exc:  # any other error of the scorer: said by its type only (no server detail)
        outcome = dict(error=f"the scorer could not score this upload ({type(exc).__name__}); tell the organizers")
    _write(Path(out), outcome)


def stopped(exitcode: int | None, cpu_seconds: int) -> str:
    """Why a scoring process ended without an outcome: killed at its CPU-time limit (SIGXCPU at
    the soft limit, SIGKILL at the hard one), or another exit status."""
    if exitcode in (-signal.SIGXCPU, -signal.SIGKILL):
        return f"scoring exceeded the challenge's limit of {cpu_seconds} CPU seconds"
    return f"the scorer stopped (exit status {exitcode}); tell the organizers"


def score_on_worker(folder: str, data: DataPaths, spec: EvalSpec, out: str, cpu_seconds: int,
                    memory_bytes: int) -> int:  # fmt: skip
    """On a Dask worker (``[challenge] scheduler``): :func:`score_in_child` in a fresh Python
    process of its own, so that the limits bind that process and not the worker; its exit status
    (negative: the signal that ended it). The upload's folder and the ground truth must be at the
    same paths on the worker (a shared file system)."""
    args = pickle.dumps((folder, data, spec, out, cpu_seconds, memory_bytes))
    cmd = [sys.executable, "-c", "from lorisnb.tools.challenge.scoring import child_main; child_main()"]
    try:
        done = subprocess.run(cmd, input=args, capture_output=True, timeout=2 * cpu_seconds + 30)
    except subprocess.TimeoutExpired:
        return -int(signal.SIGKILL)
    return int(done.returncode)


def child_main() -> None:
    """The process :func:`score_on_worker` starts: its arguments pickled on stdin (from the server
    itself, never from an upload)."""
    score_in_child(*pickle.loads(sys.stdin.buffer.read()))


class _Remote:
    """A scoring on the Dask cluster, seen as a process (is_alive, kill, join, exitcode)."""

    def __init__(self, future: Any):
        self.future = future

    def is_alive(self) -> bool:
        return not self.future.done()

    def kill(self) -> None:
        self.future.cancel()

    def join(self, timeout: float | None = None) -> None:
        return None

    @property
    def exitcode(self) -> int | None:
        if self.future.status != "finished":
            return None
        return int(self.future.result())


@dataclass
class _Running:
    process: Any
    claim: str
    started: float
    out: Path


class Scorer:
    """The queue's loop (a thread of the server): see the module docstring."""

    def __init__(self, challenge: Challenge, engine: Engine, poll: float = 0.1):
        self.challenge = challenge
        self.engine = engine
        self.poll = poll
        self.limits = challenge.limits
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._running: dict[str, _Running] = {}
        self._context = multiprocessing.get_context("forkserver")
        self._context.set_forkserver_preload(["lorisnb.tools.challenge.preload"])
        self._client: Any = None
        if challenge.scheduler is not None:  # scoring on the Dask cluster lorisnb evaluates on
            from lorisnb.tools.evaluation.pool import connect_scheduler

            self._client = connect_scheduler(challenge.scheduler)
        self.requeued = 0

    def start(self) -> None:
        self.requeued = store.requeue_unfinished(self.engine)  # what a killed server left half-scored
        self._thread = threading.Thread(target=self._loop, name="lorisnb-scorer", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stop taking work; scorings under way are stopped and stay queued for the next start."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=10)
        for r in self._running.values():
            r.process.kill()
            r.process.join(timeout=5)
        self._running.clear()
        if self._client is not None:
            self._client.close()

    def _loop(self) -> None:
        while not self._stop.is_set():
            try:
                self._reap()
                while len(self._running) < self.limits["workers"] and not self._stop.is_set():
                    claimed = store.claim_next(self.engine)
                    if claimed is None:
                        break
                    try:
                        self._start(*claimed)
                    except Exception:
                        store.release(self.engine, *claimed)  # queued again, not left half-taken
                        raise
            except Exception as exc:  # the database busy or gone for a moment: try again, say so
                print(f"lorisnb serve: scorer: {type(exc).__name__}: {exc}", flush=True)
            self._stop.wait(self.poll)

    def _start(self, sid: str, claim: str) -> None:
        folder = self.challenge.folder / "uploads" / sid
        out = folder / f"result-{claim}.json"
        memory = self.limits["score_memory_mb"] * 1_000_000
        args = (str(folder), self.challenge.data, self.challenge.spec, str(out), self.limits["score_seconds"], memory)
        if self._client is not None:
            future = self._client.submit(score_on_worker, *args, key=f"lorisnb-score-{sid}-{claim}", pure=False)
            self._running[sid] = _Running(_Remote(future), claim, time.monotonic(), out)
            return
        p = self._context.Process(
            target=score_in_child,
            args=(str(folder), self.challenge.data, self.challenge.spec, str(out), self.limits["score_seconds"], memory),
            name=f"lorisnb-score-{sid}", daemon=True,
        )  # fmt: skip
        p.start()
        self._running[sid] = _Running(p, claim, time.monotonic(), out)

    def _reap(self) -> None:
        deadline = 2 * self.limits["score_seconds"] + 30  # wall clock: a scorer asleep uses no CPU time
        for sid, r in list(self._running.items()):
            took = time.monotonic() - r.started
            if r.process.is_alive():
                if took > deadline:
                    r.process.kill()
                    r.process.join(5)
                    self._done(sid, r, "failed", None, f"scoring took longer than {deadline} s; stopped", took)
                continue
            r.process.join()
            outcome = json.loads(r.out.read_text(encoding="utf-8")) if r.out.is_file() else None
            if outcome is not None and "rows" in outcome:
                self._done(sid, r, "scored", outcome, None, took)
            elif outcome is not None:
                self._done(sid, r, "failed", None, str(outcome["error"]), took)
            else:
                self._done(sid, r, "failed", None, stopped(r.process.exitcode, self.limits["score_seconds"]), took)

    def _done(self, sid: str, r: _Running, status: str, result: Any, error: str | None, took: float) -> None:
        store.finish(self.engine, sid, r.claim, status, result, error, took)
        del self._running[sid]
