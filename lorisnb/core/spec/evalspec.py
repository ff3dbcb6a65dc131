"""The evaluation spec: every choice that decides a number, in one frozen, validated value.

One :class:`EvalSpec` describes how an estimate is scored, whatever the input (OpenLORIS result
files, plain pairs, manifests, bags): how poses are matched in time, how the estimate is aligned,
which poses count as repeated, the thresholds of the paper's metrics and the RPE step. It is
built by one function, :func:`make_spec`, from every surface (command-line options, Python
keywords, manifest tables, notebook parameters, widget values), so a value is accepted or refused
with the same message everywhere. The presets (:data:`PRESETS`: ``openloris``, ``tum``, ``rpg``,
``vio``, ``evo``, ``tartanair``, ``kitti``) are values of it.

:meth:`EvalSpec.describe` is the one line the command line prints as ``conventions:``;
:meth:`EvalSpec.canonical` is the exact text written next to every output (the ``spec`` column of
tables), which :meth:`EvalSpec.parse` turns back into the same spec, so every number can be
reproduced from what was written beside it.

Association (``association``):
    ``interpolate`` (OpenLORIS, lorisnb's default): the ground truth interpolated at each estimate
    stamp inside a bracket of ``max_gap`` seconds (:func:`lorisnb.core.alignment.association.associate`).
    ``nearest`` (TUM RGB-D's ``associate.py``, also rpg_trajectory_evaluation's): pairs whose stamps
    differ by less than ``max_diff`` seconds, accepted greedily by increasing difference, each
    stamp used once. ``t_offset`` (seconds) is added to every estimate stamp first. ``index``: pose
    i with pose i, files of the same length (:mod:`lorisnb.core.alignment.index_pairs`; chosen on every
    preset for two KITTI files without times).

Alignment (``align``; ``gt = s R est + t`` fitted on the matched positions):
    ``se3`` (Horn/Umeyama), ``sim3`` (with scale), ``scale`` (the scale only), ``origin`` (the first
    pose onto the first), ``posyaw`` (translation and yaw about gravity), ``none``, ``auto`` (``sim3``
    for monocular algorithms, ``dso`` and ``svo``, as the official tool; else ``se3``).
    ``align_frames=N`` fits on the first N matched poses. ``mode``: ``per-seq`` aligns each sequence
    (session) on itself, ``lifelong`` fits one alignment on the first sequence with matches and
    applies it to all, ``auto`` is lifelong for inputs with several sequences.

The official tool's slips, on request: ``official_interpolation`` (its orientation slips: its
slerp, and with a scale the rotation it extracts) and ``official_lifelong`` (its lifelong
alignment: when the first sequence matches nothing, ``transform_world_frame`` returns before
fitting, so no sequence is aligned; lorisnb fits on the first sequence with matches).
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, fields, replace
from typing import Any

from lorisnb.core.alignment.association import MAX_GAP
from lorisnb.core.spec import evo, validate
from lorisnb.errors import ValidationError

ASSOCIATIONS = ("interpolate", "nearest", "index", *evo.EVO_ASSOCIATIONS)
ALIGNMENTS = ("se3", "sim3", "posyaw", "none", "auto", *evo.EVO_ALIGNMENTS)
#: The alignments OpenVINS ov_eval offers for its metrics (``lorisnb consistency``; its ``*single`` variants aside).
OV_ALIGNMENTS = ("posyaw", "se3", "sim3", "none")
RPE_UNITS = evo.RPE_UNITS
REPEATED = ("drop", "keep")
#: The KITTI metric's arithmetic: the devkit's single precision, or double.
KITTI_PRECISIONS = ("single", "double")
#: Presets that compose KITTI files' matrices as written (:attr:`EvalSpec.as_written`).
AS_WRITTEN = ("kitti", "evo")
#: Presets whose own numbers are computed from the matched poses as read (:attr:`EvalSpec.poses_as_read`).
AS_READ = ("tartanair",)
MODES = ("auto", "per-seq", "lifelong")
#: An alignment without its scale (``scale`` off): what each scaled one becomes; the others stay.
UNSCALED = {"sim3": "se3", "auto": "se3", "scale": "none"}
MAX_DIFF = 0.02  # seconds; TUM's and rpg's default
THRESHOLD_NAMES = ("eps", "phi", "delta", "tau")
#: Input kinds a spec is applied to (see :meth:`EvalSpec.refuse_inapplicable`).
INPUT_KINDS = ("openloris", "pair", "manifest")

Transform = tuple[tuple[float, float, float, float], ...]


@dataclass(frozen=True)
class EvalSpec:
    """How estimates are scored (see the module docstring); every value is validated on
    construction. ``explicit`` holds the names the user set (not part of equality), so options that
    cannot apply to an input are refused rather than ignored."""

    association: str = "interpolate"
    max_gap: float = MAX_GAP
    max_diff: float = MAX_DIFF
    t_offset: float = 0.0
    repeated: str = "drop"
    align: str = "se3"
    align_frames: int | None = None
    mode: str = "auto"
    official_interpolation: bool = False
    official_lifelong: bool = False
    repair_stamps: bool = False
    eps: Any = math.inf
    phi: float = math.inf
    delta: float = 1.0
    tau: float = 60.0
    rpe_delta: float = 1.0
    rpe_unit: str = "s"
    transform: Transform | None = None
    rpe_pairs: str = "reference"
    rpe_all_pairs: bool | None = None
    rpe_tolerance: float = 0.1
    t_start: float | None = None
    t_end: float | None = None
    project_to_plane: str | None = None
    downsample: int | None = None
    motion_filter: tuple[float, float] | None = None
    relation: str | None = None
    change_unit: str | None = None
    kitti_precision: str = "single"
    tartanair_scale: bool = False
    tartanair_seed: int = 0
    preset_name: str = "openloris"
    explicit: frozenset[str] = field(default=frozenset(), compare=False, repr=False)

    def __post_init__(self) -> None:
        for name, value in _checked(vars(self), "python").items():
            object.__setattr__(self, name, value)
        if self.align in ("sim3", "scale") and self.align_frames == 1:
            raise ValidationError(f"align_frames=1 with align={self.align!r}: a scale needs 2 poses")

    # -- the presets ------------------------------------------------------------------------
    @classmethod
    def preset_names(cls) -> tuple[str, ...]:
        return tuple(PRESETS)

    @classmethod
    def preset(cls, name: str, **changes: Any) -> EvalSpec:
        """A named spec (:data:`PRESETS`), with ``changes`` over it (validated as by :func:`make_spec`)."""
        return make_spec(name, **changes)

    @property
    def as_written(self) -> bool:
        """Whether this convention composes KITTI files' pose matrices as written (the devkit's:
        the ``kitti`` preset), not the rotations nearest to their 7-digit blocks."""
        return self.preset_name in AS_WRITTEN

    @property
    def poses_as_read(self) -> bool:
        """Whether this convention's own numbers (the ``tartanair`` preset's ``tartanair_*`` columns)
        are computed from the matched poses as the files wrote them: quaternions not normalized and
        the estimate not aligned (tartanair_tools reads its two files with ``np.loadtxt`` and aligns
        by its own rules), whatever ``align`` does to lorisnb's own columns."""
        return self.preset_name in AS_READ

    # -- what it says ------------------------------------------------------------------------
    def alignment_for(self, algorithm: str) -> str:
        """The alignment used for an algorithm (``auto``: ``sim3`` for monocular ones)."""
        if self.align != "auto":
            return self.align
        from lorisnb.core.pipeline.model import is_monocular

        return "sim3" if is_monocular(algorithm) else "se3"

    def repeated_for(self, fmt: str | None) -> str:
        """The rule for repeated poses reading a file of format ``fmt``: :attr:`repeated`, except
        under the ``kitti`` and ``tartanair`` presets (unless given) for a stamped file, whose poses
        they pair by TUM's nearest rule: the last pose of a repeated stamp, as TUM's ``associate.py``
        keeps it (every pose was kept and paired with the next ground-truth stamp, one more devkit
        frame each, shifting the segments' starts; of a repeated ground-truth stamp the first was
        used). KITTI files, paired by index, keep every row."""
        if self.preset_name in ("kitti", "tartanair") and "repeated" not in self.explicit and fmt != "kitti":
            return "drop"
        return self.repeated

    def lifelong_for(self, sequences: int) -> bool:
        """Whether one alignment serves all sequences of an input with ``sequences`` of them."""
        return self.mode == "lifelong" or (self.mode == "auto" and sequences > 1)

    def describe(self, swept: str | None = None) -> str:
        """One line saying what is used (the command line's ``conventions:``); ``swept``: the
        thresholds a sweep used instead of the spec's (its grid, in words)."""
        if self.association == "interpolate":
            match = f"interpolated ground truth within {self.max_gap:g} s"
            if self.official_interpolation:
                match += " (the official tool's orientation slips)"
        elif self.association in evo.EVO_ASSOCIATIONS:
            match = evo.association_words(self)
        elif self.association == "index":
            match = "by index, pose i with pose i (stamps are pose indices: times in s count poses)"
        else:
            match = f"nearest stamps within {self.max_diff:g} s (greedy, TUM associate.py)"
        frames = "all matched poses" if self.align_frames is None else f"the first {self.align_frames} matched poses"
        offset = f", estimate stamps + {self.t_offset:g} s" if self.t_offset else ""
        align = "sim3 for monocular algorithms (dso, svo), else se3" if self.align == "auto" else self.align
        first = (
            "the first sequence, none if it matches nothing (the official tool's)"
            if self.official_lifelong
            else "the first sequence with matches"
        )
        mode = {
            "auto": f"inputs with several sequences aligned on {first}",
            "per-seq": "each sequence aligned on itself",
            "lifelong": f"one alignment ({first}) for all",
        }[self.mode]
        repeated = "repeated poses dropped" if self.repeated == "drop" else "repeated poses kept"
        if self.repeated_for("tum") != self.repeated:
            repeated += (
                " in KITTI and OpenLORIS files (of an OpenLORIS file's repeated stamp, its last pose), the last of a "
                "repeated stamp in other stamped files (TUM associate.py's)"
            )
        if self.repeated == "keep" and self.preset_name == "openloris":  # the official tool's -k: the estimate's
            repeated += " (an OpenLORIS ground truth's dropped, as the official tool reads it with or without -k)"
        extra = ", stamps repaired" if self.repair_stamps else ""
        transform = ", estimate composed with T_est_gt" if self.transform is not None else ""
        thresholds = (
            swept or f"eps {text(self.eps)}, phi {text(self.phi)} deg, delta {self.delta:g} s, tau {self.tau:g} s"
        ) + f"; RPE over {self.rpe_delta:g} {self.rpe_unit}"
        evo_words = evo.describe_evo(self)
        return (
            f"association: {match}{offset}; alignment: {align} on {frames}{transform}; {mode}; "
            f"{repeated}{extra}; {thresholds}{'; ' + evo_words if evo_words else ''}{self._matrices_words()} "
            f"(preset {self.preset_name})"
        )

    def _matrices_words(self) -> str:
        """How KITTI files' rotation blocks are taken (said wherever it matters), and the KITTI metric's settings."""
        if self.preset_name == "evo":
            return "; KITTI files' matrices composed as written, as evo (other inputs: their quaternions' rotations)"
        if self.preset_name == "tartanair":
            return (
                f"; TartanAir (tartanair_tools): ATE with Horn's rotation{' and its scale' if self.tartanair_scale else ''}, "
                f"RPE over its 10000 random pairs (seed {self.tartanair_seed}), KITTI score over 5..40 m"
                f"{', the estimate scaled by its rule' if self.tartanair_scale else ''}, of the matched poses as read"
                f"{' (the alignment is for lorisnb' + chr(39) + 's own columns)' if self.align != 'none' else ''}"
            )
        if self.preset_name == "kitti":
            return (
                f"; KITTI odometry metric (devkit evaluate_odometry.cpp): segments of 100..800 m every 10 frames, "
                f"{self.kitti_precision} precision{' as the devkit' if self.kitti_precision == 'single' else ''}, "
                "KITTI matrices as written (other inputs: their quaternions' rotations)"
            )
        return ""

    rpe_options = evo.rpe_options  # the RPE settings, as lorisnb.core.lifelong.scoring.score takes them

    def to_dict(self) -> dict[str, Any]:
        """Every value (JSON-friendly: inf as ``"inf"``), for run records."""
        out: dict[str, Any] = {}
        for f in fields(self):
            if f.name == "explicit":
                continue
            out["preset" if f.name == "preset_name" else f.name] = _jsonable(getattr(self, f.name))
        return out

    def canonical(self, thresholds: bool = True) -> str:
        """The exact text of the spec (compact JSON of :meth:`to_dict`); :meth:`parse` gives the
        same spec back. Tables carry it without the thresholds (``thresholds=False``: each row has
        its own ``eps``, ``phi``, ``delta``, ``tau`` columns) in their ``spec`` column."""
        values = self.to_dict()
        if not thresholds:
            values = {k: v for k, v in values.items() if k not in THRESHOLD_NAMES}
        return json.dumps(values, separators=(",", ":"))

    @classmethod
    def parse(cls, text: str) -> EvalSpec:
        """The spec of a :meth:`canonical` text."""
        try:
            values = json.loads(text)
        except (TypeError, ValueError):
            values = None
        if not isinstance(values, dict):
            raise ValidationError(f"spec: expected the text of EvalSpec.canonical(), got {text!r:.80}")
        preset = values.pop("preset", "openloris")
        base = PRESETS.get(preset, PRESETS["openloris"])
        full = replace(make_spec(base, **values), preset_name=preset)
        changed = {f.name for f in fields(full) if f.compare and getattr(full, f.name) != getattr(base, f.name)}
        return replace(full, explicit=frozenset(changed - {"preset_name"}))

    def refuse_inapplicable(self, kind: str, *, surface: str = "python", set_by: tuple[Iterable[str], str] = ((), "")) -> list[str]:  # fmt: skip
        """Refuse options the user set that cannot apply to an input ``kind`` (``openloris``,
        ``pair``, ``manifest``): a ValidationError naming the option and why, and those of them
        ``set_by`` another source (``(options, "the manifest PATH")``). Returns one-line notes for
        options that are harmless there."""
        kind = validate.choice("input kind", kind, INPUT_KINDS)
        given = self.explicit
        name = _namer(surface)
        problems: dict[str, str] = {}  # the option refused: why
        notes: list[str] = []
        if "max_diff" in given and self.association in ("interpolate", "index"):
            problems["max_diff"] = (f"{name('max_diff')}: only for nearest association ({name('association')} nearest); "
                                    f"interpolation uses {name('max_gap')}")  # fmt: skip
        problems.update(evo.evo_refusals(self, given, name))
        if "max_gap" in given and self.association != "interpolate":
            problems["max_gap"] = f"{name('max_gap')}: only for interpolation; nearest association uses {name('max_diff')}"  # fmt: skip
        if "t_offset" in given and self.t_offset and self.association == "index":
            problems["t_offset"] = f"{name('t_offset')}: poses paired by index ({name('association')} index) use no stamps"  # fmt: skip
        if "official_interpolation" in given and self.official_interpolation and self.association != "interpolate":
            problems["official_interpolation"] = f"{name('official_interpolation')}: the official tool's slips are those of interpolation"  # fmt: skip
        if "official_lifelong" in given and self.official_lifelong:
            if kind != "openloris":
                why = f"a {kind} is not an input of the official tool"
            elif self.mode == "per-seq":
                why = "per-seq aligns each sequence on itself"
            elif self.align == "none":
                why = f"{name('align')} none fits nothing"
            else:
                why = ""
            if why:
                problems["official_lifelong"] = (f"{name('official_lifelong')}: the official tool's alignment of a lifelong "
                                                 f"OpenLORIS file (none when its first sequence matches nothing), but {why}")  # fmt: skip
        if "align_frames" in given and self.align == "none":
            problems["align_frames"] = f"{name('align_frames')}: nothing is fitted with {name('align')} none"
        if kind == "openloris" and "transform" in given and self.transform is not None:
            problems["transform"] = (f"{name('transform')}: OpenLORIS result files name their sensor frame in the header "
                                     "(frame: ...); the transform comes from the robot's extrinsics")  # fmt: skip
        for key in ("tartanair_scale", "tartanair_seed"):
            if key in given and self.preset_name != "tartanair":
                problems[key] = f"{name(key)}: only for TartanAir's metrics (--conventions tartanair)"
        if "kitti_precision" in given and self.preset_name != "kitti":
            problems["kitti_precision"] = f"{name('kitti_precision')}: only for the KITTI metric (--conventions kitti)"
        if self.preset_name == "evo" and "delta" in given:  # evo_rpe's --delta is lorisnb's RPE step
            notes.append(
                f"delta {self.delta:g}: lorisnb's validity window of CR-T (seconds), not evo_rpe's --delta; evo's RPE "
                "step is the RPE delta (--rpe-delta with --rpe-unit; rpe_delta= and rpe_unit= in Python)"
            )
        if kind == "pair" and "mode" in given and self.mode != "auto":
            notes.append(f"{name('mode')} {self.mode}: a pair has one sequence, so per-seq and lifelong agree")
        if problems:
            theirs = [k for k in problems if k in set(set_by[0])]
            raise ValidationError("; ".join(problems.values()) + (f" ({', '.join(theirs)}: set by {set_by[1]})" * bool(theirs)))  # fmt: skip
        return notes

    def refuse_scenes(self, scenes: Iterable[str], *, surface: str = "python") -> None:
        """Refuse, before anything is read, an ``eps`` that gives no threshold for one of the input's
        ``scenes`` (a pair's scene, a manifest's): ``'paper'`` (1/3/5 m for the OpenLORIS scenes) or a
        mapping without that scene. Every table of the evaluation would refuse it
        (:func:`lorisnb.core.pipeline.model.scene_eps`), after every file was read."""
        from lorisnb.core.pipeline.model import scene_eps

        if not isinstance(self.eps, (str, Mapping)) or str(self.eps).startswith("relative:"):
            return  # metres, or a fraction of each sequence's extent: a threshold for every scene
        name = _namer(surface)
        shown = {"cli": f"--eps {self.eps}", "manifest": f"eps = {self.eps!r}"}.get(surface, f"eps={self.eps!r}")
        for scene in dict.fromkeys(scenes):
            try:
                scene_eps(self.eps, scene)
            except ValidationError:
                if isinstance(self.eps, str):  # 'paper'
                    raise ValidationError(
                        f"{shown}: the paper's 1/3/5 m are for the OpenLORIS scenes; scene {scene!r} is not one: "
                        f"give {name('eps')} in metres or as 'relative:F' (a fraction of the ground truth's extent)"
                    ) from None
                raise ValidationError(
                    f"{shown} gives no threshold for scene {scene!r}, which the inputs hold: add {scene!r} to the "
                    "mapping, or give one eps for every scene"
                ) from None

    def __repr__(self) -> str:
        changed = [
            f"{f.name}={getattr(self, f.name)!r}"
            for f in fields(self)
            if f.compare and f.name != "preset_name"
            and getattr(self, f.name) != getattr(PRESETS[self.preset_name], f.name)
        ]  # fmt: skip
        return f"EvalSpec.preset({self.preset_name!r}{''.join(', ' + c for c in changed)})"


#: The name lorisnb 0.3 used for the spec (association and alignment only then).
Conventions = EvalSpec


def text(v: Any) -> str:
    """A spec value as the README and ``describe`` show it (``inf``, ``none``, lower-case words)."""
    return "inf" if isinstance(v, float) and math.isinf(v) else ("none" if v is None else str(v).lower())


def _jsonable(v: Any) -> Any:
    if isinstance(v, float) and math.isinf(v):
        return "inf"
    if isinstance(v, dict):
        return {k: _jsonable(x) for k, x in v.items()}
    if isinstance(v, tuple):
        return [_jsonable(x) for x in v]
    return v


def _yes_no(surface: str) -> str:
    """How a surface spells a yes/no value, for messages."""
    return "true or false (TOML booleans, without quotes)" if surface == "manifest" else "True or False"


def _namer(surface: str) -> Any:
    """How an option is spelled on a surface, for messages."""
    if surface == "cli":
        spelled = {"mode": "--per-seq/--lifelong", "repeated": "--keep-repeated", "align": "--align"}
        return lambda n: spelled.get(n, "--" + n.replace("_", "-"))
    if surface == "manifest":
        return lambda n: n
    return lambda n: n


def _checked(values: Mapping[str, Any], surface: str) -> dict[str, Any]:
    """Each given value validated and normalized (the one place every surface goes through)."""
    name = _namer(surface)
    out: dict[str, Any] = {}
    for key, v in values.items():
        label = name(key)
        if key == "association":
            out[key] = validate.choice(label, v, ASSOCIATIONS)
        elif key in ("max_gap", "max_diff"):
            out[key] = validate.positive(label, v, "seconds")
        elif key == "t_offset":
            out[key] = validate.finite(label, v, "seconds")
        elif key == "repeated":
            out[key] = validate.choice(label, v, REPEATED)
        elif key == "align":
            out[key] = validate.choice(label, v, ALIGNMENTS)
        elif key == "align_frames":
            out[key] = None if v is None else int(validate.positive(label, v, validate.ALL_POSES, integer=True))
        elif key == "mode":
            out[key] = validate.choice(label, v, MODES)
        elif key in ("official_interpolation", "official_lifelong", "repair_stamps"):
            out[key] = validate.flag(label, v, _yes_no(surface))
        elif key == "eps":
            out[key] = validate.eps_value(v)
        elif key in ("phi", "delta", "tau"):
            out[key] = validate.threshold(key, v)
        elif key == "tartanair_scale":
            out[key] = validate.flag(label, v, _yes_no(surface))
        elif key == "tartanair_seed":
            seed = validate.finite(label, v, "")
            if seed < 0 or seed != int(seed):
                raise ValidationError(f"{label}={v!r}: expected a whole number >= 0 (the RPE pairs' seed)")
            out[key] = int(seed)
        elif key == "kitti_precision":
            out[key] = validate.choice(label, v, KITTI_PRECISIONS)
        elif key == "transform":
            out[key] = validate.rigid_transform(v, label)
        elif key in evo.EVO_DEFAULTS or key.startswith("rpe_"):  # the RPE step and evo's options
            out[key] = evo.check_evo(key, v, label, _yes_no(surface))
        elif key == "preset_name":
            if not isinstance(v, str) or not v:
                raise ValidationError(f"preset_name={v!r}: expected the name of a preset")
            out[key] = v
        elif key == "explicit":
            out[key] = frozenset(v)
        else:  # pragma: no cover - make_spec refuses unknown names first
            raise ValidationError(f"{label}: not an option of the evaluation spec")
    evo.check_evo_together({**values, **out}, name)
    return out


#: Spellings accepted by :func:`make_spec` besides the field names (the command line's and
#: lorisnb 0.3's): ``scale`` (True/False/'auto'/'on'/'off'), ``lifelong`` (True/False),
#: ``keep_repeated``/``remove_repeated`` (True/False).
ALIASES = ("scale", "lifelong", "keep_repeated", "remove_repeated")


def make_spec(preset: str | EvalSpec | None = None, *, surface: str = "python", **options: Any) -> EvalSpec:
    """The one way to build an :class:`EvalSpec`: a preset (a name of :data:`PRESETS`, a spec, or
    None for ``openloris``) with the options the user gave over it (``None`` is accepted only where
    it means something: ``align_frames``, ``transform``). ``surface`` (``python``, ``cli``, ``manifest``, ``notebook``, ``widget``) only changes
    how options are named in messages."""
    if preset is None:
        base = PRESETS["openloris"]
    elif isinstance(preset, EvalSpec):
        if not options:  # a spec built at the edge is passed down as it is, not validated again
            return preset
        base = preset
    else:
        base = PRESETS[validate.choice("conventions", preset, tuple(PRESETS))]
    name = _namer(surface)
    given = dict(options)  # None is a value like any other: refused where it means nothing
    known = {f.name for f in fields(EvalSpec)} - {"explicit", "preset_name"}
    validate.known_keys(given, sorted(known | set(ALIASES)), "an option of the evaluation spec", name)
    changes = {k: v for k, v in given.items() if k in known}
    if "scale" in given:  # on: sim3; auto: sim3 for monocular algorithms; off: the alignment without its scale
        s = validate.scale_value(given["scale"])
        current = validate.choice(name("align"), changes.get("align", base.align), ALIGNMENTS)
        align = "auto" if s == "auto" else "sim3" if s else UNSCALED.get(current, current)
        if "align" in changes and current != align:
            word = {True: "on", False: "off"}.get(given["scale"]) if surface == "cli" else None  # --scale off
            raise ValidationError(
                f"{name('scale')} {word or given['scale']} and {name('align')} {changes['align']}: give one "
                "(scale on = sim3, auto = sim3 for monocular algorithms, off = the alignment without a scale: "
                "sim3 becomes se3, evo's scale-only none)"
            )
        changes["align"] = align
    if "lifelong" in given:
        mode = "lifelong" if validate.flag(name("lifelong"), given["lifelong"], _yes_no(surface)) else "per-seq"
        if "mode" in changes and validate.choice(name("mode"), changes["mode"], MODES) != mode:
            raise ValidationError(f"{name('lifelong')} and {name('mode')}: give one")
        changes["mode"] = mode
    for word, keep_when in (("keep_repeated", True), ("remove_repeated", False)):
        if word in given:
            rule = "keep" if validate.flag(name(word), given[word], _yes_no(surface)) == keep_when else "drop"
            if "repeated" in changes and changes["repeated"] != rule:
                raise ValidationError(f"{name(word)} and {name('repeated')}: give one")
            changes["repeated"] = rule
    checked = _checked(changes, surface)
    merged = {**{f.name: getattr(base, f.name) for f in fields(EvalSpec)}, **checked}
    if merged["align"] in ("sim3", "scale") and merged["align_frames"] == 1:  # before any file is read
        raise ValidationError(f"{name('align_frames')} 1 with {name('align')} {merged['align']}: a scale needs 2 poses")
    merged["explicit"] = frozenset(base.explicit | set(checked))
    return EvalSpec(**merged)


def preset_over(base: EvalSpec, preset: str | EvalSpec) -> EvalSpec:
    """A preset given over a manifest's spec ``base`` (Python's ``conventions=``, the command
    line's ``--conventions``): its conventions replace the manifest's, whose thresholds, body
    transform and mode stay where the manifest gives them. A spec object is used as it is."""
    if isinstance(preset, EvalSpec):
        return preset
    kept = {k: getattr(base, k) for k in ("eps", "phi", "transform", "mode") if k in base.explicit}
    return make_spec(preset, **kept)


#: The named specs: ``openloris`` (the official tool: interpolation within 0.5 s, SE(3), repeated
#: poses dropped), ``tum`` (``evaluate_ate.py``: nearest within 0.02 s, SE(3), a repeated stamp's
#: last pose), ``rpg`` (rpg_trajectory_evaluation: nearest, Sim(3), every row), ``vio`` (rpg's, ``posyaw``).
PRESETS: dict[str, EvalSpec] = {}
PRESETS["openloris"] = EvalSpec()
PRESETS["tum"] = EvalSpec(association="nearest", align="se3", preset_name="tum")
PRESETS["rpg"] = EvalSpec(association="nearest", align="sim3", repeated="keep", preset_name="rpg")
PRESETS["vio"] = EvalSpec(association="nearest", align="posyaw", repeated="keep", preset_name="vio")
PRESETS["evo"] = EvalSpec(**evo.EVO_PRESET, preset_name="evo")
#: ``kitti``: the KITTI odometry devkit's metric (``kitti_t_err``, ``kitti_r_err`` columns): poses paired
#: one to one (by index for KITTI files without times, else nearest stamps), no alignment, the
#: matrices as written (:mod:`lorisnb.core.metrics.kitti`)
#: ``tartanair``: tartanair_tools' ATE, RPE and KITTI score (``tartanair_*`` columns,
#: :mod:`lorisnb.core.metrics.tartanair`): poses paired one to one, lorisnb's own alignment none
PRESETS["tartanair"] = EvalSpec(association="nearest", align="none", repeated="keep", rpe_unit="frames",
                                preset_name="tartanair")  # fmt: skip
PRESETS["kitti"] = EvalSpec(association="nearest", align="none", repeated="keep", rpe_unit="frames",
                            preset_name="kitti")  # fmt: skip

#: Every name :func:`make_spec` takes (the fields and :data:`ALIASES`): notebook parameters and widget
#: values of these names are checked by it.
SPEC_NAMES = frozenset({f.name for f in fields(EvalSpec)} - {"explicit", "preset_name"} | set(ALIASES))
