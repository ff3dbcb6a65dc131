"""Plausibility checks that save users hours: each returns a message (or None) saying what looks
wrong, the numbers behind it, and the likely cause. :func:`lorisnb.core.pipeline.sessions.evaluate_sessions` runs
(through :mod:`lorisnb.core.pipeline.checks`, for every input kind) and issues the messages as warnings; the evaluation itself is never changed by them.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np

from lorisnb.core.alignment.geometry import MIN_LEVER, degenerate_alignment
from lorisnb.core.metrics.relations import median_of
from lorisnb.core.trajectory.poses import Trajectory

#: A best-fit Sim(3) scale outside [1/SCALE_LIMIT, SCALE_LIMIT] that also cuts the ATE RMSE to
#: less than SCALE_GAIN of the SE(3) value suggests a monocular trajectory (a failed run fits odd
#: scales too, but scaling does not fix it).
SCALE_LIMIT = 1.5
SCALE_GAIN = 1 / 3
MIN_PATH = 2.0
#: The median AOE (degrees) above which a sequence's orientations are checked further (frame, quaternion order).
SUSPECT_AOE = 45.0


def _span(t0: float, t1: float) -> str:
    return f"{t0:.3f}..{t1:.3f} s"


#: :func:`time_overlap`'s advice on which sequence the estimate is, in words for every input kind (an
#: OpenLORIS file names it by its ``seq:`` lines, a pair by the ground truth given with it; the
#: challenge says it of a file's name: :data:`lorisnb.tools.challenge.scoring.SEQ_ADVICE`).
SEQ_QUESTION = "is the scene or the sequence wrong (an OpenLORIS file's seq: line, a pair's ground truth)?"
SEQ_CHECK = "check which sequence it is (an OpenLORIS file's seq: line, a pair's ground truth)"


def time_overlap(
    label: str,
    est_stamps: np.ndarray,
    gt_start: float,
    gt_end: float,
    other_spans: Mapping[str, tuple[float, float]] | None = None,
) -> str | None:
    """The estimate's stamps never fall inside the ground truth's time span: say both spans and the
    likely cause (nanoseconds or milliseconds instead of seconds, a clock offset, the wrong scene or
    sequence when its stamps fall in another ground-truth sequence)."""
    t = np.asarray(est_stamps, float)
    if t.size == 0 or ((t >= gt_start) & (t <= gt_end)).any():
        return None
    msg = (
        f"{label}: no estimate stamp falls inside the ground truth's time span (estimate "
        f"{_span(t[0], t[-1])}, ground truth {_span(gt_start, gt_end)})."
    )
    mid = np.median(t)
    ref = 0.5 * (gt_start + gt_end)
    if ref > 0 and mid > 0:
        ratio = mid / ref
        for factor, unit in ((1e9, "nanoseconds"), (1e6, "microseconds"), (1e3, "milliseconds")):
            if 0.5 * factor < ratio < 2 * factor:
                return (
                    msg
                    + f" The estimate's stamps are about {factor:.0e} times larger: they look like {unit}; divide them by {factor:.0e}."
                )
    for name, (a, b) in (other_spans or {}).items():
        if ((t >= a) & (t <= b)).mean() > 0.5:
            return msg + f" They fall in the span of {name} ({_span(a, b)}): {SEQ_QUESTION}"
    offset = t[0] - gt_start
    hours = offset / 3600.0
    zone = (
        f" {offset:+.0f} s is {hours:+.0f} h: a time-zone offset?"
        if abs(hours) >= 0.99 and abs(hours - round(hours)) < 0.01
        else ""
    )
    return msg + (
        f" The estimate starts {offset:+.3f} s from the ground truth: a clock offset (recording time vs "
        f"bag time?) or the wrong sequence; shift the stamps or {SEQ_CHECK}.{zone}"
    )


def groundtruth_gaps(label: str, gt: Trajectory, max_gap: float) -> str | None:
    """Ground truth with gaps longer than the association bracket: estimates inside are not matched."""
    if len(gt) < 2:
        return None
    d = np.diff(gt.stamps)
    big = np.flatnonzero(d > max_gap)
    if big.size == 0:
        return None
    k = big[np.argmax(d[big])]
    return (
        f"{label}: the ground truth has {big.size} gap(s) longer than the {max_gap} s association bracket "
        f"(longest {d[k]:.2f} s after {gt.stamps[k]:.3f} s, {gt.stamps[k] - gt.stamps[0]:.1f} s into the "
        f"sequence); estimates inside a gap are not matched, so they count neither correct nor wrong."
    )


def scale_in_range(scale: float) -> bool:
    """A best-fit scale :func:`scale_far_from_one` never warns about (the rest of its inputs need not
    be computed)."""
    return bool(np.isfinite(scale) and 1 / SCALE_LIMIT <= scale <= SCALE_LIMIT)


def scale_far_from_one(
    label: str,
    scale: float,
    ate_se3: float,
    ate_sim3: float,
    path_m: float | Callable[[], float],
    hint: str = "--scale, or --scale auto for dso/svo",
) -> str | None:
    """The best Sim(3) scale of an SE(3)-aligned trajectory is far from 1 and fixes most of its
    error (ATE RMSE after SE(3) and after Sim(3) alignment, metres), on a path long enough to judge
    (``path_m``, the matched ground truth's length, at least MIN_PATH metres; a function giving it
    is called only when the rest says to warn: a long path costs a pass over its poses)."""
    if not np.isfinite(scale) or scale <= 0 or 1 / SCALE_LIMIT <= scale <= SCALE_LIMIT:
        return None
    if not (np.isfinite(ate_se3) and np.isfinite(ate_sim3)) or ate_sim3 > SCALE_GAIN * ate_se3:
        return None
    if (path_m() if callable(path_m) else path_m) < MIN_PATH:
        return None
    return (
        f"{label}: the best-fitting scale is {scale:.3f}, far from 1, and with it the ATE RMSE drops from "
        f"{ate_se3:.3f} m to {ate_sim3:.3f} m, but the alignment is SE(3) without scale. A monocular "
        f"trajectory? Evaluate with scale ({hint})."
    )


def monocular_without_scale(label: str, algorithm: str, hint: str) -> str:
    """A monocular algorithm (``dso``, ``svo``: :func:`lorisnb.core.pipeline.model.is_monocular`) aligned
    with SE(3) by default: its trajectory's scale is arbitrary, so its ATE and CR measure the scale
    more than the tracking (on the official data dso's best-fit scales run from 0.8 to 17)."""
    return (
        f"{label}: {algorithm} is monocular (its scale is arbitrary), but it was aligned with SE(3) without "
        f"scale, the default; evaluate it with scale ({hint})"
    )


def frame_mismatch(label: str, declared: str, median_aoe: Mapping[str, float]) -> str | None:
    """The estimate's orientations fit another sensor frame far better than the declared one.

    ``median_aoe`` maps each candidate frame to the median AOE (degrees) the sequence gets when its
    ground truth is moved to that frame; the declared frame must be among them."""
    if declared not in median_aoe:
        return None
    own = median_aoe[declared]
    best = min(median_aoe, key=lambda k: median_aoe[k])
    if best == declared or own < SUSPECT_AOE or median_aoe[best] > 10.0:
        return None
    return (
        f"{label}: the header says frame {declared!r}, but the orientations fit {best!r} much better (median "
        f"AOE {median_aoe[best]:.1f} deg against {own:.1f} deg). Is the frame: header right?"
    )


def median_above(values: np.ndarray, limit: float) -> bool:
    """``np.median(values) > limit``, without the median's partition when fewer than half of the
    values exceed ``limit`` (the median then cannot: the upper middle value would not)."""
    v = np.asarray(values, float)
    if not v.size or np.count_nonzero(v > limit) < len(v) // 2:  # (no value: np.median's NaN is not above)
        return False
    return median_of(v) > limit


def quaternion_order(label: str, median_aoe: float, median_aoe_swapped: float, w_first: bool = False) -> str | None:
    """The orientations fit far better when each quaternion is read in the other order (median AOE
    in degrees either way): the file was probably written in it (Eigen's coefficients, ROS messages
    and TUM files use ``x y z w`` last-w; EuRoC and many tools print ``w x y z``). ``w_first``: the
    file was read ``w x y z`` (EuRoC's order) and fits ``x y z w``; else the reverse."""
    if not (np.isfinite(median_aoe) and np.isfinite(median_aoe_swapped)):
        return None
    if median_aoe < SUSPECT_AOE or median_aoe_swapped > 10.0:
        return None
    read, fits = ("'qw qx qy qz'", "'qx qy qz qw'") if w_first else ("'qx qy qz qw'", "'qw qx qy qz'")
    write = (
        "'timestamp_ns,x,y,z,qw,qx,qy,qz' (the real part first)"
        if w_first
        else "'stamp x y z qx qy qz qw' (the real part last)"
    )
    return (
        f"{label}: the quaternions look like {fits} instead of {read}: read that way the median "
        f"AOE drops from {median_aoe:.1f} deg to {median_aoe_swapped:.1f} deg. Write each pose as {write}."
    )


def orientations_permuted(label: str, median_aoe: float, median_aoe_moved: float, written: str) -> str | None:
    """The orientations fit far better with each quaternion's components moved one place, but in the
    direction no order mistake of the file's format explains (``written``: the order it writes,
    ``"xyzw"`` or ``"wxyz"``, or ``""``: none, its rotations are matrices or named fields): the estimate's axes are probably another frame's than the ground
    truth's (a cyclic permutation of the axes, such as a NED ground truth, TartanAir's, against a
    camera-frame estimate, can look like such a move), which an alignment without rotation keeps.
    Not a quaternion-order note: its remedy (rewrite the file in the other order) would be wrong."""
    if not (np.isfinite(median_aoe) and np.isfinite(median_aoe_moved)):
        return None
    if median_aoe < SUSPECT_AOE or median_aoe_moved > 10.0:
        return None
    order = {
        "xyzw": "its format writes 'qx qy qz qw', as it was read",
        "wxyz": "its format writes 'qw qx qy qz', as it was read",
    }.get(written, "its format writes no quaternion")
    return (
        f"{label}: its median AOE is {median_aoe:.1f} deg, and {median_aoe_moved:.1f} deg with each quaternion's "
        f"components moved one place, which no quaternion order explains ({order}): the estimate's orientations are probably in another frame than the ground truth's (axes permuted, "
        "e.g. a ground truth in NED, TartanAir's, against a camera-frame estimate: x right, y down, z forward), "
        "which an alignment without rotation keeps. Give both in one frame (a manifest's [transform], transform= in "
        "Python), or align them (--align se3)."
    )


def rotation_not_held(label: str, median_aoe: float, lever: float, matched: int, fitted_on: str | None = None) -> str:
    """A sequence's AOE is large (its median above :data:`SUSPECT_AOE`) but the matched positions the
    alignment was fitted on hold its rotation by a lever under :data:`~lorisnb.core.alignment.geometry.MIN_LEVER`
    (a short or nearly straight run): the rotation, so the AOE, comes from the positions' noise, and
    no sensor frame or quaternion order can be told apart (those checks are not run). ``fitted_on``:
    the sequence the alignment was fitted on (``seq 1``), when not the one of ``label`` (a lifelong
    file's later sequence); ``lever`` and ``matched`` are that sequence's."""
    whose = f"the alignment was fitted on {fitted_on}, whose" if fitted_on else "its"
    return (
        f"{label}: its median AOE is {median_aoe:.1f} deg, but {whose} {matched} matched positions hold the alignment's "
        f"rotation by a lever of only {lever:.3g} m (under {MIN_LEVER:g} m, 5 mm of position noise turns the fit by "
        "more than a degree): the AOE, and which poses count as correct under phi, come from the alignment more "
        "than from the estimate, and its sensor frame and quaternion order cannot be checked. Evaluate a longer "
        "run, or align on the first pose (--align-frames 1, align_frames=1)."
    )


def degenerate_fit(
    label: str,
    est_positions: np.ndarray,
    gt_positions: np.ndarray,
    with_scale: bool = False,
    applied_to: Sequence[int] = (),
) -> str | None:
    """The alignment was fitted on matched positions that cannot determine a rotation (fewer than
    3, all identical, or all on one line: :func:`lorisnb.core.alignment.geometry.degenerate_alignment`), so
    its rotation, and every error after it, is arbitrary. lorisnb aligns all the same and says so.
    The official tool does too under SE(3), and under Sim(3) (``with_scale``: dso, svo, ``--scale``)
    unless the estimate's positions have no spread at all: its ``umeyama_align`` divides by their
    variance (a scale of NaN) and it stops with ``LinAlgError`` (lorisnb takes the scale 1). An
    arbitrary rotation is each tool's own rounding, so the numbers after it need not be the official
    tool's (a lifelong file whose first sequence has 2 matched poses, with Sim(3): AOE 44.4 deg here,
    32.0 deg there). ``applied_to``: the other sequences whose errors come after this alignment (a
    lifelong file's later sequences with matches), named with it."""
    why = degenerate_alignment(est_positions, gt_positions)
    if why is None:
        return None
    p = np.asarray(est_positions, float)
    if with_scale and len(p) and not np.any(p - p.mean(axis=0)):  # the official variance is 0: 1/0 * 0 = NaN
        official = (
            "the official tool stops on it with Sim(3): its scale divides by the estimate's zero spread, a NaN "
            "alignment, and it fails with LinAlgError; lorisnb takes the scale 1"
        )
        fix = "--align none, or without the scale: --scale off --align-frames 1"
    else:
        official = (
            f"the official tool aligns all the same, with its own arbitrary rotation{' and scale' * with_scale}: "
            "the numbers may differ from its numbers"
        )
        fix = "--align-frames 1, --align none" if not with_scale else "--align none, or --scale off --align-frames 1"
    where = ""
    if applied_to:
        later = [str(k) for k in applied_to]
        named = f"seq {later[0]}" if len(later) == 1 else f"seqs {', '.join(later[:-1])} and {later[-1]}"
        where = f", in this sequence and in {named}, which the lifelong alignment is applied to"
    return (
        f"{label}: the alignment was fitted on {why}, so its rotation is arbitrary and so are the errors "
        f"after it{where} ({official}); check this sequence's output, or evaluate it with the conventions of "
        f"pairs ({fix})."
    )


RPE_UNIT_WORDS = {"s": "s", "f": "frame(s)", "frames": "frame(s)", "m": "m", "deg": "deg", "rad": "rad"}


def no_rpe_pair(label: str, n_pairs: int, stamps: np.ndarray, delta: float, unit: str) -> str | None:
    """A sequence with matched poses (their ``stamps``, seconds) but no RPE pair over ``delta``
    ``unit`` (shorter than the step, or too few poses): its RPE statistics are NaN, said with the
    sequence's span. None when there are pairs or no matched pose (that has its own message)."""
    if n_pairs or not len(stamps):
        return None
    return (
        f"{label}: no RPE pair over {delta:g} {RPE_UNIT_WORDS.get(unit, unit)} (its {len(stamps)} matched pose(s) "
        f"span {float(stamps[-1] - stamps[0]):.3f} s), so its RPE statistics are NaN; the other metrics are "
        "scored. A shorter RPE step (--rpe-delta, rpe_delta=) gives pairs"
    )
