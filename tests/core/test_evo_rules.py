"""evo's rules reproduced in lorisnb's core (issue 23): association, interpolation, RPE pairs,
pose relations, statistics, time window, projection, origin and scale alignment, downsampling and
the motion filter, each against evo's own Python API (evo 1.38) on the same input, to 1e-9."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from evo.core import filters, sync
from evo.core import metrics as em
from evo.core.trajectory import Plane
from evo.tools import file_interface as fi
from scipy.spatial.transform import Rotation

from lorisnb.core.conventions.evo_options import project_to_plane as lorisnb_project
from lorisnb.core.conventions.evo_sync import (
    evo_associate,
    evo_downsample,
    evo_match_indices,
    evo_motion_filter,
    evo_sync,
    time_window,
)
from lorisnb.core.metrics.pairs import evo_rpe_pairs
from lorisnb.core.metrics.relations import RELATIONS, ape_relation, error_statistics, rpe_relation
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.io import read_tum
from lorisnb.tools.peers.evo_bridge import to_evo

TOL = 1e-9
PAIRS = {
    "fr2_desk": ("fr2_desk_groundtruth.txt", "fr2_desk_ORB.txt"),
    "fr1_xyz": ("freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"),
}
EVO_RELATION = {
    "trans_part": em.PoseRelation.translation_part, "angle_deg": em.PoseRelation.rotation_angle_deg,
    "angle_rad": em.PoseRelation.rotation_angle_rad, "rot_part": em.PoseRelation.rotation_part,
    "full": em.PoseRelation.full_transformation, "point_distance": em.PoseRelation.point_distance,
    "point_distance_error_ratio": em.PoseRelation.point_distance_error_ratio,
}  # fmt: skip
EVO_UNIT = {"frames": em.Unit.frames, "m": em.Unit.meters, "deg": em.Unit.degrees, "rad": em.Unit.radians}


@pytest.fixture(scope="module")
def evo_pairs(data):
    """Both bundled pairs, read by evo and by lorisnb keeping repeated stamps."""
    out = {}
    for name, (g, e) in PAIRS.items():
        out[name] = (
            fi.read_tum_trajectory_file(data.tum / g),
            fi.read_tum_trajectory_file(data.tum / e),
            read_tum(data.tum / g, repeated="keep"),
            read_tum(data.tum / e, repeated="keep"),
        )
    return out


def _random_stamps(rng, n, step, digits=3):
    return np.round(np.cumsum(rng.uniform(0.0, step, n)), digits)


@pytest.mark.parametrize("seed", range(12))
def test_match_indices_equal_evo_sorted_and_unsorted(seed):
    rng = np.random.default_rng(seed)
    s1 = _random_stamps(rng, 150, 0.03)
    s2 = _random_stamps(rng, 200, 0.02)  # rounded: ties and repeated stamps happen
    for offset in (0.0, 0.004, -0.013):
        ours = evo_match_indices(s1, s2, 0.01, offset)
        theirs = sync.matching_time_indices(s1, s2, 0.01, offset)
        assert ours[0].tolist() == theirs[0] and ours[1].tolist() == theirs[1]
    shuffled = rng.permutation(s2)
    ours = evo_match_indices(s1, shuffled, 0.01)
    theirs = sync.matching_time_indices(s1, shuffled, 0.01)
    assert ours[0].tolist() == theirs[0] and ours[1].tolist() == theirs[1]


@pytest.mark.parametrize("name", PAIRS)
@pytest.mark.parametrize("method", ["nearest", "interpolate"])
@pytest.mark.parametrize("offset", [0.0, 0.007])
def test_sync_equals_evo_on_bundled_pairs(evo_pairs, name, method, offset):
    ref, est, gt, es = evo_pairs[name]
    r, e = sync.associate_trajectories(
        ref, est, max_diff=0.01, offset_2=offset, sync_method=sync.SyncMethod.nearest_time if method == "nearest" else sync.SyncMethod.interpolation
    )  # fmt: skip
    g2, e2 = evo_sync(gt, es, method, 0.01, offset)
    assert len(g2) == r.num_poses == len(e2)
    np.testing.assert_array_equal(e2.stamps, e.timestamps)
    np.testing.assert_array_equal(g2.stamps, r.timestamps)
    np.testing.assert_allclose(g2.positions, r.positions_xyz, rtol=0, atol=TOL)
    np.testing.assert_allclose(e2.positions, e.positions_xyz, rtol=0, atol=TOL)
    for ours, theirs in ((g2, r), (e2, e)):
        q = theirs.orientations_quat_wxyz[:, [1, 2, 3, 0]]
        dots = np.abs(np.einsum("ij,ij->i", ours.quaternions / np.linalg.norm(ours.quaternions, axis=1)[:, None],
                                q / np.linalg.norm(q, axis=1)[:, None]))  # fmt: skip
        assert np.all(dots > 1 - 1e-12)


def test_sync_starts_from_the_shorter_trajectory():
    gt_t = np.arange(0.0, 1.0, 0.1)
    est_t = np.array([0.0, 0.001, 0.102, 0.5])  # two estimates nearest to gt 0.0
    gi, ej, short = evo_associate(gt_t, est_t, 0.01)
    assert short == "est" and gi.tolist() == [0, 0, 1, 5] and ej.tolist() == [0, 1, 2, 3]
    gi, ej, short = evo_associate(est_t, gt_t, 0.01)  # the other way round: from the 4 stamps again
    assert short == "gt" and gi.tolist() == [0, 1, 2, 3] and ej.tolist() == [0, 0, 1, 5]


def _synced(evo_pairs, name, align=True):
    ref, est, gt, es = evo_pairs[name]
    r, e = sync.associate_trajectories(ref, est, max_diff=0.01)
    if align:
        e.align(r)
    return r, e


def _lorisnb_arrays(traj):
    return traj.positions_xyz, traj.orientations_quat_wxyz[:, [1, 2, 3, 0]]


@pytest.mark.parametrize("name", PAIRS)
@pytest.mark.parametrize("relation", [r for r in RELATIONS if r != "point_distance_error_ratio"])  # evo_rpe's only
@pytest.mark.thorough
def test_ape_relations_equal_evo(evo_pairs, name, relation):
    r, e = _synced(evo_pairs, name)
    m = em.APE(EVO_RELATION[relation])
    m.process_data((r, e))
    pg, qg = _lorisnb_arrays(r)
    pe, qe = _lorisnb_arrays(e)
    ours = ape_relation(pg, qg, pe, qe, relation)
    np.testing.assert_allclose(ours, m.error, rtol=0, atol=TOL)
    stats = error_statistics(ours)
    for k, v in m.get_all_statistics().items():
        assert stats[k] == pytest.approx(v, rel=TOL, abs=TOL), k


@pytest.mark.parametrize("name", PAIRS)
@pytest.mark.parametrize(
    "delta, unit, all_pairs, from_ref",
    [(1, "frames", False, False), (3, "frames", True, False), (0.5, "m", False, False), (0.5, "m", True, True),
     (0.2, "m", True, False), (10.0, "deg", False, True), (5.0, "deg", True, False), (0.1, "rad", False, False)],
)  # fmt: skip
@pytest.mark.thorough
def test_rpe_pairs_and_relations_equal_evo(evo_pairs, name, delta, unit, all_pairs, from_ref):
    r, e = _synced(evo_pairs, name)
    if name == "fr2_desk" and unit in ("deg", "rad") and all_pairs:
        pytest.skip("quadratic search on 2,900 poses: covered on fr1_xyz")
    pg, qg = _lorisnb_arrays(r)
    pe, qe = _lorisnb_arrays(e)
    src = (pg, qg) if from_ref else (pe, qe)
    i, j = evo_rpe_pairs(*src, delta, unit, all_pairs)
    theirs = em.id_pairs_from_delta((r if from_ref else e).poses_se3, delta, EVO_UNIT[unit], 0.1, all_pairs)
    assert list(zip(i.tolist(), j.tolist(), strict=True)) == theirs
    for relation in RELATIONS:
        m = em.RPE(EVO_RELATION[relation], delta, EVO_UNIT[unit], 0.1, all_pairs, from_ref)
        m.process_data((r, e))
        np.testing.assert_allclose(rpe_relation(pg, qg, pe, qe, i, j, relation), m.error, rtol=0, atol=TOL)


def test_statistics_with_mask_and_empty():
    v = np.array([3.0, 1.0, 2.0, 10.0])
    s = error_statistics(v, v < 5)
    assert s == pytest.approx(dict(rmse=np.sqrt(14 / 3), mean=2.0, median=2.0, std=np.std([3, 1, 2]), min=1.0,
                                   max=3.0, sse=14.0))  # fmt: skip
    assert np.isnan(error_statistics(v, v > 100)["rmse"])


def test_statistics_are_numpys_to_the_bit(evo_pairs):
    """Each statistic is what evo's numpy calls give (np.mean, np.median, np.std, np.min, np.max,
    np.sum of the squares), to the last bit: the real pairs' ATE and AOE, with a diverged pose, an
    infinite one and a NaN among them, and one to eleven values."""
    rng = np.random.default_rng(11)
    series = []
    for name in PAIRS:
        r, e = _synced(evo_pairs, name)
        pg, qg = _lorisnb_arrays(r)
        pe, qe = _lorisnb_arrays(e)
        series += [ape_relation(pg, qg, pe, qe, rel) for rel in ("trans_part", "angle_deg")]
    series += [np.r_[series[0], 1e160], np.r_[series[1], np.inf], np.r_[series[0], np.nan]]
    series += [np.abs(rng.normal(size=n)) * 10.0 ** rng.uniform(-4, 3) for n in range(1, 12)]
    # ties, signed zeros (np.median of [-0.0] is 0.0), an even and an odd count, infinities of both signs
    series += [np.array([-0.0]), np.array([-0.0, -0.0]), np.round(rng.normal(size=40)), np.round(rng.normal(size=41))]
    series += [np.r_[rng.normal(size=6), -np.inf, np.inf], np.r_[rng.normal(size=5), np.nan, -np.inf]]
    for v in series:
        got = error_statistics(v)
        with np.errstate(over="ignore", invalid="ignore"):
            sq = np.power(v, 2)
            want = dict(rmse=np.sqrt(np.mean(sq)), mean=np.mean(v), median=np.median(v), std=np.std(v), min=np.min(v),
                        max=np.max(v), sse=np.sum(sq))  # fmt: skip
        for k, x in want.items():
            same = got[k] == float(x) and np.signbit(got[k]) == np.signbit(x)
            assert same or (np.isnan(got[k]) and np.isnan(x)), (len(v), k, got[k], x)


def test_time_window_downsample_and_motion_filter_equal_evo(evo_pairs):
    ref, est, gt, es = evo_pairs["fr1_xyz"]
    t0 = ref.timestamps[0]
    r = copy.deepcopy(ref)
    r.reduce_to_time_range(t0 + 5.0, t0 + 12.5)
    np.testing.assert_array_equal(time_window(gt, t0 + 5.0, t0 + 12.5).stamps, r.timestamps)
    np.testing.assert_array_equal(time_window(gt, None, t0 + 3).stamps, ref.timestamps[ref.timestamps <= t0 + 3])
    for num in (1, 7, 500, 10**6):
        r = copy.deepcopy(ref)
        r.downsample(num)
        np.testing.assert_array_equal(gt.stamps[evo_downsample(len(gt), num)], r.timestamps)
    for dist, angle in ((0.05, 2.0), (0.2, 360.0), (10.0, 0.5), (0.0, 0.0)):
        ids = filters.filter_by_motion(est.poses_se3, dist, angle, True)
        assert evo_motion_filter(es.positions, es.quaternions, dist, angle).tolist() == ids


@pytest.mark.parametrize("plane", ["xy", "xz", "yz"])
def test_project_to_plane_equals_evo(evo_pairs, plane):
    r, e = _synced(evo_pairs, "fr2_desk")
    pos, q = _lorisnb_arrays(e)
    e.project(Plane(plane))
    p2, q2 = lorisnb_project(pos, q, plane)
    np.testing.assert_allclose(p2, e.positions_xyz, rtol=0, atol=TOL)
    np.testing.assert_allclose(Rotation.from_quat(q2).as_matrix(), np.array(e.poses_se3)[:, :3, :3], atol=TOL)


def test_random_trajectories_all_units():
    rng = np.random.default_rng(5)
    n = 120
    stamps = np.cumsum(rng.uniform(0.02, 0.1, n))
    pos = np.cumsum(rng.normal(scale=0.2, size=(n, 3)), axis=0)
    rot = Rotation.from_rotvec(np.cumsum(rng.normal(scale=0.1, size=(n, 3)), axis=0))
    gt = Trajectory.from_rotations(stamps, pos, rot)
    est = Trajectory.from_rotations(stamps, pos + rng.normal(scale=0.05, size=pos.shape),
                                    rot * Rotation.from_rotvec(rng.normal(scale=0.05, size=(n, 3))))  # fmt: skip
    r, e = to_evo(gt), to_evo(est)
    for unit, delta in (("m", 0.7), ("deg", 20.0), ("rad", 0.3), ("frames", 4)):
        for all_pairs in (False, True):
            i, j = evo_rpe_pairs(est.positions, est.quaternions, delta, unit, all_pairs)
            pairs = em.id_pairs_from_delta(e.poses_se3, delta, EVO_UNIT[unit], 0.1, all_pairs)
            assert list(zip(i.tolist(), j.tolist(), strict=True)) == pairs, (unit, all_pairs)
            m = em.RPE(em.PoseRelation.full_transformation, delta, EVO_UNIT[unit], 0.1, all_pairs)
            m.process_data((r, e))
            ours = rpe_relation(gt.positions, gt.quaternions, est.positions, est.quaternions, i, j, "full")
            np.testing.assert_allclose(ours, m.error, rtol=0, atol=TOL)


def test_statistics_columns_of_the_sequence_table(evo_pairs):
    from lorisnb.core import score
    from lorisnb.core.conventions.choices import Conventions
    from lorisnb.core.pipeline.model import STAT_COLUMNS
    from lorisnb.core.pipeline.sessions import session_errors

    ref, est, gt, es = evo_pairs["fr1_xyz"]
    f = session_errors({1: gt}, {1: es}, Conventions.preset("tum"))
    row = score(f, eps=0.02, phi=2.0, rpe_delta=1, rpe_unit="f").iloc[0]
    assert set(STAT_COLUMNS) <= set(row.index)
    e = f.sequences[0]
    # evo's statistics of the same per-pose errors (evo's APE on the aligned poses lorisnb scored)
    r = to_evo(Trajectory(e.stamps, e.gt_positions, e.gt_quaternions))
    x = to_evo(Trajectory(e.stamps, e.est_positions, e.est_quaternions))
    for name, rel in (("ate", em.PoseRelation.translation_part), ("aoe", em.PoseRelation.rotation_angle_deg)):
        m = em.APE(rel)
        m.process_data((r, x))
        stats = m.get_all_statistics()
        assert row[f"{name}_rmse"] == pytest.approx(stats["rmse"], rel=TOL)
        for k in ("mean", "median", "std", "min", "max", "sse"):
            assert row[f"{name}_{k}"] == pytest.approx(stats[k], rel=TOL), (name, k)
    m = em.RPE(em.PoseRelation.translation_part, 1, em.Unit.frames, all_pairs=True)
    m.process_data((r, x))
    for k, v in m.get_all_statistics().items():
        assert row[f"rpe_trans_{k}"] == pytest.approx(v, rel=TOL), k
    ok = (e.ate <= 0.02) & (e.aoe <= 2.0)
    assert 0 < ok.sum() < len(ok)
    for k, v in error_statistics(e.ate[ok]).items():
        assert row[f"c_ate_{k}"] == pytest.approx(v, rel=1e-12), k
    i, j, tr, _ = e.rpe(1, "f")
    both = ok[i] & ok[j]
    for k, v in error_statistics(tr[both]).items():
        assert row[f"c_rpe_trans_{k}"] == pytest.approx(v, rel=1e-12), k


@pytest.mark.parametrize(
    "delta, unit, pairs, all_pairs",
    [(1, "frames", "estimate", False), (0.3, "m", "estimate", False), (0.3, "m", "reference", True),
     (5.0, "deg", "estimate", False), (2, "f", "reference", True)],
)  # fmt: skip
@pytest.mark.thorough
def test_score_rpe_options_equal_evo_rpe(evo_pairs, delta, unit, pairs, all_pairs):
    from lorisnb.core import score
    from lorisnb.core.conventions.choices import Conventions
    from lorisnb.core.pipeline.sessions import session_errors

    _, _, gt, es = evo_pairs["fr1_xyz"]
    f = session_errors({1: gt}, {1: es}, Conventions.preset("tum"))
    row = score(f, rpe_delta=delta, rpe_unit=unit, rpe_pairs=pairs, rpe_all_pairs=all_pairs).iloc[0]
    e = f.sequences[0]
    r = to_evo(Trajectory(e.stamps, e.gt_positions, e.gt_quaternions))
    x = to_evo(Trajectory(e.stamps, e.est_positions, e.est_quaternions))
    evo_unit = EVO_UNIT["frames" if unit == "f" else unit]
    for name, rel in (("rpe_trans", em.PoseRelation.translation_part), ("rpe_rot", em.PoseRelation.rotation_angle_deg)):
        m = em.RPE(rel, delta, evo_unit, 0.1, all_pairs, pairs == "reference")
        m.process_data((r, x))
        assert row["rpe_pairs"] == len(m.error)
        for k, v in m.get_all_statistics().items():
            assert row[f"{name}_{k}"] == pytest.approx(v, rel=TOL, abs=1e-12), (name, k)


def test_lorisnb_rpe_rule_unchanged_by_default(evo_pairs):
    from lorisnb.core.metrics import openloris as metrics

    _, _, gt, es = evo_pairs["fr1_xyz"]
    from lorisnb.core.conventions.choices import Conventions
    from lorisnb.core.pipeline.sessions import session_errors

    e = session_errors({1: gt}, {1: es}, Conventions.preset("tum")).sequences[0]
    for delta, unit in ((1.0, "s"), (0.5, "m"), (3, "f")):
        i, j, _, _ = e.rpe(delta, unit)
        i0, j0 = metrics.rpe_pairs(e.stamps, e.gt_positions, delta, unit)
        assert i.tolist() == i0.tolist() and j.tolist() == j0.tolist()


def test_masked_statistics_of_full_rows_equal_the_row_computation_to_the_bit():
    """A grid row selecting every value (no threshold) takes error_statistics' path: the same numbers
    as the masked row computation gives it, to the last bit, on any length (pairwise sums)."""
    from lorisnb.core.metrics import relations

    rng = np.random.default_rng(0)
    for n in (1, 2, 7, 9, 128, 129, 4097, 100_001):
        v = rng.lognormal(size=n) * 10.0 ** rng.integers(-3, 6)
        mask = np.stack([np.ones(n, bool), rng.uniform(size=n) < 0.7, np.zeros(n, bool)])
        got = relations.masked_statistics(v, mask)
        direct = {k: np.full(3, np.nan) for k in got}
        relations._masked_rows(v, mask, direct)  # the row computation, every row
        for k in got:
            np.testing.assert_array_equal(got[k], direct[k])
        whole = error_statistics(v)
        assert all(got[k][0] == whole[k] for k in got) and np.isnan(got["mean"][2])
