"""Uploads refused as the scorer would refuse them, and the messages of the upload's refusals
(sixth-seventh pass): a file the reader refuses (``seq: one``, a malformed line, a zero-norm
quaternion) was accepted, scored as nothing and ranked CR 0; values too large to compute with gave
numpy's warnings as notes; a Windows path sent as a form's file name was taken while an archive's
was refused; two archives' members of one name were both said of the second archive; a name with
an accent was advised a rename to one naming no sequence; a sequence in no phase was listed as
expected; the admin's API asked for a team's token; the daily limit said "later" without when."""

from __future__ import annotations

import io
import json
import time
from pathlib import Path
from types import SimpleNamespace

import pytest
from challenge_fixtures import cafe_files, challenge_file, zipped

pytest.importorskip("fastapi")
from fastapi.testclient import TestClient  # noqa: E402

from lorisnb.errors import ValidationError  # noqa: E402
from lorisnb.tools.challenge import store  # noqa: E402
from lorisnb.tools.challenge.app import create_app  # noqa: E402
from lorisnb.tools.challenge.config import read_challenge  # noqa: E402
from lorisnb.tools.challenge.scoring import _one_file_each  # noqa: E402
from lorisnb.tools.challenge.uploads import Limits, UploadRefused, keep_upload, safe_name  # noqa: E402

LIMITS = "submissions_per_day = 2"


def one_phase(tmp_path: Path, data, sequences: str = "{ cafe = [1, 2] }") -> Path:
    """A challenge of one live phase on ``sequences`` of cafe, open now."""
    now = time.time()

    def iso(t: float) -> str:
        return time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(t))

    path = tmp_path / "one.toml"
    path.write_text(f"""[challenge]
title = "One phase"
groundtruth = "{data.root}"
folder = "{tmp_path / "server"}"
opens = {iso(now - 3600)}
closes = {iso(now + 3600)}

[[phase]]
name = "dev"
scenes = ["cafe"]
sequences = {sequences}
""")
    return path


@pytest.fixture()
def server(tmp_path, data):
    challenge = read_challenge(challenge_file(tmp_path, data, limits=LIMITS))
    app = create_app(challenge, score=False)
    engine = app.state.server.engine
    token = store.add_team(engine, "team", time.time() + 7000)
    with TestClient(app) as client:
        yield SimpleNamespace(client=client, token=token, engine=engine, challenge=challenge)


def post(s, files, **kw):
    return s.client.post("/api/submissions", files=files, headers={"Authorization": f"Bearer {s.token}"}, **kw)


def nothing_kept(s) -> None:
    uploads = s.challenge.folder / "uploads"
    assert not uploads.exists() or list(uploads.iterdir()) == []
    assert store.all_submissions(s.engine) == []


def _at(text: str, k: int, line: str) -> str:
    """``text`` with ``line`` as its line ``k + 1``."""
    lines = text.split("\n")
    return "\n".join(lines[:k] + [line] + lines[k:])


def _good(data) -> str:
    return cafe_files(data, "ds-slam")[0].read_text()


@pytest.mark.parametrize(
    "change, words",
    [
        (lambda t: t.replace("seq: 1", "seq: one", 1), ["x.txt", "line", "seq"]),
        (lambda t: _at(t, 12, "1560004887.0 <script>alert(1)</script> 0 0 0 0 0 1"), ["x.txt", "line 13"]),
        (lambda t: _at(t, 12, "1560004886.5 0 0 0 0 0 0 0"), ["x.txt", "line 13", "quaternion"]),
    ],
    ids=["seq-one", "malformed-line", "zero-quaternion"],
)
def test_a_file_the_reader_refuses_is_refused_at_upload(server, data, change, words):
    """Each was accepted (201) and its submission 'scored' with no error, its team ranked CR 0."""
    r = post(server, [("files", ("x.txt", change(_good(data)).encode()))])
    assert r.status_code == 400, r.text
    error = r.json()["error"]
    for w in words:
        assert w in error, error
    assert "/" not in error.split("x.txt")[0], error  # no server path before the file's name
    nothing_kept(server)


def test_values_too_large_are_refused_at_upload(server):
    """1e308 coordinates: numpy's 'overflow encountered in reduce' was shown to the team as notes."""
    body = "".join(f"{1560004885 + i} 1e308 1e308 1e308 0 0 0 1\n" for i in range(30)).encode()
    r = post(server, [("files", ("cafe-1-1.txt", body))])
    assert r.status_code == 400, r.text
    error = r.json()["error"]
    assert error.startswith("cafe-1-1.txt: the pose at stamp 1.56e+09") and "1e+308 m, over 1e+12 m" in error, error
    assert "overflow" not in error
    nothing_kept(server)


def test_a_windows_path_in_a_form_is_refused_as_in_an_archive(server, data):
    """``C:\\x\\..\\cafe-1-1.txt`` as a form's file name was kept as cafe-1-1.txt (the multipart parser
    keeps its last part), while an archive's member of that name was refused: one rule, one message."""
    good = _good(data).encode()
    path = "C:\\x\\..\\cafe-1-1.txt"
    member = post(server, [("files", ("u.zip", zipped({path: good})))])
    assert member.status_code == 400 and "a Windows path" in member.json()["error"], member.text
    said = member.json()["error"].split(": ", 1)[1]
    # as httpx sends it (backslashes escaped) and as a browser does (as typed)
    form = post(server, [("files", (path, good))])
    boundary = "b0undary"
    raw = (f'--{boundary}\r\nContent-Disposition: form-data; name="files"; filename="{path}"\r\n\r\n').encode()
    raw += good + f"\r\n--{boundary}--\r\n".encode()
    browser = server.client.post("/api/submissions", content=raw, headers={
        "Authorization": f"Bearer {server.token}", "Content-Type": f"multipart/form-data; boundary={boundary}"})  # fmt: skip
    for r in (form, browser):
        assert r.status_code == 400, r.text
        assert r.json()["error"] == f"upload: {said}", r.json()
    nothing_kept(server)


def test_two_archives_members_of_one_name_are_each_named_with_its_archive(server, data):
    z = zipped({"cafe-1-1.txt": _good(data).encode()})
    r = post(server, [("files", ("a.zip", z)), ("files", ("b.zip", z))])
    assert r.status_code == 400
    assert r.json()["error"].startswith("a.zip: 'cafe-1-1.txt' and b.zip: 'cafe-1-1.txt': a second file named"), (
        r.json()
    )
    plain = post(server, [("files", ("cafe-1-1.txt", _good(data).encode())), ("files", ("b.zip", z))])
    assert plain.json()["error"].startswith("upload: 'cafe-1-1.txt' and b.zip: 'cafe-1-1.txt'"), plain.json()
    nothing_kept(server)


def test_two_archives_of_distinct_files_are_taken(server, data):
    """Several archives, or archives and plain files, in one upload: taken (documented)."""
    one, two = cafe_files(data, "ds-slam")
    r = post(server, [("files", ("a.zip", zipped({one.name: one.read_bytes()}))),
                      ("files", ("b.zip", zipped({two.name: two.read_bytes()})))])  # fmt: skip
    assert r.status_code == 201, r.text
    assert json.loads(store.submission(server.engine, r.json()["id"])["files"]) == ["cafe-1-1.txt", "cafe-1-2.txt"]


def test_an_accented_name_is_advised_its_name_without_accents(server, data):
    """'café-1-1.txt' was advised 'caf_-1-1.txt', which names no sequence."""
    with pytest.raises(UploadRefused, match=r"rename it 'cafe-1-1.txt'"):
        safe_name("café-1-1.txt", "upload")
    with pytest.raises(UploadRefused, match=r"rename it 'home-1-2.txt'"):
        safe_name("hömé-1-2.txt", "upload")
    with pytest.raises(UploadRefused, match=r"rename it 'a_b.txt'"):  # no ASCII letter to take: '_'
        safe_name("a日b.txt", "upload")
    r = post(server, [("files", ("café-1-1.txt", _good(data).encode()))])
    assert r.status_code == 400 and "rename it 'cafe-1-1.txt'" in r.json()["error"], r.text


def test_the_expected_sequences_are_the_phases(tmp_path, data):
    """A TUM file naming no sequence of the challenge was told the ground truth's every sequence of
    its scenes, also those of no phase (cafe-1-2 here, never scored): now the phases' alone."""
    challenge = read_challenge(one_phase(tmp_path, data, "{ cafe = [1] }"))
    app = create_app(challenge, score=False)
    token = store.add_team(app.state.server.engine, "team", time.time() + 7000)
    tum = b"".join(b"%d 0 0 0 0 0 0 1\n" % (1560004885 + k) for k in range(20))
    with TestClient(app) as client:
        for name in ("office-1-1.txt", "cafe-1-2.txt"):
            r = client.post("/api/submissions", files=[("files", (name, tum))],
                            headers={"Authorization": f"Bearer {token}"})  # fmt: skip
            assert r.status_code == 400, r.text
            assert r.json()["error"].endswith("expected one of cafe-1-1"), r.json()


def test_the_admin_api_asks_for_the_admin_token(server):
    r = server.client.get("/api/admin")
    assert r.status_code == 401 and r.json()["error"].startswith("no token: send the admin token"), r.json()
    team = server.client.get("/api/team")
    assert team.json()["error"].startswith("no token: send your team's token"), team.json()


def test_the_daily_limit_says_when_it_resets(server, data):
    files = [("files", (p.name, p.read_bytes())) for p in cafe_files(data, "ds-slam")]
    for _ in range(2):
        assert post(server, files).status_code == 201
    first = store.all_submissions(server.engine)[0]["created"]
    r = post(server, files)
    assert r.status_code == 429
    wait = int(r.headers["Retry-After"])
    assert abs(wait - (first + 86400 - time.time())) < 60, (wait, first)
    assert "try again later" not in r.json()["error"] and "the next one is taken from 20" in r.json()["error"], r.json()
    assert "(in 23 h 59 min)" in r.json()["error"] or "(in 24 h 0 min)" in r.json()["error"], r.json()
    page = server.client.post("/submit", files=files, data={"token": server.token})
    assert page.status_code == 429 and page.headers["Retry-After"]


def _file(name: str, trial: int, seq: int = 2) -> SimpleNamespace:
    return SimpleNamespace(path=name, scene="home", trial=trial, sequences=[SimpleNamespace(seq=seq)])


def test_two_files_of_one_trial_number_are_said_so():
    """home-1-2_trial0.txt and home-1-2_trial00.txt were said to have 'no trial number'."""
    with pytest.raises(ValidationError) as both:
        _one_file_each([_file("home-1-2_trial0.txt", 0), _file("home-1-2_trial00.txt", 0)])
    assert "both hold home-2 trial 0: they carry the same trial number" in str(both.value), both.value
    with pytest.raises(ValidationError) as one:
        _one_file_each([_file("home-1-2.txt", 0), _file("home-1-2_trial0.txt", 0)])
    assert ("both hold home-2 trial 0: home-1-2.txt names no trial, which is read as trial 0, and "
            "home-1-2_trial0.txt carries trial 0") in str(one.value), one.value  # fmt: skip
    with pytest.raises(ValidationError, match="with no trial number to tell them apart"):
        _one_file_each([_file("home-1-2.txt", 0), _file("home_1_2_orb.txt", 0)])


def test_a_file_read_at_upload_is_read_with_the_challenge_s_spec(tmp_path, data):
    """keep_upload reads what it keeps: the reader's refusal names the file and its line."""
    challenge = read_challenge(one_phase(tmp_path, data))
    body = _good(data).replace("seq: 1", "seq: one", 1).encode()
    with pytest.raises(UploadRefused, match=r"^x\.txt, line \d+: ") as refused:
        keep_upload([("x.txt", io.BytesIO(body))], tmp_path / "sub", Limits(5, 10**7), "auto", [("cafe", 1)],
                    challenge.spec)  # fmt: skip
    assert str(tmp_path) not in str(refused.value)


def test_uploads_are_read_one_at_a_time(icra20, tmp_path, monkeypatch):
    """Reading an upload whole happens in the server's process, outside the scorer's memory limit:
    many teams' large files arriving together are read one after the other, never all at once."""
    import threading
    import time

    import lorisnb.io.readers.openloris as openloris
    from lorisnb.tools.challenge.uploads import read_upload

    src = icra20 / "per-seq" / "orbslam2_rgbd" / "cafe_1_1_orbslam2-original.txt"
    (tmp_path / "cafe-1-1.txt").write_bytes(src.read_bytes())
    real, now, most = openloris.read_openloris, [0], [0]
    lock = threading.Lock()

    def counted(*args, **kw):
        with lock:
            now[0] += 1
            most[0] = max(most[0], now[0])
        time.sleep(0.05)
        try:
            return real(*args, **kw)
        finally:
            with lock:
                now[0] -= 1

    monkeypatch.setattr(openloris, "read_openloris", counted)
    threads = [threading.Thread(target=read_upload, args=(tmp_path, ["cafe-1-1.txt"], {})) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert most[0] == 1
