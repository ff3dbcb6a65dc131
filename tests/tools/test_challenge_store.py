"""The challenge database's queue: claims are exclusive under concurrency, a result is committed
once, a killed server's half-scored submissions go back to the queue, a claim that could not
start is released; tokens are stored as their SHA-256 only; a team name that looks like another
(an adversarial pass: 'tеam1' with a Cyrillic е, and 'Team1', beside 'team1') is refused."""

from __future__ import annotations

import hashlib
import re
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

pytest.importorskip("sqlalchemy")
from lorisnb.errors import ValidationError  # noqa: E402
from lorisnb.tools.challenge import store  # noqa: E402


@pytest.fixture()
def engine(tmp_path):
    return store.connect(f"sqlite:///{tmp_path / 'c.db'}")


def test_claims_are_exclusive_and_results_committed_once(engine):
    team = store.add_team(engine, "t", time.time() + 60)
    tid = store.team_of(engine, team)["id"]
    for i in range(40):
        store.add_submission(engine, f"s{i:02d}", tid, "p", ["a.txt"], 1)
    taken: list[tuple[str, str]] = []
    lock = threading.Lock()

    def worker():
        while (c := store.claim_next(engine)) is not None:
            with lock:
                taken.append(c)

    threads = [threading.Thread(target=worker) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sorted(s for s, _ in taken) == [f"s{i:02d}" for i in range(40)]  # each once, none twice
    sid, claim = taken[0]
    assert store.finish(engine, sid, claim, "scored", {"rows": []}, None, 0.1)
    assert not store.finish(engine, sid, claim, "scored", {"rows": []}, None, 0.1)  # once only
    assert not store.finish(engine, taken[1][0], "not-its-claim", "scored", {"rows": []}, None, 0.1)
    store.release(engine, *taken[1])
    assert store.submission(engine, taken[1][0])["status"] == "queued"
    assert store.requeue_unfinished(engine) == 38  # what a killed server left half-scored
    assert store.queue_counts(engine) == {"queued": 39, "scoring": 0, "scored": 1, "failed": 0}
    assert store.scoring_ledger(engine) == {sid: 1}


def test_tokens_hashed_and_names_checked(engine):
    token = store.add_team(engine, "Team A-1", time.time() + 60)
    row = store.team_of(engine, token)
    assert row["token_hash"] == hashlib.sha256(token.encode()).hexdigest() and len(token) >= 40
    assert store.team_of(engine, token + "x") is None and store.team_of(engine, "") is None
    with pytest.raises(ValidationError, match="exists"):
        store.add_team(engine, "Team A-1", time.time() + 60)
    with pytest.raises(ValidationError, match="letters, digits"):
        store.add_team(engine, "<script>", time.time() + 60)


def test_a_token_never_starts_like_an_option(monkeypatch):
    """``lorisnb submit URL FILES --token TOKEN`` with a token starting with '-' failed to parse (a
    random token did, one in 64: the challenge server's test failed so); such a draw is drawn again."""
    draws = iter(["-GihqsCyIiG1YTqtjzpd3T_YlIkG75CBVrAVBF_nyzM", "--x", "zBPSIJWBgGOxa3CrUGrr7Z20cqn"])
    monkeypatch.setattr(store.secrets, "token_urlsafe", lambda n: next(draws))
    assert store.new_token() == "zBPSIJWBgGOxa3CrUGrr7Z20cqn"


@pytest.mark.parametrize(
    "name, words",
    [
        ("team1", "a team of that name exists"),
        ("Team1", "looks like the existing team 'team1'"),  # case
        ("TEAM 1", "looks like the existing team 'team1'"),  # case and a separator
        ("team_1", "looks like the existing team 'team1'"),
        ("ｔｅａｍ１", "looks like the existing team 'team1'"),  # full-width (NFKC)
        ("ТЕАМ1", "looks like the existing team 'team1'"),  # every letter Cyrillic: one script, drawn alike
        ("teaml", "looks like the existing team 'team1'"),  # l for 1
        ("tеam1", "mixes Latin letters with letters of Cyrillic ('е' U+0435 CYRILLIC SMALL LETTER IE)"),
        ("Ωmega", "mixes Latin letters with letters of Greek ('Ω' U+03A9"),  # the fewer named
        ("team\u202e1", "U+202E RIGHT-TO-LEFT OVERRIDE"),
        ("te\u200bam", "U+200B ZERO WIDTH SPACE"),
        ("team\u3164", "U+3164 HANGUL FILLER"),
        ("team\ufe0f2", "U+FE0F VARIATION SELECTOR-16"),
        ("team\u00a02", "U+00A0 NO-BREAK SPACE"),
    ],
)
def test_look_alike_and_hidden_team_names_refused(engine, name, words):
    store.add_team(engine, "team1", time.time() + 60)
    with pytest.raises(ValidationError, match=re.escape(words)):
        store.add_team(engine, name, time.time() + 60)
    assert [t["name"] for t in store.all_teams(engine)] == ["team1"]


def test_team_names_of_one_language_and_distinct_looks_are_taken(engine):
    taken = ["team1", "team2", "Łódź", "东京 チーム", "नमस्ते टीम", "العربية 2", "café", "équipe 3"]
    for name in taken:
        store.add_team(engine, name, time.time() + 60)
    store.add_team(engine, "cafe\u0301s", time.time() + 60)  # stored as NFC ('cafés'), not like 'café'
    assert [t["name"] for t in store.all_teams(engine)] == [*taken, "cafés"]
    with pytest.raises(ValidationError, match="looks like the existing team 'café'"):
        store.add_team(engine, "CAFE\u0301", time.time() + 60)  # NFD and capitals: the same name


def test_add_team_command_refuses_a_look_alike(tmp_path, data, capsys):
    from challenge_fixtures import challenge_file

    from lorisnb.cli import main

    path = challenge_file(tmp_path, data)
    assert main(["challenge", "add-team", str(path), "team1"]) == 0
    capsys.readouterr()
    assert main(["challenge", "add-team", str(path), "tеam1"]) != 0
    err = capsys.readouterr().err
    assert "mixes Latin letters with letters of Cyrillic" in err and "write it in one script" in err
    assert main(["challenge", "add-team", str(path), "Team1"]) != 0
    assert "looks like the existing team 'team1'" in capsys.readouterr().err


def test_the_admin_token_outlives_the_close(tmp_path, data, capsys):
    """The admin's token expired at the challenge's close, when the final results appear on the
    admin page: by default it now works 90 days after; a team's still stops at the close, and
    --expires sets either."""
    from challenge_fixtures import challenge_file

    from lorisnb.cli import main
    from lorisnb.tools.challenge.config import read_challenge

    path = challenge_file(tmp_path, data)
    closes = read_challenge(path).closes
    assert main(["challenge", "add-team", str(path), "organizers", "--admin"]) == 0
    assert main(["challenge", "add-team", str(path), "team1"]) == 0
    assert main(["challenge", "add-team", str(path), "team2", "--expires", "2099-01-01T00:00:00Z"]) == 0
    assert "valid until" in capsys.readouterr().err
    engine = store.connect(read_challenge(path).database)
    expires = {t["name"]: t["expires"] for t in store.all_teams(engine)}
    assert expires["organizers"] == pytest.approx(closes + 90 * 86400)
    assert expires["team1"] == pytest.approx(closes)
    assert expires["team2"] > closes + 365 * 86400


@pytest.mark.parametrize(
    ("name", "others", "words"),
    [
        ("\u0251lpha", ["alpha"], "looks like the existing team 'alpha'"),  # U+0251 LATIN SMALL LETTER ALPHA
        ("\u0299\u1d07\u1d1b\u1d00", ["beta"], "looks like the existing team 'beta'"),  # small capitals
        ("team\u01c3", [], "U+01C3 LATIN LETTER RETROFLEX CLICK"),  # drawn like '!'
    ],
)
def test_latin_look_alikes_refused(name, others, words):
    """Latin letters drawn like other Latin letters or like punctuation passed: 'ɑlpha' beside 'alpha'."""
    with pytest.raises(ValidationError, match=re.escape(words)):
        store.check_team_name(name, others)


def _serve_on(path, port: int) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "lorisnb.cli", "serve", str(path), "--port", str(port)],
                          capture_output=True, text=True, timeout=120)  # fmt: skip


def _queue(engine) -> dict[str, tuple[str, str | None, int]]:
    return {s["id"]: (s["status"], s["claim"], s["attempts"]) for s in store.all_submissions(engine)}


def _queued_challenge(tmp_path, data, submissions):
    """A challenge file over the real ground truth, its folder and database, and one team's
    ``submissions`` queued in phase development: the file's path, the challenge, the engine."""
    pytest.importorskip("fastapi")
    from challenge_fixtures import challenge_file

    from lorisnb.tools.challenge.config import read_challenge

    path = challenge_file(tmp_path, data)
    challenge = read_challenge(path)
    challenge.folder.mkdir(parents=True)
    engine = store.connect(challenge.database)
    tid = store.team_of(engine, store.add_team(engine, "t", time.time() + 600))["id"]
    for sid in submissions:
        store.add_submission(engine, sid, tid, "development", ["a.txt"], 1)
    return path, challenge, engine


def test_a_second_server_on_a_busy_port_touches_no_queue(tmp_path, data):
    """``lorisnb serve`` started again beside a running server, on its port: uvicorn starts the
    application (and its scorer) before it binds, fails to bind and stops. The scorer put the
    running server's submission back in the queue, claimed it and left it ``scoring`` under a claim
    no process held (forever, until a restart); now it waits for the queue's lock, which the
    running server holds, and touches nothing."""
    import fcntl
    import os
    import socket

    from lorisnb.tools.challenge.scoring import LOCK

    path, challenge, engine = _queued_challenge(tmp_path, data, ("s1", "s2"))
    store.claim_next(engine)  # the running server scores s1; s2 waits
    before = _queue(engine)
    fd = os.open(challenge.folder / LOCK, os.O_RDWR | os.O_CREAT)  # the running server's scorer
    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    try:
        with socket.socket() as busy:  # the running server's port
            busy.bind(("127.0.0.1", 0))
            busy.listen()
            done = _serve_on(path, busy.getsockname()[1])
        assert done.returncode != 0 and "address already in use" in done.stderr + done.stdout
        assert _queue(engine) == before
    finally:
        os.close(fd)


def test_a_failed_start_releases_what_it_claimed(tmp_path, data):
    """No other server holds the queue, but the port is another program's: what the failed start
    claimed goes back to the queue when it stops (its claims released), none is left ``scoring``."""
    import socket

    path, _, engine = _queued_challenge(tmp_path, data, ("s1", "s2"))
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        done = _serve_on(path, busy.getsockname()[1])
    assert done.returncode != 0
    assert {sid: q[:2] for sid, q in _queue(engine).items()} == {"s1": ("queued", None), "s2": ("queued", None)}


def test_two_challenge_folders_on_one_database_have_one_scorer(tmp_path, data):
    """Two challenge files of other folders naming one SQLite database: the second server's scorer
    claimed the first's submissions (whose files are in the first's folder) and failed them, each
    a team's daily submission spent; now the database's lock (beside its file) holds the queue for
    the first, and the second touches nothing until that one stops."""
    from dataclasses import replace

    from sqlalchemy.engine import make_url

    from lorisnb.tools.challenge.scoring import Scorer

    _, a, engine = _queued_challenge(tmp_path, data, ("s1",))
    b = replace(a, folder=tmp_path / "other-folder")
    b.folder.mkdir(parents=True)
    store.claim_next(engine)  # a killed server's half-scored submission
    first, second = Scorer(a, engine), Scorer(b, engine)
    try:
        assert Path(f"{make_url(a.database).database}.scorer.lock") in first.lock_paths()
        assert first._take_queue() and first.requeued == 1
        store.claim_next(engine)  # the first scores it
        before = _queue(engine)
        assert not second._take_queue()  # its own folder's lock is free; the database's is not
        assert _queue(engine) == before
        first.stop()
        assert second._take_queue()  # scored there once the first stops
    finally:
        first.stop()
        second.stop()
