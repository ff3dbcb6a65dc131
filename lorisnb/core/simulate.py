"""A trajectory simulator for teaching: from a real ground-truth sequence, an "estimate" with
controlled, documented faults. Deterministic for a given seed, vectorized, and labelled as
simulated everywhere (``meta["simulated"] = True``, the algorithm name ``simulated: ...`` and a
``simulated`` column in its tables).

Faults (all optional; applied in this order):

1. **drift**: the heading turns by ``yaw_drift_deg_per_m`` per metre travelled (the path bends),
   and positions wander by ``drift_per_m`` metres per metre travelled along a fixed random
   horizontal direction;
2. **scale** error: positions multiplied by ``scale`` about the start;
3. **white noise** on positions (``position_noise_m``, standard deviation per axis) and on
   orientations (``orientation_noise_deg``, standard deviation of a random rotation vector);
4. **wrong re-localization** at ``wrong_reloc_at_s`` (seconds from the start): from then on, every
   pose is moved by ``wrong_reloc_offset_m`` and turned by ``wrong_reloc_yaw_deg`` about the
   vertical axis through the pose at that time (a jump to a wrong pose that persists);
5. **output gaps**: nothing before ``init_delay_s`` (delayed initialization) and nothing inside the
   ``lost`` intervals ``[(start_s, end_s), ...]`` (tracking loss);
6. a lower **output rate** ``rate_hz`` (the first pose of each 1/rate bin is kept);
7. a **clock offset** ``clock_offset_s`` added to the stamps.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from lorisnb.core.pipeline.model import FileErrors, ResultFile
from lorisnb.core.pipeline.sessions import compute_errors
from lorisnb.core.spec import validate
from lorisnb.core.spec.validate import finite, positive
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.errors import ValidationError


@dataclass(frozen=True)
class Faults:
    """What goes wrong in a simulated estimate (units in the names: m, deg, s, Hz)."""

    position_noise_m: float = 0.0
    orientation_noise_deg: float = 0.0
    drift_per_m: float = 0.0
    yaw_drift_deg_per_m: float = 0.0
    scale: float = 1.0
    init_delay_s: float = 0.0
    lost: tuple[tuple[float, float], ...] = field(default_factory=tuple)
    wrong_reloc_at_s: float | None = None
    wrong_reloc_offset_m: tuple[float, float, float] = (3.0, 0.0, 0.0)
    wrong_reloc_yaw_deg: float = 45.0
    rate_hz: float | None = None
    clock_offset_s: float = 0.0
    seed: int = 0

    def __post_init__(self) -> None:
        """Check every value as a learner would type it; each mistake gets a message saying what to write."""
        for name in ("position_noise_m", "orientation_noise_deg", "drift_per_m", "init_delay_s"):
            v = finite(name, getattr(self, name), _UNITS[name])
            if v < 0:
                raise ValidationError(
                    f"Faults({name}={getattr(self, name)!r}): expected a number >= 0 ({_UNITS[name]})"
                )
        for name in ("yaw_drift_deg_per_m", "wrong_reloc_yaw_deg", "clock_offset_s"):
            finite(name, getattr(self, name), _UNITS[name])
        positive("scale", self.scale, "times the true size (1 = no scale error)")
        if self.rate_hz is not None:
            positive("rate_hz", self.rate_hz, "Hz (None keeps every pose)")
        if self.wrong_reloc_at_s is not None:
            finite("wrong_reloc_at_s", self.wrong_reloc_at_s, "seconds from the start (None: no wrong re-localization)")
        offset = self.wrong_reloc_offset_m
        if isinstance(offset, (str, bytes)) or not hasattr(offset, "__len__") or len(offset) != 3:
            raise ValidationError(
                f"Faults(wrong_reloc_offset_m={offset!r}): expected three numbers (x, y, z) in metres, e.g. (3.0, 0.0, 0.0)"
            )
        for v in offset:
            finite("wrong_reloc_offset_m", v, "metres")
        if not isinstance(self.seed, (int, np.integer)):  # a whole number, not "3" or 3.0
            raise ValidationError(f"Faults(seed={self.seed!r}): expected a whole number >= 0")
        object.__setattr__(self, "seed", validate.seed(self.seed, "Faults(seed)"))
        object.__setattr__(self, "lost", lost_intervals(self.lost))

    def describe(self) -> str:
        """A short label of the faults that are on."""
        on = [
            f"{k}={v}"
            for k, v in asdict(self).items()
            if k != "seed"
            and v != getattr(Faults(), k)
            and not (k.startswith("wrong_reloc_") and self.wrong_reloc_at_s is None)
        ]
        return ", ".join(on) if on else "no faults"


_UNITS = {
    "position_noise_m": "metres",
    "orientation_noise_deg": "degrees",
    "drift_per_m": "metres per metre travelled",
    "init_delay_s": "seconds",
    "yaw_drift_deg_per_m": "degrees per metre travelled",
    "wrong_reloc_yaw_deg": "degrees",
    "clock_offset_s": "seconds",
}

_LOST_EXAMPLE = "e.g. lost=((15.0, 35.0),) for one interval, lost=((5, 10), (30, 40)) for two"


def lost_intervals(lost: object) -> tuple[tuple[float, float], ...]:
    """``Faults.lost`` checked and normalized: a tuple of ``(start_s, end_s)`` pairs with
    start < end, in seconds from the start of the sequence. The usual slips get their own
    message: one pair not wrapped in a tuple (``lost=(15, 35)``), a reversed interval
    (``(35, 15)``, which would silently remove nothing), an empty one, text or NaN."""
    if lost is None:
        return ()
    if isinstance(lost, (str, bytes)) or not hasattr(lost, "__iter__"):
        raise ValidationError(f"Faults(lost={lost!r}): expected a tuple of (start_s, end_s) pairs; {_LOST_EXAMPLE}")
    items = list(lost)
    if len(items) == 2 and all(isinstance(v, (int, float, np.number)) and not isinstance(v, bool) for v in items):
        a, b = items
        raise ValidationError(
            f"Faults(lost={lost!r}): one interval must still be wrapped in a tuple of intervals: "
            f"write lost=(({a}, {b}),) (note the trailing comma)"
        )
    out = []
    for k, item in enumerate(items):
        if isinstance(item, (str, bytes)) or not hasattr(item, "__len__") or len(item) != 2:
            raise ValidationError(
                f"Faults(lost=...): interval {k + 1} is {item!r}; expected a pair (start_s, end_s); {_LOST_EXAMPLE}"
            )
        a = finite("lost start", item[0], "seconds from the start of the sequence")
        b = item[1]
        b = np.inf if isinstance(b, (int, float)) and b == np.inf else finite("lost end", b, "seconds (or inf)")
        if a < 0:
            raise ValidationError(
                f"Faults(lost=...): interval {k + 1} {item!r} starts before 0 s; times are seconds from the start"
            )
        if b <= a:
            raise ValidationError(
                f"Faults(lost=...): interval {k + 1} {item!r} ends before it starts (or is empty), so it would remove "
                f"nothing; write (start_s, end_s) with start < end, e.g. ({min(a, b)}, {max(a, b)})"
            )
        out.append((float(a), float(b)))
    return tuple(out)


def _within(faults: Faults, duration: float) -> None:
    """Refuse fault times (seconds from the start) after the end of a sequence lasting ``duration``
    seconds: such a loss interval or wrong re-localization would change nothing, such an
    initialization delay would leave no pose; most often they are stamps typed for seconds."""
    late = [f"lost interval ({a:.1f}, {b:.1f})" for a, b in faults.lost if a > duration]
    if faults.wrong_reloc_at_s is not None and faults.wrong_reloc_at_s > duration:
        late.append(f"wrong_reloc_at_s={faults.wrong_reloc_at_s:.1f}")
    if faults.init_delay_s > duration:
        late.append(f"init_delay_s={faults.init_delay_s:.1f}")
    if late:
        raise ValidationError(
            f"Faults({', '.join(late)}): after the end of the sequence, which lasts {duration:.1f} s. Fault times are "
            f"seconds from the start of the sequence (0 to {duration:.1f}), not stamps; a fault after the end would "
            "change nothing (an init delay would leave no pose: lost=((0, inf),) says 'no output at all')"
        )


def simulate(gt: Trajectory, faults: Faults = Faults()) -> Trajectory:
    """An estimate of ``gt`` with the given faults (see the module docstring). Deterministic for
    ``faults.seed``; the result's ``meta`` says ``simulated: True`` and lists the faults. A fault
    time (seconds from the start) after the end of ``gt`` is a ValidationError."""
    from scipy.spatial.transform import Rotation  # here: a simulation, not the evaluation's path

    rng = np.random.default_rng(faults.seed)
    t = np.array(gt.stamps, float)  # copies: the ground truth is never modified
    p = np.array(gt.positions, float)
    rot = gt.rotations()
    n = len(t)
    rel = t - t[0] if n else t
    if n:
        _within(faults, float(rel[-1]))
    step = np.linalg.norm(np.diff(p, axis=0), axis=1) if n > 1 else np.zeros(0)
    dist = np.concatenate(([0.0], np.cumsum(step))) if n else np.zeros(0)

    # 1. drift: bend the path by the heading error and add a wander along a fixed direction
    if n > 1 and faults.yaw_drift_deg_per_m:
        yaw = Rotation.from_euler("z", (np.radians(faults.yaw_drift_deg_per_m) * dist)[:, None])
        inc = yaw[1:].apply(np.diff(p, axis=0))
        p = np.vstack([p[:1], p[:1] + np.cumsum(inc, axis=0)])
        rot = yaw * rot
    if faults.drift_per_m:
        ang = rng.uniform(0, 2 * np.pi)
        p = p + faults.drift_per_m * dist[:, None] * np.array([np.cos(ang), np.sin(ang), 0.0])
    # 2. scale about the start
    if faults.scale != 1.0 and n:
        p = p[:1] + faults.scale * (p - p[:1])
    # 3. white noise
    if faults.position_noise_m:
        p = p + rng.normal(scale=faults.position_noise_m, size=p.shape)
    if faults.orientation_noise_deg and n:
        rot = rot * Rotation.from_rotvec(np.radians(faults.orientation_noise_deg) * rng.normal(size=(n, 3)))
    # 4. wrong re-localization: a rigid jump that persists
    if faults.wrong_reloc_at_s is not None and n:
        after = rel >= faults.wrong_reloc_at_s
        if after.any():
            k = int(np.flatnonzero(after)[0])
            turn = Rotation.from_euler("z", faults.wrong_reloc_yaw_deg, degrees=True)
            pivot = p[k].copy()
            p[after] = pivot + turn.apply(p[after] - pivot) + np.asarray(faults.wrong_reloc_offset_m, float)
            rot = Rotation.concatenate([rot[~after], turn * rot[after]]) if (~after).any() else turn * rot
    # 5. output gaps, 6. lower rate
    keep = rel >= faults.init_delay_s
    for a, b in faults.lost:
        keep &= ~((rel >= a) & (rel < b))
    if faults.rate_hz:
        bins = np.floor(rel * faults.rate_hz)
        first_in_bin = np.concatenate(([True], bins[1:] != bins[:-1]))
        keep &= first_in_bin
    meta = {"simulated": True, "faults": asdict(faults), "label": f"simulated: {faults.describe()}"}
    # 7. clock offset
    return Trajectory(
        t[keep] + faults.clock_offset_s, p[keep], rot.as_quat()[keep] if n else np.zeros((0, 4)), None, meta
    )


def simulated_result(
    groundtruth: ResultFile,
    faults: Faults | Mapping[int, Faults],
    seqs: Sequence[int] | None = None,
    name: str | None = None,
) -> ResultFile:
    """An in-memory OpenLORIS result file whose sequences are simulated from ``groundtruth``
    (in ``base_link``): ``faults`` for every sequence, or one Faults per sequence number. Its
    header says ``simulated: true`` and names the faults."""
    seqs = (
        list(seqs)
        if seqs is not None
        else (sorted(faults) if isinstance(faults, Mapping) else sorted(groundtruth.sequences))
    )
    scene = groundtruth.header.get("scene", "unknown")
    have = ", ".join(str(q) for q in sorted(groundtruth.sequences))
    if not seqs:
        raise ValidationError(f"seqs: an empty list; expected sequence numbers of {scene} ({have})")
    for q in seqs:
        if q not in groundtruth.sequences:
            raise ValidationError(
                f"sequence {q!r}: the ground truth of {scene} has sequences {have}; choose among them"
            )
    if isinstance(faults, Mapping):
        missing = [q for q in seqs if q not in faults]
        if missing:
            raise ValidationError(
                f"faults: no Faults for sequence(s) {missing}; the mapping has {sorted(faults)}. "
                "Give one Faults per simulated sequence, e.g. {1: Faults(), 2: Faults(init_delay_s=20)}"
            )
    per = {q: (faults[q] if isinstance(faults, Mapping) else faults) for q in seqs}
    for q, f in per.items():
        if not isinstance(f, Faults):
            raise ValidationError(
                f"faults for sequence {q}: expected a Faults(...) object, got {type(f).__name__} {f!r}"
            )
    sequences = {}
    for q in seqs:  # a few sequences
        try:
            sequences[q] = simulate(groundtruth.sequences[q], per[q])
        except ValidationError as exc:
            raise ValidationError(f"{scene}-{q}: {exc}") from None
    label = (
        f"simulated: {name}"
        if name
        else "simulated: "
        + "; ".join(f"seq {q}: {per[q].describe()}" if len(seqs) > 1 else per[q].describe() for q in seqs)
    )
    header = {"scene": scene, "frame": "base_link", "simulated": "true", "algorithm": label}
    return ResultFile(
        path=Path("simulated") / f"{scene}.txt",
        header=header,
        header_lines={k: 0 for k in header},
        sequences=sequences,
        seq_info={q: {} for q in seqs},
        seq_lines={q: 0 for q in seqs},
        removed_repeats={q: 0 for q in seqs},
    )


def simulated_errors(
    groundtruth: ResultFile,
    faults: Faults | Mapping[int, Faults],
    seqs: Sequence[int] | None = None,
    name: str | None = None,
    mode: str = "auto",
    scale: bool = False,
) -> FileErrors:
    """Simulate and evaluate with the real pipeline (:func:`lorisnb.core.pipeline.sessions.compute_errors`):
    the algorithm is labelled ``simulated: ...`` and the suite ``simulated``. Several sequences
    are evaluated in lifelong mode (aligned on the first) unless ``mode="per-seq"``."""
    res = simulated_result(groundtruth, faults, seqs, name)
    label = res.header["algorithm"]
    return compute_errors(res, groundtruth, algorithm=label, file=label, suite="simulated", mode=mode, scale=scale)


def simulated_trials(
    groundtruth: ResultFile,
    algorithms: Mapping[str, Faults],
    trials: int = 5,
    seqs: Sequence[int] | None = None,
    mode: str = "per-seq",
) -> list[FileErrors]:
    """Repeated runs of simulated algorithms: for each name and faults, ``trials`` runs that differ
    only in the random seed (``faults.seed + k`` for trial k = 1..trials), evaluated with the real
    pipeline. Labelled ``simulated: NAME``; ``FileErrors.trial`` holds k."""
    out = []
    for name, faults in algorithms.items():  # a few algorithms x trials, never poses
        for k in range(1, trials + 1):
            fe = simulated_errors(groundtruth, replace(faults, seed=faults.seed + k), seqs, name=name, mode=mode)
            fe.trial = k
            out.append(fe)
    return out
