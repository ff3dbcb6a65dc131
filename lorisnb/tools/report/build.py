"""Batch reports: evaluate the results once for the front page's leaderboard, run the notebooks
with papermill (in parallel where cores allow) into a new run folder under ``results/``, export
each to offline HTML, and write ``index.html`` (findings first, then the evidence), ``report.html``
(the same page in one file) and ``run.json`` (provenance, see :mod:`lorisnb.tools.report.provenance`).

A run is built in a temporary folder and moved into place at the end, so an interrupted run
leaves nothing half-written, and an existing run folder is never replaced without ``force``.
The finished folder is readable like any other output (the umask's permissions, not owner-only).
"""

from __future__ import annotations

import contextlib
import dataclasses
import datetime as _dt
import errno
import functools
import hashlib
import json
import os
import re
import shutil
import socket
import stat
import sys
import tempfile
import warnings
from collections.abc import Callable, Iterable, Iterator, Mapping
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path, PurePosixPath
from typing import Any

from lorisnb.core.spec import validate
from lorisnb.errors import DataNotFoundError, LorisError, LorisWarning, OutputError, ParseError, ValidationError
from lorisnb.io.datasets.paths import find_data
from lorisnb.io.writers import name_output, naming, overlap, remove_partial, write_csv, write_text
from lorisnb.tools.decisions.escape import clean
from lorisnb.tools.decisions.history import earlier_runs
from lorisnb.tools.evaluation.pool import start_context
from lorisnb.tools.evaluation.runner import check_filters, result_files
from lorisnb.tools.notebook.params import (
    check_parameters,
    eps_values,
    input_scenes,
    refuse_eps_gaps,
    refuse_simulated_off,
    user_path,
)
from lorisnb.tools.notebook.start import INPUT_ERRORS_CSV, RUN_MARKER
from lorisnb.tools.report import kernels as warm_kernels
from lorisnb.tools.report.baseline import since_baseline
from lorisnb.tools.report.html import single_file, write_notebook_css
from lorisnb.tools.report.index import expected_spans, git_dirty, versions, write_index
from lorisnb.tools.report.leaderboard import leaderboard_spec, refuse_unscorable_scenes, report_findings
from lorisnb.tools.report.lean_imports import jsonschema_without_iri_grammars
from lorisnb.tools.report.notebooks import (
    DEFAULT_NOTEBOOKS,
    KERNEL_ARGS,
    NOTEBOOK_CSS,
    NOTEBOOK_NEEDS,
    TYPICAL_SECONDS,
    NotebookRun,
    available_notebooks,
    current_kernel_files,
    declared_by,
    declared_parameters,
    input_roots,
    kernel_env,
    kernel_files,
    notebook_dir,
    notebook_path,
    refuse_eps_scenes,
    refuse_inapplicable_specs,
    run_one,
    select_notebooks,
    use_kernel_files,
    warm_kernels_for_report,
)
from lorisnb.tools.report.portable import (
    author_folders,
    install_roots,
    make_portable,
    named_roots,
    root_key,
    split_paths,
    unreplaced,
)
from lorisnb.tools.report.provenance import (
    checksums,
    input_files,
    links_out,
    read_run_file,
    run_file,
    run_record,
    sha256,
    where_it_is,
    with_baseline,
    write_run_json,
)

__all__ = [
    "DEFAULT_NOTEBOOKS", "findings_input_errors", "KERNEL_ARGS", "NOTEBOOK_NEEDS", "RUN_MARKER", "NotebookRun", "available_notebooks",
    "check_parameters", "declared_parameters", "kernel_env", "notebook_dir", "notebook_path", "run_notebook",
    "render_run", "run_report",
]  # fmt: skip

run_notebook = run_one  # the name the report calls (tests replace it)

#: What a worker imports to run a notebook and export its page: imported once here before the
#: workers are forked from this process (where it runs a single thread; spawned otherwise).
WORKER_MODULES = ("papermill", "nbclient", "nbconvert", "jupyter_client.manager")


def _new_run_dir(out: str | os.PathLike[str] | None) -> Path:
    if out is not None:
        if str(out).strip() == "":
            raise ValidationError("--out: an empty path; expected a folder for the run")
        return Path(out)
    stamp = _dt.datetime.now().strftime("%Y%m%d-%H%M%S")
    base = Path.cwd() / "results" / f"run-{stamp}"
    p, k = base, 1
    while p.exists():
        k += 1
        p = base.with_name(f"{base.name}-{k}")
    return p


def _protected(run_dir: Path, extra: list[Path]) -> str | None:
    """Why ``run_dir`` may not be replaced, or None."""
    target = run_dir.resolve()
    cwd = Path.cwd().resolve()
    if target == cwd or target in cwd.parents:
        return "it is the current folder or one of its parents; choose another --out"
    for p in extra:
        p = p.resolve()
        if target == p or target in p.parents or p in target.parents:
            return f"it holds or is inside {p}; choose another --out"
    if not (run_dir / RUN_MARKER).is_file():
        return f"it is not a lorisnb run folder (no {RUN_MARKER} file in it); choose another --out"
    return _not_written(run_dir)


def _meets_inputs(run_dir: Path, inputs: Iterable[Path], read: Iterable[Path] = ()) -> tuple[str, str] | None:
    """How the run folder ``run_dir`` meets the files and folders the report reads (``("lies in",
    input)``...: :func:`~lorisnb.io.writers.overlap`), compared where each really is (links resolved)
    and as written (``--out res/linked/run``, ``linked`` a link leading elsewhere, lies in ``res`` as
    the report reads it), and in a folder it reads through a link below the folders it walks, ``read``
    (``("lies in", "res/linked (a linked folder...)")``, ``--out`` given where ``linked`` leads); None
    when it meets none."""
    inputs = list(inputs)
    hit = overlap(run_dir, inputs) or overlap(run_dir, inputs, resolve=False)  # where each is, and as written
    if hit:
        return hit
    from lorisnb.tools.evaluation.inputs import walk

    target = run_dir.resolve()
    for i in read:
        if not Path(i).is_dir():
            continue
        with warnings.catch_warnings():  # a loop among the links: said by the evaluation, once
            warnings.simplefilter("ignore", LorisWarning)
            found = walk(Path(i))
        for f in found:
            if f.kind == "folder" and f.path.is_symlink():
                real = Path(f.real)
                if target == real or real in target.parents:
                    return "lies in", f"{f.path} (a linked folder: the report reads the folder it leads to)"
    return None


def _files(folder: Path) -> dict[str, str]:
    """Every file, link and empty folder below ``folder`` (its path inside, POSIX) -> its SHA-256
    (a link's: of its target's name; an empty folder's: "folder"); the run marker aside. A FIFO or
    a device in it (a received run: tar keeps them) is a :class:`~lorisnb.errors.ValidationError`
    naming it, never opened (:func:`~lorisnb.tools.report.provenance.run_file`)."""
    out: dict[str, str] = {}
    for top, dirs, files in os.walk(folder):
        here = Path(top)
        for n in files + [d for d in dirs if (here / d).is_symlink()]:
            p = here / n
            rel = p.relative_to(folder).as_posix()
            if rel != RUN_MARKER:
                out[rel] = (hashlib.sha256(os.readlink(p).encode()).hexdigest() if p.is_symlink()
                            else sha256(run_file(folder, p)))  # fmt: skip
        if not dirs and not files and here != folder:
            out[here.relative_to(folder).as_posix() + "/"] = "folder"
    return out


def _write_marker(folder: Path, files: Mapping[str, str] | None = None, out: Path | None = None) -> None:
    """The run marker: lorisnb's version, the pid and, once the run is complete, every file it wrote
    (``files``: :func:`_files`), which is all ``--force`` may later remove. Into ``out`` if given
    (a temporary name moved into place later), written whole or not at all."""
    record: dict[str, Any] = {"lorisnb": versions()["lorisnb"], "pid": os.getpid()}
    if files is not None:
        record["files"] = dict(files)
    write_text(json.dumps(record, indent=0), out if out is not None else folder / RUN_MARKER, force=True)


@dataclasses.dataclass(frozen=True)
class _AsWritten:
    """A run folder against its marker (:func:`_against_marker`): ``foreign``, the files its run did
    not write or that changed since; ``missing``, those it wrote that are gone; ``marker``, what is
    wrong with the marker itself ("missing", "damaged": it lists no files where the run's lorisnb
    always lists them), or None."""

    foreign: list[str]
    missing: list[str]
    marker: str | None = None

    def all(self) -> list[str]:
        """Every file of the run not as written, the marker too where it is missing or damaged."""
        return sorted({*self.foreign, *self.missing, *([RUN_MARKER] if self.marker else [])})


def _lists_its_files(run_dir: Path) -> bool:
    """Whether the run's run.json says the lorisnb that wrote it always writes the run's marker, listing
    the run's files: it has ``roots`` (named roots came after the marker's list of files, both of
    lorisnb 0.3.0: a marker has been written beside every run.json, its list of files since 2026-11-26,
    ``roots`` since 2026-11-28)."""
    from lorisnb.tools.report.provenance import RUN_JSON, load_json

    try:
        record = load_json(read_run_file(run_dir, run_dir / RUN_JSON), run_dir / RUN_JSON, "run.json")
    except (OSError, ValueError, LorisError):
        return False
    return isinstance(record, dict) and "roots" in record


def _against_marker(run_dir: Path, ignore: Iterable[str] = ()) -> _AsWritten | None:
    """The run folder ``run_dir`` against its marker (:class:`_AsWritten`); None where the marker
    lists nothing and the run may be one of an earlier lorisnb (no run.json saying otherwise:
    :func:`_lists_its_files`). A marker missing, or listing nothing, beside a run.json of a lorisnb
    that always writes one listing the run's files is damage (a marker removed hid every hand edit),
    not an earlier run. ``ignore``: files of the folder (paths inside it) that are none of the run's
    and not counted as added (render's own lock, :data:`RENDER_LOCK`, while it holds it)."""
    from lorisnb.tools.report.provenance import load_json

    marker = run_dir / RUN_MARKER
    try:
        raw = read_run_file(run_dir, marker)
    except LorisError:
        raise
    except OSError:
        wrote = None
    else:
        try:  # not JSON, nested too deeply, a key given twice: a damaged marker
            wrote = load_json(raw, marker, "the marker lorisnb writes").get("files")
        except (ValueError, AttributeError):
            wrote = None
    if isinstance(wrote, dict):
        for rel in wrote:  # a file of the run, by its path inside it: one elsewhere is no file of the run
            parts = PurePosixPath(rel).parts
            if not rel or PurePosixPath(rel).is_absolute() or ".." in parts or "\x00" in rel:
                raise ValidationError(f"{marker}: lists {rel!r}, which is no file inside the run folder; a "
                                      "marker lorisnb writes lists only the run's own files (an edited marker?). "
                                      "Nothing outside the run was read: copy the run again from where it came, or "
                                      "make it again with lorisnb report")  # fmt: skip
        here = _files(run_dir)
        for rel in ignore:
            here.pop(rel, None)
        foreign = sorted(rel for rel, digest in here.items() if wrote.get(rel) != digest)
        missing = sorted(rel for rel in wrote if rel not in here and rel != RUN_MARKER)
        return _AsWritten(foreign, missing)
    if _lists_its_files(run_dir):
        return _AsWritten([], [], "damaged" if os.path.lexists(marker) else "missing")
    return None


def not_as_written(run_dir: Path) -> list[str] | None:
    """The files of a run folder (relative paths) that its run did not write, that changed since, or
    that it wrote and are gone, as its marker lists them with their checksums; the marker itself
    (:data:`RUN_MARKER`) where it is missing or lists nothing beside a run.json of a lorisnb that
    always writes it listing the run's files (damage, not an earlier run: :func:`_lists_its_files`).
    None where the marker lists nothing and the run may be one of an earlier lorisnb. A marker, or a file of the run, that is a link
    leading out of it, a FIFO or a device is a :class:`~lorisnb.errors.ValidationError` naming it,
    unread (:func:`~lorisnb.tools.report.provenance.read_run_file`)."""
    found = _against_marker(run_dir)
    return None if found is None else found.all()


def missing_run_files(run_dir: Path) -> list[str]:
    """The files of a run folder its marker lists that are gone (relative paths), and the marker
    where it is gone and the run's lorisnb always writes it (:func:`not_as_written`): what verify
    should say is missing, where :func:`not_as_written` says only "not as written"."""
    found = _against_marker(run_dir)
    if found is None:
        return []
    return sorted({*found.missing, *([RUN_MARKER] if found.marker == "missing" else [])})


def _not_written(run_dir: Path, instead: str = "choose another --out", render: bool = False,
                 ignore: Iterable[str] = ()) -> str | None:  # fmt: skip
    """Why ``--force`` may not replace the run folder ``run_dir`` (or render may not write into it):
    it holds a file its run did not write (added or changed since, as its marker lists them), or its
    marker lists nothing; else None. ``instead``: what else the user can do, ending the message.
    ``render``: the advice is render's (its pages are made from index.html and the notebooks, which
    cannot be moved out; a run whose marker lists nothing cannot be rendered, only made again; a
    run missing a file it wrote other than a page render writes again is not rendered either: the
    marker render writes would no longer list it, and verify would not see it is gone). ``ignore``:
    as :func:`_against_marker`'s."""
    found = _against_marker(run_dir, ignore)
    if found is None or found.marker is not None:
        if render:
            return (f"its {RUN_MARKER} marker does not list the files its run wrote (a run of an earlier lorisnb, or "
                    "a damaged marker), so its pages cannot be told from files added since; make the run again with "
                    "lorisnb report (its numbers are in its findings/ tables meanwhile)")  # fmt: skip
        return (f"its {RUN_MARKER} marker does not list the files its run wrote (a run of an earlier lorisnb, "
                "or a damaged marker), so files added to it cannot be told apart; move what you keep out of it "
                f"and remove it yourself, or {instead}")  # fmt: skip
    foreign = found.foreign
    if render and not foreign:
        pages = {"report.html", *(f"{nb.parent.name}/{nb.stem}.html" for nb in run_dir.glob("*/*.ipynb")
                                  if nb.parent.name == nb.stem)}  # fmt: skip
        gone = [f for f in found.missing if f not in pages]
        if gone:
            shown = ", ".join(gone[:5]) + (f" and {len(gone) - 5} more" if len(gone) > 5 else "")
            return (f"{len(gone)} file(s) its run wrote are gone ({shown}); render writes only its pages again, and "
                    "the run would then be without them unnoticed: put them back (from where the run was copied), "
                    "then render again")  # fmt: skip
    if not foreign:
        return None
    shown = ", ".join(foreign[:5]) + (f" and {len(foreign) - 5} more" if len(foreign) > 5 else "")
    read = [f for f in foreign if f == "index.html" or f.endswith(".ipynb")]
    if render and read:  # what render reads: moved out, the run is no run; put back as the run wrote it
        return (f"it holds {len(foreign)} file(s) that its run did not write or that changed since ({shown}); "
                f"{', '.join(read[:3])} {'is' if len(read) == 1 else 'are'} what render reads: put back the run's own "
                "(from where the run was copied) and move any other out, then render again")  # fmt: skip
    return (f"it holds {len(foreign)} file(s) that its run did not write or that changed since ({shown}); nothing "
            f"was removed: move them out of it and run again, or {instead}")  # fmt: skip


def _by_root(failures: Any, named: Mapping[str, Path]) -> Any:
    """The failures table (:meth:`Evaluation.failures_table`) with each input named by its root
    (:func:`root_key`: ``{results}/alg/x.txt``), in its ``file`` column and where its error starts
    with it."""
    failures = failures.copy()
    keyed = {f: root_key(Path(f), named) for f in failures["file"].unique()}
    failures["error"] = [keyed[f] + e[len(f):] if isinstance(e, str) and e.startswith(f) else e
                         for f, e in zip(failures["file"], failures["error"], strict=True)]  # fmt: skip
    failures["file"] = failures["file"].map(keyed)
    return failures


def _run_all(names: list[str], tmp: Path, params: Mapping[str, Any], notebooks_dir: Any, jobs: int,
             progress: bool, zygote: warm_kernels.Zygote | None = None,
             meanwhile: Callable[[], None] = lambda: None) -> list[NotebookRun]:  # fmt: skip
    """Run the notebooks, ``jobs`` at a time, each in its own worker process (papermill's clients
    are not safe side by side in one process) and kernel; one at a time in this process when
    ``jobs`` is 1. Kernels are forked from ``zygote`` where given. Results in ``names`` order; the
    longest notebooks start first. ``meanwhile()`` runs in this process while the workers run
    (before the notebooks, when ``jobs`` is 1)."""
    runs: dict[int, NotebookRun] = {}
    order = sorted(range(len(names)), key=lambda i: -TYPICAL_SECONDS.get(Path(names[i]).stem, 0))
    if jobs > 1 and len(names) > 1:
        _run_pool(names, order, runs, tmp, params, notebooks_dir, jobs, progress, meanwhile, zygote)
        return [runs[i] for i in range(len(names))]
    meanwhile()
    warm_kernels.use(zygote)
    try:
        with _bar(progress, len(names)) as bar:
            for i in order:
                runs[i] = run_notebook(names[i], tmp, params, notebooks_dir=notebooks_dir)
                bar(runs[i].name)
    finally:
        warm_kernels.use(None)
    return [runs[i] for i in range(len(names))]


@contextlib.contextmanager
def _bar(progress: bool, total: int) -> Iterator[Callable[[str], None]]:
    """A progress bar over the notebooks (none without ``progress``); yields ``done(name)``."""
    if not progress:
        yield lambda name: None
        return
    from tqdm.auto import tqdm

    bar = tqdm(total=total, desc="report", unit="notebook")

    def done(name: str) -> None:
        bar.set_postfix_str(name)
        bar.update()

    try:
        yield done
    finally:
        bar.close()


def _run_pool(names: list[str], order: list[int], runs: dict[int, NotebookRun], tmp: Path, params: Mapping[str, Any],
              notebooks_dir: Any, jobs: int, progress: bool, meanwhile: Callable[[], None], zygote: Any) -> None:  # fmt: skip
    """:func:`_run_all`'s notebooks in ``jobs`` worker processes, their kernels forked from ``zygote``.
    The workers start (forked where this process runs a single thread) before the progress bar,
    whose monitor thread would otherwise rule out forking."""
    import multiprocessing

    context = start_context(WORKER_MODULES, fallback="spawn")  # forked: no interpreter to start, nothing to import
    with ProcessPoolExecutor(max_workers=jobs, mp_context=context, initializer=_worker_start,
                             initargs=(zygote, current_kernel_files())) as pool:  # fmt: skip
        futures = {pool.submit(run_notebook, names[i], tmp, dict(params), notebooks_dir=notebooks_dir): i
                   for i in order}  # fmt: skip
        try:
            with _bar(progress, len(names)) as bar:
                meanwhile()
                for fut in as_completed(futures):
                    runs[futures[fut]] = fut.result()
                    bar(runs[futures[fut]].name)
        except BaseException:  # Ctrl-C or an error here: stop the workers (their kernels follow them)
            pool.shutdown(wait=False, cancel_futures=True)
            workers = multiprocessing.active_children()
            for worker in workers:
                worker.terminate()
            for worker in workers:  # gone before the caller removes the run folder they write in
                worker.join(5)
            raise


def _worker_start(zygote: warm_kernels.Zygote | None, kernel_dir: str | None = None) -> None:
    """A report worker's set-up: papermill's imports without what they need not import
    (:mod:`lorisnb.tools.report.lean_imports`), kernels forked from ``zygote``, their connection files and
    sockets in the report's ``kernel_dir`` (:func:`kernel_files`)."""
    jsonschema_without_iri_grammars()
    warm_kernels.use(zygote)
    use_kernel_files(kernel_dir)
    _end_with_parent(kernel_dir)


def _end_with_parent(kernel_dir: str | None, every: float = 1.0) -> None:
    """End this worker once the process that started it is gone (killed outright, ``kill -9``: it
    could not stop its workers, which then finished their notebooks and waited on the pool's queue
    for ever). A daemon thread compares the parent's pid every ``every`` seconds; an orphan is
    adopted by another process, removes the report's kernel folder if it is empty (no kernel is
    left to), and ends itself with SIGTERM as the report's own stop would (its kernels follow it,
    removing their files, :mod:`lorisnb.tools.report.kernels`)."""
    import signal
    import threading
    import time

    parent = os.getppid()

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(every)
        if kernel_dir is not None:
            with contextlib.suppress(OSError):  # not empty: a kernel's files, which it removes as it ends
                os.rmdir(kernel_dir)
        os.kill(os.getpid(), signal.SIGTERM)

    threading.Thread(target=watch, name="lorisnb-report-parent", daemon=True).start()


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def python_call() -> list[str]:
    """How a run made from Python is recorded in ``run.json``'s ``command``: ``python`` and the
    name of the script that called :func:`run_report` (a Jupyter kernel's launcher, in a notebook),
    without its folder or arguments. ``sys.argv`` itself was recorded, and it holds this machine's
    paths (a kernel's connection file, ``/home/me/.local/share/jupyter/runtime/kernel-....json``):
    every run made from a notebook warned that it shows an absolute path."""
    script = os.path.basename(sys.argv[0]) if sys.argv and sys.argv[0] not in ("", "-c", "-m") else ""
    return ["python", script] if script else ["python"]


def run_report(
    out: str | os.PathLike[str] | None = None,
    parameters: Mapping[str, Any] | None = None,
    notebooks: Iterable[str] | None = None,
    force: bool = False,
    progress: bool = True,
    notebooks_dir: str | os.PathLike[str] | None = None,
    protect: Iterable[str | os.PathLike[str]] = (),
    results: str | os.PathLike[str] | None = None,
    jobs: int | None = None,
    command: list[str] | None = None,
    label: str | None = None,
    baseline: str | os.PathLike[str] | None = None,
    absolute_paths: bool = False,
) -> tuple[Path, list[NotebookRun]]:
    """Run the notebooks into a new run folder; returns (run folder, notebook runs).

    Args:
        out: the run folder; default ``results/run-<date>-<time>`` below the current folder. An
            existing folder is an error unless ``force``, and even then only a run folder that
            lorisnb wrote (it holds :data:`RUN_MARKER`) is replaced, never the current folder, one
            of its parents, the notebooks or a folder in ``protect`` (inputs, the data root).
        parameters: papermill parameters; each notebook gets those it declares. A parameter no
            selected notebook declares, or a value the command line would refuse, is an error.
        notebooks: names or paths (default: every notebook of the folder, shipped ones in
            :data:`DEFAULT_NOTEBOOKS` order, others alphabetically after). A notebook that cannot
            run (invalid JSON, no kernelspec, no ``parameters`` cell) is a failed entry.
        notebooks_dir: where the notebooks are (default: those shipped with lorisnb).
        results: a lab's results folder (``<algorithm>/*.txt``, trials allowed): the leaderboard's
            input and the notebooks' ``results_dir``; notebooks about the bundled data only are
            left out unless named.
        jobs: notebooks run at a time (default: the cores, at most the number of notebooks).
        command: the command line recorded in ``run.json`` (default: the Python call,
            :func:`python_call`).
        label: the code under test (its commit, tag or any name, e.g. ``$GITHUB_SHA``), recorded in
            ``run.json`` and shown on the front page and in ``history``.
        baseline: a folder of earlier runs: the front page gains "Since the baseline", this run
            against the newest comparable one there (:mod:`lorisnb.tools.report.baseline`).
        absolute_paths: write the absolute paths of the inputs, the data root and the results
            folder into the run; by default every path is written below a named root (``{data}``,
            ``{results}``...) and the run folder holds no absolute path of this machine's
            (:mod:`lorisnb.tools.report.portable`).

    The leaderboard is built when ``results`` is given or a selected notebook declares
    ``results_dir`` (the bundled icra20 results otherwise). The run is built under a hidden
    temporary name beside ``out`` and moved into place when complete; if ``out`` appeared
    meanwhile (another run), this run is kept under ``out-2`` (or the next free name) instead,
    and the returned path says so. On Ctrl-C the temporary folder is removed and
    KeyboardInterrupt propagates.
    """
    label = None if label is None else validate.code_label(label)
    given = (parameters or {}).get("results_dir")  # two folders: refused before any file is read (-p
    # results_dir /tmp was scanned for result files, all of it, before this was said)
    if results is not None and given is not None and user_path(str(given)).resolve() != Path(results).resolve():
        raise ValidationError("--results and -p results_dir name two folders; give one")
    if baseline is not None:
        earlier_runs(baseline)  # a folder without earlier runs: refused before anything runs
        if results is None:
            raise ValidationError("--baseline: compares the report's own evaluation of a results folder with earlier "
                                  "runs; give --results DIR too")  # fmt: skip
    run_dir = _new_run_dir(out)
    nb_dir = notebook_dir(notebooks_dir)
    keep_safe = [nb_dir, *map(Path, protect), Path(__file__).resolve().parents[2]]
    if results is not None:
        if not Path(results).is_dir() or not result_files([results]):
            raise ValidationError(
                f"--results {results}: {'no result files in it' if Path(results).is_dir() else 'not a folder'}; "
                "expected a folder of <algorithm>/*.txt result files"
            )
        keep_safe.append(Path(results))
    if run_dir.exists():
        if not force:
            raise LorisError(f"{run_dir} exists; choose another --out or pass --force to replace it")
        why = _protected(run_dir, keep_safe)
        if why:
            raise LorisError(f"--force will not replace {run_dir}: {why}")
    names, left_out = select_notebooks(notebooks, notebooks_dir, results)
    with kernel_files(), warm_kernels_for_report() if len(names) > 1 else contextlib.nullcontext(None) as zygote:
        # the zygote starts now: it imports the kernels' modules while the notebooks are checked
        declared = declared_by(names, notebooks_dir)
        if "output_dir" in (parameters or {}):  # each notebook writes into its own folder of the run: set here
            raise ValidationError("-p output_dir: the report sets each notebook's output folder (its folder of the "
                                  "run); choose where the run goes with --out (run_report's out)")  # fmt: skip
        params = check_parameters(dict(parameters or {}), declared, [Path(n).stem for n in names])
        refuse_inapplicable_specs(names, notebooks_dir, params)  # as each notebook would, minutes later
        if results is not None and "results_dir" in declared:
            params["results_dir"] = str(Path(results).resolve())
            refuse_simulated_off(params)  # a simulated section's value given with --results: refused now
        try:
            data = find_data(params.get("data_root"))
        except DataNotFoundError:
            data = None  # the notebooks say so, each in its entry
        if data is not None and "data_root" in declared:
            params.setdefault("data_root", str(data.root))  # kernels run in the run folder, not here
        wants_board = results is not None or "results_dir" in declared
        given_source = results if results is not None else params.get("results_dir")  # the leaderboard's input
        source = Path(str(given_source)) if given_source else (data.icra20 if data else None)
        roots = input_roots(names, params, data, source if wants_board else None)
        hit = _meets_inputs(run_dir, [*roots, nb_dir, *([data.root] if data is not None else [])], roots)  # data root
        if hit:  # the run would be read as an input by the next report on the same folder, and by verify
            raise OutputError(f"--out {run_dir} {hit[0]} the input {hit[1]} of this report; choose another folder")
        if source is not None:  # a filter naming nothing there is refused now, not by each notebook later
            check_filters(source, params.get("algorithms"), params.get("scenes"), params.get("trials_by"))
            if data is not None:  # a filter on scenes without ground truth only: nothing to score
                refuse_unscorable_scenes(params.get("scenes"), data)
        if wants_board:  # the notebooks' spec (one from the parameters): refused now if it cannot apply
            leaderboard_spec(params)
        if data is not None:  # an eps mapping (eps, an eps_grid element) missing a scene scored: refused now
            refuse_eps_scenes(names, notebooks_dir, params, data)
            if wants_board and source is not None and isinstance(params.get("eps"), Mapping):
                scored = input_scenes(source, data, params.get("algorithms"), params.get("scenes"),
                                      params.get("trials_by"))  # fmt: skip
                refuse_eps_gaps(eps_values({"eps": params["eps"]}), scored, "the report's leaderboard")
        try:  # the run is written beside where it goes, then moved there whole
            run_dir.parent.mkdir(parents=True, exist_ok=True)
            # absolute: a relative --out left papermill's output_path as "out/.r1.partial-XXXX/...", not {run}/...
            tmp = Path(os.path.abspath(tempfile.mkdtemp(prefix=f".{run_dir.name}.partial-", dir=run_dir.parent)))
        except OSError as exc:
            raise OutputError(f"--out {run_dir}: cannot write into {run_dir.parent} ({exc.strerror or exc}); "
                              "choose a folder you can write to") from None  # fmt: skip
        try:
            _write_marker(tmp)
            try:
                write_notebook_css(tmp / NOTEBOOK_CSS)
            except (OSError, IndexError, LorisError):  # no nbconvert templates: each page keeps its own style
                pass
            board: dict[str, Any] = {"spec": {"description": None, "values": {}}}
            named = named_roots(params, data.root if data else None, given_source, nb_dir if notebooks_dir else None)

            def leaderboard() -> None:  # the report's own evaluation, while the notebooks run
                if not (wants_board and source is not None and data is not None):
                    return
                findings, ev, values = report_findings(source, data, params)
                (tmp / "findings").mkdir()
                per_sequence = ev.sequences()  # the spec of the parameters, as the notebooks' (leaderboard_spec)
                failures = ev.failures_table()
                if not absolute_paths:  # each input by its root's name, as run.json names it (not as typed: a
                    # path relative to where the command ran means nothing once the run is moved)
                    failures = _by_root(failures, named)
                for table, name in ((per_sequence, "sequences.csv"), (findings.board, "leaderboard.csv"),
                                    (findings.pairs, "pairwise.csv"), (failures, INPUT_ERRORS_CSV),
                                    (ev.durations(), "durations.csv")):  # fmt: skip  # every sequence: diff, history
                    write_csv(table, tmp / "findings" / name)
                board.update(findings=findings, per_sequence=per_sequence, failures=failures, expected=expected_spans(ev, data, values["scenes"]),
                             spec={"description": ev.conventions, "values": {**ev.spec.to_dict(), **values, "source": str(source)}})  # fmt: skip

            n_jobs = jobs or min(len(names), os.cpu_count() or 1)
            runs = _run_all(names, tmp, params, notebooks_dir, n_jobs, progress, zygote, meanwhile=leaderboard)
            spec = board["spec"]
            if source is not None and "source" in spec["values"]:  # the leaderboard's input, by its root's name, or
                # where it is (--absolute-paths: as run.json's roots, not relative to where the command ran)
                spec["values"]["source"] = str(source.resolve()) if absolute_paths else root_key(source, named)
            with naming(tmp / "parameters.json"):  # (the file in the run folder: _in_run_folder)
                (tmp / "parameters.json").write_text(json.dumps(params, indent=2, default=str))
            # each input where it is (a link too: its target may lie outside every root, on this machine only)
            files = [where_it_is(f) for f in input_files(roots, resolve=False)]
            inputs = checksums(files, None if absolute_paths else named)
            # where the links among them lead out of every root: a path of this machine only, that no page may show
            real_roots = [r.resolve() for r in named.values()]
            leads_out = sorted({r for r in (f.resolve() for f in files)
                                if not any(r == q or q in r.parents for q in real_roots)})  # fmt: skip
            record = run_record(command if command is not None else python_call(), spec, data.root if data else None, inputs,
                                {r.name: r.status for r in runs}, roots, named, absolute=absolute_paths)  # fmt: skip
            if record.get("commit"):  # the commit alone does not say what ran if the checkout had changes
                record["dirty"] = git_dirty()
            if label is not None:
                record["label"] = label
            write_run_json(tmp, record)
            since = since_baseline(tmp, baseline, name=run_dir.name) if baseline is not None else None
            if baseline is not None and since is not None and since.get("baseline_files"):  # what the verdict read
                record = with_baseline(record, Path(baseline), since["baseline_files"], absolute_paths)
                write_run_json(tmp, record)

            def pages(folder: Path, name: str) -> None:  # the pages name the run's folder; the marker lists all
                index = write_index(folder, runs, params, name=name, findings=board.get("findings"), spec=spec, label=label,
                                    failures=board.get("failures"), left_out=left_out,
                                    per_sequence=board.get("per_sequence"), wanted=run_dir.name,
                                    expected=board.get("expected"), since=since, roots=named)  # fmt: skip
                if not absolute_paths:  # every path below a named root, whatever wrote it (a notebook's printout)
                    others = [("baseline", Path(baseline))] if baseline is not None else []
                    every = [*named.items(), *others, ("run", folder), ("run", run_dir), *install_roots()]
                    make_portable(folder, every)
                    rendered = [nb.with_suffix(".html") for nb in sorted(folder.glob("*/*.ipynb"))]
                    split = [page for page in rendered if page.is_file() and split_paths(page, every)]
                    if split:  # a path cut by the highlighter at an escape (caf\xe9): from the portable notebook
                        from lorisnb.tools.report.html import export_html

                        css = f"../{NOTEBOOK_CSS}" if (folder / NOTEBOOK_CSS).is_file() else None
                        for page in split:
                            export_html(page.with_suffix(".ipynb"), css=css)
                single_file(index, folder / "report.html")  # the pages as they are now, into one file
                if absolute_paths:  # papermill's output_path: the notebook where the run is, not where it was written
                    for nb in sorted(folder.glob("*/*.ipynb")):
                        _record_output_path(nb, run_dir.parent / name / nb.relative_to(folder))
                if not absolute_paths:
                    make_portable(folder, every)
                    left = unreplaced(
                        folder,
                        [*every, *(("outside", t) for t in leads_out)],
                        also=author_folders([*named.items(), *others, ("run", run_dir)]),  # the folders holding them
                    )
                    if left:
                        shown = ", ".join(str(f.relative_to(folder)) for f in left[:5])
                        warnings.warn(f"{len(left)} file(s) of the run still show an absolute path of this machine "
                                      f"({shown}): look before you share it, and report it", LorisWarning,
                                      stacklevel=2)  # fmt: skip
                _write_marker(folder, _files(folder))

            pages(tmp, run_dir.name)  # the name it is moved to (not the temporary one it is written under)
            os.chmod(tmp, 0o777 & ~_umask())  # mkdtemp made it owner-only
            final = _move_into_place(tmp, run_dir, force)
        except BaseException as exc:
            remove_partial(tmp)
            _in_run_folder(exc, tmp, run_dir)  # a full disk names the file in the run folder, not its temporary name
            name_output(exc, run_dir)  # or the run folder, where no file was named
            raise
        if final.name != run_dir.name:  # another run took the name meanwhile: this one's pages say where it is
            pages(final, final.name)
        return final, runs


#: The lock a render holds on its run folder while it writes (created by that render, with its pid
#: and host, and removed by it alone): a second render of the run is refused, the first's staged pages
#: untouched (:func:`render_run`).
RENDER_LOCK = ".lorisnb-render.lock"

#: What says the run folder's name on ``index.html`` (:func:`~lorisnb.tools.report.index.write_index`):
#: its name, and where another run took the name asked for, which one that was.
_RUN_FOLDER = re.compile(r"Run folder <code>([^<]*)</code>( \(<code>[^<]*</code> appeared while this report ran, "
                         r"another run's: this run is <code>[^<]*</code>\))?, written ")  # fmt: skip


def render_run(run: str | os.PathLike[str]) -> list[Path]:
    """Render a run folder's pages again from its own files (wherever it was copied to): each
    notebook's HTML page from the notebook executed into it, then ``report.html`` from
    ``index.html``, which names the run folder as it is named now (a run renamed or copied under
    another name); returns the pages written. Reads nothing outside the run folder. Only a run
    folder lorisnb wrote is rendered, and only if its pages are as its run wrote them (an edited
    page is kept, and the run refused, naming it). One render at a time writes into a run
    (:data:`RENDER_LOCK`): another is refused, saying so. The pages and the marker listing them are
    all written beside their places, then moved there; a move that fails puts back the pages
    already replaced, so a run is rendered whole or left as it was."""
    from lorisnb.tools.report.html import export_html
    from lorisnb.tools.report.index import esc

    folder = Path(run)
    for f in (RUN_MARKER, "index.html"):  # a link leading out, a FIFO or a device: refused, never opened
        if os.path.lexists(folder / f):
            run_file(folder, folder / f)
    absent = [f for f in (RUN_MARKER, "index.html") if not (folder / f).is_file()]
    if len(absent) == 2 or (absent and not (folder / "run.json").is_file()):
        raise LorisError(f"{folder}: not a run folder written by lorisnb report (no {' and no '.join(absent)} in it)")
    if absent == [RUN_MARKER]:  # beside its run.json: every lorisnb writing one writes the marker
        raise LorisError(f"{folder} will not be rendered again: its {RUN_MARKER} marker is gone (every run lorisnb "
                         "writes has one), so its pages cannot be told from files changed or added since; copy the "
                         "run again from where it came, or make it again with lorisnb report")  # fmt: skip
    if absent:
        raise LorisError(f"{folder} will not be rendered again: its index.html is gone, from which render makes "
                         "report.html; put back the run's own (from where the run was copied), then render again")  # fmt: skip
    out = links_out(folder)  # a page written through one lands elsewhere; a notebook read through one is not the run's
    if out:
        shown = ", ".join(str(p.relative_to(folder)) for p in out[:5]) + (f" and {len(out) - 5} more" * (len(out) > 5))
        raise LorisError(f"{folder} will not be rendered again: it holds {len(out)} link(s) leading outside it "
                         f"({shown}); a run folder lorisnb writes holds none. Nothing was read or written: replace "
                         "each link by its file, if you trust it")  # fmt: skip
    notebooks = [nb for nb in sorted(folder.glob("*/*.ipynb")) if nb.parent.name == nb.stem]
    _writable_run(folder, [folder, *(nb.parent for nb in notebooks)])
    with _render_lock(folder):
        if (folder / "run.json").is_file():  # a damaged one (not JSON, a key twice, a value no run writes) is
            from lorisnb.tools.report.provenance import read_run_json  # refused, never rendered from

            read_run_json(folder)
        why = _not_written(folder, "render a copy of the run without them", render=True, ignore=[RENDER_LOCK])
        if why:
            raise LorisError(f"{folder} will not be rendered again: {why}")
        for nb in notebooks:  # each read first: a damaged one refused, naming it, before any page is written
            _readable_notebook(nb)
        css = f"../{NOTEBOOK_CSS}" if (folder / NOTEBOOK_CSS).is_file() else None
        pid = os.getpid()
        writes: list[tuple[Path, Callable[[Path], Any]]] = [
            (nb.with_suffix(".html"), functools.partial(export_html, nb, css)) for nb in notebooks
        ]
        index = folder / "index.html"
        text = index.read_text(encoding="utf-8")
        named = _RUN_FOLDER.search(text)  # the run's name as the page states it: its folder's now (a note that
        now = esc(os.path.basename(os.path.abspath(folder)))  # another run took the name asked for: moot once renamed)
        if named and named.group(1) != now:
            text = text[: named.start()] + f"Run folder <code>{now}</code>, written " + text[named.end() :]
            writes.append((index, functools.partial(_write_page, text)))
            index = index.with_name(f".{index.name}.tmp-{pid}")  # report.html from the page as it will be
        writes.append((folder / "report.html", functools.partial(single_file, index)))
        for page, _ in writes:  # every place a page goes, before any is written: one that is no file is kept
            _replaceable(folder, page)
        _replaceable(folder, folder / RUN_MARKER)
        # every page and the marker listing them first written beside their places, then all moved there: a full
        # disk leaves the run as it was (no page cut short, none the marker does not list), renderable once freed
        staged: list[tuple[Path, Path]] = []
        marker = folder / f".{RUN_MARKER}.tmp-{pid}"
        try:
            for page, write in writes:
                tmp = page.with_name(f".{page.name}.tmp-{pid}")
                staged.append((tmp, page))
                with naming(page):
                    write(tmp)
            files = _files(folder)
            files.pop(RENDER_LOCK, None)
            for tmp, page in staged:
                files.pop(tmp.relative_to(folder).as_posix(), None)
                files[page.relative_to(folder).as_posix()] = sha256(tmp)
            with naming(folder / RUN_MARKER):
                _write_marker(folder, files, out=marker)
            _move_all([*staged, (marker, folder / RUN_MARKER)], folder)
        finally:
            for tmp, _ in staged:
                tmp.unlink(missing_ok=True)
            marker.unlink(missing_ok=True)
    return [page for page, _ in writes]


def _write_page(text: str, out: Path) -> None:
    """``text`` into ``out`` (a page render writes: ``index.html`` naming the run as it is named now)."""
    out.write_text(text, encoding="utf-8")


def _writable_run(folder: Path, places: Iterable[Path]) -> None:
    """An :class:`~lorisnb.errors.OutputError` if render cannot write into one of ``places`` (the run
    folder, a notebook's folder): on a read-only disk, or not yours to write. Said before anything is
    written, with what to do (render a copy in a writable place)."""
    for place in places:
        if not os.access(place, os.W_OK | os.X_OK):
            raise OutputError(_unwritable(folder, place, "not writable"))


def _unwritable(folder: Path, place: Path, why: str) -> str:
    where = "" if place == folder else f" ({place}: {why})"
    shown = f"the run folder is {why}" if place == folder else "the run folder cannot be written"
    return (f"{folder} will not be rendered again: {shown}{where}, and render writes the run's pages into it. "
            f"Nothing was written: render a copy of it in a writable place (cp -r {folder} COPY && lorisnb render "
            "COPY)")  # fmt: skip


def _replaceable(folder: Path, page: Path) -> None:
    """An :class:`~lorisnb.errors.OutputError` naming ``page`` if it is there but is no regular file (a
    folder, a link, a FIFO): render replaces only a page the run wrote, and says so before writing any."""
    try:
        mode = os.lstat(page).st_mode
    except FileNotFoundError:
        return
    if stat.S_ISREG(mode):
        return
    what = ("a folder" if stat.S_ISDIR(mode) else "a link" if stat.S_ISLNK(mode)
            else "not a regular file (a FIFO, a device)")  # fmt: skip
    raise OutputError(f"{page}: {what}, where render writes the run's {page.name}; {folder} will not be rendered "
                      "again, nothing was written: move it out of the run, then render again")  # fmt: skip


def _move_all(moves: list[tuple[Path, Path]], folder: Path) -> None:
    """Each staged file (``tmp``) moved to its place, the file there kept aside until every move is done:
    if one fails, the pages already replaced are put back (the run as it was) and the error names the
    place, not the staged file. Where a page cannot be put back, the error says where it was kept."""
    pid = os.getpid()
    done: list[tuple[Path, Path | None, list[bool]]] = []  # (place, its file kept aside or None, [moved there])
    try:
        for tmp, place in moves:
            with naming(place):
                old = place.with_name(f".{place.name}.old-{pid}") if os.path.lexists(place) else None
                if old is not None:
                    os.replace(place, old)
                done.append((place, old, [False]))
                os.replace(tmp, place)
                done[-1][2][0] = True
    except BaseException as exc:
        kept = []
        for place, old, moved in reversed(done):
            try:
                if old is not None:
                    os.replace(old, place)
                elif moved[0]:
                    place.unlink()
            except OSError:
                kept.append(f"{old} (the run's {place.relative_to(folder)})" if old else str(place))
        if kept:
            why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc) or type(exc).__name__
            raise OutputError(f"{folder} is rendered in part: moving its pages into place failed ({why}) and these "
                              f"could not be put back: {', '.join(kept)}; move each back to its place (a new page: "
                              "remove it), then render again") from exc  # fmt: skip
        raise
    for _, old, _ in done:
        if old is not None:
            old.unlink(missing_ok=True)


@contextlib.contextmanager
def _render_lock(folder: Path) -> Iterator[None]:
    """Hold :data:`RENDER_LOCK` in ``folder`` while rendering it: created here (never over another's),
    removed at the end only if it is still the file created here. One there already is another
    render's: refused, saying whether it is at work (its pid alive on this host) or stopped (its lock
    left; said, not removed, as it may be another host's)."""
    lock = folder / RENDER_LOCK
    host = socket.gethostname()
    try:
        fd = os.open(lock, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
    except FileExistsError:
        raise OutputError(_locked(folder, lock, host)) from None
    except OSError as exc:
        if exc.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
            raise OutputError(_unwritable(folder, folder, exc.strerror or "not writable")) from None
        raise
    try:
        mine = os.fstat(fd)
        try:
            os.write(fd, json.dumps({"pid": os.getpid(), "host": host}).encode())
        finally:
            os.close(fd)
        yield
    finally:
        with contextlib.suppress(OSError):
            now = os.lstat(lock)
            if (now.st_dev, now.st_ino) == (mine.st_dev, mine.st_ino):
                lock.unlink()


def _locked(folder: Path, lock: Path, host: str) -> str:
    """What render says of a run whose lock (``lock``) another render holds or left."""
    try:
        held = json.loads(lock.read_bytes()[:4096]) if lock.is_file() and not lock.is_symlink() else None
        pid, where = (int(held["pid"]), str(held["host"])) if isinstance(held, dict) else (0, "")
    except (OSError, ValueError, KeyError, TypeError):
        pid, where = 0, ""
    if pid > 0 and where == host:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return (f"{folder} will not be rendered now: a render (pid {pid}) that is no longer running left its lock "
                    f"{lock} (it was stopped before it could remove it). If no render is at work on the run, remove "
                    "the lock and any file of that render it still holds (named .NAME.tmp-"
                    f"{pid}), then render again")  # fmt: skip
        except OSError:
            pass  # another user's process: alive
        return (f"{folder} will not be rendered now: another render (pid {pid}) is at work on it; nothing was "
                "touched: wait for it to end, then render again")  # fmt: skip
    who = f"a render on {clean(where)} (pid {pid})" if pid > 0 and where else "another render"
    return (f"{folder} will not be rendered now: {who} holds its lock {lock}; nothing was touched: wait for it to "
            "end, then render again. If no render is at work on the run (one was stopped), remove the lock, then "
            "render again")  # fmt: skip


def _record_output_path(nb: Path, final: Path) -> None:
    """The notebook ``nb`` (executed by papermill into the run's temporary folder) with papermill's
    ``output_path`` metadata naming ``final``, where it is once the run is in place (a run made with
    ``--absolute-paths`` recorded the temporary ``.run.partial-XXXX`` folder, gone once it is moved).
    Written back as nbformat writes a notebook; one that is not JSON, or has no such metadata, is left
    as it is."""
    try:
        text = nb.read_text(encoding="utf-8")
        notebook = json.loads(text)
        papermill = notebook["metadata"]["papermill"]
    except (OSError, ValueError, RecursionError, KeyError, TypeError):
        return
    if not isinstance(papermill, dict) or papermill.get("output_path") in (None, str(final)):
        return
    papermill["output_path"] = str(final)
    with naming(nb):
        end = "\n" if text.endswith("\n") else ""
        nb.write_text(json.dumps(notebook, sort_keys=True, indent=1, ensure_ascii=False) + end, encoding="utf-8")


def _readable_notebook(nb: Path) -> None:
    """A :class:`~lorisnb.errors.ParseError` naming ``nb`` if nbformat cannot read it as a notebook
    (cut short in a copy, edited by hand): a page is rendered from it only if it reads."""
    from lorisnb.tools._extras import require

    nbformat = require("nbformat")
    text = read_run_file(nb.parent.parent, nb)  # a FIFO or a device: refused, never opened
    try:
        nbformat.validate(nbformat.reads(text.decode("utf-8"), as_version=4))
    except OSError:
        raise
    except Exception as exc:  # nbformat's errors (not JSON, not a notebook, an invalid one) have no common base
        reason = str(exc).strip().splitlines()[0][:200] if str(exc).strip() else type(exc).__name__
        raise ParseError(nb, None, f"not a notebook nbformat can read ({reason}); expected the notebook the run "
                         "executed: copy it again from the run's source. No page was rendered again") from None  # fmt: skip


def findings_input_errors(run_dir: Path) -> int:
    """How many input files the report's own evaluation (``findings/``) could not evaluate or score."""
    from lorisnb.tools.decisions.runs import unscored_inputs

    return len(unscored_inputs(run_dir))


def _in_run_folder(exc: BaseException, tmp: Path, run_dir: Path) -> None:
    """An :class:`OSError` naming a file of the run's temporary folder ``tmp`` names it where it goes,
    below ``run_dir`` (``out/run/run.json``, not ``out/.run.partial-x1y2/run.json`` nor ``out/run``)."""
    if isinstance(exc, OSError) and exc.filename is not None:
        try:
            rel = Path(os.path.abspath(os.fsdecode(exc.filename))).relative_to(tmp)
        except ValueError:
            return
        exc.filename = str(run_dir / rel) if rel.parts else str(run_dir)


def _move_into_place(tmp: Path, run_dir: Path, force: bool) -> Path:
    """Rename the finished run to ``run_dir``; links inside the report are relative, so the
    folder moves as a whole. Never clobbers a folder that appeared meanwhile."""
    if run_dir.exists() and force and (run_dir / RUN_MARKER).is_file() and _not_written(run_dir) is None:
        old = Path(tempfile.mkdtemp(prefix=f".{run_dir.name}.old-", dir=run_dir.parent))
        os.replace(run_dir, old / run_dir.name)
        if _not_written(old / run_dir.name) is None:  # checked again once moved aside: nothing added meanwhile
            os.rename(tmp, run_dir)
            shutil.rmtree(old, ignore_errors=True)
            return run_dir
        os.replace(old / run_dir.name, run_dir)  # a file appeared in it: kept, as the folder is
        old.rmdir()
    candidate, k = run_dir, 1
    while True:
        try:
            if candidate.exists():
                raise FileExistsError(candidate)
            os.rename(tmp, candidate)  # fails on a non-empty folder that appeared meanwhile
            return candidate
        except OSError:
            k += 1
            candidate = run_dir.with_name(f"{run_dir.name}-{k}")
