"""What a scoring that scored nothing, or part of an upload, says on every view (sixth-seventh
pass): a submission of which nothing was scored was ``scored`` with no error on /api/team, the team
page and the admin's listing, and its team's earlier standing replaced by CR 0; a file of a
sequence not shown yet that failed was in no view; a trial without a sequence counted it CR 0
unsaid; a TUM file was advised to check its 'seq:' number; numpy's warnings were notes."""

from __future__ import annotations

import io
import json
import re
import time

import pytest
from challenge_fixtures import cafe_files, challenge_file, wait_scored, zipped
from test_challenge_s67_uploads import one_phase

pytest.importorskip("fastapi")
from fastapi.testclient import TestClient  # noqa: E402

from lorisnb.io.datasets.paths import scene_durations  # noqa: E402
from lorisnb.tools.challenge import store  # noqa: E402
from lorisnb.tools.challenge.app import create_app  # noqa: E402
from lorisnb.tools.challenge.board import submission_view  # noqa: E402
from lorisnb.tools.challenge.config import read_challenge, sequences_of  # noqa: E402
from lorisnb.tools.challenge.scoring import score_folder  # noqa: E402
from lorisnb.tools.challenge.uploads import PLAN, Limits, keep_upload  # noqa: E402

#: A TUM file of 60 poses whose stamps (1000 s on) miss every ground truth of cafe.
MISSING = b"".join(b"%d %.1f 0 0 0 0 0 1\n" % (1000 + k, 0.1 * k) for k in range(60))


def boards(client) -> list[dict]:
    for _ in range(300):
        phases = client.get("/api/leaderboard").json()["phases"]
        if not any(p.get("updating") for p in phases):
            return phases
        time.sleep(0.2)
    raise AssertionError("the leaderboard was not updated within a minute")


def test_nothing_scored_is_failed_on_every_view_and_keeps_the_standing(tmp_path, data):
    challenge = read_challenge(challenge_file(tmp_path, data))
    app = create_app(challenge)
    engine = app.state.server.engine
    token = store.add_team(engine, "t", time.time() + 7000)
    admin = store.add_team(engine, "organizers", time.time() + 7000, admin=True)
    auth = {"Authorization": f"Bearer {token}"}
    good, second = cafe_files(data, "ds-slam")
    with TestClient(app) as client:

        def upload(files) -> dict:
            r = client.post("/api/submissions", files=[("files", f) for f in files], headers=auth)
            assert r.status_code == 201, r.text
            return wait_scored(client, r.json()["id"])

        scored = upload([(good.name, good.read_bytes())])
        assert scored["status"] == "scored" and scored["rows"][0]["cr"] > 0
        missed = upload([("cafe-1-1.txt", MISSING)])
        # partly scored: cafe-1 scored, cafe-2 (shown once the final closes) missed its ground truth
        partly = upload([(good.name, good.read_bytes()), ("cafe-1-2.txt", MISSING)])
        assert missed["status"] == "failed", missed
        error = missed["error"]
        assert error.startswith("nothing of this upload was scored: cafe-1-1.txt: not scored: "), error
        assert "no estimate stamp falls inside the ground truth's time span" in error
        team = {s["id"]: s for s in client.get("/api/team", headers=auth).json()["submissions"]}
        assert team[missed["id"]]["status"] == "failed" and team[missed["id"]]["error"] == error
        page = client.post("/team", data={"token": token}).text
        assert error.replace("'", "&#39;") in page
        listed = {s["id"]: s for s in client.get("/api/admin", headers={"Authorization": f"Bearer {admin}"}).json()[
            "submissions"]}  # fmt: skip
        assert listed[missed["id"]]["status"] == "failed" and listed[missed["id"]]["error"].startswith(
            "nothing of this upload was scored: cafe-1-1.txt: not scored: seq 1: no estimate stamp"
        )
        assert "admin" in client.post("/admin", data={"token": admin}).text

        # the partly scored: scored, its failure listed on every view, cafe-2's without a value
        assert partly["status"] == "scored" and partly["error"] is None, partly
        [hidden] = partly["failures"]
        assert hidden["file"] == "cafe-1-2.txt" and hidden["hidden"], hidden
        assert hidden["error"].startswith("cafe 2: no estimate stamp falls inside the ground truth's time span; "
                                          "the reason in full is shown once phase 'final' closes (")  # fmt: skip
        assert not re.search(r"\d+\.\d+", hidden["error"]), hidden
        said = f"cafe-1-2.txt (not scored): {hidden['error']}"
        team = {s["id"]: s for s in client.get("/api/team", headers=auth).json()["submissions"]}
        assert team[partly["id"]]["failures"] == [said], team[partly["id"]]
        assert said.replace("'", "&#39;") in client.post("/team", data={"token": token}).text
        assert (
            f"cafe-1-2.txt (not scored): {hidden['error']}".split(" (")[0]
            in client.get(f"/submissions/{partly['id']}").text
        )
        admin_list = {s["id"]: s for s in client.get("/api/admin", headers={"Authorization": f"Bearer {admin}"}).json()[
            "submissions"]}  # fmt: skip
        [full] = admin_list[partly["id"]]["failures"]
        assert full.startswith("cafe-1-2.txt (not scored): seq 2: no estimate stamp") and "ground truth 15" in full

        # the board: the team's latest submission that scored something (the partly scored one)
        dev = boards(client)[0]
        assert dev["without_output"] == [] and [r["submission"] for r in dev["rows"]] == [partly["id"]]
        assert dev["rows"][0]["cr"] == pytest.approx(scored["rows"][0]["cr"])
        assert second  # (ds-slam's cafe-1-2, unused: the hidden one is the file missing its ground truth)


def test_a_trial_without_a_sequence_is_said(tmp_path, data):
    """run_1/ with cafe-1-1 and cafe-1-2, run_2/ with cafe-1-1 alone: trial 2's cafe-2 counted CR 0
    in its mean, and the submission said nothing (``missing`` empty, no note)."""
    challenge = read_challenge(one_phase(tmp_path, data))
    durations = scene_durations(challenge.scenes, challenge.data)
    one, two = cafe_files(data, "ds-slam")
    sub = tmp_path / "sub"
    upload = zipped({"run_1/cafe-1-1.txt": one.read_bytes(), "run_1/cafe-1-2.txt": two.read_bytes(),
                     "run_2/cafe-1-1.txt": one.read_bytes()})  # fmt: skip
    keep_upload([("u.zip", io.BytesIO(upload))], sub, Limits(10, 10**8), "auto", sequences_of(durations))
    plain = json.loads((sub / PLAN).read_text()) if (sub / PLAN).is_file() else {}
    result = score_folder(sub / "files", challenge.data, challenge.spec, plain=plain, groundtruth=tmp_path / "gt")
    row = dict(id="s", team="t", phase="dev", status="scored", created=time.time(), finished=time.time(), files="[]",
               bytes=1, result=json.dumps(result), error=None)  # fmt: skip
    view = submission_view(row, challenge, durations, time.time())
    assert sorted((r["file"], r["seq"]) for r in view["rows"]) == [
        ("cafe-1-1_trial1.txt", 1), ("cafe-1-1_trial2.txt", 1), ("cafe-1-2_trial1.txt", 2)]  # fmt: skip
    assert view["missing"] == [dict(scene="cafe", seq=2, trial=2, error="trial 2 has no output for cafe-1-2 (trial 1 has "
                                    "one): it counts as a failed run (CR 0) in trial 2")]  # fmt: skip


def test_numpy_s_warnings_are_said_in_lorisnb_s_words(tmp_path, data):
    """Coordinates of 1e308 (refused at upload now) scored as they are: numpy's 'overflow
    encountered in reduce' was a note to the team; now one note of lorisnb's says what is wrong."""
    challenge = read_challenge(one_phase(tmp_path, data))
    files = tmp_path / "sub" / "files"
    files.mkdir(parents=True)
    (files / "cafe-1-1.txt").write_bytes(b"".join(b"%d 1e308 1e308 1e308 0 0 0 1\n" % (1560004885 + k)
                                                  for k in range(60)))  # fmt: skip
    result = score_folder(files, challenge.data, challenge.spec, groundtruth=tmp_path / "gt",
                          plain={"cafe-1-1.txt": dict(format="tum", scene="cafe", seq=1)})  # fmt: skip
    texts = [n["text"] for n in result["notes"]]
    assert not any("encountered" in t for t in texts), texts
    assert any(t.startswith("cafe-1-1.txt: a computation on its values overflowed") for t in texts), texts


def test_a_tum_file_is_advised_of_its_name_not_a_seq_line(tmp_path, data):
    """A TUM file's stamps missing its ground truth: the note advised to 'check the seq: number',
    a line a TUM file has not; its name names its sequence."""
    challenge = read_challenge(one_phase(tmp_path, data))
    files = tmp_path / "sub" / "files"
    files.mkdir(parents=True)
    (files / "cafe-1-1.txt").write_bytes(MISSING)
    result = score_folder(files, challenge.data, challenge.spec, groundtruth=tmp_path / "gt",
                          plain={"cafe-1-1.txt": dict(format="tum", scene="cafe", seq=1)})  # fmt: skip
    told = json.dumps(result["notes"]) + json.dumps(result["failures"])
    assert "seq: number" not in told, told
    assert "check that its name names its sequence (it names cafe-1-1)" in told, told
