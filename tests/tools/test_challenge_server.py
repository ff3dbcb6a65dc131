"""The challenge server end to end in one process (FastAPI's TestClient, the real scorer): two
teams upload real icra20 results of cafe, each is scored by the pipeline of ``lorisnb evaluate``
(the same numbers as evaluate() on the same files), the leaderboard ranks them, the team, admin
and submission pages show them, the export holds them, and no response carries a ground-truth
coordinate."""

from __future__ import annotations

import csv
import json
import time
import zipfile

import pytest
from challenge_fixtures import cafe_files, challenge_file, groundtruth_numbers, leaked, wait_scored

pytest.importorskip("fastapi")
from fastapi.testclient import TestClient  # noqa: E402

from lorisnb.cli import main  # noqa: E402
from lorisnb.tools.challenge import store  # noqa: E402
from lorisnb.tools.challenge.app import create_app  # noqa: E402
from lorisnb.tools.challenge.board import when  # noqa: E402
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


def closed_final(served):
    """The server's clock set past the final's close for a ``with`` block (restored after)."""
    import contextlib

    server = served["client"].client.app.state.server

    @contextlib.contextmanager
    def past():
        real = server.clock
        server.clock = lambda: server.challenge.phase("final").closes + 1
        try:
            yield
        finally:
            server.clock = real

    return past()


def test_scores_are_evaluate_s(served, data):
    """Each submission is scored on both its files by the pipeline of evaluate() with the
    challenge's spec, but while the final phase, the only one holding cafe-2, has not closed, its
    view holds cafe-1 alone and names cafe-2 without a value; once the final closes, both rows."""
    spec = leaderboard_spec({})
    for team, alg in (("orbs", "orbslam2_rgbd"), ("dslam", "ds-slam")):
        view = served["views"][team]
        assert view["status"] == "scored" and view["failures"] == [] and view["missing"] == []
        expected = evaluate(cafe_files(data, alg), spec, data_root=data, jobs=1).sequences()
        assert [(r["scene"], r["seq"], r["ranked"]) for r in view["rows"]] == [("cafe", 1, True)]
        assert view["hidden_sequences"] == [dict(scene="cafe", seq=2, files=[cafe_files(data, alg)[1].name],
                                                 shown="shown once phase 'final' closes (" f"{when(served['challenge'].phase('final').closes)})")]  # fmt: skip
        with closed_final(served):
            after = served["client"].get(f"/api/submissions/{view['id']}").json()
        got = {(r["scene"], r["seq"]): r for r in after["rows"]}
        assert len(got) == len(expected) == 2 and after["hidden_sequences"] == []
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
    (a file none of whose stamps is in its sequence's ground truth: a misspelt frame is refused at
    upload now), holds none of the 10^4 ground-truth coordinates of cafe."""
    client = served["client"]
    bad = b"scene: cafe\nframe: base_link\n\nseq: 1\n" + b"".join(b"%d 1 2 3 0 0 0 1\n" % (1000 + k) for k in range(20))
    r = client.post("/api/submissions", files=[("files", ("bad.txt", bad))],
                    headers={"Authorization": f"Bearer {served['tokens']['dslam']}"})  # fmt: skip
    view = wait_scored(client, r.json()["id"])
    # nothing of it scored: failed with each file's reason (it was 'scored' with no error, and ranked CR 0)
    assert view["status"] == "failed" and view["failures"] and "no estimate stamp" in view["failures"][0]["error"]
    assert (
        view["error"].startswith("nothing of this upload was scored: bad.txt: ")
        and "no estimate stamp" in view["error"]
    )
    assert str(data.root) not in view["failures"][0]["error"] and str(data.root) not in view["error"]
    assert not view["failures"][0]["error"].startswith("bad.txt")  # the file is named once, by its row
    dev = boards(client)[0]  # dslam's latest submission that scored something counts: not this one
    assert dev["without_output"] == []
    assert [r["submission"] for r in dev["rows"] if r["team"] == "dslam"] != [r.json()["id"]]
    assert all(row["cr"] > 0 for row in dev["rows"]), dev["rows"]
    gt = groundtruth_numbers(data)
    assert len(gt) > 10_000
    # every page and API answer, requested here too: the module's other tests may have run on
    # another pytest-xdist worker (their responses are then not in this client's record)
    tokens = served["tokens"]
    for sid in [*served["sids"].values(), r.json()["id"]]:
        client.get(f"/submissions/{sid}")
        client.get(f"/api/submissions/{sid}")
    for path in ("/", "/submit", "/api/leaderboard", "/api/submissions/nosuch"):
        client.get(path)
    client.get("/api/team", headers={"Authorization": f"Bearer {tokens['dslam']}"})
    client.get("/api/admin", headers={"Authorization": f"Bearer {tokens['admin']}"})
    bodies = client.bodies
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
    counts of the others stay whole numbers (seq 1, not 1.0: a join on the sequence still works);
    each row says why the submission's files failed (``failures``)."""
    path = challenge_file(tmp_path, data)
    challenge = read_challenge(path)
    challenge.folder.mkdir(parents=True)
    engine = store.connect(challenge.database)
    store.add_team(engine, "exporters", time.time() + 7000)
    team = next(t for t in store.all_teams(engine) if t["name"] == "exporters")
    row = dict(file="a.txt", scene="cafe", seq=1, poses=68, matched=68, cr=0.5, cr_t=0.5, cs_r=1.0, ate_rmse=0.1,
               c_ate_rmse=0.1, aoe_rmse=3.0, reloc_time=0.0)  # fmt: skip
    failed = [dict(file="c.txt", status="failed", error="line 3: 'x' has 1 fields"),
              dict(file="d.txt", status="skipped", error="no ground truth of office")]  # fmt: skip
    for sid, status, result in (("a" * 16, "scored", {"rows": [row], "failures": failed}), ("b" * 16, "failed", None)):
        store.add_submission(engine, sid, team["id"], "development", ["a.txt"], 10)
        claimed, claim = store.claim_next(engine)
        assert claimed == sid and store.finish(engine, sid, claim, status, result, "no" if result is None else None, 1)
    out = tmp_path / "all.csv"
    assert main(["challenge", "export", str(path), "--csv", str(out)]) == 0
    rows = {r["submission"]: r for r in csv.DictReader(out.open())}
    assert (rows["a" * 16]["seq"], rows["a" * 16]["poses"], rows["a" * 16]["matched"]) == ("1", "68", "68")
    assert (rows["b" * 16]["seq"], rows["b" * 16]["status"], rows["b" * 16]["error"]) == ("", "failed", "no")
    # the reasons its files failed, beside a scored submission's rows
    assert (
        rows["a" * 16]["failures"]
        == "c.txt (failed): line 3: 'x' has 1 fields; d.txt (skipped): no ground truth of office"
    )
    assert rows["b" * 16]["failures"] == ""


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


def test_hidden_sequence_leaves_the_server_only_after_the_final_closes(served, data, monkeypatch, capsys):
    """No response before the final closes holds a value of cafe-2 (the final's alone) as the pages
    print it (3 decimals) or the API writes it (every digit): the submission pages and their JSON,
    the team's and the leaderboard's pages and API, ``lorisnb submit --wait``'s output, and the
    figure served (drawn without cafe-2); the admin's page holds them and says so. Once the final
    closes they appear (so the test can fail)."""
    import httpx

    client, tokens, sids = served["client"], served["tokens"], served["sids"]
    app = client.client.app

    class Unstarted:  # lorisnb submit's httpx.Client, answered by the app in this process
        def __init__(self, base_url: str, timeout: float):
            self.client = TestClient(app, base_url=base_url)

        def __enter__(self):
            return self.client

        def __exit__(self, *exc):
            return False

    monkeypatch.setattr(httpx, "Client", Unstarted)
    folder = served["tmp"] / "submit-hidden"
    folder.mkdir()
    for p in cafe_files(data, "infinitam_aligned_depth"):
        (folder / p.name).write_bytes(p.read_bytes())
    capsys.readouterr()
    assert main(["submit", "http://127.0.0.1:9", str(folder), "--token", tokens["dslam"], "--wait", "120"]) == 0
    out = capsys.readouterr()
    sid = out.err.split()[1].rstrip(":")
    subs = [store.submission(served["engine"], x) for x in (sids["orbs"], sids["dslam"], sid)]
    rows = [r for s in subs for r in json.loads(s["result"])["rows"]]
    columns = ("cr", "cr_t", "cs_r", "ate_rmse", "c_ate_rmse", "aoe_rmse", "reloc_time")

    def forms(seq: int, form) -> set[str]:
        return {form(r[k]) for r in rows if r["seq"] == seq for k in columns if isinstance(r[k], float)}

    common = {"0.000", "1.000", "0.0", "1.0"}
    full = forms(2, repr) - forms(1, repr) - common  # as the API writes them
    printed = forms(2, "{:.3f}".format) - forms(1, "{:.3f}".format) - common  # as the pages and submit print them
    assert len(full) > 15 and len(printed) > 10  # the values of cafe-2 of three submissions
    team_form = {"token": tokens["dslam"]}
    auth = {"Authorization": f"Bearer {tokens['dslam']}"}

    def responses() -> tuple[list[str], list[str]]:
        """The pages (HTML) and the API's answers (JSON)."""
        pages = [client.get(f"/submissions/{x}").text for x in (sids["orbs"], sids["dslam"], sid)]
        pages += [client.get("/").text, client.post("/team", data=team_form).text]
        api = [client.get(f"/api/submissions/{x}").text for x in (sids["orbs"], sids["dslam"], sid)]
        api += [client.get("/api/leaderboard").text, client.get("/api/team", headers=auth).text]
        return pages, api

    pages, api = responses()
    shown = pages + [out.out, out.err]
    assert [f for f in printed if any(f in b for b in shown)] == []
    assert [f for f in full if any(f in b for b in shown + api)] == []
    assert "cafe 2: scored, shown once phase 'final' closes" in out.err and "cafe 2: CR" not in out.out
    assert "cafe 1: CR " in out.out  # InfiniTAM on cafe-1, shown
    # the figure served is the one drawn of cafe-1 alone
    result = json.loads(subs[2]["result"])
    png = client.get(f"/submissions/{sid}/timeline.png")
    drawn = {f["file"]: f["sequences"] for f in result["figures"]}
    assert png.status_code == 200 and png.headers["cache-control"] == "no-store"
    name = next(n for n in drawn if (served["challenge"].folder / "uploads" / sid / n).read_bytes() == png.content)
    assert drawn[name] == [["cafe", 1]] and len(drawn) == 2
    # the admin sees every value, and its page says which teams do not
    admin = client.post("/admin", data={"token": tokens["admin"]}).text
    assert 'id="admin-only"' in admin and all('id="admin-only"' not in b and "admin only" not in b for b in pages)
    assert f"cafe 2: {result['rows'][1]['cr']:.3f} (hidden from teams)" in admin
    with closed_final(served):
        pages, api = responses()
        png_after = client.get(f"/submissions/{sid}/timeline.png")
    assert all(any(f in b for b in api) for f in full)  # every value of cafe-2, in full
    assert png_after.status_code == 200 and png_after.content != png.content  # drawn with cafe-2


@pytest.mark.thorough
def test_a_team_with_trials_is_one_row_of_the_leaderboard(tmp_path, data):
    """A team's files named as trials (``cafe_1_1_trial1.txt``...) stay trials for the tests, but the
    board shows the team once per scene: three uploads of one file took positions 1 to 3 and
    pushed every other team down."""
    challenge = read_challenge(challenge_file(tmp_path, data))
    app = create_app(challenge)
    engine = app.state.server.engine
    tokens = {name: store.add_team(engine, name, time.time() + 7000) for name in ("trials", "single")}
    orb, ds = cafe_files(data, "orbslam2_rgbd")[0], cafe_files(data, "ds-slam")[0]
    uploads = {"trials": [(f"cafe_1_1_trial{k}.txt", orb) for k in (1, 2, 3)], "single": [(ds.name, ds)]}
    with TestClient(app) as client:
        for team, files in uploads.items():
            r = client.post("/api/submissions", files=[("files", (n, p.read_bytes())) for n, p in files],
                            headers={"Authorization": f"Bearer {tokens[team]}"})  # fmt: skip
            assert r.status_code == 201, r.text
            assert wait_scored(client, r.json()["id"])["status"] == "scored"
        dev = boards(client)[0]
    assert [(r["team"], r["position"]) for r in dev["rows"]] == [("trials", 1), ("single", 2)]
    first = dev["rows"][0]
    assert first["cr"] == pytest.approx(first["value"], abs=1e-12)  # the mean of its trials, as the value


def test_submit_leaves_hidden_files_and_folders_out(tmp_path):
    """``lorisnb submit FOLDER`` zips the folder's files but those under a hidden folder (a
    notebook's .ipynb_checkpoints/, .git/) or hidden themselves, as lorisnb's folder walks do."""
    import io
    import zipfile

    from lorisnb.tools.challenge.client import _parts

    folder = tmp_path / "results"
    for rel in ("cafe-1-1.txt", "more/cafe-1-2.txt", ".ipynb_checkpoints/cafe-1-1-checkpoint.txt", ".git/config",
                "more/.hidden.txt", "more/.cache/cafe-1-2.txt"):  # fmt: skip
        (folder / rel).parent.mkdir(parents=True, exist_ok=True)
        (folder / rel).write_text("x")
    [(field, (name, body))] = _parts([str(folder)])
    assert field == "files" and name == "results.zip"
    assert sorted(zipfile.ZipFile(io.BytesIO(body)).namelist()) == ["cafe-1-1.txt", "more/cafe-1-2.txt"]
