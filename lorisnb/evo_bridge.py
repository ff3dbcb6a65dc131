"""A bridge to evo both ways, and a cross-check of every number the two compute in common.

* :func:`to_evo` / :func:`from_evo` convert between :class:`~lorisnb.trajectory.Trajectory` and
  evo's ``PoseTrajectory3D``; :func:`evo_result_table` turns an evo ``Result`` into a tidy table.
* :func:`crosscheck` computes, on **identically associated pose pairs**, APE translation (ATE)
  and rotation angle (AOE) without alignment, after SE(3) and after Sim(3) alignment, and RPE
  (translation, rotation) over a delta in frames and in metres, with lorisnb and with evo; they
  must agree to floating-point precision. It then adds the places where the two *definitions*
  differ, each with its size: evo's nearest-stamp association against lorisnb's interpolation,
  and (for OpenLORIS files) lifelong alignment, dropped repeated poses and the official tool's
  interpolation slips. evo has no CR, CR-T or CS-R; the table says so.

Columns of the table: ``quantity, alignment, lorisnb, evo, abs_diff, rel_diff, agrees, n_pairs,
note``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.spatial.transform import Rotation

from . import metrics
from .association import MAX_GAP, associate, groundtruth_in_frame
from .errors import EvaluationError
from .geometry import Sim3, umeyama
from .trajectory import Trajectory

CROSSCHECK_COLUMNS = ["quantity", "alignment", "lorisnb", "evo", "abs_diff", "rel_diff", "agrees", "n_pairs", "note"]

#: Agreement on identical pairs: both libraries do the same float64 math in a different order,
#: so results agree to ~1e-12; 1e-9 (absolute, metres/degrees, or relative) leaves margin.
TOLERANCE = 1e-9

#: evo's default association window (``evo_ape --t_max_diff``), seconds.
EVO_MAX_DIFF = 0.01


def to_evo(traj: Trajectory, name: str = ""):
    """A lorisnb Trajectory as evo's ``PoseTrajectory3D`` (quaternions become ``wxyz``)."""
    from evo.core.trajectory import PoseTrajectory3D

    q = traj.rotations().as_quat() if len(traj) else np.zeros((0, 4))
    out = PoseTrajectory3D(positions_xyz=np.asarray(traj.positions, float),
                           orientations_quat_wxyz=q[:, [3, 0, 1, 2]], timestamps=np.asarray(traj.stamps, float))
    if name:
        out.name = name
    return out


def from_evo(traj) -> Trajectory:
    """evo's ``PoseTrajectory3D`` (or ``PosePath3D``: stamps become indices) as a lorisnb Trajectory."""
    q = np.asarray(traj.orientations_quat_wxyz, float)[:, [1, 2, 3, 0]]
    stamps = np.asarray(getattr(traj, "timestamps", np.arange(traj.num_poses, dtype=float)), float)
    return Trajectory(stamps, np.asarray(traj.positions_xyz, float).copy(), q, None, {"source": "evo"})


def evo_result_table(result) -> tuple[pd.DataFrame, pd.DataFrame]:
    """An evo ``Result`` (from ``evo.main_ape.ape`` / ``main_rpe.rpe`` or ``Result`` files) as
    (per-pose table: stamp, error; statistics table: statistic, value, metric)."""
    arrays = result.np_arrays
    err = np.asarray(arrays.get("error_array", []), float)
    stamps = np.asarray(arrays.get("timestamps", np.arange(len(err))), float)[: len(err)]
    title = result.info.get("title", "")
    per_pose = pd.DataFrame({"stamp": stamps, "error": err, "metric": title})
    stats = pd.DataFrame([dict(statistic=k, value=float(v), metric=title) for k, v in result.stats.items()])
    return per_pose, stats


@dataclass
class PairedPoses:
    """Estimate poses and ground truth at the same stamps (the pairs both libraries score)."""

    stamps: np.ndarray
    gt_positions: np.ndarray
    gt_rotations: Rotation
    est_positions: np.ndarray
    est_rotations: Rotation
    how: str

    def __len__(self) -> int:
        return len(self.stamps)

    def as_trajectories(self) -> tuple[Trajectory, Trajectory]:
        return (Trajectory.from_rotations(self.stamps, self.gt_positions, self.gt_rotations),
                Trajectory.from_rotations(self.stamps, self.est_positions, self.est_rotations))


def pair_poses(gt: Trajectory, est: Trajectory, max_gap: float = MAX_GAP, by_index: bool = False,
               official: bool = False) -> PairedPoses:
    """lorisnb's association: ground truth interpolated at each estimate stamp within the 0.5 s
    bracket (or, ``by_index``, pose i with pose i, as evo does for KITTI files)."""
    if by_index:
        n = min(len(gt), len(est))
        return PairedPoses(est.stamps[:n], gt.positions[:n], gt.rotations()[:n] if n else Rotation.identity(0),
                           est.positions[:n], est.rotations()[:n] if n else Rotation.identity(0), "by index")
    a = associate(gt, est.stamps, max_gap, official)
    if len(a) == 0:
        raise EvaluationError(
            f"no estimate stamp lies within {max_gap} s of ground truth on both sides; estimate spans "
            f"{est.stamps[0] if len(est) else np.nan:.3f}..{est.stamps[-1] if len(est) else np.nan:.3f} s, "
            f"ground truth {gt.stamps[0]:.3f}..{gt.stamps[-1]:.3f} s")
    return PairedPoses(a.stamps, a.gt_positions, a.gt_rotations, est.positions[a.est_index],
                       Rotation.from_quat(est.quaternions[a.est_index]), f"interpolated ground truth within {max_gap} s")


def _row(quantity, alignment, ours, theirs, n, note, tol=TOLERANCE) -> dict:
    ours = float(ours) if ours is not None else np.nan
    theirs = float(theirs) if theirs is not None else np.nan
    diff = abs(ours - theirs) if np.isfinite(ours) and np.isfinite(theirs) else np.nan
    rel = diff / abs(theirs) if np.isfinite(diff) and theirs != 0 else (0.0 if diff == 0 else np.nan)
    agrees = bool(np.isfinite(diff) and (diff <= tol or rel <= tol))
    return dict(quantity=quantity, alignment=alignment, lorisnb=ours, evo=theirs, abs_diff=diff, rel_diff=rel,
                agrees=agrees, n_pairs=int(n), note=note)


def _aligned(p: PairedPoses, alignment: str) -> tuple[np.ndarray, Rotation, Sim3]:
    if alignment == "none":
        sim = Sim3.identity()
    else:
        sim = umeyama(p.est_positions, p.gt_positions, with_scale=alignment == "sim3")
    pos = sim.apply(p.est_positions)
    rot = Rotation.from_matrix(sim.rotation) * p.est_rotations
    return pos, rot, sim


def _evo_aligned(ref, est, alignment: str):
    import copy

    e = copy.deepcopy(est)
    if alignment != "none":
        e.align(ref, correct_scale=alignment == "sim3")
    return e


def _evo_ape(ref, est, relation: str) -> np.ndarray:
    from evo.core import metrics as em

    rel = em.PoseRelation.translation_part if relation == "t" else em.PoseRelation.rotation_angle_deg
    m = em.APE(rel)
    m.process_data((ref, est))
    return np.asarray(m.error, float)


def _evo_rpe(ref, est, relation: str, delta: float, unit: str, all_pairs: bool):
    from evo.core import metrics as em

    rel = em.PoseRelation.translation_part if relation == "t" else em.PoseRelation.rotation_angle_deg
    u = em.Unit.frames if unit == "f" else em.Unit.meters
    m = em.RPE(rel, delta, u, all_pairs=all_pairs)
    m.process_data((ref, est))
    return np.asarray(m.error, float)


def evo_pairs(est_positions: np.ndarray, delta: float, unit: str, all_pairs: bool) -> tuple[np.ndarray, np.ndarray]:
    """The (i, j) pairs evo's RPE uses (pairs taken on the estimate, evo's default)."""
    from evo.core import metrics as em

    poses = np.tile(np.eye(4), (len(est_positions), 1, 1))
    poses[:, :3, 3] = est_positions
    u = em.Unit.frames if unit == "f" else em.Unit.meters
    pairs = em.id_pairs_from_delta(list(poses), delta, u, all_pairs=all_pairs)
    arr = np.asarray(pairs, int).reshape(-1, 2)
    return arr[:, 0], arr[:, 1]


def crosscheck_pairs(p: PairedPoses, rpe_deltas=((1, "f"), (1.0, "m")), rpe_alignment: str = "se3",
                     all_pairs: bool = False) -> list[dict]:
    """The identical-pairs part of :func:`crosscheck` (rows that must agree)."""
    ref_t, est_t = p.as_trajectories()
    ref, est = to_evo(ref_t), to_evo(est_t)
    rows = []
    note = f"identical pairs ({p.how})"
    for alignment in ("none", "se3", "sim3"):
        pos, rot, sim = _aligned(p, alignment)
        e = _evo_aligned(ref, est, alignment)
        ate_l = metrics.ate(pos, p.gt_positions)
        ate_e = _evo_ape(ref, e, "t")
        aoe_l = metrics.aoe(rot, p.gt_rotations)
        aoe_e = _evo_ape(ref, e, "r")
        for q, f in (("ate_rmse", lambda v: metrics.rmse(v)), ("ate_mean", np.mean), ("ate_median", np.median),
                     ("ate_max", np.max)):
            rows.append(_row(q, alignment, f(ate_l), f(ate_e), len(p), note + "; metres"))
        rows.append(_row("aoe_rmse", alignment, metrics.rmse(aoe_l), metrics.rmse(aoe_e), len(p),
                         note + "; degrees" + ("; Sim(3) scale does not change orientations" if alignment == "sim3" else "")))
    pos, rot, _ = _aligned(p, rpe_alignment)
    e = _evo_aligned(ref, est, rpe_alignment)
    for delta, unit in rpe_deltas:
        if unit == "f":
            i, j = metrics.rpe_pairs(p.stamps, p.gt_positions, delta, "f", all_pairs=all_pairs)
            how = f"delta {int(delta)} frame(s), {'all' if all_pairs else 'consecutive'} pairs"
        else:
            i, j = evo_pairs(pos, delta, "m", all_pairs)
            how = f"delta {delta:g} m along the estimate, evo's pairs ({'all' if all_pairs else 'consecutive'})"
        if len(i) == 0:
            continue
        tr, rr = metrics.rpe(p.gt_positions, p.gt_rotations, pos, rot, i, j)
        try:
            tr_e = _evo_rpe(ref, e, "t", delta, unit, all_pairs)
            rr_e = _evo_rpe(ref, e, "r", delta, unit, all_pairs)
        except Exception as exc:  # evo refuses deltas it cannot pair
            rows.append(_row("rpe_trans_rmse", rpe_alignment, metrics.rmse(tr), np.nan, len(i), f"{how}; evo: {exc}"))
            continue
        rows.append(_row("rpe_trans_rmse", rpe_alignment, metrics.rmse(tr), metrics.rmse(tr_e), len(i),
                         f"{note}; {how}; metres"))
        rows.append(_row("rpe_rot_rmse", rpe_alignment, metrics.rmse(rr), metrics.rmse(rr_e), len(i),
                         f"{note}; {how}; degrees"))
    return rows


def crosscheck_native(gt: Trajectory, est: Trajectory, p: PairedPoses, alignment: str = "se3",
                      max_diff: float = EVO_MAX_DIFF) -> list[dict]:
    """Where the association differs: evo's own nearest-stamp association (``max_diff``) against
    lorisnb's interpolation, each scored after its own alignment."""
    from evo.core import sync

    rows = []
    ref_e, est_e = to_evo(gt), to_evo(est)
    pos, _, _ = _aligned(p, alignment)
    ours = metrics.rmse(metrics.ate(pos, p.gt_positions))
    try:
        r, e = sync.associate_trajectories(ref_e, est_e, max_diff=max_diff)
        e.align(r, correct_scale=alignment == "sim3")
        theirs = _evo_ape(r, e, "t")
        rows.append(_row("ate_rmse", alignment, ours, metrics.rmse(theirs), len(theirs),
                         f"definitions differ: evo pairs each pose with the nearest stamp within {max_diff} s "
                         f"({len(theirs)} pairs), lorisnb interpolates ground truth within {MAX_GAP} s "
                         f"({len(p)} pairs)"))
    except Exception as exc:
        rows.append(_row("ate_rmse", alignment, ours, np.nan, 0,
                         f"evo's nearest-stamp association within {max_diff} s found no pairs ({exc})"))
    try:
        r, e = sync.associate_trajectories(ref_e, est_e, max_diff=MAX_GAP, sync_method=sync.SyncMethod.interpolation)
        e.align(r, correct_scale=alignment == "sim3")
        theirs = _evo_ape(r, e, "t")
        rows.append(_row("ate_rmse", alignment, ours, metrics.rmse(theirs), len(theirs),
                         f"definitions differ: evo's interpolating sync (nearest stamp within {MAX_GAP} s, then "
                         f"interpolation) against lorisnb's bracket rule (both neighbours within {MAX_GAP} s)"))
    except Exception as exc:  # older evo or no pairs
        rows.append(_row("ate_rmse", alignment, ours, np.nan, 0, f"evo's interpolating sync not available ({exc})"))
    return rows


def crosscheck(gt: Trajectory, est: Trajectory, *, scale: bool = False, by_index: bool = False,
               rpe_deltas=((1, "f"), (1.0, "m")), all_pairs: bool = False, max_gap: float = MAX_GAP) -> pd.DataFrame:
    """Cross-check lorisnb against evo on one ground truth and one estimate (see module docstring).

    Args:
        scale: use Sim(3) for the RPE rows and the association rows (SE(3) otherwise); the APE rows
            are always given for ``none``, ``se3`` and ``sim3``.
        by_index: pair pose i with pose i (KITTI files without stamps), as evo does.
        rpe_deltas: ``(delta, unit)`` with unit ``f`` (frames) or ``m`` (metres).
    """
    p = pair_poses(gt, est, max_gap, by_index)
    alignment = "sim3" if scale else "se3"
    rows = crosscheck_pairs(p, rpe_deltas, alignment, all_pairs)
    if not by_index:
        rows += crosscheck_native(gt, est, p, alignment)
    for q in ("cr", "cr_t", "cs_r"):
        rows.append(dict(quantity=q, alignment=alignment, lorisnb=np.nan, evo=np.nan, abs_diff=np.nan, rel_diff=np.nan,
                         agrees=False, n_pairs=len(p),
                         note="OpenLORIS-Scene metric (correctness over time); evo has no equivalent"))
    return pd.DataFrame(rows, columns=CROSSCHECK_COLUMNS)


def crosscheck_poses(gt: Trajectory, est: Trajectory, *, scale: bool = False, by_index: bool = False,
                     max_gap: float = MAX_GAP) -> pd.DataFrame:
    """Per pose, on identical pairs after alignment: stamp, lorisnb ATE, evo APE (metres), lorisnb
    AOE, evo APE angle (degrees). They lie on the diagonal."""
    p = pair_poses(gt, est, max_gap, by_index)
    alignment = "sim3" if scale else "se3"
    pos, rot, _ = _aligned(p, alignment)
    ref_t, est_t = p.as_trajectories()
    ref, e = to_evo(ref_t), _evo_aligned(to_evo(ref_t), to_evo(est_t), alignment)
    return pd.DataFrame({"stamp": p.stamps, "ate_lorisnb": metrics.ate(pos, p.gt_positions),
                         "ate_evo": _evo_ape(ref, e, "t"), "aoe_lorisnb": metrics.aoe(rot, p.gt_rotations),
                         "aoe_evo": _evo_ape(ref, e, "r")})


def crosscheck_openloris(result, seq: int | None = None, *, scale: bool | str = False,
                         data_root=None, groundtruth=None, rpe_deltas=((1, "f"), (1.0, "m"))) -> pd.DataFrame:
    """Cross-check one sequence of an OpenLORIS result file (ground truth moved to its frame), plus
    the OpenLORIS-specific differences: lifelong alignment on the first sequence against evo's
    alignment of the sequence on itself, dropped repeated poses, and the official interpolation.

    ``result`` is the file's path or the file already read (:func:`lorisnb.readers.read_openloris`).
    """
    from .evaluation import compute_errors, is_monocular, load_groundtruth, score
    from .readers import OpenLorisFile, read_openloris

    res = result if isinstance(result, OpenLorisFile) else read_openloris(result)
    result_path = res.path
    scene, frame = res.scene, res.frame
    gt_file = groundtruth if groundtruth is not None else load_groundtruth(scene, data_root)
    seqs = [s for s in res.sequences if len(res.sequences[s])]
    if not seqs:
        raise EvaluationError(f"{result_path}: no sequence has poses")
    s = seq if seq is not None else seqs[0]
    if s not in res.sequences or s not in gt_file.sequences:
        raise EvaluationError(f"{result_path}: sequence {s} is not in both the result ({sorted(res.sequences)}) "
                              f"and the ground truth ({sorted(gt_file.sequences)})")
    with_scale = is_monocular(result_path.parent.name) if scale == "auto" else bool(scale)
    gt = groundtruth_in_frame(gt_file.sequences[s], scene, frame)
    table = crosscheck(gt, res.sequences[s], scale=with_scale, rpe_deltas=rpe_deltas)
    extra = []
    alignment = "sim3" if with_scale else "se3"
    ref_rows = table[(table["quantity"] == "ate_rmse") & (table["alignment"] == alignment)].iloc[0]
    self_aligned = ref_rows["lorisnb"]
    if len(res.sequences) > 1:
        ll = score(compute_errors(res, gt_file, mode="lifelong", scale=with_scale)).set_index("seq").loc[s]
        extra.append(_row("ate_rmse", alignment, ll["ate_rmse"], self_aligned, ll["matched"],
                          f"definitions differ: lorisnb lifelong mode aligns on sequence "
                          f"{min(k for k in res.sequences if len(res.sequences[k]))} and applies it to "
                          f"sequence {s}; evo aligns sequence {s} on itself (evo column)"))
    kept = read_openloris(result_path, remove_repeated=False)
    if len(kept.sequences[s]) != len(res.sequences[s]):
        p2 = pair_poses(groundtruth_in_frame(gt_file.sequences[s], scene, frame), kept.sequences[s])
        pos, _, _ = _aligned(p2, alignment)
        extra.append(_row("ate_rmse", alignment, self_aligned, metrics.rmse(metrics.ate(pos, p2.gt_positions)), len(p2),
                          f"definitions differ: lorisnb drops {len(kept.sequences[s]) - len(res.sequences[s])} "
                          "repeated poses as the official tool does; evo column keeps them"))
    exact = score(compute_errors(res, gt_file, mode="per-seq", scale=with_scale)).set_index("seq").loc[s]
    official = score(compute_errors(res, gt_file, mode="per-seq", scale=with_scale, official_interpolation=True)
                     ).set_index("seq").loc[s]
    extra.append(_row("aoe_rmse", alignment, exact["aoe_rmse"], official["aoe_rmse"], exact["matched"],
                      "not an evo difference: lorisnb's correct slerp (lorisnb column) against the official "
                      "OpenLORIS tool's interpolation slips (second column, --official-interpolation)"))
    out = pd.concat([table, pd.DataFrame(extra, columns=CROSSCHECK_COLUMNS)], ignore_index=True)
    return out
