"""The notebooks' parameters, checked as the command line and the Python API check the same values:
by each notebook (:func:`lorisnb.tools.notebook.start.setup`) and by the report before any notebook runs
(:func:`check_parameters`, which also passes them on normalized: words in their case, thresholds as
numbers, paths absolute, since a notebook runs in its own folder of the run)."""

from __future__ import annotations

import ast
import io
import json
import math
import os
import sys
import tokenize
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from lorisnb.core.spec import validate
from lorisnb.core.spec.evalspec import ALIASES, PRESETS, SPEC_NAMES, EvalSpec, make_spec
from lorisnb.core.spec.exclusive import EXCLUSIVE_INPUTS
from lorisnb.core.stats.inference import WEIGHTS
from lorisnb.core.stats.trials import compile_trials_by
from lorisnb.core.trajectory.frames import SCENES
from lorisnb.core.trajectory.poses import RELATIVE
from lorisnb.errors import DataNotFoundError, ValidationError
from lorisnb.io.datasets.manifest import BUILT_IN
from lorisnb.io.datasets.paths import DataPaths, find_data
from lorisnb.io.readers.plain import TRAJECTORY_FORMATS
from lorisnb.tools.evaluation.inputs import names, result_files
from lorisnb.tools.notebook.grids import check_grid

__all__ = [
    "canonical",
    "check_parameters",
    "check_values",
    "default_eps",
    "eps_values",
    "evaluation_spec",
    "existing",
    "papermill_parameters",
    "refuse_eps_gaps",
    "refuse_eps_without_scenes",
    "refuse_scenes_without_groundtruth",
    "refuse_simulated_off",
    "simulated_on",
    "user_path",
]


#: Path parameters: that must exist (a folder: ``True``), passed on absolute (a built-in manifest
#: by its name).
PATHS = {"results_dir": True, "data_root": True, "ordslam_dir": True, "path": False, "groundtruth": False,
         "manifest": False}  # fmt: skip
#: The grid parameters of the notebooks that sweep (:data:`lorisnb.tools.notebook.grids.GRIDS`): each
#: element is checked by the rule of its one value (:func:`lorisnb.tools.notebook.grids.check_grid`).
GRID_NAMES = ("eps_grid", "phi_grid", "delta_grid", "tau_grid", "relative_grid")
#: The grids of thresholds whose infinity means "no threshold" (a fraction is never infinite).
THRESHOLD_GRIDS = ("eps_grid", "phi_grid", "delta_grid", "tau_grid")
#: Notebook parameters checked with the same rules as the command line and the Python API.
_CHECKS: dict[str, Any] = {
    **{name: (lambda v, name=name: make_spec(None, surface="notebook", **{name: v})) for name in SPEC_NAMES},
    **{g: (lambda v, g=g: check_grid(g, v)) for g in GRID_NAMES},  # errors name the grid and its element
    "trials_by": lambda v: compile_trials_by(str(v)),
    "seed": validate.seed,
    "quick": lambda v: validate.flag("quick", v),
    "simulated": lambda v: validate.flag("simulated", v),
    "algorithms": lambda v: names("algorithms", v),
    "scenes": lambda v: names("scenes", v),
    "all_files": lambda v: validate.flag("all_files", v),
    "eps_fraction": lambda v: validate.fraction("eps_fraction", v),
    "rpe_metres": lambda v: validate.positive("rpe_metres", v, "metres"),
    "ordslam_fps": lambda v: validate.positive("ordslam_fps", v, "frames per second"),
    "ordslam_max_gap": lambda v: validate.positive("ordslam_max_gap", v, "seconds"),
    "sim_eps": lambda v: validate.threshold("eps", v),
    "sim_trials": lambda v: validate.positive("sim_trials", v, "trials", integer=True),
}
#: Parameters that take a list of names (text with a comma in it is one name: refused with the list's form).
NAMES = ("algorithms", "scenes")
#: Parameters that take a list (one name or number stands for a list of one).
LISTS = ("algorithms", "scenes", "eps_grid", "phi_grid", "delta_grid", "tau_grid", "relative_grid")
#: Parameters that only apply together with another one (the notebook ignores them without it).
NEEDS = {"fmt": "groundtruth", "gt_fmt": "groundtruth", "ordslam_fps": "ordslam_dir",
         "ordslam_max_gap": "ordslam_dir"}  # fmt: skip
#: Parameters that exclude each other, with the command line's options for the same inputs and why
#: (``lorisnb evaluate`` refuses ``--gt`` with ``--manifest``): the notebook would use one and ignore
#: the other. Checked by :func:`check_values` for every notebook, so papermill's ``-p``, a parameter
#: cell edited in Jupyter and ``lorisnb report`` are refused alike. Read from the one registry the
#: command line reads too (:data:`lorisnb.core.spec.exclusive.EXCLUSIVE_INPUTS`): add a pair there.
EXCLUSIVE: list[tuple[str, str, str]] = [
    (*e.names, f"{e.options[0]} and {e.options[1]} on the command line; {e.why}") for e in EXCLUSIVE_INPUTS
]
#: Parameters naming one OpenLORIS scene whose ground truth a notebook loads (``metrics_primer``'s
#: ``scene``, ``compare_algorithms``' ``sim_scene``): refused up front when the data root holds no
#: ground truth for it (:func:`refuse_scenes_without_groundtruth`), as a ``scenes`` filter is.
SCENE_PARAMETERS = ("scene", "sim_scene")
#: Parameters of ``compare_algorithms``' simulated section, which runs only when it is on
#: (:func:`simulated_on`): their defaults are not checked against the data otherwise, and a value
#: given for one while it is off is refused (it would be ignored).
SIMULATED = ("sim_scene", "sim_trials", "sim_eps")
#: Parameters of the leaderboard checked and normalized by the validators of ``compare`` and ``diff``.
_VALUES: dict[str, Any] = {
    "metric": lambda v: validate.choice("metric", v, WEIGHTS),
    "alpha": lambda v: validate.probability("alpha", v),
    "level": lambda v: validate.probability("level", v),
    "seed": lambda v: validate.seed(v, "seed"),
    **{
        k: (lambda v, k=k: _plain(validate.eps_value(v) if k == "eps" else validate.threshold(k, v)))
        for k in ("eps", "phi", "delta", "tau")
    },  # '"1"' reaches the notebook as 1.0, "PAPER" as "paper"
    **{k: (lambda v, k=k: validate.choice(k, v, SCENES)) for k in SCENE_PARAMETERS},
    "conventions": lambda v: validate.choice("conventions", v, tuple(PRESETS)),
    "fmt": lambda v: validate.choice("fmt", v, TRAJECTORY_FORMATS),
    "gt_fmt": lambda v: validate.choice("gt_fmt", v, TRAJECTORY_FORMATS),
    "relative_to": lambda v: validate.choice("relative_to", v, RELATIVE),
    **{k: (lambda v, k=k: _absolute(k, v)) for k in PATHS},  # a notebook runs in its own folder of the run
}


def _is_number(text: str) -> bool:
    """Whether ``text`` reads as a number (``"30"``, ``" 1e-3"``, ``"inf"``; not ``"1_0"``, which
    Python's float takes and lorisnb refuses as no number)."""
    if "_" in text:
        return False
    try:
        float(text)
    except ValueError:
        return False
    return True


def _plain(checked: Any) -> Any:
    """A checked threshold as the notebook gets it: a number as a float, anything else normalized as
    the check spells it (``PAPER`` is ``paper``, `` relative:0.05`` is ``relative:0.05``), never as
    given: a notebook compares what it receives with the normalized words."""
    return float(checked) if isinstance(checked, (int, float)) and not isinstance(checked, bool) else checked


def evaluation_spec(values: Mapping[str, Any], **fixed: Any) -> EvalSpec:
    """The one evaluation spec of notebook (and report) parameters: the preset ``conventions``
    (None: lorisnb's own) with every parameter that is an option of the spec
    (:data:`lorisnb.core.spec.evalspec.SPEC_NAMES`: thresholds, ``scale``, ``official_interpolation``, the
    RPE step, ...) given over it, None meaning the spec's default, and ``fixed`` (a notebook's own
    choices, such as ``mode="per-seq"``) last, by :func:`lorisnb.core.spec.evalspec.make_spec`. The
    notebooks (``session.spec()``) and the report's leaderboard build their spec here, so a ``-p``
    reaches both alike."""
    given = {k: v for k, v in values.items() if k in SPEC_NAMES and v is not None}
    return make_spec(values.get("conventions"), surface="notebook", **{**given, **fixed})


def _absolute(name: str, value: Any) -> str:
    """A path parameter checked (:func:`existing`) and made absolute; a built-in manifest's name as given."""
    if name == "manifest" and isinstance(value, str) and value in BUILT_IN:
        return value
    path = existing(name, value, folder=PATHS[name])
    if name == "results_dir" and not result_files([path]):  # as lorisnb report --results refuses it
        raise ValidationError(f"results_dir={value}: no result files in it; expected a folder of <algorithm>/*.txt "
                              "result files (an empty folder gave empty tables and exit status 0)")  # fmt: skip
    return str(path.resolve())


def user_path(value: str | os.PathLike[str]) -> Path:
    """A path parameter as the shell means it: ``~`` (or ``~user``) at its start is that home folder,
    for every path parameter alike (inputs and ``output_dir``), never a folder named ``~``."""
    return Path(os.fspath(value)).expanduser()


def existing(name: str, value: Any, folder: bool = False) -> Path:
    """A path parameter that must exist (a folder where ``folder``): a missing one would leave a
    notebook with nothing to evaluate and empty tables."""
    p = user_path(str(value))
    if not (p.is_dir() if folder else p.exists()):
        what = "folder" if folder else "file or folder"
        found = "a file, not a folder" if p.exists() else f"no such {what}"
        raise ValidationError(f"{name}={value}: {found}; expected an existing {what}")
    return p


#: notebook -> (parameter, the parameter it needs, what to say): a ground truth without the estimate to
#: score against it (``evaluate_my_results`` scored its bundled example, ignoring it), and for
#: ``every_number`` an estimate without its ground truth too; checked by :func:`check_values`, so
#: papermill's ``-p``, a parameter cell edited in Jupyter and ``lorisnb report`` are refused alike.
PAIRED: dict[str, list[tuple[str, str, str]]] = {
    "evaluate_my_results": [("groundtruth", "path", "give both path (the estimate file or folder) and groundtruth "
                                                    "(a pair), or leave groundtruth out")],
    "every_number": [(a, b, "give both path and groundtruth (a pair), or neither (the bundled pair)")
                     for a, b in (("path", "groundtruth"), ("groundtruth", "path"))],
}  # fmt: skip

#: Notebooks whose ``eps`` is one scene's threshold in metres (their prose quotes it so): a relative
#: eps (a fraction of each sequence's size) cannot apply to them.
EPS_IN_METRES = ("metrics_primer",)


#: Parameters a notebook uses as numbers: given as text (papermill's ``-r``), a notebook run directly
#: would format or compare the text (``f"{phi:g}"`` failed in a later cell); the report converts them.
NUMBERS = ("eps", "phi", "delta", "tau", "seed", "alpha", "level", "sim_eps", "sim_trials", "eps_fraction",
           "rpe_metres", "ordslam_fps", "ordslam_max_gap")  # fmt: skip


#: Parameters whose infinity means "no threshold" (:func:`lorisnb.core.spec.validate.threshold`):
#: papermill's ``-p eps 1e400`` reaches the notebook as ``float('inf')``, as ``-p eps inf`` does, so
#: under papermill an infinite one is refused (:func:`refuse_papermill_infinity`), as is an infinite
#: element of a grid (:data:`THRESHOLD_GRIDS`) given as a number.
INFINITE_MEANS_NONE = ("eps", "phi", "delta", "tau", "sim_eps")
#: ``check_parameters``' ``by`` when the report calls it (not a notebook's first cell).
REPORT = "the selected notebooks"


def _as_text(name: str) -> str:
    """How a number reaches a notebook as text under papermill (said where one is refused as text)."""
    return (f"(papermill's -r passes text, and so does -y for a quoted value or one YAML reads as no number: "
            f"-y '{name}: inf', -y '{name}: 1e400')")  # fmt: skip


def _no_threshold(name: str) -> str:
    """What to give for no ``name`` threshold where infinity cannot be told from a number too large."""
    return f"for no threshold, a number beyond any error (papermill -p {name} 1e9) or lorisnb report -p {name} inf"


def check_values(
    values: Mapping[str, Any], notebooks: Iterable[str] = (), text_numbers: bool = True, where: str = "notebook"
) -> None:
    """Check notebook parameter values with the command line's rules (None: the notebook's default),
    and those the ``notebooks`` named cannot take. Every notebook calls it through
    :func:`lorisnb.tools.notebook.start.setup` (``parameters=``), and the report through
    :func:`check_parameters`, before anything runs. ``text_numbers=False`` (the report, which
    converts them): a number written as text (``"30"``) is not refused. ``where``: ``"report"``
    (``lorisnb report``'s check: its advice names the report's options) or ``"notebook"``."""
    for name in NUMBERS if text_numbers else ():
        value = values.get(name)
        if isinstance(value, str) and _is_number(value):
            if math.isinf(float(value)):  # "1e400" (too large) and "inf" alike: papermill -p reads both as inf
                if value.strip().lower().lstrip("+-") not in ("inf", "infinity"):  # too large to be a number: the
                    # command line's message would say "write 'inf'", which a notebook refuses in either spelling
                    raise ValidationError(f"{name}={value!r}: too large to be a number (beyond "
                                          f"+-{sys.float_info.max:.3g} it would be read as infinity), and written as "
                                          f"text {_as_text(name)}; give a number, or, {_no_threshold(name)}")  # fmt: skip
                raise ValidationError(f"{name}={value!r}: the word inf as text {_as_text(name)}, which a notebook cannot "
                                      f"use as a number; as a number (papermill -p {name} inf, -y '{name}: .inf') it "
                                      f"is refused too: papermill reads -p {name} 1e400, too large to be a number, as "
                                      f"it reads inf (and YAML 1.0e400 as .inf); give a number, or, "
                                      f"{_no_threshold(name)}")  # fmt: skip
            raise ValidationError(f"{name}={value!r}: a number written as text {_as_text(name)}; give a "
                                  f"number: papermill -p {name} {value.strip()}, or lorisnb report -p {name} "
                                  f"{value.strip()}")  # fmt: skip
    eps = values.get("eps")
    metres = [n for n in notebooks if n in EPS_IN_METRES]
    if metres and isinstance(eps, str) and str(validate.eps_value(eps)).startswith("relative:"):  # relative:F
        other = ("leave this one out with --notebooks" if where == "report"
                 else "run those with it, and this one with metres")  # fmt: skip
        raise ValidationError(f"eps={eps!r}: {', '.join(metres)} quotes eps in metres of its scene; give metres or "
                              f"paper (a relative eps is for the other notebooks: {other})")  # fmt: skip
    for a, b, why in EXCLUSIVE:
        if values.get(a) is not None and values.get(b) is not None:
            raise ValidationError(f"{a}={values[a]} and {b}={values[b]}: give one ({why})")
    for notebook in notebooks:
        for name, partner, advice in PAIRED.get(notebook, []):
            if values.get(name) is not None and values.get(partner) is None:
                raise ValidationError(f"{notebook}: {name}={values[name]} without {partner}; {advice}")
    for name, value in values.items():
        if value is None:
            continue
        if name in LISTS and isinstance(value, str) and value.lstrip().startswith(("[", "(")):
            raise ValidationError(f"{name}={value!r}: a list written as text (papermill's -p passes text); give a list: "
                                  f"papermill -y '{name}: [a, b]', or lorisnb report -p {name} '[\"a\", \"b\"]'")  # fmt: skip
        if name in NAMES and isinstance(value, str) and "," in value:
            parts = [p.strip() for p in value.split(",")]
            example = ", ".join(p or "a" for p in parts)
            raise ValidationError(f"{name}={value!r}: one name with a comma in it, not a list (text is one name: "
                                  f"papermill's -p and -r pass text); give a list: papermill -y '{name}: [{example}]', "
                                  f"or lorisnb report -p {name} '{json.dumps(parts)}' (a name that holds a comma: in "
                                  "a list of its own)")  # fmt: skip
        if name in _CHECKS:
            _CHECKS[name](value)
        if name in _VALUES:  # checked as the report normalizes them (-p scene Cafe is cafe)
            _VALUES[name](value)


def check_parameters(
    parameters: Mapping[str, Any],
    declared: Mapping[str, Mapping[str, Any]],
    notebooks: Iterable[str] = (),
    by: str = REPORT,
) -> dict[str, Any]:
    """Refuse a parameter no selected notebook declares (listing the declared names) and values
    that the command line would refuse (``-p eps -1``, ``-p alpha 2``) or the selected ``notebooks``
    cannot take (:func:`check_values`), before anything runs.
    Returns the parameters, each in its one form (:func:`canonical`: ``-p metric CR`` is ``cr``,
    ``-p scale on`` and ``-p scale Yes`` are True), as every notebook receives them."""
    unknown = sorted(set(parameters) - set(declared) - {"output_dir"})
    if unknown:
        raise ValidationError(
            f"parameter(s) {', '.join(unknown)} not declared by {by}; "
            f"{'they declare' if by == REPORT else 'it declares'}: " + ", ".join(sorted(declared))
        )
    out = dict(parameters)
    for name, value in parameters.items():  # null reaches the notebook as None, not as its default
        defaults = {str(declared.get(name, {}).get("default"))} - {"None"}
        if value is None and defaults:
            raise ValidationError(f"-p {name} null: the notebooks need a value (default {', '.join(sorted(defaults))}); "
                                  f"leave -p {name} out for the default")  # fmt: skip
    for name, partner in NEEDS.items():  # given, it would be ignored without its partner: refused
        if parameters.get(name) is not None and parameters.get(partner) is None and name in declared:
            raise ValidationError(f"-p {name}: only applies with -p {partner} (the notebook ignores it otherwise)")
    if by != REPORT:  # a notebook's first cell: papermill's -p names
        refuse_papermill_infinity(parameters)
    check_values(parameters, notebooks, text_numbers=False, where="report" if by == REPORT else "notebook")
    refuse_simulated_off(parameters)
    if any(parameters.get(n) is not None for n in SCENE_PARAMETERS):  # a scene without ground truth: refused now
        try:
            data = find_data(parameters.get("data_root"))
        except DataNotFoundError:
            data = None  # no data root: each notebook says so in its first cell
        if data is not None:
            refuse_scenes_without_groundtruth(parameters, data)
    for name, value in parameters.items():
        out[name] = canonical(name, value)
    return out


def _listed(value: Any) -> Any:
    """A checked value as papermill and JSON carry it: tuples as lists, numpy's scalars as Python's."""
    if isinstance(value, (tuple, list)):
        return [_listed(v) for v in value]
    return value.item() if isinstance(value, np.generic) else value


def _spec_option(name: str, value: Any) -> Any:
    """An option of the evaluation spec in its one form: ``scale`` as True, False or ``"auto"``
    (``"on"``, ``"Yes"``, ``true`` and ``1`` are all True), the yes/no spellings as booleans, every
    field of the spec as the spec holds it once checked (``rpe_unit M`` is ``m``, ``rpe_delta 1`` is
    1.0, a transform a list of lists)."""
    if name == "scale":
        return validate.scale_value(value)
    if name in ALIASES:  # lifelong, keep_repeated, remove_repeated: yes/no
        return validate.flag(name, value)
    return _listed(getattr(make_spec(None, surface="notebook", **{name: value}), name))


#: How each checked parameter that is neither a spec option nor in :data:`_VALUES` is written in
#: its one form (see :func:`canonical`).
_CANONICAL: dict[str, Any] = {
    **{g: (lambda v, g=g: [_plain(x) for x in check_grid(g, v)]) for g in GRID_NAMES},
    "trials_by": lambda v: (compile_trials_by(str(v)), str(v))[1],
    "quick": lambda v: validate.flag("quick", v),
    "simulated": lambda v: validate.flag("simulated", v),
    "all_files": lambda v: validate.flag("all_files", v),
    "algorithms": lambda v: names("algorithms", v),
    "scenes": lambda v: names("scenes", v),
    "eps_fraction": lambda v: validate.fraction("eps_fraction", v),
    "rpe_metres": lambda v: validate.positive("rpe_metres", v, "metres"),
    "ordslam_fps": lambda v: validate.positive("ordslam_fps", v, "frames per second"),
    "ordslam_max_gap": lambda v: validate.positive("ordslam_max_gap", v, "seconds"),
    "sim_eps": lambda v: _plain(validate.threshold("eps", v)),
    "sim_trials": lambda v: int(validate.positive("sim_trials", v, "trials", integer=True)),
}  # fmt: skip


def canonical(name: str, value: Any) -> Any:
    """A parameter's value (checked) in its one canonical form, as ``lorisnb report`` passes it to
    every notebook and records it (``parameters.json``, ``run.json``'s spec): two equivalent
    spellings give the same value, so runs made with them compare equal. ``scale`` ``"on"``,
    ``"Yes"``, ``"TRUE"``, ``true`` and ``1`` are all True; words in their case (``PAPER`` is
    ``paper``, ``Cafe`` ``cafe``); numbers as floats where the parameter is a number (1, 1.0 and
    ``"1"`` are 1.0) and as ints where it is a count (``seed``, ``sim_trials``); one name or number
    for a list is a list of one; paths absolute. None (the notebook's default) and a parameter no
    rule knows stay as given."""
    if value is None:
        return None
    if name in _VALUES:
        return _listed(_VALUES[name](value))
    if name in SPEC_NAMES:
        return _spec_option(name, value)
    if name in _CANONICAL:
        return _listed(_CANONICAL[name](value))
    return value


def _in_report() -> bool:
    """Whether this kernel runs a notebook of ``lorisnb report`` (its folder of a run folder), which
    checked and passed on the parameters itself (``-p eps inf`` as infinity)."""
    from lorisnb.tools.notebook.start import RUN_MARKER

    return (Path.cwd().resolve().parent / RUN_MARKER).is_file()


def refuse_papermill_infinity(injected: Mapping[str, Any]) -> None:
    """Refuse an infinite threshold papermill passed, one (:data:`INFINITE_MEANS_NONE`) or an element of
    a grid (:data:`THRESHOLD_GRIDS`) alike: papermill's ``-p eps 1e400`` (too large to be a number, refused by
    the command line and the report) reaches the notebook as ``float('inf')``, as ``-p eps inf`` does,
    and YAML's ``-y 'eps: 1.0e400'`` as ``-y 'eps: .inf'`` does: the notebook cannot tell them apart.
    Infinity written as a word in text stays possible where the parameter takes text: a grid's
    ``-p eps_grid 1,inf`` (or ``-r eps_grid inf``). ``injected``: the names papermill gave, as the
    kernel holds them; not in a report's run (the report refused 1e400 and passes its ``inf`` on as
    infinity)."""
    if _in_report():
        return
    for name in INFINITE_MEANS_NONE:
        value = injected.get(name)
        if isinstance(value, float) and math.isinf(value):
            raise ValidationError(f"{name}=inf: papermill turned the number given with -p {name} into infinity, or "
                                  f"YAML the one given with -y (papermill reads -p {name} 1e400, too large to be a "
                                  f"number, as it reads -p {name} inf, and YAML reads -y '{name}: 1.0e400' as "
                                  f"-y '{name}: .inf'), so it is refused as lorisnb evaluate --{name} 1e400 is; give "
                                  f"a number (at most {sys.float_info.max:.3g}), or, {_no_threshold(name)}")  # fmt: skip
    for grid in THRESHOLD_GRIDS:
        value = injected.get(grid)
        items = value if isinstance(value, (list, tuple)) else [value]
        if any(isinstance(v, float) and math.isinf(v) for v in items):
            given = "an element of the list" if isinstance(value, (list, tuple)) else "the number"
            raise ValidationError(f"{grid}=inf: papermill turned {given} given with -p {grid} or -y into "
                                  f"infinity (it reads 1e400, too large to be a number, as it reads inf, and YAML "
                                  f"1.0e400 as .inf), so it is refused as lorisnb sweep --{grid.removesuffix('_grid')} 1,1e400 "
                                  f"is; give numbers, or, for no threshold, the word inf in the grid's text: papermill "
                                  f"-p {grid} 1,inf (-r {grid} inf for inf alone), or lorisnb report -p {grid} 1,inf")  # fmt: skip


def simulated_on(values: Mapping[str, Any]) -> bool:
    """Whether ``compare_algorithms``' simulated section runs: ``simulated`` as given, else (None, its
    default) only without ``results_dir`` (on the bundled data, not on your own results)."""
    given = values.get("simulated")
    return values.get("results_dir") is None if given is None else validate.flag("simulated", given)


def refuse_simulated_off(values: Mapping[str, Any]) -> None:
    """Refuse a value given for a parameter of the simulated section (:data:`SIMULATED`) while the
    section is off (``results_dir`` given, or ``simulated`` false): the notebook would ignore it. For
    the names given only (``-p``, papermill's injected ones), never for the notebook's defaults."""
    if simulated_on(values):
        return
    for name in SIMULATED:
        if values.get(name) is not None:
            why = "simulated is false" if values.get("simulated") is not None else "results_dir is given"
            raise ValidationError(f"-p {name}: only applies to the simulated section of compare_algorithms, which is "
                                  f"off ({why}); give -p simulated true to run it, or leave -p {name} out")  # fmt: skip


def default_eps(eps: Any, groundtruth: Any = None, manifest: Any = None, fmt: str | None = "tum") -> Any:
    """``evaluate_my_results``' eps: as given (``"paper"`` on a TUM pair is still refused, naming the
    scene); None, its default, is what applies to the inputs: the paper's 1/3/5 m (``"paper"``) for
    OpenLORIS result files (no ``groundtruth`` nor ``manifest``, an OpenLORIS pair, the ``openloris``
    manifest), else None: the spec's, as ``lorisnb evaluate`` takes it (a manifest's eps, else the
    conventions': inf)."""
    if eps is not None:
        return eps
    if manifest is not None:
        from lorisnb.io.datasets.manifest import read_manifest

        return "paper" if read_manifest(manifest).openloris else None
    return "paper" if groundtruth is None or fmt == "openloris" else None


def refuse_scenes_without_groundtruth(values: Mapping[str, Any], data: DataPaths) -> None:
    """Refuse, before any work, a parameter naming a scene the data root ``data`` holds no ground truth
    for (OpenLORIS' office: none is public): one of :data:`SCENE_PARAMETERS` (the notebook would fail
    minutes later loading it), or a ``scenes`` filter of OpenLORIS scenes none of which has any
    (:func:`lorisnb.tools.report.leaderboard.refuse_unscorable_scenes`: nothing would be scored; a
    filter naming anything else is checked against the inputs' scenes later). Called by
    :func:`check_parameters` (``lorisnb report``, papermill's ``-p``) and by each notebook's
    :func:`lorisnb.tools.notebook.start.setup`."""
    from lorisnb.tools.report.leaderboard import refuse_unscorable_scenes

    have = data.scenes_with_groundtruth()
    for name in SCENE_PARAMETERS:
        if values.get(name) is None or (name in SIMULATED and not simulated_on(values)):
            continue  # (a section that does not run loads no scene: its default is not refused)
        scene = validate.choice(name, values[name], SCENES)
        if scene not in have:
            raise ValidationError(
                f"-p {name} {scene}: the data root {data.root} holds no ground truth for {scene} (it has "
                f"{', '.join(have) or 'none'}), so the notebook could not load it; name a scene with ground truth"
            )
    if values.get("scenes") is not None and set(names("scenes", values["scenes"])) <= set(SCENES):
        refuse_unscorable_scenes(values["scenes"], data)


#: notebook -> the folder of the bundled icra20 results it evaluates (OpenLORIS result files) where
#: ``results_dir`` is not given; its scenes are those an eps mapping must give a threshold for.
OPENLORIS_INPUTS = {"per_sequence_benchmark": "per-seq", "compare_algorithms": "per-seq",
                    "lifelong_benchmark": "lifelong", "threshold_sensitivity": "lifelong"}  # fmt: skip
#: ``evaluate_my_results``' bundled example (its ``path`` when none is given), below the icra20 results.
EXAMPLE = ("lifelong", "vins_mono_color_imu_with_loop", "home-1.txt")


def eps_values(values: Mapping[str, Any]) -> list[tuple[str, Any]]:
    """Every ATE threshold of the parameters, each as an error names it and checked: ``eps`` and each
    element of ``eps_grid`` (the same rule for both, :func:`lorisnb.core.spec.validate.eps_value`)."""
    out: list[tuple[str, Any]] = []
    if values.get("eps") is not None:
        out.append(("eps", validate.eps_value(values["eps"])))
    if values.get("eps_grid") is not None:
        out += [("eps_grid", e) for e in check_grid("eps_grid", values["eps_grid"])]
    return out


def input_scenes(source: Any, data: DataPaths, algorithms: Any = None, scenes: Any = None,
                 trials_by: str | None = None) -> list[str]:  # fmt: skip
    """The scenes the OpenLORIS result files of ``source`` are scored on: those their ``scene:``
    headers name, of the files the ``algorithms`` and ``scenes`` filters keep, that ``data`` holds
    ground truth for (a file of another scene is skipped, never scored)."""
    from lorisnb.io.readers.openloris import declared_scene
    from lorisnb.tools.evaluation.inputs import labels

    files = result_files([source])
    if algorithms is not None:
        keep = set(names("algorithms", algorithms))
        files = [(f, root) for f, root in files if labels(f, root, trials_by)[0] in keep]
    found = {s for s in (declared_scene(f) for f, _ in files) if s is not None}
    if scenes is not None:
        found &= set(names("scenes", scenes))
    have = set(data.scenes_with_groundtruth())
    return sorted(found & have, key=lambda s: (SCENES.index(s) if s in SCENES else len(SCENES), s))


def notebook_scenes(notebook: str, values: Mapping[str, Any], data: DataPaths) -> list[str] | None:
    """The OpenLORIS scenes ``notebook`` scores at its eps with these parameters (``values``, the
    notebook's defaults among them where it matters: ``quick``, ``scene``): its results (``results_dir``,
    else the bundled ones, trimmed by ``quick`` as :func:`lorisnb.tools.notebook.grids.quick_inputs`
    trims them) filtered by ``algorithms`` and ``scenes``; ``metrics_primer``'s ``scene``;
    ``evaluate_my_results``' result files (``path``, else its bundled example). None where the scenes
    are not known before the inputs are read (a pair, a manifest: their scenes are checked where they
    are read, :meth:`lorisnb.core.spec.evalspec.EvalSpec.refuse_scenes`)."""
    from lorisnb.tools.notebook.grids import quick_inputs

    if notebook in EPS_IN_METRES:
        scene = values.get("scene")
        return None if scene is None else [validate.choice("scene", scene, SCENES)]
    if notebook == "evaluate_my_results":
        if values.get("groundtruth") is not None or values.get("manifest") is not None:
            return None
        source = user_path(str(values["path"])) if values.get("path") is not None else data.icra20.joinpath(*EXAMPLE)
        return input_scenes(source, data)
    if notebook not in OPENLORIS_INPUTS:
        return None
    results_dir = values.get("results_dir")
    source = user_path(str(results_dir)) if results_dir is not None else data.icra20 / OPENLORIS_INPUTS[notebook]
    scenes, algorithms = quick_inputs(notebook, values.get("quick") or False, results_dir, values.get("scenes"),
                                      values.get("algorithms"))  # fmt: skip
    return input_scenes(source, data, algorithms, scenes, values.get("trials_by"))


def refuse_eps_gaps(thresholds: Iterable[tuple[str, Any]], scenes: Sequence[str], who: str) -> None:
    """Refuse an eps mapping (scene -> metres) among ``thresholds`` (:func:`eps_values`: the one
    eps and each element of a grid alike) that gives no threshold for one of ``scenes``, the scenes
    ``who`` scores: every table at it would refuse it, after every file was read."""
    for label, eps in thresholds:
        if not isinstance(eps, Mapping):
            continue
        missing = [s for s in scenes if s not in eps]
        if missing:
            shown = f"{label}={dict(eps)!r}" + ("" if label == "eps" else " (an element of the grid)")
            raise ValidationError(
                f"{shown} gives no threshold for scene {missing[0]!r}, which {who} scores ({', '.join(scenes)}): "
                f"add {', '.join(map(repr, missing))} to the mapping, or give one eps for every scene"
            )


def refuse_eps_without_scenes(values: Mapping[str, Any], data: DataPaths, notebook: str) -> None:
    """Refuse, before any file is read, an eps mapping, as ``eps`` or as an element of ``eps_grid``,
    that gives no threshold for a scene ``notebook`` scores (:func:`notebook_scenes`): the notebook
    failed minutes later, after its evaluation (a grid's element only in the cell that sweeps it).
    Called by each notebook's :func:`lorisnb.tools.notebook.start.setup` and by ``lorisnb report``
    for each notebook it runs, before any runs."""
    thresholds = [(label, eps) for label, eps in eps_values(values) if isinstance(eps, Mapping)]
    if not thresholds:
        return  # no mapping: nothing read
    scenes = notebook_scenes(notebook, values, data)
    if scenes:
        refuse_eps_gaps(thresholds, scenes, notebook)


#: The first line of the cell papermill injects after a notebook's ``parameters`` cell (Python).
INJECTED_HEADER = "# Parameters"


def _assignments(source: str) -> dict[str, str] | None:
    """name -> its value as written, for a cell of assignments to plain names only; None otherwise."""
    try:
        body = ast.parse(source).body
    except SyntaxError:
        return None
    out = {}
    for node in body:
        if not (isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name)):
            return None
        out[node.targets[0].id] = ast.unparse(node.value)
    return out


def _comments(source: str) -> int:
    try:
        return sum(t.type == tokenize.COMMENT for t in tokenize.generate_tokens(io.StringIO(source).readline))
    except (tokenize.TokenError, SyntaxError):
        return -1


def papermill_parameters(history: Sequence[str]) -> tuple[dict[str, str], list[str]] | None:
    """A notebook's declared parameters (name -> default as written) and the names papermill
    injected (``-p NAME VALUE``), read from a kernel's input history (IPython's ``In``, the cell
    running now last): the cell before it is the ``parameters`` cell (its first line starts with
    ``# Parameters``, only assignments follow), or papermill's injected cell (``# Parameters``, then
    ``name = value`` lines without comments) right after the ``parameters`` cell. None when the
    history shows neither (the setup cell run out of order): nothing can be said about names."""
    if len(history) >= 3 and history[-2].startswith(INJECTED_HEADER + "\n") and _comments(history[-2]) == 1:
        declared, injected = _assignments(history[-3]), _assignments(history[-2])
        if declared is not None and injected is not None and history[-3].lstrip().startswith(INJECTED_HEADER):
            return declared, list(injected)
    if len(history) >= 2 and history[-2].lstrip().startswith(INJECTED_HEADER):
        declared = _assignments(history[-2])
        if declared is not None:
            return declared, []
    return None
