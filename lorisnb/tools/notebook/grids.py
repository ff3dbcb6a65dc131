"""What ``quick`` trims in the notebooks: the threshold grids of the notebooks that sweep
(``threshold_sensitivity``, ``compare_algorithms``), their full and ``quick`` defaults, and
:func:`notebook_grids`, which gives a grid the user set unchanged (checked) and the default only
where the user set none; and the scenes and algorithms of the bundled results (:func:`quick_inputs`),
never of results the user gives. ``quick`` trims the work of the defaults; it never drops or trims
what the user gave."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from lorisnb.core.spec import validate
from lorisnb.errors import ValidationError

#: notebook -> grid parameter -> (full default, quick default). eps in metres, phi in degrees,
#: delta and tau in seconds, relative as fractions of each sequence's ground-truth extent.
GRIDS: dict[str, dict[str, tuple[list[float], list[float]]]] = {
    "threshold_sensitivity": {
        "eps_grid": ([0.1, 0.2, 0.3, 0.5, 0.75, 1, 1.5, 2, 3, 4, 5, 7.5, 10, 15, 20, 30, 50], [0.3, 1, 3, 10, 50]),
        "phi_grid": ([5, 10, 15, 20, 30, 45, 60, 90, 180], [10, 30, 180]),
        "delta_grid": ([0.1, 0.2, 0.5, 1, 2, 5, 10], [0.2, 1, 5]),
        "tau_grid": ([5, 10, 20, 30, 60, 120, 300, 600], [10, 60, 300]),
        "relative_grid": ([0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5], [0.05, 0.2]),
    },
    "compare_algorithms": {
        "eps_grid": ([0.3, 0.5, 1, 2, 3, 5], [0.3, 0.5, 1]),
        "phi_grid": ([10, 20, 30, 60], [10, 20]),
    },
}  # fmt: skip


def check_grid(name: str, values: Any) -> list[Any]:
    """A grid parameter (``eps_grid``, ``phi_grid``, ``delta_grid``, ``tau_grid``, ``relative_grid``)
    checked: a non-empty list (text split at commas), each element by the rule of its one value
    (``eps_grid``'s as the parameter ``eps``, scene mappings and ``paper`` included;
    ``relative_grid``'s as a fraction of the ground truth's size), each once. An error names the
    grid with the element (``eps_grid=-1: ...``), not the one value."""
    if name == "relative_grid":
        return validate.value_list(name, values, lambda v: validate.fraction(name, v))
    return validate.threshold_list(name.removesuffix("_grid"), values, label=name)


def notebook_grids(notebook: str, quick: Any, **given: Any) -> dict[str, list[Any]]:
    """The grids ``notebook`` sweeps: each grid ``given`` (not None) checked and kept as given,
    every other one its default (the ``quick`` one when ``quick``). ``quick`` is a yes/no value
    (:func:`lorisnb.core.spec.validate.flag`). A grid the notebook does not sweep is refused."""
    quick = validate.flag("quick", quick)
    grids: Mapping[str, tuple[list[float], list[float]]] = GRIDS[notebook]
    unknown = sorted(set(given) - set(grids))
    if unknown:
        raise ValidationError(f"{', '.join(unknown)}: not a grid of {notebook}; its grids: {', '.join(grids)}")
    return {
        name: list(default[1] if quick else default[0]) if given.get(name) is None else check_grid(name, given[name])
        for name, default in grids.items()
    }


def quick_default(name: str, value: Any, full: int, trimmed: int, quick: Any) -> int:
    """A count parameter (``sim_trials``): the value given (a positive whole number), kept with
    ``quick`` too; None: ``full``, or ``trimmed`` when ``quick``."""
    if value is None:
        return trimmed if validate.flag("quick", quick) else full
    return int(validate.positive(name, value, "", integer=True))


#: notebook -> (scenes, algorithms) its ``quick`` run keeps of the bundled icra20 results (None:
#: every algorithm).
QUICK_INPUTS: dict[str, tuple[list[str], list[str] | None]] = {
    "per_sequence_benchmark": (["cafe", "home"], ["dso", "orbslam2_rgbd", "vins_mono_color_imu_with_loop"]),
    "lifelong_benchmark": (["home", "cafe"], ["maslam", "vins_mono_color_imu_with_loop"]),
    "threshold_sensitivity": (["cafe", "home"], None),
    "compare_algorithms": (["home", "corridor"], ["orbslam2_rgbd", "vins_mono_color_imu_with_loop", "odom", "dso"]),
}


def quick_inputs(notebook: str, quick: Any, results_dir: Any, scenes: Any, algorithms: Any) -> tuple[Any, Any]:
    """The ``scenes`` and ``algorithms`` a notebook evaluates: as given, except that a ``quick``
    run on the bundled results (``results_dir`` None) keeps a few (:data:`QUICK_INPUTS`) where none
    were given; results the user gives are evaluated whole, quick or not."""
    if not validate.flag("quick", quick) or results_dir is not None:
        return scenes, algorithms
    keep_scenes, keep_algorithms = QUICK_INPUTS[notebook]
    return scenes or keep_scenes, algorithms or keep_algorithms
