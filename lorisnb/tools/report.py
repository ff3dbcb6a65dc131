"""Batch reports: run the notebooks with papermill into a new run folder under ``results/``,
export each to HTML, and write an ``index.html`` linking everything (parameters, versions, tables,
figures, notebooks that failed and input files that could not be read).

A run is built in a temporary folder and moved into place at the end, so an interrupted run
leaves nothing half-written, and an existing run folder is never replaced without ``force``.
"""

from __future__ import annotations

import datetime as _dt
import importlib.util
import json
import os
import shutil
import sys
import tempfile
import time
import traceback
import warnings
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from ..core import validate
from ..errors import LorisError, ValidationError
from ._extras import EXTRAS, require
from .notebook import INPUT_ERRORS_CSV
from .report_index import versions, write_index

#: Report order: the teaching notebook first, then the paper's figures, then the explorations.
DEFAULT_NOTEBOOKS = (
    "metrics_primer",
    "per_sequence_benchmark",
    "lifelong_benchmark",
    "threshold_sensitivity",
    "compare_algorithms",
    "evo_crosscheck",
    "indoor_vs_outdoor",
    "evaluate_my_results",
)

#: Kernel options: its own log is silenced (the loopback-TCP 'without encryption' notice or
#: the 'KeyboardInterrupt caught in kernel' line of a normal shutdown).
KERNEL_ARGS = ["--IPKernelApp.log_level=CRITICAL"]

#: Optional packages a notebook needs; without them the report skips it and says which extra to install.
NOTEBOOK_NEEDS: dict[str, tuple[str, ...]] = {"evo_crosscheck": ("evo",)}

#: A file lorisnb writes into every run folder; ``--force`` replaces only folders that hold it.
RUN_MARKER = ".lorisnb-run"


def notebook_dir(notebooks_dir: str | os.PathLike[str] | None = None) -> Path:
    """The folder of the notebooks: ``notebooks_dir``, else the notebooks shipped with the package
    (``lorisnb.notebooks``)."""
    if notebooks_dir is not None:
        d = Path(notebooks_dir)
        if not d.is_dir():
            raise LorisError(f"notebooks folder {d} does not exist; pass a folder holding .ipynb files")
        return d
    from importlib import resources

    return Path(str(resources.files("lorisnb.notebooks")))


def notebook_path(name: str, notebooks_dir: str | os.PathLike[str] | None = None) -> Path:
    """A notebook by name (``per_sequence_benchmark``) or path (``my.ipynb``)."""
    p = Path(name)
    nb_dir = notebook_dir(notebooks_dir)
    if p.suffix != ".ipynb":
        p = nb_dir / f"{name}.ipynb"
    if not p.is_file():
        raise LorisError(
            f"notebook {name!r} not found (looked for {p}); the notebooks are: "
            + ", ".join(sorted(q.stem for q in nb_dir.glob("*.ipynb")))
        )
    return p


def available_notebooks(notebooks_dir: str | os.PathLike[str] | None = None) -> list[str]:
    """The report's notebooks that exist, in report order."""
    d = notebook_dir(notebooks_dir)
    return [n for n in DEFAULT_NOTEBOOKS if (d / f"{n}.ipynb").exists()]


@dataclass
class NotebookRun:
    """How one notebook of a report went: status ``ok``, ``failed`` or ``skipped`` (an optional
    package it needs is missing), the error or reason, and how many of its input files could not be
    evaluated."""

    name: str
    status: str = "ok"
    seconds: float = 0.0
    error: str = ""
    parameters: dict[str, Any] = field(default_factory=dict)
    input_errors: int = 0


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


def kernel_env() -> None:
    """Environment for notebook kernels: the Python running lorisnb, the Agg backend, no noise."""
    # the kernel must be the Python that runs lorisnb (jupyter's 'python3' kernel runs `python`)
    bindir = str(Path(sys.executable).parent)
    if not os.environ.get("PATH", "").startswith(bindir + os.pathsep):
        os.environ["PATH"] = bindir + os.pathsep + os.environ.get("PATH", "")
    os.environ.setdefault("MPLBACKEND", "Agg")
    os.environ.setdefault("PYDEVD_DISABLE_FILE_VALIDATION", "1")
    # papermill's kernel talks over loopback TCP; its 'without encryption' notice is noise here
    warnings.filterwarnings("ignore", message=".*without encryption.*")
    import logging

    logging.getLogger("papermill").setLevel(logging.WARNING)
    logging.getLogger("traitlets").setLevel(logging.ERROR)


def declared_parameters(path: Path) -> dict[str, dict[str, Any]]:
    """The parameters a notebook declares in its cell tagged ``parameters`` (name -> papermill's
    description: default, inferred type, help)."""
    pm = require("papermill")
    return dict(pm.inspect_notebook(str(path)))


#: Notebook parameters checked with the same rules as the command line and the Python API.
_CHECKS: dict[str, Any] = {
    "eps": validate.eps_value,
    "phi": lambda v: validate.threshold("phi", v),
    "delta": lambda v: validate.threshold("delta", v),
    "tau": lambda v: validate.threshold("tau", v),
    "scale": validate.scale_value,
    "eps_grid": lambda v: validate.threshold_list("eps", v),
    "phi_grid": lambda v: validate.threshold_list("phi", v),
    "delta_grid": lambda v: validate.threshold_list("delta", v),
    "tau_grid": lambda v: validate.threshold_list("tau", v),
}


def check_parameters(parameters: Mapping[str, Any], declared: Mapping[str, Mapping[str, Any]]) -> None:
    """Refuse a parameter no selected notebook declares (listing the declared names) and values
    that the command line would refuse (``-p eps -1``), before anything runs."""
    unknown = sorted(set(parameters) - set(declared) - {"output_dir"})
    if unknown:
        raise ValidationError(
            f"parameter(s) {', '.join(unknown)} not declared by the selected notebooks; they declare: "
            + ", ".join(sorted(declared))
        )
    for name, value in parameters.items():
        if name in _CHECKS and value is not None and not (name == "eps" and value == "paper"):
            _CHECKS[name](value)


def _to_html(ipynb: Path) -> Path | None:
    nbformat = require("nbformat")
    HTMLExporter = require("nbconvert").HTMLExporter

    try:
        nb = nbformat.read(str(ipynb), as_version=4)
        body, _ = HTMLExporter().from_notebook_node(nb)
    except Exception:  # an HTML export failure must not lose the run
        return None
    out = ipynb.with_suffix(".html")
    out.write_text(body, encoding="utf-8")
    return out


def run_notebook(
    name: str,
    out_dir: Path,
    parameters: Mapping[str, object],
    timeout: int = 1800,
    notebooks_dir: str | os.PathLike[str] | None = None,
) -> NotebookRun:
    """Execute one notebook with papermill into ``out_dir/<name>/``; never raises for a failing
    notebook (the error is recorded), except on KeyboardInterrupt."""
    pm = require("papermill")
    kernel_env()
    src = notebook_path(name, notebooks_dir)
    stem = src.stem
    nb_dir = out_dir / stem
    nb_dir.mkdir(parents=True, exist_ok=True)
    declared = declared_parameters(src)
    params = {k: v for k, v in parameters.items() if k in declared}
    if "output_dir" in declared:
        params["output_dir"] = "."  # papermill runs the notebook in its own folder of the run
    run = NotebookRun(stem, parameters=params)
    missing = [m for m in NOTEBOOK_NEEDS.get(stem, ()) if importlib.util.find_spec(m) is None]
    if missing:
        run.status = "skipped"
        run.error = f"needs {', '.join(missing)}: pip install 'lorisnb[{EXTRAS.get(missing[0], 'all')}]'"
        return run
    t = time.perf_counter()
    target = nb_dir / f"{stem}.ipynb"
    try:
        pm.execute_notebook(
            str(src), str(target), parameters=params, kernel_name="python3", progress_bar=False,
            cwd=str(nb_dir), execution_timeout=timeout, log_output=False, extra_arguments=KERNEL_ARGS,
        )  # fmt: skip
    except KeyboardInterrupt:
        raise
    except Exception as exc:  # PapermillExecutionError and kernel failures alike
        run.status = "failed"
        ename = getattr(exc, "ename", type(exc).__name__)
        evalue = getattr(exc, "evalue", str(exc))
        run.error = f"{ename}: {evalue}" if evalue else "".join(traceback.format_exception_only(exc)).strip()
    run.seconds = time.perf_counter() - t
    if target.exists():
        _to_html(target)
    errors_csv = nb_dir / INPUT_ERRORS_CSV
    if errors_csv.exists():
        failed = pd.read_csv(errors_csv)
        run.input_errors = int(failed.get("status", pd.Series(dtype=str)).isin(["failed", "not scored"]).sum())
    return run


def _protected(run_dir: Path, extra: list[Path]) -> str | None:
    """Why ``run_dir`` may not be replaced, or None."""
    target = run_dir.resolve()
    cwd = Path.cwd().resolve()
    if target == cwd or target in cwd.parents:
        return "it is the current folder or one of its parents"
    for p in extra:
        p = p.resolve()
        if target == p or target in p.parents or p in target.parents:
            return f"it holds or is inside {p}"
    if not (run_dir / RUN_MARKER).is_file():
        return f"it is not a lorisnb run folder (no {RUN_MARKER} file in it)"
    return None


def run_report(
    out: str | os.PathLike[str] | None = None,
    parameters: Mapping[str, Any] | None = None,
    notebooks: Iterable[str] | None = None,
    force: bool = False,
    progress: bool = True,
    notebooks_dir: str | os.PathLike[str] | None = None,
    protect: Iterable[str | os.PathLike[str]] = (),
) -> tuple[Path, list[NotebookRun]]:
    """Run the notebooks into a new run folder; returns (run folder, notebook runs).

    Args:
        out: the run folder; default ``results/run-<date>-<time>`` below the current folder. An
            existing folder is an error unless ``force``, and even then only a run folder that
            lorisnb wrote (it holds :data:`RUN_MARKER`) is replaced, never the current folder, one
            of its parents, the notebooks or a folder in ``protect`` (inputs, the data root).
        parameters: papermill parameters; each notebook gets those it declares. A parameter no
            selected notebook declares, or a value the command line would refuse, is an error.
        notebooks: names (default: every notebook of :data:`DEFAULT_NOTEBOOKS` that exists).
        notebooks_dir: where the notebooks are (default: those shipped with lorisnb).

    The run is built under a hidden temporary name beside ``out`` and moved into place when
    complete; if ``out`` appeared meanwhile (another run), this run is kept under
    ``out-2`` (or the next free name) instead, and the returned path says so. On Ctrl-C the
    temporary folder is removed and KeyboardInterrupt propagates.
    """
    run_dir = _new_run_dir(out)
    nb_dir = notebook_dir(notebooks_dir)
    keep_safe = [nb_dir, *map(Path, protect), Path(__file__).resolve().parents[1]]
    if run_dir.exists():
        if not force:
            raise LorisError(f"{run_dir} exists; choose another --out or pass --force to replace it")
        why = _protected(run_dir, keep_safe)
        if why:
            raise LorisError(f"--force will not replace {run_dir}: {why}; choose another --out")
    names = list(notebooks) if notebooks else available_notebooks(notebooks_dir)
    declared: dict[str, dict[str, Any]] = {}
    for n in names:
        declared.update(declared_parameters(notebook_path(n, notebooks_dir)))
    params = dict(parameters or {})
    check_parameters(params, declared)
    run_dir.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{run_dir.name}.partial-", dir=run_dir.parent))
    try:
        (tmp / RUN_MARKER).write_text(json.dumps({"lorisnb": versions()["lorisnb"], "pid": os.getpid()}))
        runs: list[NotebookRun] = []
        if progress:
            from tqdm.auto import tqdm

            bar = tqdm(names, desc="report", unit="notebook")
            for n in bar:
                bar.set_postfix_str(n)
                runs.append(run_notebook(n, tmp, params, notebooks_dir=notebooks_dir))
        else:
            runs = [run_notebook(n, tmp, params, notebooks_dir=notebooks_dir) for n in names]
        (tmp / "parameters.json").write_text(json.dumps(params, indent=2, default=str))
        write_index(tmp, runs, params, name=run_dir.name)
        final = _move_into_place(tmp, run_dir, force)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return final, runs


def _move_into_place(tmp: Path, run_dir: Path, force: bool) -> Path:
    """Rename the finished run to ``run_dir``; links inside the report are relative, so the
    folder moves as a whole. Never clobbers a folder that appeared meanwhile."""
    if run_dir.exists() and force and (run_dir / RUN_MARKER).is_file():
        old = Path(tempfile.mkdtemp(prefix=f".{run_dir.name}.old-", dir=run_dir.parent))
        os.replace(run_dir, old / run_dir.name)
        os.rename(tmp, run_dir)
        shutil.rmtree(old, ignore_errors=True)
        return run_dir
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
