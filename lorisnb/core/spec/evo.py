"""The options of the evaluation spec that reproduce evo (``evo_ape`` / ``evo_rpe``, evo 1.38):
their validation, meaning and words (:mod:`lorisnb.core.spec.evalspec` calls these; one place per option).

Associations ``evo-nearest`` / ``evo-interpolate`` (:mod:`lorisnb.core.conventions.evo_sync`), alignments
``scale`` (evo's ``-s`` alone) and ``origin`` (``--align_origin``), the RPE pairs (``rpe_pairs``
along the ``reference`` or the ``estimate``, ``rpe_all_pairs``, ``rpe_tolerance``; units ``frames``
``m`` ``deg`` ``rad`` ``s``: :mod:`lorisnb.core.metrics.pairs`), the time window ``t_start``/``t_end`` (on the
ground truth, as evo), ``project_to_plane`` (``xy``, ``xz``, ``yz``), ``downsample`` (poses) and
``motion_filter`` (metres, degrees).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from lorisnb.core.conventions.evo_options import PLANES
from lorisnb.core.metrics.pairs import RPE_PAIRS
from lorisnb.core.metrics.relations import RELATIONS, UNITS, unit_refusal
from lorisnb.core.spec import validate
from lorisnb.errors import ValidationError

EVO_ASSOCIATIONS = ("evo-nearest", "evo-interpolate")
EVO_ALIGNMENTS = ("scale", "origin")
RPE_UNITS = ("s", "m", "f", "frames", "deg", "rad")
EVO_MAX_DIFF = 0.01  # seconds: evo's --t_max_diff

#: Default of each evo field (lorisnb's own: nothing of evo's applies).
EVO_DEFAULTS: dict[str, Any] = dict(
    rpe_pairs="reference", rpe_all_pairs=None, rpe_tolerance=0.1, t_start=None, t_end=None,
    project_to_plane=None, downsample=None, motion_filter=None, relation=None, change_unit=None,
)  # fmt: skip

#: The ``evo`` preset: evo_ape's and evo_rpe's defaults.
EVO_PRESET: dict[str, Any] = dict(
    association="evo-nearest", max_diff=EVO_MAX_DIFF, repeated="keep", align="none", rpe_delta=1.0,
    rpe_unit="frames", rpe_pairs="estimate", rpe_all_pairs=False,
)  # fmt: skip

#: meaning, unit, inputs it applies to (the README's spec table).
EVO_OPTIONS: dict[str, tuple[str, str, str]] = {
    "rpe_pairs": ("RPE pairs measured along the reference or the (aligned) estimate", "", "rpe_unit m, deg, rad"),
    "rpe_all_pairs": ("RPE: evo's all pairs (true), consecutive pairs (false), lorisnb's own (none)", "", "all"),
    "rpe_tolerance": (
        "evo's --delta_tol: all pairs within delta +- this fraction",
        "",
        "all pairs: rpe_unit m with rpe_all_pairs true, deg, rad",
    ),
    "t_start": ("ground-truth poses before this stamp left out (evo's --t_start)", "s", "all"),
    "t_end": ("ground-truth poses after this stamp left out (evo's --t_end)", "s", "all"),
    "project_to_plane": ("errors of the poses projected to xy / xz / yz (after alignment)", "", "all"),
    "downsample": ("both trajectories reduced to N evenly spaced poses first (evo's --downsample)", "poses", "all"),
    "motion_filter": ("poses kept when moved >= D m or turned >= A deg (evo's --motion_filter)", "m, deg", "all"),
    "relation": ("evo's pose relation (-r) of the ape_* and rpe_* columns it adds", "", "all"),
    "change_unit": ("evo's --change_unit: the relation columns in mm / cm / m / km or deg / rad", "", "relation"),
}


def rpe_options(spec: Any) -> dict[str, Any]:
    """The RPE settings of a spec, as :func:`lorisnb.core.lifelong.scoring.score` takes them."""
    return {k: getattr(spec, k) for k in ("rpe_delta", "rpe_unit", "rpe_pairs", "rpe_all_pairs", "rpe_tolerance")}


def check_evo(key: str, v: Any, label: str, yes_no: str = "True or False") -> Any:
    """One evo option or RPE setting validated and normalized (``label``: how the surface names it;
    ``yes_no``: how it spells a yes/no value)."""
    if key == "rpe_unit":  # evo's letters d and r are its deg and rad
        unit = validate.choice(label, v, (*RPE_UNITS, "d", "r"))
        return {"d": "deg", "r": "rad"}.get(unit, unit)  # the word as checked ('M' is 'm'), never as given
    if key == "rpe_delta":
        return validate.positive(label, v, "steps")
    if key == "rpe_pairs":
        return validate.choice(label, v, RPE_PAIRS)
    if key == "rpe_all_pairs":
        return None if v is None else validate.flag(label, v, yes_no)
    if key == "rpe_tolerance":  # evo's --delta_tol: a fraction of the step, no unit (the command line's words)
        return validate.positive(label, v, "")
    if key in ("t_start", "t_end"):
        return None if v is None else validate.finite(label, v, "seconds")
    if key == "project_to_plane":
        return None if v is None else validate.choice(label, v, PLANES)
    if key == "downsample":
        return None if v is None else int(validate.positive(label, v, "poses", integer=True))
    if key == "relation":
        return None if v is None else validate.choice(label, v, RELATIONS)
    if key == "change_unit":
        return None if v is None else validate.choice(label, v, UNITS)
    if key == "motion_filter":
        if v is None:
            return None
        if isinstance(v, str):
            parts = v.replace(",", " ").split()
        elif isinstance(v, (list, tuple, np.ndarray)):
            parts = list(np.ravel(v)) if isinstance(v, np.ndarray) else list(v)
        else:  # one number, a dict, ...
            parts = [v]
        if len(parts) != 2:
            raise ValidationError(f"{label}: expected two numbers, metres and degrees (e.g. 0.1 5), got {v!r}")
        d, a = (float(validate.finite(label, x, "metres, degrees")) for x in parts)
        if d < 0 or a < 0:
            raise ValidationError(f"{label}: thresholds must be >= 0 (metres, degrees), got {d:g} and {a:g}")
        return (d, a)
    raise ValidationError(f"{label}: not an evo option")  # pragma: no cover


def check_evo_together(values: dict[str, Any], label: Any) -> None:
    """Rules between evo options (``values``: the merged spec's fields)."""
    lo, hi = values.get("t_start"), values.get("t_end")
    if lo is not None and hi is not None and lo > hi:
        raise ValidationError(
            f"{label('t_start')} {lo:.17g} is after {label('t_end')} {hi:.17g}; expected t_start <= t_end"
        )
    unit = values.get("rpe_unit", "s")
    if unit in ("f", "frames") and float(values.get("rpe_delta", 1.0)) % 1:
        raise ValidationError(f"{label('rpe_delta')}: expected a whole number of frames with rpe_unit {unit}")
    delta = float(values.get("rpe_delta", 1.0))
    if unit in ("deg", "rad") and delta > (180.0 if unit == "deg" else math.pi):
        most = "[0, 180] deg" if unit == "deg" else f"[0, pi] rad (pi = {math.pi:.6g})"
        hint = f"; for {delta:g} degrees give {label('rpe_unit')} deg" if unit == "rad" and delta <= 180 else ""
        raise ValidationError(
            f"{label('rpe_delta')} {delta:g} with {label('rpe_unit')} {unit}: expected an angle in {most}{hint}"
        )


def tolerance_used(unit: str, all_pairs: bool | None) -> bool:
    """Whether the RPE pairs depend on ``rpe_tolerance`` (evo's ``--delta_tol``): evo's all pairs in
    metres, degrees or radians (:func:`lorisnb.core.metrics.pairs.rpe_indices`: ``rpe_all_pairs`` true,
    or left as lorisnb's own rule, which takes evo's all pairs for ``deg`` and ``rad``). Frames and
    seconds pair ``(i, i + delta)`` and the pose nearest ``t + delta``: no tolerance."""
    unit = {"f": "frames", "d": "deg", "r": "rad"}.get(unit, unit)
    return unit in ("m", "deg", "rad") and (all_pairs is True or (all_pairs is None and unit in ("deg", "rad")))


def tolerance_refusal(unit: str, all_pairs: bool | None, name: Any = str) -> str | None:
    """Why ``rpe_tolerance`` cannot apply with this RPE unit and rule, or None (:func:`tolerance_used`):
    the one rule of the spec (:func:`evo_refusals`) and of the tables (``score``, ``sweep``)."""
    if tolerance_used(unit, all_pairs):
        return None
    if all_pairs is True:
        return (f"{name('rpe_tolerance')}: only for evo's all pairs in m, deg or rad; all pairs in {unit} are "
                f"every (i, i + delta) and use no tolerance")  # fmt: skip
    return (f"{name('rpe_tolerance')}: only for evo's all pairs ({name('rpe_all_pairs')} with {name('rpe_unit')} m; "
            f"{name('rpe_unit')} deg and rad take them unless {name('rpe_all_pairs')} is false)")  # fmt: skip


def describe_evo(spec: Any) -> str:
    """Words for the evo options set in ``spec`` (empty when none is)."""
    words = []
    if spec.rpe_all_pairs is not None or spec.rpe_pairs != "reference":
        kind = "lorisnb's pairs" if spec.rpe_all_pairs is None else (
            f"evo's all pairs (tolerance {spec.rpe_tolerance:g})" if spec.rpe_all_pairs else "evo's consecutive pairs"
        )  # fmt: skip
        words.append(f"RPE {kind} along the {spec.rpe_pairs}")
    if spec.t_start is not None or spec.t_end is not None:
        start = "its start" if spec.t_start is None else f"{spec.t_start:g} s"
        end = "its end" if spec.t_end is None else f"{spec.t_end:g} s"
        words.append(f"ground truth from {start} to {end}")
    if spec.downsample is not None:
        words.append(f"downsampled to {spec.downsample} poses")
    if spec.motion_filter is not None:
        words.append(f"motion filter {spec.motion_filter[0]:g} m / {spec.motion_filter[1]:g} deg")
    if spec.project_to_plane is not None:
        words.append(f"projected to the {spec.project_to_plane} plane")
    if spec.relation is not None:
        unit = f" in {spec.change_unit}" if spec.change_unit is not None else ""
        words.append(f"pose relation {spec.relation} (ape_*, rpe_* columns{unit})")
    return "; ".join(words)


def association_words(spec: Any) -> str:
    """How the evo associations are described."""
    if spec.association == "evo-nearest":
        return f"evo's nearest stamps within {spec.max_diff:g} s (each pose of the shorter trajectory)"
    return f"evo's interpolation at matched stamps within {spec.max_diff:g} s"


def evo_refusals(spec: Any, given: frozenset[str], name: Any) -> dict[str, str]:
    """Evo options the user set that cannot apply with the rest of ``spec``: option -> why."""
    out = {}
    why = tolerance_refusal(spec.rpe_unit, spec.rpe_all_pairs, name)
    if "rpe_tolerance" in given and why:
        out["rpe_tolerance"] = why
    if "rpe_pairs" in given and spec.rpe_unit in ("s", "f", "frames"):
        out["rpe_pairs"] = (f"{name('rpe_pairs')}: pairs in {spec.rpe_unit} are the same along either trajectory; "
                            f"it applies to {name('rpe_unit')} m, deg or rad")  # fmt: skip
    if "change_unit" in given and spec.change_unit is not None:
        why = unit_refusal(spec.relation, spec.change_unit)
        if spec.relation is None:  # the relation option as the caller's surface spells it (not --relation)
            why = (f"evo's --change_unit changes the unit of the pose relation's columns: give a relation too "
                   f"({name('relation')}: {', '.join(RELATIONS)})")  # fmt: skip
        if why is not None:
            out["change_unit"] = f"{name('change_unit')} {spec.change_unit}: {why}"
    if "align_frames" in given and spec.align == "origin":
        out["align_frames"] = f"{name('align_frames')}: {name('align')} origin uses the first pose only"
    return out
