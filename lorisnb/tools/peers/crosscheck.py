"""Cross-checks of lorisnb against evo: every number the two compute in common, on identically
associated pose pairs, and where their definitions differ, with the size of the difference.

Columns of every table: :data:`~lorisnb.tools.peers.evo_bridge.CROSSCHECK_COLUMNS`.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Sequence

import numpy as np
import pandas as pd

from lorisnb.core.alignment.association import MAX_GAP, groundtruth_in_frame
from lorisnb.core.lifelong.scoring import score, score_rows
from lorisnb.core.metrics import openloris as metrics
from lorisnb.core.pipeline.model import ResultFile, is_monocular
from lorisnb.core.pipeline.sessions import compute_errors, evaluate_sessions
from lorisnb.core.spec import validate
from lorisnb.core.spec.evalspec import EvalSpec, make_spec
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.errors import EvaluationError, LorisWarning, ValidationError
from lorisnb.io.datasets.paths import DataPaths, DataRoot, load_groundtruth
from lorisnb.io.readers.openloris import read_openloris
from lorisnb.tools._extras import require
from lorisnb.tools.peers.evo_bridge import (
    CROSSCHECK_COLUMNS,
    EVO_MAX_DIFF,
    NO_RPE_PAIR,
    SMALLER_DELTA,
    PairedPoses,
    agreement_row,
    aligned_estimate,
    check_rpe_deltas,
    crosscheck_flags,
    evo_aligned,
    evo_ape,
    evo_pairs,
    evo_rpe,
    pair_poses,
    to_evo,
)


def crosscheck_pairs(
    p: PairedPoses, rpe_deltas=((1, "f"), (1.0, "m")), rpe_alignment: str = "se3", all_pairs: bool = False
) -> list[dict]:
    """The identical-pairs part of :func:`crosscheck` (rows that must agree)."""
    ref_t, est_t = p.as_trajectories()
    ref, est = to_evo(ref_t), to_evo(est_t)
    rows = []
    note = f"identical pairs ({p.how})"
    for alignment in ("none", "se3", "sim3"):
        pos, rot, sim = aligned_estimate(p, alignment)
        e = evo_aligned(ref, est, alignment)
        ate_l = metrics.ate(pos, p.gt_positions)
        ate_e = evo_ape(ref, e, "t")
        aoe_l = metrics.aoe(rot, p.gt_rotations)
        aoe_e = evo_ape(ref, e, "r")
        for q, f in (
            ("ate_rmse", lambda v: metrics.rmse(v)),
            ("ate_mean", np.mean),
            ("ate_median", np.median),
            ("ate_max", np.max),
        ):
            rows.append(agreement_row(q, alignment, f(ate_l), f(ate_e), len(p), note + "; metres"))
        rows.append(
            agreement_row(
                "aoe_rmse",
                alignment,
                metrics.rmse(aoe_l),
                metrics.rmse(aoe_e),
                len(p),
                note + "; degrees" + ("; Sim(3) scale does not change orientations" if alignment == "sim3" else ""),
            )
        )
    pos, rot, _ = aligned_estimate(p, rpe_alignment)
    e = evo_aligned(ref, est, rpe_alignment)
    for delta, unit in rpe_deltas:
        kind = f"{'all' if all_pairs else 'consecutive'} pairs"
        how = (
            f"delta {int(delta)} frame(s), {kind}"
            if unit == "f"
            else f"delta {delta:g} m along the ground truth, evo's {kind}"
        )
        try:
            if unit == "f":
                i, j = metrics.rpe_pairs(p.stamps, p.gt_positions, delta, "f", all_pairs=all_pairs)
            else:
                i, j = evo_pairs(p.gt_positions, delta, "m", all_pairs)
            if len(i) == 0:
                raise EvaluationError(f"only {len(p)} paired poses; {SMALLER_DELTA}")
        except EvaluationError as exc:  # no pair at this delta (evo raises): NaN rows that say so
            for q in ("rpe_trans_rmse", "rpe_rot_rmse"):
                rows.append(agreement_row(q, rpe_alignment, np.nan, np.nan, 0, f"{NO_RPE_PAIR} ({how}): {exc}"))
            continue
        tr, rr = metrics.rpe(p.gt_positions, p.gt_rotations, pos, rot, i, j)
        try:
            tr_e = evo_rpe(ref, e, "t", delta, unit, all_pairs)
            rr_e = evo_rpe(ref, e, "r", delta, unit, all_pairs)
        except EvaluationError as exc:  # evo refuses deltas it cannot pair
            rows.append(
                agreement_row("rpe_trans_rmse", rpe_alignment, metrics.rmse(tr), np.nan, len(i), f"{how}; {exc}")
            )
            continue
        rows.append(
            agreement_row(
                "rpe_trans_rmse", rpe_alignment, metrics.rmse(tr), metrics.rmse(tr_e), len(i), f"{note}; {how}; metres"
            )
        )
        rows.append(
            agreement_row(
                "rpe_rot_rmse", rpe_alignment, metrics.rmse(rr), metrics.rmse(rr_e), len(i), f"{note}; {how}; degrees"
            )
        )
    return rows


def crosscheck_conventions(gt: Trajectory, est: Trajectory) -> list[dict]:
    """lorisnb under TUM's and rpg's conventions (:mod:`lorisnb.core.conventions.choices`), against evo
    on the same matched pairs and alignment; and rpg's relative error (no evo equivalent).
    lorisnb reproduces TUM's ``evaluate_ate.py`` and rpg_trajectory_evaluation on the bundled
    TUM pairs to 1e-12 (``tests/tools/test_pairs.py``, values from the tools themselves)."""
    from scipy.spatial.transform import Rotation

    from lorisnb.core.conventions.choices import Conventions
    from lorisnb.core.metrics.relative import rpg_relative_errors
    from lorisnb.core.pipeline.sessions import match, session_errors

    rows = []
    for name, label in (
        ("tum", "TUM evaluate_ate.py: nearest stamps within 0.02 s (greedy), SE(3)"),
        ("rpg", "rpg_trajectory_evaluation: nearest stamps within 0.02 s, Sim(3)"),
    ):
        conv = Conventions.preset(name)
        a = match(gt, est, conv)
        if len(a) < 3 or a.gt_rotations is None:
            rows.append(agreement_row("ate_rmse", conv.align, np.nan, np.nan, len(a), f"{label}: too few matches"))
            continue
        fe = session_errors({1: gt}, {1: est}, conv).sequences[0]
        p = PairedPoses(
            a.stamps, a.gt_positions, a.gt_rotations, est.positions[a.est_index],
            Rotation.from_quat(est.quaternions[a.est_index]), f"{name} convention",
        )  # fmt: skip
        ref_t, est_t = p.as_trajectories()
        e = evo_aligned(to_evo(ref_t), to_evo(est_t), conv.align)
        ref = to_evo(ref_t)
        rows.append(agreement_row("ate_rmse", conv.align, metrics.rmse(fe.ate), metrics.rmse(evo_ape(ref, e, "t")),
                                  len(a), f"{label}; evo on the same pairs; metres"))  # fmt: skip
        rows.append(agreement_row("aoe_rmse", conv.align, metrics.rmse(fe.aoe), metrics.rmse(evo_ape(ref, e, "r")),
                                  len(a), f"{label}; evo on the same pairs; degrees"))  # fmt: skip
        if name == "rpg":
            rel = rpg_relative_errors(
                a.gt_positions, a.gt_rotations.as_quat(), est.positions[a.est_index], est.quaternions[a.est_index],
                scale=fe.scale,
            )  # fmt: skip
            for length, g in rel.groupby("length"):
                for q, col, unit in (("rpg_rel_trans", "trans_perc", "% of the length"),
                                     ("rpg_rel_rot", "rot_deg_per_m", "deg per metre")):  # fmt: skip
                    rows.append(agreement_row(q, "sim3", g[col].mean(), np.nan, len(g),
                                              f"rpg relative error over {length:g} m, mean, {unit}; evo has no equivalent"))  # fmt: skip
    return rows


def crosscheck_native(
    gt: Trajectory, est: Trajectory, p: PairedPoses, alignment: str = "se3", max_diff: float = EVO_MAX_DIFF
) -> list[dict]:
    """Where the association differs: evo's own nearest-stamp association (``max_diff``) against
    lorisnb's interpolation, each scored after its own alignment."""
    sync = require("evo.core.sync")

    ref_e, est_e = to_evo(gt), to_evo(est)
    pos, _, _ = aligned_estimate(p, alignment)
    ours = metrics.rmse(metrics.ate(pos, p.gt_positions))
    variants = [  # (evo's association options, the note when it works, the note when it does not)
        (dict(max_diff=max_diff),
         f"definitions differ: evo pairs each pose with the nearest stamp within {max_diff} s ({{n}} pairs), "
         f"lorisnb interpolates ground truth within {MAX_GAP} s ({len(p)} pairs)",
         f"evo's nearest-stamp association within {max_diff} s found no pairs"),
        (dict(max_diff=MAX_GAP, sync_method=sync.SyncMethod.interpolation),
         f"definitions differ: evo's interpolating sync (nearest stamp within {MAX_GAP} s, then interpolation) "
         f"against lorisnb's bracket rule (both neighbours within {MAX_GAP} s)",
         "evo's interpolating sync not available"),
    ]  # fmt: skip
    rows = []
    for options, note, failed in variants:  # two association variants
        try:
            r, e = sync.associate_trajectories(ref_e, est_e, **options)
            e.align(r, correct_scale=alignment == "sim3")
            theirs = evo_ape(r, e, "t")
            rows.append(agreement_row("ate_rmse", alignment, ours, metrics.rmse(theirs), len(theirs),
                                      note.format(n=len(theirs))))  # fmt: skip
        except Exception as exc:  # evo found no pairs, or an older evo
            rows.append(agreement_row("ate_rmse", alignment, ours, np.nan, 0, f"{failed} ({exc})"))
    return rows


def crosscheck(
    gt: Trajectory,
    est: Trajectory,
    *,
    scale: bool = False,
    by_index: bool = False,
    rpe_deltas=((1, "f"), (1.0, "m")),
    all_pairs: bool = False,
    max_gap: float = MAX_GAP,
    spec: EvalSpec | None = None,
) -> pd.DataFrame:
    """Cross-check lorisnb against evo on one ground truth and one estimate (see module docstring).

    Args:
        scale: use Sim(3) for the RPE rows and the association rows (SE(3) otherwise); the APE rows
            are always given for ``none``, ``se3`` and ``sim3``.
        by_index: pair pose i with pose i (KITTI files without stamps), as evo does.
        rpe_deltas: ``(delta, unit)`` with unit ``f`` (frames) or ``m`` (metres).
        spec: the evaluation spec of the CR, CR-T and CS-R rows (lorisnb's values, as ``lorisnb
            evaluate`` gives them for the pair; evo has none); default: the OpenLORIS preset with
            this alignment and ``max_gap`` (a spec whose alignment is ``auto``: resolved as ``scale`` says).
    """
    scale, by_index, all_pairs = crosscheck_flags(scale, by_index=by_index, all_pairs=all_pairs)
    p = pair_poses(gt, est, validate.positive("max_gap", max_gap, "seconds"), by_index)
    alignment = "sim3" if scale else "se3"
    rows = crosscheck_pairs(p, check_rpe_deltas(rpe_deltas), alignment, all_pairs)
    if not by_index:
        rows += crosscheck_native(gt, est, p, alignment)
        rows += crosscheck_conventions(gt, est)
    spec = make_spec(None, align=alignment, max_gap=max_gap) if spec is None else spec
    if spec.align == "auto":  # resolved as here (the command line resolves it by the estimate's name)
        spec = make_spec(spec, align=alignment)
    rows += openloris_rows(gt, est, spec, by_index)
    return pd.DataFrame(rows, columns=CROSSCHECK_COLUMNS)


def openloris_rows(gt: Trajectory, est: Trajectory, spec: EvalSpec, by_index: bool = False) -> list[dict]:
    """CR, CR-T and CS-R of the pair as ``lorisnb evaluate`` gives them under ``spec`` (its
    association, alignment and thresholds): lorisnb's column; evo has no equivalent (NaN). Two
    files paired by index have no times, so no CR (NaN, said in the note)."""
    if by_index:
        values: dict = dict.fromkeys(metrics.RATES, np.nan)
        n, why = 0, "paired by index: the files have no times, and these metrics are fractions of time"
    else:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", LorisWarning)  # evaluate's checks: not this table's subject
            fe = evaluate_sessions({1: gt}, {1: est}, spec, checks_on=False)
        values = score_rows(fe, spec.eps, spec.phi, spec.delta, spec.tau, **spec.rpe_options())[0]
        n = values["matched"]
        why = (
            f"lorisnb evaluate's value for this pair (eps {spec.eps}, phi {spec.phi:g} deg, delta {spec.delta:g} s, "
            f"tau {spec.tau:g} s)"
        )
    note = f"OpenLORIS-Scene metric (correctness over time), {why}; evo has no equivalent"
    return [agreement_row(q, spec.align, values[q], np.nan, n, note) for q in metrics.RATES]


def crosscheck_poses(
    gt: Trajectory, est: Trajectory, *, scale: bool = False, by_index: bool = False, max_gap: float = MAX_GAP
) -> pd.DataFrame:
    """Per pose, on identical pairs after alignment: stamp, lorisnb ATE, evo APE (metres), lorisnb
    AOE, evo APE angle (degrees). They lie on the diagonal."""
    scale, by_index = crosscheck_flags(scale, by_index=by_index)
    p = pair_poses(gt, est, validate.positive("max_gap", max_gap, "seconds"), by_index)
    alignment = "sim3" if scale else "se3"
    pos, rot, _ = aligned_estimate(p, alignment)
    ref_t, est_t = p.as_trajectories()
    ref, e = to_evo(ref_t), evo_aligned(to_evo(ref_t), to_evo(est_t), alignment)
    return pd.DataFrame(
        {
            "stamp": p.stamps,
            "ate_lorisnb": metrics.ate(pos, p.gt_positions),
            "ate_evo": evo_ape(ref, e, "t"),
            "aoe_lorisnb": metrics.aoe(rot, p.gt_rotations),
            "aoe_evo": evo_ape(ref, e, "r"),
        }
    )


def crosscheck_sample(results: Sequence[ResultFile]) -> list[ResultFile]:
    """A few short files of ``results`` that still cover every algorithm (a file's folder) and
    every scene, sorted by path: each algorithm's shortest file (bytes); then, for each scene none of
    them is of, that scene's shortest file whose algorithm's pick can give way (its scene stays
    covered by another pick) takes that pick's place, else it is added. On the icra20 per-seq files of
    four algorithms in two scenes: four files, one per algorithm, both scenes."""
    size = {id(r): r.path.stat().st_size for r in results}
    shortest = sorted(results, key=lambda r: (size[id(r)], str(r.path)))
    picks: dict[str, ResultFile] = {}
    for r in shortest:
        picks.setdefault(r.path.parent.name, r)
    added: list[ResultFile] = []
    for scene in dict.fromkeys(r.scene for r in shortest):
        sample = [*picks.values(), *added]
        if any(r.scene == scene for r in sample):
            continue
        of_scene = [r for r in shortest if r.scene == scene]
        covers = {sc: sum(s.scene == sc for s in sample) for sc in {s.scene for s in sample}}
        swap = next((r for r in of_scene if covers[picks[r.path.parent.name].scene] > 1), None)  # it gives way
        if swap is not None:
            picks[swap.path.parent.name] = swap
        else:
            added.append(of_scene[0])
    return sorted([*picks.values(), *added], key=lambda r: str(r.path))


def crosscheck_openloris(
    result: ResultFile | str | os.PathLike[str],
    seq: int | None = None,
    *,
    scale: bool | str = False,
    data_root: DataRoot | DataPaths | None = None,
    groundtruth: ResultFile | None = None,
    rpe_deltas: Sequence[tuple[float, str]] = ((1, "f"), (1.0, "m")),
) -> pd.DataFrame:
    """Cross-check one sequence of an OpenLORIS result file (ground truth moved to its frame), plus
    the OpenLORIS-specific differences: lifelong alignment on the first sequence against evo's
    alignment of the sequence on itself, dropped repeated poses, and the official interpolation.

    ``result`` is the file's path or the file already read (:func:`lorisnb.io.read_openloris`).
    """
    res = result if isinstance(result, ResultFile) else read_openloris(result)
    result_path = res.path
    scene, frame = res.scene, res.frame
    gt_file = groundtruth if groundtruth is not None else load_groundtruth(scene, data_root)
    if groundtruth is not None and groundtruth.scene and groundtruth.scene != scene:  # else: "no stamp within 0.5 s"
        raise ValidationError(f"{result_path} is of scene {scene} (its scene: header), the ground truth "
                              f"{groundtruth.path} of scene {groundtruth.scene}; give the {scene} ground truth, or "
                              "'auto' to take it from the data root")  # fmt: skip
    seqs = [s for s in res.sequences if len(res.sequences[s])]
    if not seqs:
        raise EvaluationError(f"{result_path}: no sequence has poses")
    s = seq if seq is not None else seqs[0]
    if s not in res.sequences or s not in gt_file.sequences:
        raise (ValidationError if seq is not None else EvaluationError)(  # a --seq that is not there: a usage error
            f"{result_path}: sequence {s} is not in both the result ({sorted(res.sequences)}) "
            f"and the ground truth ({sorted(gt_file.sequences)})"
        )
    scale, deltas = validate.scale_value(scale), check_rpe_deltas(rpe_deltas)  # ('no' was truth-tested: Sim(3))
    with_scale = is_monocular(result_path.parent.name) if scale == "auto" else bool(scale)
    gt = groundtruth_in_frame(gt_file.sequences[s], scene, frame)
    # lorisnb evaluate's own record of the file in lifelong mode: which sequences match, which one it fitted
    lifelong = compute_errors(res, gt_file, mode="lifelong", scale=with_scale) if len(res.sequences) > 1 else None
    try:
        table = crosscheck(gt, res.sequences[s], scale=with_scale, rpe_deltas=deltas)
    except EvaluationError as exc:  # named with the file and the sequence, and where to look instead
        others = [e.seq for e in (lifelong.sequences if lifelong is not None else []) if e.matched and e.seq != s]
        where = (f"; sequence {others[0]} of the file matches the ground truth: cross-check it with --seq "
                 f"{others[0]} (seq={others[0]} in Python)" if len(others) == 1 else
                 f"; sequences {', '.join(map(str, others))} of the file match the ground truth: cross-check one "
                 "with --seq N (seq=N in Python)" if others else "")  # fmt: skip
        raise EvaluationError(f"{result_path}, seq {s}: {exc}{where}") from None
    extra = []
    alignment = "sim3" if with_scale else "se3"
    ref_rows = table[(table["quantity"] == "ate_rmse") & (table["alignment"] == alignment)].iloc[0]
    self_aligned = ref_rows["lorisnb"]
    if lifelong is not None and lifelong.aligned_on not in (None, s):  # fitted on another sequence: a difference
        ll = score(lifelong).set_index("seq").loc[s]
        first = "the first sequence with matches" if lifelong.aligned_on != min(res.sequences) else "the first sequence"
        extra.append(
            agreement_row(
                "ate_rmse",
                alignment,
                ll["ate_rmse"],
                self_aligned,
                ll["matched"],
                f"definitions differ: lorisnb lifelong mode aligns on sequence {lifelong.aligned_on} ({first}) and "
                f"applies it to sequence {s}; evo aligns sequence {s} on itself (evo column)",
            )
        )
    kept = read_openloris(result_path, remove_repeated=False)
    if len(kept.sequences[s]) != len(res.sequences[s]):
        p2 = pair_poses(groundtruth_in_frame(gt_file.sequences[s], scene, frame), kept.sequences[s])
        pos, _, _ = aligned_estimate(p2, alignment)
        extra.append(
            agreement_row(
                "ate_rmse",
                alignment,
                self_aligned,
                metrics.rmse(metrics.ate(pos, p2.gt_positions)),
                len(p2),
                f"definitions differ: lorisnb drops {len(kept.sequences[s]) - len(res.sequences[s])} "
                "repeated poses as the official tool does; evo column keeps them",
            )
        )
    exact = score(compute_errors(res, gt_file, mode="per-seq", scale=with_scale)).set_index("seq").loc[s]
    official = (
        score(compute_errors(res, gt_file, mode="per-seq", scale=with_scale, official_interpolation=True))
        .set_index("seq")
        .loc[s]
    )
    extra.append(
        agreement_row(
            "aoe_rmse",
            alignment,
            exact["aoe_rmse"],
            official["aoe_rmse"],
            exact["matched"],
            "not an evo difference: lorisnb's correct slerp (lorisnb column) against the official "
            "OpenLORIS tool's interpolation slips (second column, --official-interpolation)",
        )
    )
    out = pd.concat([table, pd.DataFrame(extra, columns=CROSSCHECK_COLUMNS)], ignore_index=True)
    out.attrs["compared"] = compared_line(s, result_path, seqs)  # the header line naming what was compared
    return out


def compared_line(seq: int, path: str | os.PathLike[str], with_poses: Sequence[int]) -> str:
    """The line saying which sequence of an OpenLORIS result file a cross-check compared (one: the
    first with poses unless ``--seq`` chose), and how to compare another."""
    others = [n for n in with_poses if n != seq]
    more = f" ({len(with_poses)} with poses: --seq N, seq=N in Python, for another)" if others else ""
    return f"sequence {seq} of {os.path.basename(path)}{more}"
