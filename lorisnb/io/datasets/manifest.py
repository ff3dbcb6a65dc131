"""Multi-session datasets described by a small TOML manifest: sessions in order, each with its
ground-truth file and format, a shared map frame or not, scene names, thresholds, conventions and
the transform between estimate and ground truth. A manifest is read by :func:`read_manifest`;
built-in ones (``lorisnb.io.datasets.manifest.BUILT_IN``) ship with lorisnb: ``openloris`` (the default
OpenLORIS evaluation), ``euroc-vicon-room1``, ``euroc-vicon-room2`` and ``tum-fr1-office``.

Example (every key but ``[[session]]`` optional)::

    name = "EuRoC Vicon room 1"
    scene = "vicon-room-1"          # the scene of every session (a session may set its own)
    root = "${EUROC_ROOT}"          # where ground-truth paths start (default: the manifest's folder)
    lifelong = true                 # one map frame: align on the first session, apply to all
    groundtruth_format = "euroc"    # tum, euroc, kitti, bag, openloris
    estimate_format = "tum"
    eps = 0.3                       # default thresholds, metres / degrees
    phi = 10.0

    [conventions]                   # see lorisnb.core.conventions.choices
    association = "nearest"
    max_diff = 0.02
    align = "se3"

    [transform]                     # T_est_gt: the ground-truth body's pose in the estimate's body frame
    translation = [0.0, 0.0, 0.0]
    quaternion = [0.0, 0.0, 0.0, 1.0]   # x y z w

    [[session]]
    name = "V1_01_easy"
    groundtruth = "V1_01_easy/mav0/state_groundtruth_estimate0/data.csv"
    # estimate = "V1_01_easy.txt"   # default: the session name with the estimate format's suffix
    # groundtruth_format = "euroc"  # default: the manifest's groundtruth_format
    # estimate_times = "00/times.txt"     # KITTI estimates' stamps, one per pose (--est-times)
    # groundtruth_times = "00/times.txt"  # a KITTI ground truth's (--gt-times); both inside the root
"""

from __future__ import annotations

import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from lorisnb.core.alignment.geometry import Sim3
from lorisnb.core.spec import validate
from lorisnb.core.spec.evalspec import PRESETS, EvalSpec, make_spec
from lorisnb.errors import ParseError, ValidationError
from lorisnb.io.readers.options import check_reading
from lorisnb.io.readers.plain import TRAJECTORY_FORMATS
from lorisnb.io.readers.registry import suffixes

BUILT_IN = ("openloris", "euroc-vicon-room1", "euroc-vicon-room2", "tum-fr1-office")
#: The environment variables naming a dataset's folder that lorisnb knows (its built-in manifests'
#: ``root``, its data root): a manifest's ``root`` may lie anywhere inside the folder one names.
DATASET_VARIABLES = ("EUROC_ROOT", "TUM_ROOT", "LORISNB_DATA")
#: The environment variable listing more of them, the user's own (``KITTI_ROOT MYLAB_ROOT``).
ALLOW_VARIABLES = "LORISNB_DATASET_VARIABLES"
SUFFIX = {name: suffixes(name)[0] for name in TRAJECTORY_FORMATS}  # an estimate file's default suffix
TOP_KEYS = {"name", "scene", "root", "lifelong", "groundtruth_format", "estimate_format", "eps", "phi", "source",
            "conventions", "transform", "session", "groundtruth_topic", "estimate_topic", "groundtruth_tf",
            "estimate_tf", "openloris"}  # fmt: skip
SESSION_KEYS = {"name", "seq", "scene", "groundtruth", "estimate", "groundtruth_format", "estimate_times",
                "groundtruth_times"}  # fmt: skip
#: A session's times files (KITTI's times.txt, one stamp per pose) by the reading option they are
#: (:data:`lorisnb.io.readers.options.NEEDS`: the command line's --est-times / --gt-times).
TIMES_KEYS = {"est_times": "estimate_times", "gt_times": "groundtruth_times"}
TRANSFORM_KEYS = {"translation", "quaternion"}
READING_KEYS = {
    "topic": "estimate_topic",
    "tf": "estimate_tf",
    "gt_topic": "groundtruth_topic",
    "gt_tf": "groundtruth_tf",
}


@dataclass(frozen=True)
class Session:
    """One session: its number (order), name, scene, ground-truth file and its format, and the
    estimate file's name."""

    seq: int
    name: str
    scene: str
    groundtruth: Path
    estimate: str
    groundtruth_format: str = "tum"
    estimate_times: Path | None = None  # KITTI estimates' times file (the command line's --est-times)
    groundtruth_times: Path | None = None  # a KITTI ground truth's times file (--gt-times)


@dataclass(frozen=True)
class Manifest:
    """A dataset's sessions and how to evaluate them (see the module docstring)."""

    path: Path
    name: str
    sessions: list[Session]
    lifelong: bool = False
    groundtruth_format: str = "tum"
    estimate_format: str = "tum"
    spec: EvalSpec = field(default_factory=EvalSpec)  # [conventions], lifelong, transform, eps, phi
    transform: Sim3 | None = None
    eps: float | None = None
    phi: float | None = None
    groundtruth_topic: str | None = None
    estimate_topic: str | None = None
    groundtruth_tf: str | None = None
    estimate_tf: str | None = None
    source: str = ""
    openloris: bool = False  # the built-in OpenLORIS evaluation (lorisnb.evaluate's own path)
    outside: bool = False  # read with --manifest-outside: files (links) elsewhere are read too

    @property
    def conventions(self) -> EvalSpec:
        """The manifest's spec (its older name)."""
        return self.spec

    @property
    def scenes(self) -> list[str]:
        return list(dict.fromkeys(s.scene for s in self.sessions))

    def __repr__(self) -> str:
        if self.openloris:
            return f"<Manifest {self.name!r}: the built-in OpenLORIS evaluation>"
        n, k = len(self.sessions), len(self.scenes)
        return (
            f"<Manifest {self.name!r}: {n} session{'' if n == 1 else 's'} ({k} scene{'' if k == 1 else 's'}), "
            f"{'lifelong' if self.lifelong else 'per session'}, {self.groundtruth_format} ground truth, "
            f"{self.estimate_format} estimates>"
        )


def groundtruth_refusal(session: Session) -> str | None:
    """Why a session's ground truth cannot be read, or None: ``not found``, or a folder that is no
    trajectory (a folder is one only as a ROS 2 bag, holding ``metadata.yaml``, read with
    ``groundtruth_format = "bag"``, as ``--gt`` and a manifest's estimates take it)."""
    gt = session.groundtruth
    if not gt.exists():
        return "not found; expected a trajectory file"
    if not gt.is_dir():
        return None
    if session.groundtruth_format == "bag":
        if (gt / "metadata.yaml").is_file():
            return None
        return "is a folder without metadata.yaml, not a ROS 2 bag; expected a bag file or a ROS 2 bag's folder"
    return (f"is a folder; expected a trajectory file (a folder is a ground truth only as a ROS 2 bag, "
            f"groundtruth_format = 'bag'; this one is {session.groundtruth_format})")  # fmt: skip


def manifest_path(name_or_path: str | os.PathLike[str]) -> Path:
    """A built-in manifest's file (by name) or the given path."""
    if isinstance(name_or_path, str) and name_or_path in BUILT_IN:
        from importlib import resources  # here: 10 ms of every command's start otherwise

        return Path(str(resources.files("lorisnb.manifests").joinpath(f"{name_or_path}.toml")))
    if not isinstance(name_or_path, (str, os.PathLike)) or not str(name_or_path).strip():
        raise ValidationError(f"manifest={name_or_path!r}: expected a TOML file's path or one of {', '.join(BUILT_IN)}")
    return Path(name_or_path)


def _fmt(value: Any, key: str, path: Path, line: int | None = None) -> str:
    """A format name, in any case as ``--format``, ``evaluate_pairs(..., fmt)`` and ``read_trajectory``
    take it (:func:`lorisnb.core.spec.validate.choice`: ``"TUM"`` is ``tum``)."""
    try:
        return validate.choice(key, value, TRAJECTORY_FORMATS)
    except ValidationError:
        raise ParseError(path, line, f"{key} = {value!r}: expected one of {', '.join(TRAJECTORY_FORMATS)}") from None


#: What a manifest of the built-in OpenLORIS evaluation may hold: its scenes, ground truth, frames
#: and formats come from the data root and the result files' headers.
OPENLORIS_KEYS = {"name", "source", "openloris", "eps", "phi", "lifelong", "conventions"}


def openloris_preset_refusal(name: str, preset: object) -> str:
    """Why a preset is refused with the built-in OpenLORIS evaluation (a manifest with ``openloris =
    true``, ``--manifest openloris``, ``evaluate_manifest("openloris", ...)``): one message on every
    path, ``name`` being how the path spells the option (``--conventions``, ``conventions``,
    ``[conventions] preset``), and the route that does score OpenLORIS files under a preset."""
    shown = preset if isinstance(preset, str) else "PRESET"
    given = f"{name} {preset}" if isinstance(preset, str) else f"{name} (a {type(preset).__name__})"
    return (
        f"{given}: the built-in OpenLORIS evaluation (openloris = true) is the official conventions with "
        "single options over them (max_gap, scale, lifelong, ...), not a preset; to score OpenLORIS result files "
        f"under the {shown} preset, evaluate them without the manifest (lorisnb evaluate FILES --conventions "
        f"{shown}; lorisnb.evaluate(files, {shown!r}) in Python)"
    )


def _openloris_manifest(raw: dict, path: Path) -> Manifest:
    """A manifest with ``openloris = true``: its thresholds, mode and ``[conventions]`` make its
    spec (as the command line's options would: no preset, nothing OpenLORIS files cannot take);
    any other key is refused."""
    other = sorted(set(raw) - OPENLORIS_KEYS)
    if other:
        raise ParseError(path, None, f"{', '.join(other)}: cannot apply with openloris = true (the built-in OpenLORIS "
                         "evaluation takes the scenes, ground truth, frames and formats from the data root and the "
                         f"result files); expected only {', '.join(sorted(OPENLORIS_KEYS))}")  # fmt: skip
    table = raw.get("conventions", {})
    if not isinstance(table, dict):
        raise ParseError(path, None, "conventions: expected a [conventions] table of spec options")
    if "preset" in table:
        raise ParseError(path, None, openloris_preset_refusal("[conventions] preset", table["preset"]))
    options = dict(table)
    for key in ("eps", "phi", "lifelong"):
        if key in raw and key in options:
            raise ParseError(path, None, f"{key} is given at the top and in [conventions]; give it once")
        if key in raw:
            options[key] = raw[key]
    try:
        spec = make_spec(None, surface="manifest", **options)
        spec.refuse_inapplicable("openloris", surface="manifest")
    except ValidationError as exc:
        raise ParseError(path, None, str(exc)) from None
    return Manifest(path=path, name=str(raw.get("name", "OpenLORIS-Scene")), sessions=[], openloris=True, spec=spec,
                    lifelong=spec.mode == "lifelong", source=str(raw.get("source", "")),
                    groundtruth_format="openloris", estimate_format="openloris",
                    eps=spec.eps if "eps" in spec.explicit else None, phi=spec.phi if "phi" in spec.explicit else None)  # fmt: skip


def read_manifest(name_or_path: str | os.PathLike[str], outside: bool = False) -> Manifest:
    """Read and check a manifest (a built-in name or a TOML file). ParseError names the file, the
    key and what was expected; environment variables in ``root`` (``${EUROC_ROOT}``) are expanded
    and an unset one is named. A ground-truth file must lie inside the manifest's folder, its
    ``root`` or lorisnb's data root, and a ``root`` written in the manifest (not taken from an
    environment variable) inside the manifest's folder or the data root (links resolved:
    ``groundtruth = "../../etc/passwd"`` is refused before anything is read), unless ``outside``
    (``--manifest-outside``), which the manifest keeps: an error about an estimate linked from
    outside the results folder then quotes its content too
    (:func:`lorisnb.tools.evaluation.inputs.outside_results`)."""
    path = manifest_path(name_or_path)
    try:
        text = path.read_text(encoding="utf-8")
        raw = tomllib.loads(text)
    except FileNotFoundError:
        given = Path(str(name_or_path)).name.removesuffix(".toml")
        same = [b for b in BUILT_IN if b == given.lower().replace("_", "-")]  # a built-in's file name, or its case
        hint = f"did you mean {same[0]!r}?" if same else validate.near_miss(given, BUILT_IN)
        raise ParseError(path, None, f"manifest not found{f' ({hint})' if hint else ''}; expected a TOML file or one "
                         f"of {', '.join(BUILT_IN)}") from None  # fmt: skip
    except (OSError, UnicodeDecodeError) as exc:
        raise ParseError(path, None, f"cannot be read ({exc})") from None
    except tomllib.TOMLDecodeError as exc:
        raise ParseError(path, getattr(exc, "lineno", None), f"not valid TOML ({exc})") from None
    check_keys(raw, TOP_KEYS, path, line=lambda k: _line(text, None, k))
    for key in ("name", "scene", "root", "source", *READING_KEYS.values()):  # text, never str() of a list or a number
        _text(raw, key, path, line=_line(text, None, key))
    if "openloris" in raw and not isinstance(raw["openloris"], bool):  # "false" is not truth-tested
        raise ParseError(path, None, f"openloris = {raw['openloris']!r}: expected true or false")
    if raw.get("openloris"):
        return _openloris_manifest(raw, path)
    root_text = str(raw.get("root", "."))
    expanded = _expand(root_text)
    if "$" in expanded:
        raise ParseError(
            path, None, f"root = {root_text!r}: environment variable not set; set it to the dataset's folder"
        )
    from lorisnb.io.datasets.paths import named_entry

    root = named_entry(path.parent, Path(expanded).expanduser()).resolve()  # a name in another Unicode form too
    trusted = [path.parent.resolve(), *_data_root()]  # the manifest's folder and lorisnb's data root
    if not outside:  # a folder a dataset's variable names is the user's own: the root may lie inside it
        yours = [_folder(os.environ[v]).resolve() for v in _variables(root_text)]
        others = [v for v in _variables(root_text, known=False) if v not in _variables(root_text)]
        allow = (f" ({', '.join(others)} is not a dataset folder's variable lorisnb knows: {', '.join(DATASET_VARIABLES)}"
                 f"; if it names your dataset's folder, allow it: {ALLOW_VARIABLES}={others[0]})") if others else ""  # fmt: skip
        _confined(root, [*trusted, *yours], path, f"root = {root_text!r}{allow}",
                  "the manifest's folder" + ", the dataset folders its environment variables name" * bool(yours))  # fmt: skip
    allowed = [root, *trusted]
    gt_fmt = _fmt(
        raw.get("groundtruth_format", "tum"), "groundtruth_format", path, _line(text, None, "groundtruth_format")
    )
    est_fmt = _fmt(raw.get("estimate_format", "tum"), "estimate_format", path, _line(text, None, "estimate_format"))
    scene = str(raw.get("scene", path.stem))
    items = raw.get("session")
    if not isinstance(items, list) or not items:
        one = " ([session] is one table: write [[session]], two brackets, before each session)"
        raise ParseError(path, None, f"no [[session]] table{one if isinstance(items, dict) else ''}; expected one per "
                         "session, in order")  # fmt: skip
    sessions: list[Session] = []
    for k, item in enumerate(items, start=1):
        if not isinstance(item, dict) or "groundtruth" not in item:
            raise ParseError(path, None, f"session {k}: expected a table with at least 'groundtruth = \"file\"'")
        check_keys(item, SESSION_KEYS, path, f"[[session]] {k}: ", lambda key, k=k: _line(text, "session", key, k))
        for key in ("name", "scene", "groundtruth", "estimate", *TIMES_KEYS.values()):
            _text(item, key, path, f"[[session]] {k}: ", _line(text, "session", key, k))
            if key in item and not item[key].strip():  # "" would name the root folder, or a file ".txt"
                raise ParseError(path, None, f"[[session]] {k}: {key} = {item[key]!r}: expected a non-empty name")
        name = str(item.get("name", f"session{k}"))
        if not outside:  # as written, before any folder on the way is listed; then the file found
            _confined(root / str(item["groundtruth"]), allowed, path, f"[[session]] {k}: groundtruth")
        groundtruth = named_entry(root, str(item["groundtruth"]))  # as estimates are found: NFC or NFD on disk
        if not outside:
            _confined(groundtruth, allowed, path, f"[[session]] {k}: groundtruth")
        times: dict[str, Path | None] = {}
        for key in TIMES_KEYS.values():  # a times file: found and confined as the ground truth is
            if key not in item:
                times[key] = None
                continue
            if not outside:
                _confined(root / str(item[key]), allowed, path, f"[[session]] {k}: {key}")
            times[key] = found = named_entry(root, str(item[key]))
            if not outside:
                _confined(found, allowed, path, f"[[session]] {k}: {key}")
        seq = item.get("seq", k)
        if "seq" in item:  # the rule of every surface (--seq, seq=): a positive whole number
            try:
                if not isinstance(seq, int):  # 2.0 or "2" in TOML is not the whole number 2
                    raise ValidationError(f"seq={_toml(seq)}: expected a positive whole number (sequences are "
                                          "numbered from 1)")  # fmt: skip
                seq = validate.seq_number("seq", seq)
            except ValidationError as exc:
                why = str(exc).split(": ", 1)[-1]
                raise ParseError(path, _line(text, "session", "seq", k), f"[[session]] {k} ({name!r}): seq = "
                                 f"{_toml(item['seq'])}: {why}") from None  # fmt: skip
        sessions.append(
            Session(
                seq=seq,
                name=name,
                scene=str(item.get("scene", scene)),
                groundtruth=groundtruth,
                estimate=estimate_name(str(item.get("estimate", name + SUFFIX[est_fmt]))),
                groundtruth_format=_fmt(
                    item.get("groundtruth_format", gt_fmt),
                    f"[[session]] {k} ({name!r}): groundtruth_format",
                    path,
                    _line(text, "session", "groundtruth_format", k) if "groundtruth_format" in item else None,
                ),
                estimate_times=times["estimate_times"],
                groundtruth_times=times["groundtruth_times"],
            )  # fmt: skip
        )
        try:  # the command line's rule (--est-times, --gt-times): times files only for KITTI files
            check_reading({o: item.get(key) for o, key in TIMES_KEYS.items()}, est_fmt,
                          sessions[-1].groundtruth_format, name=lambda o: TIMES_KEYS[o])  # fmt: skip
        except ValidationError as exc:
            first = str(exc).split(":", 1)[0]
            raise ParseError(path, _line(text, "session", first, k), f"[[session]] {k} ({name!r}): {exc}") from None
    _refuse_repeated_seq(sessions, items, path, text)
    check_repeats(
        sessions, path, text, [str(i.get("estimate", s.estimate)) for i, s in zip(items, sessions, strict=True)]
    )
    table = raw.get("conventions", {})
    if not isinstance(table, dict):
        raise ParseError(path, None, "conventions: expected a [conventions] table of spec options")
    transform = _transform(raw.get("transform"), path, text)
    reading = {k: raw.get(key) for k, key in READING_KEYS.items()}
    try:  # the command line's rule: topics and TF chains only for bags, a topic or a chain, not both
        for gt_format in dict.fromkeys(s.groundtruth_format for s in sessions):
            check_reading(reading, est_fmt, gt_format, name=lambda k: READING_KEYS[k])
    except ValidationError as exc:  # the line of the key it names (estimate_topic = ... with TUM estimates)
        raise ParseError(path, _named_line(str(exc), list(READING_KEYS.values()), {}, text), str(exc)) from None
    for key in ("estimate_topic", "groundtruth_topic"):  # the command line's --topic A,B is a row per topic
        value = raw.get(key)
        if isinstance(value, str) and "," in value:
            raise ParseError(path, _named_line(key, [key], {}, text),
                             f"{key} = {value!r}: a manifest reads one topic per session; expected one topic "
                             f"(e.g. {key} = {value.split(',')[0].strip()!r}): one manifest per topic, or evaluate "
                             "the bags against their ground truth with --topic A,B (a row per topic)")  # fmt: skip
    options = {k: v for k, v in table.items() if k != "preset"}
    elsewhere = {"transform": "the [transform] table", "surface": None}
    for key in sorted(set(options) & set(elsewhere)):
        where = elsewhere[key]
        raise ParseError(path, None, f"[conventions]: {key} " + (f"is given in {where}" if where else
                         "is not an option of the evaluation spec") + "; expected spec options (align, association, ...)")  # fmt: skip
    for key in ("eps", "phi", "lifelong"):  # top-level keys; in [conventions] too, but not in both
        if key in raw and key in options:
            raise ParseError(path, _line(text, "conventions", key), f"{key} is given at the top and in [conventions]; "
                             "give it once")  # fmt: skip

        if key in raw:
            options[key] = raw[key]
    if "lifelong" not in options and "mode" not in options:  # per session unless the manifest says otherwise
        options["lifelong"] = False
    try:  # the preset named by its key (make_spec names it conventions=, the command line's word)
        preset = table.get("preset")
        preset = None if preset is None else validate.choice("[conventions] preset", preset, tuple(PRESETS))
    except ValidationError as exc:
        raise ParseError(path, _line(text, "conventions", "preset"), str(exc)) from None
    _refuse_quoted_numbers(options, table, path, text)
    spec = _manifest_spec(preset, options, transform, table, path, text)
    _refuse_own(spec, preset, table, raw, est_fmt, list(dict.fromkeys(s.scene for s in sessions)), path, text)
    _refuse_together(spec, options, table, path, text)
    return Manifest(
        path=path, name=str(raw.get("name", path.stem)), sessions=sessions, lifelong=spec.mode == "lifelong",
        groundtruth_format=gt_fmt, estimate_format=est_fmt, spec=spec,
        transform=transform, eps=spec.eps if "eps" in spec.explicit else None,
        phi=spec.phi if "phi" in spec.explicit else None, groundtruth_topic=raw.get("groundtruth_topic"),
        estimate_topic=raw.get("estimate_topic"), groundtruth_tf=raw.get("groundtruth_tf"),
        estimate_tf=raw.get("estimate_tf"), source=str(raw.get("source", "")), outside=bool(outside),
    )  # fmt: skip


_VARIABLE = re.compile(r"\$(?:\{([^}]*)\}|(\w+))")


def _folder(value: str) -> Path:
    """A folder an environment variable names (``TUM_ROOT=tumroot``), relative to the current
    directory as a shell user means it (not to the manifest's folder, inside lorisnb for a built-in
    one), ``~`` expanded."""
    return Path(os.path.abspath(os.path.expanduser(value)))


def _expand(root_text: str) -> str:
    """A manifest's ``root`` with its environment variables expanded; the one it starts with
    (``${TUM_ROOT}/sub``) names a folder, taken from the current directory if relative
    (:func:`_folder`). Variables further on are parts of a path, as written."""
    m = _VARIABLE.match(root_text)
    if m:
        value = os.environ.get(m.group(1) or m.group(2) or "", "")
        if value.strip():
            return str(_folder(value)) + os.path.expandvars(root_text[m.end() :])
    return os.path.expandvars(root_text)


def _variables(text: str, known: bool = True) -> list[str]:
    """The environment variables ``text`` names (``$NAME`` or ``${NAME}``) that are set, and (``known``)
    name a dataset's folder: :data:`DATASET_VARIABLES` (``EUROC_ROOT``, ``TUM_ROOT``, as the built-in
    manifests use, and ``LORISNB_DATA``) and those the user lists in ``LORISNB_DATASET_VARIABLES``
    (:func:`dataset_variables`). A manifest received from someone else chooses its variables:
    ``${HOME}``, ``${PWD}`` or ``${PYENV_ROOT}`` name folders of the user's that are no dataset, so a
    root under them must lie inside the manifest's folder or the data root like a root written out."""
    names = (m.group(1) or m.group(2) for m in _VARIABLE.finditer(text))
    allowed = dataset_variables() if known else None
    return [
        n for n in dict.fromkeys(names)
        if (allowed is None or n in allowed) and n in os.environ and os.environ[n].strip()
    ]  # fmt: skip


def dataset_variables() -> tuple[str, ...]:
    """The environment variables whose folder a manifest's ``root`` may lie anywhere inside:
    :data:`DATASET_VARIABLES` and the names ``LORISNB_DATASET_VARIABLES`` lists (separated by spaces,
    commas or colons: ``KITTI_ROOT,MYLAB_ROOT``), each checked to be a variable's name."""
    given = os.environ.get(ALLOW_VARIABLES, "")
    extra = [n for n in re.split(r"[\s,:]+", given) if n]
    for n in extra:
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", n):
            raise ValidationError(f"{ALLOW_VARIABLES}={given!r}: {n!r} is not an environment variable's name; "
                                  "expected names such as KITTI_ROOT, separated by spaces or commas")  # fmt: skip
    return tuple(dict.fromkeys([*DATASET_VARIABLES, *extra]))


def _data_root() -> list[Path]:
    """lorisnb's data root (:func:`~lorisnb.io.datasets.paths.find_data`), where one is found."""
    from lorisnb.errors import DataNotFoundError
    from lorisnb.io.datasets.paths import find_data

    try:
        return [find_data(None).root.resolve()]
    except DataNotFoundError:
        return []


def _confined(
    file: Path, folders: list[Path], path: Path, where: str, named: str = "the manifest's folder, its root"
) -> None:
    """Refuse a ``file`` (a ground truth, or the root) that lies (links resolved) outside
    ``folders``: a manifest received from someone else reads nothing elsewhere. Nothing is opened."""
    p = file.resolve()
    if not any(p == f or f in p.parents for f in folders):
        raise ParseError(path, None, f"{where} lies outside {named} and lorisnb's data root "
                         f"({', '.join(map(str, dict.fromkeys(folders)))}); expected a place inside them (pass "
                         "--manifest-outside, or outside=True, to read it anyway)")  # fmt: skip


def _toml(value: Any) -> str:
    """A manifest's value as TOML writes it (``true``, not Python's ``True``)."""
    return str(value).lower() if isinstance(value, bool) else repr(value)


def _text(table: dict[str, Any], key: str, path: Path, where: str = "", line: int | None = None) -> None:
    """A key whose value must be text (a name, a file, a topic): anything else is refused, never
    turned into the text of a list or a number. ``line``: where the key is written."""
    if key in table and not isinstance(table[key], str):
        raise ParseError(path, line, f"{where}{key} = {_toml(table[key])}: expected a string (in quotes)")
    if key in table and "\x00" in table[key]:  # no file system takes one: refused here, not a crash in a later call
        raise ParseError(path, line, f"{where}{key} = {table[key]!r}: a NUL character (\\u0000); expected a name")


def estimate_name(text: str) -> str:
    """A session's estimate path as written, less its ``.`` parts and doubled slashes (``./x.txt`` is
    ``x.txt``, ``sub//x.txt`` is ``sub/x.txt``): the name every message and lookup uses. A trailing
    slash (a folder: a ROS 2 bag's), ``..`` and an absolute path are kept (refused where the
    estimates are looked for)."""
    parts = [p for p in text.split("/") if p not in ("", ".")]
    if not parts:
        return text
    return ("/" if text.startswith("/") else "") + "/".join(parts) + ("/" if text.endswith("/") else "")


def estimate_key(estimate: str) -> str:
    """What two sessions' estimates are compared by: the same file whatever its spelling, Unicode NFC
    of each name (``café`` written in NFD is ``café``), without ``.`` parts or a trailing slash."""
    return validate.label(estimate_name(estimate).rstrip("/") or estimate)


def check_repeats(
    sessions: list[Session], path: Path, text: str | None = None, written: list[str] | None = None
) -> None:
    """A session listed twice (the same name, or the same estimate file, in two ``[[session]]``
    tables) is an error naming both: it would be scored twice. Names are compared in Unicode NFC (a
    name typed ``café`` and one pasted from a Mac, ``cafe`` and a combining accent, are one, as the
    file lookup finds either), estimates by the file they name (:func:`estimate_key`: ``./x.txt`` is
    ``x.txt``). ``text``: the manifest's, for the line of the second session's key; ``written``:
    each session's estimate as the manifest spells it, for the message."""
    spelled = written or [s.estimate for s in sessions]
    for what, written_as, key, raw in (
        ("name", "name", lambda k, s: validate.label(s.name), lambda k, s: s.name),
        ("estimate file", "estimate", lambda k, s: estimate_key(s.estimate), lambda k, s: spelled[k - 1]),
    ):  # (a ground-truth file may serve several sessions: one long recording, runs in its time windows)
        first: dict[object, tuple[int, Session]] = {}
        for k, s in enumerate(sessions, start=1):
            got = key(k, s)
            if got in first:
                j, t = first[got]
                a, b = raw(j, t), raw(k, s)
                if a == b:
                    same = repr(a)
                elif what == "name" and validate.label(a) == validate.label(b):
                    same = f"{ascii(a)} and {ascii(b)}, one name in two Unicode forms (NFC and NFD)"
                else:
                    same = f"{a!r} and {b!r}, two spellings of one file"
                seqs = f" (sessions {t.seq} and {s.seq})" if (t.seq, s.seq) != (j, k) else ""
                raise ParseError(
                    path, _line(text, "session", written_as, k) or _line(text, "session", "name", k),
                    f"[[session]] {j} ({t.name!r}) and [[session]] {k} ({s.name!r}){seqs} have the same {what}, {same}: "
                    "a session listed twice? Each session must be listed once, with its own files (it would be "
                    "scored twice)",
                )  # fmt: skip
            first[got] = (k, s)


def _refuse_repeated_seq(sessions: list[Session], items: list[Any], path: Path, text: str | None) -> None:
    """Two sessions with one number are a ParseError naming both, where each number comes from: its
    ``seq`` (and line) or, with none written, its position (``seq = 2`` on the first session beside a
    second session without ``seq``: both are 2, the second by its place)."""
    first: dict[int, int] = {}
    for k, s in enumerate(sessions, start=1):
        if s.seq not in first:
            first[s.seq] = k
            continue
        j = first[s.seq]

        def said(n: int) -> str:
            t = sessions[n - 1]
            if "seq" in items[n - 1]:
                line = _line(text, "session", "seq", n)
                return f"[[session]] {n} ({t.name!r}): seq = {t.seq}{f' on line {line}' if line else ''}"
            return f"[[session]] {n} ({t.name!r}): no seq, so {t.seq} by its position (the {_ordinal(n)} session)"

        line = _line(text, "session", "seq", k) or _line(text, "session", "seq", j)
        raise ParseError(path, line, f"two sessions are numbered {s.seq}: {said(j)}; {said(k)}. Expected each number "
                         "once: give every session its own seq, or write seq on none (they are numbered 1, 2, ... "
                         "in order)")  # fmt: skip


def _ordinal(n: int) -> str:
    """1st, 2nd, 3rd, 4th, 11th, 21st, ..."""
    tail = "th" if 10 <= n % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(n % 10, "th")
    return f"{n}{tail}"


_HEADER = re.compile(r"^\s*(\[\[?)\s*([A-Za-z0-9_.\- \"']+?)\s*\]\]?\s*(#.*)?$")


def _line(text: str | None, table: str | None, key: str, nth: int = 1) -> int | None:
    """The line (1-based) of ``key`` in ``table`` of a manifest's ``text`` (None: the top level;
    ``session`` with ``nth``: the nth ``[[session]]``), for messages: tomllib gives no line for a
    value. Best effort: None where it is not written as ``key = ...`` on a line of its own."""
    if not text:
        return None
    want = re.compile(rf"^\s*(?:{re.escape(key)}|\"{re.escape(key)}\"|'{re.escape(key)}')\s*=")
    here: str | None = None
    count = 0
    for n, line in enumerate(text.splitlines(), start=1):
        m = _HEADER.match(line)
        if m:
            here = m.group(2).strip().strip("\"'")
            if m.group(1) == "[[" and here == table:
                count += 1
            continue
        if here == table and (table != "session" or count == nth) and want.match(line):
            return n
    return None


def _manifest_spec(
    preset: str | None, options: dict[str, Any], transform: Sim3 | None, table: dict[str, Any], path: Path, text: str
) -> EvalSpec:
    """The manifest's spec by :func:`make_spec`, a value refused with the message of every surface
    and the line of its key (``[conventions]`` or the top level): each value on its own first (its
    value check), then together."""
    for key, value in options.items():  # each value's own check, with its line
        try:
            make_spec(preset, surface="manifest", **{key: value})
        except ValidationError as exc:
            raise ParseError(path, _key_line(key, table, text), str(exc)) from None
    try:
        return make_spec(preset, surface="manifest", **options, transform=transform)
    except ValidationError as exc:  # a rule between values: the line of the first one named
        raise ParseError(path, _named_line(str(exc), list(options), table, text), str(exc)) from None


def _refuse_quoted_numbers(options: dict[str, Any], table: dict[str, Any], path: Path, text: str) -> None:
    """A number written in quotes (``eps = "0.05"``, ``tau = "60"``) is text, not a number, as
    ``lifelong = "no"`` is no boolean: refused for every option, saying to write it without quotes.
    Words an option documents (``eps = "paper"``, ``"relative:0.1"``) are no numbers and pass."""
    for key, value in options.items():
        if not isinstance(value, str) or "_" in value:  # 1_0: the number check says to write it without underscores
            continue
        try:
            float(value.strip())
        except ValueError:
            continue
        where = "[conventions] " if key in table else ""
        raise ParseError(path, _key_line(key, table, text), f"{where}{key} = {value!r}: a number in quotes is text; "
                         f"write it without quotes ({key} = {value.strip()}), as TOML writes numbers")  # fmt: skip


def _key_line(key: str, table: dict[str, Any], text: str) -> int | None:
    """The line of a spec option of a manifest: in ``[conventions]``, else at the top level."""
    return _line(text, "conventions" if key in table else None, key)


def _named_line(message: str, keys: list[str], table: dict[str, Any], text: str) -> int | None:
    """The line of the key a refusal is about: the one its message starts with (``change_unit mm:
    ...``, ``[conventions] max_gap = 1: ...``, ``estimate_topic: ...``), the longest that fits
    (``rpe_delta``, not ``delta``), in ``[conventions]`` (``table``) or at the top level. The one
    rule of every refusal of the spec's options and reading keys, each message as every surface
    gives it; None when it names none of ``keys``."""
    said = message.removeprefix("[conventions] ")
    for key in sorted(keys, key=len, reverse=True):
        if said.startswith(key) and said[len(key) : len(key) + 1] in ("", " ", "=", ":", ",", "("):
            return _key_line(key, table, text)
    return None


def _refuse_together(spec: EvalSpec, options: dict[str, Any], table: dict[str, Any], path: Path, text: str) -> None:
    """Options of the manifest that cannot apply with its other values (``max_gap`` beside
    ``association = "nearest"``), refused when it is read, with the line of the first one, in the
    words of every surface (:meth:`~lorisnb.core.spec.evalspec.EvalSpec.refuse_inapplicable`)."""
    try:
        spec.refuse_inapplicable("manifest", surface="manifest")
    except ValidationError as exc:
        raise ParseError(path, _named_line(str(exc), list(options), table, text), str(exc)) from None


def _refuse_own(
    spec: EvalSpec,
    preset: str | None,
    table: dict[str, Any],
    raw: dict[str, Any],
    est_fmt: str,
    scenes: list[str],
    path: Path,
    text: str,
) -> None:
    """Refuse, when the manifest is read, a value of its own that applies to none of its evaluations,
    whatever a call gives over it (a preset given over the manifest replaces its ``[conventions]``):
    ``kitti_precision`` and ``tartanair_*`` without the preset they belong to, ``official_lifelong``
    (a manifest is not an input of the official tool), ``repair_stamps`` with estimates that are not
    OpenLORIS result files, ``eps = 'paper'`` with a scene that is not OpenLORIS'. The ParseError names
    the file, the line, the table and the key."""
    from lorisnb.core.pipeline.model import scene_eps

    def refuse(key: str, where: str | None, why: str) -> None:
        shown = f"[{where}] {key}" if where else key
        value = table.get(key, raw.get(key))
        shown_value = str(value).lower() if isinstance(value, bool) else repr(value)  # as TOML writes it
        raise ParseError(path, _line(text, where, key), f"{shown} = {shown_value}: {why}")

    for key in ("kitti_precision", "tartanair_scale", "tartanair_seed", "official_lifelong"):
        if key not in table:
            continue
        try:  # the rule of the spec, on this option alone
            make_spec(preset, surface="manifest", **{key: table[key]}).refuse_inapplicable(
                "manifest", surface="manifest"
            )
        except ValidationError as exc:  # "kitti_precision: only for ... (--conventions kitti)", as a manifest says it
            why = re.sub(r"\(--conventions (\w+)\)", r"([conventions] preset = '\1')", str(exc).split(": ", 1)[-1])
            refuse(key, "conventions", why)
    if "repair_stamps" in table and spec.repair_stamps and est_fmt != "openloris":
        refuse("repair_stamps", "conventions", "only OpenLORIS result files are read with this rule (command line "
               f"--repair-stamps); the manifest's estimates are {est_fmt} files (estimate_format = {est_fmt!r})")  # fmt: skip
    if "eps" in spec.explicit and isinstance(spec.eps, str) and spec.eps.strip().lower() == "paper":
        for scene in scenes:
            try:
                scene_eps(spec.eps, scene)
            except ValidationError:
                refuse("eps", "conventions" if "eps" in table else None, f"the paper's 1/3/5 m are for the OpenLORIS "
                       f"scenes; scene {scene!r} is not one: give eps in metres or as 'relative:F' (a fraction of the "
                       "ground truth's extent)")  # fmt: skip


def check_keys(table: dict[str, Any], allowed: set[str], path: Path, where: str = "", line: Any = None) -> None:
    """Refuse a key of a manifest's table that lorisnb does not know (a typo would be ignored):
    ParseError naming the file, the line (``line``: key -> its line, where known), the table
    (``where``, e.g. ``"[transform]: "``; none at the top level), the key, the nearest known key
    and all of them."""
    for key in sorted(set(table) - allowed):
        hint = validate.near_miss(key, allowed)
        raise ParseError(
            path,
            None if line is None else line(key),
            f"{where}unknown key {key!r}{f' ({hint})' if hint else ''}; expected {', '.join(sorted(allowed))}",
        )


def _transform(raw: Any, path: Path, text: str | None = None) -> Sim3 | None:
    """The ``[transform]`` table as T_est_gt; a bad value refused naming its line and key."""
    if raw is None:
        return None
    if not isinstance(raw, dict):
        raise ParseError(path, _line(text, None, "transform"), "transform: expected a [transform] table (translation, "
                         "quaternion)")  # fmt: skip
    check_keys(raw, TRANSFORM_KEYS, path, "[transform]: ", lambda k: _line(text, "transform", k))
    expected = {"translation": "[x, y, z] (metres)", "quaternion": "[x, y, z, w]"}
    values = {"translation": [0.0, 0.0, 0.0], "quaternion": [0.0, 0.0, 0.0, 1.0]}
    for key, size in (("translation", 3), ("quaternion", 4)):
        v = raw.get(key, values[key])
        if (
            not isinstance(v, list)
            or len(v) != size
            or any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in v)  # true is not 1 m
            or not np.isfinite(np.asarray(v, float)).all()
            or (key == "quaternion" and np.linalg.norm(np.asarray(v, float)) < 1e-9)
        ):
            zero = ", not all zero" if key == "quaternion" else ""
            raise ParseError(path, _line(text, "transform", key), "[transform]: expected translation = [x, y, z] and "
                             f"quaternion = [x, y, z, w]; {key} = {_toml(v)} is not {size} finite numbers "
                             f"{expected[key]}{zero}")  # fmt: skip
        values[key] = v
    t = np.asarray(values["translation"], float)
    q = np.asarray(values["quaternion"], float)
    from scipy.spatial.transform import Rotation

    return Sim3(Rotation.from_quat(q).as_matrix(), t, 1.0)
