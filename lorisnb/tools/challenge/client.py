"""``lorisnb submit URL FILES``: send result files (files, a folder of them, or a ``.zip``; their
format recognised by the server, or given) to a challenge server's API and, with ``wait``, follow
the submission until it is scored."""

from __future__ import annotations

import io
import time
import zipfile
from pathlib import Path
from typing import Any

from lorisnb.errors import LorisError, ValidationError
from lorisnb.tools._extras import require

#: HTTP statuses of a server that may take the same upload later: too many submissions now (429,
#: its ``Retry-After``), busy or behind a proxy that could not reach it (502, 503, 504).
TEMPORARY = (429, 502, 503, 504)


class TryAgain(LorisError):
    """The submission was not taken for now, and the same upload may be sent again later: the server
    could not be reached or answered :data:`TEMPORARY` (``lorisnb submit`` exits 75, EX_TEMPFAIL).
    ``retry_after``: the seconds the server said to wait (its ``Retry-After``), else None."""

    def __init__(self, message: str, retry_after: int | None = None):
        super().__init__(message)
        self.retry_after = retry_after


class NotFollowed(LorisError):
    """The submission was taken (``sid``, its page ``url``), but following it until it is scored
    failed (the server could not be reached): sending it again would count a second submission."""

    def __init__(self, message: str, sid: str, url: str):
        super().__init__(message)
        self.sid, self.url = sid, url


def _retry_after(r: Any) -> int | None:
    """A response's ``Retry-After`` in seconds (a number of seconds; a date is not read), None if it gives none."""
    value = str(r.headers.get("retry-after", "")).strip()
    return int(value) if value.isdigit() else None


def _parts(paths: list[str]) -> list[tuple[str, tuple[str, bytes]]]:
    """The multipart ``files`` of ``paths``: a folder as one zip of the files below it, but for
    those under a hidden folder or hidden themselves (a name starting with ``.``)."""
    out: list[tuple[str, tuple[str, bytes]]] = []
    for given in paths:
        p = Path(given).expanduser()
        if p.is_dir():
            buf = io.BytesIO()
            # hidden files and folders left out (.git/, .ipynb_checkpoints/), as lorisnb's folder walks do
            files = sorted(f for f in p.rglob("*") if f.is_file()
                           and not any(part.startswith(".") for part in f.relative_to(p).parts))  # fmt: skip
            if not files:
                raise ValidationError(f"{given}: a folder without files; expected result files (.txt, .csv)")
            with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
                for f in files:
                    z.write(f, f.relative_to(p).as_posix())
            out.append(("files", (f"{p.resolve().name or 'results'}.zip", buf.getvalue())))
        elif p.is_file():
            out.append(("files", (p.name, p.read_bytes())))
        else:
            raise ValidationError(f"{given}: no such file or folder; expected result files, a folder or a .zip")
    return out


def submit(url: str, paths: list[str], token: str, wait: float | None = None, poll: float = 1.0,
           fmt: str | None = None) -> dict[str, Any]:  # fmt: skip
    """Upload ``paths`` to the server at ``url`` with the team's ``token`` (``fmt``: the files'
    format, default recognised by the server from each file); the submission as the API shows it,
    after it is scored if ``wait`` (seconds) is given. A refusal is a LorisError with the server's
    message; a refusal for now, or a server that cannot be reached, is a :class:`TryAgain` (the
    same upload may be sent later; after how long, where the server says); a submission taken but
    not followed to its score is a :class:`NotFollowed`."""
    httpx = require("httpx", "serve")
    base = url.rstrip("/")
    if not base.startswith(("http://", "https://")):
        raise ValidationError(f"URL {url!r}: expected the server's address, http://HOST:PORT")
    parts = _parts(paths)
    # the server not answering now (down, busy, a connection cut): the same upload may be sent later
    unreachable = (httpx.TimeoutException, httpx.NetworkError, httpx.RemoteProtocolError)
    sid = None
    try:
        with httpx.Client(base_url=base, timeout=60.0) as client:
            r = client.post("/api/submissions", files=parts, data={"format": fmt} if fmt else None,
                            headers={"Authorization": f"Bearer {token}"})  # fmt: skip
            if r.status_code in TEMPORARY:
                wait_s = _retry_after(r)
                when = f"retry after {wait_s} s" if wait_s is not None else "retry later"
                raise TryAgain(f"{base} did not take the submission now ({r.status_code}): {_message(r)}; {when} "
                               "(nothing was submitted)", wait_s)  # fmt: skip
            if r.status_code != 201:
                raise LorisError(f"{base} refused the submission ({r.status_code}): {_message(r)}")
            sid = r.json()["id"]
            view = client.get(f"/api/submissions/{sid}").json()
            end = time.monotonic() + (wait or 0)
            while wait is not None and view["status"] in ("queued", "scoring") and time.monotonic() < end:
                time.sleep(poll)
                view = client.get(f"/api/submissions/{sid}").json()
    except httpx.HTTPError as exc:
        if sid is not None:  # taken: sending it again would count twice
            page = f"{base}/submissions/{sid}"
            raise NotFollowed(f"submission {sid} was taken, but the server could not be reached to follow it "
                              f"({type(exc).__name__}: {exc}); see its page, {page} (do not send it again: that "
                              "would count a second submission)", sid, page) from None  # fmt: skip
        if isinstance(exc, unreachable):
            raise TryAgain(f"{base}: cannot reach the server ({type(exc).__name__}: {exc}); retry later (nothing "
                           "was submitted)") from None  # fmt: skip
        raise LorisError(f"{base}: cannot reach the server ({exc})") from None
    view["url"] = f"{base}/submissions/{sid}"
    return view


def _message(r: Any) -> str:
    try:
        return str(r.json().get("error") or r.json().get("detail"))
    except ValueError:
        return r.text[:300]
