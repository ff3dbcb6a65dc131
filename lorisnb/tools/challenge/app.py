"""The challenge server's FastAPI application: pages rendered on the server (Jinja2, no script,
no CDN: they open offline) and a JSON API for the same data.

Pages: ``/`` leaderboard of every phase, ``/submit`` upload form, ``/submissions/{id}`` a
submission (reloads itself while it waits), ``/team`` and ``/admin`` (token in a form).
API: ``GET /api/leaderboard``, ``POST /api/submissions`` (``Authorization: Bearer TOKEN``,
multipart ``files`` and an optional ``format``), ``GET /api/submissions/{id}``, ``GET /api/team``,
``GET /api/admin``, ``GET /api/health``. Scores leave the server only for the sequences visible
now (:mod:`.board`); the admin's page and API alone hold the others, saying so.

An upload is refused before it is read where its headers say so (size, token; the admin's token
does not submit), and while it is read where it grows past the limit, comes too slowly or ends
before its closing boundary (:class:`BodyLimit`); then checked, unpacked and planned
(:mod:`.uploads`), written to disk and committed to the database before the response.
"""

from __future__ import annotations

import asyncio
import json
import math
import re
import secrets
import shutil
import threading
import time
from collections.abc import Awaitable, Callable
from contextlib import asynccontextmanager
from typing import Any

from fastapi import FastAPI, Request
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse, RedirectResponse, Response
from jinja2 import Environment, PackageLoader, select_autoescape
from sqlalchemy import Engine
from starlette.concurrency import run_in_threadpool
from starlette.datastructures import UploadFile
from starlette.exceptions import HTTPException
from starlette.formparsers import MultiPartException

from lorisnb.io.datasets.paths import scene_durations
from lorisnb.tools.challenge import store
from lorisnb.tools.challenge.board import (
    admin_scores,
    failure_lines,
    failures_said,
    figure_file,
    leaderboard,
    submission_view,
    team_error,
    when,
)
from lorisnb.tools.challenge.config import Challenge, sequences_of
from lorisnb.tools.challenge.uploads import Limits, UploadRefused, keep_upload, upload_format

DAY = 24 * 3600.0
MULTIPART = "lorisnb.multipart"  # the scope's key: a multipart body's closing boundary, and whether it came
Clock = Callable[[], float]


def num(v: Any, digits: int = 3) -> str:
    return "" if v is None else f"{v:.{digits}f}" if isinstance(v, float) else str(v)


class BodyLimit:
    """ASGI middleware: a POST whose body is declared or grows over ``max_bytes``, or takes longer
    than ``seconds`` to arrive (a slow client holding the server), is refused (413, 408) with a
    message; the rest of the server keeps serving."""

    def __init__(self, app: Any, max_bytes: int, seconds: float):
        self.app = app
        self.max_bytes = max_bytes
        self.seconds = seconds

    async def __call__(self, scope: dict[str, Any], receive: Callable[[], Awaitable[dict[str, Any]]],
                       send: Callable[[dict[str, Any]], Awaitable[None]]) -> None:  # fmt: skip
        if scope["type"] != "http" or scope["method"] != "POST":
            await self.app(scope, receive, send)
            return
        declared = dict(scope["headers"]).get(b"content-length")
        if declared is not None:
            try:
                size = int(declared)
            except ValueError:
                await _refuse(send, 400, f"Content-Length {declared[:20]!r}: expected a number of bytes")
                return
            if size > self.max_bytes:
                await _refuse(send, 413, f"upload of {size / 1e6:.1f} MB: over the challenge's limit of "
                              f"{self.max_bytes / 1e6:g} MB")  # fmt: skip
                return
        loop = asyncio.get_running_loop()
        deadline = loop.time() + self.seconds
        received = 0
        # a multipart body cut off after a boundary parses as a shorter form: its closing boundary tells
        ctype = dict(scope["headers"]).get(b"content-type", b"")
        multi = ctype[:10].lower() == b"multipart/"
        found = re.search(rb'boundary="?([^";,\s]+)', ctype, re.IGNORECASE) if multi else None
        multipart = scope[MULTIPART] = dict(closing=b"--" + found.group(1) + b"--" if found else None, closed=False)
        tail = b""

        async def limited() -> dict[str, Any]:
            nonlocal received, tail
            try:
                message = await asyncio.wait_for(receive(), max(deadline - loop.time(), 0.001))
            except TimeoutError:
                raise UploadRefused(f"the upload took longer than the challenge's {self.seconds:g} s to arrive; "
                                    "send it again on a faster connection", 408) from None  # fmt: skip
            if message["type"] == "http.request":
                body = message.get("body", b"")
                received += len(body)
                if received > self.max_bytes:
                    raise UploadRefused(f"upload over the challenge's limit of {self.max_bytes / 1e6:g} MB", 413)
                closing = multipart["closing"]
                if closing is not None and not multipart["closed"]:
                    window = tail + body
                    multipart["closed"] = closing in window
                    tail = window[-(len(closing) - 1) :]
            return message

        await self.app(scope, limited, send)


async def _refuse(send: Callable[[dict[str, Any]], Awaitable[None]], status: int, message: str) -> None:
    body = json.dumps({"error": message}).encode()
    await send({"type": "http.response.start", "status": status,
                "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode()),
                            (b"connection", b"close")]})  # fmt: skip
    await send({"type": "http.response.body", "body": body})


def http_protocol(header_seconds: float) -> type[asyncio.Protocol]:
    """uvicorn's HTTP/1.1 protocol (h11; its ``http`` option takes the class) that drops a client
    whose request headers have not all come within ``header_seconds`` of its connection or of its
    last response: uvicorn waits for them forever, and a few hundred connections that never finish
    their headers (slowloris) held every slot (``--max-connections``), every other client answered
    503. A connection is dropped only while no request of it is in the application (an upload
    being read has its own deadline, ``upload_seconds``, :class:`BodyLimit`); one that sent part
    of a request is answered 408 first."""
    import h11
    from uvicorn.protocols.http.h11_impl import H11Protocol

    class HeaderDeadline(H11Protocol):
        _deadline: asyncio.TimerHandle | None = None

        def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
            super().connection_made(transport)
            self._arm()

        def on_response_complete(self) -> None:
            super().on_response_complete()
            self._arm()

        def connection_lost(self, exc: Exception | None) -> None:
            if self._deadline is not None:
                self._deadline.cancel()
                self._deadline = None
            super().connection_lost(exc)

        def _arm(self) -> None:
            if self._deadline is not None:
                self._deadline.cancel()
            self._deadline = None if self.transport.is_closing() else self.loop.call_later(header_seconds, self._due)

        def _due(self) -> None:
            self._deadline = None
            if self.transport.is_closing() or (self.cycle is not None and not self.cycle.response_complete):
                return  # a request in the application: its response re-arms the deadline
            if self.conn.their_state is h11.IDLE and self.conn.trailing_data[0]:
                body = f"the request's headers took longer than {header_seconds:g} s to arrive; send it again".encode()
                self.transport.write(b"HTTP/1.1 408 Request Timeout\r\ncontent-type: text/plain; charset=utf-8\r\n"
                                     b"connection: close\r\ncontent-length: " + str(len(body)).encode()
                                     + b"\r\n\r\n" + body)  # fmt: skip
            self.transport.close()

    return HeaderDeadline


class Refused(Exception):
    def __init__(self, status: int, message: str, headers: dict[str, str] | None = None):
        super().__init__(message)
        self.status = status
        self.message = message
        self.headers = headers or {}


class Server:
    """The application's state: the challenge, the database, the scorer and the page renderer."""

    def __init__(self, challenge: Challenge, engine: Engine, clock: Clock):
        self.challenge = challenge
        self.engine = engine
        self.clock = clock
        self.durations = scene_durations(challenge.scenes, challenge.data)
        self.jinja = Environment(loader=PackageLoader("lorisnb.tools.challenge", "templates"),
                                 autoescape=select_autoescape(["html"]))  # fmt: skip
        self.jinja.globals.update(when=when, num=num, challenge=challenge)
        self.team_locks: dict[int, asyncio.Lock] = {}
        self._board: tuple[Any, list[dict[str, Any]]] | None = None  # (its key, the boards)
        self._computing: tuple[Any, threading.Thread] | None = None
        self._board_lock = threading.Lock()

    def page(self, name: str, title: str, status: int = 200, **context: Any) -> HTMLResponse:
        html = self.jinja.get_template(name).render(title=title, **context)
        return HTMLResponse(html, status_code=status)

    def team(self, token: str | None, admin: bool = False) -> dict[str, Any]:
        if not token:
            whose = "the admin token" if admin else "your team's token"
            raise Refused(401, f"no token: send {whose} (the form's token field, or the header "
                          "'Authorization: Bearer TOKEN')")  # fmt: skip
        team = store.team_of(self.engine, token)
        if team is None:
            raise Refused(401, "unknown token; check it, or ask the organizers for your team's token")
        if team["expires"] <= self.clock():
            raise Refused(401, f"the token of {team['name']!r} expired at {when(team['expires'])}; ask the "
                          "organizers for a new one")  # fmt: skip
        if admin and not team["admin"]:
            raise Refused(403, f"{team['name']!r} is a team token; this page needs the admin token")
        return team

    def submitter(self, token: str | None) -> dict[str, Any]:
        """The team of a submission's token; the admin's is refused (it would be ranked as a team)."""
        team = self.team(token)
        if team["admin"]:
            raise Refused(403, f"{team['name']!r} is the admin token, which does not submit (it would be ranked "
                          f"as a team); to try the server, add a team for yourself: lorisnb challenge add-team "
                          f"{self.challenge.path.name} NAME, and submit with its token")  # fmt: skip
        return team

    def _compute(self, key: Any, now: float) -> None:
        subs = store.all_submissions(self.engine)  # with results (a scoring finished since: a newer key next time)
        boards = [leaderboard(self.challenge, p, subs, self.durations, now) for p in self.challenge.phases]
        with self._board_lock:
            self._board = (key, boards)
            self._computing = None

    def boards(self, wait: float = 0.5) -> list[dict[str, Any]]:
        """Every phase's leaderboard. A new one (a submission scored since) is computed in a thread
        of its own; a page waits for it up to ``wait`` seconds, then shows the one before, saying
        so (``updating``): the ranks' tests take seconds with many teams, and pages stay quick."""
        subs = store.all_submissions(self.engine, results=False)
        now = self.clock()
        key = tuple((p.name, p.shows_scores(now)) for p in self.challenge.phases) + tuple(
            (s["id"], s["status"]) for s in subs
        )
        with self._board_lock:
            if self._board is not None and self._board[0] == key:
                return self._board[1]
            if self._computing is None:  # one at a time: the next request starts the next one
                thread = threading.Thread(target=self._compute, args=(key, now), daemon=True)
                self._computing = (key, thread)
                thread.start()
            thread = self._computing[1]
        thread.join(wait if self._board is not None else None)
        with self._board_lock:
            assert self._board is not None
            boards = self._board[1]
            if self._board[0] != key:
                return [dict(b, updating=True) for b in boards]
            return boards

    def view(self, sid: str) -> dict[str, Any]:
        sub = store.submission(self.engine, sid)
        if sub is None:
            raise Refused(404, f"no submission {sid!r}")
        return submission_view(sub, self.challenge, self.durations, self.clock())

    async def accept(self, team: dict[str, Any], files: list[tuple[str, Any]], fmt: str = "auto") -> str:
        """Check the phase and the team's daily limit, unpack and plan the files (``fmt``: the
        upload's format, :func:`.uploads.plan`), and commit the submission; its id."""
        now = self.clock()
        phase = self.challenge.phase_at(now)
        if phase is None:
            raise Refused(403, f"no phase is open now; the challenge runs from {when(self.challenge.opens)} to "
                          f"{when(self.challenge.closes)}: " + "; ".join(f"{p.name} {when(p.opens)} to "
                          f"{when(p.closes)}" for p in self.challenge.phases))  # fmt: skip
        limits = self.challenge.limits
        lock = self.team_locks.setdefault(team["id"], asyncio.Lock())
        async with lock:  # two uploads of one team at once are counted one after the other
            made = store.submission_times_since(self.engine, team["id"], now - DAY)
            if len(made) >= limits["submissions_per_day"]:
                # the limit resets when the oldest submission counted over it leaves the 24 hours
                resets = made[len(made) - limits["submissions_per_day"]] + DAY
                wait = max(math.ceil(resets - now), 1)
                raise Refused(429, f"team {team['name']!r} made {len(made)} submissions in the last 24 hours, the "
                              f"challenge's limit of {limits['submissions_per_day']}; the next one is taken from "
                              f"{when(resets + 60)} (in {_duration(wait)})",
                              {"Retry-After": str(wait)})  # fmt: skip
            sid = secrets.token_hex(8)
            folder = self.challenge.folder / "uploads" / sid
            lim = Limits(limits["files"], limits["unpacked_mb"] * 1_000_000)
            # the sequences a file may name: those of the challenge's phases (one of no phase is never scored)
            seqs = [q for q in sequences_of(self.durations) if any(p.keeps(*q) for p in self.challenge.phases)]
            try:
                names = await run_in_threadpool(keep_upload, files, folder, lim, fmt, seqs, self.challenge.spec)
            except BaseException:  # refused, or the server failed: nothing of the upload is left
                shutil.rmtree(folder, ignore_errors=True)
                raise
            size = sum((folder / "files" / n).stat().st_size for n in names)
            await run_in_threadpool(store.add_submission, self.engine, sid, team["id"], phase.name, names, size)
        return sid


async def _form(request: Request) -> tuple[str | None, list[tuple[str, Any]], str, Any]:
    """The multipart form: its token field, its files, its format (:func:`.uploads.upload_format`)
    and the form (closed by the caller)."""
    limits = request.app.state.server.challenge.limits
    try:
        form = await request.form(max_files=limits["files"] + 1, max_fields=10, max_part_size=64 * 1024)
    except (MultiPartException, HTTPException) as exc:
        detail = getattr(exc, "detail", None) or getattr(exc, "message", None) or str(exc)
        raise Refused(400, f"a malformed upload ({detail}); expected multipart/form-data with files") from None
    multipart = request.scope.get(MULTIPART) or {}
    if multipart.get("closing") is not None and not multipart.get("closed"):
        await form.close()
        raise Refused(400, "a malformed upload (the body ends before its closing boundary: cut off on the way?); "
                      "expected multipart/form-data with files, ending with its closing boundary: send it again")  # fmt: skip
    token = form.get("token")
    files = [(_sent_name(f), f.file) for f in form.getlist("files") if isinstance(f, UploadFile)]
    if any(not isinstance(v, UploadFile) for v in form.getlist("files")):
        await form.close()
        raise Refused(400, "'files' holds text, not files; expected files sent as multipart/form-data")
    try:
        fmt = upload_format(form.get("format"))
    except UploadRefused:
        await form.close()
        raise
    return token if isinstance(token, str) else None, files, fmt, form


#: A part's ``filename="..."`` as sent (a quoted string: ``\\`` and ``\"`` escaped).
FILENAME = re.compile(r'(?:^|;)\s*filename\s*=\s*"((?:[^"\\]|\\.)*)"', re.IGNORECASE)


def _sent_name(f: UploadFile) -> str:
    """An uploaded file's name as its part sent it: the multipart parser keeps only the last part
    of a Windows path (``C:\\x\\..\\cafe-1-1.txt`` as ``cafe-1-1.txt``, for an old browser), which
    :func:`.uploads.safe_name` refuses as it refuses an archive member's: one rule for both."""
    name = f.filename or ""
    found = FILENAME.search(f.headers.get("content-disposition", ""))
    if found is None:
        return name
    raw = found.group(1).replace("\\\\", "\\").replace('\\"', '"')
    return raw if raw != name and raw.endswith(name) else name


def _duration(seconds: float) -> str:
    """A wait in words: hours and minutes, or minutes, or seconds."""
    if seconds >= 3600:
        return f"{int(seconds // 3600)} h {int(seconds % 3600 // 60)} min"
    return f"{math.ceil(seconds / 60)} min" if seconds >= 60 else f"{int(seconds)} s"


def _bearer(request: Request) -> str | None:
    value = request.headers.get("authorization", "")
    return value[7:].strip() if value.lower().startswith("bearer ") else None


def create_app(challenge: Challenge, engine: Engine | None = None, *, score: bool = True,
               clock: Clock = time.time) -> FastAPI:  # fmt: skip
    """The application of ``challenge``; ``score=False`` leaves the queue to another process
    (tests), ``clock`` gives the time (epoch seconds)."""
    challenge.folder.mkdir(parents=True, exist_ok=True)
    engine = engine if engine is not None else store.connect(challenge.database)
    server = Server(challenge, engine, clock)

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> Any:
        scorer = None
        if score:
            from lorisnb.tools.challenge.scoring import Scorer

            scorer = Scorer(challenge, engine)
            scorer.start()
        app.state.scorer = scorer
        yield
        if scorer is not None:
            scorer.stop()

    app = FastAPI(title=challenge.title, lifespan=lifespan, docs_url=None, redoc_url=None, openapi_url=None)
    app.state.server = server
    app.add_middleware(BodyLimit, max_bytes=challenge.limits["upload_mb"] * 1_000_000,
                       seconds=float(challenge.limits["upload_seconds"]))  # fmt: skip

    def api_error(status: int, message: str) -> JSONResponse:
        return JSONResponse({"error": message}, status_code=status)

    @app.exception_handler(Refused)
    async def _refused(request: Request, exc: Refused) -> Response:
        if request.url.path.startswith("/api/"):
            response: Response = api_error(exc.status, exc.message)
        else:
            response = server.page("token.html" if exc.status in (401, 403) and request.url.path in ("/team", "/admin")
                                   else "error.html", "Refused", exc.status, error=exc.message,
                                   action=request.url.path, label="Token")  # fmt: skip
        response.headers.update(exc.headers)
        return response

    @app.exception_handler(UploadRefused)
    async def _upload_refused(request: Request, exc: UploadRefused) -> Response:
        return await _refused(request, Refused(exc.status, str(exc)))

    @app.exception_handler(HTTPException)
    async def _http_error(request: Request, exc: HTTPException) -> Response:
        """The framework's own refusals (no such route, a method a route does not take, a form
        that does not parse) in the server's words: ``{"error": ...}`` on the API, a page otherwise."""
        where = f"{request.method} {request.url.path}"
        if exc.status_code == 404:
            message = (f"{where}: no such page; the pages are /, /submit, /team, /admin and /submissions/ID, "
                       "the API /api/leaderboard, /api/submissions, /api/team, /api/admin and /api/health")  # fmt: skip
        elif exc.status_code == 405:
            message = f"{where}: not allowed; expected {(exc.headers or {}).get('Allow', 'another method')}"
        else:
            message = f"{where}: {exc.detail}"
        response = await _refused(request, Refused(exc.status_code, message))
        response.headers.update(exc.headers or {})
        return response

    @app.get("/", response_class=HTMLResponse)
    async def board_page() -> HTMLResponse:
        return server.page("leaderboard.html", "Leaderboard", boards=await run_in_threadpool(server.boards))

    @app.get("/api/leaderboard")
    async def board_api() -> JSONResponse:
        boards = await run_in_threadpool(server.boards, 10.0)  # a script would rather wait than read an old one
        return JSONResponse({"challenge": challenge.title, "practice": challenge.public_groundtruth, "phases": boards})

    @app.get("/api/health")
    async def health() -> JSONResponse:
        return JSONResponse({"queue": store.queue_counts(engine), "now": server.clock()})

    def submit_page(status: int = 200, error: str | None = None) -> HTMLResponse:
        return server.page("submit.html", "Submit", status, phase=challenge.phase_at(server.clock()),
                           limits=challenge.limits, error=error)  # fmt: skip

    @app.get("/submit", response_class=HTMLResponse)
    async def submit_form() -> HTMLResponse:
        return submit_page()

    async def receive(request: Request, token: str | None) -> str:
        if token is not None:  # the API's header: refused before the body is read
            server.submitter(token)
        field, files, fmt, form = await _form(request)
        try:
            team = server.submitter(token if token is not None else field)
            return await server.accept(team, files, fmt)
        finally:
            await form.close()

    @app.post("/submit")
    async def submit(request: Request) -> Response:
        try:
            sid = await receive(request, None)
        except (Refused, UploadRefused) as exc:
            status, message = (exc.status, exc.message) if isinstance(exc, Refused) else (exc.status, str(exc))
            page = submit_page(status, message)
            page.headers.update(exc.headers if isinstance(exc, Refused) else {})
            return page
        return RedirectResponse(f"/submissions/{sid}", status_code=303)

    @app.post("/api/submissions")
    async def submit_api(request: Request) -> JSONResponse:
        sid = await receive(request, _bearer(request) or "")
        return JSONResponse({"id": sid, "status": "queued", "url": f"/submissions/{sid}",
                             "api": f"/api/submissions/{sid}"}, status_code=201)  # fmt: skip

    @app.get("/submissions/{sid}", response_class=HTMLResponse)
    async def submission_page(sid: str) -> HTMLResponse:
        s = await run_in_threadpool(server.view, sid)
        waiting = s["status"] in ("queued", "scoring")
        return server.page("submission.html", "Submission", s=s, refresh=2 if waiting else None)

    @app.get("/api/submissions/{sid}")
    async def submission_api(sid: str) -> JSONResponse:
        return JSONResponse(await run_in_threadpool(server.view, sid))

    @app.get("/submissions/{sid}/timeline.png")
    async def timeline(sid: str) -> Response:
        """The figure of the sequences visible now (:func:`.board.figure_file`), never kept by a browser."""
        s = await run_in_threadpool(server.view, sid)
        sub = store.submission(engine, sid) if s.get("figure") else None
        name = figure_file(json.loads(sub["result"]), challenge, server.durations, server.clock()) if sub else None
        figure = challenge.folder / "uploads" / s["id"] / name if name else None
        if figure is None or not figure.is_file():
            raise Refused(404, "no timeline figure for this submission (not scored, or its phase shows scores "
                          "once it closes)")  # fmt: skip
        return FileResponse(figure, media_type="image/png", headers={"Cache-Control": "no-store"})

    def listing(subs: list[dict[str, Any]]) -> list[dict[str, Any]]:
        keep = ("id", "team", "phase", "created", "status", "error", "finished", "bytes")
        return [{k: s[k] for k in keep} | {"files_list": json.loads(s["files"])} for s in reversed(subs)]

    @app.get("/team", response_class=HTMLResponse)
    async def team_form() -> HTMLResponse:
        return server.page("token.html", "Team", action="/team", label="Team token")

    def team_data(team: dict[str, Any]) -> dict[str, Any]:
        left = challenge.limits["submissions_per_day"] - store.submissions_since(
            engine, team["id"], server.clock() - DAY
        )
        now = server.clock()
        subs = []
        for s in store.all_submissions(engine, team["id"]):
            result = json.loads(s["result"]) if s["result"] else {}
            # a scored submission's failures listed (a failed one's error says each file's reason)
            said = failures_said(s, result, challenge, server.durations, now) if s["status"] == "scored" else []
            subs += [t | {"error": team_error(s, challenge, now, server.durations), "failures": failure_lines(said)}
                     for t in listing([s])]  # fmt: skip
        return dict(team={k: team[k] for k in ("name", "expires", "admin")}, left=max(left, 0), subs=subs)

    @app.post("/team", response_class=HTMLResponse)
    async def team_page(request: Request) -> HTMLResponse:
        form = await request.form(max_files=0, max_fields=5)
        token = form.get("token")
        team = server.team(token if isinstance(token, str) else None)
        return server.page("team.html", "Team", **team_data(team))

    @app.get("/api/team")
    async def team_api(request: Request) -> JSONResponse:
        data = team_data(server.team(_bearer(request)))
        return JSONResponse(data | {"submissions": data.pop("subs")})

    @app.get("/admin", response_class=HTMLResponse)
    async def admin_form() -> HTMLResponse:
        return server.page("token.html", "Admin", action="/admin", label="Admin token")

    def admin_data() -> dict[str, Any]:
        """The queue, the teams and every submission, with each one's scores of every sequence and
        whether teams see them now (the admin's view alone holds the hidden ones)."""
        subs = store.all_submissions(engine)
        now = server.clock()
        scores = {s["id"]: admin_scores(s, challenge, now) for s in subs}
        failed = {s["id"]: failure_lines(json.loads(s["result"])["failures"]) if s["status"] == "scored" else []
                  for s in subs}  # fmt: skip
        return dict(queue=store.queue_counts(engine), teams=store.all_teams(engine),
                    subs=[s | {"scores": scores[s["id"]], "failures": failed[s["id"]]} for s in listing(subs)],
                    note="scores with shown false are hidden from teams until a phase holding their sequence "
                    "closes: only the admin's view holds them")  # fmt: skip

    @app.post("/admin", response_class=HTMLResponse)
    async def admin_page(request: Request) -> HTMLResponse:
        form = await request.form(max_files=0, max_fields=5)
        token = form.get("token")
        server.team(token if isinstance(token, str) else None, admin=True)
        return server.page("admin.html", "Admin", admin=True, **admin_data())

    @app.get("/api/admin")
    async def admin_api(request: Request) -> JSONResponse:
        server.team(_bearer(request), admin=True)
        data = admin_data()
        return JSONResponse(data | {"submissions": data.pop("subs")})

    return app
