"""What every notebook does first, in one call: find the data, choose the output folder, show
lorisnb's warnings once; and :class:`Outputs`, where a notebook writes its tables and figures.

A notebook's default output folder is never beside the notebook in the source tree: it is
``results/notebooks/<name>/`` of the checkout (or of the current folder) when there is one,
else a new temporary folder. ``lorisnb report`` passes ``output_dir="."`` (its run folder).
"""

from __future__ import annotations

import io
import os
import tempfile
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from lorisnb.errors import DataNotFoundError, LorisWarning
from lorisnb.io.datasets.paths import DataPaths, DataRoot, find_data, sample_data
from lorisnb.io.writers import write_csv

if TYPE_CHECKING:
    from lorisnb.core.spec.evalspec import EvalSpec

INPUT_ERRORS_CSV = "input_errors.csv"

#: A file ``lorisnb report`` writes into every run folder (``--force`` replaces only folders that
#: hold it); a notebook whose output folder lies directly in such a folder is part of a report.
RUN_MARKER = ".lorisnb-run"


class Outputs:
    """Where a notebook writes what it shows: tables as CSV, figures as PNG and SVG.

    ``table`` and ``figure`` return their argument so a cell can write and display at once.
    Input files that could not be evaluated go to ``input_errors.csv``, which the report lists.
    Inside a report's run folder (:data:`RUN_MARKER` in the parent folder) a figure is stored once:
    one PNG at 100 dpi (the size it is shown at) in 256 colours (:func:`compact_png`), which the
    notebook (and its HTML page) shows by reference instead of embedding.
    """

    def __init__(self, output_dir: str | os.PathLike[str]):
        self.dir = Path(output_dir)
        self.dir.mkdir(parents=True, exist_ok=True)
        self.in_report = (self.dir.resolve().parent / RUN_MARKER).is_file()

    def table(self, df: pd.DataFrame, name: str, index: bool = False) -> pd.DataFrame:
        write_csv(df.reset_index() if index else df, self.dir / f"{name}.csv", force=True)
        return df

    def figure(self, fig: Any, name: str) -> None:
        """Save ``fig`` as PNG, SVG and PDF and show it once in the notebook (:func:`show_figure`)."""
        from lorisnb.tools.figures.plotting import save_figure

        if self.in_report:  # one PNG at 100 dpi (the size it is shown at), 256 colours: about 20 kB
            path = self.dir / f"{name}.png"
            path.write_bytes(compact_png(figure_png(fig, dpi=100)))
            show_figure(fig, url=path.name)
            return
        paths = save_figure(fig, self.dir, name)
        show_figure(fig, png=paths[0].read_bytes())  # the PNG just written: drawn once, not twice

    def input_errors(self, failures: pd.DataFrame) -> pd.DataFrame:
        write_csv(failures, self.dir / INPUT_ERRORS_CSV, force=True)
        return failures


def figure_png(fig: Any, dpi: int = 150) -> bytes:
    """A figure rendered to PNG bytes (tight bounding box), on the calling thread, for the notebook's
    browser or to be made compact (:func:`compact_png`): zlib level 1, not Pillow's 6 (13-15 %
    larger; the timeline's PNG encoded about 5 times faster by
    :func:`~lorisnb.tools.figures.blit.encode_png`, other figures' 1.7 times by Pillow). A :class:`~lorisnb.tools.figures.plotting.Timeline`'s
    figure (the explorers') is redrawn only from what its thresholds change on
    (:class:`~lorisnb.tools.figures.blit.BlitCanvas`): the same pixels as a full savefig."""
    from lorisnb.tools.figures.blit import FAST_PNG, BlitCanvas

    if isinstance(fig.canvas, BlitCanvas):
        return fig.canvas.png(dpi, FAST_PNG)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight", pil_kwargs=FAST_PNG)
    return buf.getvalue()


def compact_png(png: bytes) -> bytes:
    """A PNG with its colours reduced to a 256-colour palette (Pillow's fast octree): a plot's
    flat colours and antialiasing survive, the file is about four times smaller."""
    from PIL import Image

    out = io.BytesIO()
    Image.open(io.BytesIO(png)).convert("RGB").quantize(256, method=Image.Quantize.FASTOCTREE).save(
        out, format="PNG", optimize=True
    )
    return out.getvalue()


def show_figure(fig: Any, dpi: int = 150, png: bytes | None = None, url: str | None = None) -> None:
    """Display a figure once, as a PNG image at its own size (not scaled to the notebook width
    unless wider), without going through pyplot; a pyplot figure is closed so that the inline
    backend does not show it a second time. With ``url`` (a PNG beside the notebook), the image
    is shown by reference, not embedded. Outside IPython, nothing is shown."""
    try:
        from IPython import get_ipython
        from IPython.display import Image, display
    except ImportError:
        return
    import matplotlib.pyplot as plt

    if plt.fignum_exists(getattr(fig, "number", -1)):
        plt.close(fig)
    if get_ipython() is None:
        return
    width = int(round(fig.get_figwidth() * 100))  # CSS pixels of the figure as designed
    if url is not None:
        display(Image(url=url, embed=False, width=width))
        return
    display(Image(data=png if png is not None else figure_png(fig, dpi), format="png", width=width))


def show_inputs(ev: Any, out: Outputs) -> None:
    """What a notebook shows about its inputs: the files that failed or were skipped (written to
    ``input_errors.csv`` for the report, shown only when there are any) and the warnings about
    the inputs, one row per file with the count and the first message (all of them in
    ``ev.warnings``)."""
    from IPython.display import display

    failures = out.input_errors(ev.failures_table())
    if len(failures):
        display(failures)
    table = warnings_table(ev)
    if len(table):
        print(f"{int(table['warnings'].sum())} note(s) about {len(table)} input file(s); all of them: ev.warnings")
        with pd.option_context("display.max_colwidth", 160):
            display(table)


def warnings_table(ev: Any) -> pd.DataFrame:
    """One row per input file with warnings: file, how many, the first message."""
    rows = [dict(file=f.file, warnings=len(f.warnings), first=f.warnings[0]) for f in ev.errors if f.warnings]
    return pd.DataFrame(rows, columns=["file", "warnings", "first"])


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
    """What :func:`setup` returns: the data root, the notebook's outputs and its parameters (as
    checked), whose evaluation spec :meth:`spec` builds."""

    data: DataPaths
    out: Outputs
    name: str
    parameters: Mapping[str, Any] = field(default_factory=dict)

    def spec(self, **fixed: Any) -> EvalSpec:
        """The evaluation spec of the notebook's parameters, with ``fixed`` (the notebook's own
        choices, such as ``mode="per-seq"``) over them: built by the same function as the report's
        leaderboard (:func:`lorisnb.tools.notebook.params.evaluation_spec`)."""
        from lorisnb.tools.notebook.params import evaluation_spec

        return evaluation_spec(self.parameters, **fixed)

    def filters(
        self, source: Any, algorithms: Any = None, scenes: Any = None
    ) -> tuple[list[str] | None, list[str] | None]:
        """``algorithms`` and ``scenes`` (None: all) as lists of names (one name: a list of one), each
        refused if it names nothing in ``source`` (result files or folders), as :func:`lorisnb.evaluate`
        and ``lorisnb report`` refuse them: for a notebook that reads its inputs later than its first cell."""
        from lorisnb.tools.evaluation.inputs import names
        from lorisnb.tools.evaluation.runner import check_filters

        algorithms = None if algorithms is None else names("algorithms", algorithms)
        scenes = None if scenes is None else names("scenes", scenes)
        check_filters(source, algorithms, scenes)
        return algorithms, scenes

    def show_inputs(self, ev: Any) -> None:
        """Show the input files that failed and the warnings about inputs (:func:`show_inputs`)."""
        show_inputs(ev, self.out)

    def interactive(self, make: Callable[[], Any]) -> None:
        """Display the widget ``make()`` builds. In a report's run folder nothing would ever move its
        sliders (the page is static), so it is not built; a note says where it works instead."""
        from IPython.display import display

        if self.out.in_report:
            print("(interactive explorer: open this notebook's .ipynb in Jupyter to use its sliders)")
            return
        display(make())


def check_notebook_parameters(name: str, parameters: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Check a notebook's parameters with the command line's rules
    (:func:`lorisnb.tools.notebook.params.check_values`): ``parameters``, and in a kernel every
    parameter its ``parameters`` cell declares, as the kernel holds it now. Under papermill, the
    names given with ``-p`` are checked as ``lorisnb report`` checks them
    (:func:`lorisnb.tools.notebook.params.check_parameters`): a name the notebook does not declare
    (``-p epss 3``: papermill only logs it) is refused, listing the declared names, as are ``-p NAME
    null`` for a parameter with a default and an option given without the one it needs. Returns
    the values checked, name -> value."""
    from lorisnb.tools.notebook.params import check_parameters, check_values, papermill_parameters

    values = dict(parameters or {})
    try:
        from IPython import get_ipython
    except ImportError:
        get_ipython = None
    shell = get_ipython() if get_ipython is not None else None
    history = getattr(shell, "user_ns", {}).get("In") if shell is not None else None
    found = papermill_parameters(history) if isinstance(history, list) else None
    if found is not None:
        assert shell is not None
        declared, injected = found
        namespace = shell.user_ns
        check_parameters({n: namespace.get(n) for n in injected}, {n: {"default": d} for n, d in declared.items()},
                         [name], by=name)  # fmt: skip
        values = {**{n: namespace[n] for n in declared if n in namespace and n != "output_dir"}, **values}
    check_values(values, [name])
    return values


def setup(
    name: str,
    data_root: DataRoot | None = None,
    output_dir: str | os.PathLike[str] | None = None,
    sample: bool = False,
    parameters: Mapping[str, Any] | None = None,
) -> Session:
    """The first call of every notebook: find the data (``data_root``, else ``$LORISNB_DATA``, else
    ``../shared/data``), create the output folder (``output_dir``, else :func:`default_output_dir`),
    and keep lorisnb's warnings about input files out of the cell output as Python warnings (they are
    summarized per file by :func:`show_inputs`). With ``sample=True`` (the primer and the labs), a
    notebook given no ``data_root`` that finds no data runs on the small data shipped with lorisnb
    (:func:`lorisnb.io.datasets.paths.sample_data`) and says so. ``parameters``: the notebook's parameters,
    checked first with the command line's rules (:func:`lorisnb.tools.notebook.params.check_values`:
    thresholds, grids, seed, yes/no values such as ``quick``, folders that must exist, ...)."""
    values = check_notebook_parameters(name, parameters)
    try:
        data = find_data(data_root)
    except DataNotFoundError:
        if not sample or data_root is not None:
            raise
        data = sample_data()
        print("no data root found: using the small sample data shipped with lorisnb (cafe scene only)")
    if values.get("scenes") is not None:  # OpenLORIS scenes, none with ground truth (office): nothing to score
        from lorisnb.core.trajectory.frames import SCENES
        from lorisnb.tools.evaluation.inputs import names
        from lorisnb.tools.report.leaderboard import refuse_unscorable_scenes

        if set(names("scenes", values["scenes"])) <= set(SCENES):  # any other name: refused naming the inputs' scenes
            refuse_unscorable_scenes(values["scenes"], data)
    out = Outputs(output_dir if output_dir is not None else default_output_dir(name))
    warnings.filterwarnings("ignore", category=LorisWarning)
    shown = out.dir.resolve() if output_dir is None else out.dir  # as given (a report passes ".")
    print(f"data root: {data.root}\noutputs:   {shown}")
    return Session(data, out, name, dict(parameters or {}))
