"""The challenge file (``CHALLENGE.toml``): where the hidden ground truth is, the phases and the
sequences each ranks on, the metric and the evaluation spec, the limits and the opening and
closing times. Every key is checked here; a wrong one is a :class:`~lorisnb.errors.ParseError`
naming the file, the key and what was expected.

Example::

    [challenge]
    title = "Lifelong SLAM, class of 2026"
    groundtruth = "../shared/data"      # a data root (openloris-scene/groundtruth/gt_<scene>_1.txt): hidden
    folder = "challenge-data"          # the server's own folder: database, uploads (default: beside the file)
    metric = "cr"                      # cr, cr_t, cs_r or c_ate_rmse
    opens = 2026-11-01T00:00:00Z
    closes = 2026-12-01T00:00:00Z

    [spec]                             # any lorisnb evaluation spec: a preset and its options
    mode = "per-seq"
    eps = 1.0

    [limits]
    submissions_per_day = 5
    upload_mb = 20

    [[phase]]
    name = "development"
    scenes = ["cafe"]
    sequences = { cafe = [1] }         # default: every sequence of the scenes
    leaderboard = "live"               # or "after-close": scores and figures hidden until it closes
"""

from __future__ import annotations

import datetime as dt
import math
import os
import re
import tomllib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from lorisnb.core.spec import validate
from lorisnb.core.spec.evalspec import SPEC_NAMES, EvalSpec
from lorisnb.core.stats.inference import WEIGHTS
from lorisnb.core.trajectory.frames import SCENES
from lorisnb.errors import LorisError, ParseError
from lorisnb.io.datasets.manifest import check_keys
from lorisnb.io.datasets.paths import DataPaths, find_data

CHALLENGE_KEYS = {"title", "groundtruth", "folder", "database", "metric", "opens", "closes", "scheduler"}
#: The limits and their defaults: submissions per team in any 24 hours, the upload's size (MB),
#: the files in it, their unpacked size (MB), a submission's scoring time (CPU seconds) and memory
#: (MB), the scoring processes at a time, the time a client may take to send its upload (s), and
#: to send a request's headers (s: a connection is dropped past it, :func:`.app.http_protocol`).
LIMITS: dict[str, int] = {
    "submissions_per_day": 5,
    "upload_mb": 20,
    "files": 200,
    "unpacked_mb": 200,
    "score_seconds": 300,
    "score_memory_mb": 3072,
    "workers": 1,
    "upload_seconds": 60,
    "header_seconds": 10,
}
PHASE_KEYS = {"name", "scenes", "sequences", "opens", "closes", "leaderboard"}
BOARDS = ("live", "after-close")


@dataclass(frozen=True)
class Phase:
    """A phase: its name, the scenes and sequences its leaderboard ranks on (None: every sequence
    of the scene), its opening and closing times (UTC, epoch seconds) and whether its scores show
    while it runs (``live``) or only once it has closed (``after-close``)."""

    name: str
    scenes: tuple[str, ...]
    sequences: Mapping[str, tuple[int, ...]] | None
    opens: float
    closes: float
    leaderboard: str = "live"

    def is_open(self, now: float) -> bool:
        return self.opens <= now < self.closes

    def shows_scores(self, now: float) -> bool:
        """Scores, tables and figures of this phase may be shown: once it has opened (a phase not yet
        open shows nothing of its sequences: an organizer reveals a sequence a week by a phase of
        its own), while it runs if ``live``, and once it has closed."""
        return now >= self.opens and (self.leaderboard == "live" or now >= self.closes)

    @property
    def shows_from(self) -> float:
        """When this phase's scores are first shown (:meth:`shows_scores`): its opening if ``live``,
        else its close."""
        return self.opens if self.leaderboard == "live" else self.closes

    def keeps(self, scene: str, seq: int) -> bool:
        if scene not in self.scenes:
            return False
        # a scene not named in ``sequences`` ranks on all its sequences
        return self.sequences is None or scene not in self.sequences or seq in self.sequences[scene]


@dataclass(frozen=True)
class Challenge:
    """A checked challenge file (see the module docstring)."""

    path: Path
    title: str
    data: DataPaths  # the hidden ground truth
    folder: Path
    database: str
    metric: str
    opens: float
    closes: float
    spec_options: Mapping[str, Any]
    spec: EvalSpec
    limits: Mapping[str, int]
    phases: tuple[Phase, ...] = field(default_factory=tuple)
    scheduler: str | None = None  # a Dask scheduler's address: scoring there instead of here

    @property
    def public_groundtruth(self) -> str | None:
        """Why teams may hold this challenge's ground truth (None when nothing says so): it is the
        sample data shipped in the lorisnb package (``lorisnb/sample_data``), which every
        ``pip install lorisnb`` holds. Such a challenge is for practice: a team can upload the
        ground truth itself (refused, :func:`.scoring.groundtruth_copies`) or a copy of it changed a
        little (not told from a very good estimate)."""
        parts = self.data.root.resolve().parts
        if "sample_data" in parts and "lorisnb" in parts[: parts.index("sample_data")]:
            return ("its ground truth is lorisnb's sample data (lorisnb/sample_data), which ships with lorisnb: every "
                    "team that installed lorisnb has it, so this challenge is for practice, not for grading")  # fmt: skip
        return None

    def phase_at(self, now: float) -> Phase | None:
        """The phase open at ``now`` (phases do not overlap: :func:`read_challenge`), None between phases."""
        if not self.opens <= now < self.closes:
            return None
        return next((p for p in self.phases if p.is_open(now)), None)

    def phase(self, name: str) -> Phase:
        for p in self.phases:
            if p.name == name:
                return p
        raise LorisError(f"no phase {name!r}; the phases are {', '.join(p.name for p in self.phases)}")

    @property
    def scenes(self) -> tuple[str, ...]:
        return tuple(s for s in SCENES if any(s in p.scenes for p in self.phases))

    def visible(self, sequences: Iterable[tuple[str, int]], now: float) -> frozenset[tuple[str, int]]:
        """The ``sequences`` (scene, seq) whose scores may leave the server at ``now``: those of a
        phase that shows its scores (opened and live, or closed). A sequence in a shown and a hidden
        phase is shown; one in no phase never is."""
        shown = [p for p in self.phases if p.shows_scores(now)]
        return frozenset((s, int(q)) for s, q in sequences if any(p.keeps(s, int(q)) for p in shown))

    def shown(self, phase: Phase, sequences: Iterable[tuple[str, int]], now: float) -> frozenset[tuple[str, int]]:
        """The ``sequences`` of a submission of ``phase`` shown to its team at ``now``: none while the
        phase's scores are hidden (:meth:`Phase.shows_scores`), else the :meth:`visible` ones. The one
        test of what a team is told of its submission now: its rows, and whether a copy of the ground
        truth it uploaded is named by its sequence (:func:`.board.team_error`)."""
        return self.visible(sequences, now) if phase.shows_scores(now) else frozenset()

    def views(
        self, sequences: Iterable[tuple[str, int]], phase: Phase | None = None
    ) -> list[frozenset[tuple[str, int]]]:
        """Every set of :meth:`visible` sequences the challenge goes through, in order: as each
        phase's scores start to show (a ``live`` phase's opening, an ``after-close`` phase's close);
        of ``phase``, those while its scores show. A submission of the phase is scored on each set
        alone, and its figure drawn of each (:func:`.scoring.score_folder`): no number shown comes
        from ground truth not shown."""
        seqs = list(sequences)
        times = [-math.inf] + sorted({p.shows_from for p in self.phases})
        if phase is not None:
            times = [t for t in times if phase.shows_scores(t)]
        return [v for v in dict.fromkeys(self.visible(seqs, t) for t in times) if v]

    def shown_by(self, scene: str, seq: int) -> Phase | None:
        """The phase whose scores first show a sequence (:attr:`Phase.shows_from`: a live phase's
        opening, an after-close phase's close); None if no phase holds it (never shown)."""
        holding = [p for p in self.phases if p.keeps(scene, seq)]
        return min(holding, key=lambda p: p.shows_from, default=None)


def sequences_of(durations: Any) -> list[tuple[str, int]]:
    """The (scene, seq) of every ground-truth sequence of a durations table (its ``scene`` and
    ``seq`` columns: :func:`lorisnb.io.datasets.paths.scene_durations`)."""
    return [(str(s), int(q)) for s, q in zip(durations["scene"], durations["seq"], strict=True)]


def _time(raw: Mapping[str, Any], key: str, path: Path, where: str, default: float | None = None) -> float:
    value = raw.get(key)
    if value is None:
        if default is not None:
            return default
        raise ParseError(path, None, f"{where}{key}: missing; expected a date and time with its offset, "
                         "e.g. 2026-12-01T18:00:00Z")  # fmt: skip
    if not isinstance(value, dt.datetime) or value.tzinfo is None:
        raise ParseError(path, None, f"{where}{key} = {value!r}: expected a date and time with its offset "
                         "(TOML, unquoted), e.g. 2026-12-01T18:00:00Z or 2026-12-01T18:00:00+01:00")  # fmt: skip
    return value.timestamp()


def _text(raw: Mapping[str, Any], key: str, path: Path, where: str, default: str | None = None) -> str:
    value = raw.get(key, default)
    if not isinstance(value, str) or not value.strip():
        raise ParseError(path, None, f"{where}{key} = {value!r}: expected a non-empty text in quotes")
    return value


def _choice(name: str, value: Any, options: tuple[str, ...], path: Path) -> str:
    try:
        return validate.choice(name, value, options)
    except LorisError as exc:
        raise ParseError(path, None, str(exc)) from None


def _table(raw: Mapping[str, Any], key: str, path: Path) -> dict[str, Any]:
    value = raw.get(key, {})
    if not isinstance(value, dict):
        raise ParseError(path, None, f"{key}: expected a table [{key}], got {value!r}")
    return value


def _phase(raw: Any, k: int, challenge: tuple[float, float], have: list[str], path: Path) -> Phase:
    where = f"[[phase]] {k}: "
    if not isinstance(raw, dict):
        raise ParseError(path, None, f"{where}expected a table with name, scenes, ...")
    check_keys(raw, PHASE_KEYS, path, where)
    name = _text(raw, "name", path, where)
    scenes = raw.get("scenes")
    if isinstance(scenes, str):
        scenes = [scenes]
    if not isinstance(scenes, list) or not scenes or not all(isinstance(s, str) for s in scenes):
        raise ParseError(path, None, f'{where}scenes = {scenes!r}: expected a list of scene names, e.g. ["cafe"]')
    for s in scenes:
        if s not in have:
            hint = validate.near_miss(s, have)
            raise ParseError(path, None, f"{where}scenes: {s!r} has no ground truth in the challenge's groundtruth "
                             f"folder{f' ({hint})' if hint else ''}; it has {', '.join(have) or 'none'}")  # fmt: skip
    sequences = raw.get("sequences")
    kept: dict[str, tuple[int, ...]] | None = None
    if sequences is not None:
        if not isinstance(sequences, dict):
            raise ParseError(path, None, f"{where}sequences = {sequences!r}: expected a table scene = [numbers]")
        kept = {}
        for s, seqs in sequences.items():
            if s not in scenes:
                raise ParseError(path, None, f"{where}sequences: {s!r} is not one of the phase's scenes "
                                 f"({', '.join(scenes)})")  # fmt: skip
            if not isinstance(seqs, list) or not seqs or not all(isinstance(q, int) and q > 0 for q in seqs):
                raise ParseError(path, None, f"{where}sequences.{s} = {seqs!r}: expected a list of sequence "
                                 "numbers (1, 2, ...)")  # fmt: skip
            kept[s] = tuple(sorted(set(seqs)))
    opens = _time(raw, "opens", path, where, challenge[0])
    closes = _time(raw, "closes", path, where, challenge[1])
    if closes <= opens:
        raise ParseError(path, None, f"{where}closes is not after opens; expected closes later than opens")
    board = _choice(f"{where}leaderboard", raw.get("leaderboard", "live"), BOARDS, path)
    return Phase(name, tuple(s for s in SCENES if s in scenes), kept, opens, closes, board)


def _check_sequences(phases: tuple[Phase, ...], data: DataPaths, path: Path) -> None:
    """Refuse a phase's ``sequences`` naming a sequence its scene's ground truth does not have
    (the phase would rank on nothing). Only the scenes with a ``sequences`` table are read (cached:
    the server reads them again for the durations)."""
    from lorisnb.io.datasets.paths import load_groundtruth

    for k, phase in enumerate(phases, start=1):
        for scene, seqs in (phase.sequences or {}).items():
            have = sorted(int(q) for q in load_groundtruth(scene, data).sequences)
            absent = [q for q in seqs if q not in have]
            if absent:
                raise ParseError(path, None, f"[[phase]] {k}: sequences.{scene}: no ground truth for sequence(s) "
                                 f"{', '.join(map(str, absent))} of {scene}; expected some of "
                                 f"{', '.join(map(str, have))}")  # fmt: skip


def _stamp(t: float) -> str:
    return dt.datetime.fromtimestamp(t, dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def _check_times(phases: tuple[Phase, ...], opens: float, closes: float, path: Path) -> None:
    """Refuse a phase opening or closing outside the challenge's window (an upload then would go
    to no phase, or its board would never show), and two phases open at once (an upload goes to
    one of them only: the other's teams could not tell which), naming the phases and their times."""
    window = f"the challenge runs from {_stamp(opens)} to {_stamp(closes)} ([challenge] opens, closes)"
    for k, p in enumerate(phases, start=1):
        where = f"[[phase]] {k} ({p.name!r}): "
        if p.opens < opens:
            raise ParseError(path, None, f"{where}opens = {_stamp(p.opens)}, before the challenge opens; {window}: "
                             "expected a time within it")  # fmt: skip
        if p.opens >= closes:
            raise ParseError(path, None, f"{where}opens = {_stamp(p.opens)}, after the challenge closes; {window}: "
                             "expected a time within it")  # fmt: skip
        if p.closes > closes:
            raise ParseError(path, None, f"{where}closes = {_stamp(p.closes)}, after the challenge closes; {window}: "
                             "expected a time within it")  # fmt: skip
    for i, p in enumerate(phases, start=1):
        for j, q in enumerate(phases[i:], start=i + 1):
            if p.opens < q.closes and q.opens < p.closes:
                raise ParseError(path, None, f"[[phase]] {i} ({p.name!r}, {_stamp(p.opens)} to {_stamp(p.closes)}) and "
                                 f"[[phase]] {j} ({q.name!r}, {_stamp(q.opens)} to {_stamp(q.closes)}) overlap; an "
                                 "upload goes to one phase: expected one phase to close when or before the other "
                                 "opens (a phase's opens and closes default to the challenge's)")  # fmt: skip


#: What ``groundtruth`` names, said where it names something else.
GROUNDTRUTH_EXPECTED = ("expected groundtruth to name a data root: the folder holding openloris-scene/groundtruth/"
                        "gt_<scene>_1.txt (absolute, or relative to the challenge file)")  # fmt: skip
#: What ``database`` names, said where it names something else.
DATABASE_EXPECTED = ("expected an SQLAlchemy database URL, e.g. sqlite:////srv/challenge/challenge.db (a file in an "
                     "existing folder) or postgresql://USER@HOST/NAME; leave database out for challenge.db in the "
                     "server's folder")  # fmt: skip


def _groundtruth_advice(text: str, gt: Path) -> str:
    """:func:`find_data`'s message about ``groundtruth``, said for the challenge file: its advice
    on the command line (``--data``, ``LORISNB_DATA``, ``data_root=``), which ``lorisnb serve``
    does not take, left out for the key's; a folder inside a data root named with the root."""
    text = text.replace(" (argument)", "")
    kept = [
        t
        for t in re.split(r"(?<=\.)\s+", text)
        if not re.search(r"--data\b|LORISNB_DATA|data_root|^A data root holds", t)
    ]
    hint = ""
    for root in (gt, *gt.parents):
        if (root / "openloris-scene" / "groundtruth").is_dir() and root != gt:
            hint = f" ({gt} is inside the data root {root}: name that)"
            break
    return " ".join(kept).rstrip(". ") + f"; {GROUNDTRUTH_EXPECTED}{hint}"


def _check_folder(folder: Path, named: str, path: Path, where: str) -> None:
    """Refuse a ``folder`` that is, or lies under, an existing file (it could not be created)."""
    existing = next((p for p in (folder, *folder.parents) if p.exists()), None)
    if existing is not None and not existing.is_dir():
        what = "is a file" if existing == folder else f"lies under the file {existing}"
        raise ParseError(path, None, f"{where}folder = {named!r}: {folder} {what}; expected a folder, new or existing "
                         "(the server's own: its database, uploads)")  # fmt: skip


def _check_database(url: str, folder: Path, path: Path, where: str) -> str:
    """Refuse a ``database`` that is no SQLAlchemy URL, names a dialect or driver not installed,
    or an SQLite file in a folder that does not exist (the server's ``folder`` is created), or an
    in-memory SQLite database; the URL, a relative SQLite file made absolute from the challenge
    file's folder (as ``folder`` and ``groundtruth``: add-team and serve, started anywhere, use one)."""
    try:
        from sqlalchemy.engine import make_url
        from sqlalchemy.exc import ArgumentError, NoSuchModuleError
    except ImportError:  # serve and the challenge commands require it first
        return url
    said = url.split("@")[-1] if "@" in url else url  # never a password
    try:
        parsed = make_url(url)
    except (ArgumentError, ValueError):
        raise ParseError(path, None, f"{where}database = {said!r}: not a database URL; {DATABASE_EXPECTED}") from None
    try:
        dialect = parsed.get_dialect()
    except NoSuchModuleError:
        raise ParseError(path, None, f"{where}database = {said!r}: SQLAlchemy has no database {parsed.drivername!r}; "
                         f"{DATABASE_EXPECTED}") from None  # fmt: skip
    try:
        dialect.import_dbapi()
    except ImportError as exc:
        raise ParseError(path, None, f"{where}database = {said!r}: its driver is not installed ({exc}): install "
                         f"it; {DATABASE_EXPECTED}") from None  # fmt: skip
    name = parsed.database
    if parsed.get_backend_name() != "sqlite":
        return url
    memory = not name or name == ":memory:" or "mode=memory" in name or parsed.query.get("mode") == "memory"
    if memory:  # each connection its own empty database: a team added is gone, serve finds no table
        raise ParseError(path, None, f"{where}database = {said!r}: an in-memory SQLite database, lost when each "
                         f"connection closes (add-team's tokens, every submission); {DATABASE_EXPECTED}")  # fmt: skip
    if name is None or name.startswith("file:"):
        return url
    file = path.parent / Path(name).expanduser()  # a relative one: to the challenge file, as folder and groundtruth
    file = file.absolute()
    if file.is_dir():
        raise ParseError(path, None, f"{where}database = {said!r}: {file} is a folder; {DATABASE_EXPECTED}")
    if not file.parent.is_dir() and file.parent.resolve() != folder:
        raise ParseError(path, None, f"{where}database = {said!r}: the folder {file.parent} does not exist; expected a "
                         "database file in an existing folder (create it), or leave database out for challenge.db in the "
                         "server's folder")  # fmt: skip
    return parsed.set(database=str(file)).render_as_string(hide_password=False)


def read_challenge(path_like: str | os.PathLike[str]) -> Challenge:
    """Read and check a challenge file (see the module docstring)."""
    from lorisnb.tools.report.leaderboard import leaderboard_spec

    path = Path(path_like).expanduser().resolve()
    try:
        raw = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ParseError(path, None, "challenge file not found; expected a TOML file (see docs/guide/"
                         "challenge-server.md)") from None  # fmt: skip
    except (OSError, UnicodeDecodeError) as exc:
        raise ParseError(path, None, f"cannot be read ({exc})") from None
    except tomllib.TOMLDecodeError as exc:
        raise ParseError(path, getattr(exc, "lineno", None), f"not valid TOML ({exc})") from None
    check_keys(raw, {"challenge", "spec", "limits", "phase"}, path)
    top = _table(raw, "challenge", path)
    check_keys(top, CHALLENGE_KEYS, path, "[challenge]: ")
    where = "[challenge]: "
    title = _text(top, "title", path, where, "lorisnb challenge")
    gt = (path.parent / Path(_text(top, "groundtruth", path, where)).expanduser()).resolve()
    try:
        data = find_data(gt)
    except LorisError as exc:
        raise ParseError(
            path, None, f"{where}groundtruth = {top['groundtruth']!r}: {_groundtruth_advice(str(exc), gt)}"
        ) from None
    have = data.scenes_with_groundtruth()
    named = _text(top, "folder", path, where, f"{path.stem}-data")
    folder = (path.parent / Path(named).expanduser()).resolve()
    if folder == gt or gt in folder.parents:
        raise ParseError(path, None, f"{where}folder: inside the ground-truth folder; expected a folder of its own")
    _check_folder(folder, named, path, where)
    database = _text(top, "database", path, where, f"sqlite:///{folder / 'challenge.db'}")
    database = _check_database(database, folder, path, where)
    metric = _choice(f"{where}metric", top.get("metric", "cr"), tuple(WEIGHTS), path)
    opens = _time(top, "opens", path, where)
    closes = _time(top, "closes", path, where)
    if closes <= opens:
        raise ParseError(path, None, f"{where}closes is not after opens; expected closes later than opens")
    options = _table(raw, "spec", path)
    check_keys(options, set(SPEC_NAMES) | {"conventions"}, path, "[spec]: ")  # a typo would be ignored
    try:
        spec = leaderboard_spec(options)
    except LorisError as exc:
        raise ParseError(path, None, f"[spec]: {exc}") from None
    given = _table(raw, "limits", path)
    check_keys(given, set(LIMITS), path, "[limits]: ")
    limits = dict(LIMITS)
    for key, value in given.items():
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ParseError(path, None, f"[limits]: {key} = {value!r}: expected a whole number of 1 or more")
        limits[key] = value
    items = raw.get("phase")
    if not isinstance(items, list) or not items:
        raise ParseError(path, None, "no [[phase]] table; expected at least one, with name and scenes")
    phases = tuple(_phase(item, k, (opens, closes), have, path) for k, item in enumerate(items, start=1))
    _check_sequences(phases, data, path)
    names = [p.name for p in phases]
    if len(set(names)) < len(names):
        raise ParseError(path, None, f"[[phase]]: two phases named {next(n for n in names if names.count(n) > 1)!r}; "
                         "expected distinct names")  # fmt: skip
    _check_times(phases, opens, closes, path)
    scheduler = None
    if "scheduler" in top:
        from lorisnb.tools.evaluation.pool import scheduler_address

        scheduler = _text(top, "scheduler", path, where)
        try:
            scheduler_address(scheduler)
        except LorisError as exc:
            raise ParseError(path, None, f"{where}scheduler: {exc}") from None
    return Challenge(path, title, data, folder, database, metric, opens, closes, dict(options), spec, limits, phases,
                     scheduler)  # fmt: skip
