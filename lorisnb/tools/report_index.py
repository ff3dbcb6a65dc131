"""The report's front page, ``index.html``: parameters, versions, every notebook with its status,
input files that could not be evaluated, links to every table and figure."""

from __future__ import annotations

import datetime as _dt
import html
import json
import platform
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import pandas as pd

from .notebook import INPUT_ERRORS_CSV

if TYPE_CHECKING:
    from .report import NotebookRun


def versions() -> dict[str, str]:
    """Versions of Python and the packages a report depends on."""
    out = {"python": platform.python_version()}
    from importlib import metadata

    for pkg in (
        "lorisnb",
        "numpy",
        "scipy",
        "pandas",
        "matplotlib",
        "seaborn",
        "evo",
        "papermill",
        "ipywidgets",
        "tqdm",
    ):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = "not installed"
    return out


def _rel(p: Path, root: Path) -> str:
    return p.relative_to(root).as_posix()


def write_index(
    run_dir: Path, runs: list["NotebookRun"], parameters: Mapping[str, object], name: str | None = None
) -> Path:
    """``index.html``: parameters, versions, notebooks with status, input errors, tables, figures."""
    esc = html.escape
    parts = [
        "<!doctype html><html><head><meta charset='utf-8'><title>lorisnb report</title>",
        "<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto}table{border-collapse:collapse}"
        "td,th{border:1px solid #ccc;padding:3px 8px;text-align:left;vertical-align:top}"
        ".failed{color:#b00}.ok{color:#070}.skipped{color:#b60}img{max-width:100%;border:1px solid #ddd}</style></head><body>",
        f"<h1>lorisnb report</h1><p>Run folder <code>{esc(name or run_dir.name)}</code>, written "
        f"{esc(_dt.datetime.now().isoformat(timespec='seconds'))}.</p>",
        "<h2>Notebooks</h2><table><tr><th>notebook</th><th>status</th><th>seconds</th><th>files</th><th>error</th></tr>",
    ]
    for r in runs:
        d = run_dir / r.name
        links = " ".join(
            f"<a href='{esc(_rel(p, run_dir))}'>{esc(p.suffix[1:])}</a>"
            for p in (d / f"{r.name}.html", d / f"{r.name}.ipynb")
            if p.exists()
        )
        parts.append(
            f"<tr><td>{esc(r.name)}</td><td class='{r.status}'>{r.status}</td><td>{r.seconds:.1f}</td>"
            f"<td>{links}</td><td><pre>{esc(r.error)}</pre></td></tr>"
        )
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
            parts.append(
                f"<tr><td>{esc(n)}</td><td>{esc(str(row.file))}</td><td class='failed'>{esc(str(row.error))}</td></tr>"
            )
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
        parts.append(
            f"<h3>{esc(_rel(p, run_dir))}{extra}</h3><a href='{esc(_rel(p, run_dir))}'>"
            f"<img src='{esc(_rel(p, run_dir))}' loading='lazy'></a>"
        )
    parts.append("<h2>Parameters</h2><pre>" + esc(json.dumps(dict(parameters), indent=2, default=str)) + "</pre>")
    parts.append(
        "<h2>Versions</h2><table>"
        + "".join(f"<tr><td>{esc(k)}</td><td>{esc(v)}</td></tr>" for k, v in versions().items())
        + "</table>"
    )
    parts.append("</body></html>")
    index = run_dir / "index.html"
    index.write_text("\n".join(parts), encoding="utf-8")
    return index
