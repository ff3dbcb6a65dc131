"""Each plausibility warning, with a real-looking file (issue #7)."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest
from helpers import errors_of

import lorisnb as ln
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.errors import LorisWarning
from lorisnb.io import load_groundtruth, read_openloris

ORB_CAFE = "per-seq/orbslam2_rgbd/cafe_1_1_orbslam2-original.txt"


def _rewrite(src, dst, header=None, stamp=lambda t: t):
    """A copy of a real result file with some header values replaced and stamps transformed."""
    out = []
    for line in src.read_text().splitlines():
        key = line.split(":")[0].strip()
        if header and ":" in line and key in header:
            out.append(f"{key}: {header[key]}")
        elif line[:1].isdigit():
            parts = line.split()
            out.append(" ".join([repr(stamp(float(parts[0])))] + parts[1:]))
        else:
            out.append(line)
    dst.write_text("\n".join(out) + "\n")
    return dst


def _warned(path, **kw) -> list[str]:
    """The warnings a user sees evaluating ``path`` (lorisnb.evaluate gives the checks the spans of
    every ground-truth sequence in the data)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        ev = ln.evaluate(path, **kw)
    assert not ev.failures, ev.failures
    msgs = [str(w.message) for w in caught]
    assert set(ev.warnings) <= set(msgs)
    return msgs


def test_nanosecond_stamps(icra20, tmp_path):
    f = _rewrite(icra20 / ORB_CAFE, tmp_path / "ns.txt", stamp=lambda t: round(t * 1e9))
    msgs = _warned(f)
    assert any("look like nanoseconds; divide them by 1e+09" in m for m in msgs)


def test_clock_offset_of_one_hour(icra20, tmp_path):
    f = _rewrite(icra20 / ORB_CAFE, tmp_path / "tz.txt", stamp=lambda t: t + 3600.0)
    msgs = _warned(f)
    m = next(m for m in msgs if "no estimate stamp falls inside" in m)
    assert "+3600" in m and "time-zone" in m and "1560004885.4" in m


def test_stamps_of_another_scene(icra20, tmp_path):
    f = _rewrite(icra20 / ORB_CAFE, tmp_path / "scene.txt", header={"scene": "home"})
    msgs = _warned(f)
    assert any("They fall in the span of cafe-1" in m for m in msgs)


def test_unpadded_nanoseconds_and_repair(icra20):
    f = icra20 / "lifelong/maslam/cafe.txt"
    msgs = _warned(f)
    assert any("nanoseconds written without zero padding" in m and "1560004886.013218880" in m for m in msgs)
    repaired = _warned(f, repair_stamps=True)
    assert not any("not increasing" in m for m in repaired)
    assert all(np.all(np.diff(t.stamps) > 0) for t in read_openloris(f, repair_stamps=True).sequences.values())


def test_frame_that_does_not_match(icra20, tmp_path):
    f = _rewrite(icra20 / ORB_CAFE, tmp_path / "frame.txt", header={"frame": "base_link"})
    msgs = _warned(f)
    assert any("header says frame 'base_link', but the orientations fit 'd400_" in m for m in msgs)
    assert not any("orientations fit" in m for m in _warned(icra20 / ORB_CAFE))


def test_scale_far_from_one_without_scale(icra20):
    msgs = _warned(icra20 / "per-seq/dso/corridor-1-1-all.txt", scale=False)
    assert any("best-fitting scale is 4.0" in m and "--scale" in m for m in msgs)
    assert not any(
        "best-fitting scale" in m for m in _warned(icra20 / "per-seq/dso/corridor-1-1-all.txt", scale="auto")
    )


@pytest.mark.parametrize("f", ["per-seq/dso/corridor-1-3-all.txt", "per-seq/dso/market-1-1-all.txt"])
def test_monocular_files_aligned_without_scale_by_default_are_warned(icra20, f):
    """dso's real outputs: best-fit scales of 9.9 and 16.7 whose Sim(3) gain is under the scale
    check's (ATE 9.78 -> 4.39 m, 19.6 -> 11.6 m), yet SE(3) numbers of a monocular method mean
    little: said whenever the default alignment is used, never when the user chose one."""
    msgs = _warned(icra20 / f)
    assert any("dso is monocular" in m and "--scale auto" in m for m in msgs), msgs
    for kw in ({"scale": "auto"}, {"scale": False}, {"align": "se3"}):
        assert not any("is monocular" in m for m in _warned(icra20 / f, **kw)), kw
    assert not any("is monocular" in m for m in _warned(icra20 / ORB_CAFE))


def test_groundtruth_gap_longer_than_bracket(icra20):
    gt = load_groundtruth("cafe")
    t = gt.sequences[1]
    rel = t.stamps - t.stamps[0]
    keep = ~((rel > 20) & (rel < 22.5))
    holed = dataclasses.replace(gt, sequences={**gt.sequences, 1: t.subset(keep)})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        errors_of(icra20 / ORB_CAFE, holed)
    msgs = [str(w.message) for w in caught]
    assert any("1 gap(s) longer than the 0.5 s association bracket (longest 2.5" in m for m in msgs)
    assert isinstance(t, Trajectory)


@pytest.mark.parametrize("f", [ORB_CAFE, "lifelong/vins_mono_color_imu_with_loop/home-1.txt"])
def test_clean_files_raise_no_plausibility_warning(icra20, f):
    msgs = _warned(icra20 / f)
    assert not any(
        k in m for m in msgs for k in ("nanoseconds", "time span", "orientations fit", "best-fitting", "gap")
    )


def test_quaternions_written_w_first(icra20, tmp_path):
    """A file written 'stamp x y z qw qx qy qz' gives AOE near 180 deg: lorisnb says why."""
    out = []
    for line in (icra20 / ORB_CAFE).read_text().splitlines():
        parts = line.split()
        if line[:1].isdigit():
            parts = parts[:-4] + [parts[-1]] + parts[-4:-1]
        out.append(" ".join(parts))
    f = tmp_path / "wxyz" / "cafe.txt"
    f.parent.mkdir()
    f.write_text("\n".join(out) + "\n")
    msgs = _warned(f)
    assert any("look like 'qw qx qy qz' instead of 'qx qy qz qw'" in m for m in msgs), msgs
    assert not any("'qw qx qy qz'" in m for m in _warned(icra20 / ORB_CAFE))


def test_quaternions_written_w_last_read_as_euroc(data, tmp_path):
    """The reverse: a EuRoC file (nanosecond stamps, commas) whose quaternions were written
    'qx qy qz qw' is read 'qw qx qy qz', its AOE near 165 deg and its ATE right: lorisnb says so
    (only the other direction was checked), naming the order that fits."""
    t = ln.read_tum(data.tum / "freiburg1_xyz-rgbdslam.txt")
    rows = [f"{round(s * 1e9)}," + ",".join(repr(float(x)) for x in (*p, *q))
            for s, p, q in zip(t.stamps, t.positions, t.quaternions, strict=True)]  # fmt: skip
    f = tmp_path / "xyzw.csv"
    f.write_text("\n".join(rows) + "\n")
    gt = data.tum / "freiburg1_xyz-groundtruth.txt"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        ev = ln.evaluate_pairs(f, gt, fmt="euroc", gt_fmt="tum")
    msgs = [str(w.message) for w in caught]
    assert any("look like 'qx qy qz qw' instead of 'qw qx qy qz'" in m and "real part first" in m for m in msgs), msgs
    assert ev.sequences()["aoe_rmse"].iloc[0] > 150
    with warnings.catch_warnings(record=True) as caught:  # the same poses read right: nothing said
        warnings.simplefilter("always", LorisWarning)
        ln.evaluate_pairs(data.tum / "freiburg1_xyz-rgbdslam.txt", gt, fmt="tum", gt_fmt="tum")
    assert not any("instead of" in str(w.message) for w in caught)


def test_median_above_is_the_median_compared():
    """The orientation checks' trigger skips the median's partition when fewer than half of the
    AOEs exceed the limit: it says what ``np.median(v) > limit`` says on every array (odd and
    even lengths, the limit itself among the values, NaN, infinities, empty)."""
    from lorisnb.core.pipeline.plausibility import median_above

    rng = np.random.default_rng(3)
    cases = [np.zeros(0), np.array([45.0]), np.array([45.0, 45.0]), np.array([44.0, 46.0]), np.array([45.0, 47.0]),
             np.array([np.inf, -np.inf]), np.array([np.nan, 90.0, 90.0]), np.array([np.inf, 50.0])]  # fmt: skip
    for _ in range(3000):
        n = int(rng.integers(1, 12))
        v = rng.choice(
            [0.0, 10.0, 44.999, 45.0, 45.001, 90.0, 180.0, np.inf, np.nan],
            n,
            p=[0.1, 0.1, 0.1, 0.2, 0.1, 0.2, 0.1, 0.05, 0.05],
        )
        cases.append(v)
    cases += [rng.uniform(0, 90, n) for n in (999, 1000, 100_001)]
    above = 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # the median of nothing
        for v in cases:
            expected = bool(np.median(v) > 45.0)
            assert median_above(v, 45.0) is expected, v
            above += expected
    assert 100 < above < len(cases) - 100  # both answers are exercised


@pytest.mark.parametrize("poses", [12, 20, 40])
def test_a_short_run_whose_alignment_holds_no_rotation_is_said(icra20, tmp_path, poses):
    """The first poses of a real run (a fraction of a second, millimetres apart): their alignment's
    rotation is the positions' noise, so the AOE is large and means nothing. lorisnb says so with the
    lever, instead of checking frames and quaternion orders it cannot tell apart; aligned on the first
    pose (as the note suggests) the AOE is small and nothing is said; the whole run holds its rotation."""
    from lorisnb.core.alignment.geometry import MIN_LEVER

    lines = (icra20 / ORB_CAFE).read_text().splitlines(keepends=True)
    head = next(i for i, line in enumerate(lines) if line[:1].isdigit())
    f = tmp_path / "orb" / "cafe.txt"
    f.parent.mkdir()
    f.write_text("".join(lines[: head + poses]))
    msgs = _warned(f)
    said = [m for m in msgs if "hold the alignment's rotation by a lever of only" in m]
    ev = ln.evaluate(f)
    row = ev.sequences().iloc[0]
    assert row["rotation_lever"] < MIN_LEVER and row["aoe_rmse"] > 45
    assert (
        len(said) == 1 and f"{f}, seq 1: its median AOE is " in said[0] and f"{row['rotation_lever']:.3g} m" in said[0]
    )
    assert not any("'qw qx qy qz'" in m or "best-fitting" in m or "orientations fit" in m for m in msgs), msgs
    first = _warned(f, align_frames=1)
    assert not any("lever of only" in m for m in first)
    assert ln.evaluate(f, align_frames=1).sequences().iloc[0]["aoe_rmse"] < 5
    assert not any("lever of only" in m for m in _warned(icra20 / ORB_CAFE))


def test_advice_on_the_sequence_fits_a_pair(data, tmp_path):
    """A TUM pair whose estimate is an hour off its ground truth: the advice names what picks a
    pair's sequence (the ground truth given), where it said 'check the seq: number', a line a TUM
    file does not have; an OpenLORIS file's advice still names its seq: line."""
    gt = data.tum / "fr2_desk_groundtruth.txt"
    lines = [ln_ for ln_ in (data.tum / "fr2_desk_ORB.txt").read_text().splitlines() if ln_[:1].isdigit()]
    est = tmp_path / "est.txt"
    est.write_text("".join(f"{float(ln_.split()[0]) + 3600.0!r} {' '.join(ln_.split()[1:])}\n" for ln_ in lines))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        ev = ln.evaluate_pairs(est, gt, "tum")
    told = [str(w.message) for w in caught if "no estimate stamp falls inside" in str(w.message)]
    told += [m for m in [*ev.warnings, *(str(f) for f in ev.failures)] if "no estimate stamp falls" in m]
    assert told, (ev.warnings, ev.failures)
    assert all("seq: number" not in m and "a pair's ground truth" in m for m in told), told
