"""The challenge server killed while scoring (SIGKILL to its whole session: server, fork server
and scorers, as a crash would) and started again: every queued submission, the one half-scored
too, is scored exactly once, none is lost, and the scores are those of an undisturbed run. Then
``lorisnb submit`` sends a folder to the restarted server and waits for its score."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import pytest
from challenge_fixtures import cafe_files, challenge_file

pytest.importorskip("fastapi")
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import httpx  # noqa: E402
from challenge_load import free_port, kill, start_server  # noqa: E402

from lorisnb.cli import main  # noqa: E402
from lorisnb.tools.challenge import store  # noqa: E402
from lorisnb.tools.challenge.config import read_challenge  # noqa: E402

pytestmark = pytest.mark.slow


def test_killed_mid_scoring_resumes_once(tmp_path, data, capsys):
    path = challenge_file(tmp_path, data, limits="submissions_per_day = 10")
    challenge = read_challenge(path)
    challenge.folder.mkdir(parents=True)
    engine = store.connect(challenge.database)
    token = store.add_team(engine, "crashers", time.time() + 7000)
    port = free_port()
    url = f"http://127.0.0.1:{port}"
    log = tmp_path / "server.log"
    proc = start_server(path, port, log)
    algs = ["orbslam2_rgbd", "ds-slam", "odom", "infinitam_aligned_depth"]
    sids = []
    try:
        for alg in algs:
            files = [("files", (p.name, p.read_bytes())) for p in cafe_files(data, alg)]
            r = httpx.post(f"{url}/api/submissions", files=files, headers={"Authorization": f"Bearer {token}"},
                           timeout=60)  # fmt: skip
            assert r.status_code == 201, r.text
            sids.append(r.json()["id"])
        end = time.monotonic() + 120
        while store.queue_counts(engine)["scoring"] == 0 and time.monotonic() < end:
            time.sleep(0.02)
        before = {s["id"]: s["status"] for s in store.all_submissions(engine)}
    finally:
        kill(proc)  # SIGKILL to the session: no clean-up runs
    assert "scoring" in before.values(), before
    killed = [sid for sid, st in before.items() if st == "scoring"]
    after_kill = {s["id"]: s for s in store.all_submissions(engine)}
    assert set(after_kill) == set(sids)  # none lost
    assert all((challenge.folder / "uploads" / sid / "files").is_dir() for sid in sids)
    unfinished = [sid for sid in sids if after_kill[sid]["status"] in ("queued", "scoring")]
    assert unfinished and set(killed) <= set(unfinished)

    proc = start_server(path, port, log)
    try:
        end = time.monotonic() + 300
        while time.monotonic() < end:
            counts = store.queue_counts(engine)
            if counts["queued"] == counts["scoring"] == 0:
                break
            time.sleep(0.2)
        final = {s["id"]: s for s in store.all_submissions(engine)}
        assert all(final[sid]["status"] == "scored" for sid in sids), {k: v["status"] for k, v in final.items()}
        ledger = store.scoring_ledger(engine)
        assert {sid: ledger.get(sid) for sid in sids} == {sid: 1 for sid in sids}  # each exactly once
        for sid in killed:
            assert final[sid]["attempts"] == 2  # taken again after the restart
        # the scores of the resumed run are those of the files: ORB-SLAM2 on cafe-1
        view = httpx.get(f"{url}/api/submissions/{sids[0]}", timeout=30).json()
        assert view["rows"][0]["cr"] == pytest.approx(0.99947, abs=1e-5)

        folder = tmp_path / "mine"
        folder.mkdir()
        for p in cafe_files(data, "ds-slam"):
            (folder / p.name).write_bytes(p.read_bytes())
        capsys.readouterr()
        code = main(["submit", url, str(folder), "--token", token, "--wait", "240"])
        out = capsys.readouterr()
        assert code == 0, out.err
        assert "scored" in out.err and "cafe 1: CR 0.163" in out.out
        # cafe-2 is the final's alone, not closed: scored, named, no value
        assert "cafe 2: CR" not in out.out and "cafe 2: scored, shown once phase 'final' closes" in out.err
        assert main(["submit", url, str(folder), "--token", "wrong"]) == 2
        assert "unknown token" in capsys.readouterr().err
    finally:
        kill(proc)
