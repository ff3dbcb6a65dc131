"""lorisnb under evo's conventions against evo itself, each reading the files its own way: lorisnb
evaluates the pair with the spec (the ``evo`` preset and its options), evo reads the files with its
readers and runs what ``evo_ape`` / ``evo_rpe`` run (sync, alignment, projection, APE and RPE), and
every statistic of ATE, AOE and RPE is compared; the reading rows of
:func:`lorisnb.tools.peers.crosscheck_reading.crosscheck_reading` say where the readings differ and why.
Alignment ``auto`` is the alignment lorisnb chose for the estimate's algorithm, on both sides; what
evo has no equivalent for (lorisnb's own associations, dropped repeated poses, ``posyaw``, a
``transform``) is run the nearest evo way and said in every row's note (:func:`evo_lacks`); where
that nearest way cannot be computed (evo's SE(3) for posyaw on a straight line), the statistics it
leaves without evo's value are judged on lorisnb's pairs as the others are (:func:`evo_on_pairs`).
"""

from __future__ import annotations

import copy
import os
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from lorisnb.core.metrics.relations import STATISTICS
from lorisnb.core.spec import validate
from lorisnb.core.spec.evalspec import EvalSpec, make_spec
from lorisnb.errors import EvaluationError, LorisError, LorisWarning, ValidationError
from lorisnb.io.readers.plain import TRAJECTORY_FORMATS
from lorisnb.tools._extras import require
from lorisnb.tools.peers.crosscheck_reading import crosscheck_reading, evo_read
from lorisnb.tools.peers.evo_bridge import CROSSCHECK_COLUMNS, NO_RPE_PAIR, agreement_row, evo_errors

#: lorisnb's RPE units as evo's ``Unit`` names (seconds: evo has none).
_EVO_UNITS = {"f": "frames", "frames": "frames", "m": "meters", "deg": "degrees", "rad": "radians"}


def evo_lacks(spec: EvalSpec, pairs_identical: bool = False) -> list[str]:
    """What of ``spec`` evo has no equivalent for, and what evo does instead (one phrase each; empty
    for the ``evo`` preset and its options). ``pairs_identical``: lorisnb and evo formed the same
    pose pairs (:func:`identical_pairs`), so the association and the repeated rule, which decide only
    which poses pair, explain nothing and are left out."""
    out = []
    if pairs_identical:
        pass
    elif spec.association == "nearest":
        out.append(f"lorisnb pairs stamps by TUM's greedy one-to-one rule within {spec.max_diff:g} s (association "
                   "nearest), evo each pose of the shorter trajectory with its nearest stamp (evo-nearest)")  # fmt: skip
    elif spec.association == "interpolate":
        out.append(f"lorisnb interpolates the ground truth at each estimate stamp within {spec.max_gap:g} s "
                   f"(association interpolate), evo pairs nearest stamps within {spec.max_diff:g} s")  # fmt: skip
    if spec.repeated == "drop" and not pairs_identical:
        out.append("lorisnb drops poses repeating the previous one or its stamp (repeated drop), evo keeps all")
    if spec.align == "posyaw":
        out.append("lorisnb aligns position and yaw (posyaw), which evo has not: evo's column is its SE(3) alignment")
    if spec.transform is not None:
        out.append("lorisnb moves the ground truth by the transform T_est_gt, evo reads it as it is")
    return out


@dataclass(frozen=True)
class EvoPairs:
    """Pose pairs, one a row, as a side formed them: the ground truth's positions (interpolated where
    the association interpolates), the estimate's positions, and the estimate's stamps (None where
    evo read no stamps: KITTI files, paired by index)."""

    gt_positions: np.ndarray
    est_positions: np.ndarray
    est_stamps: np.ndarray | None


def lorisnb_pairs(
    groundtruth: str | os.PathLike,
    estimate: str | os.PathLike,
    spec: EvalSpec,
    fmt: str,
    gt_fmt: str,
    topic: str | None = None,
    gt_topic: str | None = None,
) -> tuple[EvoPairs, bool] | None:
    """The pose pairs lorisnb's pipeline forms for the two files under ``spec`` (read by its readers,
    by the spec's repeated rule; pose i with pose i for KITTI files without times, as ``lorisnb
    evaluate`` pairs them; the spec's transform, downsampling, motion filter and time window, then
    its association), and whether they were paired by index. None where they cannot be formed."""
    from lorisnb.core.alignment.index_pairs import by_index, indexed
    from lorisnb.core.conventions import evo_steps
    from lorisnb.core.pipeline.steps import match, with_transform
    from lorisnb.core.spec.evo import EVO_ASSOCIATIONS
    from lorisnb.io.readers.plain import read_trajectory

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", LorisWarning)  # evaluate said them already
            gt = read_trajectory(groundtruth, gt_fmt, topic=gt_topic, repeated=spec.repeated_for(gt_fmt))
            est = read_trajectory(estimate, fmt, topic=topic, repeated=spec.repeated_for(fmt))
        if indexed([gt, est]):  # KITTI files without times: pose i with pose i, on every preset
            spec = by_index(spec)
        gt, est = evo_steps.prepare(gt, with_transform(est, spec.transform), spec)
        if spec.association in EVO_ASSOCIATIONS:
            a, est = evo_steps.evo_match(gt, est, spec)
        else:
            a = match(gt, est, spec)
    except LorisError:  # what evaluate refused (it said why): no pairs to compare
        return None
    k = a.est_index
    return EvoPairs(np.asarray(a.gt_positions, float), est.positions[k], est.stamps[k]), spec.association == "index"


def identical_pairs(ours: EvoPairs | None, theirs: EvoPairs | None, transformed: bool = False) -> bool:
    """Whether lorisnb and evo paired the same poses: as many pairs, and (in the order of the
    estimate's stamps, or by index where evo read no stamps) the same ground-truth positions (to
    1e-9 m), estimate stamps (to 1 us) and estimate positions (unless ``transformed``: lorisnb moved
    the estimate by a transform evo does not apply). Decided from the pairs formed, whatever the
    options that formed them (lorisnb's association, a KITTI file's index)."""
    if ours is None or theirs is None or len(ours.gt_positions) != len(theirs.gt_positions):
        return False
    a, b = ours, theirs
    if b.est_stamps is not None:
        if a.est_stamps is None:
            return False
        i, j = np.argsort(a.est_stamps, kind="stable"), np.argsort(b.est_stamps, kind="stable")
        if not np.allclose(a.est_stamps[i], b.est_stamps[j], rtol=0.0, atol=1e-6):
            return False
        a = EvoPairs(a.gt_positions[i], a.est_positions[i], None)
        b = EvoPairs(b.gt_positions[j], b.est_positions[j], None)

    def same(x: np.ndarray, y: np.ndarray) -> bool:
        return x.shape == y.shape and bool(np.allclose(x, y, rtol=1e-12, atol=1e-9))

    return same(a.gt_positions, b.gt_positions) and (transformed or same(a.est_positions, b.est_positions))


def evo_order(
    ref, est, groundtruth: str | os.PathLike, estimate: str | os.PathLike, spec: EvalSpec
) -> tuple[str, bool]:
    """Where evo and lorisnb take poses in another order: a file whose stamps go backwards is sorted by
    lorisnb (with a warning) and kept in the file's order by evo (docs/guide/evo.md). The phrase saying
    so (empty when every stamp read by evo increases), and whether ATE, AOE and ``matched`` depend on
    the order too: RPE always does (its pairs are consecutive poses, or poses a distance apart along the
    path, in that order); the others only under options that take poses in order (``downsample``,
    ``motion_filter``, ``align_frames``, align ``origin``: the first pose) or evo's interpolating sync
    (its binary search needs sorted stamps)."""
    back = []
    for path, traj in ((groundtruth, ref), (estimate, est)):
        stamps = getattr(traj, "timestamps", None)
        n = int(np.sum(np.diff(stamps) < 0)) if stamps is not None and len(stamps) > 1 else 0
        if n:
            back.append(f"{os.fspath(path)} ({n} {'time' if n == 1 else 'times'})")
    if not back:
        return "", False
    phrase = (f"stamps go backwards in {' and '.join(back)}: lorisnb sorts them, evo keeps the file's order, so "
              "the RPE pairs differ")  # fmt: skip
    rest = (spec.downsample is not None or spec.motion_filter is not None or spec.align_frames is not None
            or spec.align == "origin" or spec.association == "evo-interpolate")  # fmt: skip
    if rest:
        phrase += "; with the options given, the poses ATE and AOE are over depend on the order too"
    return phrase, rest


def evo_statistics(ref, est, spec: EvalSpec, alignment: str | None = None) -> dict[str, Any]:
    """What evo computes for trajectories it read itself, under ``spec`` (its sync, alignment,
    projection, APE and RPE; evo's CLI order): ``matched``, ``rpe_pairs`` and ``{ate, aoe, rpe_trans,
    rpe_rot}_{statistic}``; ``pairs``: the poses evo paired (:class:`EvoPairs`); ``rpe_refused``:
    evo's reason when its RPE finds no pair (evo_rpe raises).
    ``alignment``: the one to run (default ``spec.align``; ``auto`` must be resolved first, and
    ``posyaw``, which evo has not, runs as ``se3``). Where evo raises (a degenerate alignment, no
    pair in its sync, a NaN pose), ``failed`` maps the step that failed (``sync``: every value;
    ``ape``: ATE and AOE; ``rpe``) to evo's reason, and the values of that step are missing; an RPE
    step evo cannot align but which has no pair at its delta either is ``rpe_refused``."""
    em, filters = require("evo.core.metrics"), require("evo.core.filters")
    sync = require("evo.core.sync")
    main_ape, main_rpe = require("evo.main_ape"), require("evo.main_rpe")
    from evo.core.trajectory import Plane, PoseTrajectory3D

    evo = require("evo")
    fails = (evo.EvoException, np.linalg.LinAlgError)  # evo's own, and numpy's inside evo's math
    ref, est = copy.deepcopy(ref), copy.deepcopy(est)
    if spec.downsample is not None:
        ref.downsample(spec.downsample)
        est.downsample(spec.downsample)
    if spec.motion_filter is not None:
        ref.motion_filter(*spec.motion_filter, True)
        est.motion_filter(*spec.motion_filter, True)
    if isinstance(ref, PoseTrajectory3D) and isinstance(est, PoseTrajectory3D):
        if spec.t_start is not None or spec.t_end is not None:
            ref.reduce_to_time_range(spec.t_start, spec.t_end)
        method = (
            sync.SyncMethod.interpolation if spec.association == "evo-interpolate" else sync.SyncMethod.nearest_time
        )
        try:
            ref, est = sync.associate_trajectories(ref, est, max_diff=spec.max_diff, offset_2=spec.t_offset,
                                                   sync_method=method)  # fmt: skip
        except fails as exc:  # no pair in evo's sync: nothing of evo's to compare
            return {"failed": {"sync": str(exc)}}
    stamped = getattr(est, "timestamps", None) if isinstance(est, PoseTrajectory3D) else None
    pairs = EvoPairs(
        np.array(ref.positions_xyz, float), np.array(est.positions_xyz, float),
        None if stamped is None else np.array(stamped, float),
    )  # fmt: skip
    how = {"posyaw": "se3"}.get(alignment or spec.align, alignment or spec.align)
    if how == "auto":
        raise ValidationError("align 'auto': resolve it for the algorithm first (EvalSpec.alignment_for)")
    align = dict(
        align=how in ("se3", "sim3"), correct_scale=how in ("sim3", "scale"),
        align_origin=how == "origin", n_to_align=spec.align_frames or -1,
        project_to_plane=Plane(spec.project_to_plane) if spec.project_to_plane else None,
    )  # fmt: skip
    out: dict[str, Any] = {"matched": ref.num_poses, "pairs": pairs}
    failed: dict[str, str] = {}
    c = copy.deepcopy
    try:
        for name, rel in (("ate", em.PoseRelation.translation_part), ("aoe", em.PoseRelation.rotation_angle_deg)):
            out.update({f"{name}_{k}": v for k, v in main_ape.ape(c(ref), c(est), rel, **align).stats.items()})
    except fails as exc:  # evo's alignment (or its APE) cannot be computed here
        out = {k: v for k, v in out.items() if not k.startswith(("ate", "aoe"))}
        failed["ape"] = str(exc)
    unit = _EVO_UNITS.get(spec.rpe_unit)
    if unit is not None:

        def rpe(rel: Any, **aligned: Any) -> Any:
            return main_rpe.rpe(
                c(ref), c(est), rel, delta=spec.rpe_delta, delta_unit=em.Unit[unit],
                rel_delta_tol=spec.rpe_tolerance, all_pairs=bool(spec.rpe_all_pairs),
                pairs_from_reference=spec.rpe_pairs == "reference", **aligned,
            )  # fmt: skip

        for name, rel in (("rpe_trans", em.PoseRelation.translation_part),
                          ("rpe_rot", em.PoseRelation.rotation_angle_deg)):  # fmt: skip
            try:
                r = rpe(rel, **align)
            except filters.FilterException as exc:  # evo_rpe raises where lorisnb gives NaN with a warning
                out["rpe_refused"] = str(exc)
                break
            except fails as exc:  # evo aligns before it pairs: is there a pair at all? (no pair: refused, as above)
                out = {k: v for k, v in out.items() if not k.startswith("rpe_")}
                try:
                    paired = rpe(rel)  # its pairs, which no alignment changes
                except filters.FilterException as no_pair:
                    out["rpe_refused"] = str(no_pair)
                    break
                except fails:
                    paired = None
                failed["rpe"] = str(exc)
                if paired is not None:
                    out["rpe_pairs"] = len(paired.np_arrays["error_array"])
                break
            out.update({f"{name}_{k}": v for k, v in r.stats.items()})
            out["rpe_pairs"] = len(r.np_arrays["error_array"])
    if failed:
        out["failed"] = failed
    return out


def evo_on_pairs(errors: Any, spec: EvalSpec, alignment: str) -> dict[str, Any]:
    """What evo computes on lorisnb's own pose pairs (``errors``: the
    :class:`~lorisnb.core.pipeline.model.SequenceErrors` of the pair, its matched ground truth and
    aligned estimate): evo's APE statistics, and its RPE ones where evo has the spec's RPE unit,
    keyed as :func:`evo_statistics` keys them. This is evo's number under lorisnb's stated
    definitions (its association, dropped poses, transform, alignment): a difference from evo's own
    value is explained by them only if lorisnb's number is this one. An SE(3) or Sim(3) alignment is
    fitted again by evo (on pairs lorisnb aligned best, the identity: a worse fit shows); another
    (``posyaw``, ``origin``, the first frames) is lorisnb's. Empty where it cannot be computed (no
    orientation kept, evo raising)."""
    em = require("evo.core.metrics")
    main_ape, main_rpe = require("evo.main_ape"), require("evo.main_rpe")
    from evo.core.trajectory import PoseTrajectory3D

    if errors.gt_quaternions is None or errors.est_quaternions is None or not errors.matched:
        return {}

    def traj(positions: np.ndarray, quaternions: np.ndarray) -> Any:
        return PoseTrajectory3D(positions_xyz=np.array(positions, dtype=float),
                                orientations_quat_wxyz=np.asarray(quaternions)[:, [3, 0, 1, 2]],
                                timestamps=np.array(errors.stamps, dtype=float))  # fmt: skip

    ref, est = traj(errors.gt_positions, errors.gt_quaternions), traj(errors.est_positions, errors.est_quaternions)
    refit = alignment in ("se3", "sim3") and spec.align_frames is None
    align = dict(align=refit, correct_scale=refit and alignment == "sim3")
    out: dict[str, Any] = {}
    c = copy.deepcopy
    try:
        for name, rel in (("ate", em.PoseRelation.translation_part), ("aoe", em.PoseRelation.rotation_angle_deg)):
            out.update({f"{name}_{k}": v for k, v in main_ape.ape(c(ref), c(est), rel, **align).stats.items()})
    except Exception:  # evo's GeometryException, numpy's LinAlgError: nothing recomputed, nothing explained
        return {}
    unit = _EVO_UNITS.get(spec.rpe_unit)
    if unit is not None:
        try:
            for name, rel in (("rpe_trans", em.PoseRelation.translation_part),
                              ("rpe_rot", em.PoseRelation.rotation_angle_deg)):  # fmt: skip
                r = main_rpe.rpe(
                    c(ref), c(est), rel, delta=spec.rpe_delta, delta_unit=em.Unit[unit],
                    rel_delta_tol=spec.rpe_tolerance, all_pairs=bool(spec.rpe_all_pairs),
                    pairs_from_reference=spec.rpe_pairs == "reference", **align,
                )  # fmt: skip
                out.update({f"{name}_{k}": v for k, v in r.stats.items()})
                out["rpe_pairs"] = len(r.np_arrays["error_array"])
        except Exception:  # evo's FilterException (no RPE pair), or evo raising: the RPE rows are not explained
            out = {k: v for k, v in out.items() if not k.startswith("rpe")}
    return out


def crosscheck_evo(
    groundtruth: str | os.PathLike,
    estimate: str | os.PathLike,
    spec: EvalSpec | str | None = "evo",
    *,
    fmt: str = "tum",
    gt_fmt: str | None = None,
    topic: str | None = None,
    gt_topic: str | None = None,
    tol: float = 1e-9,
) -> pd.DataFrame:
    """Reading rows of both files, then every statistic lorisnb gives under ``spec`` against what
    evo gives reading the files itself (see the module docstring). ``fmt``: the estimate's format
    (``tum``, ``kitti``, ``euroc``, ``bag``), ``gt_fmt`` the ground truth's (default ``fmt``).
    KITTI files print rotations to 7 digits: evo computes with those blocks as they are, lorisnb
    with the nearest rotation, so pass ``tol=1e-5`` for them."""
    from lorisnb.tools.evaluation.runner import evaluate_pairs

    the_spec = make_spec(spec)
    fmt = validate.choice("fmt", fmt, TRAJECTORY_FORMATS)  # ('TUM' was read as a bag)
    gt_fmt = validate.choice("gt_fmt", gt_fmt, TRAJECTORY_FORMATS) if gt_fmt is not None else fmt
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not 0.0 <= tol < 1.0:  # (NaN too)
        raise ValidationError(f"tol={tol!r}: expected a tolerance in [0, 1) (1e-9; 1e-5 for KITTI's 7 digits)")
    if "openloris" in (fmt, gt_fmt):
        raise ValidationError(
            "format openloris: evo reads no OpenLORIS files (scene: and frame: headers, seq: blocks, ground truth in "
            "base_link); compare one with evo on identical pairs, each sequence in its sensor frame, with "
            "lorisnb crosscheck GT EST --format openloris [--seq N] without --conventions (crosscheck_openloris "
            "in Python), or write each sequence as a TUM file"
        )
    if the_spec.rpe_all_pairs is None and the_spec.rpe_unit != "s":
        the_spec = make_spec(the_spec, rpe_all_pairs=False)  # lorisnb's own pairs have no evo equivalent
    reading = []
    for label, path, f, t in (("ground truth", groundtruth, gt_fmt, gt_topic), ("estimate", estimate, fmt, topic)):
        r = crosscheck_reading(path, f, t)
        r["quantity"] = label + ": " + r["quantity"]
        reading.append(r)
    ev = evaluate_pairs(estimate, groundtruth, the_spec, fmt=fmt, gt_fmt=gt_fmt, topic=topic, gt_topic=gt_topic)
    if ev.failures:
        raise ev_error(ev)
    ours = ev.sequences().iloc[0]
    if not ours["poses"]:
        raise EvaluationError(f"{estimate}: the estimate has no poses (only comments or blank lines?): nothing to "
                              "compare; check that the file is the right one and that the run wrote its output")  # fmt: skip
    if not ours["matched"]:  # lorisnb's reason (with its advice) rather than evo's SyncException
        why = [w for w in ev.warnings if any(w.startswith(f.error) for f in ev.unscored)] or [
            f.error for f in ev.unscored] or [f"{estimate}: no pose matched the ground truth"]  # fmt: skip
        raise EvaluationError(f"{why[0]} Nothing to compare with evo.")
    how = the_spec.alignment_for(str(ours["algorithm"]))  # auto: what lorisnb chose for this algorithm
    shown = how if how == the_spec.align else f"{how} ({the_spec.align})"
    ref, est = evo_read(groundtruth, gt_fmt, gt_topic), evo_read(estimate, fmt, topic)
    theirs = evo_statistics(ref, est, the_spec, how)
    failed: dict[str, str] = theirs.pop("failed", {})
    formed = lorisnb_pairs(groundtruth, estimate, the_spec, fmt, gt_fmt, topic, gt_topic)
    evo_pairs = theirs.pop("pairs", None)  # (not a statistic: compared here, not shown)
    identical = formed is not None and identical_pairs(formed[0], evo_pairs, the_spec.transform is not None)
    lacks = evo_lacks(the_spec)
    pairs_note = ""
    identical = identical and evo_lacks(the_spec, True) != lacks  # (evo's own association: nothing to say)
    if identical and formed is not None:  # the association and the repeated rule changed nothing: judged by value
        n_formed = len(formed[0].gt_positions)
        sync = "interpolating sync" if the_spec.association == "evo-interpolate" else "nearest-stamp sync"
        pairs_note = "identical pairs (" + ("by index" if formed[1] else
                                            f"association {the_spec.association} and evo's {sync} pair the same "
                                            f"{n_formed} poses") + ")"  # fmt: skip
    nan_poses = non_finite_poses(ref, est, groundtruth, estimate)
    if failed and (nan_poses or not lacks):  # not a definition evo lacks: evo cannot evaluate what lorisnb did
        raise EvaluationError(
            f"evo cannot evaluate this pair: {next(iter(failed.values()))}; "
            + (f"{nan_poses}: lorisnb skips NaN poses, evo does not; remove them to compare with evo" if nan_poses
               else "check the poses of both files (evo's alignment needs 3 matched poses not on one line)")
        )  # fmt: skip
    order, all_rows = evo_order(ref, est, groundtruth, estimate, the_spec)
    sequences = [s for f in ev.errors for s in f.sequences]
    with evo_errors("cannot evaluate lorisnb's pairs", "check the poses of both files"):
        bridged = evo_on_pairs(sequences[0], the_spec, how) if len(sequences) == 1 else {}

    def note_of(rpe: bool) -> str:
        why = evo_lacks(the_spec, identical) + ([order] if order and (rpe or all_rows) else [])
        on = f"; {pairs_note}" if pairs_note else ""
        return (f"{DEFINITIONS_DIFFER}: {'; '.join(why)}{on}" if why else
                (f"{pairs_note}: " if pairs_note else "") +
                f"lorisnb (preset {the_spec.preset_name}, align {shown}) against evo reading the files itself")  # fmt: skip

    def judged(row: dict[str, Any], step: str | None = None) -> dict[str, Any]:
        """A row that differs from evo's own value by the definitions its note states: said whether evo,
        on lorisnb's pairs under those definitions (:func:`evo_on_pairs`), gives lorisnb's number. A row
        whose evo ``step`` failed (evo's substitute for a stated definition cannot be computed here) has
        no evo value; it is judged alike, and its note gives evo's reason."""
        key = row["quantity"]
        if step is not None:
            row["note"] += f"; evo's own value cannot be computed under its substitute ({failed[step]})"
        elif row["agrees"] or not str(row["note"]).startswith(DEFINITIONS_DIFFER) or not np.isfinite(row["evo"]):
            return row
        if key == "matched":  # what the association and the dropped poses decide: both stated
            size = any(w in row["note"] for w in ("association", "repeated"))
            row["note"] += (f"; {SAME_ON_PAIRS}: the association stated decides which poses pair" if size else
                            f"; {NOT_SAME_ON_PAIRS}: no definition stated changes which poses pair")  # fmt: skip
            return row
        if key not in bridged:
            row["note"] += f"; {NOT_SAME_ON_PAIRS}: evo cannot compute it on lorisnb's pairs"
            return row
        same = agreement_row(key, shown, row["lorisnb"], bridged[key], 0, "", tol)["agrees"]
        row["note"] += (f"; {SAME_ON_PAIRS if same else NOT_SAME_ON_PAIRS}: evo on lorisnb's pairs gives "
                        f"{float(bridged[key]):.10g}")  # fmt: skip
        return row

    def step_of(key: str) -> str | None:
        """The evo step whose failure left ``key`` without evo's value (None: it did not fail)."""
        if key.startswith("rpe") and _EVO_UNITS.get(the_spec.rpe_unit) is None:
            return None  # a unit evo has not: said as such, whatever evo's sync did
        step = "sync" if "sync" in failed else "rpe" if key.startswith("rpe") else "ape"
        return step if step in failed and key not in theirs else None

    rows = [judged(agreement_row("matched", shown, ours["matched"], theirs.get("matched", np.nan), ours["matched"],
                                 note_of(False)), step_of("matched"))]  # fmt: skip
    if "rpe_pairs" in theirs or step_of("rpe_pairs"):
        rows.append(judged(agreement_row("rpe_pairs", shown, ours["rpe_pairs"], theirs.get("rpe_pairs", np.nan),
                                         ours["rpe_pairs"], note_of(True)), step_of("rpe_pairs")))  # fmt: skip
    for m in ("ate", "aoe", "rpe_trans", "rpe_rot"):
        n = ours["rpe_pairs"] if m.startswith("rpe") else ours["matched"]  # what the statistics are over
        note = note_of(m.startswith("rpe"))
        for k in STATISTICS:
            key = f"{m}_{k}"
            if key in theirs or step_of(key):
                rows.append(judged(agreement_row(key, shown, ours[key], theirs.get(key, np.nan), n, note, tol),
                                   step_of(key)))  # fmt: skip
            elif "rpe_refused" in theirs and m.startswith("rpe"):
                rows.append(agreement_row(key, shown, ours[key], float("nan"), 0,
                                          f"{NO_RPE_PAIR}: evo_rpe raises ({theirs['rpe_refused']}); lorisnb gives NaN "
                                          "with a warning"))  # fmt: skip
            else:
                rows.append(agreement_row(key, shown, ours[key], float("nan"), n,
                                          NO_SUCH_UNIT))  # fmt: skip
    table = pd.concat([*reading, pd.DataFrame(rows, columns=CROSSCHECK_COLUMNS)], ignore_index=True)
    table.attrs["order"] = order  # for the CLI's summary of what explains a difference
    return table


#: How a row's note states the definition that explains a difference from evo.
DEFINITIONS_DIFFER = "definitions differ"
#: How it says that evo, on lorisnb's pairs under those definitions, gives lorisnb's number (or not).
SAME_ON_PAIRS = "explained"
NOT_SAME_ON_PAIRS = "NOT explained"
NO_SUCH_UNIT = "RPE in seconds: evo has no such unit"


def explained(table: pd.DataFrame) -> pd.Series:
    """Which rows of a :func:`crosscheck_evo` table differ from evo (or have no evo value) for a
    reason their note states: the conventions are not evo's (``definitions differ: ...``) and evo,
    computing on lorisnb's pairs under them, gives lorisnb's number (``; explained: evo on
    lorisnb's pairs gives ...``; for ``matched``, a stated association or dropping of poses), or
    evo has no such quantity (RPE in seconds). A row that disagrees otherwise is unexplained: a
    stated definition that cannot produce the difference explains nothing."""
    note = table["note"].astype(str)
    stated = note.str.startswith(DEFINITIONS_DIFFER) & note.str.contains(f"; {SAME_ON_PAIRS}", regex=False)
    return ~table["agrees"].astype(bool) & (stated | (note == NO_SUCH_UNIT))


def non_finite_poses(ref: Any, est: Any, groundtruth: str | os.PathLike, estimate: str | os.PathLike) -> str:
    """Which of the two trajectories evo read hold poses with NaN or infinite values, with how many
    (``FILE (N poses)``, joined by ``and``; empty when none): lorisnb skips them, evo computes with them."""
    found = []
    for path, traj in ((groundtruth, ref), (estimate, est)):
        values = np.hstack([np.asarray(traj.positions_xyz, float), np.asarray(traj.orientations_quat_wxyz, float)])
        n = int(np.count_nonzero(~np.isfinite(values).all(axis=1)))
        if n:
            found.append(f"{os.fspath(path)} ({n} {'pose' if n == 1 else 'poses'})")
    return " and ".join(found)


def ev_error(ev) -> Exception:
    return EvaluationError("; ".join(f.error for f in ev.failures))
