"""``lorisnb submit``'s exit statuses and printed rows (s72): a temporary refusal (429, with its
Retry-After) and an unreachable server exited 2, as a refused upload does, so a script could not
tell "send it again later" from "fix it"; a sequence of CR 0 printed ``C-ATE RMSE nan m``, and a
C-ATE of exactly 0 printed as nan too."""

from __future__ import annotations

import socket
import time

import pytest
from challenge_fixtures import cafe_files, challenge_file

pytest.importorskip("fastapi")
import httpx  # noqa: E402
from fastapi.testclient import TestClient  # noqa: E402

from lorisnb.cli import main  # noqa: E402
from lorisnb.cli.challenge import TEMPFAIL  # noqa: E402
from lorisnb.tools.challenge import client as submit_client  # noqa: E402
from lorisnb.tools.challenge import store  # noqa: E402
from lorisnb.tools.challenge.app import create_app  # noqa: E402
from lorisnb.tools.challenge.config import read_challenge  # noqa: E402


@pytest.fixture()
def in_process(tmp_path, data, monkeypatch):
    """A challenge server of one submission a day (not scoring), answering ``lorisnb submit``'s
    httpx.Client in this process; its team's token."""
    challenge = read_challenge(challenge_file(tmp_path, data, limits="submissions_per_day = 1"))
    app = create_app(challenge, score=False)
    token = store.add_team(app.state.server.engine, "team", time.time() + 7000)

    class InProcess:
        def __init__(self, base_url: str, timeout: float):
            self.client = TestClient(app, base_url=base_url)

        def __enter__(self):
            return self.client

        def __exit__(self, *exc):
            return False

    monkeypatch.setattr(httpx, "Client", InProcess)
    return token


def test_rate_limited_exits_tempfail_saying_when(in_process, data, capsys):
    good = str(cafe_files(data, "ds-slam")[0])
    assert main(["submit", "http://127.0.0.1:9", good, "--token", in_process]) == 0
    capsys.readouterr()
    assert main(["submit", "http://127.0.0.1:9", good, "--token", in_process]) == TEMPFAIL == 75
    err = capsys.readouterr().err
    assert "(429)" in err and "nothing was submitted" in err, err
    wait = int(err.split("retry after ")[1].split(" s")[0])
    assert 0 < wait <= 86400, err


def test_a_refused_upload_still_exits_2(in_process, tmp_path, capsys):
    bag = tmp_path / "run.bag"
    bag.write_bytes(b"#ROSBAG V2.0\n")
    assert main(["submit", "http://127.0.0.1:9", str(bag), "--token", in_process]) == 2
    assert "(415)" in capsys.readouterr().err


def test_an_unreachable_server_exits_tempfail(data, capsys):
    """A port of this machine (loopback) nothing listens on: refused at once."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    good = str(cafe_files(data, "ds-slam")[0])
    t0 = time.monotonic()
    assert main(["submit", f"http://127.0.0.1:{port}", good, "--token", "t"]) == TEMPFAIL
    assert time.monotonic() - t0 < 30
    err = capsys.readouterr().err
    assert "cannot reach the server" in err and "retry later" in err and "nothing was submitted" in err, err


def test_a_submission_taken_but_not_followed_exits_1_naming_its_page(in_process, data, monkeypatch, capsys):
    """Taken (201), then the server gone while following it: sending it again would count twice,
    so not the status of 'send it again'."""
    real = TestClient.get

    def gone(self, url, *a, **kw):
        if "/api/submissions/" in str(url):
            raise httpx.ConnectError("connection refused")
        return real(self, url, *a, **kw)

    monkeypatch.setattr(TestClient, "get", gone)
    good = str(cafe_files(data, "ds-slam")[0])
    assert main(["submit", "http://127.0.0.1:9", good, "--token", in_process, "--wait", "5"]) == 1
    err = capsys.readouterr().err
    assert "was taken" in err and "http://127.0.0.1:9/submissions/" in err and "do not send it again" in err, err


def test_c_ate_is_printed_as_a_number_or_as_no_correct_pose(monkeypatch, capsys):
    """The scorer writes a missing C-ATE (CR 0: no correct pose) as null; 0.0 is a value."""
    rows = [dict(scene="cafe", seq=1, cr=0.0, c_ate_rmse=None, file="a.txt"),
            dict(scene="cafe", seq=2, cr=1.0, c_ate_rmse=0.0, file="b.txt")]  # fmt: skip
    view = dict(id="x", status="scored", url="http://127.0.0.1:1/submissions/x", rows=rows, failures=[], missing=[])
    monkeypatch.setattr(submit_client, "submit", lambda *a, **kw: dict(view))
    assert main(["submit", "http://127.0.0.1:1", "x.txt", "--token", "t"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out == [
        "cafe 1: CR 0.000, C-ATE RMSE no correct pose (a.txt)",
        "cafe 2: CR 1.000, C-ATE RMSE 0.000 m (b.txt)",
    ]
