"""Scoring on a Dask cluster (``[challenge] scheduler``): a local cluster on 127.0.0.1 scores two
real uploads in processes of its workers' own, with the numbers the server's own scorer gives
(those of evaluate() on the same files)."""

from __future__ import annotations

import json
import time

import pytest
from challenge_fixtures import cafe_files, challenge_file

pytest.importorskip("fastapi")
distributed = pytest.importorskip("distributed")
from fastapi.testclient import TestClient  # noqa: E402

from lorisnb.errors import ParseError  # noqa: E402
from lorisnb.tools.challenge import store  # noqa: E402
from lorisnb.tools.challenge.app import create_app  # noqa: E402
from lorisnb.tools.challenge.config import read_challenge  # noqa: E402
from lorisnb.tools.evaluation.runner import evaluate  # noqa: E402

pytestmark = pytest.mark.slow


def test_scoring_on_a_dask_cluster(tmp_path, data):
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=True, protocol="tcp",
                                  host="127.0.0.1", dashboard_address=None) as cluster:  # fmt: skip
        path = challenge_file(tmp_path, data, workers=2)
        text = path.read_text()
        path.write_text(text.replace("[challenge]\n", f'[challenge]\nscheduler = "{cluster.scheduler_address}"\n', 1))
        challenge = read_challenge(path)
        assert challenge.scheduler == cluster.scheduler_address
        app = create_app(challenge)
        token = store.add_team(app.state.server.engine, "cluster", time.time() + 7000)
        with TestClient(app) as client:
            sids = {}
            for alg in ("orbslam2_rgbd", "ds-slam"):
                files = [("files", (p.name, p.read_bytes())) for p in cafe_files(data, alg)]
                r = client.post("/api/submissions", files=files, headers={"Authorization": f"Bearer {token}"})
                assert r.status_code == 201, r.text
                sids[alg] = r.json()["id"]
            end = time.monotonic() + 300
            views = {}
            for alg, sid in sids.items():
                while (v := client.get(f"/api/submissions/{sid}").json())["status"] in ("queued", "scoring"):
                    assert time.monotonic() < end, v
                    time.sleep(0.3)
                views[alg] = v
    for alg, v in views.items():
        assert v["status"] == "scored", v
        expected = evaluate(cafe_files(data, alg), challenge.spec, data_root=data, jobs=1).sequences()
        result = json.loads(store.submission(app.state.server.engine, v["id"])["result"])  # every sequence scored
        assert [r["cr"] for r in result["rows"]] == pytest.approx(list(expected["cr"]), abs=1e-12)
        assert [r["seq"] for r in v["rows"]] == [1]  # shown: cafe-1 (cafe-2 is the final's, not closed)
    assert store.scoring_ledger(app.state.server.engine) == {sid: 1 for sid in sids.values()}


def test_scheduler_address_checked(tmp_path, data):
    path = challenge_file(tmp_path, data)
    path.write_text(path.read_text().replace("[challenge]\n", '[challenge]\nscheduler = "http://x"\n', 1))
    with pytest.raises(ParseError, match="scheduler"):
        read_challenge(path)
