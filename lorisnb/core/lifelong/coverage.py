"""Coverage: a sequence an algorithm has no output for counts as the paper counts missing output.

In the OpenLORIS-Scene paper a scene's CR is the correct time over the ground-truth time of *all*
its sequences (Eq. 2), so a sequence without output adds nothing correct and its whole duration
(:func:`lorisnb.core.lifelong.aggregate.aggregate_scenes` does the same). :func:`complete` adds such a
sequence to a per-sequence table as a failed run, so that every statistic (intervals, tests,
rankings, diffs) sees the same sequences for every algorithm: CR, CR-T and CS-R 0, nothing matched,
no correct time, errors (ATE, AOE, C-ATE, RPE) undefined. CR-T is weighted by tracked time, which is
0, so CR-T keeps its meaning (correct over tracked time); C-ATE is over correct poses, of which
there are none.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import pandas as pd

from lorisnb.core.lifelong.aggregate import has_output
from lorisnb.errors import ValidationError

#: Values of a sequence without output (the columns not listed: NaN, or copied: labels, thresholds).
FAILED_RUN = {"poses": 0, "matched": 0, "c_matched": 0, "correct_time": 0.0, "track_time": 0.0, "cr": 0.0,
              "cr_t": 0.0, "cs_r": 0.0}  # fmt: skip
#: Columns copied from the algorithm's other rows of the scene.
COPIED = ("frame", "eps", "phi", "delta", "tau", "mode", "scale", "official_interpolation", "eps_value")


def complete(
    table: pd.DataFrame, expected: pd.DataFrame, peers: bool = False, lost: Iterable[tuple[str, str, int]] = ()
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Add the missing sequences of every algorithm (and trial) as failed runs.

    Args:
        table: a per-sequence table (columns ``algorithm``, ``scene``, ``seq``; ``suite`` and
            ``trial`` optional).
        expected: the sequences of each scene: columns ``scene``, ``seq`` and ``gt_duration``
            (seconds), e.g. :func:`lorisnb.core.lifelong.aggregate.durations_table`.

        peers: also expect, of an algorithm with numbered trials, as many trials as the other
            algorithms of its suite have in the scene (``compare``: the algorithms of one
            comparison); a diff or a history compares an algorithm with itself only.
        lost: (suite, algorithm, trial) of runs known to have left no output (an empty trial
            folder: :attr:`lorisnb.tools.evaluation.result.Failure.trials`), expected as that
            algorithm's trials too, so each is a failed run of every sequence.

    An algorithm is expected to cover, in each scene that any algorithm of its suite has, every
    sequence of ``expected``, with each of its trials, those of every scene of its suite (trial 0
    if none): the expected trials never depend on what a crashed trial left behind, so a trial
    without a single file (a crash, an empty or never created ``trial3/``) is a failed run of every
    sequence, as a sequence missing from a trial is. With ``peers``, an algorithm with fewer
    trials than another of the scene gets the labels it lacks of theirs (trial numbers are labels,
    not pairings: 1 to 3 against 0 to 2 lacks nothing), or new ones; a single unnumbered run (trial
    0 alone) is one run, beside reruns of another algorithm, not a crash.

    Returns:
        (the table with a ``missing`` column, True on the added rows; the coverage, one row per
        suite, algorithm and scene: ``sequences`` with output (some trial matched a pose),
        ``expected``, ``coverage`` (a share), ``missing_seqs`` (the sequence numbers without output,
        as text), ``missing_trials`` (``"seq: trials"`` of sequences lacking some of the scene's
        trials, each added as a failed run of that trial), ``lost_trials`` (the trials with no
        output at all in the scene, as text, each added as a failed run of every sequence) and
        ``trials_expected`` (how many, and why: ``"3, as B has in this scene"``)).
    """
    for c in ("algorithm", "scene", "seq"):
        if c not in table.columns:
            raise ValidationError(f"the table lacks column {c}; expected a per-sequence table (score)")
    for c in ("scene", "seq", "gt_duration"):
        if c not in expected.columns:
            raise ValidationError(f"expected sequences lack column {c}; expected a durations table")
    t = table.copy()
    for c, v in (("suite", ""), ("trial", 0)):
        if c not in t.columns:
            t[c] = v
    t["missing"] = False
    exp = expected.drop_duplicates(["scene", "seq"]).astype({"scene": str})
    by_scene = {s: g for s, g in exp.groupby("scene", sort=False)}
    added, cover = [], []
    for suite, g in t.groupby("suite", sort=False, observed=True):
        scenes = [s for s in dict.fromkeys(g["scene"].astype(str)) if s in by_scene]
        own = {alg: set(m["trial"]) for alg, m in g.groupby("algorithm", sort=False, observed=True)}
        for s, alg, trial in lost:
            if s == suite and alg in own:
                own[alg].add(trial)
        for alg in dict.fromkeys(g["algorithm"]):
            mine = g[g["algorithm"] == alg]
            for scene in scenes:
                rows = mine[mine["scene"].astype(str) == scene]
                want = by_scene[scene]
                here = g[g["scene"].astype(str) == scene]
                trials, why = expected_trials(alg, own, here, peers)
                template = (rows if len(rows) else here).iloc[0]
                have = set(zip(rows["seq"], rows["trial"], strict=True))
                lost = [trial for trial in trials if trial not in set(rows["trial"])] if len(rows) else []
                partial = {}  # a sequence with some of the scene's trials: the others count as failed runs
                for seq, duration in zip(want["seq"], want["gt_duration"], strict=True):
                    absent = [trial for trial in trials if (seq, trial) not in have]
                    if absent and len(absent) < len(trials) and set(absent) - set(lost):
                        partial[seq] = [trial for trial in absent if trial not in lost]
                    for trial in absent:
                        row = {c: template[c] for c in COPIED if c in t.columns}
                        row.update(FAILED_RUN, suite=suite, algorithm=alg, scene=template["scene"], seq=seq,
                                   trial=trial, gt_duration=float(duration), file="", missing=True)  # fmt: skip
                        added.append(row)
                # with output: some trial of the sequence matched a pose (a row without one is a failed run)
                ran = rows if "matched" not in rows.columns else rows[has_output(rows["matched"])]
                lacking = sorted(set(want["seq"]) - set(ran["seq"]))
                cover.append(dict(suite=suite, algorithm=alg, scene=scene, sequences=len(want) - len(lacking),
                                  expected=len(want), coverage=(len(want) - len(lacking)) / len(want),
                                  missing_seqs=", ".join(str(s) for s in lacking),
                                  missing_trials="; ".join(f"{q}: {', '.join(str(x) for x in v)}"
                                                           for q, v in partial.items()),
                                  lost_trials=", ".join(str(x) for x in lost),
                                  trials_expected=f"{len(trials)}, {why}"))  # fmt: skip
    if added:
        extra = pd.DataFrame(added).reindex(columns=t.columns)
        for c in FAILED_RUN:
            if c in extra.columns:
                extra[c] = extra[c].astype(float)
        t = pd.concat([t, extra], ignore_index=True) if len(t) else extra
        t = t.sort_values(["suite", "algorithm", "scene", "seq", "trial"], key=_sortable, kind="stable")
    cols = ["suite", "algorithm", "scene", "sequences", "expected", "coverage", "missing_seqs", "missing_trials",
            "lost_trials", "trials_expected"]  # fmt: skip
    return t.reset_index(drop=True), pd.DataFrame(cover, columns=cols)


def expected_trials(alg: object, own: dict, scene: pd.DataFrame, peers: bool) -> tuple[list, str]:
    """The trials ``alg`` is expected to have in a scene (the rows of its suite there: ``scene``)
    and why: each of its own trials in any scene of its suite (``own``: algorithm -> trials), and
    with ``peers`` as many as the algorithm of the scene with most trials has (see :func:`complete`)."""
    mine = set(own.get(alg, set())) or {0}
    trials, why = sorted(mine, key=_trial_key), f"as {alg} has in the scenes of its suite"
    if not peers or mine == {0}:  # a single unnumbered run is one run beside another's reruns
        return trials, why
    others = {a: set(own.get(a, set())) | set(g["trial"])
              for a, g in scene.groupby("algorithm", sort=False, observed=True) if a != alg}  # fmt: skip
    if not others:
        return trials, why
    most = max(others, key=lambda a: len(others[a]))
    if len(others[most]) <= len(mine):
        return trials, why
    labels = set().union(*others.values()) - mine
    low = min(mine, key=_trial_key)
    order = sorted((x for x in labels if _trial_key(x) >= _trial_key(low)), key=_trial_key) + sorted(
        (x for x in labels if _trial_key(x) < _trial_key(low)), key=_trial_key, reverse=True
    )
    extra = order[: len(others[most]) - len(mine)]
    top = max(_trial_key(x) for x in mine | labels)
    extra += [top + 1 + k for k in range(len(others[most]) - len(mine) - len(extra))]
    here = set(scene.loc[scene["algorithm"] == most, "trial"])  # its trials here, or also elsewhere in its suite
    where = "in this scene" if len(here) >= len(others[most]) else "in the scenes of its suite"
    return sorted(mine | set(extra), key=_trial_key), f"as {most} has {where}"


def _trial_key(x: object) -> float:
    try:
        return float(x)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return float("inf")


def _sortable(c: pd.Series) -> pd.Series:
    return c if c.name in ("seq", "trial") else c.astype(str)


def coverage_notes(cover: pd.DataFrame) -> list[str]:
    """One line per algorithm and scene that lacks sequences (naming them), and one per algorithm
    and scene whose sequences lack some of its trials (naming sequence and trials)."""
    notes = []
    for r in cover.itertuples():
        who = f"{r.algorithm}{f' ({r.suite})' if r.suite else ''}"
        if r.coverage < 1:
            notes.append(f"{who} has no output for {r.scene} sequence(s) {r.missing_seqs} (output for {r.sequences} "
                         f"of its {r.expected} sequences); they count as failed runs (CR 0, their duration counted), "
                         "as evaluate counts them")  # fmt: skip
        if getattr(r, "lost_trials", ""):
            notes.append(f"{who} has no output at all of trial(s) {r.lost_trials} in {r.scene} (a crashed or missing "
                         f"trial; trials expected: {r.trials_expected}); each counts as a failed run of every sequence "
                         "(CR 0, its duration counted)")  # fmt: skip
        if getattr(r, "missing_trials", ""):
            notes.append(f"{who} lacks trials of {r.scene} (sequence: trials) {r.missing_trials}; each counts as a "
                         "failed run of that trial")  # fmt: skip
    return notes


def expected_from(*tables: pd.DataFrame) -> pd.DataFrame:
    """The sequences of each scene seen in any of ``tables``, with their ground-truth duration."""
    parts = [t[["scene", "seq", "gt_duration"]] for t in tables if len(t) and "gt_duration" in t.columns]
    if not parts:
        return pd.DataFrame(columns=["scene", "seq", "gt_duration"])
    both = pd.concat(parts).dropna(subset=["gt_duration"])
    return (
        both.groupby(["scene", "seq"], sort=False, as_index=False)["gt_duration"]
        .max()
        .astype({"gt_duration": np.float64})
    )
