"""How a formula check grades a learner's function: call it on each case (watching that it does not
call lorisnb, whose numbers it is checked against), compare with lorisnb's answer, and name every
typical mistake whose values the answers match. Used by :mod:`._checks`."""

from __future__ import annotations

import abc
import math
import os
import re
import sys
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from types import FrameType
from typing import Any, NoReturn

import numpy as np

from lorisnb.errors import AnswerError
from lorisnb.tools.teaching._mistakes import MISTAKES
from lorisnb.tools.teaching.sandbox import NotPlain

#: (mistake name in MISTAKES, the function that makes it), in the order their hints are given
Variants = Sequence[tuple[str, Callable[..., Any]]]

_PACKAGE = Path(__file__).resolve().parents[2]  # lorisnb/
_PACKAGE_DIRS = tuple({str(_PACKAGE) + os.sep, str(Path(__file__).parents[2]) + os.sep})


class SandboxedAnswer(abc.ABC):
    """A learner's function that runs in the grading sandbox (:mod:`.autograde`), where lorisnb
    cannot be imported: it is called as it is, with no watch on what it calls."""

    @abc.abstractmethod
    def __call__(self, **kwargs: Any) -> Any:
        """The learner's function called in the sandbox with ``kwargs``; its value."""


def fail(message: str, mistakes: str | Sequence[str] | None = None) -> NoReturn:
    """Raise the AnswerError of a wrong answer, with the hint of each mistake named."""
    names = [mistakes] if isinstance(mistakes, str) else list(mistakes or [])
    hints = "".join(f"\nHint ({m.replace('_', ' ')}): {MISTAKES[m]}" for m in names)
    raise AnswerError(f"✗ {message}{hints}")


def ok(message: str) -> bool:
    print(f"✓ {message}")
    return True


def how_far(got: float, want: float, tol: float) -> str:
    """Whether ``got`` is too high or too low for ``want`` and the decade of the difference (``just
    outside the tolerance`` within 3 ``tol``), never ``want`` itself: a check a learner sees while
    working, or in feedback before submitting again, must not hand them the number to type in."""
    d = abs(got - want)
    side = "too high" if got > want else "too low"
    if not math.isfinite(d):
        return f"{side} (it is not finite)"
    if d <= 3 * tol:
        return f"{side}, just outside the tolerance"
    k = math.floor(math.log10(d))
    return f"{side}, by between {10.0**k:g} and {10.0 ** (k + 1):g}"


def same(a: Any, b: Any, tol: float) -> bool:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return a.shape == b.shape and bool(np.all((np.isclose(a, b, rtol=tol, atol=tol)) | (np.isnan(a) & np.isnan(b))))


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def number(what: str, value: Any) -> float:
    """``value`` as one finite-or-infinite number; anything else fails with what was given."""
    if value is Ellipsis:
        fail(f"{what}: no answer yet (replace the `...` and the NotImplementedError placeholder with your answer)")
    if isinstance(value, NotPlain) and value.error is not None:  # the grader read no value: say why, whole
        fail(f"{what}: no value: {value.error}")
    if isinstance(value, (bool, np.bool_)) or value is None:
        fail(f"{what}: expected a number, got {value!r}")
    try:
        a = np.asarray(value, float)
    except (TypeError, ValueError):
        fail(f"{what}: expected one number, got {type(value).__name__} {_short(value)}")
    if a.size != 1:
        fail(
            f"{what}: expected one number, got {type(value).__name__} of shape {a.shape} ({a.size} values); "
            "is a sum (np.sum) or a selection ([0], .iloc[0]) missing?"
        )
    v = float(a.reshape(()))
    if math.isnan(v):
        fail(f"{what}: your answer is NaN")
    return v


def _in_package(filename: str) -> bool:
    return filename.startswith(_PACKAGE_DIRS)


def call_watched(fn: Callable[..., Any], args: Mapping[str, Any]) -> tuple[Any, str | None]:
    """``fn(**args)``, and the first lorisnb function it called itself (None when it called none):
    a learner's formula that hands its inputs to lorisnb (or to the check's own reference, reached
    through the call stack, or given as the answer itself) returns lorisnb's answer without
    computing anything. Module-level
    ``__getattr__`` (lazy imports) and module bodies run by an import do not count."""
    if isinstance(fn, SandboxedAnswer):
        return fn(**args), None
    entered: list[str] = []
    own_code = sys._getframe().f_code  # a lorisnb function given as the answer is called from here

    def watch(frame: FrameType, event: str, _arg: Any) -> None:
        code = frame.f_code
        if event != "call" or entered or not _in_package(code.co_filename):
            return
        if code.co_name in ("__getattr__", "<module>"):
            return
        caller = frame.f_back
        if caller is not None and _in_package(caller.f_code.co_filename) and caller.f_code is not own_code:
            return  # lorisnb calling itself: the entry was reported (or was a lazy import)
        entered.append(f"{frame.f_globals.get('__name__', 'lorisnb')}.{code.co_qualname}")

    previous = sys.getprofile()
    sys.setprofile(watch)
    try:
        got = fn(**args)
    finally:
        sys.setprofile(previous)
    return got, (entered[0] if entered else None)


def describe(case: Mapping[str, Any]) -> str:
    parts = []
    for n, v in case.items():
        if isinstance(v, np.ndarray):
            parts.append(f"{n}: {v.size} values")
        else:
            parts.append(f"{n}={v!r}")
    return ", ".join(parts)


def _values(variant: Callable[..., Any], cases: Sequence[Mapping[str, Any]]) -> list[Any] | None:
    """A mistake's values on every case (None where the mistake itself cannot be computed)."""
    try:
        with np.errstate(all="ignore"):
            return [variant(**c) for c in cases]
    except (ArithmeticError, ValueError, IndexError):
        return None


def matching_mistakes(
    answers: list[Any], cases: Sequence[Mapping[str, Any]], variants: Variants, tol: float
) -> list[str]:
    """Every mistake (once, in the order of ``variants``) whose values the answers match on every
    case: on cases that cannot tell two mistakes apart, both are named, not the first one alone."""
    names: list[str] = []
    for name, variant in variants:
        values = _values(variant, cases)
        if name in names or values is None:
            continue
        if all(same(a, v, tol) for a, v in zip(answers, values, strict=True)):
            names.append(name)
    return names


def check_function(
    what: str,
    fn: Callable[..., Any],
    cases: Sequence[Mapping[str, Any]],
    reference: Callable[..., Any],
    variants: Variants,
    boolean: bool = False,
    tol: float = 1e-9,
    reveal: bool = False,
) -> bool:
    """Call ``fn(**case)`` on each case; compare with ``reference(**case)``; name the mistakes whose
    ``variant(**case)`` the answers match on every case. ``reveal``: a wrong number's message gives
    lorisnb's value on the case (the hand-made public cases, whose values anyone can compute with
    lorisnb); else it says too high or too low and by roughly how much (:func:`how_far`): the
    hidden tests' values, in the grader's feedback, would let a resubmission return them case by case."""
    if not callable(fn):
        fail(f"{what}: expected the function you wrote, got {type(fn).__name__} {_short(fn)}")
    if len(cases) == 0:  # e.g. the default cases emptied by the notebook: nothing would be checked
        raise AnswerError(f"✗ {what}: no case to check it on (the list of cases is empty); it is not graded")
    answers, wrong = [], None
    for k, case in enumerate(cases):
        # numpy numbers, as lorisnb's data are: a division by zero gives inf (and the mistake's hint), not an error
        args = {n: (np.array(v, copy=True) if isinstance(v, np.ndarray) else np.float64(v) if type(v) is float else v)
                for n, v in case.items()}  # fmt: skip
        try:
            got, used = call_watched(fn, args)
        except AnswerError:  # the grader refused the answer (its code used lorisnb): its message as is
            raise
        except NotImplementedError:
            fail(f"{what}: not written yet (the NotImplementedError placeholder is still there)")
        except Exception as exc:  # the learner's code failed: say where and with what
            ambiguous = isinstance(exc, ValueError) and "truth value of an array" in str(exc)
            renamed = isinstance(exc, TypeError) and re.search(
                r"unexpected keyword argument|required positional", str(exc)
            )
            with np.errstate(all="ignore"):
                fail(
                    f"{what} raised {type(exc).__name__}: {exc} on case {k + 1} ({describe(case)})",
                    "elementwise" if ambiguous else "signature" if renamed else None,
                )
        if used is not None:
            fail(
                f"{what} calls lorisnb's own `{used}` (case {k + 1}): it then returns lorisnb's answer "
                "without computing it. Write the formula yourself, with numpy."
            )
        want = reference(**case)
        if boolean:
            got_a = np.asarray(got)
            if got_a.shape != np.shape(want):
                fail(
                    f"{what} returned shape {got_a.shape} on case {k + 1}; expected one value per pose, {np.shape(want)}"
                )
            if got_a.dtype != bool:  # numbers would be truth-tested: 0.3 or -1 would count as correct
                fail(
                    f"{what} returned {got_a.dtype} values on case {k + 1}; expected True/False per pose "
                    "(a comparison such as `ate_m <= eps`, combined with `&`)"
                )
            got = got_a
        elif got is None:
            fail(f"{what} returned None on case {k + 1}: did you forget `return`?")
        else:
            if _is_nan(got):
                gives = f"; lorisnb gives {float(want):.6g}" if reveal else ""
                fail(f"{what} returned NaN on case {k + 1} ({describe(case)}){gives}", "nan")
            got = number(f"{what} on case {k + 1}", got)
        answers.append(got)
        if wrong is None and not same(got, want, tol):
            wrong = (k, got, want)
    if wrong is None:
        return ok(f"{what} matches lorisnb on {len(cases)} case(s)")
    k, got, want = wrong
    mistakes = matching_mistakes(answers, cases, variants, tol)
    if boolean:
        bad = np.flatnonzero(np.asarray(got) != np.asarray(want))
        i = int(bad[0])
        c = cases[k]
        detail = (
            f"{len(bad)} of {len(want)} poses differ on case {k + 1}; e.g. pose {i} with ATE {c['ate_m'][i]:g} m, "
            f"AOE {c['aoe_deg'][i]:g} deg (eps {c['eps']:g} m, phi {c['phi']:g} deg): you say {bool(got[i])}, "
            f"Eq. (1) says {bool(want[i])}"
        )
    else:
        w = float(want)
        close = abs(got - w) <= 1e-4 * max(1.0, abs(w))  # the 6-digit forms would be equal
        why = _why_close(got, w, _on_float32(reference, cases[k]) if close else [])
        if reveal:
            mine, theirs = distinct(got, w)
            detail = f"on case {k + 1} ({describe(cases[k])}) you return {mine}; lorisnb gives {theirs}"
            if close:
                detail += f" (they differ by {abs(got - w):.2g}, more than the tolerance {tol:g}: {why})"
        else:
            detail = f"on case {k + 1} ({describe(cases[k])}) you return {got:.6g}, "
            if close:
                detail += (f"{'too high' if got > w else 'too low'} but close: within 1e-4 of lorisnb's value, not "
                           f"within the tolerance {tol:g} ({why})")  # fmt: skip
            else:
                detail += how_far(got, w, tol)
    fail(f"{what}: {detail}", mistakes)


#: float32 keeps 24 bits: a result computed in it is off by a few of its units in the last place, relative
FLOAT32_REL = 64 * 2.0**-24


def _on_float32(reference: Callable[..., Any], case: Mapping[str, Any]) -> list[float]:
    """lorisnb's value on ``case`` with its float arrays rounded to float32, then with its float numbers
    too: what a formula that casts its inputs to float32 (and computes on in float64) returns."""
    out = []
    for numbers in (False, True):
        c = {
            n: np.asarray(v, np.float32)
            if isinstance(v, np.ndarray) and v.dtype.kind == "f"
            else np.float32(v)
            if numbers and isinstance(v, (float, np.floating))
            else v
            for n, v in case.items()
        }
        try:
            with np.errstate(all="ignore"):
                out.append(float(reference(**c)))
        except (ArithmeticError, ValueError, TypeError, IndexError):
            continue
    return out


def _why_close(got: float, want: float, on_float32: Sequence[float] = ()) -> str:
    """Why a number this close to lorisnb's is still refused: rounded to some decimals, or computed in
    float32: a float32 number within a few float32 units of ``want`` (float32 arithmetic), or lorisnb's
    value on the case's inputs rounded to float32 (``on_float32``, :func:`_on_float32`); else only that
    it is close (an offset of 1e-7 is no float32, whatever its size)."""
    places = next((d for d in range(10) if abs(got - round(want, d)) <= 1e-12 * max(1.0, abs(want))), None)
    if places is not None:
        return f"rounded to {places} decimal(s)? return the number unrounded"
    in_float32 = float(np.float32(got)) == got and abs(got - want) <= FLOAT32_REL * abs(want)
    of_float32 = any(v != want and abs(got - v) <= 1e-12 * max(1.0, abs(v)) for v in on_float32)
    if in_float32 or of_float32:
        return (
            "computed in float32? float32 keeps about 7 significant digits, and the formula checks compare to "
            f"{1e-9:g}: compute in float64 (numpy's default; leave out np.float32 and .astype(np.float32))"
        )
    return (
        "close, but not the formula's value: look for a small term that differs (a constant added or rounded, "
        "a bound one pose off)"
    )


def distinct(a: float, b: float) -> tuple[str, str]:
    """``a`` and ``b`` printed with 6 significant digits, or as many more as it takes to tell them apart."""
    for digits in (6, 9, 12, 17):
        x, y = f"{a:.{digits}g}", f"{b:.{digits}g}"
        if x != y:
            break
    return x, y


def _is_nan(value: Any) -> bool:
    try:
        a = np.asarray(value, float)
    except (TypeError, ValueError):
        return False
    return a.size == 1 and bool(np.isnan(a.reshape(())))
