"""What the scoring processes' fork server imports and warms once, so that each scoring process,
forked from it, starts with lorisnb's evaluation and figures ready (a fresh process would spend
seconds importing them and loading the fonts for every submission)."""

from __future__ import annotations

import io

import matplotlib

matplotlib.use("Agg")

import lorisnb.tools.challenge.scoring  # noqa: E402,F401  (the evaluation pipeline)
from lorisnb.tools.figures.plotting import subplots  # noqa: E402


def _warm() -> None:
    fig, ax = subplots()
    ax.set_title("warm")
    fig.savefig(io.BytesIO(), format="png", dpi=10)  # the font cache and the PNG writer, loaded once


_warm()
