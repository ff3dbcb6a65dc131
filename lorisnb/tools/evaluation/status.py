"""What an evaluation did not score, and the exit status every command returns from it:

* 0: every input was read and matched the ground truth;
* 1: an input failed (it could not be read or evaluated, or a trial folder held no result file),
  matched no ground-truth stamp at all, or a declared session had no estimate; each still appears (in the table, scored as the paper
  scores it, or among the failures) with a one-line reason;
* 2: a usage error (a bad option, a bad output, a manifest or ground truth that cannot be read).

A file skipped because the data holds no ground truth for its scene is reported; it does not
count when the scene is OpenLORIS' office (:data:`NOT_PUBLIC`: its ground truth was never
published, there is nothing it could have matched), and counts as not scored (1) for any other
scene: a data root missing ``gt_cafe_1.txt`` (a partial copy, a renamed file) left every cafe file
out of the tables with exit status 0. A run that evaluated nothing at all (an empty folder, every
file skipped) is 1.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from lorisnb.tools.evaluation.result import Evaluation, Failure

#: Exit statuses of the ``lorisnb`` commands.
OK, UNSCORED, USAGE = 0, 1, 2

#: OpenLORIS scenes whose ground truth is not public: their files are skipped without counting
#: (kind ``not-public``; another scene's missing ground truth is kind ``no-groundtruth``).
NOT_PUBLIC = ("office",)


def unscored(ev: Evaluation) -> list[Failure]:
    """Inputs that were read but not scored: inputs none of whose poses matched the ground truth
    in time (kind ``no-match``, with the reason the evaluation gave), estimates of a pair holding
    no pose at all (kind ``no-pose``: an empty or comments-only file; an OpenLORIS file whose
    ``seq:`` blocks hold no pose declares failed runs, as the official data's ``*-failed.txt``
    do, and is scored) and, for manifests, declared sessions without an estimate (kind
    ``missing-estimate``: rows with 0 poses, :mod:`lorisnb.core.lifelong.missing`) or sessions with poses
    none of which matched (kind ``no-match``, as a pair's file), and files skipped for want of
    their scene's ground truth where the scene is not one of :data:`NOT_PUBLIC` (kind
    ``no-groundtruth``; they stay in ``ev.skipped`` too). Failures are in ``ev.failures``."""
    from lorisnb.tools.evaluation.result import Failure

    out = []
    if not ev.errors and not ev.failures:  # nothing at all: an empty folder, or every file skipped
        where = ev.root if ev.root is not None else Path(".")
        why = "every input was skipped" if ev.skipped else "no input file was found"
        out.append(Failure(where, f"nothing was evaluated: {why}", "nothing"))
    for f in ev.errors:
        absent = [e.seq for e in f.sequences if e.poses == 0] if ev.kind == "manifest" else []
        if absent:
            out.append(Failure(f.path, f"{f.path}: no estimate for session(s) {absent}", "missing-estimate"))
        unmatched = [e.seq for e in f.sequences if e.poses and not e.matched] if ev.kind == "manifest" else []
        if unmatched and len(unmatched) < len(f.sequences):  # a session is an input of its own, as a pair's file:
            out.append(Failure(f.path, f"{f.path}: session(s) {unmatched} matched no ground-truth stamp in time",
                               "no-match"))  # fmt: skip
            continue  # (every session unmatched: said below, with the evaluation's reason)
        if any(e.matched for e in f.sequences):
            continue
        if not any(e.poses for e in f.sequences):
            if ev.kind == "pair" and not f.frame:  # an empty estimate (a crashed run, comments only): scored as
                # missing, and said; an OpenLORIS file (its frame: header) given as a pair: as below
                out.append(Failure(f.path, f"{f.path}: holds no pose (scored as a missing output)", "no-pose"))
            continue  # an OpenLORIS file of seq: blocks without poses declares failed runs (the official data's
            # *-failed.txt): scored as the paper scores them; a manifest's missing sessions are said above
        why = next((w for w in f.warnings if "no estimate stamp" in w or "no pose" in w), "")
        reason = why.split(". ")[0] if why else f"{f.algorithm} {f.file}: no pose matched the ground truth in time"
        out.append(Failure(f.path, reason.splitlines()[0], "no-match"))  # one line; the warning has the rest
    for s in ev.skipped:  # no ground truth in the data: only a scene never published is expected
        if s.kind != "not-public":
            out.append(
                Failure(s.path, f"{s.path}: skipped, {s.error.splitlines()[0].split('. ')[0]}", "no-groundtruth")
            )
    return out


def skipped_only(ev: Evaluation, said: list[Failure] | None = None) -> list[Failure]:
    """The skipped inputs that are not also among the not scored (``said``, default
    :func:`unscored`): a public scene's ground truth missing from the data root is both, and each
    input is said and counted once."""
    paths = {str(f.path) for f in (unscored(ev) if said is None else said)}
    return [f for f in ev.skipped if str(f.path) not in paths]


def exit_status(ev: Evaluation) -> int:
    """0 if every input was read and matched the ground truth, else 1 (see the module docstring)."""
    return UNSCORED if ev.failures or unscored(ev) else OK
