"""``lorisnb history DIR...``: scene values of many runs over time (nightly report runs, or
per-sequence CSV/Parquet tables), where a value first changed, and which runs cannot be compared
with the run before them.

Runs are ordered by ``created`` of their run.json; runs without one (bare tables) by the file's
modification time, and the table says which (``created_from``). Two runs are **not comparable**
when their specs differ (:func:`lorisnb.tools.decisions.runs.spec_differences`), when lorisnb's
version differs, or when the checksums of their ground-truth files differ (run.json's ``inputs``);
each break is named. Each run is compared with its **baseline**, the last earlier run it is
comparable with (not only the run just before it: a run with other thresholds in between hides
nothing), by the one decision rule of ``lorisnb diff`` (:mod:`lorisnb.core.stats.regression`): a
value **changed** when that rule calls it a regression or an improvement, or a sequence or trial of
its scene was lost; a value absent in a run and in its baseline is no change. The newest run also
fails for a sequence any earlier run of its series had and it lacks (:func:`lost_since`). Scene
values count missing sequences as failed runs
(:mod:`lorisnb.core.lifelong.coverage`).
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable, Mapping, Sequence
from datetime import date, datetime, time
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pandas as pd

from lorisnb.core.lifelong.coverage import complete, expected_from
from lorisnb.core.stats.inference import WEIGHTS, scene_means
from lorisnb.core.stats.regression import BAD, Tolerance, parse_tolerances
from lorisnb.errors import LorisError, ValidationError
from lorisnb.tools.decisions.diff import Diff, diff_tables, keyed
from lorisnb.tools.decisions.escape import clean
from lorisnb.tools.decisions.runs import Run, held_results, load_run, spec_differences

COLUMNS = ["run", "path", "created", "created_from", "lorisnb_version", "label", "comparable", "not_comparable",
           "baseline", "suite", "algorithm", "scene", "metric", "value", "status", "change", "changed",
           "first_change"]  # fmt: skip


def natural(name: str) -> tuple:
    """A name's sort key with its numbers compared as numbers: ``night-9`` before ``night-10`` (as
    text, ``night-10`` sorts first), ``2026-02-01`` before ``2026-02-02`` as before."""
    return tuple((0, int(x), "") if x.isdigit() else (1, 0, x) for x in re.split(r"(\d+)", name) if x)


def load_runs(paths: Iterable[str | os.PathLike[str]], passed: list[str] | None = None) -> list[Run]:
    """The runs, oldest first (see the module docstring); runs of the same time by their paths,
    numbers as numbers (:func:`natural`), as a folder's runs are ordered: ``night-9.csv`` before
    ``night-10.csv`` however they are given (sorted as text, or in the order given, a shell's
    ``night-*.csv`` made ``night-9`` the newest run, the one the exit status judges).

    A path that cannot be read as a run (:func:`read_runs`) is an error, unless ``passed`` is given:
    then one that is no run at all (a table without per-sequence rows, such as ``history --csv``'s
    own output left in the folder, or a file of another kind), or a damaged run older than the
    newest run read, is passed over, said in ``passed``; a damaged run that would be the newest (the
    night the exit status judges) is still the error. ``history nightly/*`` exited 2 for a damaged
    older night, hiding the newest night's regression, and for its own ``--csv`` kept in the folder."""
    runs, unread = read_runs(paths)
    if unread and passed is None:
        raise unread[0].error
    ordered = load_runs_sorted(runs) if runs else []
    newest = _order_key(ordered[-1]) if ordered else None
    results = [u for u in unread if u.results]
    if results:  # tonight's results, given as a folder: never passed over (history judged the night before it)
        raise results[0].error
    damaged = [u for u in unread if not u.foreign]
    later = [u for u in damaged if newest is None or u.when is None or (False, u.when, natural(str(u.path))) > newest]
    if later or (unread and not ordered):
        raise max(later or damaged or unread, key=lambda u: (u.when is None, u.when or 0, natural(str(u.path)))).error
    newer = [u for u in unread if u.foreign and newest is not None and u.when is not None
             and (False, u.when, natural(str(u.path))) > newest and _may_be_a_night(u.path)]  # fmt: skip
    if newer:  # the newest path given is no run: its night cannot be judged, and the night before it is not it
        u = newer[-1]
        raise ValidationError(f"{u.path}: {u.foreign}; it is newer than the newest run read ({ordered[-1].path}), so it "
                              "may be the night to judge in a form history does not read: nothing judged. Give "
                              "history the runs (report run folders, per-sequence tables of lorisnb evaluate --csv), "
                              "the newest last made")  # fmt: skip
    if passed is not None:  # else nothing is unread (raised above)
        for u in unread:
            what = (
                "no run (not a per-sequence table or a report run)"
                if u.foreign
                else "a damaged run older than the newest"
            )
            passed.append(f"{u.path} passed over, {what}: {u.why}; {ordered[-1].path} is judged as the newest run")
    return ordered


class Unread(NamedTuple):
    """A path :func:`read_runs` could not read as a run: the error, its message, when the path was
    made (run.json's ``created`` where it holds one, else the modification time; None where the path
    does not exist) and, where it is **foreign**, no run at all rather than a damaged one, why
    (:func:`foreign`; None for a damaged run)."""

    path: Path
    why: str
    error: LorisError
    when: datetime | None
    foreign: str | None
    #: what it holds that lorisnb evaluates, where it is a result folder or file
    #: (:func:`~lorisnb.tools.decisions.runs.held_results`): refused, never passed over
    results: str | None = None


def read_runs(paths: Iterable[str | os.PathLike[str]]) -> tuple[list[Run], list[Unread]]:
    """Each path read as a run (:func:`lorisnb.tools.decisions.runs.load_run`), in the order given,
    and those that could not be (:class:`Unread`): the one reading of ``history``'s runs and of the
    folder ``diff`` / ``report --baseline last-comparable`` choose a baseline from."""
    runs, unread = [], []
    for p in map(Path, paths):
        try:
            runs.append(load_run(p))
        except LorisError as exc:
            why = foreign(p)
            held = held_results(p) if why == NOT_A_RUN else None
            unread.append(Unread(p, str(exc), exc, _made(p), why, held))
    return runs, unread


#: Why a path that is neither a report run nor a table is no run (:func:`foreign`).
NOT_A_RUN = "not a report run and not a CSV/Parquet table"


def _may_be_a_night(path: Path) -> bool:
    """Whether a path that is no run (:func:`foreign`) may be a night kept in a form ``history`` does
    not read, so that, newer than every run read, it is not passed over: a folder, or a table
    without per-sequence rows; not ``history``'s own outputs (its ``--csv`` table, its ``--out``
    folder of figures), which a second ``history`` the same night finds newer than the night, nor a
    file of another kind (a verdict's JSON, Markdown or XML kept beside the runs)."""
    from lorisnb.tools.decisions.runs import csv_records

    if path.is_dir():
        names = [f.name for f in path.iterdir()]
        return not (names and all(re.fullmatch(r"history_\w+\.(png|svg)", n) for n in names))
    if path.suffix.lower() == ".csv":
        try:
            header = next((r for _, r in csv_records(path)), [])
        except (LorisError, OSError):
            return True
        return not set(COLUMNS) <= set(header)
    return path.suffix.lower() == ".parquet"


def foreign(path: Path) -> str | None:
    """Why ``path`` is no run at all (None where it may be one, damaged or not): neither a report run
    nor a table (:func:`~lorisnb.tools.decisions.runs.is_table`), or a table without the columns of
    per-sequence rows (``algorithm``, ``scene``, ``seq``: ``history --csv``'s own table, a scene or
    pairs table). An empty table (no header: a failed ``--csv``, a shell redirect) may be a run, damaged."""
    from lorisnb.tools.decisions.runs import csv_records, holds_run_json, is_table

    if not path.exists() or holds_run_json(path):  # a report run, damaged or not
        return None
    if not is_table(path):
        return NOT_A_RUN
    try:
        if path.is_file() and path.suffix.lower() == ".csv":
            header = next((r for _, r in csv_records(path)), [])
        elif path.is_file():
            import pyarrow.parquet as pq

            header = list(pq.read_schema(path).names)
        else:
            return None
    except (LorisError, ImportError, OSError, ValueError):
        return None
    if not [
        c for c in header if str(c).strip()
    ]:  # empty (a failed --csv, a redirect): a damaged run, not another table
        return None
    lacks = [c for c in ("algorithm", "scene", "seq") if c not in header]
    return f"a table without per-sequence rows (no column {', '.join(lacks)})" if lacks else None


def _made(path: Path) -> datetime | None:
    """When a path that could not be read as a run was made, as :func:`load_run` would order it."""
    from lorisnb.tools.decisions.runs import created_of, holds_run_json, modified
    from lorisnb.tools.report.provenance import RUN_JSON, read_run_json

    if not path.exists():
        return None
    if holds_run_json(path):
        try:
            created = created_of(read_run_json(path), path / RUN_JSON)
        except LorisError:
            created = None
        return created or modified(path / RUN_JSON)
    return modified(path)


def _order_key(r: Run) -> tuple:
    """A run's place, oldest first: its time, then its path, numbers as numbers."""
    return (r.created is None, r.created or 0, natural(str(r.path)))


def load_runs_sorted(runs: list[Run]) -> list[Run]:
    """Runs already read (:func:`load_runs`), oldest first, those of one time by path, numbers as numbers."""
    if len({r.path.resolve() for r in runs}) < len(runs):
        raise ValidationError("history: a run is given twice; give each run once")
    out = sorted(runs, key=_order_key)
    for before, run in zip(out, out[1:], strict=False):  # the newest run baseline and exit status hang on the order
        if run.created is not None and run.created == before.created:
            run.notes.append(f"{run.path} has the same time as {before.path} ({run.created.isoformat()}, "
                             f"{run.created_from}): ordered after it by name, numbers as numbers; a copy or a "
                             "download resets files' modification times, a report run's run.json keeps when it was "
                             "made")  # fmt: skip
    return out


#: A date in a part of a run's name (``2026-01-05.csv``, ``nightly-2026-01-05``, ``2026-02-01/sequences.csv``,
#: ``20260105.csv``, ``2026-01-05T03:00``): ISO 8601, year first, in its extended form (with its time, if
#: any) or its basic one (8 digits that form a date, with a time ``T0300`` if any). Day-first or
#: month-first forms (``05-01-2026``) are ambiguous, and left out.
_NAME_DATES = (
    re.compile(r"(?<!\d)(\d{4})-(\d{2})-(\d{2})(?:[T_ ](\d{2})[:-]?(\d{2})(?:[:-]?(\d{2}))?)?(?!\d)"),
    re.compile(r"(?<!\d)(\d{4})(\d{2})(\d{2})(?:[T_](\d{2})(\d{2})(\d{2})?)?(?!\d)"),
)


#: A date named in a run's path (:func:`name_dates`): the day, and the time of day where one is named.
NameDate = tuple[date, time | None]


def _part_dates(part: str) -> list[NameDate]:
    out = []
    for form in _NAME_DATES:
        for m in form.finditer(part):
            y, mo, d, hh, mm, ss = m.groups()
            if not 1900 <= int(y) <= 2199:
                continue
            try:
                day = date(int(y), int(mo), int(d))
            except ValueError:  # 8 digits that form no date: an id, not a date
                continue
            try:
                at = None if hh is None else time(int(hh), int(mm), int(ss or 0))
            except ValueError:
                at = None  # no time of day: the date alone
            out.append((day, at))
    return out


def name_dates(runs: Sequence[Run]) -> list[NameDate | None]:
    """The date in each run's name: every part of its path below the folder all the runs share
    (``2026-02-01`` of ``nightly/2026-02-01/sequences.csv``), ISO 8601 (:data:`_NAME_DATES`); None
    where the name holds none, or two different days (ambiguous). A time of day is kept where
    exactly one is named."""
    if not runs:
        return []
    resolved = [r.path.resolve() for r in runs]
    common = Path(os.path.commonpath([str(p.parent) for p in resolved]))
    out: list[NameDate | None] = []
    for p in resolved:
        found = [d for part in p.relative_to(common).parts for d in _part_dates(part)]
        days = {d for d, _ in found}
        times = {t for _, t in found if t is not None}
        out.append((days.pop(), times.pop() if len(times) == 1 else None) if len(days) == 1 else None)
    return out


def _later(a: NameDate, b: NameDate) -> bool:
    """Whether the name date ``a`` is later than ``b``: by the day, and by the time where both name one."""
    if a[0] != b[0] or a[1] is None or b[1] is None:
        return a[0] > b[0]
    return a[1] > b[1]


def _shown(d: NameDate) -> str:
    return d[0].isoformat() + (f"T{d[1].isoformat()}" if d[1] is not None else "")


def date_order_warnings(runs: Sequence[Run], taken: Run | None = None, role: str = "the newest run") -> list[str]:
    """Where runs ordered by their files' modification time (as :func:`load_runs` orders them,
    whatever order they are given in) are named with dates in another order (:func:`name_dates`:
    any part of the path below the runs' common folder, ISO 8601 extended or basic): one line naming
    the first such pair, how many there are, and the run taken as ``role`` (``taken``: the newest
    run). A copy or a download resets modification times, so the newest run, the baseline ``diff
    --baseline last-comparable`` chooses, and the exit status, may not be the ones the names say.
    Runs whose run.json records when they were made are ordered by that, and not checked."""
    ordered = sorted(runs, key=_order_key)
    labels = dict(zip(map(id, ordered), run_labels(ordered), strict=True))
    dated = [(r, d) for r, d in zip(ordered, name_dates(ordered), strict=True)
             if d is not None and r.created_from.startswith("modification time")]  # fmt: skip
    wrong = [(a, b) for a, b in zip(dated, dated[1:], strict=False) if _later(a[1], b[1])]
    if not wrong:
        return []
    (ra, da), (rb, db) = wrong[0]
    more = f" ({len(wrong)} such pair(s))" if len(wrong) > 1 else ""
    chosen = taken if taken is not None else ordered[-1]
    name = labels.get(id(chosen), chosen.name)
    return [f"runs ordered by modification time contradict the dates in their names: {labels[id(ra)]} (named "
            f"{_shown(da)}) is ordered before {labels[id(rb)]} (named {_shown(db)}){more}, so {name} is taken as "
            f"{role}; a copy or a download resets modification times: set them (touch -d) or keep report runs, "
            "whose run.json records when each was made"]  # fmt: skip


def run_labels(runs: Sequence[Run]) -> list[str]:
    """A name per run, unique: its file or folder name, or, where two runs share it (nightly
    ``2026-02-01/sequences.csv`` and ``2026-02-02/sequences.csv``), as many of the last parts of
    their paths as tell them apart (the whole path if nothing shorter does)."""
    parts = [r.path.resolve().parts for r in runs]
    labels = [r.name for r in runs]
    for depth in range(2, max((len(p) for p in parts), default=0) + 1):
        clash = {x for x in labels if labels.count(x) > 1}
        if not clash:
            break
        labels = ["/".join(p[-depth:]) if lab in clash else lab for p, lab in zip(parts, labels, strict=True)]
    return [lab if labels.count(lab) == 1 else str(r.path.resolve()) for r, lab in zip(runs, labels, strict=True)]


def comparability(prev: Run, run: Run) -> list[str]:
    """Why ``run`` cannot be compared with ``prev`` (empty: it can): the one rule of ``diff``,
    ``history``, ``diff --baseline last-comparable`` and ``report --baseline``. Their specs or
    thresholds differ (:func:`~lorisnb.tools.decisions.runs.spec_differences`), lorisnb's version
    differs, or a ground-truth file both record has another checksum; what a run does not record (a
    table holds no version and no checksum) is no difference (:func:`checked` names it). A result
    folder ``diff`` scores records the running lorisnb's version and the checksums of the ground
    truth it was scored against. ``diff`` of two runs of different versions noted the change and
    judged (exit 0) where ``history`` of the same two runs exited 2."""
    reasons = spec_differences(prev, run)
    if prev.version and run.version and prev.version != run.version:
        reasons.append(f"lorisnb_version {prev.version} -> {run.version}")
    ga, gb = prev.groundtruth_sums(), run.groundtruth_sums()
    changed = sorted(k for k in set(ga) & set(gb) if ga[k] != gb[k])
    if changed:
        reasons.append(f"ground truth changed: {', '.join(changed)}")
    return reasons


def earlier_runs(folder: str | os.PathLike[str], unread: list[tuple[str, str]] | None = None) -> list[Run]:
    """The runs kept in ``folder`` (report run folders and per-sequence tables directly in it),
    oldest first; an error naming the folder when it holds none. A file or folder there that cannot
    be read as a run (another table, say ``history --csv nightly/h.csv``, or a damaged one) is passed
    over, its name and why added to ``unread``: it made every later night's baseline refuse the folder."""
    from lorisnb.tools.decisions.runs import is_report_run, is_table

    f = Path(folder)
    if not f.is_dir():
        raise ValidationError(f"{f}: not a folder of earlier runs (report run folders or per-sequence tables)")

    # hidden names are left out: a report's unfinished run folder (.NAME.partial-*) is not an earlier run;
    # runs of one time (a folder copied or downloaded) are ordered by name, numbers as numbers
    def listed(p: Path) -> bool:  # a run, or a damaged one (run.json a FIFO): read_runs passes it over, saying why
        try:
            return is_report_run(p) or is_table(p)
        except ValidationError:
            return True

    found = sorted((p for p in f.iterdir() if not p.name.startswith(".") and listed(p)), key=lambda p: natural(p.name))
    runs, missed = read_runs(found)  # as history reads its runs
    passed = [(u.path.name, u.why) for u in missed]
    if unread is not None:
        unread.extend(passed)
    if not runs:
        shown = "; ".join(w for _, w in passed[:3])
        why = f"; of its {len(passed)} file(s) none can be read as a run: {shown}" if passed else ""
        raise ValidationError(f"{f} holds no run folder (run.json) and no per-sequence table (.csv, .parquet){why}; "
                              "give the folder the nightly runs are kept in")  # fmt: skip
    return load_runs_sorted(runs)


def checked(a: Run, b: Run) -> str:
    """What :func:`comparability` could check of two runs, in words: the spec (a report run's
    run.json, else the settings its table records), lorisnb's version and the ground truth's
    checksums where both runs record them, and what was not checked, with which run lacks it and
    why (:func:`unrecorded`): "same spec, lorisnb version and ground truth" claimed what was never
    checked, and a result folder scored now was said to be a table."""
    done = ["spec" if a.spec is not None and b.spec is not None else "the spec and thresholds their tables record"]
    unchecked: list[str] = []
    lacking: dict[str, list[str]] = {}  # run -> why it records what was not checked
    for what, has in (("lorisnb version", lambda r: bool(r.version)),
                      ("ground-truth checksums", lambda r: bool(r.groundtruth_sums()))):  # fmt: skip
        if has(a) and has(b):
            done.append(what)
            continue
        unchecked.append(what)
        for r in (a, b):
            if not has(r):
                lacking.setdefault(clean(r.name), []).append(unrecorded(r, what))
    text = "checked: " + ", ".join(done)
    if unchecked:
        why = "; ".join(f"{name}: {', '.join(dict.fromkeys(w))}" for name, w in lacking.items())
        text += f"; not checked: {' and '.join(unchecked)} (not recorded by {why})"
    return text


def unrecorded(run: Run, what: str) -> str:
    """Why ``run`` records no ``what`` (``lorisnb version`` or ``ground-truth checksums``), by its kind."""
    if run.kind == "table":
        return "a table records no lorisnb version and no ground-truth checksum"
    if run.kind == "results":  # scored now: the version is the running lorisnb's, the ground truth's read where known
        return (
            "a result folder scored by a manifest, whose sessions name their own ground-truth files"
            if (what != "lorisnb version")
            else "a result folder scored now"
        )
    return "its run.json records none"


def last_comparable(folder: str | os.PathLike[str], cand: Run) -> tuple[Run, list[Run]]:
    """The newest run in ``folder`` made before ``cand`` and comparable with it (:func:`comparability`:
    same spec, lorisnb version and ground truth), and every such run there, oldest first; an error
    naming the nearest runs and why when none is. Runs made at ``cand``'s time or after it
    (:func:`not_before`) are passed over with a note in ``cand.notes``: a copy of tonight's run
    kept with the earlier ones was its own baseline, "ok" whatever it held. Where the runs' names
    hold dates in another order than their modification times, ``cand.warnings`` says so
    (:func:`date_order_warnings`, as ``history`` warns): the baseline was chosen by time."""
    unread: list[tuple[str, str]] = []
    runs = [r for r in earlier_runs(folder, unread) if r.path.resolve() != Path(cand.path).resolve()]
    cand.notes.extend(f"{folder}: {name} passed over, not read as an earlier run ({why})" for name, why in unread)
    later = [r for r in runs if not_before(r, cand)]
    runs = [r for r in runs if r not in later]
    fits = [r for r in runs if not comparability(r, cand)]
    if fits:  # the baseline is chosen by time, as history orders its runs: a contradiction of the names said
        cand.warnings.extend(date_order_warnings([*runs, *later, cand], fits[-1], "the baseline"))
    if later:  # a copy of CAND kept with the earlier runs (its twin: "ok"), or a run made after it
        cand.notes.append(f"{len(later)} run(s) in {folder} made at or after {cand.name} ({cand.created_from} "
                          f"{cand.created.isoformat() if cand.created else '?'}) passed over: "
                          + ", ".join(r.name for r in later[:5]) + (" ..." if len(later) > 5 else "")
                          + "; a baseline is a run made before CAND (a copy of CAND kept there would pass it)")  # fmt: skip
    if not fits:
        why = "; ".join(f"{r.name}: {', '.join(comparability(r, cand))}" for r in runs[-3:])
        if not runs and later:  # every run passed over by CAND's time: say the time and where it came from
            when = cand.created.isoformat() if cand.created else "?"
            raise ValidationError(f"every run in {folder} ({len(later)}) was made at or after {cand.name} ({cand.created_from} "
                                  f"{when}), so none is its baseline; if CAND's files kept older times (tar -x, cp -p, "
                                  "rsync -a), give them the time they were made (touch them) or give BASE itself")  # fmt: skip
        after = f"; {len(later)} made at or after it passed over" if later else ""
        raise ValidationError(f"none of the {len(runs)} run(s) in {folder} made before {cand.name} is comparable "
                              f"with it ({why or 'none left'}{after}); compare runs made with the same spec, lorisnb "
                              "version and ground truth, made before CAND")  # fmt: skip
    from lorisnb.tools.decisions.diff import same_values

    copies = []  # CAND's time unknown (its files' times in the future): a run holding every value of it is its copy
    while cand.created is None and len(fits) > 1 and same_values(fits[-1].table, cand.table):
        copies.append(fits.pop())
    if copies:
        cand.notes.append(f"{', '.join(r.name for r in copies)} in {folder} passed over: holds every value of "
                          f"{cand.name} to the last digit, and CAND's time is unknown, so it is taken as CAND's "
                          "copy; the newest earlier run that differs is the baseline")  # fmt: skip
    return fits[-1], fits


def not_before(run: Run, cand: Run) -> bool:
    """Whether ``run`` was made at the time of ``cand`` or after it (both times known): it is no
    baseline of ``cand`` (a copy of CAND, or a later night)."""
    return run.created is not None and cand.created is not None and run.created >= cand.created


def baselines(runs: Sequence[Run]) -> list[tuple[int | None, str]]:
    """For each run (oldest first), the index of its **baseline**, the last earlier run it can be
    compared with (None: none, a new series starts), and why it cannot be compared with the run
    just before it ("" when it can). A run with other thresholds between two comparable runs does
    not hide a change between them: the later one is compared with the earlier one."""
    out: list[tuple[int | None, str]] = []
    for k, run in enumerate(runs):
        before = "; ".join(comparability(runs[k - 1], run)) if k else ""
        base = next((j for j in range(k - 1, -1, -1) if not comparability(runs[j], run)), None)
        out.append((base, before))
    return out


def history_table(
    runs: Sequence[Run], metrics: Sequence[str] = tuple(WEIGHTS), tolerances: Mapping[str, Tolerance] | None = None,
    alpha: float = 0.05,
) -> tuple[pd.DataFrame, dict[int, Diff]]:  # fmt: skip
    """One row per run, suite, algorithm, scene and metric (see :data:`COLUMNS`), and each run's
    diff against its baseline (by the run's index). A value's ``status`` is the verdict of
    ``lorisnb diff`` of the run against its baseline (:func:`baselines`) for that scene value:
    ``regression``, ``improvement``, ``missing`` (a sequence or trial of the scene lost), ``ok``,
    ``unjudged``; empty where the run has no baseline. A scene value's status is also that of any of
    its sequences' values of the metric (a sequence that regressed in CR makes its scene's CR row a
    regression, though the scene's mean may hide it)."""
    tols = parse_tolerances() if tolerances is None else dict(tolerances)
    bad = [m for m in metrics if m not in WEIGHTS]
    if bad:
        raise ValidationError(f"history metric(s) {', '.join(bad)}: expected scene metrics {', '.join(WEIGHTS)}")
    tables = [keyed(r.table, str(r.path)) for r in runs]
    expected = expected_from(*tables, *(r.expected for r in runs if r.expected is not None))  # as the leaderboard
    rows = []
    names = run_labels(runs)  # the run column: one name per run, or two runs' rows would merge
    seen_series: dict[tuple, int] = {}  # (suite, algorithm, scene, metric) -> the first run that has it
    diffs: dict[int, Diff] = {}
    for k, ((base, before), run, table) in enumerate(zip(baselines(runs), runs, tables, strict=True)):
        status: dict[tuple, str] = {}
        if base is not None:
            diffs[k] = diff_tables(tables[base], table, tols, alpha, run.unscored, names=(names[base], names[k]),
                                   expected=expected)  # fmt: skip
            for r in diffs[k].scenes.itertuples():
                key = (r.suite, r.algorithm, r.scene, r.metric)
                status[key] = r.status if key not in status or r.status in BAD else status[key]
            for r in diffs[k].sequences.itertuples():  # a sequence's change of a metric is its scene's too
                key = (r.suite, r.algorithm, r.scene, r.metric)
                if r.status in (*BAD, "improvement") and status.get(key) not in BAD:
                    status[key] = r.status
            for r in diffs[k].scenes[diffs[k].scenes["metric"] == "coverage"].itertuples():
                for m in metrics:  # a lost sequence or trial fails every value of its scene
                    status[(r.suite, r.algorithm, r.scene, m)] = "missing"
        meta = dict(run=names[k], path=str(run.path), created=run.created.isoformat() if run.created else "",
                    created_from=run.created_from, lorisnb_version=run.version or "", label=run.label or "",
                    comparable=not before, not_comparable=before,
                    baseline="" if base is None else names[base])  # fmt: skip
        full, _ = complete(table, expected)
        here = set()
        for m in metrics:
            for r in scene_means(full, m).itertuples():
                key = (r.suite, r.algorithm, r.scene, m)
                here.add(key)
                seen_series.setdefault(key, k)
                rows.append(dict(meta, suite=r.suite, algorithm=r.algorithm, scene=r.scene, metric=m, value=r.value,
                                 status="" if base is None else status.get(key, "")))  # fmt: skip
        for key in (key for key in seen_series if key not in here):  # a scene the run lost: no value, a change
            rows.append(dict(meta, suite=key[0], algorithm=key[1], scene=key[2], metric=key[3], value=np.nan,
                             status="" if base is None else "missing"))  # fmt: skip
    out = pd.DataFrame(rows, columns=COLUMNS[:-3])
    out["change"], out["changed"], out["first_change"] = np.nan, False, False
    for _, g in out.groupby(["suite", "algorithm", "scene", "metric"], sort=False):
        by_run = dict(zip(g["run"], g["value"], strict=True))
        seen = False
        for i in g.index:
            base_value = by_run.get(out.at[i, "baseline"], np.nan)
            if np.isfinite(base_value) and np.isfinite(out.at[i, "value"]):
                out.at[i, "change"] = out.at[i, "value"] - base_value
            gone_both = (
                out.at[i, "status"] == "missing" and not np.isfinite(out.at[i, "value"]) and not np.isfinite(base_value)
            )  # absent in the run and in its baseline: still lost (the exit status says so), no change
            if out.at[i, "status"] in ("regression", "improvement", "missing") and not gone_both:
                out.at[i, "changed"] = True
                out.at[i, "first_change"] = not seen
                seen = True
            if not out.at[i, "baseline"]:
                seen = False  # a new series starts here
    return out, diffs


def drift(
    runs: Sequence[Run], tolerances: Mapping[str, Tolerance] | None = None, alpha: float = 0.05
) -> tuple[int, Diff] | None:
    """The newest run against the **first run of its series** (the oldest run given that is
    comparable with it), by ``diff``'s rule at ``alpha``: a slow drift, each night within rerun
    noise of the night before (never a change against its baseline), is a change against the
    series' start, and a sequence or trial lost and left lost is missing against it every night.
    Only the latter fails the night (:func:`drift_gates`); a drift of the values is named. None
    where that run is the newest run's baseline (nothing more to judge) or there is none."""
    k = len(runs) - 1
    if k < 1:
        return None
    first = next((j for j in range(k) if not comparability(runs[j], runs[k])), None)
    base = baselines(runs)[k][0]
    if first is None or first == base:
        return None
    tols = parse_tolerances() if tolerances is None else dict(tolerances)
    a, b = keyed(runs[first].table, str(runs[first].path)), keyed(runs[k].table, str(runs[k].path))
    expected = expected_from(a, b, *(r.expected for r in (runs[first], runs[k]) if r.expected is not None))
    names = run_labels(runs)
    d = diff_tables(a, b, tols, alpha, runs[k].unscored, names=(names[first], names[k]), expected=expected)
    return first, d


#: The statuses of a drift's regressions that fail the night (:func:`drift_gates`): coverage.
LOST = ("missing", "failed")


def drift_gates(d: Diff) -> list[dict]:
    """The regressions of a drift (:func:`drift`) that fail the night: a sequence or trial missing
    or failed since the series' start (coverage, no statistics: noise-only nights never lose one).
    A drift of the values is named, not gated: every night of a series is judged against the same
    first run, so one unusually good first night fails night after night; gating on it (at alpha /
    2) failed 6.8 % [3.5, 12.8] of noise-only nights with 3 trials against 3.4 % [1.3, 8.4] without
    (heavy model 10.2 % against 6.8 %; 59-night series, docs/guide/history.md), above the 5 % the
    gate is held to. ``lorisnb diff FIRST NEWEST`` gates on it where wanted."""
    return [r for r in d.verdict["regressions"] if r.get("status") in LOST]


def lost_since(runs: Sequence[Run], names: Sequence[str] | None = None,
               judged: Iterable[tuple] = ()) -> list[tuple[tuple, str, str]]:  # fmt: skip
    """The sequences an earlier run of the newest run's series had (any earlier run comparable with
    it, since the sequence first appeared) that the newest run lacks, each as ((suite, algorithm,
    scene, seq), what, the name of the last run that had it): ``missing`` (no row), or ``failed``
    (nothing matched in any trial, where that run matched at least
    :data:`~lorisnb.core.stats.tolerances.MIN_MATCHED` poses in a trial, as ``diff`` judges a
    failed sequence). Sequences in ``judged`` (already failed by the night's other diffs) are left
    out. Only the first run's sequences were gated (:func:`drift`): an algorithm added after the
    first night and lost later failed only the night it was lost, then passed night after night."""
    from lorisnb.core.stats.tolerances import MIN_MATCHED

    k = len(runs) - 1
    if k < 1:
        return []
    names = list(names) if names is not None else run_labels(runs)
    keys = ["suite", "algorithm", "scene", "seq"]

    def seen(run: Run) -> tuple[set[tuple], set[tuple], set[tuple]]:
        t = keyed(run.table, str(run.path))
        have = set(map(tuple, t[keys].itertuples(index=False)))
        if "matched" not in t.columns:
            return have, have, have
        m = pd.to_numeric(t["matched"], errors="coerce").fillna(0)
        out = set(map(tuple, t.loc[m > 0, keys].itertuples(index=False)))
        tracked = set(map(tuple, t.loc[m >= MIN_MATCHED, keys].itertuples(index=False)))
        return have, out, tracked

    have_k, out_k, _ = seen(runs[k])
    skip = set(judged)
    last: dict[tuple, tuple[str, str]] = {}
    for j in range(k):  # oldest first: the last run that had a sequence is the one kept
        if comparability(runs[j], runs[k]):
            continue
        have, _, tracked = seen(runs[j])
        for key in have - have_k:
            last[key] = ("missing", names[j])
        for key in (tracked & have_k) - out_k:
            last[key] = ("failed", names[j])
    return [(key, *last[key]) for key in sorted(last, key=lambda x: tuple(map(str, x))) if key not in skip]


def newest_verdict(runs: Sequence[Run], diffs: Mapping[int, Diff], names: Sequence[str] | None = None,
                   since_first: tuple[int, Diff] | None = None) -> tuple[int, list[str]]:  # fmt: skip
    """``history``'s exit status and what it says of the newest run: ``diff``'s exit status of the
    newest run against its baseline (:func:`lorisnb.tools.decisions.diff.exit_status`: 1 when it
    regressed, or when an input of either run was not scored, as ``findings/input_errors.csv``
    lists them), 0 only when it was judged, every input of both scored and nothing regressed; 2
    when the newest run has no baseline (no earlier run comparable with it: ``diff`` of runs that
    are not comparable exits 2), nothing judged. It exited 0 on both: a night whose spec or
    lorisnb version changed, or whose failed inputs its baseline had failed too, passed unjudged.
    A newest run holding every value of its baseline (or of its series' first run) is noted as
    ``diff`` notes it (:func:`~lorisnb.tools.decisions.diff.same_run_note`: a night that re-uploaded
    the previous night's table passed with no word); the exit status stays the comparison's."""
    from lorisnb.core.stats.regression import regressed_phrase
    from lorisnb.tools.decisions.diff import exit_status, same_run_note, verdict_phrase, with_unscored

    if not runs:
        return 2, ["no run given: nothing judged"]
    names = list(names) if names is not None else run_labels(runs)
    k = len(runs) - 1
    run = runs[k]
    if k not in diffs:
        base, before = baselines(runs)[k]
        why = f" ({before})" if before else ""
        what = f"no earlier run is comparable with it: not with {names[k - 1]}{why}" if k else "the only run given"
        return 2, [f"newest run {names[k]}: {what}; nothing judged (exit 2, as diff of runs that are not comparable). "
                   "Compare it with a run made with the same spec, lorisnb version and ground truth; a new series "
                   "starts here"]  # fmt: skip
    base = baselines(runs)[k][0]
    assert base is not None
    d = with_unscored(diffs[k], runs[base].unscored, run.unscored)
    what = verdict_phrase(d)
    lines = [f"newest run {names[k]} against {names[base]}: {d.verdict['verdict']}" + (f" ({what})" if what else "")]
    rc = exit_status(d, runs[base].unscored, run.unscored)
    same = same_run_note(runs[base].table, run.table, names[base], names[k])
    if same:  # "ok" against itself: said, as diff says it (exit status diff's: the comparison's own)
        lines.append(f"note: {same}")
    drift_line = None
    if since_first is not None:  # a drift: within noise night to night, a change since the series' start
        j, f = since_first
        gates = drift_gates(f)
        said = f" ({regressed_phrase(f.verdict)})" if f.regressed else ""
        lines.append(f"newest run {names[k]} against {names[j]}, the first run of its series: "
                     f"{'regression' if f.regressed else 'ok'}{said}")  # fmt: skip
        if f.regressed and not gates:  # its words once the night's exit status is known (below)
            drift_line = (len(lines) - 1, names[j])
        same = same_run_note(runs[j].table, run.table, names[j], names[k])
        if same:
            lines.append(f"note: {same}")
        rc = max(rc, 1 if gates else 0)
    judged = {(r["suite"], r["algorithm"], r["scene"], r["seq"]) for r in d.verdict["regressions"]
              if r.get("status") in LOST and r.get("seq") is not None}  # fmt: skip
    if since_first is not None:
        judged |= {(r["suite"], r["algorithm"], r["scene"], r["seq"]) for r in drift_gates(since_first[1])
                   if r.get("seq") is not None}  # fmt: skip
    gone = lost_since(runs, names, judged)
    if gone:
        shown = "; ".join(f"{alg}{f' ({suite})' if suite else ''} {scene}-{seq} {what} (last seen in {name})"
                          for (suite, alg, scene, seq), what, name in gone[:5])  # fmt: skip
        more = f"; {len(gone) - 5} more" if len(gone) > 5 else ""
        lines.append(f"newest run {names[k]}: {len(gone)} sequence(s) an earlier run of its series had are lost: "
                     f"{shown}{more}; a sequence lost and left lost fails every night until it is back")  # fmt: skip
        rc = max(rc, 1)
    if drift_line is not None:  # a drift of values is named, never gated: what fails the night is said as it is
        i, first = drift_line
        lines[i] += ("; a drift of values, which does not fail the night by itself" + (
            f" (the night exits {rc} for its other findings here)" if rc else " (the night passes: exit 0)")
            + f"; gate on it with lorisnb diff {first} {names[k]}")  # fmt: skip
    lines += [f"note: {x}" for x in renames_said(runs, diffs, names, since_first)]
    lost = [(names[base], runs[base].unscored), (names[k], run.unscored)]
    for name, files in lost:
        if files:
            lines.append(f"error: {len(files)} input(s) of {name} could not be evaluated or were not scored "
                         f"({', '.join(sorted(files)[:3])}{' ...' if len(files) > 3 else ''}): not every sequence "
                         "was compared")  # fmt: skip
    return rc, lines


def renames_said(runs: Sequence[Run], diffs: Mapping[int, Diff], names: Sequence[str] | None = None,
                 since_first: tuple[int, Diff] | None = None) -> list[str]:  # fmt: skip
    """The likely renames of an algorithm (:func:`lorisnb.tools.decisions.diff.renamed`) among the
    runs' diffs against their baselines and the newest run's against its series' first run, each
    said once, at the run that renamed it (:func:`~lorisnb.tools.decisions.diff.rename_notes`, with
    where a new series would start): every night after a rename fails on the lost name."""
    from lorisnb.tools.decisions.diff import rename_notes, renamed

    names = list(names) if names is not None else run_labels(runs)
    found = baselines(runs)
    pairs = [(found[k][0], k, diffs[k]) for k in sorted(diffs)]
    if since_first is not None:
        pairs.append((since_first[0], len(runs) - 1, since_first[1]))
    out, said = [], set()
    for base, k, d in pairs:
        if base is None:
            continue
        for (suite, old, new, _), note in zip(renamed(d), rename_notes(d, names[base], names[k], series=True),
                                              strict=True):  # fmt: skip
            if (suite, old, new) not in said:  # oldest pair first: said at the run that renamed it
                said.add((suite, old, new))
                out.append(note)
    return out


def first_changes(history: pd.DataFrame) -> list[str]:
    """One line per value that changed (regression, improvement or a lost sequence), each against
    the run's baseline; a series' first change says so."""
    lines = []
    by_key = history.set_index(["run", "suite", "algorithm", "scene", "metric"])["value"]
    for r in history[history["changed"].astype(bool)].itertuples():
        was = by_key.get((r.baseline, r.suite, r.algorithm, r.scene, r.metric), np.nan)
        now = f"{r.value:.4f}" if np.isfinite(r.value) else "no value"
        word = {"regression": "worse", "improvement": "better"}.get(r.status, "a sequence or trial lost")
        first = "first change" if r.first_change else "change"
        lines.append(f"{r.algorithm}{f' ({r.suite})' if r.suite else ''} {r.scene} {r.metric}: {first} in {r.run} "
                     f"against {r.baseline} ({was:.4f} -> {now}, {word})")  # fmt: skip
    return lines


def plot_history(history: pd.DataFrame, metric: str):
    """One panel per scene, one line per algorithm over the runs; runs not comparable with the one
    before are marked with a dashed line, changes by diff's rule against each run's baseline with a
    ring. Names (runs, algorithms, suites, scenes) shown as the terminal shows them (:func:`clean`):
    a control character, which no font draws and XML 1.0 cannot hold, never reaches an SVG file."""
    from lorisnb.tools.figures.plotting import MAX_WIDTH_IN, subplots

    h = history[history["metric"] == metric]
    scenes = list(dict.fromkeys(h["scene"]))
    runs = list(dict.fromkeys(h["run"]))
    x = {r: i for i, r in enumerate(runs)}
    fig, axes = subplots(1, max(len(scenes), 1), figsize=(min(MAX_WIDTH_IN, 3.2 * max(len(scenes), 1)), 3.2),
                         squeeze=False, sharey=True)  # fmt: skip
    for ax, scene in zip(axes[0], scenes, strict=False):
        s = h[h["scene"] == scene]
        for (suite, alg), g in s.groupby(["suite", "algorithm"], sort=False):
            xs = g["run"].map(x).to_numpy()
            line = ax.plot(
                xs, g["value"].to_numpy(float), marker="o", ms=3, label=clean(f"{alg}{f' ({suite})' if suite else ''}")
            )
            ch = g[g["changed"].astype(bool)]
            ax.plot(ch["run"].map(x), ch["value"], "o", mfc="none", ms=9, color=line[0].get_color())
        for r in s.loc[~s["comparable"], "run"].unique():
            ax.axvline(x[r] - 0.5, color="0.4", ls="--", lw=1)
        ax.set_title(clean(scene))
        ax.set_xticks(range(len(runs)), [clean(r) for r in runs], rotation=45, ha="right", fontsize=7)
    axes[0][0].set_ylabel(metric)
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.suptitle(f"{metric} over runs (ring: changed by diff's rule; dashed: not comparable with the run before)",
                 fontsize=8)  # fmt: skip
    fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 3) or 1, fontsize=7, frameon=False)
    fig.tight_layout(rect=(0, 0.08 + 0.05 * ((len(labels) - 1) // 3), 1, 1))
    return fig


def write_figures(history: pd.DataFrame, out_dir: str | os.PathLike[str]) -> list[Path]:
    """``history_<metric>.png`` and ``.svg`` for every metric of the table."""
    from lorisnb.tools.figures.plotting import save_figure

    paths = []
    for m in dict.fromkeys(history["metric"]):
        paths += save_figure(plot_history(history, m), Path(out_dir), f"history_{m}", formats=("png", "svg"))
    return paths
