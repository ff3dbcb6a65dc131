"""The trajectory simulator: deterministic, vectorized, labelled, and each fault does what it says."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import errors_of

import lorisnb as ln
from lorisnb.core import score
from lorisnb.core.simulate import Faults, simulate, simulated_errors
from lorisnb.errors import ValidationError
from lorisnb.io import load_groundtruth, read_openloris, write_openloris


@pytest.fixture(scope="module")
def gt_file():
    return load_groundtruth("cafe")


@pytest.fixture(scope="module")
def gt(gt_file):
    return gt_file.sequences[1]


def test_deterministic_and_labelled(gt):
    f = Faults(position_noise_m=0.2, orientation_noise_deg=3, drift_per_m=0.01, seed=42)
    a, b = simulate(gt, f), simulate(gt, f)
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(a.quaternions, b.quaternions)
    assert not np.array_equal(simulate(gt, Faults(position_noise_m=0.2, seed=1)).positions, a.positions)
    assert a.meta["simulated"] is True and a.meta["faults"]["seed"] == 42
    assert a.meta["label"].startswith("simulated: ")


def test_ground_truth_is_never_modified(gt):
    before = gt.positions.copy(), gt.quaternions.copy(), gt.stamps.copy()
    simulate(gt, Faults(wrong_reloc_at_s=10, position_noise_m=0.1, yaw_drift_deg_per_m=1, scale=2))
    for x, y in zip(before, (gt.positions, gt.quaternions, gt.stamps), strict=True):
        np.testing.assert_array_equal(x, y)


def test_each_fault(gt):
    rel = lambda t: t.stamps - gt.stamps[0]  # noqa: E731
    t = simulate(gt, Faults(init_delay_s=10))
    assert rel(t).min() >= 10 and rel(t).min() < 10.1
    t = simulate(gt, Faults(lost=((5, 15), (30, 32))))
    r = rel(t)
    assert not ((r >= 5) & (r < 15)).any() and not ((r >= 30) & (r < 32)).any()
    t = simulate(gt, Faults(rate_hz=2.0))
    assert np.all(np.diff(t.stamps) > 0.45) and len(t) == pytest.approx(2 * gt.duration, abs=2)
    t = simulate(gt, Faults(clock_offset_s=2.5))
    np.testing.assert_allclose(t.stamps, gt.stamps + 2.5)
    t = simulate(gt, Faults(scale=0.5))
    np.testing.assert_allclose(t.positions - gt.positions[0], 0.5 * (gt.positions - gt.positions[0]))
    t = simulate(gt, Faults(wrong_reloc_at_s=20, wrong_reloc_offset_m=(1, 2, 3), wrong_reloc_yaw_deg=0))
    after = rel(t) >= 20
    np.testing.assert_allclose(
        t.positions[after] - gt.positions[after], np.tile([1, 2, 3], (after.sum(), 1)), atol=1e-9
    )
    np.testing.assert_allclose(t.positions[~after], gt.positions[~after])
    t = simulate(gt, Faults(drift_per_m=0.05, seed=3))
    err = np.linalg.norm(t.positions - gt.positions, axis=1)
    assert err[-1] == pytest.approx(0.05 * gt.path_length, rel=1e-9)


def test_metrics_of_simulated_faults(gt_file, gt):
    noise = score(simulated_errors(gt_file, Faults(position_noise_m=0.1, seed=0), seqs=[1])).iloc[0]
    assert noise["ate_rmse"] == pytest.approx(0.1 * np.sqrt(3), rel=0.05)
    delay = score(simulated_errors(gt_file, Faults(init_delay_s=30), seqs=[1]), eps=1, phi=30).iloc[0]
    assert delay["cs_r"] == pytest.approx(np.exp(-30 / 60), abs=2e-3) and delay["cr_t"] == pytest.approx(1.0)
    lost = score(simulated_errors(gt_file, Faults(lost=((15, 35),)), seqs=[1]), eps=1, phi=30).iloc[0]
    assert lost["cr"] == pytest.approx(1 - 19 / gt.duration, abs=2e-3) and lost["ate_rmse"] < 1e-9
    life = score(simulated_errors(gt_file, {1: Faults(), 2: Faults(wrong_reloc_at_s=0.0)}), eps=1, phi=30).set_index(
        "seq"
    )
    assert life.loc[1, "cr"] == pytest.approx(1.0, abs=1e-3) and life.loc[2, ["cr", "cs_r"]].tolist() == [0.0, 0.0]
    fe = simulated_errors(gt_file, Faults(), seqs=[1])
    assert fe.algorithm.startswith("simulated:") and fe.suite == "simulated"


def test_write_openloris_roundtrip_keeps_existing_files(tmp_path, gt):
    t = simulate(gt, Faults(position_noise_m=0.01))
    p = tmp_path / "sim.txt"
    write_openloris(p, {1: t}, "cafe")
    back = read_openloris(p)
    assert back.header["simulated"] == "true" and back.scene == "cafe"
    np.testing.assert_allclose(back.sequences[1].positions, t.positions)
    with pytest.raises(ln.OutputError):
        write_openloris(p, {1: t}, "cafe")
    errs = errors_of(p, algorithm="sim")
    assert errs.sequences[0].matched == len(t)


@pytest.mark.parametrize(
    "kwargs, words",
    [
        (dict(lost=(15, 35)), ["wrapped in a tuple", "lost=((15, 35),)"]),
        (dict(lost=((35, 15),)), ["ends before it starts", "(15.0, 35.0)"]),
        (dict(lost=((15, 15),)), ["ends before it starts"]),
        (dict(lost=((15,),)), ["interval 1", "expected a pair"]),
        (dict(lost=((5, 10), 40)), ["interval 2", "expected a pair"]),
        (dict(lost="15-35"), ["expected a tuple of (start_s, end_s) pairs"]),
        (dict(lost=((-5, 10),)), ["starts before 0 s"]),
        (dict(lost=((float("nan"), 10),)), ["finite number"]),
        (dict(position_noise_m=-0.1), ["position_noise_m", ">= 0", "metres"]),
        (dict(orientation_noise_deg=float("nan")), ["orientation_noise_deg", "finite"]),
        (dict(scale=0), ["scale=0", "positive"]),
        (dict(rate_hz=-1), ["rate_hz", "positive", "Hz"]),
        (dict(wrong_reloc_offset_m=3.0), ["three numbers"]),
        (dict(seed=-1), ["seed", "whole number"]),
        (dict(init_delay_s="late"), ["init_delay_s", "not a number"]),
    ],
)
def test_faults_refuse_a_learners_mistakes_with_a_message(kwargs, words):
    """Each typical slip is a ValidationError (never a silent no-op or a bare TypeError) whose
    message says what to write (issue 26)."""
    with pytest.raises(ValidationError) as exc:
        Faults(**kwargs)
    for w in words:
        assert w in str(exc.value), (w, str(exc.value))


def test_simulated_errors_refuse_unknown_sequences_and_missing_faults(gt_file):
    with pytest.raises(ValidationError, match=r"sequence 7: the ground truth of cafe has sequences 1, 2"):
        simulated_errors(gt_file, Faults(), seqs=[7])
    with pytest.raises(ValidationError, match=r"no Faults for sequence\(s\) \[2\]"):
        simulated_errors(gt_file, {1: Faults()}, seqs=[1, 2])
    with pytest.raises(ValidationError, match=r"expected a Faults\(...\) object, got dict"):
        simulated_errors(gt_file, {1: {"lost": (1, 2)}}, seqs=[1])
    # a valid interval list in any sequence type is normalized, and the simulation honours it
    f = Faults(lost=[[15, 35]])
    assert f.lost == ((15.0, 35.0),)
    fe = simulated_errors(gt_file, f, seqs=[1])
    rel = fe.sequences[0].stamps - gt_file.sequences[1].stamps[0]
    assert not ((rel >= 15) & (rel < 35)).any() and (rel > 35).any()
