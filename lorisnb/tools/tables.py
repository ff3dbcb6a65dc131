"""Paper-ready tables: values with confidence intervals as ``0.83 [0.79, 0.87]``, the best value of
each column in bold, written as LaTeX (booktabs) or Markdown."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pandas as pd

from ..core.stats import WEIGHTS
from ..errors import ValidationError
from ..io.writers import write_text

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


def comparison_table(ci: pd.DataFrame, metric: str = "cr", digits: int = 2) -> tuple[pd.DataFrame, pd.DataFrame]:
    """From :func:`lorisnb.core.stats.confidence_intervals`: one row per algorithm, one column per
    scene, cells ``value [low, high]`` of ``metric``. Returns (the table of strings, a boolean
    table marking the best value of each column)."""
    if metric not in WEIGHTS:
        raise ValidationError(f"metric={metric}: expected one of {', '.join(WEIGHTS)}")
    c = ci[ci["metric"] == metric]
    if c.empty:
        raise ValidationError(f"no confidence intervals of {metric} in the table")
    cells = c.assign(
        cell=[interval(v, lo, hi, digits) for v, lo, hi in zip(c["value"], c["low"], c["high"], strict=True)]
    )
    text = cells.pivot_table(index="algorithm", columns="scene", values="cell", aggfunc="first", sort=False)
    values = c.pivot_table(index="algorithm", columns="scene", values="value", aggfunc="first", sort=False)
    values = values.reindex(index=text.index, columns=text.columns)
    target = values.min() if metric in LOWER_IS_BETTER else values.max()
    best = values.eq(target) & values.notna()
    return text.fillna("n/a"), best


_LATEX_SPECIAL = {"&": r"\&", "%": r"\%", "$": r"\$", "#": r"\#", "_": r"\_", "{": r"\{", "}": r"\}",
                  "~": r"\textasciitilde{}", "^": r"\textasciicircum{}", "\\": r"\textbackslash{}"}  # fmt: skip


def latex_escape(text: str) -> str:
    return "".join(_LATEX_SPECIAL.get(ch, ch) for ch in str(text))


def to_latex(text: pd.DataFrame, best: pd.DataFrame, caption: str = "", label: str = "") -> str:
    """A booktabs table (``\\toprule``, ``\\midrule``, ``\\bottomrule``), one row per algorithm,
    the best value of each column in ``\\textbf``."""
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
    """A Markdown (pipe) table, one row per algorithm, the best value of each column in bold."""
    cols = list(text.columns)

    def esc(v: object) -> str:
        return str(v).replace("|", r"\|")

    lines = ["| algorithm | " + " | ".join(esc(c) for c in cols) + " |", "|---|" + "---|" * len(cols)]
    for alg, row in text.iterrows():
        cells = [f"**{esc(v)}**" if best.loc[alg, c] else esc(v) for c, v in row.items()]
        lines.append(f"| {esc(alg)} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def write_comparison(ci: pd.DataFrame, metric: str, out: str | os.PathLike[str], force: bool = False,
                     digits: int = 2) -> Path:  # fmt: skip
    """Write :func:`comparison_table` as LaTeX (``.tex``) or Markdown (``.md``), by the suffix."""
    text, best = comparison_table(ci, metric, digits)
    suffix = Path(out).suffix.lower()
    level = float(np.nanmax(ci["level"])) if len(ci) else 0.95
    caption = f"{LABELS.get(metric, metric)} per scene with {level:.0%} bootstrap confidence intervals; best in bold."
    if suffix == ".tex":
        body = to_latex(text, best, caption=caption, label=f"tab:{metric}")
    elif suffix == ".md":
        body = to_markdown(text, best)
    else:
        raise ValidationError(f"{out}: expected a .tex (LaTeX) or .md (Markdown) file name")
    return write_text(body, out, force)
