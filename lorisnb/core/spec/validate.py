"""Validation of every user value, in one place.

The command line, the Python API, sweeps, notebook parameters and widgets all pass user values
through these functions, so the same value is accepted or refused with the same message
everywhere. Each returns the normalized value or raises :class:`~lorisnb.errors.ValidationError`
naming the value, what was given and what is expected.
"""

from __future__ import annotations

import math
import sys
import unicodedata
from collections.abc import Callable, Iterable, Mapping
from typing import Any, NoReturn

import numpy as np

from lorisnb.core.trajectory.frames import SCENES
from lorisnb.errors import ValidationError


def label(text: object) -> str:
    """An algorithm, scene or file label as lorisnb compares and groups it: Unicode NFC, so that
    ``algé`` typed (one code point) and ``algé`` from a macOS folder name (``e`` and a combining
    accent) are one algorithm, not two that look alike. Control characters are kept (they are
    escaped where printed, :func:`lorisnb.cli.text.clean`)."""
    s = str(text)
    return s if s.isascii() else unicodedata.normalize("NFC", s)


#: The words accepted for ``scale`` (command line ``--scale WORD``, Python ``scale=``), any case.
SCALE_WORDS: dict[str, bool | str] = {
    "auto": "auto",
    "on": True, "yes": True, "true": True, "1": True, "sim3": True,
    "off": False, "no": False, "false": False, "0": False, "se3": False,
}  # fmt: skip

#: Thresholds: name -> (unit, whether 0 is allowed). Infinity is allowed for all of them.
THRESHOLDS: dict[str, tuple[str, bool]] = {
    "eps": ("metres", True),
    "phi": ("degrees", True),
    "delta": ("seconds", False),
    "tau": ("seconds", False),
}

#: Largest finite value that still has a meaning, with what a larger one probably is: an AOE
#: is at most 180 degrees; a validity window or time factor of more than a day is a value in
#: milliseconds (or a typo). ``inf`` (no threshold) stays allowed.
LIMITS: dict[str, tuple[float, str]] = {
    "phi": (180.0, "an orientation error is at most 180 degrees; use 180 or 'inf' for no AOE threshold"),
    "delta": (86400.0, "more than a day: milliseconds instead of seconds? (the paper uses 1 s)"),
    "tau": (86400.0, "more than a day: milliseconds instead of seconds? (the paper uses 60 s)"),
}

#: The unit of ``align_frames`` in messages: no value (not evo's -1) fits on every matched pose.
ALL_POSES = "poses (leave it out to fit on all matched poses: evo's -1)"

#: A relative eps (``relative:F``) is a fraction of the ground truth's extent, at most this.
MAX_FRACTION = 1.0


#: Longest value a message prints as it is: a longer one (a table passed where a number was asked
#: for) is named by its type and shape, or cut, never printed in full.
SHOWN_MAX = 60


def shown(value: Any) -> str:
    """A value as a message shows it: as the user typed it (strings without quotes, so command-line
    values read naturally); a table or array by its type and shape (``<DataFrame of 12 rows x 9
    columns>``), never its contents; any other long value cut to :data:`SHOWN_MAX` characters."""
    if isinstance(value, str):
        return value if len(value) <= 4 * SHOWN_MAX else value[: 4 * SHOWN_MAX - 3] + "..."
    shape = getattr(value, "shape", None)
    if isinstance(shape, tuple) and len(shape) >= 1 and not isinstance(value, (int, float)):
        kind = type(value).__name__
        if len(shape) == 2:
            return f"<{kind} of {shape[0]} rows x {shape[1]} columns>"
        return f"<{kind} of {shape[0]} values>" if len(shape) == 1 else f"<{kind} of shape {shape}>"
    try:
        text = repr(value)
    except ValueError:  # an int of more digits than Python prints (sys.get_int_max_str_digits)
        return f"<{type(value).__name__}>"
    return text if len(text) <= SHOWN_MAX else text[: SHOWN_MAX - 3] + "..."


_show = shown


def _number(name: str, value: Any, words: Mapping[str, Any]) -> Any:
    if isinstance(value, (bool, np.bool_)) or value is None:  # numpy's True is no more a number than Python's
        raise ValidationError(f"{name}={_show(value)}: expected a number")
    if isinstance(value, (bytes, bytearray, np.bytes_)):  # float(b"3") is 3.0: text of no known encoding
        raise ValidationError(f"{name}={_show(value)} (bytes): expected a number (or text: decode it first)")
    if isinstance(value, str):
        text = value.strip().lower()
        if text in words:
            return words[text]
        if "_" in text:  # float("1_0") is 10; the file readers refuse 1_000: one number syntax for user values
            raise ValidationError(f"{name}={_show(value)} is not a number: write it without underscores (1000, not "
                                  "1_000), as trajectory files are read")  # fmt: skip
        try:
            v = float(text)
        except ValueError:
            extra = "".join(f", '{w}'" for w in words if w not in ("inf", "+inf", "infinity"))
            extra = (", 'inf'" if "inf" in words else "") + extra  # only where infinity is allowed
            raise ValidationError(f"{name}={_show(value)} is not a number; expected a number{extra}") from None
        if math.isinf(v) and text.lstrip("+-") not in ("inf", "infinity"):  # "1e400": finite as written
            _overflow(name, value, words)
        return v
    try:  # numbers of any kind, numpy 0-d arrays and the like
        v = float(value)
    except OverflowError:  # an int or Fraction past float's range (10**400)
        _overflow(name, value, words)
    except (TypeError, ValueError):
        raise ValidationError(f"{name}={_show(value)} ({type(value).__name__}): expected a number") from None
    if math.isinf(v) and not _infinite(value):  # a Decimal or long double past float's range: infinity as a float
        _overflow(name, value, words)
    return v


def _infinite(value: Any) -> bool:
    """Whether a number is itself infinite (not a finite one that is infinity as a float)."""
    try:
        return bool(value == math.inf or value == -math.inf)
    except (TypeError, ValueError):
        return False


def _overflow(name: str, value: Any, words: Mapping[str, Any]) -> NoReturn:
    """Refuse a finite number too large for a float (``"1e400"``, ``10**400``): as a float it is
    infinity, which means "no threshold" where it is allowed, so infinity is spelled ``inf``."""
    inf = "write 'inf' for no threshold, else " if "inf" in words else ""
    try:
        shown = _show(value)
    except ValueError:  # an int of more digits than Python prints (sys.get_int_max_str_digits)
        shown = f"<{type(value).__name__}>"
    shown = shown if len(shown) <= 40 else shown[:30] + "..."  # 10**400: its 401 digits say nothing more
    raise ValidationError(
        f"{name}={shown}: too large to be a number (beyond +-{sys.float_info.max:.3g} it would be read as "
        f"infinity); {inf}expected a number"
    )


_INF = {"inf": math.inf, "+inf": math.inf, "infinity": math.inf}


def threshold(name: str, value: Any) -> float:
    """One threshold: ``eps`` (metres), ``phi`` (degrees), ``delta`` or ``tau`` (seconds).

    Accepts numbers and number strings, ``"inf"`` in any case. Refuses NaN, negative values, and
    zero for ``delta`` and ``tau`` (a zero validity window or time factor has no meaning)."""
    unit, zero_ok = THRESHOLDS[name]
    v = _number(name, value, _INF)
    if math.isnan(v):
        raise ValidationError(f"{name}={_show(value)}: expected a number of {unit}, not NaN")
    if v < 0 or (v == 0 and not zero_ok):
        bound = ">= 0" if zero_ok else "> 0"
        raise ValidationError(f"{name}={_show(value)}: expected a number of {unit} {bound}")
    if name in LIMITS and math.isfinite(v) and v > LIMITS[name][0]:
        top, why = LIMITS[name]
        raise ValidationError(f"{name}={_show(value)}: expected at most {top:g} {unit} (or 'inf'); {why}")
    return float(v) + 0.0  # -0.0 is 0 (shown as 0.0 in every table)


def eps_value(value: Any) -> float | str | dict[str, float]:
    """The ATE threshold: metres (as :func:`threshold`), ``"paper"`` in any case (1/3/5 m by
    scene), ``"relative:F"`` (F times each sequence's ground-truth extent, the diagonal of its
    bounding box), or a mapping scene -> metres."""
    if isinstance(value, Mapping):
        if not value:
            raise ValidationError("eps={}: an empty mapping; expected scene -> metres for every scene of the inputs")
        bad = [k for k in value if not isinstance(k, str) or not k.strip()]
        if bad:
            raise ValidationError(f"eps: key {bad[0]!r}: expected scene names (str) -> metres")
        cased = [k for k in value if k not in SCENES and k.strip().lower() in SCENES]
        if cased:  # an OpenLORIS scene in another case: the inputs' is lower case
            raise ValidationError(f"eps: scene {cased[0]!r}: OpenLORIS scene names are lower case "
                                  f"({cased[0].strip().lower()!r})")  # fmt: skip
        # any scene name of the inputs (a pair's, a manifest's: fr2_desk); one the inputs hold without
        # a threshold is refused where the scores are computed (lorisnb.core.pipeline.model.scene_eps)
        return {str(k): threshold("eps", v) for k, v in value.items()}
    if isinstance(value, str) and value.strip().lower() == "paper":
        return "paper"
    if isinstance(value, str) and value.strip().lower().startswith("relative:"):
        return f"relative:{fraction('eps', value.strip()[len('relative:') :], value.strip())!r}"
    try:
        return threshold("eps", value)
    except ValidationError as exc:
        raise ValidationError(
            str(exc).replace("expected a number", "expected 'paper', 'relative:F', a number", 1)
        ) from None


def fraction(name: str, value: Any, shown: Any = None) -> float:
    """A fraction of the ground truth's size (``relative:F`` eps, relative grids, ``eps_fraction``):
    a finite number from 0 to :data:`MAX_FRACTION`. 0 is allowed as ``eps = 0`` is (only poses
    with no error at all are correct), in every form and on every surface."""
    shown = value if shown is None else shown
    why = f"{name}={_show(shown)}: expected a fraction of the ground truth's size, a number from 0 to {MAX_FRACTION:g}"
    try:
        v = _number(name, value, {})
    except ValidationError:
        raise ValidationError(why) from None
    if not (math.isfinite(v) and v >= 0):  # NaN too
        raise ValidationError(why)
    return relative_fraction(name, v, shown)


def relative_fraction(name: str, fraction: float, shown: Any) -> float:
    """A fraction of a sequence's size (relative eps, ``--relative-to``): in (0, 1]; 5 meant as
    5 % is refused with the fraction it probably meant."""
    if fraction > MAX_FRACTION:
        raise ValidationError(
            f"{name}={_show(shown)}: a fraction of the ground truth's size is at most {MAX_FRACTION:g}; "
            f"for {fraction:g} % write {fraction / 100:g} (relative:{fraction / 100:g})"
        )
    return fraction


def threshold_list(name: str, values: Any, label: str | None = None) -> list[Any]:
    """A non-empty list of thresholds (for sweeps): one value or an iterable of them; ``eps``
    values may be ``"paper"``. A string is split at commas, as on the command line; an empty item
    (``1,,2``, a trailing comma) is refused, not dropped; a 0-d numpy array is one value. Each item
    is checked by the rule of the one threshold ``name`` (:func:`eps_value`, :func:`threshold`).
    ``label``: what the errors call the list when it is not ``name`` itself (a notebook's
    ``eps_grid``): ``eps_grid=-1: expected ...``, ``eps_grid: an empty list``."""
    return value_list(name, values, eps_value if name == "eps" else (lambda v: threshold(name, v)), label)


def value_list(name: str, values: Any, check: Callable[[Any], Any], label: str | None = None) -> list[Any]:
    """A non-empty list of values, each checked by ``check`` (which names its value ``name=...``),
    as :func:`threshold_list` reads one; the same value twice is refused. ``label`` (default
    ``name``): the list's name in the errors, each item's error then naming ``label`` and the item."""
    called = name if label is None else label
    if isinstance(values, np.ndarray) and values.ndim == 0:
        values = values.item()
    if isinstance(values, np.ndarray) and values.ndim > 1:  # its rows were taken as values (one named, wrongly)
        raise ValidationError(f"{called}: an array of shape {values.shape}; expected a list of values (one dimension: "
                              f"{called}=values.ravel() for each of them)")  # fmt: skip
    if isinstance(values, str):
        items: list[Any] = values.split(",")
        if any(p.strip() for p in items) and not all(p.strip() for p in items):  # all empty: below
            raise ValidationError(f"{called}={values}: an empty item between commas; expected values separated by "
                                  "commas")  # fmt: skip
        items = [p for p in items if p.strip()]
    elif isinstance(values, Iterable) and not isinstance(values, Mapping):
        items = list(values)
    else:
        items = [values]
    if not items:
        raise ValidationError(f"{called}: an empty list; expected at least one value")
    out: list[Any] = []
    for item in items:
        try:
            out.append(check(item))
        except ValidationError as exc:
            if label is None or label == name:
                raise
            raise ValidationError(element_error(label, name, item, exc)) from None
    for k, v in enumerate(out):  # the same setting twice (60 and 60.0, inf and Infinity): rows twice, refused
        if v in out[:k]:
            raise ValidationError(f"{called}={_show(values)}: {_show(items[out.index(v)])} and {_show(items[k])} are "
                                  "the same value; expected each value once")  # fmt: skip
    return out


def element_error(label: str, name: str, item: Any, exc: ValidationError) -> str:
    """The error of one item of the list ``label`` as the check of the one value ``name`` said it
    (``eps=-1: expected ...``), naming the list with the item instead: ``eps_grid=-1: expected ...``
    (as ``relative_grid=5: ...`` and the command line's ``-p eps_grid=1e400: ...`` name it)."""
    text = str(exc)
    shown_item = _show(item.strip() if isinstance(item, str) else item)
    for given in (f"{name}={_show(item)}", f"{name}={shown_item}", f"{name}={item}"):
        if text.startswith(given):
            return f"{label}={shown_item}{text[len(given) :]}"
    if text.startswith(f"{name}:"):  # eps: key 1: ..., eps: scene 'Cafe': ...
        return f"{label}={shown_item}:{text[len(name) + 1 :]}"
    if text.startswith(f"{name}=") and not isinstance(item, Mapping):  # an item shown shortened (10**400)
        return f"{label}={text[len(name) + 1 :]}"
    return f"{label}={shown_item}: {text}"


def scale_value(value: Any) -> bool | str:
    """Alignment scale: True (Sim(3)), False (SE(3)) or ``"auto"`` (Sim(3) for monocular
    algorithms). Accepts booleans and the words of :data:`SCALE_WORDS` in any case."""
    if isinstance(value, bool):
        return value
    if isinstance(value, str) and value.strip().lower() in SCALE_WORDS:
        return SCALE_WORDS[value.strip().lower()]
    if isinstance(value, (bool, np.bool_, int, np.integer)) and value in (0, 1):  # numpy's as Python's
        return bool(value)
    raise ValidationError(f"scale={_show(value)}: expected True, False, 'auto', or one of {', '.join(SCALE_WORDS)}")


def choice(name: str, value: Any, options: Iterable[str]) -> str:
    """One of a fixed set of words (case-insensitive)."""
    opts = tuple(options)
    if isinstance(value, str) and value.strip().lower() in opts:
        return value.strip().lower()
    raise ValidationError(f"{name}={_show(value)}: expected one of {', '.join(opts)}")


def positive(name: str, value: Any, unit: str, *, integer: bool = False) -> float:
    """A positive number (for example an RPE step), optionally a whole number."""
    v = _number(name, value, {})
    if math.isnan(v) or v <= 0 or math.isinf(v) or (integer and v != int(v)):
        kind = "a positive whole number" if integer else "a positive number"
        finite = ", not infinity" if math.isinf(v) else ""  # inf is positive, but no value here
        raise ValidationError(f"{name}={_show(value)}: expected {kind}" + (f" of {unit}" if unit else "") + finite)
    return float(v)


def positive_list(name: str, values: Any, unit: str, most: float = math.inf) -> tuple[float, ...]:
    """A non-empty list of distinct positive numbers, at most ``most`` each (lengths, fractions): a
    list, tuple or array, or text split at commas as on the command line. The same value twice
    (``1,1``) is refused: it gave its row twice the samples."""
    if isinstance(values, str):
        parts = values.split(",")
        if not all(p.strip() for p in parts):
            raise ValidationError(f"{name}={values}: an empty item between commas; expected {unit or 'numbers'} "
                                  "separated by commas")  # fmt: skip
        items: list[Any] = parts
    elif isinstance(values, (list, tuple, np.ndarray)):
        items = list(values)
    else:
        items = []
    if not items:
        raise ValidationError(f"{name}={_show(values)}: expected a non-empty list of positive numbers")
    out = tuple(positive(name, v, unit) for v in items)
    if any(v > most for v in out):
        raise ValidationError(f"{name}={_show(values)}: each is a fraction of the path length, at most {most:g}")
    for k, v in enumerate(out):
        if v in out[:k]:
            raise ValidationError(f"{name}={_show(values)}: {_show(items[out.index(v)])} and {_show(items[k])} are "
                                  "the same value; expected each value once")  # fmt: skip
    return out


def seq_number(name: str, value: Any) -> int:
    """A sequence's number (a manifest session's ``seq``, ``--seq``, ``seq=``): a positive whole
    number, as OpenLORIS numbers its ``seq:`` blocks from 1; bools and fractions refused."""
    if isinstance(value, (bool, np.bool_)) or value is None:
        raise ValidationError(
            f"{name}={_show(value)}: expected a positive whole number (sequences are numbered from 1)"
        )
    v = _number(name, value, {})
    if not (math.isfinite(v) and v >= 1 and v == int(v)):
        raise ValidationError(
            f"{name}={_show(value)}: expected a positive whole number (sequences are numbered from 1)"
        )
    return int(v)


def decimals(name: str, value: Any) -> int:
    """How many decimals to print: a whole number from 0 to 17 (a float64 holds 17 significant
    digits; more print noise, never information)."""
    v = _number(name, value, {})
    if not (0 <= v <= 17 and v == int(v)):  # NaN too
        raise ValidationError(f"{name}={_show(value)}: expected a whole number of decimals from 0 to 17")
    return int(v)


def significant(name: str, value: Any) -> int:
    """How many significant digits to print: a whole number from 1 to 17 (a float64 holds 17)."""
    v = _number(name, value, {})
    if not (1 <= v <= 17 and v == int(v)):  # NaN too
        raise ValidationError(f"{name}={_show(value)}: expected a whole number of significant digits from 1 to 17")
    return int(v)


def probability(name: str, value: Any) -> float:
    """A probability strictly between 0 and 1 (a confidence level, a test's alpha)."""
    v = _number(name, value, {})
    if not 0 < v < 1:  # NaN too
        raise ValidationError(f"{name}={_show(value)}: expected a probability between 0 and 1")
    return float(v)


def finite(name: str, value: Any, unit: str) -> float:
    """A finite number of any sign (for example a clock offset)."""
    v = _number(name, value, {})
    if math.isnan(v) or math.isinf(v):
        raise ValidationError(f"{name}={_show(value)}: expected a finite number of {unit}")
    return float(v)


def seed(value: Any, label: str = "seed") -> int:
    """A random seed (bootstrap, sampled relabellings, simulator): a whole number >= 0 (numpy's
    ``default_rng`` refuses a negative one with a traceback). Accepts ints, numpy integers and
    whole-number strings ("7", as typed on the command line); refuses bools, fractions, NaN."""
    if isinstance(value, (bool, np.bool_)) or value is None:
        raise ValidationError(f"{label}={_show(value)}: expected a whole number >= 0")
    v: int | None = None
    if isinstance(value, (int, np.integer)):
        v = int(value)
    elif isinstance(value, str) and value.strip().lstrip("+-").isdigit():
        v = int(value.strip())
    elif isinstance(value, (float, np.floating)) and math.isfinite(value) and value == int(value):
        v = int(value)
    if v is None:
        raise ValidationError(f"{label}={_show(value)}: expected a whole number >= 0")
    if v < 0:
        raise ValidationError(f"{label}={_show(value)}: expected a whole number >= 0 (a seed is not negative)")
    return v


def present(what: str, given: Iterable[str], there: Iterable[str], where: str = "the inputs") -> list[str]:
    """A filter (``scenes``, ``algorithms``) whose every value names something ``there``: a value
    that names nothing would drop every input silently, so it is refused, listing what is there,
    with a hint for a difference of case (``Cafe`` for ``cafe``) or a near miss. Returns ``given``
    as a list."""
    wanted, have = list(given), sorted(set(there))
    absent = [n for n in wanted if n not in have]
    if not absent:
        return wanted
    hints = [f"{n!r}: {hint}" for n in absent if (hint := near_miss(n, have))]
    listed = ", ".join(have) if have else "none"
    raise ValidationError(
        f"{what}: {', '.join(repr(n) for n in absent)} name(s) nothing in {where}, which hold {what}: {listed}"
        + ("; " + "; ".join(hints) if hints else "")
    )


def near_miss(name: str, known: Iterable[str]) -> str:
    """``did you mean 'x'?`` for a name differing from a known one only in case or by a typo (the
    one rule of filters, manifest keys and spec options), else an empty string."""
    import difflib

    have = sorted(known)
    same_case = [h for h in have if h.lower() == name.strip().lower()]
    near = same_case or difflib.get_close_matches(name, have, n=1, cutoff=0.75)
    return f"did you mean {near[0]!r}?" + (" (names are case-sensitive)" if same_case else "") if near else ""


def known_keys(given: Iterable[str], known: Iterable[str], what: str, shown: Callable[[str], str] = str) -> None:
    """Refuse a keyword that names none of the ``known`` settings (a typo: ``epsilon`` for ``eps``),
    as every surface does (the spec's options, the scores' settings, the tables' thresholds): the
    first unknown one, ``not`` ``what``, with a near miss (:func:`near_miss`) and every known one,
    in their order. ``shown``: how the surface names a key (``--max-diff`` on the command line)."""
    have = list(dict.fromkeys(known))
    unknown = sorted(set(given) - set(have))
    if unknown:
        hint = near_miss(unknown[0], have)
        raise ValidationError(f"{shown(unknown[0])}: not {what}{f' ({hint})' if hint else ''}; expected one of "
                              f"{', '.join(have)}")  # fmt: skip


def flag(label: str, value: Any, expected: str = "True or False") -> bool:
    """A yes/no value: a bool (numpy's too); strings are refused, never truth-tested. ``expected``:
    how the surface spells the two (a TOML manifest: ``true or false``)."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise ValidationError(f"{label}={value!r} ({type(value).__name__}): expected {expected}")


def rigid_transform(value: Any, label: str = "transform") -> tuple[tuple[float, ...], ...] | None:
    """``T_est_gt`` as a 4x4 tuple (from a :class:`~lorisnb.core.alignment.geometry.Sim3`, an array or nested
    lists); None stays None. A rigid transform is expected: a rotation block and a last row 0 0 0 1."""
    if value is None:
        return None
    m = value.matrix() if hasattr(value, "matrix") else value  # a Sim3
    try:
        arr = np.asarray(m, float)
    except (TypeError, ValueError):
        raise ValidationError(f"{label}: expected a 4x4 matrix T_est_gt, got {type(value).__name__}") from None
    if arr.shape != (4, 4) or not np.isfinite(arr).all():
        raise ValidationError(f"{label}: expected a finite 4x4 matrix T_est_gt, got shape {arr.shape}")
    r = arr[:3, :3]
    if not np.allclose(arr[3], [0, 0, 0, 1]) or not np.allclose(r @ r.T, np.eye(3), atol=1e-6):
        raise ValidationError(f"{label}: expected a rigid transform (a rotation block and last row 0 0 0 1)")
    return tuple(tuple(float(x) for x in row) for row in arr)


def code_label(value: Any, label: str = "label") -> str:
    """The name of the code under test (``report --label``: a commit, a tag, ``$GITHUB_SHA``): text
    of 1 to 200 characters on one line, no control characters (it is shown on pages and in
    terminal tables)."""
    if not isinstance(value, str) or not value.strip():
        raise ValidationError(f"{label}={_show(value)}: expected the name of the code under test, e.g. a commit hash")
    text = value.strip()
    if len(text) > 200 or not text.isprintable():
        raise ValidationError(f"{label}={_show(value)}: expected one printable line of at most 200 characters")
    return text
