"""The formula checks (Eq. 1-4), numbers and choices; re-exported by :mod:`lorisnb.tools.teaching`.

Every formula check runs on small hand-made cases (:data:`CORRECTNESS_CASES`, ...) chosen so that
each typical mistake gives a different number; the labs' hidden tests pass cases taken from real
sequences (:func:`cases_from`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from ...core import metrics
from ...core.model import FileErrors
from ...errors import AnswerError
from ._mistakes import MISTAKES


def _fail(message: str, mistake: str | None = None) -> None:
    hint = f"\nHint ({mistake.replace('_', ' ')}): {MISTAKES[mistake]}" if mistake else ""
    raise AnswerError(f"✗ {message}{hint}")


def _ok(message: str) -> bool:
    print(f"✓ {message}")
    return True


def _same(a: Any, b: Any, tol: float) -> bool:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return a.shape == b.shape and bool(np.all((np.isclose(a, b, rtol=tol, atol=tol)) | (np.isnan(a) & np.isnan(b))))


def _number(what: str, value: Any) -> float:
    if value is Ellipsis:
        _fail(f"{what}: no answer yet (replace the `...` and the NotImplementedError placeholder with your answer)")
    if isinstance(value, (bool, np.bool_)) or value is None:
        _fail(f"{what}: expected a number, got {value!r}")
    try:
        v = float(np.asarray(value, float).reshape(()))
    except (TypeError, ValueError):
        _fail(f"{what}: expected one number, got {type(value).__name__} {value!r}")
    if math.isnan(v):
        _fail(f"{what}: your answer is NaN")
    return v


Variants = Sequence[tuple[str, Callable[..., Any]]]


def _match_mistake(answers: list[Any], variants: Sequence[tuple[str, list[Any]]], tol: float) -> str | None:
    """The first mistake whose values the answers match on every case."""
    for name, values in variants:
        if all(_same(a, v, tol) for a, v in zip(answers, values, strict=True)):
            return name
    return None


def _check_function(
    what: str,
    fn: Callable[..., Any],
    cases: Sequence[Mapping[str, Any]],
    reference: Callable[..., Any],
    variants: Variants,
    boolean: bool = False,
    tol: float = 1e-9,
) -> bool:
    """Call ``fn(**case)`` on each case; compare with ``reference(**case)``; name a mistake whose
    ``variant(**case)`` the answers match on every case."""
    if not callable(fn):
        _fail(f"{what}: expected the function you wrote, got {type(fn).__name__} {fn!r}")
    answers, wrong = [], None
    for k, case in enumerate(cases):
        args = {n: (np.array(v, copy=True) if isinstance(v, np.ndarray) else v) for n, v in case.items()}
        try:
            got = fn(**args)
        except NotImplementedError:
            _fail(f"{what}: not written yet (the NotImplementedError placeholder is still there)")
        except Exception as exc:  # the learner's code failed: say where and with what
            ambiguous = isinstance(exc, ValueError) and "truth value of an array" in str(exc)
            _fail(
                f"{what} raised {type(exc).__name__}: {exc} on case {k + 1} ({_describe(case)})",
                "elementwise" if ambiguous else None,
            )
        want = reference(**case)
        if boolean:
            got_a = np.asarray(got)
            if got_a.shape != np.shape(want):
                _fail(
                    f"{what} returned shape {got_a.shape} on case {k + 1}; expected one value per pose, {np.shape(want)}"
                )
            if got_a.dtype != bool:  # numbers would be truth-tested: 0.3 or -1 would count as correct
                _fail(
                    f"{what} returned {got_a.dtype} values on case {k + 1}; expected True/False per pose "
                    "(a comparison such as `ate_m <= eps`, combined with `&`)"
                )
            got = got_a
        elif got is None:
            _fail(f"{what} returned None on case {k + 1}: did you forget `return`?")
        else:
            got = _number(f"{what} on case {k + 1}", got)
        answers.append(got)
        if wrong is None and not _same(got, want, tol):
            wrong = (k, got, want)
    if wrong is None:
        return _ok(f"{what} matches lorisnb on {len(cases)} case(s)")
    k, got, want = wrong
    mistake = _match_mistake(answers, [(n, vals) for n, v in variants if (vals := _values(v, cases)) is not None], tol)
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
        detail = f"on case {k + 1} ({_describe(cases[k])}) you return {got:.6g}; lorisnb gives {float(want):.6g}"
    _fail(f"{what}: {detail}", mistake)
    return False  # not reached


def _values(variant: Callable[..., Any], cases: Sequence[Mapping[str, Any]]) -> list[Any] | None:
    """A mistake's values on every case (None where the mistake itself cannot be computed)."""
    try:
        with np.errstate(all="ignore"):
            return [variant(**c) for c in cases]
    except (ArithmeticError, ValueError):
        return None


def _describe(case: Mapping[str, Any]) -> str:
    parts = []
    for n, v in case.items():
        if isinstance(v, np.ndarray):
            parts.append(f"{n}: {v.size} values")
        else:
            parts.append(f"{n}={v!r}")
    return ", ".join(parts)


# --- Eq. (1): per-pose correctness ---------------------------------------------------------------

CORRECTNESS_CASES: list[dict[str, Any]] = [
    dict(
        ate_m=np.array([0.0, 0.5, 1.0, 1.2, 3.0, 0.3, 0.2, 0.8, 0.4]),
        aoe_deg=np.array([0.3, 10.0, 5.0, 2.0, 40.0, 30.0, 45.0, 20.0, 1.0]),
        eps=1.0,
        phi=30.0,
    ),
    dict(ate_m=np.array([0.05, 0.1, 0.31, 0.2, 0.0]), aoe_deg=np.array([1.0, 0.2, 3.0, 12.0, 10.0]), eps=0.3, phi=10.0),
    # a tight phi: AOE converted to radians would pass poses up to 28.6 degrees
    dict(ate_m=np.array([0.1, 0.1, 0.1, 0.1, 0.1]), aoe_deg=np.array([0.2, 0.5, 10.0, 40.0, 100.0]), eps=2.0, phi=0.5),
]


def check_correctness(fn: Callable[..., Any], cases: Sequence[Mapping[str, Any]] = CORRECTNESS_CASES) -> bool:
    """``fn(ate_m, aoe_deg, eps, phi)`` -> one boolean per pose, Eq. (1), against
    :func:`lorisnb.core.metrics.correctness` (ATE in metres, AOE and phi in degrees)."""
    variants: Variants = [
        ("and_or", lambda ate_m, aoe_deg, eps, phi: (ate_m <= eps) | (aoe_deg <= phi)),
        ("inclusive", lambda ate_m, aoe_deg, eps, phi: (ate_m < eps) & (aoe_deg < phi)),
        ("inclusive", lambda ate_m, aoe_deg, eps, phi: (ate_m < eps) & (aoe_deg <= phi)),
        ("inclusive", lambda ate_m, aoe_deg, eps, phi: (ate_m <= eps) & (aoe_deg < phi)),
        ("degrees_radians", lambda ate_m, aoe_deg, eps, phi: (ate_m <= eps) & (aoe_deg <= np.radians(phi))),
        ("degrees_radians", lambda ate_m, aoe_deg, eps, phi: (ate_m <= eps) & (np.radians(aoe_deg) <= phi)),
        ("degrees_radians", lambda ate_m, aoe_deg, eps, phi: (ate_m <= eps) & (np.degrees(aoe_deg) <= phi)),
        ("swapped", lambda ate_m, aoe_deg, eps, phi: (ate_m <= phi) & (aoe_deg <= eps)),
        ("ate_only", lambda ate_m, aoe_deg, eps, phi: ate_m <= eps),
        ("aoe_only", lambda ate_m, aoe_deg, eps, phi: aoe_deg <= phi),
    ]
    return _check_function("correctness", fn, cases, metrics.correctness, variants, boolean=True)


# --- Eq. (2) and (3): correct rate -----------------------------------------------------------------


def _gap_case(delta: float) -> dict[str, Any]:
    """Ground truth from 100 s to 160 s; output at 10 Hz from 105 s to 120 s, lost until 130 s, then
    1 Hz from 130 s to 150 s, with runs of wrong poses."""
    stamps = np.concatenate([np.arange(105.0, 120.0, 0.1), np.arange(130.0, 150.5, 1.0)])
    correct = np.ones(len(stamps), bool)
    correct[40:70] = False
    correct[-5:-3] = False
    return dict(stamps=stamps, correct=correct, t_min=100.0, t_max=160.0, delta=delta)


CR_CASES: list[dict[str, Any]] = [
    _gap_case(0.5),
    _gap_case(2.0),
    dict(
        stamps=np.array([0.0, 0.1, 0.2, 0.3, 5.0, 5.1]),
        correct=np.array([True, True, False, True, True, True]),
        t_min=0.0,
        t_max=6.0,
        delta=1.0,
    ),
]


def _cr(stamps: Any, correct: Any, t_min: float, t_max: float, delta: float) -> float:
    """CR as lorisnb computes it (Eq. 2)."""
    return float(metrics.correct_rate(metrics.correct_time(stamps, correct, t_max, delta, t_min), t_min, t_max))


def _cr_t(stamps: Any, correct: Any, t_min: float, t_max: float, delta: float) -> float:
    """CR-T as lorisnb computes it (Eq. 3)."""
    return float(
        metrics.correct_rate_tracking(
            metrics.correct_time(stamps, correct, t_max, delta, t_min), max(stamps[0], t_min), t_max
        )
    )


def _no_last(stamps: Any, correct: Any, t_min: float, t_max: float, delta: float) -> float:
    return float(np.sum(np.minimum(np.diff(stamps), delta) * correct[:-1]) / (t_max - t_min))


def _last_uncapped(stamps: Any, correct: Any, t_min: float, t_max: float, delta: float) -> float:
    held = np.append(np.minimum(np.diff(stamps), delta), t_max - stamps[-1])
    return float(np.sum(held * correct) / (t_max - t_min))


def _held_backward(stamps: Any, correct: Any, t_min: float, t_max: float, delta: float) -> float:
    held = np.minimum(np.diff(np.asarray(stamps, float), prepend=t_min), delta)
    return float(np.sum(held * correct) / (t_max - t_min))


def check_correct_rate(fn: Callable[..., Any], cases: Sequence[Mapping[str, Any]] = CR_CASES) -> bool:
    """``fn(stamps, correct, t_min, t_max, delta)`` -> CR, Eq. (2), against
    :func:`lorisnb.core.metrics.correct_time` and :func:`~lorisnb.core.metrics.correct_rate`."""
    variants: Variants = [
        ("delta_cap", lambda stamps, correct, t_min, t_max, delta: _cr(stamps, correct, t_min, t_max, np.inf)),
        ("cr_vs_crt", _cr_t),
        ("delta_cap", lambda stamps, correct, t_min, t_max, delta: _cr_t(stamps, correct, t_min, t_max, np.inf)),
        ("poses_not_time", lambda stamps, correct, t_min, t_max, delta: float(np.mean(correct))),
        ("wrong_poses_count", lambda stamps, correct, t_min, t_max, delta: _cr(stamps, True, t_min, t_max, delta)),
        ("last_pose", _no_last),
        ("last_pose", _last_uncapped),
        ("held_backward", _held_backward),
        ("gt_span", lambda stamps, correct, t_min, t_max, delta: _cr(stamps, correct, stamps[0], stamps[-1], delta)),
        (
            "gt_span",
            lambda stamps, correct, t_min, t_max, delta: (
                _cr(stamps, correct, t_min, t_max, delta) * (t_max - t_min) / (stamps[-1] - stamps[0])
            ),
        ),  # fmt: skip
        ("fraction", lambda stamps, correct, t_min, t_max, delta: 100.0 * _cr(stamps, correct, t_min, t_max, delta)),
    ]
    return _check_function("correct_rate", fn, cases, _cr, variants)


def check_correct_rate_tracking(fn: Callable[..., Any], cases: Sequence[Mapping[str, Any]] = CR_CASES) -> bool:
    """``fn(stamps, correct, t_min, t_max, delta)`` -> CR-T, Eq. (3), against
    :func:`lorisnb.core.metrics.correct_rate_tracking`."""
    variants: Variants = [
        ("crt_vs_cr", _cr),
        ("delta_cap", lambda stamps, correct, t_min, t_max, delta: _cr_t(stamps, correct, t_min, t_max, np.inf)),
        ("delta_cap", lambda stamps, correct, t_min, t_max, delta: _cr(stamps, correct, t_min, t_max, np.inf)),
        ("wrong_poses_count", lambda stamps, correct, t_min, t_max, delta: _cr_t(stamps, True, t_min, t_max, delta)),
        ("fraction", lambda stamps, correct, t_min, t_max, delta: 100.0 * _cr_t(stamps, correct, t_min, t_max, delta)),
    ]
    return _check_function("correct_rate_tracking", fn, cases, _cr_t, variants)


# --- Eq. (4): re-localization score --------------------------------------------------------------

CSR_CASES: list[dict[str, Any]] = [
    dict(t0=130.0, t_min=100.0, first_correct=True, tau=60.0),
    dict(t0=100.0, t_min=100.0, first_correct=True, tau=60.0),
    dict(t0=130.0, t_min=100.0, first_correct=False, tau=60.0),
    dict(t0=115.0, t_min=100.0, first_correct=True, tau=30.0),
]


def _csr(t0: float, t_min: float, first_correct: bool, tau: float) -> float:
    """CS-R as lorisnb computes it (Eq. 4)."""
    return float(metrics.relocalization_score(t0, t_min, first_correct, tau))


def check_cs_r(fn: Callable[..., Any], cases: Sequence[Mapping[str, Any]] = CSR_CASES) -> bool:
    """``fn(t0, t_min, first_correct, tau)`` -> CS-R, Eq. (4), against
    :func:`lorisnb.core.metrics.relocalization_score`."""
    variants: Variants = [
        ("first_pose", lambda t0, t_min, first_correct, tau: _csr(t0, t_min, True, tau)),
        (
            "tau_inverted",
            lambda t0, t_min, first_correct, tau: float(np.exp(-np.float64(tau) / (t0 - t_min)) * first_correct),
        ),
        ("tau_sign", lambda t0, t_min, first_correct, tau: float(np.exp((t0 - t_min) / tau) * first_correct)),
        ("tau_inverted", lambda t0, t_min, first_correct, tau: float(np.exp(-(t0 - t_min) * tau) * first_correct)),
        ("linear", lambda t0, t_min, first_correct, tau: float((1 - (t0 - t_min) / tau) * first_correct)),
        ("first_pose", lambda t0, t_min, first_correct, tau: float(np.exp(-np.float64(tau) / (t0 - t_min)))),
        ("fraction", lambda t0, t_min, first_correct, tau: 100.0 * _csr(t0, t_min, first_correct, tau)),
    ]
    return _check_function("cs_r", fn, cases, _csr, variants)


# --- numbers: predictions and read-off answers ---------------------------------------------------


def check_value(
    what: str,
    answer: Any,
    expected: float,
    *,
    tol: float = 0.02,
    mistakes: Mapping[str, float] | None = None,
    source: str = "lorisnb",
    fraction: bool = False,
) -> bool:
    """A number the learner predicted or read off: right when within ``tol`` (absolute) of
    ``expected``; else the message gives both, and a hint when the answer is within ``tol`` of
    the value a typical mistake gives (``mistakes``: name in :data:`MISTAKES` -> that value).
    ``fraction``: the answer is a rate in [0, 1] (CR, CR-T, CS-R); one given in percent gets a hint."""
    unknown = [m for m in (mistakes or {}) if m not in MISTAKES]
    if unknown:
        raise ValueError(f"unknown mistake(s) {unknown}; known: {', '.join(MISTAKES)}")
    v = _number(what, answer)
    if abs(v - expected) <= tol:
        return _ok(f"{what}: {v:.4g} (computed by {source}: {expected:.4g})")
    hit = next((m for m, x in (mistakes or {}).items() if abs(v - x) <= tol and abs(x - expected) > tol), None)
    if hit is None and fraction and abs(v / 100.0 - expected) <= tol and v > 1:
        hit = "fraction"  # a rate given in percent
    _fail(f"{what}: you answered {v:.4g}; {source} computes {expected:.4g} (tolerance {tol:g})", hit)
    return False  # not reached


def check_choice(what: str, answer: Any, expected: Any, why: str) -> bool:
    """A choice (a sequence number, an algorithm name, True/False): right when equal to
    ``expected``; else the message says what to look at (``why``)."""
    if answer is Ellipsis or answer is None:
        _fail(f"{what}: no answer yet (replace the `...` and the NotImplementedError placeholder with your answer)")
    kind = _kind(expected)
    if _kind(answer) != kind:  # True == 1 in Python: a yes/no answer to "which sequence?" is not 1
        _fail(f"{what}: you answered {answer!r} ({type(answer).__name__}); expected {kind}. {why}")
    norm = (lambda x: x.strip().lower()) if isinstance(expected, str) and isinstance(answer, str) else (lambda x: x)
    if norm(answer) == norm(expected):
        return _ok(f"{what}: {answer!r}")
    _fail(f"{what}: you answered {answer!r}, which is not right. {why}")
    return False  # not reached


def _kind(value: Any) -> str:
    """What sort of answer ``value`` is: numpy's bools and numbers count as Python's."""
    if isinstance(value, (bool, np.bool_)):
        return "True or False"
    if isinstance(value, (int, float, np.integer, np.floating)):
        return "a number"
    if isinstance(value, str):
        return "a text"
    return f"a {type(value).__name__}"


# --- cases from real sequences (the labs' hidden tests) ------------------------------------------


def cases_from(errors: FileErrors, eps: float, phi: float, delta: float, tau: float) -> dict[str, list[dict[str, Any]]]:
    """Test cases for every formula check made from real evaluated sequences (one per matched
    sequence): ``{"correctness": [...], "correct_rate": [...], "cs_r": [...]}``."""
    out: dict[str, list[dict[str, Any]]] = {"correctness": [], "correct_rate": [], "cs_r": []}
    for e in errors.sequences:
        if e.matched == 0:
            continue
        c = metrics.correctness(e.ate, e.aoe, eps, phi)
        out["correctness"].append(dict(ate_m=e.ate, aoe_deg=e.aoe, eps=eps, phi=phi))
        out["correct_rate"].append(dict(stamps=e.stamps, correct=c, t_min=e.gt_start, t_max=e.gt_end, delta=delta))
        out["cs_r"].append(dict(t0=float(e.stamps[0]), t_min=e.gt_start, first_correct=bool(c[0]), tau=tau))
    return out
