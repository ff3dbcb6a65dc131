"""The challenge's database (SQLAlchemy; SQLite in WAL mode by default, any SQLAlchemy URL such as
``postgresql://...`` otherwise): teams with their tokens stored as SHA-256 hashes, submissions,
and the scoring queue, which lives in the submissions' ``status`` so that a server killed while
scoring resumes on restart.

A submission goes ``queued`` -> ``scoring`` -> ``scored`` (or ``failed``: the scorer ran and
refused it, with the reason). A result is committed by one conditional update (only a
submission still ``scoring`` under the same claim takes it) together with its row in
``scorings``, whose primary key is the submission: a submission is scored at most once, and the
queue scores it at least once.
"""

from __future__ import annotations

import hashlib
import json
import secrets
import time
import unicodedata
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any

from sqlalchemy import (
    Boolean,
    Column,
    Engine,
    Float,
    ForeignKey,
    Integer,
    MetaData,
    String,
    Table,
    Text,
    create_engine,
    event,
    func,
    select,
    update,
)
from sqlalchemy.engine import Connection
from sqlalchemy.exc import SQLAlchemyError

from lorisnb.errors import LorisError, ValidationError

metadata = MetaData()

teams = Table(
    "teams",
    metadata,
    Column("id", Integer, primary_key=True),
    Column("name", String(80), unique=True, nullable=False),
    Column("token_hash", String(64), unique=True, nullable=False),
    Column("admin", Boolean, nullable=False, default=False),
    Column("created", Float, nullable=False),
    Column("expires", Float, nullable=False),  # epoch seconds, UTC
)

submissions = Table(
    "submissions",
    metadata,
    Column("id", String(32), primary_key=True),  # random: a submission's page is not guessable
    Column("team_id", Integer, ForeignKey("teams.id"), nullable=False, index=True),
    Column("phase", String(80), nullable=False),
    Column("created", Float, nullable=False, index=True),
    Column("status", String(16), nullable=False, index=True),  # queued, scoring, scored, failed
    Column("files", Text, nullable=False),  # JSON list of the names accepted
    Column("bytes", Integer, nullable=False),
    Column("claim", String(32), nullable=True),  # the scorer's claim while scoring
    Column("attempts", Integer, nullable=False, default=0),
    Column("error", Text, nullable=True),  # why the scorer refused it (public words)
    Column("result", Text, nullable=True),  # JSON: per-sequence rows and failures (server-side)
    Column("finished", Float, nullable=True),
)

scorings = Table(  # one row per scored submission: the ledger behind "each scored exactly once"
    "scorings",
    metadata,
    Column("submission_id", String(32), ForeignKey("submissions.id"), primary_key=True),
    Column("finished", Float, nullable=False),
    Column("seconds", Float, nullable=False),
)

STATUSES = ("queued", "scoring", "scored", "failed")


def hash_token(token: str) -> str:
    """The stored form of a token: its SHA-256 in hex (tokens are 32 random bytes: no salt needed)."""
    return hashlib.sha256(token.encode("utf-8", "surrogatepass")).hexdigest()


def new_token() -> str:
    """32 random bytes, URL-safe, never starting with ``-``: a command line takes ``--token -abc...``
    for two options ("expected one argument"), which one token in 64 was."""
    while (token := secrets.token_urlsafe(32)).startswith("-"):
        pass
    return token


def connect(url: str) -> Engine:
    """The engine of ``url``, its tables created; SQLite in WAL mode (readers never block the
    writer, a backup can run while the server does) with a busy timeout. A database that cannot be
    opened is a :class:`LorisError` saying why (the challenge file's ``database``)."""
    try:
        return _connect(url)
    except (SQLAlchemyError, ImportError, ValueError) as exc:
        said = url.split("@")[-1]  # never a password
        why = getattr(exc, "orig", None) or exc
        raise LorisError(f"database {said}: cannot be opened ({type(why).__name__}: {why}); check the challenge "
                         "file's [challenge] database (an SQLAlchemy URL; left out: challenge.db in its folder)") from None  # fmt: skip


def _connect(url: str) -> Engine:
    sqlite = url.startswith("sqlite")
    engine = create_engine(url, connect_args={"timeout": 30, "check_same_thread": False} if sqlite else {})
    if sqlite:

        @event.listens_for(engine, "connect")
        def _pragmas(dbapi_connection: Any, _record: Any) -> None:
            cur = dbapi_connection.cursor()
            cur.execute("PRAGMA journal_mode=WAL")
            cur.execute("PRAGMA synchronous=FULL")  # a committed upload survives a power cut
            cur.execute("PRAGMA foreign_keys=ON")
            cur.close()

    metadata.create_all(engine)
    return engine


@contextmanager
def transaction(engine: Engine) -> Iterator[Connection]:
    with engine.begin() as conn:
        yield conn


#: Characters that show nothing though Unicode counts them as letters or marks (Hangul fillers, the
#: combining grapheme joiner); the others that show nothing or turn the text around (formats, such
#: as U+200B and U+202E, and variation selectors) are found by their category and name.
INVISIBLE_LETTERS = frozenset("\u115f\u1160\u3164\uffa0\u034f")
#: Scripts that may share a name (Unicode's "highly restrictive" profile, UTS #39): one script, or
#: Latin with Han, Hiragana and Katakana (Japanese), with Han and Bopomofo, or with Han and Hangul.
SCRIPT_SETS = (
    frozenset({"Latin", "Han", "Hiragana", "Katakana"}),
    frozenset({"Latin", "Han", "Bopomofo"}),
    frozenset({"Latin", "Han", "Hangul"}),
)
#: Letters of other scripts (and digits) drawn like Latin letters, with the Latin letter they look
#: like (before case folding: Cyrillic and Greek capitals and small letters, 1 and I as l, 0 as O).
#: Latin letters of the IPA and small capitals drawn like plain ones are these too (ɑ U+0251 as a,
#: ɡ as g, dotless ı and ȷ, small capital ɪ as i...).
LOOK_ALIKE = str.maketrans(
    "АВЕЅІЈКМНОРСТХУҮҺӀаеѕіјорсхуүһӏԁԛԝьΑΒΕΖΗΙΚΜΝΟΡΤΥΧαεικνορτυχ10I|ɑɡɩıȷɪʟʀɴʏʙʜᴀᴄᴅᴇᴊᴋᴍᴏᴘᴛᴜᴠᴡᴢ",
    "ABESIJKMHOPCTXYYHIaesijopcxyyhldqwbABEZHIKMNOPTYXaeikvoptuxlOllagiijilrnybhacdejkmoptuvwz",
)
#: Letters drawn like punctuation a name cannot hold (the click letters: ǀ like |, ǁ like ||, ǂ,
#: ǃ U+01C3 like !): refused, as the punctuation is.
PUNCTUATION_LETTERS = frozenset("\u01c0\u01c1\u01c2\u01c3")
SEPARATORS = " -_."


def _script(ch: str) -> str | None:
    """The script of a letter or digit, from its Unicode name (None: a separator or an ASCII digit,
    which go with any script)."""
    if ch in SEPARATORS or ch in "0123456789":
        return None
    first = unicodedata.name(ch, "UNKNOWN").split(" ")[0].split("-")[0]
    return {"CJK": "Han", "IDEOGRAPHIC": "Han", "HANGUL": "Hangul", "HIRAGANA": "Hiragana", "KATAKANA": "Katakana",
            "BOPOMOFO": "Bopomofo"}.get(first, first.capitalize())  # fmt: skip


def name_key(name: str) -> str:
    """What a team name looks like (names with the same key are refused as look-alikes): its NFKC
    form (full-width, mathematical and other compatibility letters as the plain ones), each letter
    drawn like a Latin one as that letter (:data:`LOOK_ALIKE`), case folded, without separators,
    ``rn`` as ``m`` and ``vv`` as ``w``."""
    folded = unicodedata.normalize("NFKC", unicodedata.normalize("NFKC", name).translate(LOOK_ALIKE).casefold())
    key = "".join(c for c in folded.translate(LOOK_ALIKE) if c not in SEPARATORS)
    return key.replace("rn", "m").replace("vv", "w")


def _hidden(c: str) -> bool:
    """Whether ``c`` shows nothing, turns the text around it, or is a space other than ' '."""
    category = unicodedata.category(c)
    return (category in ("Cf", "Cc", "Co", "Cs", "Cn", "Zl", "Zp") or (category == "Zs" and c != " ")
            or c in INVISIBLE_LETTERS or unicodedata.name(c, "").startswith("VARIATION SELECTOR"))  # fmt: skip


def _allowed(c: str) -> bool:
    """A letter, a digit, a separator, or a mark of a script's own (a Devanagari vowel sign: a
    combining accent on a Latin letter is composed by NFC, or refused)."""
    if c in PUNCTUATION_LETTERS:
        return False
    if c.isalnum() or c in SEPARATORS:
        return True
    return unicodedata.category(c) in ("Mn", "Mc") and _script(c) not in (
        None,
        "Combining",
        "Latin",
        "Greek",
        "Cyrillic",
    )


def check_team_name(name: str, others: Sequence[str] = ()) -> str:
    """``name`` as it is stored (stripped, NFC), or a :class:`ValidationError` saying what to change:
    1 to 80 letters, digits, spaces, ``-``, ``_`` or ``.``; no invisible or direction-changing
    character, no space but ' '; letters of one script (or of a set that writes one language:
    :data:`SCRIPT_SETS`); not looking like one of ``others`` (:func:`name_key`)."""
    name = unicodedata.normalize("NFC", name.strip())
    hidden = [c for c in name if _hidden(c)]
    if hidden:
        what = ", ".join(f"U+{ord(c):04X} {unicodedata.name(c, 'unnamed')}" for c in dict.fromkeys(hidden))
        raise ValidationError(f"team name {name!r}: holds a character that is invisible, turns the text around it or "
                              f"is a space other than ' ' ({what}); type the name with letters, digits, spaces, '-', "
                              "'_' or '.' only")  # fmt: skip
    clicks = [c for c in name if c in PUNCTUATION_LETTERS]
    if clicks:
        what = ", ".join(f"{c!r} U+{ord(c):04X} {unicodedata.name(c, '')}" for c in dict.fromkeys(clicks))
        raise ValidationError(f"team name {name!r}: holds a letter drawn like punctuation ({what}); expected 1 to 80 "
                              "letters, digits, spaces, '-', '_' or '.'")  # fmt: skip
    if not name or len(name) > 80 or not all(map(_allowed, name)):
        raise ValidationError(f"team name {name!r}: expected 1 to 80 letters, digits, spaces, '-', '_' or '.'")
    letters = [(c, _script(c)) for c in unicodedata.normalize("NFKC", name)]
    scripts = {s for _, s in letters if s is not None}
    if len(scripts) > 1 and not any(scripts <= allowed for allowed in SCRIPT_SETS):
        counts = {s: sum(1 for _, t in letters if t == s) for s in scripts}
        main = max(sorted(scripts), key=lambda s: counts[s])
        odd = ", ".join(f"{c!r} U+{ord(c):04X} {unicodedata.name(c, '')}" for c in dict.fromkeys(
            c for c, t in letters if t is not None and t != main))  # fmt: skip
        raise ValidationError(f"team name {name!r}: mixes {main} letters with letters of "
                              f"{', '.join(sorted(scripts - {main}))} ({odd}), which makes names that look alike but "
                              "differ; write it in one script")  # fmt: skip
    key = name_key(name)
    for other in others:
        if other == name:
            raise ValidationError(f"team name {name!r}: a team of that name exists; choose another name")
        if name_key(other) == key:
            raise ValidationError(f"team name {name!r}: looks like the existing team {other!r} (names are compared as "
                                  "they look: any case, width or script of a letter drawn alike, 1 and l, 0 and O, "
                                  "and with spaces, '-', '_' and '.' left out); choose a name that looks different")  # fmt: skip
    return name


def add_team(engine: Engine, name: str, expires: float, admin: bool = False) -> str:
    """Add a team (or the admin, ``admin``); returns its token, which is stored hashed only. The
    name is checked by :func:`check_team_name` against every team's (one that looks like another
    on the leaderboard is refused)."""
    name = check_team_name(name)
    token = new_token()
    with transaction(engine) as conn:
        others = [str(n) for n in conn.execute(select(teams.c.name)).scalars()]
        name = check_team_name(name, others)
        conn.execute(teams.insert().values(name=name, token_hash=hash_token(token), admin=admin, created=time.time(),
                                           expires=expires))  # fmt: skip
    return token


def team_of(engine: Engine, token: str | None) -> dict[str, Any] | None:
    """The team whose token this is (any expiry), None for no such token."""
    if not token:
        return None
    with engine.connect() as conn:
        row = conn.execute(select(teams).where(teams.c.token_hash == hash_token(token))).mappings().first()
    return dict(row) if row is not None else None


def submissions_since(engine: Engine, team_id: int, since: float) -> int:
    with engine.connect() as conn:
        q = (
            select(func.count())
            .select_from(submissions)
            .where((submissions.c.team_id == team_id) & (submissions.c.created >= since))
        )
        return int(conn.execute(q).scalar_one())


def submission_times_since(engine: Engine, team_id: int, since: float) -> list[float]:
    """When each of a team's submissions since ``since`` was made, oldest first (the daily limit's
    count, and when it resets)."""
    with engine.connect() as conn:
        q = (
            select(submissions.c.created)
            .where((submissions.c.team_id == team_id) & (submissions.c.created >= since))
            .order_by(submissions.c.created)
        )
        return [float(t) for t in conn.execute(q).scalars()]


def add_submission(engine: Engine, sid: str, team_id: int, phase: str, files: list[str], size: int) -> None:
    with transaction(engine) as conn:
        conn.execute(submissions.insert().values(id=sid, team_id=team_id, phase=phase, created=time.time(),
                                                 status="queued", files=json.dumps(files), bytes=size,
                                                 attempts=0))  # fmt: skip


def requeue_unfinished(engine: Engine) -> int:
    """Put back in the queue every submission a killed server left ``scoring`` (no result was
    committed for it); the number put back."""
    with transaction(engine) as conn:
        res = conn.execute(
            update(submissions).where(submissions.c.status == "scoring").values(status="queued", claim=None)
        )
        return int(res.rowcount or 0)


def claim_next(engine: Engine) -> tuple[str, str] | None:
    """Take the oldest queued submission for scoring: (its id, the claim), or None if none waits.
    The update is conditional on ``queued``, so two scorers never take the same one."""
    with transaction(engine) as conn:
        while True:
            row = conn.execute(
                select(submissions.c.id).where(submissions.c.status == "queued").order_by(submissions.c.created)
                .limit(1)
            ).first()  # fmt: skip
            if row is None:
                return None
            claim = secrets.token_hex(8)
            res = conn.execute(
                update(submissions).where((submissions.c.id == row.id) & (submissions.c.status == "queued"))
                .values(status="scoring", claim=claim, attempts=submissions.c.attempts + 1)
            )  # fmt: skip
            if res.rowcount == 1:
                return row.id, claim


def release(engine: Engine, sid: str, claim: str) -> None:
    """Put a claimed submission back in the queue (its scoring could not start)."""
    with transaction(engine) as conn:
        conn.execute(
            update(submissions).where((submissions.c.id == sid) & (submissions.c.claim == claim)
                                      & (submissions.c.status == "scoring")).values(status="queued", claim=None)
        )  # fmt: skip


def finish(engine: Engine, sid: str, claim: str, status: str, result: dict[str, Any] | None, error: str | None,
           seconds: float) -> bool:  # fmt: skip
    """Commit a scoring's outcome (``scored`` with its result, or ``failed`` with the reason) and
    its ledger row, in one transaction; False if the claim is no longer the submission's."""
    if status not in ("scored", "failed"):
        raise ValueError(status)
    now = time.time()
    with transaction(engine) as conn:
        res = conn.execute(
            update(submissions).where((submissions.c.id == sid) & (submissions.c.status == "scoring")
                                      & (submissions.c.claim == claim))
            .values(status=status, result=None if result is None else json.dumps(result), error=error,
                    finished=now, claim=None)
        )  # fmt: skip
        if res.rowcount != 1:
            return False
        conn.execute(scorings.insert().values(submission_id=sid, finished=now, seconds=seconds))
    return True


def submission(engine: Engine, sid: str) -> dict[str, Any] | None:
    with engine.connect() as conn:
        row = conn.execute(
            select(submissions, teams.c.name.label("team")).join(teams).where(submissions.c.id == sid)
        ).mappings().first()  # fmt: skip
    return dict(row) if row is not None else None


def all_submissions(engine: Engine, team_id: int | None = None, results: bool = True) -> list[dict[str, Any]]:
    """Every submission (of one team), oldest first, with its team's name; without the results'
    JSON unless ``results``."""
    cols = [c for c in submissions.c if results or c.name != "result"]
    q = select(*cols, teams.c.name.label("team")).join(teams).order_by(submissions.c.created)
    if team_id is not None:
        q = q.where(submissions.c.team_id == team_id)
    with engine.connect() as conn:
        return [dict(r) for r in conn.execute(q).mappings()]


def all_teams(engine: Engine) -> list[dict[str, Any]]:
    with engine.connect() as conn:
        rows = conn.execute(select(teams.c.id, teams.c.name, teams.c.admin, teams.c.created, teams.c.expires)
                            .order_by(teams.c.id)).mappings()  # fmt: skip
        return [dict(r) for r in rows]


def queue_counts(engine: Engine) -> dict[str, int]:
    with engine.connect() as conn:
        rows = conn.execute(select(submissions.c.status, func.count()).group_by(submissions.c.status)).all()
    counts = {s: 0 for s in STATUSES}
    counts.update({str(s): int(n) for s, n in rows})
    return counts


def scoring_ledger(engine: Engine) -> dict[str, int]:
    """Submission id -> how many results were committed for it (each scored exactly once: all 1)."""
    with engine.connect() as conn:
        rows = conn.execute(select(scorings.c.submission_id, func.count()).group_by(scorings.c.submission_id)).all()
    return {str(s): int(n) for s, n in rows}
