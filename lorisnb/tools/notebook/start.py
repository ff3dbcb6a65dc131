"""What every notebook does first, in one call: find the data, choose the output folder, show
lorisnb's warnings once; and :class:`Outputs`, where a notebook writes its tables and figures.

A notebook's default output folder is never beside the notebook in the source tree: it is
``results/notebooks/<name>/`` of the checkout (or of the current folder) when there is one,
else a new temporary folder. ``lorisnb report`` passes ``output_dir="."`` (its run folder).
An output folder is never one of the notebook's inputs, nor holds or lies in one
(:func:`check_output_dir`), and a notebook replaces only the files it wrote there itself
(:data:`OUTPUTS_MARKER` lists them).
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import tempfile
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from lorisnb.errors import DataNotFoundError, LorisWarning, OutputError, ValidationError
from lorisnb.io.datasets.paths import ENV_VAR, DataPaths, DataRoot, find_data, sample_data
from lorisnb.io.writers import overlap, write_atomically, write_csv, write_text
from lorisnb.tools.decisions.escape import clean

if TYPE_CHECKING:
    from lorisnb.core.spec.evalspec import EvalSpec

INPUT_ERRORS_CSV = "input_errors.csv"

#: A file ``lorisnb report`` writes into every run folder (``--force`` replaces only folders that
#: hold it); a notebook whose output folder lies directly in such a folder is part of a report.
RUN_MARKER = ".lorisnb-run"

#: A file :class:`Outputs` writes into a notebook's output folder (JSON): every file a notebook wrote
#: there, by its name in the folder, and which notebook wrote it. A notebook replaces a file of its
#: output folder only where this marker lists it as that notebook's own: a notebook run again into
#: its folder replaces its files, and any other file of the same name (the user's, another notebook's)
#: is refused and left as it is. The one exception: the notebook's default folder before it holds a
#: marker, where a file that shows it is lorisnb's (:func:`written_by_lorisnb`) is an earlier run's.
OUTPUTS_MARKER = ".lorisnb-notebook"

#: What the figures lorisnb saves (matplotlib) say of themselves near their start, by suffix.
_FIGURE_SIGNS = {".png": b"Matplotlib version", ".svg": b"Matplotlib v", ".pdf": b"(Matplotlib"}


def written_by_lorisnb(path: Path, header: str | None = None) -> bool:
    """Whether the file ``path`` plausibly is one an earlier lorisnb notebook wrote under this name:
    a figure that says matplotlib made it (PNG, SVG, PDF), or a CSV table whose first line is
    ``header`` (the column names of the table about to replace it). Anything else, or a file that
    cannot be read, is not: there is no way to know, so it is never replaced."""
    suffix = path.suffix.lower()
    try:
        if path.is_symlink() or not path.is_file():
            return False
        with open(path, "rb") as f:
            start = f.read(8192)
    except OSError:
        return False
    if suffix in _FIGURE_SIGNS:
        return _FIGURE_SIGNS[suffix] in start
    if suffix == ".csv" and header is not None:
        return start.split(b"\n", 1)[0].rstrip(b"\r") == header.encode()
    return False


#: The files :meth:`Outputs.figure` saves a figure as (outside a report's run folder).
FIGURE_FORMATS = ("png", "svg", "pdf")


def check_output_dir(output_dir: Any, inputs: Mapping[str, str | os.PathLike[str]] | None = None) -> Path:
    """A notebook's ``output_dir`` as a path, checked before anything is made or written: a folder
    name (not empty, not a file), and neither one of the notebook's ``inputs`` nor holding one nor
    lying in one, as the command line refuses an output folder among its inputs
    (:func:`lorisnb.io.writers.overlap`, :func:`lorisnb.cli.outputs.check_output`): the tables and
    figures would be mixed with what the notebook reads, and read as inputs by a later run.
    ``inputs``: each input as the error names it (``"the input path=DIR"``) -> its path."""
    if not isinstance(output_dir, (str, os.PathLike)) or not str(output_dir).strip():
        raise ValidationError(
            f"output_dir={output_dir!r}: expected a folder name (None: the notebook's default folder)"
        )
    from lorisnb.tools.notebook.params import user_path

    target = user_path(output_dir)  # "~/out" is the home folder's out, as for the input paths
    for label, where in (inputs or {}).items():
        hit = overlap(target, [where])
        if hit:
            raise OutputError(
                f"output_dir={output_dir} {hit[0]} {label} of this notebook: its tables and figures would be "
                "mixed with what it reads; choose an output_dir outside the notebook's inputs"
            )
    if target.exists() and not target.is_dir():
        raise OutputError(f"output_dir={output_dir} is a file; expected a folder (the notebook writes its tables "
                          "and figures into it): choose another output_dir")  # fmt: skip
    return target


def notebook_inputs(values: Mapping[str, Any], data: DataPaths) -> dict[str, Path]:
    """What a notebook reads, for :func:`check_output_dir`: its path parameters given (``values``;
    :data:`lorisnb.tools.notebook.params.PATHS`: results, estimates, ground truth, a manifest and the
    ground truth it names) and the data root, each named as an error names it."""
    from lorisnb.tools.notebook.params import PATHS, user_path
    from lorisnb.tools.report.portable import manifest_files

    found: dict[str, Path] = {}
    for name in PATHS:
        value = values.get(name)
        if value is None or name == "data_root":  # the data root: as found, below
            continue
        if name == "manifest":  # the file (a built-in manifest's name is none of the user's) and its ground truth
            found.update({f"the input {f} (of manifest={value})": f for f in manifest_files(value)})
            continue
        found[f"the input {name}={value}"] = user_path(str(value))
    found[f"the data root {data.root}"] = data.root
    return found


def _who(owner: str) -> str:
    return f"the notebook {owner}" if owner else "lorisnb's Outputs without a notebook's name"


class Outputs:
    """Where a notebook writes what it shows: tables as CSV, figures as PNG and SVG.

    ``table`` and ``figure`` return their argument so a cell can write and display at once.
    Input files that could not be evaluated go to ``input_errors.csv``, which the report lists.
    Inside a report's run folder (:data:`RUN_MARKER` in the parent folder) a figure is stored once:
    one PNG at 100 dpi (the size it is shown at) in 256 colours (:func:`compact_png`), which the
    notebook (and its HTML page) shows by reference instead of embedding.

    The folder is checked first (:func:`check_output_dir`: a folder, none of the notebook's ``inputs``,
    name -> path). Every file written is listed in the folder's :data:`OUTPUTS_MARKER` as ``notebook``'s
    before it is written; a file of the same name that the marker does not list as ``notebook``'s is
    never replaced (:class:`~lorisnb.errors.OutputError`, before any file of the call is written), except,
    in the notebook's default folder (``own_folder``) before it holds a marker, a file that shows it is
    an earlier lorisnb run's (:func:`written_by_lorisnb`). A notebook that writes a file itself asks
    :meth:`path` for its name.
    """

    def __init__(
        self,
        output_dir: str | os.PathLike[str],
        *,
        notebook: str | None = None,
        inputs: Mapping[str, str | os.PathLike[str]] | None = None,
        own_folder: bool = False,
    ):
        self.dir = check_output_dir(output_dir, inputs)
        self.notebook = notebook or ""
        #: the notebook's default folder (``results/notebooks/<name>``, named for it)
        self.own_folder = own_folder
        self.marker = self.dir / OUTPUTS_MARKER
        #: the default folder without a marker when this run began (a lorisnb before the marker wrote it): a
        #: file there that shows it is lorisnb's (:func:`written_by_lorisnb`) is an earlier run's, replaced;
        #: once a marker exists, only the files it lists are
        self.adopting = own_folder and not (self.marker.exists() or self.marker.is_symlink())
        self.written()  # a marker lorisnb did not write: refused before the folder is used
        self.dir.mkdir(parents=True, exist_ok=True)
        self.in_report = (self.dir.resolve().parent / RUN_MARKER).is_file()

    def table(self, df: pd.DataFrame, name: str, index: bool = False) -> pd.DataFrame:
        table = df.reset_index() if index else df
        with self._writing([f"{_stem(name)}.csv"], header=_header(table)) as (path,):
            write_csv(table, path, force=True)
        return df

    def figure(self, fig: Any, name: str) -> None:
        """Save ``fig`` as PNG, SVG and PDF and show it once in the notebook (:func:`show_figure`)."""
        from lorisnb.tools.figures.plotting import save_figure

        if self.in_report:  # one PNG at 100 dpi (the size it is shown at), 256 colours: about 20 kB
            png = compact_png(figure_png(fig, dpi=100))
            with self._writing([f"{_stem(name)}.png"]) as (path,):
                write_atomically(path, lambda tmp: tmp.write_bytes(png), force=True)
            show_figure(fig, url=path.relative_to(self.dir).as_posix())
            return
        with self._writing([f"{_stem(name)}.{f}" for f in FIGURE_FORMATS]) as paths:
            save_figure(fig, self.dir, name, FIGURE_FORMATS)
        show_figure(fig, png=paths[0].read_bytes())  # the PNG just written: drawn once, not twice

    def input_errors(self, failures: pd.DataFrame) -> pd.DataFrame:
        with self._writing([INPUT_ERRORS_CSV], header=_header(failures)) as (path,):
            write_csv(failures, path, force=True)
        return failures

    def path(self, name: str) -> Path:
        """The path of the file ``name`` (its name in the output folder, with its suffix) for a notebook
        that writes a file itself, listed first as this notebook's (refused as :meth:`table` refuses a
        file it did not write)."""
        rel = self._name(name)
        self._claim([rel])
        return self.dir / rel

    def written(self) -> dict[str, str]:
        """The files of the folder its marker lists: name -> the notebook that wrote it ("": an
        :class:`Outputs` given no notebook's name); empty without a marker."""
        if not (self.marker.exists() or self.marker.is_symlink()):
            return {}
        try:
            files = json.loads(self.marker.read_text(encoding="utf-8")).get("files")
        except (OSError, UnicodeDecodeError, ValueError, AttributeError, RecursionError):  # nested past the stack
            files = None
        if not isinstance(files, dict) or not all(isinstance(k, str) and isinstance(v, str) for k, v in files.items()):
            raise OutputError(
                f"{self.marker}: not a list of the files a notebook wrote (lorisnb writes it as JSON, beside the "
                f"tables and figures); nothing is written into {self.dir}: choose another output_dir, or move "
                f"{OUTPUTS_MARKER} out of it"
            )
        return files

    def _name(self, name: str) -> str:
        """``name`` as the marker lists it: a path inside the output folder (POSIX), never the marker."""
        p = Path(name) if isinstance(name, str) else None
        if p is None or p.is_absolute() or ".." in p.parts or p.name in ("", ".") or p.name == OUTPUTS_MARKER:
            raise ValidationError(f"{name!r}: expected a file name inside the output folder {self.dir}")
        return p.as_posix()

    def expect(self, tables: Sequence[str] = (), figures: Sequence[str] = (), files: Sequence[str] = ()) -> None:
        """Refuse now, before anything is written, a file this notebook will write (``tables`` and
        ``figures`` by the names :meth:`table` and :meth:`figure` take, ``files`` by their names) that
        its write would refuse (the user's file, another notebook's): called by :func:`setup` with
        :data:`NOTEBOOK_OUTPUTS`, so a refusal never comes partway through, after the first tables were
        written. Nothing is listed in the marker; a CSV file in the default folder before any marker is
        left to its write, which alone knows the table's first line (:func:`written_by_lorisnb`)."""
        kinds = ("png",) if self.in_report else FIGURE_FORMATS
        names = [f"{_stem(t)}.csv" for t in tables] + [f"{_stem(f)}.{k}" for f in figures for k in kinds]
        self._check([self._name(n) for n in [*names, *files]], self.written(), ahead=True)

    def _claim(self, names: Sequence[str], header: str | None = None) -> None:
        """List ``names`` (:meth:`_name`) as this notebook's in the marker, after checking that each
        is either absent or already this notebook's (or, in the default folder before any marker, an
        earlier lorisnb run's: :attr:`adopting`; ``header``: the first line of the CSV table about to be
        written, which such a table's file starts with); one refused, none is listed."""
        listed = self.written()
        self._check(names, listed, header)
        new = {rel: self.notebook for rel in names if listed.get(rel) != self.notebook}
        if new:
            self._list({**listed, **new})

    def _check(self, names: Sequence[str], listed: Mapping[str, str], header: str | None = None,
               ahead: bool = False) -> None:  # fmt: skip
        """Refuse the first of ``names`` this notebook may not write (:meth:`_claim`); ``ahead``
        (:meth:`expect`): a CSV file that may be an earlier run's is not refused yet."""
        for rel in names:
            p = self.dir / rel
            owner = listed.get(rel)
            if not (p.exists() or p.is_symlink()):
                continue
            if owner is None and self.adopting and (written_by_lorisnb(p, header) or (ahead and p.suffix == ".csv")):
                continue  # an earlier run's of this notebook (no marker then): listed below as its own
            if owner is None:
                why = (
                    "it is not a table or figure an earlier lorisnb run could have written (no marker lists it)"
                    if self.adopting
                    else f"the folder's {OUTPUTS_MARKER} does not list it"
                )
                raise OutputError(
                    f"{p} exists and this notebook did not write it ({why}); it is left as it is: choose another "
                    f"output_dir, or move {rel} out of {self.dir} and run again"
                )
            if owner != self.notebook:
                raise OutputError(
                    f"{p} was written by {_who(owner)}, not by {_who(self.notebook)}; it is left as it is: choose "
                    f"another output_dir for this notebook (each notebook its own), or move {rel} out of {self.dir}"
                )

    def _list(self, files: Mapping[str, str]) -> None:
        from lorisnb._version import __version__

        record = {"lorisnb": __version__, "files": dict(sorted(files.items()))}
        write_text(json.dumps(record, indent=1) + "\n", self.marker, force=True)

    @contextlib.contextmanager
    def _writing(self, names: Sequence[str], header: str | None = None) -> Iterator[list[Path]]:
        """The paths of ``names``, claimed (:meth:`_claim`) before the block writes them; a name whose
        file the block did not write (it failed) is no longer listed."""
        rels = [self._name(n) for n in names]
        self._claim(rels, header)
        try:
            yield [self.dir / r for r in rels]
        except BaseException:
            with contextlib.suppress(OSError, OutputError):
                listed = self.written()
                missing = [r for r in rels if not (self.dir / r).exists() and r in listed]
                if missing:
                    self._list({k: v for k, v in listed.items() if k not in missing})
            raise


def _header(df: pd.DataFrame) -> str:
    """The first line of ``df`` written as CSV (:func:`~lorisnb.io.writers.write_csv`): its column names."""
    return df.iloc[:0].to_csv(index=False, lineterminator="\n").rstrip("\n")


def _stem(name: Any) -> str:
    """A table's or figure's name (its file's name without the suffix): some text."""
    if not isinstance(name, str) or not name.strip():
        raise ValidationError(f"{name!r}: expected a file name (without its suffix) for the table or figure")
    return name


def figure_png(fig: Any, dpi: int = 150) -> bytes:
    """A figure rendered to PNG bytes (tight bounding box), on the calling thread, for the notebook's
    browser or to be made compact (:func:`compact_png`): zlib level 1, not Pillow's 6 (13-15 %
    larger; the timeline's PNG encoded about 5 times faster by
    :func:`~lorisnb.tools.figures.blit.encode_png`, other figures' 1.7 times by Pillow). A :class:`~lorisnb.tools.figures.plotting.Timeline`'s
    figure (the explorers') is redrawn only from what its thresholds change on
    (:class:`~lorisnb.tools.figures.blit.BlitCanvas`): the same pixels as a full savefig."""
    from lorisnb.tools.figures.blit import FAST_PNG, BlitCanvas
    from lorisnb.tools.figures.plotting import escape_unprintable

    escape_unprintable(fig)  # a text not printable (a caller's title): escaped, as save_figure escapes it
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


def _shown(value: Any) -> Any:
    return clean(value) if isinstance(value, str) else value


def _shown_index(index: pd.Index) -> pd.Index:
    if isinstance(index, pd.MultiIndex):
        return index.set_levels([_shown_index(level) for level in index.levels]).set_names(
            [_shown(n) for n in index.names]
        )
    texts = pd.api.types.is_object_dtype(index.dtype) or pd.api.types.is_string_dtype(index.dtype)
    return (index.map(_shown) if texts else index).rename(_shown(index.name))


def shown_table(table: Any) -> Any:
    """A copy of a DataFrame (or Series) as a notebook shows it: every text in its cells, column
    names and index labels as the terminal shows it (:func:`~lorisnb.tools.decisions.escape.clean`:
    ``orb\\x1b`` for ``orb`` + ESC, ``\\\\`` for a backslash; one-to-one, so two names stay two);
    numbers untouched. The table given (the one the Python API returns and the CSV holds) keeps its
    names whole. Anything else is returned as it is."""
    if isinstance(table, pd.Series):
        return shown_table(table.to_frame()).iloc[:, 0].rename(_shown(table.name))
    if not isinstance(table, pd.DataFrame):
        return table
    out = table.copy()
    for i in range(table.shape[1]):
        column = table.iloc[:, i]
        if isinstance(column.dtype, pd.CategoricalDtype):
            out.isetitem(i, column.cat.rename_categories(_shown_index(column.cat.categories)))
        elif pd.api.types.is_object_dtype(column.dtype) or pd.api.types.is_string_dtype(column.dtype):
            out.isetitem(i, column.map(_shown))
    out.columns = _shown_index(table.columns)
    out.index = _shown_index(table.index)
    return out


def show_tables_escaped() -> None:
    """In an IPython kernel, every DataFrame and Series shown from now on (a cell's last value,
    ``display(df)``) is shown as :func:`shown_table` makes it, as HTML and as text: a name's control
    character never reaches the notebook, its HTML page or a terminal. The one place notebooks'
    tables are escaped; :func:`setup` calls it (and the threshold explorers, which may run without).
    Outside IPython, nothing changes."""
    try:
        from IPython import get_ipython
    except ImportError:
        return
    shell = get_ipython()
    formatter = getattr(shell, "display_formatter", None)  # none outside IPython, or in a shell without one
    if formatter is None:
        return
    formatters = formatter.formatters

    def as_html(table: pd.DataFrame) -> str | None:
        return shown_table(table)._repr_html_()

    def as_text(table: Any, printer: Any, cycle: bool) -> None:
        printer.text(repr(shown_table(table)))

    formatters["text/html"].for_type(pd.DataFrame, as_html)
    for kind in (pd.DataFrame, pd.Series):
        formatters["text/plain"].for_type(kind, as_text)


def show_inputs(ev: Any, out: Outputs) -> None:
    """What a notebook shows about its inputs: the files that failed or were skipped (written to
    ``input_errors.csv`` for the report, shown only when there are any) and the warnings about
    the inputs, one row per file with the count and the first message (all of them in
    ``ev.warnings``), after the spec's notes on the options (``ev.notes``: ``lifelong`` on a pair),
    which no file carries."""
    from IPython.display import display

    for note in getattr(ev, "notes", []):  # (setup silences LorisWarnings: this is where a notebook says them)
        print(f"note: {note}")
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


def _simulated(values: Mapping[str, Any]) -> bool:
    from lorisnb.tools.notebook.params import simulated_on

    return simulated_on(values)


#: notebook -> (its parameters -> the tables, figures and files it writes on any inputs at those
#: parameters), each checked by :meth:`Outputs.expect` in its first cell (:func:`setup`): a file of the
#: user's under one of these names was refused only when the cell writing it ran, after the first
#: tables and the marker were written. Names that depend on the data (a figure per scene, per
#: estimate) or are written only on some inputs are checked when written. The notebooks' sources are
#: checked against this table by tests/tools/test_s70_report_params.py.
NOTEBOOK_OUTPUTS: dict[str, Callable[[Mapping[str, Any]], dict[str, list[str]]]] = {
    "every_number": lambda v: {"tables": ["every_number"], "figures": ["every_number_ate"]},
    "per_sequence_benchmark": lambda v: {"tables": ["sequences", "scenes"], "figures": ["timeline_per_sequence"]},
    "lifelong_benchmark": lambda v: {"tables": ["sequences", "scenes", "cs_r"], "figures": ["timeline_lifelong"]},
    "evaluate_my_results": lambda v: {"tables": ["sequences", "scenes", "relative"]},
    "evo_crosscheck": lambda v: {"tables": ["crosscheck_tum", "crosscheck_openloris"],
                                 "figures": ["crosscheck_per_pose"]},
    "metrics_primer": lambda v: {"tables": ["real_estimates", "primer_cases"],
                                 "figures": ["primer_timeline", "primer_lifelong"]},
    "threshold_sensitivity": lambda v: {
        "tables": ["cr_vs_eps", "cr_eps_phi", "cr_vs_delta", "output_gaps", "cs_r_vs_tau", "rank_stability",
                   "rank_swaps", "eps_for_cr50", "cr_vs_relative_eps", "explorer_current"],
        "figures": ["cr_vs_eps", "cr_vs_delta", "cs_r_vs_tau", "rank_stability", "cr_vs_relative_eps",
                    "explorer_current"]},
    "compare_algorithms": lambda v: {
        "tables": ["sequences", "coverage", "intervals", "pairwise", "ranking", "robust_first", "robust_region",
                   *(["simulated_sequences", "simulated_trial_summary", "simulated_pairwise", "simulated_ranking"]
                     if _simulated(v) else [])],
        "figures": ["simulated_trials"] if _simulated(v) else [],
        "files": [f"{str(v.get('metric') or 'cr').strip().lower()}_table.{k}" for k in ("tex", "md")]},
    "indoor_vs_outdoor": lambda v: {
        "tables": ["trajectory_stats", "difficulty_per_sequence", "difficulty_computed", "ate_pct_side_by_side"],
        "figures": ["ate_pct_length"]},
}  # fmt: skip


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
    summarized per file by :func:`show_inputs`). With ``sample=True`` (the primer), a notebook given
    neither ``data_root`` nor ``$LORISNB_DATA`` that finds no ``shared/data`` folder runs on the small
    data shipped with lorisnb (:func:`lorisnb.io.datasets.paths.sample_data`) and says so; a
    ``data_root`` or ``$LORISNB_DATA`` that names no data root is refused with
    :func:`~lorisnb.io.datasets.paths.find_data`'s error, never passed over for the sample (the labs
    choose their data with :func:`lorisnb.tools.teaching.lab_data`). ``parameters``: the notebook's parameters,
    checked first with the command line's rules (:func:`lorisnb.tools.notebook.params.check_values`:
    thresholds, grids, seed, yes/no values such as ``quick``, folders that must exist, ...). The
    output folder is then refused if it is, holds or lies in one of the notebook's inputs (its path
    parameters, the data root: :func:`check_output_dir`), before it is made; the notebook writes
    into it only files of its own (:class:`Outputs`)."""
    values = check_notebook_parameters(name, parameters)
    try:
        data = find_data(data_root)
    except DataNotFoundError:
        if not sample or data_root is not None or os.environ.get(ENV_VAR):  # a root the user named: refused, as given
            raise
        data = sample_data()
        print(f"no data_root given, {ENV_VAR} not set and no shared/data folder found: using the small sample data "
              f"shipped with lorisnb (cafe scene only); set {ENV_VAR}=DIR or the data_root parameter for other data")  # fmt: skip
    from lorisnb.tools.notebook.params import refuse_eps_without_scenes, refuse_scenes_without_groundtruth

    refuse_scenes_without_groundtruth(values, data)  # scene, sim_scene, scenes without ground truth (office)
    refuse_eps_without_scenes(values, data, name)  # an eps mapping (eps, eps_grid) missing a scene it scores
    out = Outputs(output_dir if output_dir is not None else default_output_dir(name), notebook=name,
                  inputs=notebook_inputs(values, data), own_folder=output_dir is None)  # fmt: skip
    if name in NOTEBOOK_OUTPUTS:  # every file it will write, checked before the first is written
        out.expect(**NOTEBOOK_OUTPUTS[name](values))
    warnings.filterwarnings("ignore", category=LorisWarning)
    show_tables_escaped()  # every table the notebook shows: its names as the terminal shows them
    shown = out.dir.resolve() if output_dir is None else out.dir  # as given (a report passes ".")
    print(f"data root: {data.root}\noutputs:   {shown}")
    return Session(data, out, name, dict(parameters or {}))
