"""The report's front page, ``index.html``: what was found first (per scene a leaderboard with
intervals, ranks with ties, coverage, the thresholds, one sentence), then the evidence behind
each claim (timelines, threshold sensitivity, per-sequence values, failures), each figure once
with a caption, then the notebooks, tables, parameters and versions. No script, no remote file."""

from __future__ import annotations

import datetime as _dt
import html
import json
import platform
import re
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from lorisnb.core.stats.regression import regressed_phrase
from lorisnb.io.writers import naming
from lorisnb.tools.decisions.escape import clean
from lorisnb.tools.decisions.runs import NOT_SCORED
from lorisnb.tools.notebook.start import INPUT_ERRORS_CSV

if TYPE_CHECKING:
    from lorisnb.tools.report.leaderboard import Findings
    from lorisnb.tools.report.notebooks import NotebookRun


def esc(text: object) -> str:
    """Text shown on the page in a line (a name in a table cell, a heading, a sentence): every
    control and format character (a newline, a tab, ESC, CR, a right-to-left override U+202E from a
    folder's name) and a backslash escaped visibly as the terminal shows them (``\\n``, ``\\t``,
    ``\\x1b``, ``\\u202e``: :func:`~lorisnb.tools.decisions.escape.clean`), so that ``new\\nline``
    never shows as ``new line``; then HTML's ``&<>"'``. A block in ``<pre>`` (a traceback) takes
    :func:`esc_block`, a link's address :func:`attr`."""
    return html.escape(clean(text))


def esc_block(text: object) -> str:
    """Text shown in ``<pre>`` (a traceback, the parameters): as :func:`esc`, its newlines and tabs
    kept."""
    return html.escape("\n".join("\t".join(map(clean, line.split("\t"))) for line in str(text).split("\n")))


#: A link's address (``href``, ``src``): HTML's characters escaped, the file's name as it is.
attr = html.escape

#: The "why" sections, in page order: (anchor, title, what they are evidence of).
SECTIONS = (
    ("timelines", "Timelines: when each algorithm tracked", "coverage and CR: when the output was there, and correct"),
    ("thresholds", "Threshold sensitivity", "whether a ranking holds at other thresholds than the report's"),
    ("trials", "Trials and comparisons", "run-to-run spread"),
    ("crosscheck", "Cross-check with evo", "that the errors behind every number agree with evo"),
    ("other", "Other figures", "the notebooks' other views"),
)

#: Captions of the shipped notebooks' figures: file stem (or stem prefix ending in '_') -> (section, caption).
CAPTIONS: dict[str, tuple[str, str]] = {
    "timeline_per_sequence": (
        "timelines",
        "Each sequence evaluated on its own (the paper's Fig. 2, at the notebook's thresholds: without any, "
        "by default, its percentages are the time tracked, not the leaderboards' CR): blue segments are the "
        "time covered by output poses; ATE RMSE bottom right.",
    ),
    "timeline_lifelong": (
        "timelines",
        "Sequences fed one after another and aligned on the first (Fig. 3): "
        "correct and wrong poses at the notebook's thresholds.",
    ),
    "timeline": ("timelines", "Your results over time: correct and wrong poses per sequence."),
    "trajectories_": ("timelines", "Your trajectory against the ground truth, coloured by correctness."),
    "cr_vs_eps": (
        "thresholds",
        "CR against the ATE threshold eps per scene: where curves cross, the ranking depends on eps.",
    ),
    "cr_heatmap_": ("thresholds", "CR of each algorithm over eps x phi in this scene."),
    "cr_vs_delta": ("thresholds", "CR against the validity window delta."),
    "cs_r_vs_tau": ("thresholds", "CS-R against the time factor tau."),
    "rank_stability": (
        "thresholds",
        "Kendall tau between the ranking at each eps and at the paper's eps: 1 means the same order.",
    ),
    "cr_vs_relative_eps": ("thresholds", "CR with eps relative to each sequence's extent."),
    "explorer_current": (
        "thresholds",
        "The threshold explorer's first view (the notebook's parameters); the sliders work in the .ipynb.",
    ),
    "simulated_trials": (
        "trials",
        "Simulated algorithms (not real results): spread of CR over trials with a "
        "known difference, to show what the tests can separate.",
    ),
    "crosscheck_per_pose": ("crosscheck", "Per-pose errors of lorisnb against evo on the same pairs: on the diagonal."),
    "primer_": ("other", "Teaching examples on simulated estimates (metrics primer)."),
    "ate_pct_length": ("other", "ATE as a share of path length across datasets (published and computed)."),
}


def versions() -> dict[str, str]:
    """Versions of Python and the packages a report depends on."""
    out = {"python": platform.python_version()}
    from importlib import metadata

    for pkg in ("lorisnb", "numpy", "scipy", "pandas", "matplotlib", "seaborn", "evo", "papermill", "ipywidgets",
                "nbconvert", "tqdm"):  # fmt: skip
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = "not installed"
    return out


def git_dirty(start: Path | None = None) -> bool | None:
    """Whether the git checkout lorisnb runs from has uncommitted changes (modified, staged or new
    files that git does not ignore): run.json's ``dirty`` beside its ``commit``. None when unknown."""
    import subprocess

    here = start or Path(__file__).resolve().parents[3]
    try:
        out = subprocess.run(["git", "-C", str(here), "status", "--porcelain"], capture_output=True, text=True,
                             timeout=20, check=False)  # fmt: skip
    except (OSError, subprocess.TimeoutExpired):
        return None
    return bool(out.stdout.strip()) if out.returncode == 0 else None


def caption(stem: str, notebook: str) -> tuple[str, str]:
    """(section, caption) of a figure; unknown figures go to 'other' with a plain caption."""
    if stem in CAPTIONS:
        return CAPTIONS[stem]
    for key, value in CAPTIONS.items():
        if key.endswith("_") and stem.startswith(key):
            scene = stem[len(key) :]
            return value[0], f"{value[1]} ({scene})" if scene else value[1]
    return "other", f"Figure '{stem}' of the notebook {notebook}."


def _table(df: pd.DataFrame, cls: str = "") -> str:
    head = "".join(f"<th>{esc(str(c))}</th>" for c in df.columns)
    rows = "".join("<tr>" + "".join(f"<td>{esc(str(v))}</td>" for v in r) + "</tr>" for r in df.itertuples(index=False))
    return f"<table class='{cls}'><thead><tr>{head}</tr></thead><tbody>{rows}</tbody></table>"


def _fmt(v: float) -> str:
    return "" if pd.isna(v) else f"{v:.3f}"


def _board_rows(board: pd.DataFrame) -> pd.DataFrame:
    everyone = set(board["algorithm"])
    tied = [
        "all others" if t and set(t.split(", ")) == everyone - {a} else t
        for a, t in zip(
            board["algorithm"],
            board.get("tied_with", pd.Series("", index=board.index)).fillna("").astype(str),
            strict=True,
        )  # fmt: skip
    ]
    out = pd.DataFrame({
        "rank": board["rank"], "algorithm": board["algorithm"], board["metric"].iloc[0]: board["value"].map(_fmt),
        f"{board['level'].iloc[0]:.0%} interval": [
            ("(one sequence)" if n <= 1 else "") if pd.isna(lo) else f"[{lo:.3f}, {hi:.3f}]"
            for lo, hi, n in zip(board["low"], board["high"], board["sequences_covered"], strict=True)
        ],
        "coverage (sequences)": board["coverage"], "trials": board["trials"], "tied with": tied,
    })  # fmt: skip
    return out


def _findings_html(f: "Findings", spec: Mapping[str, Any], evidence: Mapping[str, list[str]]) -> list[str]:
    values = spec.get("values", {})
    parts = ["<h2 id='findings'>What was found</h2>"]
    parts.append(
        f"<p class='spec'>Thresholds: eps = {esc(str(values.get('eps')))} (m; 'paper' = 1/3/5 m by scene size), "
        f"phi = {esc(str(values.get('phi')))} deg, delta = {esc(str(values.get('delta')))} s, "
        f"tau = {esc(str(values.get('tau')))} s; scale {esc(str(values.get('scale')))}. "
        f"Intervals: {values.get('level', 0.95):.0%} bootstrap over sequences (and trials). "
        f"Ranks: {esc(f.test)}. Coverage: sequences with output out of the scene's sequences with ground truth. "
        f"{esc(str(spec.get('description', '')))}</p>"
    )
    for (suite, scene), g in f.board.groupby(["suite", "scene"], sort=False):
        title = f"{scene}" + (f" ({suite})" if suite else "")
        anchor = f"scene-{suite}-{scene}".replace("/", "-")
        parts.append(f"<h3 id='{esc(anchor)}'>{esc(title)}</h3>")
        parts.append(_table(_board_rows(g), "leaderboard"))
        links = " · ".join(evidence.get(scene, []) + evidence.get(f"suite:{suite}", []) + evidence.get("*", []))
        links += f" · <a href='#seq-{esc(anchor[6:])}'>per-sequence values</a> · <a href='#failures'>failures</a>"
        parts.append(f"<p class='sentence'>{esc(f.sentences[(suite, scene)])}</p><p class='why'>Why: {links}</p>")
    return parts


def _figures(run_dir: Path, runs: Sequence["NotebookRun"]) -> dict[str, list[tuple[Path, str, str]]]:
    """section -> [(png, notebook, caption)], each figure once (the PNG; other formats linked)."""
    out: dict[str, list[tuple[Path, str, str]]] = {s[0]: [] for s in SECTIONS}
    for r in runs:
        for p in sorted((run_dir / r.name).glob("*.png")):
            section, text = caption(p.stem, r.name)
            out[section].append((p, r.name, text))
    return out


#: Figures that are evidence for every scene: the suite's timeline, the threshold curves.
_TIMELINE = {"per-seq": "timeline_per_sequence", "lifelong": "timeline_lifelong"}
_GENERAL = ("cr_vs_eps", "rank_stability")


def _evidence(figures: Mapping[str, list[tuple[Path, str, str]]], scenes: Sequence[str]) -> dict[str, list[str]]:
    """Links to the figures behind a scene's claims: its own (``cr_heatmap_<scene>``), its suite's
    timeline (key ``suite:<suite>``; both timelines for a results folder without suites), and the
    threshold curves (key ``*``)."""
    ev: dict[str, list[str]] = {"*": []}
    for items in figures.values():
        for p, nb, _ in items:
            link = f"<a href='#fig-{esc(nb)}-{esc(p.stem)}'>{esc(p.stem.replace('_', ' '))}</a>"
            for s in scenes:
                if p.stem.endswith(f"_{s}"):
                    ev.setdefault(s, []).append(link)
            for suite, stem in _TIMELINE.items():
                if p.stem == stem:
                    ev.setdefault(f"suite:{suite}", []).append(link)
                    ev.setdefault("suite:", []).append(link)
            if p.stem in _GENERAL:
                ev["*"].append(link)
    return ev


def write_index(
    run_dir: Path,
    runs: list["NotebookRun"],
    parameters: Mapping[str, object],
    name: str | None = None,
    findings: "Findings | None" = None,
    spec: Mapping[str, Any] | None = None,
    failures: pd.DataFrame | None = None,
    left_out: Mapping[str, str] | None = None,
    per_sequence: pd.DataFrame | None = None,
    wanted: str | None = None,
    expected: Mapping[str, Any] | None = None,
    label: str | None = None,
    since: Mapping[str, Any] | None = None,
    roots: Mapping[str, Path] | None = None,
) -> Path:
    """``index.html`` (see the module docstring). ``label``: the code under test, shown in the header;
    ``since``: this run against its baseline (:func:`lorisnb.tools.report.baseline.since_baseline`). ``name``: the run folder's name (``run_dir``'s by
    default); ``wanted``: the name asked for, when another run took it and this one is ``name``;
    ``expected``: scene -> its sequences with ground truth (each one gets a column of the
    per-sequence values, with or without output); ``roots``: the report's named roots (name -> folder,
    :func:`lorisnb.tools.report.portable.named_roots`), where a failure's file keyed ``{results}/...``
    is, to tell it is the file a notebook names by its path (listed and counted once)."""
    spec = spec or {}
    name = name or run_dir.name
    moved = (f" (<code>{esc(wanted)}</code> appeared while this report ran, another run's: this run is "
             f"<code>{esc(name)}</code>)") if wanted and wanted != name else ""  # fmt: skip
    parts = [
        "<!doctype html><html><head><meta charset='utf-8'><title>lorisnb report</title>",
        "<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto}table{border-collapse:collapse;"
        "margin:.5em 0}td,th{border:1px solid #ccc;padding:3px 8px;text-align:left;vertical-align:top}"
        ".leaderboard th{background:#eef}.sentence{font-size:1.05em}.why,.spec{color:#444}figure{margin:1em 0}"
        "figcaption{color:#333;font-size:.95em}.failed{color:#b00}.ok{color:#070}.skipped{color:#b60}"
        "img{max-width:100%;border:1px solid #ddd}</style></head><body>",
        f"<h1>lorisnb report</h1><p>{f'Code under test: <code class=label>{esc(label)}</code>. ' if label else ''}"
        f"Run folder <code>{esc(name)}</code>{moved}, written "
        f"{esc(_dt.datetime.now().isoformat(timespec='seconds'))}; provenance (command, version, inputs' "
        f"checksums) in <a href='run.json'>run.json</a>; one file for e-mail: <a href='report.html'>report.html</a>.</p>",
    ]
    if since:
        # the run itself, as the baseline's messages name it (its folder where it goes): "this run", not its path
        this = {str(run_dir.parent / n) for n in (name, wanted) if n}
        parts += _since_html(since, this)
    figures = _figures(run_dir, runs)
    if findings is not None and not len(findings.board):
        parts.append("<h2 id='findings'>What was found</h2><p class='failed'>No leaderboard: no result file could be "
                     "scored (see the failures below).</p>")  # fmt: skip
    elif findings is not None:
        scenes = list(dict.fromkeys(findings.board["scene"]))
        parts += _findings_html(findings, spec, _evidence(figures, scenes))
    else:
        parts.append("<h2 id='findings'>What was found</h2><p>No leaderboard: none of the selected notebooks "
                     "evaluates a results folder (run per_sequence_benchmark or compare_algorithms, or pass "
                     "--results DIR).</p>")  # fmt: skip
    seen = set(per_sequence["scene"]) if per_sequence is not None and len(per_sequence) else set()
    missing = [f"{esc(s)} ({len(seqs)} sequences)" for s, seqs in (expected or {}).items() if s not in seen]
    if findings is not None and missing:  # a scene with ground truth that no result file is of: said, not left out
        parts.append(f"<p class='failed'>No result file for {', '.join(missing)} with ground truth: not scored, on no "
                     "leaderboard.</p>")  # fmt: skip
    failed = [r for r in runs if r.status == "failed"]
    if failed:
        parts.append(f"<p class='failed'>{len(failed)} notebook(s) failed: " + ", ".join(
            f"<a href='#nb-{esc(r.name)}'>{esc(r.name)}</a>" for r in failed) + ".</p>")  # fmt: skip
    parts.append("<h2 id='why'>Why: the evidence</h2>")
    for key, title, what in SECTIONS:
        items = figures[key]
        if not items:
            continue
        parts.append(f"<h3 id='{key}'>{esc(title)}</h3><p class='why'>Evidence of {esc(what)}.</p>")
        for p, nb, text in items:
            rel = p.relative_to(run_dir).as_posix()
            parts.append(
                f"<figure id='fig-{esc(nb)}-{esc(p.stem)}'><a href='{attr(rel)}'><img src='{attr(rel)}' loading='lazy' "
                f"alt='{esc(text)}'></a><figcaption><b>{esc(p.stem)}</b> ({esc(nb)}): {esc(text)}</figcaption></figure>"
            )
    parts.append("<h3 id='per-sequence'>Per-sequence values</h3>")
    if per_sequence is not None and len(per_sequence):
        metric = spec.get("values", {}).get("metric", "cr")
        parts.append(f"<p class='why'>The {esc(metric)} of every sequence with ground truth (the mean over its trials) behind "
                     "the leaderboards ('no output': the algorithm has no result for it, counted as a failed run; 'k of n "
                     "trials': n - k of its trials are missing, each counted as a failed run on the leaderboard, not "
                     "in this mean; blank: not defined); all columns in <a href='findings/sequences.csv'>findings/sequences.csv</a>.</p>")  # fmt: skip
        for (suite, scene), g in per_sequence.groupby(["suite", "scene"], sort=False):
            pivot = _per_sequence(g, metric, (expected or {}).get(scene, ()), findings, suite, scene)
            parts.append(
                f"<h4 id='seq-{esc(f'{suite}-{scene}'.replace('/', '-'))}'>{esc(scene)}"
                + (f" ({esc(suite)})" if suite else "")
                + "</h4>"
            )
            parts.append(_table(pivot.reset_index(), "values"))
    else:
        parts.append("<p>None in this report.</p>")
    parts += _failures(run_dir, runs, failures, roots)
    parts += _notebooks(run_dir, runs, left_out or {})
    parts.append("<h2>Tables (CSV)</h2><ul>")
    for p in sorted(run_dir.glob("*/*.csv")):
        rel = p.relative_to(run_dir).as_posix()
        parts.append(f"<li><a href='{attr(rel)}'>{esc(rel)}</a></li>")
    parts.append(
        "</ul><h2>Parameters</h2><pre>" + esc_block(json.dumps(dict(parameters), indent=2, default=str)) + "</pre>"
    )
    parts.append("<h2>Versions</h2>" + _table(pd.DataFrame(list(versions().items()), columns=["package", "version"])))
    parts.append("</body></html>")
    index = run_dir / "index.html"
    with naming(index):  # a full disk names the page
        index.write_text("\n".join(parts), encoding="utf-8")
    return index


def expected_spans(ev: Any, data: Any, scenes: Any = None) -> dict[str, dict[int, tuple[float, float]]]:
    """scene -> sequence -> ground-truth span (s) of every scene evaluated (``ev.spans()``), and of
    every other scene with ground truth in ``data`` that the ``scenes`` filter (None: all) keeps:
    the scenes no result file is of, which the front page names instead of leaving them out."""
    from lorisnb.io.datasets.paths import scene_spans
    from lorisnb.tools.evaluation.inputs import names

    spans = dict(ev.spans())
    kept = None if scenes is None else set(names("scenes", scenes))
    other = [s for s in data.scenes_with_groundtruth() if s not in spans and (kept is None or s in kept)]
    return {**spans, **(scene_spans(other, data) if other else {})}


def _per_sequence(g: pd.DataFrame, metric: str, expected: Any, findings: "Findings | None", suite: str,
                  scene: str) -> pd.DataFrame:  # fmt: skip
    """Algorithms (every one of the scene's leaderboard) x every sequence of the scene (``expected``,
    and any with a row): the metric as text, 'no output' where the algorithm has no row."""
    values = g.pivot_table(index="algorithm", columns="seq", values=metric, aggfunc="mean", dropna=False)
    rows = g.pivot_table(index="algorithm", columns="seq", values=metric, aggfunc="size", dropna=False)
    algorithms = list(values.index)
    if findings is not None and len(findings.board):
        b = findings.board
        algorithms += [a for a in b[(b["suite"] == suite) & (b["scene"] == scene)]["algorithm"] if a not in algorithms]
    seqs = sorted(set(values.columns) | {int(s) for s in expected})
    values, rows = values.reindex(index=algorithms, columns=seqs), rows.reindex(index=algorithms, columns=seqs)
    text = values.map(_fmt).where(rows.fillna(0).to_numpy() > 0, "no output")
    most = rows.max(axis=1)  # an algorithm's trials: a sequence with fewer lacks some (a failed run each, as ranked)
    short = (rows.fillna(0).to_numpy() > 0) & (rows.to_numpy() < most.to_numpy()[:, None])
    counts = rows.fillna(0).astype(int).astype(str)
    marks = (
        " ("
        + counts
        + " of "
        + pd.DataFrame({c: most.fillna(0).astype(int).astype(str) for c in rows.columns})
        + " trials)"
    )
    text = text.where(~short, text + marks)
    text.columns = [f"seq {c}" for c in seqs]
    return text


def _same_file(file: str, roots: Mapping[str, Path] | None) -> str:
    """What tells one input file from another however it is written: where it really is (a key
    ``{results}/alg/x.txt`` below its root in ``roots``, a path as typed or absolute, links
    resolved); the text as it is where it is neither."""
    import os

    from lorisnb.tools.report.portable import split_key

    named = split_key(file)
    if named is not None:
        if not roots or named[0] not in roots:
            return file
        where = roots[named[0]] / named[1] if named[1] else roots[named[0]]
    else:
        where = Path(file)
    try:
        return os.path.realpath(where)
    except (OSError, ValueError):
        return file


def _failures(run_dir: Path, runs: Sequence["NotebookRun"], failures: pd.DataFrame | None,
              roots: Mapping[str, Path] | None = None) -> list[str]:  # fmt: skip
    """Every input file the report's own evaluation or a notebook did not score (failed, or not
    scored: :data:`lorisnb.tools.decisions.runs.NOT_SCORED`, as the terminal counts them), each once with its
    path, status and reason (once too where the report keys it below its root, ``{results}/...``,
    and a notebook names it by its path: :func:`_same_file`); then the files skipped on purpose (a
    scene without ground truth, ...), each with its path and reason too."""
    rows = [] if failures is None else [("report", r) for r in failures.itertuples()]
    for r in runs:
        f = run_dir / r.name / INPUT_ERRORS_CSV
        if f.exists():
            rows += [(r.name, row) for row in pd.read_csv(f, dtype=str, keep_default_na=False).itertuples()]
    unscored: dict[str, tuple[str, Any]] = {}
    skipped: dict[str, tuple[str, Any]] = {}
    for n, row in rows:
        status = str(getattr(row, "status", "failed"))
        (unscored if status in NOT_SCORED else skipped).setdefault(_same_file(str(row.file), roots), (n, row))
    for file in unscored:
        skipped.pop(file, None)
    parts = [f"<h3 id='failures'>Failures: input files that could not be evaluated or scored ({len(unscored)})</h3>"]
    for rows_, cls in ((unscored, "failed"), (skipped, "skipped")):
        if not rows_:
            continue
        if cls == "skipped":
            parts.append(f"<p>Skipped on purpose ({len(skipped)} file(s), not counted as failures):</p>")
        parts.append("<table><tr><th>found by</th><th>file</th><th>status</th><th>reason</th></tr>")
        for n, row in rows_.values():
            parts.append(f"<tr><td>{esc(n)}</td><td>{esc(str(row.file))}</td><td>{esc(str(getattr(row, 'status', 'failed')))}"
                         f"</td><td class='{cls}'>{esc(str(row.error))}</td></tr>")  # fmt: skip
        parts.append("</table>")
    if not unscored:
        parts.insert(1, "<p>None.</p>")
    return parts


def _notebooks(run_dir: Path, runs: Sequence["NotebookRun"], left_out: Mapping[str, str]) -> list[str]:
    per_seq = next((r.thresholds for r in runs if r.name == "per_sequence_benchmark"), {})
    none = all(per_seq.get(k, "inf") == "inf" for k in ("eps", "phi"))
    fig2 = ("; the per-sequence benchmark reproduces Fig. 2 " + ("without any" if none else
            "at " + ", ".join(f"{k} {v}" for k, v in per_seq.items() if k in ("eps", "phi"))) if per_seq else "")  # fmt: skip
    parts = [f"<h2>Notebooks</h2><p>Each notebook's CR, CR-T, CS-R and C-ATE are at its own thresholds{esc(fig2)}; "
             "the leaderboards use those stated above.</p><table><tr><th>notebook</th><th>status</th><th>seconds</th>"
             "<th>thresholds</th><th>files</th><th>error</th></tr>"]  # fmt: skip
    for r in runs:
        d = run_dir / r.name
        links = " ".join(
            f"<a href='{attr(p.relative_to(run_dir).as_posix())}'>{esc(p.suffix[1:])}</a>"
            for p in (d / f"{r.name}.html", d / f"{r.name}.ipynb")
            if p.exists()
        )
        parts.append(
            f"<tr id='nb-{esc(r.name)}'><td>{esc(r.name)}</td><td class='{r.status}'>{r.status}</td>"
            f"<td>{r.seconds:.1f}</td><td>{esc(', '.join(f'{k} {v}' for k, v in r.thresholds.items()))}</td>"
            f"<td>{links}</td><td><pre>{esc_block(r.error)}</pre></td></tr>"
        )
    parts.append("</table>")
    if left_out:
        parts.append("<p>Not run: " + "; ".join(f"{esc(k)} ({esc(v)})" for k, v in left_out.items()) + ".</p>")
    return parts


def _since_html(since: Mapping[str, Any], this: Iterable[str] = ()) -> list[str]:
    """The "Since the baseline" section: the verdict of diff against the baseline, what changed, and
    the trend figure (a file of the run folder: opens offline); without a comparable earlier run,
    why, and that a new series starts here. ``this``: the run's own folder as the messages of
    :func:`~lorisnb.tools.report.baseline.since_baseline` name it, said "this run" (a portable run
    showed the literal ``{run}`` its path was replaced by)."""
    this = sorted(this, key=len, reverse=True)

    def said(text: object) -> str:  # the path whole, not the start of another's (night3 of night3-2)
        out = str(text)
        for path in this:
            out = re.sub(re.escape(path) + r"(?![\w/-])", "this run", out)
        return out

    if since.get("baseline") is None:
        return [
            "<h2 id='since-baseline'>Since the baseline</h2>",
            f"<p class='verdict failed'>No baseline: {esc(said(since.get('no_baseline', '')))}. Nothing was judged; "
            "a new series starts with this run (the next run comparable with it is judged against it).</p>",
        ]
    v = since["verdict"]
    ok = v["verdict"] == "ok"
    who = esc(str(since["baseline"])) + (f" (code <code>{esc(str(since['baseline_label']))}</code>)"
                                         if since.get("baseline_label") else "")  # fmt: skip
    parts = [
        "<h2 id='since-baseline'>Since the baseline</h2>",
        f"<p class='verdict {'ok' if ok else 'failed'}'>Against <code>{who}</code>: <b>{esc(v['verdict'])}</b>"
        + ("" if ok else f" ({esc(regressed_phrase(v))})")
        + ". "
        + esc(", ".join(f"{n} {k}" for k, n in v["counts"].items() if n))
        + ".</p>",
        f"<p class='why'>{esc(v.get('rule', ''))}</p>",
    ]
    for warning in since.get("warnings", []):  # the baseline chosen by time against the dates in the runs' names
        parts.append(f"<p class='verdict failed'>Warning: {esc(said(warning))}</p>")
    for title, rows in (("Regressions", v["regressions"]), ("Improvements", v["improvements"])):
        if not rows:
            continue
        parts.append(f"<h3>{title} ({len(rows)})</h3><table class='changes'><tr><th>algorithm</th><th>where</th>"
                     "<th>metric</th><th>baseline</th><th>this run</th></tr>")  # fmt: skip
        for r in rows[:50]:
            where = f"{r['scene']}-{r['seq']}" if r["seq"] is not None else f"{r['scene']} (scene)"
            cells = [r["algorithm"], where, r["metric"], _num(r["base"]), _num(r["cand"])]
            parts.append("<tr>" + "".join(f"<td>{esc(str(c))}</td>" for c in cells) + "</tr>")
        parts.append("</table>" + (f"<p>... {len(rows) - 50} more in findings/since_baseline.json</p>"
                                   if len(rows) > 50 else ""))  # fmt: skip
    for t in v.get("tradeoffs", []):
        parts.append(f"<p>Trade-off: <b>{esc(t['algorithm'])}</b> worse in {esc(', '.join(t['worse']))}; "
                     f"better in {esc(', '.join(t['better']))}.</p>")  # fmt: skip
    if since.get("new_algorithms"):
        parts.append("<p>New algorithms (not in the baseline): " + esc(", ".join(since["new_algorithms"])) + ".</p>")
    if since.get("passed_over"):
        parts.append("<p>Earlier runs passed over, not comparable with this one (changed settings) or not read as a run: " + esc("; ".join(
            f"{p['run']}: {said(p['why'])}" for p in since["passed_over"])) + ".</p>")  # fmt: skip
    if since.get("failed_inputs"):
        parts.append(
            f"<p class='failed'>Inputs this run could not score: {esc(', '.join(since['failed_inputs']))}.</p>"
        )
    if since.get("trend"):
        parts.append(f"<figure><img src='{attr(since['trend'])}' alt='CR per scene over the last comparable runs'>"
                     "<figcaption>CR per scene over the last comparable runs (ring: changed by diff's rule).</figcaption>"
                     "</figure>")  # fmt: skip
    return parts


def _num(v: Any) -> str:
    return f"{v:.4g}" if isinstance(v, float) else ("" if v is None else str(v))
