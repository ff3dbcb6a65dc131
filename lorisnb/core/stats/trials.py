"""Repeated trials: several result files of one algorithm on one sequence.

A trial number is read from a file's path relative to the results folder: a token such as
``cafe_trial3.txt``, ``cafe-trial-3.txt``, ``trial3/cafe.txt``, ``run_2/cafe.txt``, ``run-2/`` or
rpg_trajectory_evaluation's ``stamped_traj_estimate3.txt``; or by a user's regular expression whose
first group (or group named ``trial``) is the number. A path without a trial token is trial 0 (the
only trial). The token is removed from the path to tell which files belong together.
"""

from __future__ import annotations

import re
import unicodedata
from collections.abc import Iterable
from pathlib import PurePosixPath

from lorisnb.core.spec import validate
from lorisnb.errors import ValidationError

#: Trial tokens recognized by default, in a file name or as a folder of their own.
TRIAL_PATTERNS = (
    re.compile(r"(?:^|[_\-./])(?:trial|run)[_\-]?(?P<trial>\d+)(?=$|[_\-./])", re.IGNORECASE),
    re.compile(r"(?<=^stamped_traj_estimate)(?P<trial>\d+)(?=\.)"),
)


def compile_trials_by(regex: str | None) -> re.Pattern[str] | None:
    """A user's ``--trials-by`` expression, checked: it must compile and have a group. It is
    searched in one file or folder name at a time (the file's name first), so a ``/`` is refused."""
    if regex is None:
        return None
    if not isinstance(regex, str):
        raise ValidationError(f"trials_by={regex!r}: expected a regular expression (a string), e.g. 'run(\\d+)'")
    if "/" in regex:
        raise ValidationError(f"trials_by={regex}: it is searched in one file or folder name at a time, so '/' never "
                              "matches; expected an expression for the name that holds the trial, e.g. 'run_(\\d+)'")  # fmt: skip
    try:
        pat = re.compile(regex)
    except re.error as exc:
        raise ValidationError(f"trials_by={regex}: not a regular expression ({exc})") from None
    if pat.groups < 1:
        raise ValidationError(f"trials_by={regex}: expected a group around the trial number, e.g. 'run(\\d+)'")
    return pat


def split_trial(relpath: str, trials_by: str | re.Pattern[str] | None = None) -> tuple[str, int]:
    """(the path without its trial token, the trial number) of a result file's relative path
    (``/``-separated); trial 0 when the path names none."""
    pattern = compile_trials_by(trials_by) if isinstance(trials_by, str) else trials_by
    parts = list(PurePosixPath(relpath).parts)
    found: list[tuple[int, str]] = []  # (trial, the token) of each name that carries one
    for k in range(len(parts) - 1, -1, -1):  # the file name first, then its folders
        for pat in [pattern] if pattern is not None else TRIAL_PATTERNS:
            m = pat.search(parts[k])
            if m is None:
                continue
            number = m.group("trial") if "trial" in pat.groupindex else m.group(1)
            try:
                trial = int(number)
            except (TypeError, ValueError):
                raise ValidationError(f"trials_by: matched {m.group(0)!r} in {relpath}, not a whole number") from None
            found.append((trial, m.group(0).strip("_-./")))
            cut = re.sub(r"[_\-]+(?=\.|$)", "", parts[k][: m.start()] + parts[k][m.end() :]).strip("_-")
            if k == len(parts) - 1 and (not cut or cut.startswith(".")):
                cut = "estimate" + cut  # the whole name was the trial token
            rest = cut if k == len(parts) - 1 or cut not in (".", "") else ""
            parts = parts[:k] + ([rest] if rest else []) + parts[k + 1 :]
            break  # one token a name; a folder's and the file's own both say the trial (trial2/cafe_trial2.txt)
    if not found:
        return relpath, 0
    if len({t for t, _ in found}) > 1:
        said = " and ".join(f"{token!r} (trial {t})" for t, token in reversed(found))
        raise ValidationError(f"{relpath}: names two trials, {said}; name each file's trial once, or the same in its "
                              "folder and its file name")  # fmt: skip
    return "/".join(parts), found[0][0]


def names_a_trial(relpath: str, trials_by: str | re.Pattern[str] | None = None) -> bool:
    """Whether a result file's relative path carries a trial token (the user's or the defaults)."""
    pattern = compile_trials_by(trials_by) if isinstance(trials_by, str) else trials_by
    pats = [pattern] if pattern is not None else list(TRIAL_PATTERNS)
    return any(p.search(part) for part in PurePosixPath(relpath).parts for p in pats)


def check_trials_by(relpaths: list[str], trials_by: str | None) -> None:
    """A ``--trials-by`` expression that matches none of the files is an error (it was meant to
    number them)."""
    if trials_by is None or not relpaths:
        return
    if not any(names_a_trial(p, trials_by) for p in relpaths):
        shown = ", ".join(relpaths[:3]) + (f" and {len(relpaths) - 3} more" if len(relpaths) > 3 else "")
        raise ValidationError(
            f"trials_by={trials_by}: matches none of the file or folder names of the {len(relpaths)} result file "
            f"path(s) ({shown}); expected an expression that finds the trial number in one of them, e.g. 'run(\\d+)'"
        )


def check_duplicates(keys: list[tuple[str, tuple, tuple[int, ...]]]) -> None:
    """Several files for one sequence and trial are an error, never averaged: ``keys`` holds, per
    evaluated file, (its path, its labels (suite, algorithm, scene, trial), its sequence numbers).
    The message names the files and suggests ``--trials-by``."""
    seen: dict[tuple, tuple[int, str]] = {}
    for k, (path, label, seqs) in enumerate(keys):
        for s in dict.fromkeys(seqs):
            j, other = seen.setdefault((*label, s), (k, path))
            if j == k:
                continue
            suite, algorithm, scene, trial = label
            held = (
                f"{algorithm}{f' ({suite})' if suite else ''} {scene}-{s}{f' trial {trial}' if trial else ''}".strip()
            )
            if PurePosixPath(other) == PurePosixPath(path):
                raise ValidationError(f"{path} is given twice (it holds {held}); give each file or folder once")
            first, second = told_apart(str(other), str(path))
            # the default tokens that read this number (a --trials-by's are not known here: None then)
            tokens = [t[0] if t is not None and t[1] == trial else None for t in map(_token, (str(other), str(path)))]
            if trial or None not in tokens:  # both carry a trial token, of one number (trial1/ and trial01/)
                a, b = tokens
                spelled = f" ({a} and {b} are one number)" if a is not None and b is not None and a != b else ""
                raise ValidationError(
                    f"{first} and {second} both hold {held}: both name trial {trial}{spelled}; renumber one of them "
                    "so that each trial has its own number, or evaluate them separately"
                )
            if tokens != [None, None]:  # x.txt and x_trial0.txt
                unnamed, named = (first, second) if tokens[0] is None else (second, first)
                raise ValidationError(
                    f"{first} and {second} both hold {held}: {unnamed} names no trial, which is read as trial 0, and "
                    f"{named} names trial 0; number the trials from 1 (cafe_trial1.txt, run_2/, ...), or evaluate "
                    "them separately"
                )
            above = [_token(str(x)) for x in (other, path)]  # trial tokens in the folders given (trial1/ as input)
            if None not in above and above[0] != above[1]:
                raise ValidationError(
                    f"{first} and {second} both hold {held}: their trial numbers ({above[0][0]}, {above[1][0]}) are "  # type: ignore[index]
                    "in the names of the folders given, which are read from the folders below them only; give the "
                    "folder that holds the trial folders instead, so that their names number the "
                    "trials, or evaluate them separately"
                )
            raise ValidationError(
                f"{first} and {second} both hold {held}, with no trial number to tell them apart; name the trials "
                "(cafe_trial1.txt, run_2/, ...) or give --trials-by REGEX (trials_by= in Python) whose group is "
                "the trial number, or evaluate them separately"
            )


def _token(relpath: str) -> tuple[str, int] | None:
    """The default trial token in a path as written and its number (``trial01``: 1, ``run_2``: 2),
    the file's name first; None if it holds none."""
    for part in reversed(PurePosixPath(relpath).parts):
        for pat in TRIAL_PATTERNS:
            m = pat.search(part)
            if m is not None:
                return m.group(0).lstrip("_-./"), int(m.group("trial"))
    return None


def told_apart(a: str, b: str) -> tuple[str, str]:
    """Two names shown side by side, as they are; where they differ only by their Unicode spelling
    (one NFC, the other NFD: ``algé`` typed and ``algé`` from a Mac's folder, the same in
    :func:`~lorisnb.core.spec.validate.label`, and printed alike), the part that differs escaped as
    Python writes it (``alg\\xe9`` and ``alge\\u0301``) and the spellings named, so that the
    message shows two names, not one twice."""
    if a == b or validate.label(a) != validate.label(b):
        return a, b
    i = 0
    while i < min(len(a), len(b)) and a[i] == b[i]:
        i += 1
    while i > 0 and any(i < len(s) and unicodedata.combining(s[i]) for s in (a, b)):  # from the letter marked
        i -= 1
    j = 0
    while j < min(len(a), len(b)) - i and a[-1 - j] == b[-1 - j]:
        j += 1
    while j > 0 and any(unicodedata.combining(s[len(s) - j]) for s in (a, b)):  # a mark kept with its letter
        j -= 1

    def shown(s: str) -> str:
        form = next((f for f in ("NFC", "NFD") if unicodedata.is_normalized(f, s[i : len(s) - j])), "mixed")
        return f"{s[:i]}{ascii(s[i : len(s) - j])[1:-1]}{s[len(s) - j :]} ({form})"

    return shown(a), shown(b)


def trial_folders(relpaths: Iterable[str], trials_by: str | re.Pattern[str] | None = None) -> list[str]:
    """Notes naming the folders whose names hold a trial token beside other text (``slam_run1/``,
    ``slam_run2/``) and so were read as trials of one name (``slam``): the convention that makes
    ``orbslam2_run1/`` a trial also merges two systems' outputs kept as ``slam_run1/`` (one) and
    ``slam_run2/`` (another) into one algorithm's trials, silently. A folder that is the token alone
    (``run_2/``, ``trial3/``) says what it is and is not named. One note per merged name, with how to
    number the trials otherwise."""
    pattern = compile_trials_by(trials_by) if isinstance(trials_by, str) else trials_by
    merged: dict[str, dict[str, int]] = {}
    for rel in dict.fromkeys(str(p) for p in relpaths):
        parts = list(PurePosixPath(rel).parts)
        if len(parts) < 2:
            continue
        base, trial = split_trial(rel, pattern)
        kept = base.split("/")
        if len(kept) != len(parts):  # a folder that was the token alone (run_2/): dropped, says what it is
            continue
        for k, part in enumerate(parts[:-1]):  # the folders; the one whose token was read
            if kept[k] != part:
                merged.setdefault("/".join(kept[: k + 1]), {})[part] = trial
                break
    notes = []
    for name, folders in merged.items():
        shown = ", ".join(f"{f}/" for f in sorted(folders, key=lambda f: folders[f]))
        numbers = ", ".join(str(t) for t in sorted(folders.values()))
        notes.append(f"the folder(s) {shown} were read as trial(s) {numbers} of one name, {name} (a trial token, run "
                     "or trial and a number, in their names): if they hold different systems' outputs, rename them "
                     "(slam_a/, slam_b/), or give --trials-by REGEX (trials_by= in Python) for the token that numbers "
                     "the trials")  # fmt: skip
    return notes
