"""A challenge server (``lorisnb serve CHALLENGE.toml``): teams upload result files (OpenLORIS,
or TUM and EuRoC named after their sequence), a worker process scores each upload with the
pipeline of ``lorisnb evaluate`` against ground truth the server keeps hidden, and a leaderboard
ranks the teams with the report's ranking (:mod:`lorisnb.tools.report.leaderboard`); a
sequence's scores leave the server only once a phase holding it shows them.

Modules: :mod:`.config` (the challenge file), :mod:`.store` (the database: teams, hashed tokens,
submissions and the persisted scoring queue; SQLAlchemy, SQLite in WAL mode by default),
:mod:`.uploads` (hostile-input checks, safe unpacking, each file's format and sequence),
:mod:`.scoring` (the worker process with time and memory limits), :mod:`.preload` (what the scoring
processes' fork server imports and warms once), :mod:`.board` (leaderboard and public views of a
submission: never a ground-truth pose, nor a sequence not yet shown), :mod:`.app` (the FastAPI
application: pages rendered on the server, no CDN, and a JSON API) and :mod:`.client`
(``lorisnb submit``).

May import: :mod:`lorisnb.tools.evaluation`, the leaderboard :mod:`lorisnb.tools.report.leaderboard`,
the figures of :mod:`lorisnb.tools.figures.plotting`, the optional-dependency check
:mod:`lorisnb.tools._extras`, :mod:`lorisnb.io`, :mod:`lorisnb.core` and :mod:`lorisnb.errors`; of other
packages FastAPI, Starlette, uvicorn, SQLAlchemy, Jinja2 and httpx (the ``serve`` extra), imported by
the modules that need them.
"""
