"""The notebooks of a report: where they are, in which order they run, whether each can run
(valid JSON, a kernelspec, a cell tagged ``parameters``), the parameters they declare, and one
notebook executed with papermill into its own folder of the run, with its offline HTML page."""

from __future__ import annotations

import ast
import contextlib
import importlib.util
import json
import os
import re
import shutil
import sys
import tempfile
import time
import traceback
import uuid
import warnings
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from lorisnb.errors import LorisError, ValidationError
from lorisnb.tools._extras import EXTRAS, require
from lorisnb.tools.notebook.start import INPUT_ERRORS_CSV
from lorisnb.tools.report import kernels as warm_kernels
from lorisnb.tools.report.html import export_html
from lorisnb.tools.report.portable import manifest_files

#: The notebook pages' shared style sheet in the run folder (written once by the report).
NOTEBOOK_CSS = "notebook.css"

#: Report order: the teaching notebook first, then the paper's figures, then the explorations.
DEFAULT_NOTEBOOKS = (
    "metrics_primer",
    "per_sequence_benchmark",
    "lifelong_benchmark",
    "threshold_sensitivity",
    "compare_algorithms",
    "evo_crosscheck",
    "every_number",
    "indoor_vs_outdoor",
    "evaluate_my_results",
)

#: About how long each shipped notebook runs alone (seconds, 2 cores): a report starts the longest
#: first, so that notebooks running side by side finish close together.
TYPICAL_SECONDS = {
    "evo_crosscheck": 20, "threshold_sensitivity": 20, "compare_algorithms": 10, "per_sequence_benchmark": 8,
    "indoor_vs_outdoor": 7, "evaluate_my_results": 7, "metrics_primer": 6, "lifelong_benchmark": 6,
    "every_number": 5,
}  # fmt: skip

#: Kernel options: its own log is silenced (the loopback-TCP 'without encryption' notice or
#: the 'KeyboardInterrupt caught in kernel' line of a normal shutdown).
KERNEL_ARGS = ["--IPKernelApp.log_level=CRITICAL"]

#: Notebooks that need the bundled data and say nothing about a lab's own results folder: a report
#: on ``results`` leaves them out unless they are named.
BUNDLED_ONLY = ("metrics_primer", "evo_crosscheck", "every_number", "indoor_vs_outdoor", "evaluate_my_results")

#: Optional packages a notebook needs; without them the report skips it and says which extra to install.
NOTEBOOK_NEEDS: dict[str, tuple[str, ...]] = {"evo_crosscheck": ("evo",)}


def notebook_dir(notebooks_dir: str | os.PathLike[str] | None = None) -> Path:
    """The folder of the notebooks: ``notebooks_dir``, else the notebooks shipped with the package
    (``lorisnb.notebooks``)."""
    if notebooks_dir is not None:
        d = Path(notebooks_dir)
        if not d.is_dir():
            raise ValidationError(f"notebooks folder {d} does not exist; pass a folder holding .ipynb files")
        return d
    from importlib import resources

    return Path(str(resources.files("lorisnb.notebooks")))


def notebook_path(name: str, notebooks_dir: str | os.PathLike[str] | None = None) -> Path:
    """A notebook by name (``per_sequence_benchmark``, or ``per_sequence_benchmark.ipynb``: a file name
    of the notebooks' folder, where none of that name is here) or path (``my.ipynb``)."""
    p = Path(name)
    nb_dir = notebook_dir(notebooks_dir)
    if p.suffix != ".ipynb":
        p = nb_dir / f"{name}.ipynb"
    elif not p.is_file() and p.name == name and (nb_dir / name).is_file():  # the folder's file, by its name
        p = nb_dir / name
    if not p.is_file():
        raise LorisError(
            f"notebook {name!r} not found (looked for {p}); the notebooks are: "
            + ", ".join(sorted(q.stem for q in nb_dir.glob("*.ipynb")))
        )
    return p


def available_notebooks(notebooks_dir: str | os.PathLike[str] | None = None) -> list[str]:
    """Every notebook of the folder, in report order: those named like the shipped ones in
    :data:`DEFAULT_NOTEBOOKS` order, then the others alphabetically. A folder without any
    ``.ipynb`` file is an error."""
    d = notebook_dir(notebooks_dir)
    found = {p.stem for p in d.glob("*.ipynb") if not p.name.startswith(".")}
    if not found:
        raise ValidationError(f"--notebooks-dir {d}: no .ipynb file in it; pass a folder holding notebooks")
    return [n for n in DEFAULT_NOTEBOOKS if n in found] + sorted(found - set(DEFAULT_NOTEBOOKS))


def notebook_problem(path: Path) -> str | None:
    """Why the notebook at ``path`` cannot run in a report (not JSON, not a notebook, no
    kernelspec, no cell tagged ``parameters``), or None."""
    try:
        raw = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        return f"{path.name} is not a readable notebook (invalid JSON: {exc})"
    except RecursionError:
        return f"{path.name} is not a readable notebook (invalid JSON: nested too deeply to be read)"
    if not isinstance(raw, dict) or not isinstance(raw.get("cells"), list):
        return f"{path.name} is not a notebook (no list of cells)"
    if not (raw.get("metadata") or {}).get("kernelspec"):
        return f"{path.name} has no kernelspec in its metadata; open it in Jupyter, choose a kernel and save it"
    tagged = any(
        "parameters" in ((c.get("metadata") or {}).get("tags") or []) for c in raw["cells"] if isinstance(c, dict)
    )
    if not tagged:
        return f"{path.name} has no cell tagged 'parameters' (papermill needs one to pass the report's parameters)"
    return None


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
    thresholds: dict[str, str] = field(default_factory=dict)  # eps, phi, delta, tau it ran with, as written


def kernel_environ(environ: Mapping[str, str]) -> dict[str, str]:
    """``environ`` as notebook kernels get it: the Python running lorisnb first on PATH, the Agg
    backend unless one is set, no debugger file check."""
    env = dict(environ)
    # the kernel must be the Python that runs lorisnb (jupyter's 'python3' kernel runs `python`)
    bindir = str(Path(sys.executable).parent)
    if not env.get("PATH", "").startswith(bindir + os.pathsep):
        env["PATH"] = bindir + os.pathsep + env.get("PATH", "")
    env.setdefault("MPLBACKEND", "Agg")
    env.setdefault("PYDEVD_DISABLE_FILE_VALIDATION", "1")
    return env


def kernel_env() -> None:
    """This process's environment set up for notebook kernels (:func:`kernel_environ`), without noise."""
    os.environ.update(kernel_environ(os.environ))
    # papermill's kernel talks over loopback TCP; its 'without encryption' notice is noise here
    warnings.filterwarnings("ignore", message=".*without encryption.*")
    import logging

    logging.getLogger("papermill").setLevel(logging.WARNING)
    logging.getLogger("traitlets").setLevel(logging.ERROR)


#: The folder of this process's kernels' connection files and ipc sockets (:func:`kernel_files`), or None.
_kernel_files: str | None = None


def use_kernel_files(folder: str | None) -> None:
    """Put this process's kernels' connection files and sockets in ``folder`` (a report's workers get
    it from their initializer), or in the temporary folder as Jupyter does (None)."""
    global _kernel_files
    _kernel_files = folder


def current_kernel_files() -> str | None:
    """The folder of this process's kernel files (:func:`use_kernel_files`), or None."""
    return _kernel_files


#: The longest path of an ipc socket (``sun_path`` holds 108 bytes with its NUL on Linux).
SOCKET_PATH_MAX = 107


def _socket_dir() -> str:
    """The temporary folder, or ``/tmp`` where a kernel's ipc socket below it (``lorisnb-k-XXXXXXXX/
    kernel-XXXXXXXX-N``, or ``lorisnb-kernel-`` and 16 hex digits) would be longer than a socket's
    path may be: a deep ``TMPDIR`` (a test runner's, a job scheduler's) made every kernel fail with
    "File name too long"."""
    base = tempfile.gettempdir()
    if (
        os.name == "posix"
        and len(os.path.join(base, warm_kernels.KERNEL_FOLDER_PREFIX + "x" * 8, "kernel-" + "x" * 8 + "-99"))
        > SOCKET_PATH_MAX
    ):
        return "/tmp"
    return base


@contextlib.contextmanager
def kernel_files() -> Iterator[str]:
    """A private folder for a report's kernel connection files (they hold each kernel's key) and
    ipc sockets, used by this process and the workers given it (:func:`use_kernel_files`), and
    removed on leaving: a kernel whose run is interrupted (Ctrl-C, SIGTERM) cannot remove its own."""
    folder = tempfile.mkdtemp(prefix=warm_kernels.KERNEL_FOLDER_PREFIX, dir=_socket_dir())
    previous = _kernel_files
    use_kernel_files(folder)
    try:
        yield folder
    finally:
        use_kernel_files(previous)
        shutil.rmtree(folder, ignore_errors=True)


#: Seconds a wait for a kernel's message looks at its socket again (:func:`waking_client_class`).
MESSAGE_LOOK_SECONDS = 1.0


def waking_client_class() -> Any:
    """Jupyter's asynchronous kernel client whose waits for a message look at the socket again every
    :data:`MESSAGE_LOOK_SECONDS` (a wait of ``timeout`` seconds is cut into such waits, the same
    timeout in all). A message already on the socket was once left unseen until the wait's timeout:
    under load, threshold_sensitivity's widget cell took 240.0 s, the whole ``execution_timeout`` given
    to papermill, in 2 of 7 runs, although the kernel had sent its reply and gone idle within 0.7 s
    (the reply's own time stamp), and was then read as if nothing had happened (jupyter/nbclient#312;
    with ``lorisnb report``'s 1,800 s a notebook stalled half an hour). Uses only the public
    ``*_channel_class`` traits and ``get_msg``."""
    from queue import Empty

    from jupyter_client.asynchronous import AsyncKernelClient
    from jupyter_client.channels import AsyncZMQSocketChannel
    from traitlets import Type

    class WakingChannel(AsyncZMQSocketChannel):
        async def get_msg(self, timeout: float | None = None) -> dict[str, Any]:  # type: ignore[override]
            deadline = None if timeout is None else time.monotonic() + timeout
            while True:
                left = MESSAGE_LOOK_SECONDS if deadline is None else max(0.0, deadline - time.monotonic())
                try:
                    return await super().get_msg(timeout=min(MESSAGE_LOOK_SECONDS, left))
                except Empty:
                    if deadline is not None and time.monotonic() >= deadline:
                        raise

    class WakingKernelClient(AsyncKernelClient):
        shell_channel_class = Type(WakingChannel)
        iopub_channel_class = Type(WakingChannel)
        stdin_channel_class = Type(WakingChannel)
        control_channel_class = Type(WakingChannel)

    return WakingKernelClient


def kernel_manager_class() -> Any:
    """Jupyter's kernel manager with the kernel's sockets on ipc files of a unique name (POSIX):
    kernels started side by side by several processes never race for the same free TCP port (a
    kernel that loses dies "before replying to kernel_info"). During a report, its kernels are
    forked warm (:mod:`lorisnb.tools.report.kernels`). Its clients never leave a message unseen
    past a second (:func:`waking_client_class`)."""
    from jupyter_client.manager import AsyncKernelManager
    from traitlets import default

    class WakingKernelManager(AsyncKernelManager):
        @default("client_factory")
        def _client_factory_default(self) -> Any:
            return waking_client_class()

    if os.name != "posix":
        return WakingKernelManager

    class IpcKernelManager(WakingKernelManager):
        @default("transport")
        def _transport_default(self) -> str:
            return "ipc"

        @default("ip")
        def _ip_default(self) -> str:
            if _kernel_files:  # short: a socket's path has at most 107 bytes
                return os.path.join(_kernel_files, f"kernel-{uuid.uuid4().hex[:8]}")
            return os.path.join(_socket_dir(), f"lorisnb-kernel-{uuid.uuid4().hex[:16]}")

        @default("connection_file")
        def _connection_file_default(self) -> str:  # "": Jupyter's own temporary file
            return os.path.join(_kernel_files, f"kernel-{uuid.uuid4().hex}.json") if _kernel_files else ""

        async def _async_pre_start_kernel(self, **kw: Any) -> Any:
            if self.provisioner is None and warm_kernels.current() is not None:
                self.kernel_id = self.kernel_id or kw.pop("kernel_id", str(uuid.uuid4()))
                self.provisioner = warm_kernels.provisioner_class()(
                    kernel_id=self.kernel_id, kernel_spec=self.kernel_spec, parent=self
                )
            return await super()._async_pre_start_kernel(**kw)

    return IpcKernelManager


def warm_kernels_for_report() -> Any:
    """A context giving the zygote a report's kernels are forked from (see
    :mod:`lorisnb.tools.report.kernels`; None where they cannot be), started with the kernels' own
    command and environment. Without Jupyter's client or a ``python3`` kernel, None: each notebook
    then fails in its own entry, saying why, as without this."""
    try:
        argv = kernel_manager_class()(kernel_name="python3").format_kernel_cmd()
    except Exception:  # noqa: BLE001 - no jupyter_client, no such kernel: the notebooks say so
        return contextlib.nullcontext(None)
    return warm_kernels.zygote(argv, kernel_environ(os.environ))


def declared_parameters(path: Path) -> dict[str, dict[str, Any]]:
    """The parameters a notebook declares in its cell tagged ``parameters`` (name -> papermill's
    description: default, inferred type, help)."""
    pm = require("papermill")
    return dict(pm.inspect_notebook(str(path)))


def shown_default(source: Any) -> str:
    """A parameter's default as papermill reads it (the cell's source text) shown as a value:
    ``float("inf")`` as ``inf``, ``"paper"`` as ``paper``, ``30.0`` as is."""
    text = str(source).strip()
    m = re.fullmatch(r"""float\(\s*(['"])([^'"]*)\1\s*\)""", text)
    if m:
        return m.group(2)
    m = re.fullmatch(r"""(['"])([^'"]*)\1""", text)
    return m.group(2) if m else text


def run_one(
    name: str,
    out_dir: Path,
    parameters: Mapping[str, object],
    timeout: int = 1800,
    notebooks_dir: str | os.PathLike[str] | None = None,
) -> NotebookRun:
    """Execute one notebook with papermill into ``out_dir/<name>/`` and export its offline HTML
    page; never raises for a failing notebook (the error is recorded), except on KeyboardInterrupt.
    Its kernel's connection file and ipc sockets go to the report's folder (:func:`kernel_files`);
    called outside a report, to a private folder of their own, removed when it returns, not loose in
    the temporary folder."""
    pm = require("papermill")
    kernel_env()
    src = notebook_path(name, notebooks_dir)
    stem = src.stem
    nb_dir = out_dir / stem
    nb_dir.mkdir(parents=True, exist_ok=True)
    problem = notebook_problem(src)
    if problem:
        return NotebookRun(stem, status="failed", error=problem)
    declared = declared_parameters(src)
    params = {k: v for k, v in parameters.items() if k in declared}
    if "output_dir" in declared:
        params["output_dir"] = "."  # papermill runs the notebook in its own folder of the run
    run = NotebookRun(stem, parameters=params)
    run.thresholds = {
        k: str(params[k]) if k in params else shown_default(declared[k].get("default"))
        for k in ("eps", "phi", "delta", "tau")
        if k in declared
    }
    missing = [m for m in NOTEBOOK_NEEDS.get(stem, ()) if importlib.util.find_spec(m) is None]
    if missing:
        run.status = "skipped"
        run.error = f"needs {', '.join(missing)}: pip install 'lorisnb[{EXTRAS.get(missing[0], 'all')}]'"
        return run
    t = time.perf_counter()
    target = nb_dir / f"{stem}.ipynb"
    try:
        with kernel_files() if _kernel_files is None else contextlib.nullcontext():
            pm.execute_notebook(
                str(src), str(target), parameters=params, kernel_name="python3", progress_bar=False,
                execution_timeout=timeout, log_output=False, extra_arguments=KERNEL_ARGS,
                resources={"metadata": {"path": str(nb_dir)}},  # the kernel's folder; cwd= would chdir this process
                kernel_manager_class=kernel_manager_class(),
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
        try:
            export_html(target, css=f"../{NOTEBOOK_CSS}" if (out_dir / NOTEBOOK_CSS).is_file() else None)
        except Exception as exc:  # an HTML export failure must not lose the run: say so
            note = f"HTML export failed: {type(exc).__name__}: {exc}"
            run.error = f"{run.error}\n{note}" if run.error else note
    errors_csv = nb_dir / INPUT_ERRORS_CSV
    if errors_csv.exists():
        failed = pd.read_csv(errors_csv)
        run.input_errors = int(failed.get("status", pd.Series(dtype=str)).isin(["failed", "not scored"]).sum())
    return run


def declared_by(names: Iterable[str], notebooks_dir: str | os.PathLike[str] | None) -> dict[str, dict[str, Any]]:
    """The parameters declared by the notebooks that can run (see :func:`notebook_problem`)."""
    declared: dict[str, dict[str, Any]] = {}
    for n in names:
        p = notebook_path(n, notebooks_dir)
        if notebook_problem(p) is None:
            declared.update(declared_parameters(p))
    return declared


def select_notebooks(
    notebooks: Iterable[str] | None, notebooks_dir: Any, results: Any
) -> tuple[list[str], dict[str, str]]:
    """The notebooks to run, and those left out with the reason. A name given with the suffix of the
    notebooks' folder's file (``evaluate_my_results.ipynb``, no such file here) is that notebook's name."""
    if notebooks:
        nb_dir = notebook_dir(notebooks_dir)
        return [
            n.removesuffix(".ipynb")
            if n.endswith(".ipynb") and Path(n).name == n and not Path(n).is_file() and (nb_dir / n).is_file()
            else n
            for n in notebooks
        ], {}
    names = available_notebooks(notebooks_dir)
    if results is None:
        return names, {}
    keep = [n for n in names if n not in BUNDLED_ONLY]
    return keep, {n: "about the bundled data; name it with --notebooks to run it" for n in names if n not in keep}


def input_roots(names: list[str], params: Mapping[str, Any], data: Any, source: Path | None) -> list[Path]:
    """The files and folders the report reads (every file below them, :func:`lorisnb.tools.report.provenance.input_files`): its
    results, the ground truth and extrinsics, and the data the selected notebooks read besides
    (TUM pairs, published tables, folders given as parameters)."""
    roots = [source] if source is not None else []
    roots += [Path(str(params[k])) for k in ("results_dir", "path", "groundtruth", "ordslam_dir") if params.get(k)]
    roots += manifest_files(params.get("manifest"))  # the file and its ground truth
    if data is not None:
        roots += [data.root / "openloris-scene" / "groundtruth", data.root / "openloris-scene" / "extrinsics.json"]
        if source is None or any(n in names for n in BUNDLED_ONLY):
            roots += [data.root / "openloris-scene" / "icra20_results"]
        if any(Path(n).stem in ("evo_crosscheck", "indoor_vs_outdoor") for n in names):
            roots += [data.root / "tum-rgbd", data.root / "published"]
    # each where it is (a link on the way kept: {data}/openloris-scene/... where openloris-scene is a link), once
    return list({r.resolve(): Path(os.path.abspath(r)) for r in roots}.values())


def declared_values(declared: Mapping[str, Mapping[str, Any]]) -> dict[str, Any]:
    """A notebook's declared defaults as values (name -> value) where they are Python literals
    (``"cafe"``, ``False``, ``None``, ``[...]``); None for any other (``float("inf")``)."""
    out: dict[str, Any] = {}
    for name, about in declared.items():
        try:
            out[name] = ast.literal_eval(str(about.get("default")))
        except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
            out[name] = None
    return out


def refuse_eps_scenes(
    names: Iterable[str], notebooks_dir: str | os.PathLike[str] | None, parameters: Mapping[str, Any], data: Any
) -> None:
    """Refuse, before anything runs, an eps mapping (scene -> metres), given as ``eps`` or as an element
    of ``eps_grid``, that gives no threshold for a scene a selected notebook scores, with the notebook's
    own check (:func:`lorisnb.tools.notebook.params.refuse_eps_without_scenes`: its defaults, then the
    parameters it declares): ``-p eps_grid '[{"cafe": 1}]'`` ran ``compare_algorithms``, which failed
    after its evaluation, leaving a run folder and exit status 1."""
    from lorisnb.tools.notebook.params import eps_values, refuse_eps_without_scenes

    if data is None or not any(isinstance(eps, Mapping) for _, eps in eps_values(parameters)):
        return
    for name in names:
        path = notebook_path(name, notebooks_dir)
        if notebook_problem(path) is not None:  # a failed entry of its own (run_one says why)
            continue
        declared = declared_parameters(path)
        values = {**declared_values(declared), **{k: v for k, v in parameters.items() if k in declared}}
        if any(isinstance(eps, Mapping) for _, eps in eps_values(values)):
            refuse_eps_without_scenes(values, data, path.stem)


def refuse_inapplicable_specs(
    names: Iterable[str], notebooks_dir: str | os.PathLike[str] | None, parameters: Mapping[str, Any]
) -> None:
    """Refuse, before the run folder exists, parameters a selected notebook would refuse once it
    runs: each notebook's evaluation spec is built from the parameters it declares as the notebook
    builds it (:func:`lorisnb.tools.notebook.params.evaluation_spec`, its ``session.spec()``) and
    checked against the inputs it scores (:meth:`~lorisnb.core.spec.evalspec.EvalSpec.refuse_inapplicable`:
    a pair with ``groundtruth``, as :func:`~lorisnb.tools.evaluation.runner.pair_kind` of its ``fmt``; the
    sessions of a ``manifest``; else OpenLORIS result files). ``-p conventions tum -p
    official_interpolation true`` ran ``evaluate_my_results``, which then failed, leaving a run
    folder and exit status 1, where the report's own check promises a usage error and nothing run."""
    from lorisnb.core.spec.evalspec import SPEC_NAMES
    from lorisnb.io.datasets.manifest import read_manifest
    from lorisnb.tools.evaluation.inputs import scene_label
    from lorisnb.tools.evaluation.runner import pair_kind
    from lorisnb.tools.notebook.params import evaluation_spec

    for name in names:
        path = notebook_path(name, notebooks_dir)
        if notebook_problem(path) is not None:  # a failed entry of its own (run_one says why)
            continue
        declared = declared_parameters(path)
        values = {k: v for k, v in parameters.items() if k in declared and v is not None}
        if not any(k in SPEC_NAMES or k == "conventions" for k in values):
            continue  # nothing of the spec given to this notebook: its own defaults, which it can take
        scenes: list[str] = []  # the input's scenes, where known before it is read: eps must give each a threshold
        if values.get("groundtruth") is not None:
            fmt = values.get("fmt", shown_default(declared.get("fmt", {}).get("default", "tum")))
            kind, what = pair_kind(str(fmt)), "the pair path, groundtruth"
            if kind == "pair":
                scene = values.get("scene")
                scenes = [str(scene) if scene else scene_label(Path(str(values["groundtruth"])))]
        elif values.get("manifest") is not None:
            m = read_manifest(values["manifest"])
            kind, what = ("openloris" if m.openloris else "manifest"), f"the sessions of manifest {values['manifest']}"
            scenes = [] if m.openloris else m.scenes
        else:
            kind, what = "openloris", "OpenLORIS result files"
        try:
            spec = evaluation_spec(values)
            spec.refuse_inapplicable(kind, surface="notebook")
            spec.refuse_scenes(scenes, surface="notebook")
        except ValidationError as exc:
            raise ValidationError(f"{path.stem} (scoring {what}) would refuse its parameters: {exc}; change or "
                                  f"leave out the parameter named, or leave {path.stem} out with --notebooks") from None  # fmt: skip
