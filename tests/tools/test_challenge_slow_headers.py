"""Clients that never finish their request headers (slowloris) are dropped after the challenge's
``header_seconds``: they held every connection slot of ``lorisnb serve`` and every other client
was answered 503 for as long as they stayed (100 s and more)."""

from __future__ import annotations

import socket
import threading
import time

import pytest
from challenge_fixtures import challenge_file

pytest.importorskip("fastapi")
import httpx  # noqa: E402
import uvicorn  # noqa: E402

from lorisnb.tools.challenge.app import create_app, http_protocol  # noqa: E402
from lorisnb.tools.challenge.config import read_challenge  # noqa: E402


def test_clients_that_never_finish_their_headers_are_dropped(tmp_path, data):
    challenge = read_challenge(challenge_file(tmp_path, data, limits="header_seconds = 1"))
    assert challenge.limits["header_seconds"] == 1
    app = create_app(challenge, score=False)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    config = uvicorn.Config(app, host="127.0.0.1", port=port, log_level="error", limit_concurrency=8,
                            http=http_protocol(challenge.limits["header_seconds"]))  # fmt: skip
    server = uvicorn.Server(config)
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    slow: list[socket.socket] = []
    try:
        for _ in range(100):
            if server.started:
                break
            time.sleep(0.05)
        assert server.started
        for _ in range(10):  # more than the connection limit, none finishing its headers
            c = socket.create_connection(("127.0.0.1", port), timeout=5)
            c.sendall(b"GET / HTTP/1.1\r\nHost: x\r\n")
            slow.append(c)
        idle = socket.create_connection(("127.0.0.1", port), timeout=5)  # nothing sent at all
        slow.append(idle)
        time.sleep(0.3)
        with httpx.Client(timeout=5) as client:  # held: every slot taken
            assert client.get(f"http://127.0.0.1:{port}/api/health").status_code == 503
        t0 = time.monotonic()
        replies = []
        for c in slow:
            got = b""
            while chunk := c.recv(4096):  # the server closes it
                got += chunk
            replies.append(got)
        took = time.monotonic() - t0
        assert took < 4
        assert all(r.startswith(b"HTTP/1.1 408") and b"headers took longer than 1 s" in r for r in replies[:-1])
        assert replies[-1] == b""  # sent nothing: closed without a word
        with httpx.Client(timeout=5) as client:
            assert client.get(f"http://127.0.0.1:{port}/api/health").status_code == 200
            # a kept-alive client is served, and a request in the application is not cut at the deadline
            for _ in range(2):
                assert client.get(f"http://127.0.0.1:{port}/api/health").status_code == 200
                time.sleep(0.6)
    finally:
        for c in slow:
            c.close()
        server.should_exit = True
        thread.join(10)
    assert not thread.is_alive()
