"""The challenge commands: ``serve``, ``challenge add-team``, ``challenge export`` and ``submit``
(see :mod:`lorisnb.tools.challenge`)."""

from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import sys
import time
from typing import Any

from lorisnb.cli.text import say
from lorisnb.core.spec import validate
from lorisnb.errors import ValidationError
from lorisnb.tools._extras import require

TOKEN_VAR = "LORISNB_TOKEN"
#: An admin token's default life after the challenge closes (seconds): 90 days.
ADMIN_AFTER_CLOSE = 90 * 86400.0


def port(text: str) -> int:
    value = int(validate.positive("--port", text, "port number", integer=True))
    if value > 65535:
        raise ValidationError(f"--port {text}: expected a port number from 1 to 65535")
    return value


def expiry(text: str) -> float:
    """An ISO date and time with its offset (``2026-12-01T18:00:00+00:00``, ``...Z``), epoch seconds."""
    try:
        when = dt.datetime.fromisoformat(text.strip())
    except ValueError:
        raise ValidationError(f"--expires {text!r}: expected a date and time, e.g. 2026-12-01T18:00:00Z") from None
    if when.tzinfo is None:
        raise ValidationError(f"--expires {text!r}: no offset; expected one, e.g. 2026-12-01T18:00:00Z")
    return when.timestamp()


def _engine(challenge: Any) -> Any:
    from lorisnb.tools.challenge import store

    challenge.folder.mkdir(parents=True, exist_ok=True)
    return store.connect(challenge.database)


def cmd_serve(args: argparse.Namespace) -> int:
    for module in ("fastapi", "uvicorn", "sqlalchemy", "multipart", "jinja2"):
        require(module, "serve")
    import uvicorn

    from lorisnb.tools.challenge.app import create_app, http_protocol
    from lorisnb.tools.challenge.config import read_challenge

    challenge = read_challenge(args.challenge)
    if challenge.scheduler is not None:  # an unreachable cluster: one line now, not a failed start-up
        from lorisnb.tools.evaluation.pool import probe_scheduler

        require("distributed", "dask")
        probe_scheduler(challenge.scheduler, 10.0)
    app = create_app(challenge)
    phases = "; ".join(p.name for p in challenge.phases)
    print(f"lorisnb serve: {challenge.title!r} on http://{args.host}:{args.port}/ (phases: {phases}); database "
          f"{challenge.database.split('@')[-1]}; uploads in {challenge.folder / 'uploads'}", file=sys.stderr)  # fmt: skip
    if challenge.public_groundtruth:  # the bundled class challenge: said on start and on the leaderboard
        say(f"lorisnb serve: note: {challenge.public_groundtruth}. For a graded challenge, set [challenge] "
            "groundtruth to a data root kept on this server only (docs/guide/challenge-server.md, 'Ground truth "
            "the teams cannot have')")  # fmt: skip
    uvicorn.run(app, host=args.host, port=args.port, log_level="warning", timeout_keep_alive=5,
                limit_concurrency=args.max_connections, http=http_protocol(challenge.limits["header_seconds"]))  # fmt: skip
    return 0


def cmd_add_team(args: argparse.Namespace) -> int:
    require("sqlalchemy", "serve")
    from lorisnb.tools.challenge import store
    from lorisnb.tools.challenge.config import read_challenge

    challenge = read_challenge(args.challenge)
    # a team's token works until the challenge closes; the admin's on after it (the final results
    # appear at the close, and the admin page is where the organizer reads them)
    default = challenge.closes + (ADMIN_AFTER_CLOSE if args.admin else 0.0)
    expires = args.expires if args.expires is not None else default
    if expires <= time.time():
        raise ValidationError(f"--expires: {dt.datetime.fromtimestamp(expires, dt.UTC).isoformat()} is past; "
                              "expected a later time")  # fmt: skip
    token = store.add_team(_engine(challenge), args.name, expires, admin=args.admin)
    what = "admin" if args.admin else "team"
    until = dt.datetime.fromtimestamp(expires, dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    print(f"{what} {args.name!r} added, its token valid until {until} (--expires sets another time); the token "
          "(shown once, stored hashed only):", file=sys.stderr)  # fmt: skip
    print(token)
    return 0


def cmd_export(args: argparse.Namespace) -> int:
    require("sqlalchemy", "serve")
    import pandas as pd

    from lorisnb.cli.outputs import check_outputs
    from lorisnb.io.writers import write_csv
    from lorisnb.tools.challenge import store
    from lorisnb.tools.challenge.board import PUBLIC_COLUMNS
    from lorisnb.tools.challenge.config import read_challenge

    challenge = read_challenge(args.challenge)
    check_outputs(args, [args.challenge], ["csv"])
    rows = []
    for s in store.all_submissions(_engine(challenge)):
        base = dict(submission=s["id"], team=s["team"], phase=s["phase"], status=s["status"],
                    submitted=dt.datetime.fromtimestamp(s["created"], dt.UTC).isoformat(), error=s["error"] or "")  # fmt: skip
        result = json.loads(s["result"]) if s["result"] else {"rows": []}
        base["failures"] = "; ".join(f"{f['file']} ({f['status']}): {f['error']}" for f in result.get("failures", []))
        rows += [base | {k: r.get(k) for k in PUBLIC_COLUMNS} for r in result["rows"]] or [base]
    table = pd.DataFrame(rows, columns=["submission", "team", "phase", "status", "submitted", "error", "failures",
                                        *PUBLIC_COLUMNS])  # fmt: skip
    for column in ("seq", "poses", "matched"):  # counts stay whole numbers beside a submission without rows
        table[column] = table[column].astype("Int64")
    out = write_csv(table, args.csv, args.force)
    print(f"wrote {len(table)} rows ({table['submission'].nunique()} submissions) to {out}", file=sys.stderr)
    return 0


#: ``lorisnb submit``'s exit status when the submission was not taken for now and the same upload
#: may be sent again later (the server unreachable, too many submissions today, a busy server):
#: EX_TEMPFAIL of sysexits.h. 2 is a refused input (fix the upload), 1 a submission that failed.
TEMPFAIL = 75


def _c_ate(value: Any) -> str:
    """A row's C-ATE RMSE as ``lorisnb submit`` prints it: the number (0 too), or why it has none."""
    if value is None or (isinstance(value, float) and value != value):
        return "no correct pose"
    return f"{float(value):.3f} m"


def cmd_submit(args: argparse.Namespace) -> int:
    from lorisnb.tools.challenge.client import NotFollowed, TryAgain, submit

    token = args.token or os.environ.get(TOKEN_VAR)
    if not token:
        raise ValidationError(f"no token: give --token TOKEN or set {TOKEN_VAR} (your team's token)")
    try:
        view = submit(args.url, args.files, token, wait=args.wait, fmt=args.format)
    except TryAgain as exc:  # nothing submitted: the same command may be run again (later)
        say(f"error: {exc}")
        return TEMPFAIL
    except NotFollowed as exc:  # submitted: its page says how it scores
        say(f"error: {exc}")
        return 1
    print(f"submission {view['id']}: {view['status']} ({view['url']})", file=sys.stderr)
    for r in view.get("rows", []):
        cr = "no value" if r["cr"] is None else f"{r['cr']:.3f}"
        print(f"{r['scene']} {r['seq']}: CR {cr}, C-ATE RMSE {_c_ate(r['c_ate_rmse'])} ({r['file']})")
    for h in view.get("hidden_sequences", []):  # scored, shown once a phase closes: no value here
        say(f"{h['scene']} {h['seq']}: scored, {h['shown']} ({', '.join(h['files'])})")
    for m in view.get("missing", []):
        say(f"error: {m['scene']} {m['seq']}: {m['error']}")
    for f in view.get("failures", []):
        say(f"error: {f['file']}: {f['error']}")
    if view.get("error"):
        say(f"error: {view['error']}")
    if view.get("hidden"):  # scored, but its phase shows scores once it closes
        say(view["hidden"])
    if view["status"] in ("queued", "scoring"):
        return 0 if args.wait is None else 1
    return 0 if view["status"] == "scored" and not view.get("failures") and not view.get("missing") else 1
