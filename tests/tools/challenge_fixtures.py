"""Shared set-up of the challenge server's tests: a challenge file over the real ground truth, and
real icra20 result files of the cafe scene."""

from __future__ import annotations

import io
import re
import time
import zipfile
from pathlib import Path

CAFE = {  # algorithm -> its per-sequence result files of cafe-1 and cafe-2 (icra20_results/per-seq)
    "orbslam2_rgbd": ["cafe_1_1_orbslam2-original.txt", "cafe_1_2_orbslam2-original.txt"],
    "ds-slam": ["cafe-1-1.txt", "cafe-1-2.txt"],
    "vins_mono_color_imu_with_loop": ["cafe-1-1.txt", "cafe-1-2.txt"],
    "infinitam_aligned_depth": ["cafe-1-1_infinitam-cuda.txt", "cafe-1-2_infinitam-cuda.txt"],
    "odom": ["cafe-1-1-odom.txt", "cafe-1-2-odom.txt"],
}


def cafe_files(data, algorithm: str) -> list[Path]:
    return [data.icra20 / "per-seq" / algorithm / f for f in CAFE[algorithm]]


def challenge_file(tmp_path: Path, data, *, limits: str = "", final_closed: bool = False, workers: int = 1) -> Path:
    """A challenge over the real ground truth: phase development ranks cafe-1 (live), phase final
    all of cafe (scores after it closes: closed already with ``final_closed``)."""
    now = time.time()

    def iso(t: float) -> str:
        return time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(t))

    dev_close = now + 3600
    final = (f'opens = {iso(now - 7200)}\ncloses = {iso(now - 3600)}\n' if final_closed
             else f'opens = {iso(dev_close)}\ncloses = {iso(now + 7200)}\n')  # fmt: skip
    path = tmp_path / "class.toml"
    path.write_text(
        f"""[challenge]
title = "Class challenge"
groundtruth = "{data.root}"
folder = "{tmp_path / "server"}"
opens = {iso(now - 7200)}
closes = {iso(now + 7200)}

[limits]
workers = {workers}
{limits}

[[phase]]
name = "development"
scenes = ["cafe"]
sequences = {{ cafe = [1] }}
opens = {iso(now - 3600)}
closes = {iso(dev_close)}

[[phase]]
name = "final"
scenes = ["cafe"]
leaderboard = "after-close"
{final}""",
        encoding="utf-8",
    )
    return path


def groundtruth_numbers(data, scene: str = "cafe") -> set[str]:
    """Every ground-truth coordinate of the scene (x y z qx qy qz qw) of 4 significant digits or
    more, as Python writes the number (the file's ``21.377251`` is ``repr(21.377251)``)."""
    out = set()
    for line in (data.root / "openloris-scene" / "groundtruth" / f"gt_{scene}_1.txt").read_text().splitlines():
        parts = line.split()
        if len(parts) == 8 and not line.startswith("seq"):
            out.update(repr(float(v)) for v in parts[1:8] if len(v.strip("-0.")) >= 4)
    return out


NUMBER = re.compile(r"-?\d+\.\d+")


def leaked(text: str, gt: set[str]) -> list[str]:
    """The numbers in ``text`` that are ground-truth coordinates."""
    return [n for n in NUMBER.findall(text) if repr(float(n)) in gt]


def wait_scored(client, sid: str, seconds: float = 120) -> dict:
    """A submission's view once the server has scored it (or failed it), within ``seconds``."""
    end = time.monotonic() + seconds
    view: dict = {}
    while time.monotonic() < end:
        view = client.get(f"/api/submissions/{sid}").json()
        if view["status"] not in ("queued", "scoring"):
            return view
        time.sleep(0.2)
    raise AssertionError(f"submission {sid} not scored within {seconds} s: {view}")


def zipped(members: dict[str, bytes]) -> bytes:
    """A zip (deflated) of ``members``, name -> bytes, as a team uploads it."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        for name, body in members.items():
            z.writestr(name, body)
    return buf.getvalue()
