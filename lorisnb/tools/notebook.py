"""What every notebook does first, in one call: find the data, choose the output folder, show
lorisnb's warnings once; and :class:`Outputs`, where a notebook writes its tables and figures.

A notebook's default output folder is never beside the notebook in the source tree: it is
``results/notebooks/<name>/`` of the checkout (or of the current folder) when there is one,
else a new temporary folder. ``lorisnb report`` passes ``output_dir="."`` (its run folder).
"""

from __future__ import annotations

import os
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from ..errors import LorisWarning
from ..io.data import DataPaths, DataRoot, find_data
from ..io.writers import write_csv

INPUT_ERRORS_CSV = "input_errors.csv"


class Outputs:
    """Where a notebook writes what it shows: tables as CSV, figures as PNG and SVG.

    ``table`` and ``figure`` return their argument so a cell can write and display at once.
    Input files that could not be evaluated go to ``input_errors.csv``, which the report lists.
    """

    def __init__(self, output_dir: str | os.PathLike[str]):
        self.dir = Path(output_dir)
        self.dir.mkdir(parents=True, exist_ok=True)

    def table(self, df: pd.DataFrame, name: str, index: bool = False) -> pd.DataFrame:
        write_csv(df.reset_index() if index else df, self.dir / f"{name}.csv", force=True)
        return df

    def figure(self, fig: Any, name: str) -> Any:
        from .plotting import save_figure

        save_figure(fig, self.dir, name)
        return fig

    def input_errors(self, failures: pd.DataFrame) -> pd.DataFrame:
        write_csv(failures, self.dir / INPUT_ERRORS_CSV, force=True)
        return failures


def default_output_dir(name: str, start: Path | None = None) -> Path:
    """``results/notebooks/<name>`` of the nearest folder (the current one or a parent) that holds
    both ``notebooks/`` and ``results/`` (a lorisnb checkout), else a new temporary folder."""
    here = (start or Path.cwd()).resolve()
    for folder in (here, *here.parents):
        if (folder / "results").is_dir() and (folder / "notebooks").is_dir():
            return folder / "results" / "notebooks" / name
    return Path(tempfile.mkdtemp(prefix=f"lorisnb-{name}-"))


@dataclass(frozen=True)
class Session:
    """What :func:`setup` returns: the data root and the notebook's outputs."""

    data: DataPaths
    out: Outputs
    name: str


def setup(name: str, data_root: DataRoot | None = None, output_dir: str | os.PathLike[str] | None = None) -> Session:
    """The first call of every notebook: find the data (``data_root``, else ``$LORISNB_DATA``, else
    ``../shared/data``), create the output folder (``output_dir``, else :func:`default_output_dir`),
    and show each lorisnb warning once (not once per line of code that issued it)."""
    data = find_data(data_root)
    out = Outputs(output_dir if output_dir is not None else default_output_dir(name))
    warnings.filterwarnings("once", category=LorisWarning)
    print(f"data root: {data.root}\noutputs:   {out.dir.resolve()}")
    return Session(data, out, name)
