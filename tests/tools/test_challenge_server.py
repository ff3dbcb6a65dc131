"""The challenge server end to end in one process (FastAPI's TestClient, the real scorer): two
teams upload real icra20 results of cafe, each is scored by the pipeline of ``lorisnb evaluate``
(the same numbers as evaluate() on the same files), the leaderboard ranks them, the team, admin
and submission pages show them, the export holds them, and no response carries a ground-truth
coordinate."""

from __future__ import annotations

import csv
import time
import zipfile

import pytest
from challenge_fixtures import cafe_files, challenge_file, groundtruth_numbers, leaked

pytest.importorskip("fastapi")
from fastapi.testclient import TestClient  # noqa: E402

from lorisnb.cli import main  # noqa: E402
from lorisnb.tools.challenge import store  # noqa: E402
from lorisnb.tools.challenge.app import create_app  # noqa: E402
from lorisnb.tools.challenge.config import read_challenge  # noqa: E402
from lorisnb.tools.evaluation.runner import evaluate  # noqa: E402
from lorisnb.tools.report.leaderboard import leaderboard_spec  # noqa: E402


class Recording:
    """A TestClient whose every response body is kept (the ground-truth test reads them all)."""

    def __init__(self, client: TestClient):
        self.client = client
        self.bodies: list[str] = []

    def __getattr__(self, name):
        method = getattr(self.client, name)

        def call(*a, **kw):
            r = method(*a, **kw)
            self.bodies.append(r.text if not r.headers.get("content-type", "").startswith("image/") else "")
            return r

        return call


def wait_scored(client, sid: str, seconds: float = 90) -> dict:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        view = client.get(f"/api/submissions/{sid}").json()
        if view["status"] not in ("queued", "scoring"):
            return view
        time.sleep(0.2)
    raise AssertionError(f"submission {sid} not scored within {seconds} s: {view}")


def boards(client) -> list[dict]:
    """The leaderboards once every scored submission is ranked (a new ranking runs in a thread)."""
    for _ in range(300):
        phases = client.get("/api/leaderboard").json()["phases"]
        if not any(p.get("updating") for p in phases):
            return phases
        time.sleep(0.2)
    raise AssertionError("the leaderboard was not updated within a minute")


@pytest.fixture(scope="module")
def served(tmp_path_factory, data):
    tmp = tmp_path_factory.mktemp("challenge")
    path = challenge_file(tmp, data, final_closed=False, workers=2)
    challenge = read_challenge(path)
    app = create_app(challenge)
    engine = app.state.server.engine
    tokens = {name: store.add_team(engine, name, time.time() + 7000) for name in ("orbs", "dslam")}
    tokens["admin"] = store.add_team(engine, "organizers", time.time() + 3600, admin=True)
    with TestClient(app) as raw:
        client = Recording(raw)
        sids = {}
        for team, alg in (("orbs", "orbslam2_rgbd"), ("dslam", "ds-slam")):
            files = [("files", (p.name, p.read_bytes())) for p in cafe_files(data, alg)]
            r = client.post("/api/submissions", files=files, headers={"Authorization": f"Bearer {tokens[team]}"})
            assert r.status_code == 201, r.text
            sids[team] = r.json()["id"]
        views = {team: wait_scored(client, sid) for team, sid in sids.items()}
        yield dict(client=client, tokens=tokens, sids=sids, views=views, path=path, challenge=challenge, tmp=tmp,
                   engine=engine)  # fmt: skip


def test_scores_are_evaluate_s(served, data):
    """Each submission's per-sequence rows are those of evaluate() on the same files with the
    challenge's spec; both files count, seq 2 is scored but not ranked in development."""
    spec = leaderboard_spec({})
    for team, alg in (("orbs", "orbslam2_rgbd"), ("dslam", "ds-slam")):
        view = served["views"][team]
        assert view["status"] == "scored" and view["failures"] == [] and view["missing"] == []
        expected = evaluate(cafe_files(data, alg), spec, data_root=data, jobs=1).sequences()
        got = {(r["scene"], r["seq"]): r for r in view["rows"]}
        assert len(got) == len(expected) == 2
        for e in expected.itertuples():
            r = got[(e.scene, e.seq)]
            assert r["cr"] == pytest.approx(e.cr, abs=1e-12)
            assert r["c_ate_rmse"] == pytest.approx(e.c_ate_rmse, abs=1e-12)
            assert r["poses"] == e.poses and r["ranked"] == (e.seq == 1)
    # the real values: ORB-SLAM2 tracks cafe-1 almost throughout, DS-SLAM a sixth of it
    orbs = {r["seq"]: r for r in served["views"]["orbs"]["rows"]}
    assert orbs[1]["cr"] == pytest.approx(0.99947, abs=1e-5)


def test_leaderboard_ranks_on_the_phase_s_sequences(served):
    client = served["client"]
    dev, final = boards(client)
    assert dev["phase"] == "development" and [r["team"] for r in dev["rows"]] == ["orbs", "dslam"]
    assert [r["position"] for r in dev["rows"]] == [1, 2]
    assert all(r["coverage"] == "1/1" for r in dev["rows"])  # cafe-1 only
    first = dev["rows"][0]
    assert first["value"] == pytest.approx(served["views"]["orbs"]["rows"][0]["cr"], abs=1e-12)
    assert "significantly better" in dev["test"] and dev["sentences"][0].startswith("In cafe")
    assert final["rows"] == [] and "once it closes" in final["hidden"]  # after-close: nothing shown yet
    page = client.get("/").text
    assert page.index("orbs") < page.index("dslam") and "http" not in page.replace("http-equiv", "")  # no CDN


def test_pages(served):
    client, tokens, sids = served["client"], served["tokens"], served["sids"]
    page = client.get(f"/submissions/{sids['orbs']}")
    assert page.status_code == 200 and "cafe_1_1_orbslam2-original.txt" in page.text and "refresh" not in page.text
    assert 'id="status" class="status-scored"' in page.text
    png = client.get(f"/submissions/{sids['orbs']}/timeline.png")
    assert png.status_code == 200 and png.content[:4] == b"\x89PNG"
    team = client.post("/team", data={"token": tokens["orbs"]})
    assert team.status_code == 200 and sids["orbs"] in team.text and sids["dslam"] not in team.text
    assert "4 submission(s) left" in team.text
    api = client.get("/api/team", headers={"Authorization": f"Bearer {tokens['dslam']}"}).json()
    assert [s["id"] for s in api["submissions"]] == [sids["dslam"]] and api["left"] == 4
    assert client.post("/admin", data={"token": tokens["orbs"]}).status_code == 403  # a team is not the admin
    admin = client.post("/admin", data={"token": tokens["admin"]})
    assert admin.status_code == 200 and sids["orbs"] in admin.text and sids["dslam"] in admin.text
    api = client.get("/api/admin", headers={"Authorization": f"Bearer {tokens['admin']}"}).json()
    assert api["queue"]["scored"] == 2 and {t["name"] for t in api["teams"]} == {"orbs", "dslam", "organizers"}
    assert all("token" not in str(t) for t in api["teams"])
    assert client.get("/api/submissions/nosuch").status_code == 404
    assert client.get("/submit").status_code == 200 and 'type="file"' in client.get("/submit").text


def test_tokens_are_stored_hashed(served):
    with served["engine"].connect() as conn:
        stored = [r.token_hash for r in conn.execute(store.teams.select())]
    assert len(stored) == 3 and not set(stored) & set(served["tokens"].values())
    assert all(len(h) == 64 for h in stored)


def test_export_csv(served, tmp_path):
    out = tmp_path / "all.csv"
    assert main(["challenge", "export", str(served["path"]), "--csv", str(out)]) == 0
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == 4 and {r["team"] for r in rows} == {"orbs", "dslam"}
    cr = {(r["team"], r["seq"]): float(r["cr"]) for r in rows}
    assert cr[("orbs", "1")] == pytest.approx(served["views"]["orbs"]["rows"][0]["cr"], abs=1e-9)
    assert main(["challenge", "export", str(served["path"]), "--csv", str(out)]) == 2  # no overwrite without --force


def test_the_database_backs_up_while_the_server_runs(served, tmp_path):
    """SQLite's online backup (the guide's ``.backup``; here Python's ``sqlite3`` backup API) copies
    the database while the server holds it open and answers: every team and submission is in the copy."""
    import sqlite3

    db = served["challenge"].database.removeprefix("sqlite:///")
    copy = tmp_path / "backup.db"
    with sqlite3.connect(db) as live, sqlite3.connect(copy) as out:
        live.backup(out)
    assert served["client"].get("/api/leaderboard").status_code == 200  # still serving
    with sqlite3.connect(copy) as out:
        teams = {r[0] for r in out.execute("select name from teams")}
        subs = out.execute("select count(*) from submissions where status = 'scored'").fetchone()[0]
    assert {"orbs", "dslam"} <= teams and subs >= 2


def test_final_scores_hidden_until_it_closes(served, data):
    """A submission to the final phase (after-close) is scored, but neither its page nor the
    leaderboard shows a score, a table or the figure before the phase closes."""
    app = served["client"].client.app
    server = app.state.server
    final = server.challenge.phase("final")
    real = server.clock
    server.clock = lambda: final.opens + 1  # the final phase is open
    try:
        client = served["client"]
        files = [("files", (p.name, p.read_bytes())) for p in cafe_files(data, "odom")]
        r = client.post(
            "/api/submissions", files=files, headers={"Authorization": f"Bearer {served['tokens']['orbs']}"}
        )
        assert r.status_code == 201, r.text
        sid = r.json()["id"]
        assert store.submission(served["engine"], sid)["phase"] == "final"
        view = wait_scored(client, sid)
        assert view["status"] == "scored" and "rows" not in view and "once it closes" in view["hidden"]
        assert client.get(f"/submissions/{sid}/timeline.png").status_code == 404
        board = boards(client)[1]
        assert board["rows"] == [] and "once it closes" in board["hidden"]
        server.clock = lambda: final.closes + 1  # closed: shown
        assert len(client.get(f"/api/submissions/{sid}").json()["rows"]) == 2
        assert [r["team"] for r in boards(client)[1]["rows"]] == ["orbs"]
    finally:
        server.clock = real


def test_no_response_holds_a_groundtruth_coordinate(served, data):
    """Every response of this module so far (pages, API, errors), and a failed file's message
    (a file of the wrong scene's frame), holds none of the 10^4 ground-truth coordinates of cafe."""
    client = served["client"]
    bad = b"scene: cafe\nframe: nosuchframe\n\nseq: 1\n1560004885.5 1 2 3 0 0 0 1\n"
    r = client.post("/api/submissions", files=[("files", ("bad.txt", bad))],
                    headers={"Authorization": f"Bearer {served['tokens']['dslam']}"})  # fmt: skip
    view = wait_scored(client, r.json()["id"])
    assert view["status"] == "scored" and view["failures"] and "nosuchframe" in view["failures"][0]["error"]
    assert str(data.root) not in view["failures"][0]["error"]
    dev = boards(client)[0]  # dslam's latest submission is the one that counts: no output on cafe-1
    assert dev["without_output"] == ["dslam"]  # named, and ranked with every sequence a failed run
    assert [r["team"] for r in dev["rows"]] == ["orbs", "dslam"]
    assert dev["rows"][1]["cr"] == 0 and dev["rows"][1]["coverage"].startswith("0/")
    gt = groundtruth_numbers(data)
    assert len(gt) > 10_000
    bodies = client.bodies + [client.get(f"/submissions/{r.json()['id']}").text]
    assert len(bodies) > 20
    found = [n for b in bodies for n in leaked(b, gt)]
    assert found == []
    # and the test can fail: a ground-truth line would be caught
    line = (data.root / "openloris-scene/groundtruth/gt_cafe_1.txt").read_text().splitlines()[4]
    assert leaked(line, gt)


def test_zip_and_folder_submit(served, data, tmp_path):
    """A .zip of result files is unpacked and scored like the files themselves."""
    archive = tmp_path / "r.zip"
    with zipfile.ZipFile(archive, "w", zipfile.ZIP_DEFLATED) as z:
        for p in cafe_files(data, "orbslam2_rgbd"):
            z.write(p, f"results/{p.name}")
    client = served["client"]
    r = client.post("/api/submissions", files=[("files", ("r.zip", archive.read_bytes()))],
                    headers={"Authorization": f"Bearer {served['tokens']['orbs']}"})  # fmt: skip
    assert r.status_code == 201, r.text
    view = wait_scored(client, r.json()["id"])
    assert view["files"] == sorted(p.name for p in cafe_files(data, "orbslam2_rgbd"))
    assert [x["cr"] for x in view["rows"]] == [x["cr"] for x in served["views"]["orbs"]["rows"]]


def test_export_keeps_counts_whole_beside_a_failed_submission(tmp_path, data):
    """A submission without rows (failed) is one row of the export with its counts empty, and the
    counts of the others stay whole numbers (seq 1, not 1.0: a join on the sequence still works)."""
    path = challenge_file(tmp_path, data)
    challenge = read_challenge(path)
    challenge.folder.mkdir(parents=True)
    engine = store.connect(challenge.database)
    store.add_team(engine, "exporters", time.time() + 7000)
    team = next(t for t in store.all_teams(engine) if t["name"] == "exporters")
    row = dict(file="a.txt", scene="cafe", seq=1, poses=68, matched=68, cr=0.5, cr_t=0.5, cs_r=1.0, ate_rmse=0.1,
               c_ate_rmse=0.1, aoe_rmse=3.0, reloc_time=0.0)  # fmt: skip
    for sid, status, result in (("a" * 16, "scored", {"rows": [row]}), ("b" * 16, "failed", None)):
        store.add_submission(engine, sid, team["id"], "development", ["a.txt"], 10)
        claimed, claim = store.claim_next(engine)
        assert claimed == sid and store.finish(engine, sid, claim, status, result, "no" if result is None else None, 1)
    out = tmp_path / "all.csv"
    assert main(["challenge", "export", str(path), "--csv", str(out)]) == 0
    rows = {r["submission"]: r for r in csv.DictReader(out.open())}
    assert (rows["a" * 16]["seq"], rows["a" * 16]["poses"], rows["a" * 16]["matched"]) == ("1", "68", "68")
    assert (rows["b" * 16]["seq"], rows["b" * 16]["status"], rows["b" * 16]["error"]) == ("", "failed", "no")


def test_submit_says_why_a_scored_submission_shows_no_score(monkeypatch, capsys):
    """A submission to a phase whose scores show once it closes: ``lorisnb submit --wait`` says so,
    not just "scored" with nothing under it."""
    from lorisnb.tools.challenge import client

    view = dict(id="f" * 16, status="scored", url="http://127.0.0.1:1/submissions/ffff", error=None,
                hidden="scores of phase 'final' are shown once it closes")  # fmt: skip
    monkeypatch.setattr(client, "submit", lambda *a, **kw: dict(view))
    assert main(["submit", "http://127.0.0.1:1", "x.txt", "--token", "t", "--wait", "1"]) == 0
    err = capsys.readouterr().err
    assert "scored" in err and "scores of phase 'final' are shown once it closes" in err
