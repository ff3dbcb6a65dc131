"""The challenge server under load, on loopback only: ``lorisnb serve`` in its own process, N teams
each uploading real icra20 per-sequence results of cafe at the same moment, a probe loading the
leaderboard page throughout; figures: uploads accepted and their latency, the time until every
submission is scored, the page's latency meanwhile, and the scoring ledger (each exactly once).

Used by ``tests/tools/test_challenge_load.py`` (asserts) and ``bench.py`` (prints the figures);
``python benchmarks/challenge_load.py [N]`` runs it alone.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

#: Per-sequence icra20 results of cafe: algorithm -> files (cafe-1, cafe-2; dso has cafe-1 only).
CAFE_RESULTS: dict[str, list[str]] = {
    "orbslam2_rgbd": ["cafe_1_1_orbslam2-original.txt", "cafe_1_2_orbslam2-original.txt"],
    "ds-slam": ["cafe-1-1.txt", "cafe-1-2.txt"],
    "vins_mono_color_imu_with_loop": ["cafe-1-1.txt", "cafe-1-2.txt"],
    "vins_mono_fisheye_imu_with_loop": ["cafe-1-1.txt", "cafe-1-2.txt"],
    "infinitam_aligned_depth": ["cafe-1-1_infinitam-cuda.txt", "cafe-1-2_infinitam-cuda.txt"],
    "efusion_reloc_aligned_depth": ["cafe-1-1_efusion-cuda.txt", "cafe-1-2_efusion-cuda.txt"],
    "odom": ["cafe-1-1-odom.txt", "cafe-1-2-odom.txt"],
    "dso": ["cafe-1-1-all.txt"],
}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def start_server(challenge: Path, port: int, log: Path) -> subprocess.Popen:
    """``lorisnb serve CHALLENGE --port PORT`` on 127.0.0.1 in a session of its own (killed as a
    group: the server, its fork server and its scorers); returns once it answers."""
    import httpx

    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(Path(__file__).resolve().parents[1]),
                                                       os.environ.get("PYTHONPATH", "")]))  # fmt: skip
    proc = subprocess.Popen(
        [sys.executable, "-m", "lorisnb.cli", "serve", str(challenge), "--port", str(port)],
        stdout=open(log, "ab"), stderr=subprocess.STDOUT, env=env, start_new_session=True,
    )  # fmt: skip
    end = time.monotonic() + 120
    while time.monotonic() < end:
        if proc.poll() is not None:
            raise RuntimeError(f"lorisnb serve stopped ({proc.returncode}): {log.read_text()[-2000:]}")
        try:
            if httpx.get(f"http://127.0.0.1:{port}/api/health", timeout=2).status_code == 200:
                return proc
        except httpx.HTTPError:
            time.sleep(0.2)
    kill(proc)
    raise RuntimeError(f"lorisnb serve did not answer within 120 s: {log.read_text()[-2000:]}")


def kill(proc: subprocess.Popen, sig: int = signal.SIGKILL) -> None:
    """Kill the server's whole session (as a machine's crash or a container's stop would)."""
    try:
        os.killpg(proc.pid, sig)
    except ProcessLookupError:
        pass
    proc.wait(30)


def write_challenge(folder: Path, groundtruth: Path, workers: int, per_day: int = 5) -> Path:
    now = time.time()

    def iso(t: float) -> str:
        return time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(t))

    path = folder / "load.toml"
    path.write_text(
        f'[challenge]\ntitle = "Load test"\ngroundtruth = "{groundtruth}"\nfolder = "{folder / "server"}"\n'
        f"opens = {iso(now - 60)}\ncloses = {iso(now + 7200)}\n\n[limits]\nworkers = {workers}\n"
        f'submissions_per_day = {per_day}\n\n[[phase]]\nname = "class"\nscenes = ["cafe"]\n',
        encoding="utf-8",
    )
    return path


def run_load(folder: Path, data: Any, n: int = 50, workers: int = 2, timeout: float = 900) -> dict[str, Any]:
    """The load run (see the module docstring); its figures."""
    import httpx

    from lorisnb.tools.challenge import store
    from lorisnb.tools.challenge.config import read_challenge

    path = write_challenge(folder, data.root, workers)
    challenge = read_challenge(path)
    challenge.folder.mkdir(parents=True, exist_ok=True)
    engine = store.connect(challenge.database)
    tokens = [store.add_team(engine, f"team {i:02d}", time.time() + 7000) for i in range(n)]
    algs = list(CAFE_RESULTS)
    uploads = []
    for i in range(n):
        alg = algs[i % len(algs)]
        uploads.append((alg, [(f, (data.icra20 / "per-seq" / alg / f).read_bytes()) for f in CAFE_RESULTS[alg]]))
    port = free_port()
    url = f"http://127.0.0.1:{port}"
    proc = start_server(path, port, folder / "server.log")
    pages: list[float] = []
    done = threading.Event()

    def probe() -> None:  # the leaderboard page, as a class watching it would load it
        with httpx.Client(base_url=url, timeout=60) as c:
            while not done.is_set():
                t = time.perf_counter()
                r = c.get("/")
                pages.append(time.perf_counter() - t)
                assert r.status_code == 200
                done.wait(0.25)

    def send(i: int) -> tuple[int, float, str]:
        alg, files = uploads[i]
        t = time.perf_counter()
        with httpx.Client(base_url=url, timeout=120) as c:
            r = c.post("/api/submissions", files=[("files", f) for f in files],
                       headers={"Authorization": f"Bearer {tokens[i]}"})  # fmt: skip
        return r.status_code, time.perf_counter() - t, r.json().get("id", r.text)

    watcher = threading.Thread(target=probe, daemon=True)
    try:
        watcher.start()
        t0 = time.perf_counter()
        with ThreadPoolExecutor(n) as pool:
            sent = list(pool.map(send, range(n)))
        accepted_in = time.perf_counter() - t0
        end = time.monotonic() + timeout
        counts: dict[str, int] = {}
        while time.monotonic() < end:
            counts = httpx.get(f"{url}/api/health", timeout=30).json()["queue"]
            if counts["queued"] == 0 and counts["scoring"] == 0:
                break
            time.sleep(0.5)
        scored_in = time.perf_counter() - t0
        done.set()
        watcher.join(60)
        subs = {s["id"]: s for s in store.all_submissions(engine)}
    finally:
        done.set()
        kill(proc, signal.SIGTERM)
    ledger = store.scoring_ledger(engine)
    by_alg: dict[str, set[str]] = {}
    for (alg, _), (_, _, sid) in zip(uploads, sent, strict=True):
        s = subs.get(sid)
        rows = json.loads(s["result"])["rows"] if s and s["result"] else []
        by_alg.setdefault(alg, set()).add(json.dumps([(r["seq"], r["cr"], r["c_ate_rmse"]) for r in rows]))
    latency = np.array([t for _, t, _ in sent])
    page = np.array(pages)
    return dict(
        n=n, workers=workers, accepted=sum(code == 201 for code, _, _ in sent), stored=len(subs),
        scored=sum(s["status"] == "scored" for s in subs.values()), queue=counts,
        once=sum(v == 1 for v in ledger.values()), ledger_rows=len(ledger),
        upload_p50=float(np.median(latency)), upload_max=float(latency.max()), all_accepted_s=accepted_in,
        all_scored_s=scored_in, per_minute=60 * n / scored_in, page_loads=len(page),
        page_p50=float(np.median(page)) if len(page) else float("nan"),
        page_p95=float(np.percentile(page, 95)) if len(page) else float("nan"),
        page_max=float(page.max()) if len(page) else float("nan"),
        same_scores=all(len(v) == 1 for v in by_alg.values()),
    )  # fmt: skip


def describe(f: dict[str, Any]) -> str:
    return (
        f"challenge server, {f['n']} concurrent uploads of icra20 cafe results on loopback, {f['workers']} scorers: "
        f"{f['accepted']}/{f['n']} accepted in {f['all_accepted_s']:.1f} s (upload p50 {f['upload_p50']:.2f} s, "
        f"max {f['upload_max']:.2f} s); all scored after {f['all_scored_s']:.1f} s ({f['per_minute']:.1f}/min), "
        f"{f['once']}/{f['n']} scored exactly once; leaderboard page during the run: {f['page_loads']} loads, "
        f"p50 {f['page_p50']:.2f} s, p95 {f['page_p95']:.2f} s, max {f['page_max']:.2f} s"
    )


if __name__ == "__main__":
    import tempfile

    from lorisnb.io import find_data

    with tempfile.TemporaryDirectory(prefix="lorisnb-load-") as tmp:
        print(describe(run_load(Path(tmp), find_data(), n=int(sys.argv[1]) if len(sys.argv) > 1 else 50)))
