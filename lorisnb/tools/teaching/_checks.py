"""The formula checks (Eq. 1-4), numbers and choices; re-exported by :mod:`lorisnb.tools.teaching`.

Every formula check runs on small hand-made cases (:data:`CORRECTNESS_CASES`, ...) chosen so that
each typical mistake gives a different number; the labs' hidden tests pass cases taken from real
sequences (:func:`cases_from`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from lorisnb.core.metrics import openloris as metrics
from lorisnb.core.pipeline.model import FileErrors
from lorisnb.tools.teaching._grading import Variants, how_far
from lorisnb.tools.teaching._grading import check_function as _check_function
from lorisnb.tools.teaching._grading import fail as _fail
from lorisnb.tools.teaching._grading import number as _number
from lorisnb.tools.teaching._grading import ok as _ok
from lorisnb.tools.teaching._mistakes import MISTAKES

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
    :func:`lorisnb.core.metrics.openloris.correctness` (ATE in metres, AOE and phi in degrees)."""
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
    # uneven intervals, a wrong pose after each correct run, the last interval under delta: a pose's
    # time given to the next pose, or the last pose held for delta, each give their own number
    dict(
        stamps=np.array([10.0, 10.5, 11.0, 14.0, 14.2, 18.0]),
        correct=np.array([True, False, True, True, False, True]),
        t_min=9.0,
        t_max=18.4,
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


# The numerators the typical mistakes compute instead of Eq. (2)'s correct time (seconds):
# (name in MISTAKES, numerator(stamps, correct, t_start, t_max, delta)), t_start the ground truth's first stamp;
# over t_max - t_min for CR, t_max - t0 for CR-T.
_NUMERATORS: list[tuple[str, Callable[..., Any]]] = [
    ("delta_cap", lambda s, c, t_start, t_max, d: np.sum(np.diff(np.append(s, t_max)) * c)),
    ("wrong_poses_count", lambda s, c, t_start, t_max, d: np.sum(np.minimum(np.diff(np.append(s, t_max)), d))),
    ("last_pose", lambda s, c, t_start, t_max, d: np.sum(np.minimum(np.diff(s), d) * c[:-1])),  # the last pose dropped
    ("last_pose", lambda s, c, t_start, t_max, d: np.sum(np.append(np.minimum(np.diff(s), d), t_max - s[-1]) * c)),  # uncapped
    ("last_pose", lambda s, c, t_start, t_max, d: np.sum(np.append(np.minimum(np.diff(s), d), d) * c)),  # held delta
    ("held_backward", lambda s, c, t_start, t_max, d: np.sum(np.minimum(np.diff(s, prepend=t_start), d) * c)),  # t_k - t_{k-1}
    ("held_backward", lambda s, c, t_start, t_max, d: np.sum(np.minimum(np.diff(s), d) * c[1:])),  # the first holds 0
    ("held_delta", lambda s, c, t_start, t_max, d: np.count_nonzero(c) * d),
    ("delta_cut", lambda s, c, t_start, t_max, d: np.sum(np.where(np.diff(np.append(s, t_max)) <= d, np.diff(np.append(s, t_max)), 0) * c)),
]  # fmt: skip


def _over(numerator: Callable[..., Any], tracking: bool) -> Callable[..., float]:
    """A mistaken numerator over CR's denominator (t_max - t_min) or CR-T's (t_max - t0)."""

    def rate(stamps: Any, correct: Any, t_min: float, t_max: float, delta: float) -> float:
        s, c = np.asarray(stamps, float), np.asarray(correct, bool)
        return float(numerator(s, c, t_min, t_max, delta) / (t_max - (max(s[0], t_min) if tracking else t_min)))

    return rate


def _rate_variants(tracking: bool) -> list[tuple[str, Callable[..., Any]]]:
    """The mistakes shared by CR and CR-T: how time is counted, per pose or as a whole."""
    right = _cr_t if tracking else _cr
    return [
        *[(name, _over(num, tracking)) for name, num in _NUMERATORS],
        ("poses_not_time", lambda stamps, correct, t_min, t_max, delta: float(np.mean(correct))),
        ("gt_span", lambda stamps, correct, t_min, t_max, delta: _cr(stamps, correct, stamps[0], stamps[-1], delta)),
        ("gt_span", lambda stamps, correct, t_min, t_max, delta: float(
            metrics.correct_time(stamps, correct, t_max, delta, t_min) / (stamps[-1] - stamps[0]))),
        ("absolute_time", lambda stamps, correct, t_min, t_max, delta: float(
            metrics.correct_time(stamps, correct, t_max, delta, t_min) / t_max)),
        ("fraction", lambda stamps, correct, t_min, t_max, delta: 100.0 * right(stamps, correct, t_min, t_max, delta)),
    ]  # fmt: skip


def check_correct_rate(fn: Callable[..., Any], cases: Sequence[Mapping[str, Any]] = CR_CASES) -> bool:
    """``fn(stamps, correct, t_min, t_max, delta)`` -> CR, Eq. (2), against
    :func:`lorisnb.core.metrics.openloris.correct_time` and :func:`~lorisnb.core.metrics.openloris.correct_rate`."""
    variants: Variants = [
        ("cr_vs_crt", _cr_t),
        ("delta_cap", lambda stamps, correct, t_min, t_max, delta: _cr_t(stamps, correct, t_min, t_max, np.inf)),
        *_rate_variants(tracking=False),
    ]
    return _check_function("correct_rate", fn, cases, _cr, variants, reveal=cases is CR_CASES)


def check_correct_rate_tracking(fn: Callable[..., Any], cases: Sequence[Mapping[str, Any]] = CR_CASES) -> bool:
    """``fn(stamps, correct, t_min, t_max, delta)`` -> CR-T, Eq. (3), against
    :func:`lorisnb.core.metrics.openloris.correct_rate_tracking`."""
    variants: Variants = [
        ("crt_vs_cr", _cr),
        ("delta_cap", lambda stamps, correct, t_min, t_max, delta: _cr(stamps, correct, t_min, t_max, np.inf)),
        *_rate_variants(tracking=True),
    ]
    return _check_function("correct_rate_tracking", fn, cases, _cr_t, variants, reveal=cases is CR_CASES)


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
    :func:`lorisnb.core.metrics.openloris.relocalization_score`."""
    variants: Variants = [
        ("first_pose", lambda t0, t_min, first_correct, tau: _csr(t0, t_min, True, tau)),
        ("absolute_time", lambda t0, t_min, first_correct, tau: float(np.exp(-np.float64(t0) / tau) * first_correct)),
        ("absolute_time", lambda t0, t_min, first_correct, tau: float(np.exp(-np.float64(t0) / tau))),
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
    return _check_function("cs_r", fn, cases, _csr, variants, reveal=cases is CSR_CASES)


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
    ``expected``; else the message says whether the answer is too high or too low and by roughly
    how much (:func:`how_far`), never ``expected`` itself (typed in, it would score without any
    work), and gives a hint when the answer is within ``tol`` of the value a typical mistake gives
    (``mistakes``: name in :data:`MISTAKES` -> that value). A right answer's line gives the
    number ``source`` computed. ``fraction``: the answer is a rate in [0, 1] (CR, CR-T, CS-R); one
    given in percent gets a hint."""
    unknown = [m for m in (mistakes or {}) if m not in MISTAKES]
    if unknown:
        raise ValueError(f"unknown mistake(s) {unknown}; known: {', '.join(MISTAKES)}")
    v = _number(what, answer)
    if abs(v - expected) <= tol:
        return _ok(f"{what}: {v:.4g} (computed by {source}: {expected:.4g})")
    hit = next((m for m, x in (mistakes or {}).items() if abs(v - x) <= tol and abs(x - expected) > tol), None)
    if hit is None and fraction and abs(v / 100.0 - expected) <= tol and v > 1:
        hit = "fraction"  # a rate given in percent
    _fail(f"{what}: you answered {v:.4g}, {how_far(v, expected, tol)} (tolerance {tol:g})", hit)
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
