"""What the server shows: a submission's public view and a phase's leaderboard. Only errors and
rates leave the server: per-sequence rows keep :data:`PUBLIC_COLUMNS` (never a pose, a ground-truth
stamp or a path), and a phase whose leaderboard is ``after-close`` shows no score until it closes.

The leaderboard is the report's (:func:`lorisnb.tools.report.leaderboard.findings`, the ranks and
intervals of ``lorisnb compare``): each team's latest scored submission of the phase is one
algorithm, on the phase's sequences, a sequence without output counting as a failed run.
``rank`` is 1 + the number of teams significantly better (teams the data cannot separate share a
rank). The order within a rank, the paper's (Sec. IV: robustness first, then accuracy of the
correct poses): the metric's scene value, then the C-ATE RMSE (lower first; the CR, higher first,
when the metric is C-ATE itself), then the earlier submission; the two values compared to
:data:`ORDER_DIGITS` significant digits, so that results equal but for the last bits of their
floating-point means (one run, and the same run uploaded as 8 trials) are ordered by their
submission. A row's CR and C-ATE RMSE are means over its trials computed exactly
(:func:`exact_mean`: 8 copies of one value average to that value), and the column of the metric
itself is the row's ``value`` (one number, not a second computation of it). The sentence under
a scene's table is worded from that ordered table: the team it names first is the table's first.

Hidden stays hidden: a submission is scored on every sequence it has output for, but its page, its
JSON and its figure show only the sequences whose scores are visible now
(:meth:`.config.Challenge.visible`: held by a phase that is live or has closed); the others are
named, without a value, with the phase whose close shows them. Its timeline figure was drawn for
each set of visible sequences the challenge goes through (:meth:`.config.Challenge.views`), and
the one of the set visible now is shown (:func:`figure_file`). Only the admin's view
(:func:`admin_scores`) holds scores of sequences not yet shown, and says which.
"""

from __future__ import annotations

import datetime as dt
import json
import math
import re
import statistics
from collections.abc import Callable
from typing import Any

import numpy as np
import pandas as pd

from lorisnb.core.lifelong.aggregate import aggregate_scenes
from lorisnb.core.lifelong.coverage import COPIED, FAILED_RUN
from lorisnb.tools.challenge.config import Challenge, Phase, sequences_of
from lorisnb.tools.report.leaderboard import METRICS, findings, sentence

#: The per-sequence columns a team sees: rates and errors of its own estimate, nothing of the ground truth.
PUBLIC_COLUMNS = ["file", "scene", "seq", "poses", "matched", "cr", "cr_t", "cs_r", "ate_rmse", "c_ate_rmse",
                  "aoe_rmse", "reloc_time"]  # fmt: skip
BOARD_COLUMNS = ["scene", "position", "rank", "team", "value", "low", "high", "coverage", "tied_with", "c_ate_rmse",
                 "cr", "submission", "submitted"]  # fmt: skip
#: The significant digits the order within a rank compares the metric's value and the C-ATE RMSE
#: (or the CR) to: two values that agree to these are equal there, and the earlier submission goes
#: first (a mean's last bits depend on how many trials were summed, not on the result).
ORDER_DIGITS = 12


def phase_sequences(phase: Phase, durations: pd.DataFrame) -> pd.DataFrame:
    """The ground-truth durations of the phase's sequences (scene, seq, gt_duration...)."""
    keep = [phase.keeps(s, int(q)) for s, q in zip(durations["scene"], durations["seq"], strict=True)]
    return durations[np.array(keep, bool)].reset_index(drop=True)


def when(ts: float | None) -> str:
    """An epoch time as the pages show it (UTC, to the minute)."""
    if ts is None:
        return ""
    return dt.datetime.fromtimestamp(ts, dt.UTC).strftime("%Y-%m-%d %H:%M UTC")


def _scored(result: dict[str, Any]) -> set[tuple[str, int]]:
    return {(r["scene"], int(r["seq"])) for r in result["rows"]}


def _shown_notes(notes: list[Any], shown: frozenset[tuple[str, int]], all_shown: bool) -> list[str]:
    """The notes about sequences shown: a note names the sequences it is about (a file's, or the
    ``seq N`` it names); one of a result scored before notes did is shown only if every sequence is."""
    out = []
    for n in notes:
        if isinstance(n, str):
            if all_shown:
                out.append(n)
        elif {(s, int(q)) for s, q in n["sequences"]} <= shown:
            out.append(n["text"])
    return out


#: Sentences of a message that speak to whoever runs lorisnb (where the data root is, how to point
#: lorisnb at another): a team cannot act on them, and they name what the private data root holds.
SERVER_ADVICE = re.compile(r"--data\b|LORISNB_DATA|data[ _]root|Point lorisnb at", re.IGNORECASE)
NO_GROUNDTRUTH = re.compile(r"ground truth of scene '?(\w+)'? not found")


#: A command-line option (``--align-frames``) or a Python keyword argument (``align_frames=1``,
#: ``trials_by= in Python``) a message advises: a team passes neither (the challenge's spec is the
#: organizers', and its files are scored by the server).
OPTION = re.compile(r"(?<![\w-])--[A-Za-z][\w-]*|\b[a-z]+(?:_[a-z]+)+=|\bin Python\b")
ALTERNATIVE = re.compile(r",? or ")


def _outside(text: str, at: int) -> bool:
    """Whether position ``at`` of ``text`` is outside every parenthesis."""
    return text.count("(", 0, at) <= text.count(")", 0, at)


def _split_outside(text: str, pattern: str) -> list[str]:
    """``text`` split where ``pattern`` matches outside parentheses (a clause of a parenthesis
    stays in it: ``(median 1e18; divide by 1e9)`` is one piece)."""
    out, at = [], 0
    for m in re.finditer(pattern, text):
        if _outside(text, m.start()):
            out.append(text[at : m.start()])
            at = m.end()
    return out + [text[at:]]


def _paren_without_options(m: re.Match[str]) -> str:
    """A parenthesis of a message without its clauses (``;``-separated) that advise an option; a
    clause after one left out loses its leading ``or``/``else``; none left: the parenthesis goes."""
    clauses = m.group(2).split(";")
    kept, dropped = [], False
    for c in clauses:
        if OPTION.search(c):
            dropped = True
            continue
        c = c.strip()
        kept.append(re.sub(r"^(?:or|else)\s+", "", c) if dropped else c)
        dropped = False
    return f"{m.group(1)}({'; '.join(kept)})" if kept and any(kept) else ""


def _without_options(part: str) -> str:
    """A sentence of a message without its advice to pass options (:data:`OPTION`): of its
    alternatives (``A, or B (--opt)``, split at ``or`` outside parentheses) those naming none (a
    sentence of one alternative is kept); then a parenthesis naming one left out; empty when what
    is left still names one (all of it is such advice)."""
    if not OPTION.search(part):
        return part
    end = part[-1] if part[-1:] in ".;" else ""
    body = part[: len(part) - len(end)]
    pieces, seps, at = [], [""], 0
    for m in ALTERNATIVE.finditer(body):
        if _outside(body, m.start()):
            pieces.append(body[at : m.start()])
            seps.append(m.group())
            at = m.end()
    pieces.append(body[at:])
    kept = [(sep, piece) for k, (sep, piece) in enumerate(zip(seps, pieces, strict=True)) if not OPTION.search(piece)
            and not (k and piece.startswith("neither ") and OPTION.search(pieces[k - 1]))]  # fmt: skip
    if len(pieces) == 1:  # no alternatives: the sentence stays, without its parenthesis of options (below)
        kept = [("", body)]
    out = "".join((sep if k else "") + piece for k, (sep, piece) in enumerate(kept))
    out = re.sub(r"(\s*)\(([^()]*)\)", lambda m: _paren_without_options(m) if OPTION.search(m.group()) else m.group(),
                 out).strip()  # fmt: skip
    return "" if not out or OPTION.search(out) else out + end


def team_text(text: str, challenge: Challenge) -> str:
    """A scoring message as a team sees it: one about ground truth the server lacks says which
    scenes the challenge ranks (not which the data root holds, nor how to point lorisnb at other
    data); sentences of advice on running lorisnb with other data are left out, and so is advice
    to pass an option (:func:`_without_options`: a team uploads files, it passes no option). The
    organizer's views (the admin page, the export) keep the full text."""
    scenes = ", ".join(challenge.scenes)
    found = NO_GROUNDTRUTH.search(text)
    if found:
        scene = found.group(1)
        if scene in challenge.scenes:
            return f"the server could not read the ground truth of {scene}; tell the organizers"
        return f"{scene} is not one of this challenge's scenes; it ranks {scenes}: upload result files of those"
    text = re.sub(r"\s*\(data root [^)]*\)", "", text)
    parts = [
        p for p in _split_outside(text, r"(?<=[.;])(?<!\.\.\.)\s+") if p
    ]  # a parenthesis's ';' is not a clause's end
    kept: list[str] = []
    dropped = False  # the part before was advice, left out: a clause after its ';' goes with it
    gap = False  # a part left out since the last one kept
    for p in parts:
        if dropped and p[:1].islower():
            continue
        q = "" if SERVER_ADVICE.search(p) else _without_options(p)
        dropped = not q and p.endswith(";")
        if q:
            if gap and kept and kept[-1].endswith(";") and q[:1].isupper():  # "...; [advice.] Nothing was"
                kept[-1] = kept[-1][:-1] + "."
            kept.append(q)
        gap = not q
    if kept == parts:
        return text
    out = re.sub(r"([?!]);", r"\1", " ".join(kept))  # "text? (--opt); else" without its parenthesis
    return out.rstrip(" ;.") or "the server could not score this file; tell the organizers"


#: A copy's detail in the scorer's words (:func:`.scoring.groundtruth_copies`): the sequence it
#: names and its count of poses.
COPY_SAID = re.compile(r"(?P<scene>[a-z]+)-(?P<seq>\d+)'s (?:positions and orientations|positions|orientations) are "
                       r"the ground truth's \(all \d+ matched poses within [^()]* of it after the alignment\)")  # fmt: skip


def copies_as_shown(text: str, shown: Callable[[str, int], bool]) -> str:
    """``text`` with each copy of the ground truth it names (:func:`.scoring.groundtruth_copies`) of a
    sequence not ``shown`` said as ``a copy of the ground truth`` alone: no sequence, no count of
    its poses (nothing of a hidden sequence's ground truth is told)."""
    return COPY_SAID.sub(lambda m: m[0] if shown(m["scene"], int(m["seq"])) else "a copy of the ground truth", text)


#: The error of a submission of which nothing was scored (each file failed or was not scored):
#: ``failed``, its result kept (its failures), never ``scored`` with no error (:func:`nothing_scored`).
NOTHING_SCORED = "nothing of this upload was scored"


def scored_nothing(result: dict[str, Any]) -> bool:
    """Whether a scoring's outcome scored nothing: a file failed or was not scored, and no sequence
    has a matched pose (a file whose stamps miss its ground truth has a row of CR 0 and 0 matched,
    and its reason: no score of the team's output, never ranked as one)."""
    return bool(result.get("failures")) and not any((r.get("matched") or 0) > 0 for r in result.get("rows", []))


def nothing_scored(result: dict[str, Any]) -> str:
    """The organizer's words for a scoring that scored nothing: each file with its reason."""
    said = "; ".join(f"{f['file'] or 'the upload'}: {f['status']}: {f['error']}" for f in result.get("failures", []))
    return f"{NOTHING_SCORED}{': ' + said if said else ''}"


def _result(sub: dict[str, Any]) -> dict[str, Any] | None:
    raw = sub.get("result")
    return json.loads(raw) if raw else None


def team_error(sub: dict[str, Any], challenge: Challenge, now: float,
               durations: pd.DataFrame | None = None) -> str | None:  # fmt: skip
    """A submission's error as its team sees it at ``now`` (:func:`team_text`): a copy of the ground
    truth it holds is named by its sequence only while that sequence is shown to the team
    (:meth:`.config.Challenge.shown`: its phase's scores shown, the sequence visible), else said
    as a copy alone; decided each time it is shown, so it never tells more than the team sees then.
    A submission of which nothing was scored says each file's reason as its team is told it
    (:func:`failures_said`: a sequence not shown yet without values; needs ``durations`` and the
    submission's ``result``)."""
    if not sub["error"]:
        return sub["error"]
    result = _result(sub)
    if result is not None and sub["status"] == "failed" and "rows" in result and durations is not None:
        said = "; ".join(f"{f['file'] or 'the upload'}: {f['status']}: {f['error']}"
                         for f in failures_said(sub, result, challenge, durations, now))  # fmt: skip
        return f"{NOTHING_SCORED}{': ' + said if said else ''}"
    phase = challenge.phase(sub["phase"])
    text = copies_as_shown(str(sub["error"]), lambda scene, seq: bool(challenge.shown(phase, [(scene, seq)], now)))
    return team_text(text, challenge)


def _hidden_note(challenge: Challenge, scene: str, seq: int) -> str:
    phase = challenge.shown_by(scene, seq)
    if phase is None:
        return "in no phase of this challenge: never shown"
    return f"shown once phase {phase.name!r} {_shows_when(phase)}"


def _shows_when(phase: Phase) -> str:
    """When a phase's scores start to show, in words (:attr:`.config.Phase.shows_from`)."""
    return f"{'opens' if phase.leaderboard == 'live' else 'closes'} ({when(phase.shows_from)})"


#: Numbers a reason of a sequence not shown yet may not hold (a stamp, a span, an error: values of
#: hidden ground truth); small whole numbers (a sequence's, a count of files) are words.
VALUE = re.compile(r"\d+\.\d+|\d{3,}")


def _without_values(text: str) -> str | None:
    """A failure's reason told without a value of hidden ground truth: its first sentence without
    its parentheses holding numbers; None when a value is left even so."""
    first = re.sub(r"^seq:? ?\d+: ", "", _split_outside(text, r"(?<=[.;])\s+")[0].rstrip(" .;"))  # named before it
    first = re.sub(r"\s*\([^()]*\d[^()]*\)", "", first)
    return None if VALUE.search(first) or "(" in first else first


def failures_said(sub: dict[str, Any], result: dict[str, Any], challenge: Challenge, durations: pd.DataFrame,
                  now: float) -> list[dict[str, Any]]:  # fmt: skip
    """A submission's failures as its team is told them at ``now``: each file with its status and
    reason (:func:`team_text`), the reason in full where every sequence of the scoring that said
    it is shown (:meth:`.config.Challenge.shown`; a reason of reading a file names none: always
    told), else said with its sequences not shown yet and when they are, without a value
    (:func:`_without_values`: ``cafe-1-2.txt (not scored): cafe 2: no estimate stamp falls inside
    the ground truth's time span; the reason in full is shown once phase 'final' closes ...``)."""
    phase = challenge.phase(sub["phase"])
    every = set(sequences_of(durations))
    unseen = every - challenge.shown(phase, every, now)
    out = []
    for f in result.get("failures", []):
        about = sorted({(s, int(q)) for s, q in f.get("sequences", [])} & unseen)
        said = {k: v for k, v in f.items() if k != "sequences"}
        if not about:
            out.append(said | dict(error=team_text(str(f["error"]), challenge)))
            continue
        named = "; ".join(f"{s} {', '.join(str(q) for q in sorted(q for t, q in about if t == s))}"
                          for s in dict.fromkeys(s for s, _ in about))  # fmt: skip
        later = (f"shown once phase {phase.name!r} {_shows_when(phase)}" if not phase.shows_scores(now)
                 else _hidden_note(challenge, *about[0]))  # fmt: skip
        reason = _without_values(team_text(str(f["error"]), challenge))
        told = f"{reason}; the reason in full is {later}" if reason else f"its reason is {later}"
        out.append(said | dict(error=f"{named}: {told}", hidden=True))
    if any(f["file"] for f in out):  # "nothing was evaluated", named for no file: the files' rows say why
        out = [f for f in out if f["file"]]
    return out


def failure_lines(failures: list[dict[str, Any]]) -> list[str]:
    """Failures as the listings (the team's, the admin's) show them: ``FILE (status): reason``."""
    return [f"{f['file'] or 'the upload'} ({f['status']}): {f['error']}" for f in failures]


def missing_trials(rows: list[dict[str, Any]], wanted: pd.DataFrame) -> list[dict[str, Any]]:
    """Each sequence of the phase (``wanted``) with output in some of a submission's trials but not
    in another (``run_1/`` with home-1-2, ``run_2/`` without): that trial counts it as a failed run
    (CR 0) in its mean, said with the trial and the sequence."""
    by_seq: dict[tuple[str, int], set[int]] = {}
    for r in rows:
        by_seq.setdefault((r["scene"], int(r["seq"])), set()).add(int(r.get("trial") or 0))
    trials = set().union(*by_seq.values()) if by_seq else set()
    if len(trials) < 2:
        return []
    out = []
    for s, q in zip(wanted["scene"], wanted["seq"], strict=True):
        have = by_seq.get((s, int(q)), set())
        for t in sorted(trials - have) if have else []:
            others = f"trial {min(have)} has" if len(have) == 1 else f"trials {', '.join(map(str, sorted(have)))} have"
            out.append(dict(scene=s, seq=int(q), trial=t,
                            error=f"trial {t} has no output for {s}-1-{int(q)} ({others} one): it counts as a failed "
                            f"run (CR 0) in trial {t}"))  # fmt: skip
    return out


def submission_view(sub: dict[str, Any], challenge: Challenge, durations: pd.DataFrame, now: float) -> dict[str, Any]:
    """A submission as its page and the API show it (see the module docstring): the rows of the
    sequences visible now; ``hidden_sequences`` lists the others a file scored (scene, seq, the files,
    when shown), no value; a file of one of them that failed (its row without a matched pose, its
    failure about that sequence) is listed under ``failures`` alone, never as scored."""
    phase = challenge.phase(sub["phase"])
    view: dict[str, Any] = dict(
        id=sub["id"], team=sub["team"], phase=sub["phase"], status=sub["status"], submitted=sub["created"],
        finished=sub["finished"], files=json.loads(sub["files"]), bytes=sub["bytes"],
        error=team_error(sub, challenge, now, durations),
        scores_shown=phase.shows_scores(now),
    )  # fmt: skip
    kept = _result(sub)
    if kept is not None and "failures" in kept:  # what failed, told as the team may see it now
        view["failures"] = failures_said(sub, kept, challenge, durations, now)
    if sub["status"] != "scored" or not phase.shows_scores(now):
        if sub["status"] == "scored":
            view["hidden"] = f"scores of phase {phase.name!r} are shown once it {_shows_when(phase)}"
        return view
    result = json.loads(sub["result"])
    scored = _scored(result)
    shown = challenge.shown(phase, scored, now)
    wanted = phase_sequences(phase, durations)
    rows = [{k: r.get(k) for k in PUBLIC_COLUMNS} | {"ranked": phase.keeps(r["scene"], int(r["seq"]))}
            for r in result["rows"] if (r["scene"], int(r["seq"])) in shown]  # fmt: skip
    # a sequence not shown yet is named with the files of it that scored; one whose file failed
    # (its row of no matched pose, that file's failure about it) is a failure only (failures_said)
    failed = {(f.get("file"), s, int(q)) for f in result.get("failures", []) for s, q in f.get("sequences", [])}
    hidden = [dict(scene=s, seq=q, files=files, shown=_hidden_note(challenge, s, q)) for s, q in sorted(scored - shown)
              if (files := sorted({r["file"] for r in result["rows"] if (r["scene"], int(r["seq"])) == (s, q)
                                   and ((r.get("matched") or 0) > 0 or (r["file"], s, q) not in failed)}))]  # fmt: skip
    missing = [dict(scene=s, seq=int(q), error="no output for this sequence: it counts as a failed run")
               for s, q in zip(wanted["scene"], wanted["seq"], strict=True) if (s, int(q)) not in scored]  # fmt: skip
    missing += missing_trials([r for r in result["rows"] if (r["scene"], int(r["seq"])) in shown], wanted)
    # a failure or a note is shown when every sequence of the scoring that said it is visible
    # (its numbers, spans included, may come from any of them: a hidden one's stays hidden,
    # its failure told without values, :func:`failures_said`)
    # (a failure about a scene outside the challenge holds none of its ground truth: shown)
    told = challenge.visible(set(sequences_of(durations)) | scored, now)
    failures = view["failures"]
    notes = list(dict.fromkeys(team_text(n, challenge) for n in _shown_notes(result["notes"], told, scored <= shown)))
    view.update(rows=rows, hidden_sequences=hidden, failures=failures, missing=missing,
                notes=notes, conventions=result["conventions"],
                figure=figure_file(result, challenge, durations, now) is not None)  # fmt: skip
    return view


def figure_file(result: dict[str, Any], challenge: Challenge, durations: pd.DataFrame, now: float) -> str | None:
    """The file name of the submission's timeline figure of the sequences visible now (in its
    folder), None if it has none: one drawn for exactly the set visible now, or, for a result scored
    before figures were drawn per set, its one figure if every sequence it holds is visible."""
    visible = challenge.visible(sequences_of(durations), now)
    figures = result.get("figures")
    if figures is None:
        return "timeline.png" if result.get("figure") and _scored(result) <= visible else None
    for f in figures:
        if {(s, int(q)) for s, q in f["sequences"]} == visible and re.fullmatch(
            r"(?:claims/\w+/)?timeline-\d+\.png", f["file"]
        ):
            return str(f["file"])
    return None


def admin_scores(sub: dict[str, Any], challenge: Challenge, now: float) -> list[dict[str, Any]]:
    """Every scored sequence of a submission with its CR and C-ATE RMSE and whether teams see it
    now (``shown``): the admin's view, which alone holds scores not yet shown."""
    if sub["status"] != "scored" or not sub.get("result"):
        return []
    phase = challenge.phase(sub["phase"])
    result = json.loads(sub["result"])
    shown = challenge.shown(phase, _scored(result), now)
    return [dict(scene=r["scene"], seq=int(r["seq"]), file=r.get("file"), cr=r.get("cr"), c_ate_rmse=r.get("c_ate_rmse"),
                 shown=(r["scene"], int(r["seq"])) in shown) for r in result["rows"]]  # fmt: skip


def latest_scored(subs: list[dict[str, Any]], phase: str) -> list[dict[str, Any]]:
    """Each team's latest scored submission of the phase: one that scored something (a submission
    of which nothing was scored is ``failed``, :func:`nothing_scored`, and leaves the team's
    standing as it was)."""
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
        out["hidden"] = f"the leaderboard of phase {phase.name!r} is shown once it {_shows_when(phase)}"
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
    f = findings(table, wanted, challenge.metric, who="teams")
    board = f.board.rename(columns={"algorithm": "team"})
    scenes = aggregate_scenes(table, wanted)[["scene", "algorithm", "cr", "c_ate_rmse"]].rename(
        columns={"algorithm": "team"}
    )  # a team's trials: one row each here, one value on the board (their exact mean, as compare's value)
    scenes = scenes.groupby(["scene", "team"], as_index=False, sort=False)[["cr", "c_ate_rmse"]].agg(exact_mean)
    board = board.merge(scenes, on=["scene", "team"], how="left", validate="one_to_one")
    if challenge.metric in ("cr", "c_ate_rmse"):  # the metric's column is the value ranked on: one number
        board[challenge.metric] = board["value"]
    when = {s["team"]: s for s in latest}
    board["submission"] = [when[t]["id"] for t in board["team"]]
    board["submitted"] = [when[t]["created"] for t in board["team"]]
    higher = METRICS.get(challenge.metric, ("", True))[1]
    second, second_higher = ("cr", True) if challenge.metric == "c_ate_rmse" else ("c_ate_rmse", False)
    board["_v"] = [order_key(v, higher) for v in board["value"]]
    board["_s"] = [order_key(v, second_higher) for v in board[second]]
    board = board.sort_values(["scene", "rank", "_v", "_s", "submitted"], kind="stable").drop(columns=["_v", "_s"])
    board["position"] = board.groupby("scene").cumcount() + 1
    order = {s: i for i, s in enumerate(phase.scenes)}
    board = board.sort_values(["scene", "position"], key=lambda c: c.map(order) if c.name == "scene" else c)
    out["rows"] = [{k: _plain(r[k]) for k in BOARD_COLUMNS} for _, r in board.iterrows()]
    out["sentences"] = [_sentence(board, f.pairs, suite, scene) for suite, scene in f.sentences]
    out["test"] = f.test
    return out


def exact_mean(values: Any) -> float:
    """The mean of the finite ``values`` (NaN left out, as pandas' mean leaves it out), their sum
    taken exactly and rounded once (:func:`statistics.mean`): copies of one value average to that
    value, whatever their count (pandas' mean of 8 copies of 0.4725435807036217 is
    0.4725435807036216, numpy's of 3 is 0.47254358070362174); NaN without a value; an infinite
    value makes it infinite (or NaN), as a plain mean does."""
    kept = [float(v) for v in values if not math.isnan(float(v))]
    if not kept:
        return math.nan
    if not all(math.isfinite(v) for v in kept):
        return float(np.mean(kept))
    return float(statistics.mean(kept))


def order_key(value: Any, higher: bool) -> float:
    """A value as the order within a rank compares it (the smaller key first): rounded to
    :data:`ORDER_DIGITS` significant digits, negated where higher is better; a missing value last."""
    v = float(value) if value is not None else math.nan
    if math.isnan(v):
        return math.inf
    rounded = float(f"{v:.{ORDER_DIGITS}g}")  # an infinity stays one
    return -rounded if higher else rounded


def _sentence(board: pd.DataFrame, pairs: pd.DataFrame, suite: str, scene: str) -> str:
    """The sentence under a scene's table (:func:`lorisnb.tools.report.leaderboard.sentence`),
    worded from the board as ordered and shown (the team it names first is the table's first)."""
    rows = board[board["scene"] == scene].rename(columns={"team": "algorithm"}).reset_index(drop=True)
    if {"suite", "scene"} <= set(pairs.columns):
        pairs = pairs[(pairs["suite"] == suite) & (pairs["scene"] == scene)]
    return sentence(rows, pairs)


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
