"""A bridge to evo both ways: :func:`to_evo` / :func:`from_evo` convert between lorisnb's
:class:`~lorisnb.core.trajectory.poses.Trajectory` and evo's ``PoseTrajectory3D``; :func:`evo_result_table`
turns an evo ``Result`` into tidy tables; :func:`pair_poses` builds identically associated pose
pairs, and :func:`evo_ape` / :func:`evo_rpe` compute evo's numbers on them, which
:mod:`lorisnb.tools.peers.crosscheck` compares with lorisnb's. evo is imported when first used
(``pip install 'lorisnb[evo]'``).
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from scipy.spatial.transform import Rotation

from lorisnb.core.alignment.association import MAX_GAP, associate
from lorisnb.core.alignment.geometry import Sim3, umeyama
from lorisnb.core.spec import validate
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.errors import EvaluationError, ParseError, ValidationError
from lorisnb.tools._extras import require

CROSSCHECK_COLUMNS = ["quantity", "alignment", "lorisnb", "evo", "abs_diff", "rel_diff", "agrees", "n_pairs", "note"]

#: Agreement on identical pairs: both libraries do the same float64 math in a different order,
#: so results agree to ~1e-12; 1e-9 (absolute, metres/degrees, or relative) leaves margin.
TOLERANCE = 1e-9

#: What to do when a delta gives no RPE pair; the note that starts a crosscheck row without pairs.
SMALLER_DELTA = "give a smaller delta (--rpe-frames / --rpe-metres; rpe_deltas= in Python)"
NO_RPE_PAIR = "no RPE pair"

#: evo's default association window (``evo_ape --t_max_diff``), seconds.
EVO_MAX_DIFF = 0.01


@contextmanager
def evo_errors(what: str, advice: str = "", path: str | os.PathLike[str] | None = None) -> Iterator[None]:
    """evo's own exceptions (``evo.EvoException``: its FilterException, FileInterfaceException,
    GeometryException, SyncException, LieAlgebraException, ...) raised inside the block, as
    lorisnb's: a ParseError naming ``path`` when given (evo could not read that file), an
    EvaluationError otherwise; the message says what evo was doing (``what``), evo's reason and
    what to do (``advice``). numpy's LinAlgError inside evo's math (NaN poses, a degenerate
    alignment) is turned alike; any other exception passes unchanged."""
    evo = require("evo")
    try:
        yield
    except (evo.EvoException, np.linalg.LinAlgError) as exc:
        msg = f"evo {what}: {exc}" + (f"; {advice}" if advice else "")
        if path is not None:
            raise ParseError(path, None, msg) from None
        raise EvaluationError(msg) from None


def check_rpe_deltas(value: Any) -> list[tuple[float, str]]:
    """A crosscheck's RPE steps ``[(delta, unit), ...]``, unit ``f`` (``frames``: a positive whole
    number) or ``m`` (metres, positive); anything else is a ValidationError (a unit ``frames``,
    ``s`` or ``deg`` was taken as metres)."""
    try:
        items = [tuple(x) for x in value]
    except TypeError:
        items = [()]
    out = []
    for item in items:
        if len(item) != 2:
            raise ValidationError(f"rpe_deltas={value!r}: expected pairs (delta, unit), e.g. [(1, 'f'), (1.0, 'm')]")
        unit = {"frames": "f", "metres": "m", "meters": "m"}.get(
            str(item[1]).strip().lower(), str(item[1]).strip().lower()
        )
        if unit not in ("f", "m"):
            raise ValidationError(f"rpe_deltas: unit {item[1]!r}: expected 'f' (frames) or 'm' (metres); evo's other "
                                  "units (deg, rad) are lorisnb evaluate's --rpe-unit under --conventions evo")  # fmt: skip
        delta = validate.positive(f"rpe_deltas ({item[1]})", item[0], "frames" if unit == "f" else "metres",
                                  integer=unit == "f")  # fmt: skip
        out.append((int(delta) if unit == "f" else delta, unit))
    return out


def crosscheck_flags(scale: Any, **flags: Any) -> tuple[bool, ...]:
    """A crosscheck's yes/no options checked (strings are never truth-tested: ``all_pairs="no"``
    was all pairs): ``scale`` True, False or a scale word (not ``auto``: two trajectories have no
    algorithm name), then each of ``flags`` True or False."""
    s = validate.scale_value(scale)
    if s == "auto":
        raise ValidationError("scale='auto': two trajectories have no algorithm name; give True or False "
                              "(crosscheck_openloris and lorisnb crosscheck take 'auto')")  # fmt: skip
    return (bool(s), *(validate.flag(k, v) for k, v in flags.items()))


def to_evo(traj: Trajectory, name: str = ""):
    """A lorisnb Trajectory as evo's ``PoseTrajectory3D`` (quaternions become ``wxyz``). evo holds
    no empty trajectory: one without poses is a ValidationError (it was evo's TrajectoryException)."""
    PoseTrajectory3D = require("evo.core.trajectory").PoseTrajectory3D
    if not len(traj):
        raise ValidationError(f"to_evo: the trajectory{f' {name!r}' if name else ''} has no poses, and evo's "
                              "PoseTrajectory3D needs at least one; check the file it was read from")  # fmt: skip

    q = traj.rotations().as_quat() if len(traj) else np.zeros((0, 4))
    out = PoseTrajectory3D(
        positions_xyz=np.asarray(traj.positions, float),
        orientations_quat_wxyz=q[:, [3, 0, 1, 2]],
        timestamps=np.asarray(traj.stamps, float),
    )
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
        return (
            Trajectory.from_rotations(self.stamps, self.gt_positions, self.gt_rotations),
            Trajectory.from_rotations(self.stamps, self.est_positions, self.est_rotations),
        )


def pair_poses(
    gt: Trajectory,
    est: Trajectory,
    max_gap: float = MAX_GAP,
    by_index: bool = False,
    official_interpolation: bool = False,
) -> PairedPoses:
    """lorisnb's association: ground truth interpolated at each estimate stamp within the 0.5 s
    bracket (or, ``by_index``, pose i with pose i, as evo does for KITTI files). A trajectory with
    no pose is an EvaluationError saying so."""
    for label, t in (("ground truth", gt), ("estimate", est)):
        if not len(t):
            raise EvaluationError(
                f"the {label} has no poses (only comments or blank lines?): nothing to compare; "
                "check that the file is the right one and that the run wrote its output"
            )
    if by_index:
        if len(gt) != len(est):
            raise EvaluationError(
                f"pairing by index needs files of the same length, but the ground truth has {len(gt)} poses and "
                f"the estimate {len(est)}; give stamps for each (command line: --gt-times and --est-times)"
            )
        n = len(gt)
        return PairedPoses(
            est.stamps[:n],
            gt.positions[:n],
            gt.rotations()[:n] if n else Rotation.identity(0),
            est.positions[:n],
            est.rotations()[:n] if n else Rotation.identity(0),
            "by index",
        )
    a = associate(gt, est.stamps, max_gap, official_interpolation)
    if len(a) == 0:
        raise EvaluationError(
            f"no estimate stamp lies within {max_gap} s of ground truth on both sides; estimate spans "
            f"{est.stamps[0]:.3f}..{est.stamps[-1]:.3f} s, ground truth {gt.stamps[0]:.3f}..{gt.stamps[-1]:.3f} s"
        )
    return PairedPoses(
        a.stamps,
        a.gt_positions,
        a.gt_rotations,
        est.positions[a.est_index],
        Rotation.from_quat(est.quaternions[a.est_index]),
        f"interpolated ground truth within {max_gap} s",
    )


def agreement_row(quantity, alignment, ours, theirs, n, note, tol=TOLERANCE) -> dict:
    ours = float(ours) if ours is not None else np.nan
    theirs = float(theirs) if theirs is not None else np.nan
    diff = abs(ours - theirs) if np.isfinite(ours) and np.isfinite(theirs) else np.nan
    rel = diff / abs(theirs) if np.isfinite(diff) and theirs != 0 else (0.0 if diff == 0 else np.nan)
    agrees = bool(np.isfinite(diff) and (diff <= tol or rel <= tol))
    return dict(
        quantity=quantity,
        alignment=alignment,
        lorisnb=ours,
        evo=theirs,
        abs_diff=diff,
        rel_diff=rel,
        agrees=agrees,
        n_pairs=int(n),
        note=note,
    )


def aligned_estimate(p: PairedPoses, alignment: str) -> tuple[np.ndarray, Rotation, Sim3]:
    if alignment == "none":
        sim = Sim3.identity()
    else:
        sim = umeyama(p.est_positions, p.gt_positions, with_scale=alignment == "sim3")
    pos = sim.apply(p.est_positions)
    rot = Rotation.from_matrix(sim.rotation) * p.est_rotations
    return pos, rot, sim


def evo_aligned(ref: Any, est: Any, alignment: str) -> Any:
    """A copy of evo trajectory ``est`` aligned on ``ref`` by evo (``none``, ``se3``, ``sim3``);
    an alignment evo cannot compute (degenerate: collinear or too few poses) is an EvaluationError."""
    import copy

    e = copy.deepcopy(est)
    if alignment != "none":
        try:
            e.align(ref, correct_scale=alignment == "sim3")
        except Exception as exc:  # evo's GeometryException and numpy's LinAlgError
            raise EvaluationError(
                f"evo cannot align these trajectories ({exc}); they need at least 3 poses not on one line"
            ) from None
    return e


#: evo's APE of the last inputs (:func:`evo_ape`), keyed by the bytes of both trajectories' poses.
_APE_SEEN: dict[tuple[str, bytes], np.ndarray] = {}


def evo_ape(ref, est, relation: str) -> np.ndarray:
    """evo's APE per pose (``t``: metres, ``r``: degrees) of ``est`` against ``ref``. evo computes it
    once per input: a cross-check that asks again for the same poses (a table and its per-pose
    plot) gets the same array back (a copy) instead of evo's per-pose loop run twice. The
    translation APE is keyed by the positions, which are all evo reads for it. The angle
    depends on the rotations alone (the rotation block of ``inv(ref) @ est`` is ``R_ref^T R_est``,
    the translations meeting only exact zeros), so it is keyed by them: an estimate aligned with
    Sim(3), whose rotations are those of its SE(3) alignment, gets that alignment's angles."""
    em = require("evo.core.metrics")

    digest = hashlib.blake2b(digest_size=20)
    for traj in (ref, est):
        if relation == "t":  # evo's translation APE reads the positions alone (no per-pose matrices built)
            poses = np.ascontiguousarray(traj.positions_xyz, float)
        else:
            poses = np.asarray(traj.poses_se3, float)
            if poses.ndim == 3 and np.isfinite(poses[:, :3, 3]).all():
                poses = np.ascontiguousarray(poses[:, :3, :3])  # (a non-finite translation would not meet zeros)
        digest.update(np.asarray(poses.shape).tobytes() + poses.tobytes())
    key = (relation, digest.digest())
    if key not in _APE_SEEN:
        rel = em.PoseRelation.translation_part if relation == "t" else em.PoseRelation.rotation_angle_deg
        m = em.APE(rel)
        with evo_errors("cannot compute the APE", "check that both trajectories hold the same number of valid poses"):
            m.process_data((ref, est))
        _APE_SEEN[key] = np.asarray(m.error, float)
        while len(_APE_SEEN) > 1 and (len(_APE_SEEN) > 32 or sum(v.nbytes for v in _APE_SEEN.values()) > 2**26):
            del _APE_SEEN[next(iter(_APE_SEEN))]  # the oldest first; at most 32 arrays and 64 MiB
    return _APE_SEEN[key].copy()


def evo_rpe(ref, est, relation: str, delta: float, unit: str, all_pairs: bool):
    em = require("evo.core.metrics")

    rel = em.PoseRelation.translation_part if relation == "t" else em.PoseRelation.rotation_angle_deg
    u = em.Unit.frames if unit == "f" else em.Unit.meters
    m = em.RPE(rel, delta, u, all_pairs=all_pairs, pairs_from_reference=True)  # metres along the ground truth
    with evo_errors(f"found no RPE pair over {delta:g} {'frame(s)' if unit == 'f' else 'm'}", SMALLER_DELTA):
        m.process_data((ref, est))
    return np.asarray(m.error, float)


def evo_pairs(positions: np.ndarray, delta: float, unit: str, all_pairs: bool) -> tuple[np.ndarray, np.ndarray]:
    """The (i, j) pairs evo's RPE takes on ``positions`` (lorisnb passes the ground truth's: a
    distance in metres is travelled along the ground truth everywhere in lorisnb, and evo is run
    with ``pairs_from_reference=True`` to match)."""
    em = require("evo.core.metrics")

    poses = np.tile(np.eye(4), (len(positions), 1, 1))
    poses[:, :3, 3] = positions
    u = em.Unit.frames if unit == "f" else em.Unit.meters
    with evo_errors(f"found no RPE pair over {delta:g} {'frame(s)' if unit == 'f' else 'm'}", SMALLER_DELTA):
        pairs = em.id_pairs_from_delta(list(poses), delta, u, all_pairs=all_pairs)
    arr = np.asarray(pairs, int).reshape(-1, 2)
    return arr[:, 0], arr[:, 1]
