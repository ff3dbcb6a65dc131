"""Result files in the formats the challenge takes besides OpenLORIS': a TUM or EuRoC file named
after its sequence (``cafe-1-1.txt``, ``cafe_1_2.csv``) is scored exactly as ``lorisnb evaluate
FILE --format F --gt GT --gt-format openloris --scene cafe`` scores it against that sequence's
ground truth (GT: the ``seq:`` block of the scene's file, cut out here as text) with the
challenge's spec, and a TUM file of an OpenLORIS file's poses (odometry, in base_link, the ground
truth's frame) scores as that OpenLORIS file does."""

from __future__ import annotations

import csv
import time
from pathlib import Path

import pytest
from challenge_fixtures import challenge_file

pytest.importorskip("fastapi")
from fastapi.testclient import TestClient  # noqa: E402

from lorisnb.cli import main  # noqa: E402
from lorisnb.tools.challenge import store  # noqa: E402
from lorisnb.tools.challenge.app import create_app  # noqa: E402
from lorisnb.tools.challenge.config import read_challenge  # noqa: E402
from lorisnb.tools.evaluation.runner import evaluate_pairs  # noqa: E402

COLUMNS = ("poses", "matched", "cr", "cr_t", "cs_r", "ate_rmse", "c_ate_rmse", "aoe_rmse")


def poses(path: Path) -> list[list[str]]:
    """The pose lines of an OpenLORIS result file of one sequence, as written (stamp x y z qx qy qz qw)."""
    return [line.split() for line in path.read_text().splitlines() if line[:1].isdigit()]


def as_tum(rows: list[list[str]]) -> bytes:
    return "".join(" ".join(r) + "\n" for r in rows).encode()


def as_euroc(rows: list[list[str]]) -> bytes:
    """EuRoC CSV: whole nanoseconds, then position, then the quaternion w first."""

    def ns(stamp: str) -> str:
        whole, _, frac = stamp.partition(".")
        return whole + (frac + "0" * 9)[:9]

    lines = ["#timestamp [ns],p_x [m],p_y [m],p_z [m],q_w,q_x,q_y,q_z"]
    lines += [",".join([ns(r[0]), *r[1:4], r[7], *r[4:7]]) for r in rows]
    return ("\n".join(lines) + "\n").encode()


def sequence_groundtruth(data, seq: int, out: Path) -> Path:
    """The scene's ground-truth file with only its ``seq: <seq>`` block, cut out as text."""
    keep, lines = True, []
    for line in (data.root / "openloris-scene/groundtruth/gt_cafe_1.txt").read_text().splitlines():
        if line.startswith("seq:"):
            keep = int(line.split(":")[1]) == seq
        if keep:
            lines.append(line)
    out.write_text("\n".join(lines) + "\n")
    return out


@pytest.fixture(scope="module")
def scored(tmp_path_factory, data):
    tmp = tmp_path_factory.mktemp("formats")
    path = challenge_file(tmp, data, final_closed=True)  # every sequence shown
    path.write_text(path.read_text().replace("[limits]", '[spec]\neps = "paper"\nphi = 30\n\n[limits]', 1))
    challenge = read_challenge(path)
    odom = {q: data.icra20 / "per-seq" / "odom" / f"cafe-1-{q}-odom.txt" for q in (1, 2)}
    files = {"cafe-1-1.txt": as_tum(poses(odom[1])), "cafe_1_2.csv": as_euroc(poses(odom[2]))}
    kept = tmp / "sent"
    kept.mkdir()
    for name, body in files.items():
        (kept / name).write_bytes(body)
    app = create_app(challenge)
    with TestClient(app) as client:
        sids = {}
        for what, sent in (("plain", [(n, b) for n, b in files.items()]),
                           ("openloris", [(p.name, p.read_bytes()) for p in odom.values()])):  # fmt: skip
            token = store.add_team(app.state.server.engine, what, time.time() + 7000)
            r = client.post("/api/submissions", files=[("files", f) for f in sent],
                            headers={"Authorization": f"Bearer {token}"})  # fmt: skip
            assert r.status_code == 201, r.text
            sids[what] = r.json()["id"]
        views = {}
        end = time.monotonic() + 180
        for what, sid in sids.items():
            while (v := client.get(f"/api/submissions/{sid}").json())["status"] in ("queued", "scoring"):
                assert time.monotonic() < end, v
                time.sleep(0.2)
            views[what] = v
        for _ in range(300):
            boards = client.get("/api/leaderboard").json()["phases"]
            if not any(b.get("updating") for b in boards):
                break
            time.sleep(0.2)
    yield dict(views=views, challenge=challenge, sent=kept, tmp=tmp, boards=boards)


@pytest.mark.thorough
def test_plain_files_scored_as_lorisnb_evaluate_scores_them(scored, data, tmp_path):
    view = scored["views"]["plain"]
    assert view["status"] == "scored" and view["failures"] == [] and view["missing"] == [], view
    got = {r["file"]: r for r in view["rows"]}
    assert {(r["file"], r["seq"]) for r in view["rows"]} == {("cafe-1-1.txt", 1), ("cafe_1_2.csv", 2)}
    for name, fmt, seq in (("cafe-1-1.txt", "tum", 1), ("cafe_1_2.csv", "euroc", 2)):
        gt = sequence_groundtruth(data, seq, tmp_path / f"gt_cafe_1-seq{seq}.txt")
        file = scored["sent"] / name
        out = tmp_path / f"{seq}.csv"
        assert main(["evaluate", str(file), "--format", fmt, "--gt", str(gt), "--gt-format", "openloris", "--scene",
                     "cafe", "--eps", "paper", "--phi", "30", "--scale", "auto", "--csv", str(out)]) == 0  # fmt: skip
        (cli,) = list(csv.DictReader(out.open()))
        (py,) = evaluate_pairs([file], gt, scored["challenge"].spec, fmt=fmt, gt_fmt="openloris", scene="cafe",
                               jobs=1).sequence_rows()  # fmt: skip
        assert (cli["scene"], int(cli["seq"]), py["seq"]) == ("cafe", seq, seq)
        for k in COLUMNS:
            assert got[name][k] == pytest.approx(py[k], abs=1e-12, rel=1e-12), (name, k)
            assert got[name][k] == pytest.approx(float(cli[k]), abs=1e-12, rel=1e-12), (name, k)
    assert got["cafe-1-1.txt"]["matched"] > 1000 and got["cafe-1-1.txt"]["cr"] > 0.9  # odometry: correct throughout


def test_a_tum_file_scores_as_the_openloris_file_of_its_poses(scored):
    """The TUM file holds the poses of an OpenLORIS file in base_link: the same numbers, every
    column; the EuRoC file's stamps (nanoseconds, divided by 1e9) are not quite the same floats:
    its numbers agree to a millionth."""
    plain = {r["seq"]: r for r in scored["views"]["plain"]["rows"]}
    native = {r["seq"]: r for r in scored["views"]["openloris"]["rows"]}
    assert scored["views"]["openloris"]["failures"] == [] and set(native) == {1, 2}
    for k in COLUMNS:
        assert plain[1][k] == native[1][k], k
        assert plain[2][k] == pytest.approx(native[2][k], rel=1e-6), k


def test_plain_files_ranked_as_openloris_files(scored):
    """On the development leaderboard (cafe-1) the team of the TUM and EuRoC files and the team of
    the OpenLORIS files of the same poses have the same values."""
    dev = scored["boards"][0]
    rows = {r["team"]: r for r in dev["rows"]}
    assert dev["phase"] == "development" and set(rows) == {"plain", "openloris"}
    assert rows["plain"]["coverage"] == rows["openloris"]["coverage"] == "1/1"
    for k in ("value", "cr", "c_ate_rmse"):
        assert rows["plain"][k] == rows["openloris"][k], k
