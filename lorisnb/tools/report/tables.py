"""Paper-ready tables: values with confidence intervals as ``0.83 [0.79, 0.87]``, written as LaTeX
(booktabs) or Markdown. Bold marks come from the ranking's test (:func:`lorisnb.core.stats.ranking.ranking`),
never from the point estimates alone: in a scene where some pair differs significantly, the
algorithms of rank 1 (significantly worse than none) are bold; where no pair differs, none is."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pandas as pd

from lorisnb.core.stats.inference import WEIGHTS
from lorisnb.errors import ValidationError
from lorisnb.io.writers import write_text
from lorisnb.tools.decisions.escape import clean, markdown_cell

#: Metrics where smaller is better; for the others larger is better.
LOWER_IS_BETTER = {"c_ate_rmse", "ate_rmse", "aoe_rmse", "c_aoe_rmse", "rpe_trans_rmse", "rpe_rot_rmse"}
LABELS = {"cr": "CR", "cr_t": "CR-T", "cs_r": "CS-R", "c_ate_rmse": "C-ATE (m)"}


def interval(value: float, low: float, high: float, digits: int = 2) -> str:
    """``0.83 [0.79, 0.87]``; just the value when there is no interval; ``n/a`` for NaN."""
    if value is None or not math.isfinite(value):
        return "n/a"
    if low is None or high is None or not (math.isfinite(low) and math.isfinite(high)):
        return f"{value:.{digits}f}"
    return f"{value:.{digits}f} [{low:.{digits}f}, {high:.{digits}f}]"


def comparison_table(
    ci: pd.DataFrame, metric: str = "cr", digits: int = 2, ranks: pd.DataFrame | None = None
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """From :func:`lorisnb.core.stats.inference.confidence_intervals`: one row per algorithm, one column per
    scene, cells ``value [low, high]`` of ``metric``. Returns (the table of strings, a boolean
    table of the bold cells: rank 1 in ``ranks`` (:func:`lorisnb.core.stats.ranking.ranking` of the same
    metric) in scenes where the test separates some algorithms; all False without ``ranks``)."""
    if metric not in WEIGHTS:
        raise ValidationError(f"metric={metric}: expected one of {', '.join(WEIGHTS)}")
    c = ci[ci["metric"] == metric]
    if c.empty:
        raise ValidationError(f"no confidence intervals of {metric} in the table")
    cells = c.assign(
        cell=[interval(v, lo, hi, digits) for v, lo, hi in zip(c["value"], c["low"], c["high"], strict=True)]
    )
    several = "suite" in c.columns and c["suite"].nunique() > 1  # rows per algorithm and suite
    cells["row"] = _rows(cells, several)
    text = cells.pivot_table(index="row", columns="scene", values="cell", aggfunc="first", sort=False)
    text.index.name = "algorithm"
    best = pd.DataFrame(False, index=text.index, columns=text.columns)
    if ranks is not None and len(ranks):
        r = ranks[ranks["metric"] == metric] if "metric" in ranks.columns else ranks
        if r.empty:
            raise ValidationError(f"the ranking is not of {metric}; rank the same metric as the table")
        by = [c for c in ("suite", "scene") if c in r.columns]
        separated = r.groupby(by)["rank"].transform("max") > 1
        top = r[(r["rank"] == 1) & separated]
        for row, scene in zip(_rows(top, several), top["scene"], strict=True):
            if row in best.index and scene in best.columns:
                best.loc[row, scene] = True
    return text.fillna("n/a"), best


def _rows(df: pd.DataFrame, several: bool) -> list[str]:
    """Row labels: the algorithm, with its suite when the table holds several suites."""
    if not several or "suite" not in df.columns:
        return [str(a) for a in df["algorithm"]]
    return [f"{a} ({s})" if s else str(a) for a, s in zip(df["algorithm"], df["suite"], strict=True)]


def caption_of(metric: str, level: float, test: str = "", alpha: float | None = None) -> str:
    """What the table shows and what bold means."""
    text = f"{LABELS.get(metric, metric)} per scene with {level:.0%} bootstrap confidence intervals."
    if test:
        text += (f" Bold: rank 1 by the {test} (Holm, alpha {alpha}), in scenes where some pair differs"
                 " significantly; no bold where none does.")  # fmt: skip
    return text


_LATEX_SPECIAL = {"&": r"\&", "%": r"\%", "$": r"\$", "#": r"\#", "_": r"\_", "{": r"\{", "}": r"\}",
                  "~": r"\textasciitilde{}", "^": r"\textasciicircum{}", "\\": r"\textbackslash{}"}  # fmt: skip


def latex_escape(text: str) -> str:
    """Text for LaTeX: what is not printable shown escaped as the terminal shows it (:func:`clean`:
    a control character stops LaTeX), then LaTeX's special characters."""
    return "".join(_LATEX_SPECIAL.get(ch, ch) for ch in clean(text))


def to_latex(text: pd.DataFrame, best: pd.DataFrame, caption: str = "", label: str = "") -> str:
    """A booktabs table (``\\toprule``, ``\\midrule``, ``\\bottomrule``), one row per algorithm,
    the cells marked in ``best`` in ``\\textbf``."""
    cols = list(text.columns)
    lines = [r"\begin{table}[t]", r"\centering"]
    if caption:
        lines.append(r"\caption{" + latex_escape(caption) + "}")
    if label:
        lines.append(r"\label{" + latex_escape(label) + "}")
    lines += [r"\begin{tabular}{l" + "c" * len(cols) + "}", r"\toprule"]
    lines.append(" & ".join(["Algorithm"] + [latex_escape(c) for c in cols]) + r" \\")
    lines.append(r"\midrule")
    for alg, row in text.iterrows():
        cells = [r"\textbf{" + latex_escape(v) + "}" if best.loc[alg, c] else latex_escape(v) for c, v in row.items()]
        lines.append(" & ".join([latex_escape(alg)] + cells) + r" \\")
    lines += [r"\bottomrule", r"\end{tabular}", r"\end{table}"]
    return "\n".join(lines) + "\n"


def to_markdown(text: pd.DataFrame, best: pd.DataFrame) -> str:
    """A Markdown (pipe) table, one row per algorithm, the cells marked in ``best`` in bold."""
    cols = list(text.columns)
    esc = markdown_cell  # a name's pipe, newline or escape sequence: shown, never a row of its own

    lines = ["| algorithm | " + " | ".join(esc(c) for c in cols) + " |", "|---|" + "---|" * len(cols)]
    for alg, row in text.iterrows():
        cells = [f"**{esc(v)}**" if best.loc[alg, c] else esc(v) for c, v in row.items()]
        lines.append(f"| {esc(alg)} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def write_comparison(ci: pd.DataFrame, metric: str, out: str | os.PathLike[str], force: bool = False,
                     digits: int = 2, ranks: pd.DataFrame | None = None, alpha: float | None = None) -> Path:  # fmt: skip
    """Write :func:`comparison_table` as LaTeX (``.tex``) or Markdown (``.md``), by the suffix;
    bold from ``ranks`` (see there). Markdown gets the caption as a line below the table."""
    check_table_suffix(out)
    text, best = comparison_table(ci, metric, digits, ranks)
    level = float(np.nanmax(ci["level"])) if len(ci) else 0.95
    caption = caption_of(metric, level, "permutation test" if ranks is not None else "", alpha)
    if Path(out).suffix.lower() == ".tex":
        body = to_latex(text, best, caption=caption, label=f"tab:{metric}")
    else:
        body = to_markdown(text, best) + "\n" + caption + "\n"
    return write_text(body, out, force)


def check_table_suffix(out: str | os.PathLike[str]) -> None:
    """A table file name must end in .tex or .md (checked before any work)."""
    if Path(out).suffix.lower() not in (".tex", ".md"):
        raise ValidationError(f"{out}: expected a .tex (LaTeX) or .md (Markdown) file name")
