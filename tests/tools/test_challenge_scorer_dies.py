"""A scoring process ends with the server that started it: the server killed (SIGKILL, nothing of
its clean-up runs) left its scorers, forked from the fork server, scoring on beside the restarted
server's scorer of the same submission, both writing into its folder. Each scoring also writes
into a folder of its own claim (``claims/<claim>``), so that two never write one file."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

pytest.importorskip("fastapi")

SERVER = textwrap.dedent("""
    import multiprocessing, sys, time
    from pathlib import Path
    from lorisnb.core.spec.evalspec import EvalSpec
    from lorisnb.io.datasets.paths import DataPaths
    from lorisnb.tools.challenge.scoring import Task, score_in_child

    if __name__ == "__main__":
        tmp = Path(sys.argv[1])
        task = Task(str(tmp / "sub"), DataPaths(root=tmp / "data"), EvalSpec(), str(tmp / "sub" / "result-c1.json"), 60,
                    4_000_000_000, str(tmp / "gt"), ((("cafe", 1),),), str(tmp / "sub" / "claims" / "c1"))
        p = multiprocessing.get_context("forkserver").Process(target=score_in_child, args=(task,), daemon=True)
        p.start()
        print(p.pid, flush=True)
        time.sleep(120)
""")


def _gone(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return True
    return state in ("Z", "X")


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="reads /proc to see the scorer's state")
def test_a_scorer_dies_with_its_server(tmp_path, data):
    """The scorer hangs reading its ground truth (a FIFO nobody writes: a long scoring); its
    server is killed with SIGKILL; the scorer must be gone within 10 s, not keep scoring."""
    gt = tmp_path / "data" / "openloris-scene" / "groundtruth"
    gt.mkdir(parents=True)
    os.mkfifo(gt / "gt_cafe_1.txt")
    sub = tmp_path / "sub"
    (sub / "files").mkdir(parents=True)
    odom = data.icra20 / "per-seq" / "odom" / "cafe-1-1-odom.txt"
    (sub / "files" / "cafe-1-1.txt").write_text("".join(line + "\n" for line in odom.read_text().splitlines()
                                                        if line[:1].isdigit()))  # fmt: skip
    (sub / "plan.json").write_text(json.dumps({"cafe-1-1.txt": dict(format="tum", scene="cafe", seq=1)}))
    (tmp_path / "server.py").write_text(SERVER)
    server = subprocess.Popen([sys.executable, str(tmp_path / "server.py"), str(tmp_path)], stdout=subprocess.PIPE,
                              cwd=tmp_path, start_new_session=True, text=True)  # fmt: skip
    scorer = None
    try:
        scorer = int(server.stdout.readline())
        end = time.monotonic() + 30
        while not (sub / "claims" / "c1").is_dir():  # scoring under way, in its claim's folder
            assert time.monotonic() < end and server.poll() is None
            time.sleep(0.05)
        time.sleep(0.5)
        assert not _gone(scorer)  # hung on the ground truth
        server.send_signal(signal.SIGKILL)
        server.wait(10)
        end = time.monotonic() + 10
        while not _gone(scorer) and time.monotonic() < end:
            time.sleep(0.1)
        assert _gone(scorer), "the scorer outlived its killed server"
        assert not (sub / "result-c1.json").exists()
    finally:
        if server.poll() is None:
            server.kill()
            server.wait(10)
        if scorer is not None and not _gone(scorer):
            os.kill(scorer, signal.SIGKILL)


def test_each_scoring_writes_in_its_claims_folder(tmp_path, data):
    """A scoring's figures and work are in ``claims/<claim>/`` of the submission's folder (two
    scorings of one submission wrote one timeline-0.png and one pairs/0/files), and the page serves
    the figure from there."""
    from challenge_fixtures import challenge_file, wait_scored
    from fastapi.testclient import TestClient

    from lorisnb.tools.challenge import store
    from lorisnb.tools.challenge.app import create_app
    from lorisnb.tools.challenge.config import read_challenge

    challenge = read_challenge(challenge_file(tmp_path, data))
    app = create_app(challenge)
    token = store.add_team(app.state.server.engine, "t", time.time() + 7000)
    odom = data.icra20 / "per-seq" / "odom" / "cafe-1-1-odom.txt"
    tum = "".join(line + "\n" for line in odom.read_text().splitlines() if line[:1].isdigit())
    with TestClient(app) as client:
        r = client.post("/api/submissions", files=[("files", ("cafe-1-1.txt", tum.encode()))],
                        headers={"Authorization": f"Bearer {token}"})  # fmt: skip
        sid = r.json()["id"]
        view = wait_scored(client, sid)
        png = client.get(f"/submissions/{sid}/timeline.png")
    assert view["status"] == "scored" and [r["seq"] for r in view["rows"]] == [1]
    sub = challenge.folder / "uploads" / sid
    claim = json.loads(store.submission(app.state.server.engine, sid)["result"])["figures"][0]["file"]
    [work] = (sub / "claims").iterdir()
    assert claim == f"claims/{work.name}/timeline-0.png" and (sub / claim).is_file()
    assert (work / "pairs" / "0" / "files" / "cafe-1-1.txt").is_file()
    assert not (sub / "pairs").exists() and not (sub / "timeline-0.png").exists()
    assert png.status_code == 200 and png.content == (sub / claim).read_bytes()
