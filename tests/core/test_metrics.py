"""Metric functions on hand-checkable inputs (equation numbers from the OpenLORIS-Scene paper)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from lorisnb.core.alignment.association import associate
from lorisnb.core.alignment.geometry import (
    PositionPairs,
    degenerate_alignment,
    official_slerp,
    ros_quaternion_from_matrix,
    umeyama,
)
from lorisnb.core.metrics import openloris as metrics
from lorisnb.core.trajectory.poses import Trajectory


def test_correct_time_cr_crt_by_hand():
    # ground truth spans 0..10 s; poses at 2, 2.5, 5, 9 s; the one at 5 s is wrong
    stamps = np.array([2.0, 2.5, 5.0, 9.0])
    correct = np.array([True, True, False, True])
    # held times: min(0.5,1) + min(2.5,1) + 0 (wrong) + min(1, 1) [runs to t_max = 10]
    ct = metrics.correct_time(stamps, correct, 10.0, 1.0)
    assert ct == pytest.approx(0.5 + 1.0 + 1.0)
    assert metrics.correct_rate(ct, 0.0, 10.0) == pytest.approx(0.25)  # Eq. 2
    assert metrics.correct_rate_tracking(ct, 2.0, 10.0) == pytest.approx(2.5 / 8)  # Eq. 3
    # delta broadcasts: a grid of three windows at once
    np.testing.assert_allclose(
        metrics.correct_time(stamps, correct, 10.0, np.array([0.1, 1.0, 10.0])), [0.3, 2.5, 0.5 + 2.5 + 1.0]
    )


def test_relocalization_score_eq4():
    assert metrics.relocalization_score(30.0, 0.0, True, 60.0) == pytest.approx(np.exp(-0.5))
    assert metrics.relocalization_score(30.0, 0.0, False, 60.0) == 0.0
    assert metrics.relocalization_score(-1.0, 0.0, True, 60.0) == 1.0  # estimate before GT start


def test_correctness_eq1_inclusive_thresholds():
    c = metrics.correctness(np.array([1.0, 1.0, 0.5]), np.array([30.0, 30.1, 0.0]), 1.0, 30.0)
    assert c.tolist() == [True, False, True]


def test_umeyama_recovers_similarity():
    rng = np.random.default_rng(1)
    src = rng.normal(size=(50, 3))
    rot = Rotation.from_euler("xyz", [10, -20, 30], degrees=True)
    dst = 2.5 * rot.apply(src) + [1, 2, 3]
    sim = umeyama(src, dst, with_scale=True)
    assert sim.scale == pytest.approx(2.5)
    np.testing.assert_allclose(sim.rotation, rot.as_matrix(), atol=1e-12)
    np.testing.assert_allclose(sim.apply(src), dst, atol=1e-12)
    assert umeyama(src, dst, with_scale=False).scale == 1.0


def test_position_pairs_share_one_fit_and_its_degeneracy_test_with_the_same_answers():
    """The checks' shared positions (PositionPairs) give umeyama's fits and degenerate_alignment's
    reasons bit for bit: general positions, a line, identical points, two points."""
    rng = np.random.default_rng(7)
    src = rng.normal(size=(40, 3))
    dst = (
        0.7 * Rotation.from_euler("zyx", [5, 50, -10], degrees=True).apply(src)
        + [3, -1, 2]
        + rng.normal(scale=0.01, size=(40, 3))
    )
    line = np.outer(np.linspace(0, 1, 10), [1.0, 2.0, 3.0])
    cases = [(src, dst), (line, line + 1.0), (np.ones((5, 3)), dst[:5]), (src[:2], dst[:2])]
    reasons = []
    for a, b in cases:
        pairs = PositionPairs.of(a, b)
        reasons.append(pairs.degenerate())
        assert reasons[-1] == degenerate_alignment(a, b)
        for scale in (False, True):
            mine, theirs = pairs.fit(scale), umeyama(a, b, scale)
            assert np.array_equal(mine.rotation, theirs.rotation) and mine.scale == theirs.scale
            assert np.array_equal(mine.translation, theirs.translation)
    assert reasons[0] is None and "line" in reasons[1] and "identical" in reasons[2] and "fewer than 3" in reasons[3]


def _gt():
    stamps = np.array([0.0, 0.4, 1.0, 1.3])
    pos = np.array([[0, 0, 0], [4, 0, 0], [10, 0, 0], [13, 0, 0]], float)
    rot = Rotation.from_euler("z", np.array([0, 40, 100, 130])[:, None], degrees=True)
    return Trajectory(stamps, pos, rot.as_quat())


def test_association_bracket_is_strict_and_interpolates():
    gt = _gt()
    # 0.2: bracket [0, .4]; 0.7: bracket [.4, 1] gap .3 ok; 1.3 = last stamp; -0.1 and 1.4 outside
    a = associate(gt, np.array([-0.1, 0.2, 0.7, 1.3, 1.4]), max_gap=0.5)
    np.testing.assert_array_equal(a.est_index, [1, 2, 3])
    np.testing.assert_allclose(a.gt_positions[:, 0], [2.0, 7.0, 13.0])
    np.testing.assert_allclose(a.gt_rotations.as_euler("xyz", degrees=True)[:, 2], [20.0, 70.0, 130.0])
    # with a 0.3 s bracket, 0.7 is 0.3 from both ends: not matched (strict <)
    b = associate(gt, np.array([0.2, 0.7]), max_gap=0.3)
    np.testing.assert_array_equal(b.est_index, [0])


def test_official_slerp_at_a_groundtruth_stamp_takes_the_interval_ending_there():
    gt = _gt()
    exact = associate(gt, np.array([0.4]), official_interpolation=False)
    off = associate(gt, np.array([0.4]), official_interpolation=True)
    # positions identical; the correct slerp gives 40 deg, the official one the start of [0, 0.4]
    np.testing.assert_allclose(off.gt_positions, exact.gt_positions)
    assert exact.gt_rotations.as_euler("xyz", degrees=True)[0, 2] == pytest.approx(40.0)
    assert off.gt_rotations.as_euler("xyz", degrees=True)[0, 2] == pytest.approx(0.0, abs=1e-9)


def test_official_slerp_swaps_weights():
    q1 = Rotation.from_euler("z", 0, degrees=True).as_quat()[None]
    q2 = Rotation.from_euler("z", 90, degrees=True).as_quat()[None]
    q = official_slerp(q1, q2, np.array([0.75]), np.array([0.25]))
    # swapped weights: 1/4 of the way becomes 3/4 (the dot-product slip is harmless here: w1 = w2)
    angle = Rotation.from_quat(q).as_euler("xyz", degrees=True)[0, 2]
    assert angle != pytest.approx(22.5, abs=1.0)


def test_ros_quaternion_from_matrix_matches_rotation_up_to_sign():
    rot = Rotation.random(200, random_state=3)
    q = ros_quaternion_from_matrix(rot.as_matrix())
    np.testing.assert_allclose(np.abs(np.einsum("ij,ij->i", q, rot.as_quat())), 1.0, atol=1e-12)
    trace_pos = np.trace(rot.as_matrix(), axis1=1, axis2=2) > 0
    assert (q[trace_pos, 3] > 0).all()  # trace branch: w positive


def test_rpe_zero_for_rigidly_moved_copy_and_pairs_by_unit():
    rng = np.random.default_rng(0)
    n = 100
    stamps = np.arange(n) * 0.1
    pos = np.cumsum(rng.normal(size=(n, 3)), axis=0)
    rot = Rotation.random(n, random_state=1)
    moved = Rotation.from_euler("z", 33, degrees=True)
    est_pos = moved.apply(pos) + 5.0
    est_rot = moved * rot
    i, j = metrics.rpe_pairs(stamps, pos, 1.0, "s")
    t, r = metrics.rpe(pos, rot, est_pos, est_rot, i, j)
    assert t.max() < 1e-9 and r.max() < 1e-6
    np.testing.assert_array_equal(j - i, 10)
    assert len(i) == n - 10  # no pair whose target stamp lies past the end
    i, j = metrics.rpe_pairs(stamps, pos, 5, "f", all_pairs=False)
    np.testing.assert_array_equal(i, np.arange(0, 95, 5))


def test_rpe_translation_by_hand():
    pos = np.array([[0, 0, 0], [1, 0, 0]], float)
    rot = Rotation.identity(2)
    est = np.array([[0, 0, 0], [1.5, 0, 0]], float)
    t, r = metrics.rpe(pos, rot, est, rot, np.array([0]), np.array([1]))
    assert t[0] == pytest.approx(0.5) and r[0] == pytest.approx(0.0)


def test_groundtruth_in_another_frame_composes_extrinsics():
    from lorisnb.core.alignment.association import groundtruth_in_frame

    gt = _gt()
    via_base = groundtruth_in_frame(gt, "cafe", "t265_fisheye1")
    in_color = groundtruth_in_frame(gt, "cafe", "d400_color")
    again = groundtruth_in_frame(in_color, "cafe", "t265_fisheye1", gt_frame="d400_color")
    np.testing.assert_allclose(again.positions, via_base.positions, atol=1e-12)
    np.testing.assert_allclose((again.rotations().inv() * via_base.rotations()).magnitude(), 0, atol=1e-12)


def test_quaternion_helpers_equal_scipy():
    """The quaternion algebra the evaluation runs on (lorisnb.core.alignment.geometry) is scipy's Rotation:
    products, inverses, angles, vector rotation, matrices both ways and Slerp."""
    from scipy.spatial.transform import Rotation, Slerp

    from lorisnb.core.alignment.geometry import (
        as_quaternions,
        quat_angle_deg,
        quat_conj_multiply,
        quat_conjugate,
        quat_from_matrix,
        quat_multiply,
        quat_normalize,
        quat_rotate,
        quat_to_matrix,
        slerp,
    )

    a, b = Rotation.random(500, random_state=1), Rotation.random(500, random_state=2)
    qa, qb = a.as_quat(), b.as_quat()
    mat = Rotation.from_quat(quat_multiply(qa, qb)).as_matrix()
    np.testing.assert_allclose(mat, (a * b).as_matrix(), atol=1e-14)
    np.testing.assert_allclose(
        Rotation.from_quat(quat_multiply(qa, qb[0])).as_matrix(), (a * b[0]).as_matrix(), atol=1e-14
    )
    np.testing.assert_allclose(Rotation.from_quat(quat_conjugate(qa)).as_matrix(), a.inv().as_matrix(), atol=1e-14)
    # the conjugate folded into the product: the very same numbers (sign changes are exact)
    np.testing.assert_array_equal(quat_conj_multiply(qa, qb), quat_multiply(quat_conjugate(qa), qb))
    np.testing.assert_allclose(quat_angle_deg(qa), a.magnitude() * 180 / np.pi, atol=1e-12)
    v = np.random.default_rng(4).normal(size=(500, 3))
    np.testing.assert_allclose(quat_rotate(qa, v), a.apply(v), atol=1e-13)
    raw = 3.7 * qa  # not unit, as read from a file
    np.testing.assert_allclose(quat_to_matrix(raw), a.as_matrix(), atol=1e-14)
    np.testing.assert_allclose(quat_normalize(raw), qa, atol=1e-15)
    np.testing.assert_allclose(as_quaternions(raw), qa, atol=1e-15)
    np.testing.assert_array_equal(as_quaternions(a), qa)
    # every branch of the matrix conversion: trace largest, and each diagonal element largest
    turns = Rotation.from_euler("xyz", [[0, 0, 10], [179, 0, 0], [0, 179, 0], [0, 0, 179]], degrees=True)
    for r in (a, turns):
        np.testing.assert_allclose(
            quat_from_matrix(r.as_matrix()), Rotation.from_matrix(r.as_matrix()).as_quat(), atol=1e-15
        )
    assert quat_from_matrix(np.eye(3)).shape == (4,)
    # one block (an alignment's, computed on Python floats) gives the vectorized numbers to the bit:
    # every branch of Markley's method, half turns about each axis, NaN
    blocks = np.concatenate([a.as_matrix(), turns.as_matrix(), np.diag([1.0, -1, -1])[None], np.diag([-1.0, 1, -1])[None],
                             np.diag([-1.0, -1, 1])[None], np.full((1, 3, 3), np.nan)])  # fmt: skip
    together = quat_from_matrix(blocks)
    for block, q in zip(blocks, together, strict=True):
        np.testing.assert_array_equal(quat_from_matrix(block), q)
    w = np.random.default_rng(3).uniform(0, 1, 500)
    ours = Rotation.from_quat(slerp(qa, -qb, w))  # signs must not matter
    theirs = Rotation.concatenate([Slerp([0.0, 1.0], Rotation.concatenate([a[k], b[k]]))(w[k]) for k in range(500)])
    np.testing.assert_allclose(ours.as_matrix(), theirs.as_matrix(), atol=1e-12)
    near = Rotation.from_quat(slerp(qa, qa, w))  # equal ends: no division by zero
    np.testing.assert_allclose(near.as_matrix(), a.as_matrix(), atol=1e-14)


def test_rpe_equals_its_definition_with_matrices():
    """metrics.rpe goes through D_k = R(Q_k) R(P_k)^-1; compare with E = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j)
    written out with scipy rotations and 4x4 matrices, on random poses and random pairs."""
    rng = np.random.default_rng(7)
    n = 500
    gt_pos, est_pos = rng.normal(size=(n, 3)) * 20, rng.normal(size=(n, 3)) * 20
    gt_rot, est_rot = Rotation.random(n, random_state=3), Rotation.random(n, random_state=4)
    i = rng.integers(0, n, 2000)
    j = rng.integers(0, n, 2000)

    def matrices(p, r):
        m = np.tile(np.eye(4), (n, 1, 1))
        m[:, :3, :3], m[:, :3, 3] = r.as_matrix(), p
        return m

    q, p = matrices(gt_pos, gt_rot), matrices(est_pos, est_rot)
    e = np.linalg.inv(np.linalg.inv(q[i]) @ q[j]) @ (np.linalg.inv(p[i]) @ p[j])
    t, r = metrics.rpe(gt_pos, gt_rot, est_pos, est_rot, i, j)
    np.testing.assert_allclose(t, np.linalg.norm(e[:, :3, 3], axis=1), rtol=0, atol=1e-9)
    np.testing.assert_allclose(r, Rotation.from_matrix(e[:, :3, :3]).magnitude() * 180 / np.pi, rtol=0, atol=1e-8)
