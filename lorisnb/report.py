"""Batch reports: run the notebooks with papermill into a new run folder under ``results/``,
export each to HTML, and write an ``index.html`` linking everything (parameters, versions, tables,
figures, notebooks that failed and input files that could not be read).

A run is built in a temporary folder and moved into place at the end, so an interrupted run
leaves nothing half-written, and an existing run folder is never replaced without ``force``.
"""

from __future__ import annotations

import datetime as _dt
import html
import json
import os
import platform
import shutil
import sys
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Mapping

import pandas as pd

from .data import PROJECT_ROOT
from .errors import LorisError

NOTEBOOK_DIR = PROJECT_ROOT / "notebooks"
RESULTS_DIR = PROJECT_ROOT / "results"

#: Report order: the teaching notebook first, then the paper's figures, then the explorations.
DEFAULT_NOTEBOOKS = (
    "metrics_primer",
    "per_sequence_benchmark",
    "lifelong_benchmark",
    "threshold_sensitivity",
    "evo_crosscheck",
    "indoor_vs_outdoor",
    "evaluate_my_results",
)

INPUT_ERRORS_CSV = "input_errors.csv"


class Outputs:
    """Where a notebook writes what it shows: tables as CSV, figures as PNG and SVG.

    ``table`` and ``figure`` return their argument so a cell can write and display at once.
    Input files that could not be evaluated go to ``input_errors.csv``, which the report lists.
    """

    def __init__(self, output_dir: str | os.PathLike):
        self.dir = Path(output_dir)
        self.dir.mkdir(parents=True, exist_ok=True)

    def table(self, df: pd.DataFrame, name: str, index: bool = False) -> pd.DataFrame:
        df.to_csv(self.dir / f"{name}.csv", index=index)
        return df

    def figure(self, fig, name: str):
        from .plotting import save_figure

        save_figure(fig, self.dir, name)
        return fig

    def input_errors(self, failures: pd.DataFrame) -> pd.DataFrame:
        failures.to_csv(self.dir / INPUT_ERRORS_CSV, index=False)
        return failures


def notebook_path(name: str) -> Path:
    p = Path(name)
    if p.suffix != ".ipynb":
        p = NOTEBOOK_DIR / f"{name}.ipynb"
    if not p.exists():
        raise LorisError(f"notebook {name!r} not found (looked for {p}); the notebooks are: "
                         + ", ".join(sorted(q.stem for q in NOTEBOOK_DIR.glob("*.ipynb"))))
    return p


def available_notebooks() -> list[str]:
    return [n for n in DEFAULT_NOTEBOOKS if (NOTEBOOK_DIR / f"{n}.ipynb").exists()]


@dataclass
class NotebookRun:
    name: str
    status: str = "ok"
    seconds: float = 0.0
    error: str = ""
    parameters: dict = field(default_factory=dict)


def versions() -> dict[str, str]:
    """Versions of Python and the packages a report depends on."""
    out = {"python": platform.python_version()}
    from importlib import metadata

    for pkg in ("lorisnb", "numpy", "scipy", "pandas", "matplotlib", "seaborn", "evo", "papermill",
                "ipywidgets", "tqdm"):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = "not installed"
    return out


def _new_run_dir(out: str | os.PathLike | None) -> Path:
    if out is not None:
        return Path(out)
    stamp = _dt.datetime.now().strftime("%Y%m%d-%H%M%S")
    base = RESULTS_DIR / f"run-{stamp}"
    p, k = base, 1
    while p.exists():
        k += 1
        p = base.with_name(f"{base.name}-{k}")
    return p


def _kernel_env() -> None:
    # the kernel must be the Python that runs lorisnb (jupyter's 'python3' kernel runs `python`)
    bindir = str(Path(sys.executable).parent)
    if not os.environ.get("PATH", "").startswith(bindir + os.pathsep):
        os.environ["PATH"] = bindir + os.pathsep + os.environ.get("PATH", "")
    os.environ.setdefault("MPLBACKEND", "Agg")


def _declared_parameters(path: Path) -> dict:
    import papermill as pm

    return pm.inspect_notebook(str(path))


def _to_html(ipynb: Path) -> Path | None:
    import nbformat
    from nbconvert import HTMLExporter

    try:
        nb = nbformat.read(str(ipynb), as_version=4)
        body, _ = HTMLExporter().from_notebook_node(nb)
    except Exception:  # an HTML export failure must not lose the run
        return None
    out = ipynb.with_suffix(".html")
    out.write_text(body, encoding="utf-8")
    return out


def run_notebook(name: str, out_dir: Path, parameters: Mapping[str, object], timeout: int = 1800) -> NotebookRun:
    """Execute one notebook with papermill into ``out_dir/<name>/``; never raises for a failing
    notebook (the error is recorded)."""
    import papermill as pm

    _kernel_env()
    src = notebook_path(name)
    stem = src.stem
    nb_dir = out_dir / stem
    nb_dir.mkdir(parents=True, exist_ok=True)
    declared = _declared_parameters(src)
    params = {k: v for k, v in parameters.items() if k in declared}
    if "output_dir" in declared:
        params["output_dir"] = "."  # papermill runs the notebook in its own folder of the run
    run = NotebookRun(stem, parameters=params)
    t = time.perf_counter()
    target = nb_dir / f"{stem}.ipynb"
    try:
        pm.execute_notebook(str(src), str(target), parameters=params, kernel_name="python3",
                            progress_bar=False, cwd=str(nb_dir), execution_timeout=timeout)
    except Exception as exc:  # PapermillExecutionError and kernel failures alike
        run.status = "failed"
        ename = getattr(exc, "ename", type(exc).__name__)
        evalue = getattr(exc, "evalue", str(exc))
        run.error = f"{ename}: {evalue}" if evalue else "".join(traceback.format_exception_only(exc)).strip()
    run.seconds = time.perf_counter() - t
    if target.exists():
        _to_html(target)
    return run


def _rel(p: Path, root: Path) -> str:
    return p.relative_to(root).as_posix()


def write_index(run_dir: Path, runs: list[NotebookRun], parameters: Mapping[str, object],
                name: str | None = None) -> Path:
    """``index.html``: parameters, versions, notebooks with status, input errors, tables, figures."""
    esc = html.escape
    parts = [
        "<!doctype html><html><head><meta charset='utf-8'><title>lorisnb report</title>",
        "<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto}table{border-collapse:collapse}"
        "td,th{border:1px solid #ccc;padding:3px 8px;text-align:left;vertical-align:top}"
        ".failed{color:#b00}.ok{color:#070}img{max-width:100%;border:1px solid #ddd}</style></head><body>",
        f"<h1>lorisnb report</h1><p>Run folder <code>{esc(name or run_dir.name)}</code>, written "
        f"{esc(_dt.datetime.now().isoformat(timespec='seconds'))}.</p>",
        "<h2>Notebooks</h2><table><tr><th>notebook</th><th>status</th><th>seconds</th><th>files</th><th>error</th></tr>",
    ]
    for r in runs:
        d = run_dir / r.name
        links = " ".join(f"<a href='{esc(_rel(p, run_dir))}'>{esc(p.suffix[1:])}</a>"
                         for p in (d / f"{r.name}.html", d / f"{r.name}.ipynb") if p.exists())
        parts.append(f"<tr><td>{esc(r.name)}</td><td class='{r.status}'>{r.status}</td><td>{r.seconds:.1f}</td>"
                     f"<td>{links}</td><td><pre>{esc(r.error)}</pre></td></tr>")
    parts.append("</table>")
    errs = []
    for r in runs:
        f = run_dir / r.name / INPUT_ERRORS_CSV
        if f.exists():
            df = pd.read_csv(f)
            for row in df.itertuples():
                errs.append((r.name, row))
    failed_inputs = [(n, row) for n, row in errs if getattr(row, "status", "failed") == "failed"]
    skipped_inputs = [(n, row) for n, row in errs if getattr(row, "status", "failed") != "failed"]
    parts.append(f"<h2>Input files that could not be evaluated ({len(failed_inputs)})</h2>")
    if failed_inputs:
        parts.append("<table><tr><th>notebook</th><th>file</th><th>error</th></tr>")
        for n, row in failed_inputs:
            parts.append(f"<tr><td>{esc(n)}</td><td>{esc(str(row.file))}</td><td class='failed'>{esc(str(row.error))}</td></tr>")
        parts.append("</table>")
    else:
        parts.append("<p>None.</p>")
    if skipped_inputs:
        reasons = sorted({str(row.error).split(":")[0] for _, row in skipped_inputs})
        parts.append(f"<p>Skipped {len(skipped_inputs)} file(s): {esc('; '.join(reasons))}.</p>")
    parts.append("<h2>Tables (CSV)</h2><ul>")
    for p in sorted(run_dir.glob("*/*.csv")):
        parts.append(f"<li><a href='{esc(_rel(p, run_dir))}'>{esc(_rel(p, run_dir))}</a></li>")
    parts.append("</ul><h2>Figures</h2>")
    for p in sorted(run_dir.glob("*/*.png")):
        svg = p.with_suffix(".svg")
        extra = f" (<a href='{esc(_rel(svg, run_dir))}'>svg</a>)" if svg.exists() else ""
        parts.append(f"<h3>{esc(_rel(p, run_dir))}{extra}</h3><a href='{esc(_rel(p, run_dir))}'>"
                     f"<img src='{esc(_rel(p, run_dir))}' loading='lazy'></a>")
    parts.append("<h2>Parameters</h2><pre>" + esc(json.dumps(dict(parameters), indent=2, default=str)) + "</pre>")
    parts.append("<h2>Versions</h2><table>" + "".join(
        f"<tr><td>{esc(k)}</td><td>{esc(v)}</td></tr>" for k, v in versions().items()) + "</table>")
    parts.append("</body></html>")
    index = run_dir / "index.html"
    index.write_text("\n".join(parts), encoding="utf-8")
    return index


def run_report(out: str | os.PathLike | None = None, parameters: Mapping[str, object] | None = None,
               notebooks: Iterable[str] | None = None, force: bool = False, progress: bool = True) -> tuple[Path, list[NotebookRun]]:
    """Run the notebooks into a new run folder; returns (run folder, notebook runs).

    Args:
        out: the run folder; default ``results/run-<date>-<time>``. An existing folder is an
            error unless ``force`` (then it is replaced once the new run is complete).
        parameters: papermill parameters; each notebook gets those it declares.
        notebooks: names (default: every notebook of :data:`DEFAULT_NOTEBOOKS` that exists).
    """
    run_dir = _new_run_dir(out)
    if run_dir.exists() and not force:
        raise LorisError(f"{run_dir} exists; choose another --out or pass --force to replace it")
    names = list(notebooks) if notebooks else available_notebooks()
    for n in names:
        notebook_path(n)
    params = dict(parameters or {})
    run_dir.parent.mkdir(parents=True, exist_ok=True)
    tmp = run_dir.with_name(f".{run_dir.name}.partial-{os.getpid()}")
    if tmp.exists():
        shutil.rmtree(tmp)
    tmp.mkdir(parents=True)
    runs: list[NotebookRun] = []
    it = names
    if progress:
        from tqdm.auto import tqdm

        it = tqdm(names, desc="report", unit="notebook")
    for n in it:
        if progress:
            it.set_postfix_str(n)
        runs.append(run_notebook(n, tmp, params))
    (tmp / "parameters.json").write_text(json.dumps(params, indent=2, default=str))
    write_index(tmp, runs, params, name=run_dir.name)
    # links inside the report are relative, so the folder can be moved into place as a whole
    if run_dir.exists():
        old = run_dir.with_name(f".{run_dir.name}.old-{os.getpid()}")
        os.replace(run_dir, old)
        os.replace(tmp, run_dir)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(tmp, run_dir)
    return run_dir, runs
