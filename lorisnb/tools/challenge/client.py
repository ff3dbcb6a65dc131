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
    message."""
    httpx = require("httpx", "serve")
    base = url.rstrip("/")
    if not base.startswith(("http://", "https://")):
        raise ValidationError(f"URL {url!r}: expected the server's address, http://HOST:PORT")
    parts = _parts(paths)
    try:
        with httpx.Client(base_url=base, timeout=60.0) as client:
            r = client.post("/api/submissions", files=parts, data={"format": fmt} if fmt else None,
                            headers={"Authorization": f"Bearer {token}"})  # fmt: skip
            if r.status_code != 201:
                raise LorisError(f"{base} refused the submission ({r.status_code}): {_message(r)}")
            sid = r.json()["id"]
            view = client.get(f"/api/submissions/{sid}").json()
            end = time.monotonic() + (wait or 0)
            while wait is not None and view["status"] in ("queued", "scoring") and time.monotonic() < end:
                time.sleep(poll)
                view = client.get(f"/api/submissions/{sid}").json()
    except httpx.HTTPError as exc:
        raise LorisError(f"{base}: cannot reach the server ({exc})") from None
    view["url"] = f"{base}/submissions/{sid}"
    return view


def _message(r: Any) -> str:
    try:
        return str(r.json().get("error") or r.json().get("detail"))
    except ValueError:
        return r.text[:300]
