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

import numpy as np
import pandas as pd

from lorisnb.core.lifelong.aggregate import has_output
from lorisnb.errors import ValidationError

#: Values of a sequence without output (the columns not listed: NaN, or copied: labels, thresholds).
FAILED_RUN = {"poses": 0, "matched": 0, "c_matched": 0, "correct_time": 0.0, "track_time": 0.0, "cr": 0.0,
              "cr_t": 0.0, "cs_r": 0.0}  # fmt: skip
#: Columns copied from the algorithm's other rows of the scene.
COPIED = ("frame", "eps", "phi", "delta", "tau", "mode", "scale", "official_interpolation", "eps_value")


def complete(table: pd.DataFrame, expected: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Add the missing sequences of every algorithm (and trial) as failed runs.

    Args:
        table: a per-sequence table (columns ``algorithm``, ``scene``, ``seq``; ``suite`` and
            ``trial`` optional).
        expected: the sequences of each scene: columns ``scene``, ``seq`` and ``gt_duration``
            (seconds), e.g. :func:`lorisnb.core.lifelong.aggregate.durations_table`.

    An algorithm is expected to cover, in each scene that any algorithm of its suite has, every
    sequence of ``expected``, with each of its trials in that scene (trial 0 if none).

    Returns:
        (the table with a ``missing`` column, True on the added rows; the coverage, one row per
        suite, algorithm and scene: ``sequences`` with output (some trial matched a pose),
        ``expected``, ``coverage`` (a share), ``missing_seqs`` (the sequence numbers without output,
        as text), ``missing_trials`` (``"seq: trials"`` of sequences lacking some of the scene's
        trials, each added as a failed run of that trial)).
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
        for alg in dict.fromkeys(g["algorithm"]):
            mine = g[g["algorithm"] == alg]
            for scene in scenes:
                rows = mine[mine["scene"].astype(str) == scene]
                want = by_scene[scene]
                trials = sorted(set(rows["trial"])) or sorted(set(mine["trial"])) or [0]
                template = (rows if len(rows) else g[g["scene"].astype(str) == scene]).iloc[0]
                have = set(zip(rows["seq"], rows["trial"], strict=True))
                partial = {}  # a sequence with some of the scene's trials: the others count as failed runs
                for seq, duration in zip(want["seq"], want["gt_duration"], strict=True):
                    absent = [trial for trial in trials if (seq, trial) not in have]
                    if absent and len(absent) < len(trials):
                        partial[seq] = absent
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
                                                           for q, v in partial.items())))  # fmt: skip
    if added:
        extra = pd.DataFrame(added).reindex(columns=t.columns)
        for c in FAILED_RUN:
            if c in extra.columns:
                extra[c] = extra[c].astype(float)
        t = pd.concat([t, extra], ignore_index=True) if len(t) else extra
        t = t.sort_values(["suite", "algorithm", "scene", "seq", "trial"], key=_sortable, kind="stable")
    cols = ["suite", "algorithm", "scene", "sequences", "expected", "coverage", "missing_seqs", "missing_trials"]
    return t.reset_index(drop=True), pd.DataFrame(cover, columns=cols)


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
