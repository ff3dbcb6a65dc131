"""What the server shows: a submission's public view and a phase's leaderboard. Only errors and
rates leave the server: per-sequence rows keep :data:`PUBLIC_COLUMNS` (never a pose, a ground-truth
stamp or a path), and a phase whose leaderboard is ``after-close`` shows no score until it closes.

The leaderboard is the report's (:func:`lorisnb.tools.report.leaderboard.findings`, the ranks and
intervals of ``lorisnb compare``): each team's latest scored submission of the phase is one
algorithm, on the phase's sequences, a sequence without output counting as a failed run.
``rank`` is 1 + the number of teams significantly better (teams the data cannot separate share a
rank). The order within a rank, the paper's (Sec. IV: robustness first, then accuracy of the
correct poses): the metric's scene value, then the C-ATE RMSE (lower first; the CR, higher first,
when the metric is C-ATE itself), then the earlier submission.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import pandas as pd

from lorisnb.core.lifelong.aggregate import aggregate_scenes
from lorisnb.core.lifelong.coverage import COPIED, FAILED_RUN
from lorisnb.tools.challenge.config import Challenge, Phase
from lorisnb.tools.report.leaderboard import METRICS, findings

#: The per-sequence columns a team sees: rates and errors of its own estimate, nothing of the ground truth.
PUBLIC_COLUMNS = ["file", "scene", "seq", "poses", "matched", "cr", "cr_t", "cs_r", "ate_rmse", "c_ate_rmse",
                  "aoe_rmse", "reloc_time"]  # fmt: skip
BOARD_COLUMNS = ["scene", "position", "rank", "team", "value", "low", "high", "coverage", "tied_with", "c_ate_rmse",
                 "cr", "submission", "submitted"]  # fmt: skip


def phase_sequences(phase: Phase, durations: pd.DataFrame) -> pd.DataFrame:
    """The ground-truth durations of the phase's sequences (scene, seq, gt_duration...)."""
    keep = [phase.keeps(s, int(q)) for s, q in zip(durations["scene"], durations["seq"], strict=True)]
    return durations[np.array(keep, bool)].reset_index(drop=True)


def submission_view(sub: dict[str, Any], challenge: Challenge, durations: pd.DataFrame, now: float) -> dict[str, Any]:
    """A submission as its page and the API show it (see the module docstring)."""
    phase = challenge.phase(sub["phase"])
    view: dict[str, Any] = dict(
        id=sub["id"], team=sub["team"], phase=sub["phase"], status=sub["status"], submitted=sub["created"],
        finished=sub["finished"], files=json.loads(sub["files"]), bytes=sub["bytes"], error=sub["error"],
        scores_shown=phase.shows_scores(now),
    )  # fmt: skip
    if sub["status"] != "scored" or not phase.shows_scores(now):
        if sub["status"] == "scored":
            view["hidden"] = f"scores of phase {phase.name!r} are shown once it closes"
        return view
    result = json.loads(sub["result"])
    wanted = phase_sequences(phase, durations)
    rows = [{k: r.get(k) for k in PUBLIC_COLUMNS} | {"ranked": phase.keeps(r["scene"], int(r["seq"]))}
            for r in result["rows"]]  # fmt: skip
    have = {(r["scene"], int(r["seq"])) for r in rows}
    missing = [dict(scene=s, seq=int(q), error="no output for this sequence: it counts as a failed run")
               for s, q in zip(wanted["scene"], wanted["seq"], strict=True) if (s, int(q)) not in have]  # fmt: skip
    view.update(rows=rows, failures=result["failures"], missing=missing, notes=result["notes"],
                conventions=result["conventions"], figure=bool(result.get("figure")))  # fmt: skip
    return view


def latest_scored(subs: list[dict[str, Any]], phase: str) -> list[dict[str, Any]]:
    """Each team's latest scored submission of the phase."""
    latest: dict[int, dict[str, Any]] = {}
    for s in sorted(subs, key=lambda s: s["created"]):
        if s["phase"] == phase and s["status"] == "scored":
            latest[s["team_id"]] = s
    return list(latest.values())


def leaderboard(challenge: Challenge, phase: Phase, subs: list[dict[str, Any]], durations: pd.DataFrame,
                now: float) -> dict[str, Any]:  # fmt: skip
    """The phase's leaderboard (rows of :data:`BOARD_COLUMNS`, one per scene and team), its
    sentences and the test behind the ranks; empty with a reason while scores are hidden."""
    out: dict[str, Any] = dict(phase=phase.name, metric=challenge.metric, opens=phase.opens, closes=phase.closes,
                               metric_name=METRICS.get(challenge.metric, (challenge.metric, True))[0],
                               rows=[], sentences=[], test="", hidden=None, without_output=[])  # fmt: skip
    if not phase.shows_scores(now):
        out["hidden"] = f"the leaderboard of phase {phase.name!r} is shown once it closes"
        return out
    latest = latest_scored(subs, phase.name)
    wanted = phase_sequences(phase, durations)
    # a team's trials (files named ..._trial2.txt) stay trials: the ranks' tests use them
    rows = [dict(r, algorithm=s["team"], suite="") for s in latest for r in json.loads(s["result"])["rows"]
            if phase.keeps(r["scene"], int(r["seq"]))]  # fmt: skip
    out["without_output"] = sorted(s["team"] for s in latest if s["team"] not in {r["algorithm"] for r in rows})
    if not rows:
        return out
    rows += _failed_teams(out["without_output"], rows, wanted)
    table = pd.DataFrame(rows)
    f = findings(table, wanted, challenge.metric)
    board = f.board.rename(columns={"algorithm": "team"})
    scenes = aggregate_scenes(table, wanted)[["scene", "algorithm", "cr", "c_ate_rmse"]].rename(
        columns={"algorithm": "team"}
    )
    board = board.merge(scenes, on=["scene", "team"], how="left")
    when = {s["team"]: s for s in latest}
    board["submission"] = [when[t]["id"] for t in board["team"]]
    board["submitted"] = [when[t]["created"] for t in board["team"]]
    higher = METRICS.get(challenge.metric, ("", True))[1]
    second, second_higher = ("cr", True) if challenge.metric == "c_ate_rmse" else ("c_ate_rmse", False)
    missing = np.inf if not higher else -np.inf
    board["_v"] = board["value"].fillna(missing) * (-1 if higher else 1)
    board["_s"] = board[second].fillna(-np.inf if second_higher else np.inf) * (-1 if second_higher else 1)
    board = board.sort_values(["scene", "rank", "_v", "_s", "submitted"]).drop(columns=["_v", "_s"])
    board["position"] = board.groupby("scene").cumcount() + 1
    order = {s: i for i, s in enumerate(phase.scenes)}
    board = board.sort_values(["scene", "position"], key=lambda c: c.map(order) if c.name == "scene" else c)
    out["rows"] = [{k: _plain(r[k]) for k in BOARD_COLUMNS} for _, r in board.iterrows()]
    out["sentences"] = [f.sentences[k] for k in f.sentences]
    out["test"] = f.test
    return out


def _failed_teams(teams: list[str], rows: list[dict[str, Any]], wanted: pd.DataFrame) -> list[dict[str, Any]]:
    """A failed run of the phase's first sequence for each team whose latest submission has no
    output on the phase: the leaderboard's coverage rule (:func:`lorisnb.core.lifelong.coverage.complete`)
    then counts every other sequence of theirs as failed too, so they are ranked (CR 0), not left out."""
    if not teams or wanted.empty:
        return []
    first = wanted.iloc[0]
    like = next((r for r in rows if r["scene"] == first["scene"]), rows[0])
    copied = {k: like[k] for k in COPIED if k in like}
    return [copied | FAILED_RUN | dict(algorithm=team, suite="", file="", scene=first["scene"], seq=int(first["seq"]),
                                       trial=0, gt_duration=float(first["gt_duration"])) for team in teams]  # fmt: skip


def _plain(v: Any) -> Any:
    if hasattr(v, "item"):
        v = v.item()
    if isinstance(v, float) and not np.isfinite(v):
        return None
    return v
