"""TartanAir's metrics, as tartanair_tools' ``TartanAirEvaluator.evaluate_one_trajectory`` computes
them (github.com/castacks/tartanair_tools, ``evaluation/``) on two trajectories of the same length,
pose i with pose i.

- **ATE** (``ate_score``): Horn's rotation between the centred positions, the ground truth turned
  onto the estimate, and with ``scale`` the estimate multiplied by TartanAir's own scale
  ``s = sum |g_c|^2 / sum e_c . (R g_c)`` (not Umeyama's: it scales the estimate to the ground
  truth so that a small estimate cannot make the error small); the RMS of ``R g_c - s e_c``, metres.
- **Scale rule** (``rescale``), for the RPE and the KITTI score: both trajectories expressed
  relative to their first pose, the estimate's positions multiplied by ``1 / mean(|dp_est| / |dp_gt|)``
  over the steps where the ground truth moved more than 0.1 mm.
- **RPE** (``rpe_score``): over 10,000 random pairs (i, j) drawn with Python's ``random.randint``
  (all n^2 pairs below 100 poses; i = j allowed), ``E = (E_j^-1 E_i)^-1 (G_j^-1 G_i)``: the mean
  rotation angle (radians) and the mean translation norm (metres). The pairs come from
  ``random.Random(seed)``, so that a seed reproduces tartanair_tools run after ``random.seed(seed)``.
- **KITTI score** (``kitti_score``): the KITTI devkit's segment errors in double precision over
  5, 10, ..., 40 m from every frame (step 1), the mean over lengths of each length's mean: rotation in
  degrees per metre, translation as a fraction (m/m).
"""

from __future__ import annotations

import random
import warnings

import numpy as np

from lorisnb.core.metrics.kitti import kitti_segments
from lorisnb.errors import EvaluationError, LorisWarning

#: TartanAir's KITTI-style segment lengths, metres (evaluate_kitti.py's ``lens``).
TARTANAIR_LENGTHS = (5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0, 40.0)
#: Random RPE pairs (evaluate_rpe.py's ``param_max_pairs``).
TARTANAIR_PAIRS = 10000
#: The columns :func:`tartanair_scores` gives (the ``tartanair`` preset's in the sequence table).
TARTANAIR_COLUMNS = ["tartanair_ate", "tartanair_ate_scale", "tartanair_scale", "tartanair_rpe_rot",
                     "tartanair_rpe_trans", "tartanair_kitti_r", "tartanair_kitti_t"]  # fmt: skip
#: Ground-truth steps shorter than this are left out of the scale, metres.
TARTANAIR_STILL = 1e-4


def tartanair_ate(gt_positions: np.ndarray, est_positions: np.ndarray, scale: bool = False) -> tuple[float, float]:
    """TartanAir's ATE (metres) and its scale (1 without ``scale``); see the module docstring."""
    g, e = np.asarray(gt_positions, float), np.asarray(est_positions, float)
    g_c, e_c = g - g.mean(axis=0), e - e.mean(axis=0)
    w = g_c.T @ e_c  # sum of outer(model_c, data_c)
    u, _, vh = np.linalg.svd(w.T)
    s_mat = np.eye(3)
    if np.linalg.det(u) * np.linalg.det(vh) < 0:
        s_mat[2, 2] = -1
    rot = u @ s_mat @ vh
    rg = g_c @ rot.T
    s = 1.0
    if scale:  # a ground truth at one point has no scale (NaN, with no numpy warning; tartanair_tools
        # divides rounding by rounding), nor has an estimate whose centred positions are across its own
        den = float(np.sum(e_c * rg))
        still = not len(g) or bool(np.all(g == g[0]))
        s = float(np.sum(g_c * g_c)) / den if den != 0.0 and not still else float("nan")
        if not np.isfinite(s):
            return float("nan"), float("nan")
    err = rg - s * e_c
    return float(np.sqrt(np.sum(err * err) / len(err))), s


def tartanair_poses(gt: np.ndarray, est: np.ndarray, scale: bool = False) -> tuple[np.ndarray, np.ndarray, float]:
    """Both (N, 4, 4) trajectories relative to their first pose, and with ``scale`` the estimate's
    positions multiplied by TartanAir's scale rule; returns them and the scale (1 without).

    As tartanair_tools computes them (``shift0``, ``rescale``, ``quats2SEs``): each relative pose
    written as a position and a quaternion (scipy's ``Rotation.from_matrix``) and turned back into a
    matrix (``Rotation.from_quat``). The round trip moves a rotation by a few ulps only, but its RPE
    takes the arccos of pairs whose error is the identity (i = j: 1 pair in n for n below 100), where an
    ulp of the trace is 1e-8 rad: without it the mean rotation error differed from tartanair_tools' by up
    to 4e-7 relative on 3..10 poses. Give the poses as read (quaternions not normalized: scipy normalizes
    them as tartanair_tools' scipy does), or the last bits, and with them the scale rule's borderline
    steps, may differ from its."""
    from scipy.spatial.transform import Rotation

    def shifted(m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rel = np.linalg.inv(m[0]) @ m
        return rel[:, :3, 3].copy(), Rotation.from_matrix(rel[:, :3, :3]).as_quat()

    (pg, qg), (pe, qe) = shifted(np.asarray(gt, float)), shifted(np.asarray(est, float))
    s = 1.0
    if scale:
        sg = np.sqrt(np.sum(np.diff(pg, axis=0) ** 2, axis=1))  # its pose2trans and speed, in its order
        se = np.sqrt(np.sum(np.diff(pe, axis=0) ** 2, axis=1))
        moving = sg > TARTANAIR_STILL
        ratio = float(np.mean(se[moving] / sg[moving])) if moving.any() else 0.0
        s = 1.0 / ratio if ratio > 0.0 else float("nan")  # no scale: see tartanair_scores
        _borderline_steps(sg, se, moving, s, float(np.abs(pg).max(initial=1.0)))
        pe = pe * s
    return matrices(pg, qg), matrices(pe, qe), s


#: Up to this many borderline steps, the warning of :func:`_borderline_steps` names the range of scales
#: their choices give (2^k of them); beyond, it says how many steps the scale depends on.
BORDERLINE_SPAN = 12


def _borderline_steps(sg: np.ndarray, se: np.ndarray, moving: np.ndarray, s: float, size: float) -> None:
    """Warn where the scale rule's 0.1 mm threshold decides by rounding: ground-truth steps of 0.1 mm to
    within a few ulps (positions written with 4 decimals move by exactly 0.1 mm), which a computation
    keeps or drops by the last bits of its input and arithmetic. lorisnb's are tartanair_tools' on the
    same poses as read (:attr:`lorisnb.core.spec.evalspec.EvalSpec.poses_as_read`); poses written or
    computed otherwise may flip each of these steps, and a step kept with a long estimate step moves the
    scale by percents: the warning names the range of scales the 2^k choices give (up to
    :data:`BORDERLINE_SPAN` steps; beyond, their number alone)."""
    near = np.flatnonzero(np.abs(sg - TARTANAIR_STILL) <= 64 * np.finfo(float).eps * max(1.0, size))
    if not near.size:
        return
    fixed = moving.copy()
    fixed[near] = False
    total, count = float(np.sum(se[fixed] / sg[fixed])), int(fixed.sum())
    k = near.size
    span = ""
    if k <= BORDERLINE_SPAN:
        ratios = se[near] / sg[near]
        choose = (np.arange(2**k)[:, None] >> np.arange(k)) & 1  # every subset of the borderline steps kept
        n = count + choose.sum(axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            scales = 1.0 / ((total + choose @ ratios) / n)
        scales = scales[(n > 0) & np.isfinite(scales) & (scales > 0)]
        if not scales.size or (scales.min() == s and scales.max() == s):
            return
        span = f"; kept or dropped, they give a scale from {scales.min():.9g} to {scales.max():.9g} ({2**k} choices)"
    kept = int(moving[near].sum())
    warnings.warn(
        f"TartanAir's scale rule drops ground-truth steps of at most 0.1 mm; {k} step(s) are 0.1 mm to within "
        f"rounding, and the last bits of the poses and of the arithmetic decide whether each is kept: lorisnb keeps "
        f"{kept} of them (as tartanair_tools does on the same poses as read), for a scale of {s:.9g}{span}; poses "
        "written or computed otherwise may give another, and other RPE and KITTI scores with it",
        LorisWarning,
        stacklevel=4,
    )


def matrices(positions: np.ndarray, quaternions: np.ndarray) -> np.ndarray:
    """(N, 4, 4) poses of positions and ``xyzw`` quaternions, with scipy's
    ``Rotation.from_quat(q).as_matrix()`` (tartanair_tools' ``pos_quats2SE_matrices``: bit for bit)."""
    from scipy.spatial.transform import Rotation

    out = np.zeros((len(positions), 4, 4))
    out[:, :3, :3] = Rotation.from_quat(np.asarray(quaternions, float)).as_matrix()
    out[:, :3, 3] = positions
    out[:, 3, 3] = 1.0
    return out


def tartanair_rpe_pairs(n: int, seed: int = 0, pairs: int = TARTANAIR_PAIRS) -> tuple[np.ndarray, np.ndarray]:
    """The pairs tartanair_tools draws (see the module docstring), from ``random.Random(seed)``."""
    if pairs == 0 or n < np.sqrt(pairs):
        i, j = np.divmod(np.arange(n * n), n)
        return i, j
    rng = random.Random(seed)
    drawn = [rng.randint(0, n - 1) for _ in range(2 * pairs)]  # i then j for each pair, as its list comprehension
    return np.asarray(drawn[0::2]), np.asarray(drawn[1::2])


def tartanair_rpe(gt: np.ndarray, est: np.ndarray, seed: int = 0) -> tuple[float, float]:
    """TartanAir's RPE of (N, 4, 4) poses (as :func:`tartanair_poses` gives them): mean rotation
    angle (radians) and mean translation error (metres) over its random pairs."""
    if len(gt) != len(est):
        raise EvaluationError(
            f"TartanAir pairs pose i with pose i: {len(est)} estimate and {len(gt)} ground-truth poses"
        )
    i, j = tartanair_rpe_pairs(len(est), seed)
    inv = np.linalg.inv
    err = inv(inv(est[j]) @ est[i]) @ (inv(gt[j]) @ gt[i])
    trans = np.linalg.norm(err[:, :3, 3], axis=1)
    rot = np.arccos(np.clip((np.trace(err[:, :3, :3], axis1=1, axis2=2) - 1) / 2, -1.0, 1.0))
    if len(trans) < 2:
        raise EvaluationError("TartanAir's RPE needs at least 2 pairs (its 'Couldn't find pairs')")
    return float(np.mean(rot)), float(np.mean(trans))


def tartanair_kitti(gt: np.ndarray, est: np.ndarray) -> tuple[float, float]:
    """TartanAir's KITTI score: mean over its lengths of each length's mean rotation error (degrees
    per metre) and translation error (m/m); NaN where no segment fits."""
    seg = kitti_segments(gt, est, precision="double", lengths=TARTANAIR_LENGTHS, step=1)
    rot, tra = [], []
    for length in TARTANAIR_LENGTHS:
        sel = np.abs(seg.length - length) < 0.1
        if sel.any():
            rot.append(sum(seg.r_err[sel].tolist()) / int(sel.sum()))  # Python's sum, as calculate_ave_errors
            tra.append(sum(seg.t_err[sel].tolist()) / int(sel.sum()))
    if not rot:
        return float("nan"), float("nan")
    return float(np.mean(np.array(rot) * 180 / np.pi)), float(np.mean(tra))


def tartanair_scores(
    gt_positions: np.ndarray, gt_quaternions: np.ndarray, est_positions: np.ndarray, est_quaternions: np.ndarray,
    scale: bool = False, seed: int = 0,
) -> dict[str, float]:  # fmt: skip
    """Every TartanAir number of paired poses: ``tartanair_ate`` (m), ``tartanair_ate_scale``,
    ``tartanair_scale`` (the scale rule's, for RPE and KITTI), ``tartanair_rpe_rot`` (rad),
    ``tartanair_rpe_trans`` (m), ``tartanair_kitti_r`` (deg/m), ``tartanair_kitti_t`` (m/m).

    NaN, without a warning (``lorisnb evaluate`` says which sequences, :func:`tartanair_gaps`), where a
    number is undefined: with ``scale``, the ATE and its scale of a ground truth at one point (or of an
    estimate giving a zero denominator), and the scale rule, with the RPE and KITTI scores, where no
    ground-truth step exceeds 0.1 mm or the estimate does not move over those that do (tartanair_tools
    divides rounding by rounding, or by zero, there); the KITTI score where no segment of 5..40 m fits."""
    ate, ate_s = tartanair_ate(gt_positions, est_positions, scale)
    g, e, s = tartanair_poses(matrices(gt_positions, gt_quaternions), matrices(est_positions, est_quaternions), scale)
    rot, trans = tartanair_rpe(g, e, seed)
    kr, kt = tartanair_kitti(g, e)
    return dict(tartanair_ate=ate, tartanair_ate_scale=ate_s, tartanair_scale=s, tartanair_rpe_rot=rot,
                tartanair_rpe_trans=trans, tartanair_kitti_r=kr, tartanair_kitti_t=kt)  # fmt: skip


def tartanair_gaps(table) -> list[tuple[str, list[str], str]]:
    """What :func:`tartanair_scores` left NaN in a sequence table (``file``, ``seq``, ``matched`` and
    :data:`TARTANAIR_COLUMNS`), as ``(what, ["file, seq N", ...], why)`` notes: sequences without a scale
    (with ``tartanair_scale`` NaN) and sequences that hold no KITTI segment of 5..40 m. Sequences of
    fewer than 2 matched poses are left out (they have no TartanAir number at all, said elsewhere)."""
    if not len(table) or "tartanair_scale" not in table:
        return []
    scored = np.asarray(table["matched"], float) >= 2
    no_scale = scored & np.isnan(np.asarray(table["tartanair_scale"], float))
    no_kitti = scored & ~no_scale & np.isnan(np.asarray(table["tartanair_kitti_t"], float))
    names = [f"{f}, seq {q}" for f, q in zip(table["file"], table["seq"], strict=True)]
    out = []
    if no_scale.any():
        out.append((
            "have no TartanAir scale",
            [n for n, k in zip(names, no_scale, strict=True) if k],
            "the scale rule of --tartanair-scale divides the estimate's steps by the ground truth's where the "
            "ground truth moves more than 0.1 mm a step; their ground truth never does (or their estimate does not "
            "move there), so tartanair_rpe_* and tartanair_kitti_* are empty, and tartanair_ate too where the "
            "ground truth stays at one point (tartanair_tools divides rounding by rounding there, or by zero)",
        ))  # fmt: skip
    if no_kitti.any():
        out.append((
            "hold no TartanAir KITTI segment",
            [n for n, k in zip(names, no_kitti, strict=True) if k],
            "tartanair_tools' KITTI score measures drift over 5 to 40 m of "
            "ground-truth path, and these travel less (or match too few poses); their tartanair_kitti_r and "
            "tartanair_kitti_t are empty",
        ))  # fmt: skip
    return out
