"""Per-sequence and lifelong evaluation of OpenLORIS result files, as the official tool does it.

Two steps, so that thresholds can change without redoing the geometry:

1. :func:`compute_errors` (threshold-free): frames, association with interpolated ground truth,
   alignment (per sequence, or on the first sequence for a lifelong file), and per-pose ATE and
   AOE. Returns a :class:`FileErrors`.
2. :func:`score` (cheap): correctness, CR, CR-T, CS-R and accuracy for given eps, phi, delta and
   tau, one row per sequence; :func:`aggregate_scenes` for the paper's per-scene figures.

:func:`evaluate` does both for files and folders and collects failures instead of stopping.
"""

from __future__ import annotations

import os
import re
import warnings
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Iterable, Mapping

import numpy as np
import pandas as pd
from scipy.spatial.transform import Rotation

from . import metrics, plausibility
from .association import MAX_GAP, associate, groundtruth_in_frame
from .data import find_data
from .errors import DataNotFoundError, EvaluationError, LorisError, LorisWarning, ParseError
from .frames import FRAMES, PAPER_EPS, SCENES
from .geometry import Sim3, ros_quaternion_from_matrix, umeyama
from .readers import OpenLorisFile, read_openloris
from .trajectory import Trajectory

MODES = ("auto", "per-seq", "lifelong")

#: Columns of the per-sequence table (``lorisnb evaluate --csv``); scripts rely on these names.
SEQUENCE_COLUMNS = [
    "algorithm", "file", "scene", "seq", "frame", "poses", "matched", "ate_rmse", "aoe_rmse",
    "c_ate_rmse", "c_aoe_rmse", "correct_time", "cr", "cr_t", "reloc_time", "cs_r",
    "eps", "phi", "delta", "tau",
]
EXTRA_COLUMNS = [
    "suite", "mode", "aligned_on", "scale", "c_matched", "gt_start", "gt_end", "gt_duration",
    "t0", "track_time", "first_correct", "rpe_trans_rmse", "rpe_rot_rmse", "c_rpe_trans_rmse",
    "c_rpe_rot_rmse", "rpe_pairs", "c_rpe_pairs", "official_interpolation",
]

SCENE_COLUMNS = [
    "suite", "algorithm", "scene", "eps", "phi", "delta", "tau", "sequences", "scene_sequences", "matched",
    "c_matched", "correct_time", "track_time", "scene_duration", "cr", "cr_t", "c_ate_rmse",
    "c_ate_rmse_pooled", "ate_rmse", "cs_r_mean",
]


@dataclass
class SequenceErrors:
    """Threshold-free per-pose errors of one sequence.

    Attributes:
        seq: sequence number.
        poses: estimate poses after reading (NaN and repeated poses dropped).
        stamps: (M,) matched estimate stamps, seconds.
        ate: (M,) metres. aoe: (M,) degrees.
        est_positions, gt_positions: (M, 3) aligned estimate and interpolated ground truth, metres.
        est_rotations, gt_rotations: the matching orientations (scipy Rotation, or None if M = 0).
        gt_start, gt_end: ground-truth time span of the sequence, seconds.
        scale: the scale of the alignment applied to this sequence (1 for SE(3)).
    """

    seq: int
    poses: int
    stamps: np.ndarray
    ate: np.ndarray
    aoe: np.ndarray
    est_positions: np.ndarray
    gt_positions: np.ndarray
    est_rotations: Rotation | None
    gt_rotations: Rotation | None
    gt_start: float
    gt_end: float
    scale: float = 1.0
    _rpe_cache: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def matched(self) -> int:
        return len(self.stamps)

    def rpe(self, delta: float = 1.0, unit: str = "s") -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Relative pose error pairs (i, j) and errors (metres, degrees) over ``delta`` in ``unit``
        (see :func:`lorisnb.metrics.rpe_pairs`); computed once per setting and kept."""
        key = (float(delta), unit)
        if key not in self._rpe_cache:
            if self.matched < 2:
                z = np.zeros(0, int)
                self._rpe_cache[key] = (z, z, np.zeros(0), np.zeros(0))
            else:
                i, j = metrics.rpe_pairs(self.stamps, self.gt_positions, delta, unit)
                tr, rr = metrics.rpe(self.gt_positions, self.gt_rotations, self.est_positions,
                                     self.est_rotations, i, j)
                self._rpe_cache[key] = (i, j, tr, rr)
        return self._rpe_cache[key]


@dataclass
class FileErrors:
    """Threshold-free errors of one result file."""

    path: Path
    algorithm: str
    file: str
    suite: str
    scene: str
    frame: str
    mode: str
    alignment: Sim3
    aligned_on: int | None
    official_interpolation: bool
    sequences: list[SequenceErrors]
    warnings: list[str] = field(default_factory=list)


def is_monocular(algorithm: str) -> bool:
    """Whether ``scale="auto"`` treats an algorithm as monocular (Sim(3) alignment): the official
    tool does so for ``dso`` and ``svo``; lorisnb also accepts them as a token of the name
    (``dso_v2``, ``my-svo``)."""
    tokens = re.split(r"[^a-z0-9]+", algorithm.lower())
    return "dso" in tokens or "svo" in tokens


@lru_cache(maxsize=32)
def _read_gt_cached(path: str, mtime: float, remove_repeated: bool) -> OpenLorisFile:
    return read_openloris(path, remove_repeated=remove_repeated)


def load_groundtruth(scene: str, data_root: str | os.PathLike | None = None,
                     remove_repeated: bool = True) -> OpenLorisFile:
    """The ground truth of an OpenLORIS scene (``gt_<scene>_1.txt``), read once and cached.

    Repeated poses are dropped from ground truth too, as the official tool does.
    """
    path = find_data(data_root).groundtruth(scene)
    return _read_gt_cached(str(path), path.stat().st_mtime, remove_repeated)


def _apply(sim: Sim3, positions: np.ndarray, rotations: Rotation, official: bool) -> tuple[np.ndarray, Rotation]:
    pos = sim.apply(positions)
    if official and sim.scale != 1.0:
        # slip (b): the official tool extracts the quaternion from s * R * R_p
        blocks = sim.scale * np.einsum("ij,njk->nik", sim.rotation, rotations.as_matrix())
        return pos, Rotation.from_quat(ros_quaternion_from_matrix(blocks))
    return pos, Rotation.from_matrix(sim.rotation) * rotations


def compute_errors(result: OpenLorisFile | str | os.PathLike,
                   groundtruth: OpenLorisFile | None = None, *,
                   algorithm: str | None = None, file: str | None = None, suite: str = "",
                   mode: str = "auto", scale: bool | str = False,
                   official_interpolation: bool = False, remove_repeated: bool = True,
                   max_gap: float = MAX_GAP, repair_stamps: bool = False, checks: bool = True,
                   data_root: str | os.PathLike | None = None) -> FileErrors:
    """Per-pose errors of one OpenLORIS result file against its scene's ground truth.

    Steps (the official tool's order): ground truth moved to the estimate's frame; association by
    interpolation within ``max_gap`` seconds; alignment of estimated positions (Horn/Umeyama SE(3),
    or Sim(3) with ``scale``); ATE (metres) and AOE (degrees) per matched pose.

    Args:
        result: the file or its path.
        groundtruth: the scene's ground truth; default: found with :func:`load_groundtruth`.
        algorithm: label; default the name of the folder holding the file.
        mode: ``per-seq`` aligns each sequence on itself; ``lifelong`` aligns on the
            lowest-numbered sequence with matches and applies that to every sequence;
            ``auto`` is lifelong for files with several ``seq:`` blocks, else per-seq.
        scale: True for Sim(3), False for SE(3), ``"auto"`` for Sim(3) on monocular
            algorithms (:func:`is_monocular`).
        official_interpolation: reproduce the official tool's orientation slips (AOE only).
        remove_repeated: drop repeated poses (estimate and ground truth) as the official tool.
        repair_stamps: read unpadded nanosecond stamps as such (see :func:`read_openloris`).
        checks: run the plausibility checks of :mod:`lorisnb.plausibility` (warnings only).

    Everything noticed (reader notes, plausibility checks) is issued as LorisWarning and kept in
    ``FileErrors.warnings``.
    """
    if mode not in MODES:
        raise ValueError(f"unknown mode {mode!r}; expected one of {MODES}")
    notes: list[str] = []
    if not isinstance(result, OpenLorisFile):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", LorisWarning)
            result = read_openloris(result, remove_repeated=remove_repeated, repair_stamps=repair_stamps)
        notes.extend(str(w.message) for w in caught)
    else:
        notes.extend(result.warnings)
    path = result.path
    algorithm = algorithm if algorithm is not None else path.parent.name
    scene = result.scene
    frame = result.frame
    if groundtruth is None:
        groundtruth = load_groundtruth(scene, data_root, remove_repeated)
    with_scale = is_monocular(algorithm) if scale == "auto" else bool(scale)
    seqs = sorted(result.sequences)
    if not seqs:
        raise ParseError(path, None, "no 'seq: N' block; expected at least one sequence")
    missing = [s for s in seqs if s not in groundtruth.sequences]
    if missing:
        s = missing[0]
        raise ParseError(path, result.seq_lines.get(s),
                         f"sequence {s} has no ground truth in {groundtruth.path.name} "
                         f"(it has {', '.join(map(str, sorted(groundtruth.sequences)))})")
    lifelong = mode == "lifelong" or (mode == "auto" and len(seqs) > 1)
    used_mode = "lifelong" if lifelong else "per-seq"
    gt_frame = groundtruth.header.get("frame", "base_link")
    if gt_frame not in FRAMES:
        raise ParseError(groundtruth.path, groundtruth.header_lines.get("frame"),
                         f"unknown ground-truth frame {gt_frame!r}; expected one of {', '.join(FRAMES)}")

    assoc = {}
    for s in seqs:  # one iteration per sequence
        gt = groundtruth_in_frame(groundtruth.sequences[s], scene, frame, official_interpolation, gt_frame)
        assoc[s] = associate(gt, result.sequences[s].stamps, max_gap, official_interpolation)
        if checks:
            label = f"{path.name}, seq {s}"
            notes.append(plausibility.groundtruth_gaps(label, groundtruth.sequences[s], max_gap))
            if len(assoc[s]) == 0 and len(result.sequences[s]):
                notes.append(plausibility.time_overlap(label, result.sequences[s].stamps, assoc[s].gt_start,
                                                       assoc[s].gt_end, _other_spans(scene, s, groundtruth, data_root)))

    def fit(s: int) -> Sim3:
        a = assoc[s]
        est = result.sequences[s].positions[a.est_index]
        return umeyama(est, a.gt_positions, with_scale)

    aligned_on: int | None = None
    alignment = Sim3.identity()
    per_seq_align: dict[int, Sim3] = {}
    if lifelong:
        with_matches = [s for s in seqs if len(assoc[s])]
        if with_matches:
            aligned_on = with_matches[0]
            alignment = fit(aligned_on)
            if aligned_on != seqs[0]:
                notes.append(
                    f"{path}: sequence {seqs[0]} has no pose matched to ground truth, so the "
                    f"lifelong alignment was computed on sequence {aligned_on} (the official tool "
                    f"would apply no alignment at all)")
        elif any(len(result.sequences[s]) for s in seqs):
            notes.append(f"{path}: no pose of any sequence matches the ground truth in time; nothing to align "
                         f"(see the time-span warnings; is the scene or the clock right?)")
        per_seq_align = {s: alignment for s in seqs}
    else:
        for s in seqs:
            per_seq_align[s] = fit(s) if len(assoc[s]) else Sim3.identity()
        if len(seqs) == 1:
            alignment = per_seq_align[seqs[0]]
            aligned_on = seqs[0] if len(assoc[seqs[0]]) else None

    if checks and not with_scale:
        fitted = [aligned_on] if lifelong and aligned_on is not None else [s for s in seqs if len(assoc[s]) > 2]
        for s in fitted:
            a = assoc[s]
            p_est = result.sequences[s].positions[a.est_index]
            sim, se3 = umeyama(p_est, a.gt_positions, True), per_seq_align[s]
            notes.append(plausibility.scale_far_from_one(
                f"{path.name}, seq {s}", sim.scale, float(metrics.rmse(metrics.ate(se3.apply(p_est), a.gt_positions))),
                float(metrics.rmse(metrics.ate(sim.apply(p_est), a.gt_positions))),
                float(np.linalg.norm(np.diff(a.gt_positions, axis=0), axis=1).sum())))

    out: list[SequenceErrors] = []
    for s in seqs:
        a = assoc[s]
        traj = result.sequences[s]
        if len(a) == 0:
            out.append(SequenceErrors(s, len(traj), np.zeros(0), np.zeros(0), np.zeros(0),
                                      np.zeros((0, 3)), np.zeros((0, 3)), None, None,
                                      a.gt_start, a.gt_end))
            continue
        est_rot_raw = Rotation.from_quat(traj.quaternions[a.est_index])
        pos, rot = _apply(per_seq_align[s], traj.positions[a.est_index], est_rot_raw,
                          official_interpolation)
        out.append(SequenceErrors(
            s, len(traj), a.stamps, metrics.ate(pos, a.gt_positions), metrics.aoe(rot, a.gt_rotations),
            pos, a.gt_positions, rot, a.gt_rotations, a.gt_start, a.gt_end, per_seq_align[s].scale))
    if checks:
        first = next((e for e in out if e.matched > 10), None)
        if first is not None and np.median(first.aoe) > 45.0:
            notes.append(plausibility.frame_mismatch(
                f"{path.name}, seq {first.seq}", frame,
                _median_aoe_by_frame(result.sequences[first.seq], groundtruth.sequences[first.seq], scene,
                                     with_scale, max_gap, gt_frame)))
    notes = [n for n in dict.fromkeys(notes) if n]
    for n in notes:
        warnings.warn(n, LorisWarning, stacklevel=2)
    return FileErrors(path, algorithm, file if file is not None else path.name, suite, scene, frame,
                      used_mode, alignment, aligned_on, official_interpolation, out, notes)


def _other_spans(scene: str, seq: int, groundtruth: OpenLorisFile, data_root) -> dict[str, tuple[float, float]]:
    """Time spans of the other ground-truth sequences (this scene's, then other scenes' when their
    ground truth is at hand), for the time-overlap check."""
    spans = {f"{scene}-{k}": (float(t.stamps[0]), float(t.stamps[-1]))
             for k, t in groundtruth.sequences.items() if k != seq and len(t)}
    for other in SCENES:
        if other == scene:
            continue
        try:
            gt = load_groundtruth(other, data_root)
        except LorisError:
            continue
        spans.update({f"{other}-{k}": (float(t.stamps[0]), float(t.stamps[-1])) for k, t in gt.sequences.items() if len(t)})
    return spans


def _median_aoe_by_frame(est: Trajectory, gt_base: Trajectory, scene: str, with_scale: bool,
                         max_gap: float, gt_frame: str = "base_link") -> dict[str, float]:
    """Median AOE (deg) of one sequence with its ground truth moved to each sensor frame."""
    out = {}
    for fr in FRAMES:  # seven frames, on a suspicious sequence only
        e = sequence_errors(groundtruth_in_frame(gt_base, scene, fr, gt_frame=gt_frame), est, scale=with_scale,
                            max_gap=max_gap)
        if e.matched:
            out[fr] = float(np.median(e.aoe))
    return out


def sequence_errors(gt: Trajectory, est: Trajectory, *, scale: bool = False, max_gap: float = MAX_GAP,
                    official_interpolation: bool = False) -> SequenceErrors:
    """Per-pose errors of one estimate against one ground truth in the same frame (TUM RGB-D,
    ORDSLAM, a simulated estimate): association within ``max_gap`` seconds, alignment of the
    estimate on itself (SE(3), or Sim(3) with ``scale``), ATE (m) and AOE (deg)."""
    a = associate(gt, est.stamps, max_gap, official_interpolation)
    if len(a) == 0:
        return SequenceErrors(1, len(est), np.zeros(0), np.zeros(0), np.zeros(0), np.zeros((0, 3)),
                              np.zeros((0, 3)), None, None, a.gt_start, a.gt_end)
    sim = umeyama(est.positions[a.est_index], a.gt_positions, scale)
    pos, rot = _apply(sim, est.positions[a.est_index], Rotation.from_quat(est.quaternions[a.est_index]),
                      official_interpolation)
    return SequenceErrors(1, len(est), a.stamps, metrics.ate(pos, a.gt_positions), metrics.aoe(rot, a.gt_rotations),
                          pos, a.gt_positions, rot, a.gt_rotations, a.gt_start, a.gt_end, sim.scale)


def scene_eps(eps: float | str | Mapping[str, float], scene: str) -> float:
    """The ATE threshold for a scene: a number, ``"paper"`` (1 / 3 / 5 m by scene size, Fig. 3),
    or a mapping scene -> metres."""
    if isinstance(eps, str):
        if eps == "paper":
            return PAPER_EPS[scene]
        return float(eps)
    if isinstance(eps, Mapping):
        return float(eps[scene])
    return float(eps)


def _rpe_rows(e: SequenceErrors, correct: np.ndarray, rpe_delta: float, rpe_unit: str) -> dict:
    nan = float("nan")
    i, j, tr, rr = e.rpe(rpe_delta, rpe_unit)
    if len(i) == 0:
        return dict(rpe_trans_rmse=nan, rpe_rot_rmse=nan, c_rpe_trans_rmse=nan, c_rpe_rot_rmse=nan,
                    rpe_pairs=0, c_rpe_pairs=0)
    both = correct[i] & correct[j] if len(i) else np.zeros(0, bool)
    return dict(rpe_trans_rmse=float(metrics.rmse(tr)), rpe_rot_rmse=float(metrics.rmse(rr)),
                c_rpe_trans_rmse=float(metrics.rmse(tr, both)), c_rpe_rot_rmse=float(metrics.rmse(rr, both)),
                rpe_pairs=int(len(i)), c_rpe_pairs=int(both.sum()))


def score(errors: FileErrors | Iterable[FileErrors], eps: float | str | Mapping[str, float] = np.inf,
          phi: float = np.inf, delta: float = 1.0, tau: float = 60.0, rpe_delta: float = 1.0,
          rpe_unit: str = "s") -> pd.DataFrame:
    """One row per sequence: every metric of the paper at one threshold setting.

    Args:
        eps: ATE threshold, metres (number, ``"paper"`` or scene -> metres). Default infinity.
        phi: AOE threshold, degrees. Default infinity.
        delta: validity window of a pose, seconds (Eq. 2). Default 1 s.
        tau: re-localization time factor, seconds (Eq. 4). Default 60 s.
        rpe_delta, rpe_unit: the RPE step (see :func:`lorisnb.metrics.rpe_pairs`).

    A sequence with no matched pose has CR = CR-T = CS-R = 0, no ATE (NaN) and 0 matches.
    Columns: :data:`SEQUENCE_COLUMNS` then :data:`EXTRA_COLUMNS`.
    """
    files = [errors] if isinstance(errors, FileErrors) else list(errors)
    rows = []
    for f in files:  # one iteration per file and sequence, never per pose
        e_scene = scene_eps(eps, f.scene)
        for e in f.sequences:
            row = dict(algorithm=f.algorithm, file=f.file, scene=f.scene, seq=e.seq, frame=f.frame,
                       poses=e.poses, matched=e.matched, eps=e_scene, phi=float(phi), delta=float(delta),
                       tau=float(tau), suite=f.suite, mode=f.mode, aligned_on=f.aligned_on,
                       scale=e.scale, gt_start=e.gt_start, gt_end=e.gt_end,
                       gt_duration=e.gt_end - e.gt_start, official_interpolation=f.official_interpolation)
            if e.matched == 0:
                row.update(ate_rmse=np.nan, aoe_rmse=np.nan, c_ate_rmse=np.nan, c_aoe_rmse=np.nan,
                           c_matched=0, correct_time=0.0, cr=0.0, cr_t=0.0, reloc_time=np.inf, cs_r=0.0,
                           t0=np.nan, track_time=0.0, first_correct=False)
                row.update(_rpe_rows(e, np.zeros(0, bool), rpe_delta, rpe_unit))
                rows.append(row)
                continue
            c = metrics.correctness(e.ate, e.aoe, e_scene, phi)
            ct = float(metrics.correct_time(e.stamps, c, e.gt_end, delta))
            t0 = float(e.stamps[0])
            row.update(
                ate_rmse=float(metrics.rmse(e.ate)), aoe_rmse=float(metrics.rmse(e.aoe)),
                c_ate_rmse=float(metrics.rmse(e.ate, c)), c_aoe_rmse=float(metrics.rmse(e.aoe, c)),
                c_matched=int(c.sum()), correct_time=ct,
                cr=float(metrics.correct_rate(ct, e.gt_start, e.gt_end)),
                cr_t=float(metrics.correct_rate_tracking(ct, t0, e.gt_end)),
                reloc_time=metrics.relocalization_time(t0, e.gt_start),
                cs_r=float(metrics.relocalization_score(t0, e.gt_start, c[0], tau)),
                t0=t0, track_time=e.gt_end - t0, first_correct=bool(c[0]))
            row.update(_rpe_rows(e, c, rpe_delta, rpe_unit))
            rows.append(row)
    return pd.DataFrame(rows, columns=SEQUENCE_COLUMNS + EXTRA_COLUMNS)


def pose_table(errors: FileErrors | Iterable[FileErrors], eps: float | str | Mapping[str, float] = np.inf,
               phi: float = np.inf) -> pd.DataFrame:
    """One row per matched pose: algorithm, scene, seq, stamp, ate (m), aoe (deg), correct."""
    files = [errors] if isinstance(errors, FileErrors) else list(errors)
    parts = []
    for f in files:
        e_scene = scene_eps(eps, f.scene)
        for e in f.sequences:
            if e.matched == 0:
                continue
            parts.append(pd.DataFrame({
                "algorithm": f.algorithm, "file": f.file, "suite": f.suite, "scene": f.scene,
                "seq": e.seq, "stamp": e.stamps, "t_rel": e.stamps - e.gt_start, "ate": e.ate,
                "aoe": e.aoe, "correct": metrics.correctness(e.ate, e.aoe, e_scene, phi),
            }))
    cols = ["algorithm", "file", "suite", "scene", "seq", "stamp", "t_rel", "ate", "aoe", "correct"]
    return pd.concat(parts, ignore_index=True) if parts else pd.DataFrame(columns=cols)


def scene_durations(scenes: Iterable[str], data_root: str | os.PathLike | None = None,
                    remove_repeated: bool = True) -> pd.DataFrame:
    """Ground-truth duration (last minus first stamp, seconds) of every sequence of each scene."""
    rows = []
    for scene in scenes:
        gt = load_groundtruth(scene, data_root, remove_repeated)
        for s, t in gt.sequences.items():
            rows.append(dict(scene=scene, seq=s, gt_start=float(t.stamps[0]), gt_end=float(t.stamps[-1]),
                             gt_duration=t.duration))
    return pd.DataFrame(rows, columns=["scene", "seq", "gt_start", "gt_end", "gt_duration"])


def aggregate_scenes(sequences: pd.DataFrame, durations: pd.DataFrame | None = None,
                     data_root: str | os.PathLike | None = None) -> pd.DataFrame:
    """Per algorithm and scene, as in the paper's Fig. 2 and Fig. 3 (and the official
    ``evaluate_all.py``):

    - ``cr``: sum of correct time / sum of the ground-truth durations of *all* the scene's
      sequences (a sequence the algorithm has no result for counts as not tracked);
    - ``cr_t``: sum of correct time / sum of tracked time (t_max - t0);
    - ``c_ate_rmse``: mean of per-sequence C-ATE RMSE weighted by their correct-pose counts (the
      paper's figure value); ``c_ate_rmse_pooled``: RMSE over all correct poses of the scene;
    - ``ate_rmse``: the same weighted mean of ATE RMSE over matched poses (Fig. 2's value);
    - ``cs_r_mean``: mean CS-R over the sequences evaluated.

    Rows are grouped by ``suite``, ``algorithm``, ``scene`` and the thresholds.
    """
    if sequences.empty:
        return pd.DataFrame(columns=SCENE_COLUMNS)
    if durations is None:
        durations = scene_durations(sorted(sequences["scene"].unique()), data_root)
    total = durations.groupby("scene")["gt_duration"].sum()
    nseq = durations.groupby("scene")["seq"].count()
    keys = ["suite", "algorithm", "scene", "eps", "phi", "delta", "tau"]
    keys += [c for c in ("eps_value",) if c in sequences.columns]  # a sweep: eps as given
    dup = sequences.duplicated(subset=keys + ["seq"], keep=False)
    if dup.any():
        d = sequences[dup].iloc[0]
        same = sequences[dup & (sequences["algorithm"] == d["algorithm"]) & (sequences["scene"] == d["scene"])
                         & (sequences["seq"] == d["seq"])]["file"].astype(str).unique()
        raise EvaluationError(
            f"several results for {d['algorithm']} {d['scene']}-{d['seq']} ({', '.join(same[:3])}); "
            "evaluate them in separate folders (suites)")
    df = sequences.copy()
    df["_c_sq"] = np.where(df["c_matched"] > 0, df["c_ate_rmse"] ** 2 * df["c_matched"], 0.0)
    df["_c_w"] = np.where(df["c_matched"] > 0, df["c_ate_rmse"] * df["c_matched"], 0.0)
    df["_a_w"] = np.where(df["matched"] > 0, df["ate_rmse"] * df["matched"], 0.0)
    g = df.groupby(keys, sort=False, dropna=False)
    out = g.agg(sequences=("seq", "count"), matched=("matched", "sum"), c_matched=("c_matched", "sum"),
                correct_time=("correct_time", "sum"), track_time=("track_time", "sum"),
                cs_r_mean=("cs_r", "mean"), _c_sq=("_c_sq", "sum"), _c_w=("_c_w", "sum"),
                _a_w=("_a_w", "sum")).reset_index()
    out["scene_sequences"] = out["scene"].map(nseq).astype(int)
    out["scene_duration"] = out["scene"].map(total)
    with np.errstate(invalid="ignore", divide="ignore"):
        out["cr"] = out["correct_time"] / out["scene_duration"]
        out["cr_t"] = np.where(out["track_time"] > 0, out["correct_time"] / out["track_time"], np.nan)
        out["c_ate_rmse"] = np.where(out["c_matched"] > 0, out["_c_w"] / out["c_matched"], np.nan)
        out["c_ate_rmse_pooled"] = np.where(out["c_matched"] > 0, np.sqrt(out["_c_sq"] / out["c_matched"]), np.nan)
        out["ate_rmse"] = np.where(out["matched"] > 0, out["_a_w"] / out["matched"], np.nan)
    order = {s: i for i, s in enumerate(SCENES)}
    out = out.drop(columns=["_c_sq", "_c_w", "_a_w"])[SCENE_COLUMNS + keys[7:]]
    out = out.sort_values(["suite", "algorithm", "scene"], key=lambda c: c.map(order) if c.name == "scene" else c)
    return out.reset_index(drop=True)


@dataclass
class Failure:
    """A file that could not be evaluated, with the reason (file, line, what was expected)."""

    path: Path
    error: str
    kind: str


@dataclass
class Evaluation:
    """What :func:`evaluate` returns: the errors of every file evaluated, and the failures."""

    errors: list[FileErrors]
    failures: list[Failure]
    root: Path | None = None
    skipped: list[Failure] = field(default_factory=list)

    def sequences(self, eps=np.inf, phi=np.inf, delta=1.0, tau=60.0, **kw) -> pd.DataFrame:
        """Per-sequence table at one setting (see :func:`score`)."""
        return score(self.errors, eps, phi, delta, tau, **kw)

    def poses(self, eps=np.inf, phi=np.inf) -> pd.DataFrame:
        return pose_table(self.errors, eps, phi)

    def scenes(self, eps=np.inf, phi=np.inf, delta=1.0, tau=60.0, data_root=None) -> pd.DataFrame:
        return aggregate_scenes(self.sequences(eps, phi, delta, tau), data_root=data_root)

    @property
    def algorithms(self) -> list[str]:
        return sorted({f.algorithm for f in self.errors})

    def durations(self, data_root=None) -> pd.DataFrame:
        """Ground-truth durations of every sequence of the scenes evaluated."""
        return scene_durations(sorted({f.scene for f in self.errors}, key=SCENES.index), data_root)

    @property
    def warnings(self) -> list[str]:
        return [w for f in self.errors for w in f.warnings]

    def failures_table(self) -> pd.DataFrame:
        """Failed and skipped files with the reason, one row each."""
        rows = [dict(file=str(f.path), status="failed", kind=f.kind, error=f.error) for f in self.failures]
        rows += [dict(file=str(f.path), status="skipped", kind=f.kind, error=f.error) for f in self.skipped]
        return pd.DataFrame(rows, columns=["file", "status", "kind", "error"])


def result_files(paths: Iterable[str | os.PathLike]) -> list[tuple[Path, Path | None]]:
    """Expand files and folders into ``(file, root)`` pairs; a folder is walked for ``*.txt``
    below it (``root/<algorithm>/*.txt``, or deeper: ``root/<suite>/<algorithm>/*.txt``)."""
    out: list[tuple[Path, Path | None]] = []
    for p in paths:
        p = Path(p)
        if p.is_dir():
            files = sorted(f for f in p.rglob("*.txt") if f.is_file())
            out.extend((f, p) for f in files)
        else:
            out.append((p, None))
    return out


def _labels(path: Path, root: Path | None) -> tuple[str, str, str]:
    """(algorithm, file relative to the root, suite) for a result file."""
    if root is None:
        return path.parent.name, path.name, ""
    rel = path.relative_to(root)
    parts = rel.parts
    algorithm = parts[-2] if len(parts) >= 2 else root.name
    suite = "/".join(parts[:-2])
    return algorithm, rel.as_posix(), suite


def evaluate(paths: str | os.PathLike | Iterable[str | os.PathLike], *, mode: str = "auto",
             scale: bool | str = False, official_interpolation: bool = False,
             remove_repeated: bool = True, data_root: str | os.PathLike | None = None,
             algorithms: Iterable[str] | None = None, scenes: Iterable[str] | None = None,
             repair_stamps: bool = False, progress: bool = False) -> Evaluation:
    """Evaluate result files and folders. A file that fails (bad line, unknown frame, ...) is
    recorded in ``failures`` with its reason and the rest go on; a file whose scene has no ground
    truth in the data (office, in the bundled data) is recorded in ``skipped``.

    Args:
        paths: files, or folders walked as ``<algorithm>/*.txt`` (see :func:`result_files`).
        algorithms, scenes: evaluate only these (None: all).
        progress: show a progress bar over files (tqdm; notebook-aware).
        The other arguments are those of :func:`compute_errors`.
    """
    paths = [paths] if isinstance(paths, (str, os.PathLike)) else list(paths)
    items = result_files(paths)
    if algorithms is not None:
        wanted = set(algorithms)
        items = [(p, r) for p, r in items if _labels(p, r)[0] in wanted]
    scene_set = None if scenes is None else set(scenes)
    if progress:
        from tqdm.auto import tqdm

        items_iter = tqdm(items, desc="evaluating", unit="file")
    else:
        items_iter = items
    done: list[FileErrors] = []
    failed: list[Failure] = []
    skipped: list[Failure] = []
    find_data(data_root)  # no data at all is an error for the whole call, not per file
    for path, root in items_iter:
        algorithm, rel, suite = _labels(path, root)
        try:
            if scene_set is not None:
                path = read_openloris(path, remove_repeated=remove_repeated, warn=False, repair_stamps=repair_stamps)
                if path.scene not in scene_set:
                    continue
            done.append(compute_errors(path, algorithm=algorithm, file=rel, suite=suite, mode=mode,
                                       scale=scale, official_interpolation=official_interpolation,
                                       remove_repeated=remove_repeated, repair_stamps=repair_stamps,
                                       data_root=data_root))
        except DataNotFoundError as exc:
            skipped.append(Failure(getattr(path, "path", path), str(exc), "no-groundtruth"))
        except LorisError as exc:
            failed.append(Failure(getattr(path, "path", path), str(exc), type(exc).__name__))
    root = Path(paths[0]) if len(paths) == 1 and Path(paths[0]).is_dir() else None
    return Evaluation(done, failed, root, skipped)
