"""Reruns of a SLAM system, made from one real output: the noise model behind the measured error
rates of the regression gate (``make calibrate``, :mod:`lorisnb.core.stats.regression`).

Running a SLAM system twice on the same recording gives two different trajectories: it starts
tracking a little earlier or later, resumes at another moment after losing track, drops other
frames, drifts differently and jitters. A rerun here is the real estimate with such differences
drawn at random (each size from the distributions of :class:`RerunNoise`), applied by the
trajectory simulator (:func:`lorisnb.core.simulate.simulate`, faults in its order):

1. **start delay**: no pose for the first ``Exp(start_delay_s)`` seconds;
2. **resume delay**: after each gap of the estimate longer than ``gap_s`` (where the system had
   lost track), no pose for a further ``Exp(resume_delay_s)`` seconds;
3. **dropouts**: ``Poisson(dropouts_per_min x minutes)`` intervals of ``Exp(dropout_s)`` seconds
   without output, at uniform times;
4. **drift** growing with the distance travelled along a random horizontal direction, reaching
   ``|N(0, drift)|`` times the estimate's own error (its ATE RMSE, which the caller passes) at the
   end: reruns of an accurate system stay close, those of a drifting one differ by as much as it
   drifts;
5. **jitter**: white noise on positions (``jitter_m``, per axis) and orientations (``jitter_deg``);
6. **lost for good** (``lost_rest``, a probability): tracking lost at a uniform time and never
   regained, the heavy tail of real reruns.

Units: seconds, metres, degrees. Deterministic for a seed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lorisnb.core.simulate import Faults, simulate
from lorisnb.core.spec.validate import finite
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.errors import ValidationError


@dataclass(frozen=True)
class RerunNoise:
    """How reruns of one system differ: the scale of each difference (see the module docstring).
    The defaults give two reruns of the icra20 systems about the median differences of their real
    rerun pairs (|dCR| 0.016, |log ATE ratio| 0.18; ``make calibrate`` prints both)."""

    start_delay_s: float = 3.0
    resume_delay_s: float = 1.0
    gap_s: float = 1.0
    dropouts_per_min: float = 0.8
    dropout_s: float = 1.0
    drift: float = 2.0
    jitter_m: float = 0.003
    jitter_deg: float = 0.1
    lost_rest: float = 0.0

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            v = finite(name, value, "a scale of the rerun noise")
            if v < 0 or (name == "lost_rest" and v > 1):  # a spread, a rate or a probability
                raise ValidationError(f"RerunNoise({name}={value!r}): expected a number >= 0"
                                      + (" and <= 1 (a probability)" if name == "lost_rest" else ""))  # fmt: skip


def rerun(estimate: Trajectory, noise: RerunNoise, seed: int, error_m: float | None = None) -> Trajectory:
    """One rerun of the system that produced ``estimate`` (its own frame and stamps, seconds).
    ``error_m``: the size of the estimate's own error (its ATE RMSE, metres): a rerun drifts by
    ``|N(0, drift)|`` times that (reruns of an accurate system stay close); None: no drift."""
    n = len(estimate)
    if n < 2:
        return estimate
    rng = np.random.default_rng(seed)
    rel = np.asarray(estimate.stamps, float) - float(estimate.stamps[0])
    duration = float(rel[-1])
    lost: list[tuple[float, float]] = []
    gaps = np.flatnonzero(np.diff(rel) > noise.gap_s)
    for g in gaps:  # resume later after each loss of tracking
        start = float(rel[g + 1])
        lost.append((start, start + float(rng.exponential(noise.resume_delay_s)) + 1e-9))
    k = rng.poisson(noise.dropouts_per_min * duration / 60.0)
    for a in rng.uniform(0.0, duration, k):
        lost.append((float(a), float(a) + float(rng.exponential(noise.dropout_s)) + 1e-9))
    if noise.lost_rest and rng.uniform() < noise.lost_rest:
        lost.append((float(rng.uniform(0.0, duration)), np.inf))
    lost = [(a, b) for a, b in lost if a < duration and b > a]
    delay = min(float(rng.exponential(noise.start_delay_s)) if noise.start_delay_s else 0.0, 0.5 * duration)
    faults = Faults(
        init_delay_s=delay,
        lost=tuple(lost),
        drift_per_m=0.0
        if error_m is None
        else abs(float(rng.normal(0.0, noise.drift))) * error_m / max(estimate.path_length, 1e-9),
        position_noise_m=noise.jitter_m,
        orientation_noise_deg=noise.jitter_deg,
        seed=int(rng.integers(2**31)),
    )
    out = simulate(estimate, faults)
    return Trajectory.from_checked(out.stamps, out.positions, out.quaternions, None, {**estimate.meta, "rerun": seed})
