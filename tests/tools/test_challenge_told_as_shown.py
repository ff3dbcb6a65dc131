"""What a team is told of its upload, as the server shows it (a re-attack's findings): a copy of
the ground truth uploaded in an after-close phase named its hidden sequence and pose count (the
test of "shown" was the phase's first view, the set shown after the close), now named only while
the team is shown that sequence's scores, decided when the message is shown; a trial number too
long to read (a folder run_<5000 digits>/) was a 500 leaving an empty upload folder, now the
refusal a too-large trial number gets; two files of one sequence were told to rename to a name the
server refuses (cafe_trial1.txt) with its internal algorithm name 'files', and a clash of a file
with one renamed from its run_1/ folder named only one of them."""

from __future__ import annotations

import io
import time
import zipfile

import pytest
from challenge_fixtures import challenge_file, wait_scored

pytest.importorskip("fastapi")
from fastapi.testclient import TestClient  # noqa: E402

from lorisnb.errors import ValidationError  # noqa: E402
from lorisnb.tools.challenge import store, uploads  # noqa: E402
from lorisnb.tools.challenge.app import create_app  # noqa: E402
from lorisnb.tools.challenge.config import read_challenge  # noqa: E402


class Clock:
    def __init__(self, t: float):
        self.t = t

    def __call__(self) -> float:
        return self.t


def _zip(members: dict[str, bytes]) -> bytes:
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as z:
        for name, data in members.items():
            z.writestr(name, data)
    return out.getvalue()


def _post(client, token: str, files: list[tuple[str, bytes]]):
    return client.post("/api/submissions", files=[("files", f) for f in files],
                       headers={"Authorization": f"Bearer {token}"})  # fmt: skip


def _gt(data) -> str:
    return (data.root / "openloris-scene" / "groundtruth" / "gt_cafe_1.txt").read_text()


def _tum(data) -> bytes:
    odom = (data.icra20 / "per-seq" / "odom" / "cafe-1-1-odom.txt").read_text().splitlines()
    return ("\n".join(line for line in odom if line[:1].isdigit()) + "\n").encode()


def test_a_copy_uploaded_in_an_after_close_phase_is_named_once_its_scores_show(tmp_path, data):
    challenge = read_challenge(challenge_file(tmp_path, data))
    final = challenge.phase("final")
    clock = Clock(final.opens + 1)  # the final runs; its scores show once it closes
    app = create_app(challenge, clock=clock)
    gt = _gt(data)
    uploads_ = {
        "gt2.txt": "scene: cafe\nframe: base_link\n" + gt[gt.index("seq: 2") :],
        "gt1.txt": gt[: gt.index("seq: 2")],
    }
    with TestClient(app) as client:
        ids = {}
        for name, text in uploads_.items():
            token = store.add_team(app.state.server.engine, name, final.closes + 3600)
            ids[name] = _post(client, token, [(name, text.encode())]).json()["id"]
        while_hidden = {n: wait_scored(client, sid)["error"] for n, sid in ids.items()}
        for name, error in while_hidden.items():  # cafe-2 hidden; cafe-1 shown by the development phase, but
            # no score of a final submission is shown before the final closes: the file, a copy, nothing more
            assert error == ("refused, not ranked: this upload holds the ground truth itself, not an estimate "
                             f"({name}: a copy of the ground truth). Upload your system's output")  # fmt: skip
            assert "3605" not in client.get(f"/submissions/{ids[name]}").text
        clock.t = final.closes + 1  # the final closed: every cafe sequence's scores show
        shown = {n: client.get(f"/api/submissions/{sid}").json()["error"] for n, sid in ids.items()}
    assert "(gt2.txt: cafe-2's positions and orientations are the ground truth's (all 3605 matched poses within " \
           "0.1 mm of it after the alignment))" in shown["gt2.txt"]  # fmt: skip
    assert "(gt1.txt: cafe-1's positions and orientations are the ground truth's (all " in shown["gt1.txt"]


def test_a_trial_number_too_long_to_read_is_refused_and_nothing_is_left(tmp_path, data):
    challenge = read_challenge(challenge_file(tmp_path, data))
    app = create_app(challenge, score=False)
    token = store.add_team(app.state.server.engine, "t", time.time() + 3600)
    up = challenge.folder / "uploads"
    with TestClient(app, raise_server_exceptions=False) as client:
        r = _post(client, token, [("u.zip", _zip({"run_" + "9" * 5000 + "/cafe-1-1.txt": _tum(data)}))])
        assert r.status_code == 400, r.text
        assert r.json()["error"].endswith("/cafe-1-1.txt': trial number 99999999999999999999... (5000 digits), "
                                          "too large; expected a trial number of at most 9223372036854775807 "
                                          "(cafe-1-2_trial2.txt, run_2/)")  # fmt: skip
        assert not up.exists() or list(up.iterdir()) == []


def test_any_error_of_reading_an_upload_is_a_refusal_with_nothing_left(tmp_path, data, monkeypatch):
    """The class: a LorisError of reading the upload is a 400 with its words (no server path); any
    other error a 500, and no folder of the upload is left either way."""
    challenge = read_challenge(challenge_file(tmp_path, data))
    app = create_app(challenge, score=False)
    token = store.add_team(app.state.server.engine, "t", time.time() + 3600)
    up = challenge.folder / "uploads"

    def plan(folder, names, fmt, sequences):
        raise ValidationError(f"{folder / names[0]}: something the reader refuses")

    monkeypatch.setattr(uploads, "plan", plan)
    with TestClient(app, raise_server_exceptions=False) as client:
        r = _post(client, token, [("cafe-1-1.txt", _tum(data))])
        assert (r.status_code, r.json()) == (400, {"error": "cafe-1-1.txt: something the reader refuses"})
        assert list(up.iterdir()) == []
        monkeypatch.setattr(uploads, "plan", lambda *a: 1 / 0)
        assert _post(client, token, [("cafe-1-1.txt", _tum(data))]).status_code == 500
        assert list(up.iterdir()) == []


def test_two_files_of_one_sequence_are_told_names_the_server_takes(tmp_path, data):
    challenge = read_challenge(challenge_file(tmp_path, data))
    app = create_app(challenge)
    engine = app.state.server.engine
    tum = _tum(data)
    with TestClient(app) as client:
        r = _post(client, store.add_team(engine, "a", time.time() + 3600), [("cafe-1-1.txt", tum),
                                                                           ("cafe_1_1_orb.txt", tum)])  # fmt: skip
        told = wait_scored(client, r.json()["id"])["error"]
        assert told == ("cafe-1-1.txt and cafe_1_1_orb.txt both hold cafe-1, with no trial number to tell them apart; "
                        "name each file for its trial (cafe-1-1_trial1.txt, cafe-1-1_trial2.txt, ...; or put them in "
                        "folders run_1/, run_2/, ... of one .zip), or upload them in separate submissions")  # fmt: skip
        # the names it advises are taken and scored as trials
        r = _post(client, store.add_team(engine, "b", time.time() + 3600), [("cafe-1-1_trial1.txt", tum),
                                                                           ("cafe-1-1_trial2.txt", tum)])  # fmt: skip
        view = wait_scored(client, r.json()["id"])
        assert view["status"] == "scored" and sorted(row["file"] for row in view["rows"]) == [
            "cafe-1-1_trial1.txt",
            "cafe-1-1_trial2.txt",
        ]
        # a clash made by a run_1/ folder's trial names both files and why
        r = _post(client, store.add_team(engine, "c", time.time() + 3600),
                  [("u.zip", _zip({"run_1/cafe-1-1.txt": tum, "cafe-1-1_trial1.txt": tum}))])  # fmt: skip
    assert (r.status_code, r.json()["error"]) == (400, (
        "u.zip: 'run_1/cafe-1-1.txt' and 'cafe-1-1_trial1.txt': a second file named 'cafe-1-1_trial1.txt': "
        "'run_1/cafe-1-1.txt' is kept as 'cafe-1-1_trial1.txt' (trial 1, which its folder names, in its name); "
        "expected distinct file names"))  # fmt: skip
