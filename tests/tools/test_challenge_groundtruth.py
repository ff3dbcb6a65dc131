"""The ground truth uploaded as an estimate (an adversarial pass: a copy of gt_cafe_1.txt ranked
first with CR 1.0 and C-ATE 0.0, no flag): refused, with the reason, and kept off the
leaderboard, whatever its format or however little it copies (its positions only); an honest
upload beside it is ranked. A challenge whose ground truth is lorisnb's own sample data (which
ships with the package) says on start and on its leaderboard that it is for practice."""

from __future__ import annotations

import re
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from challenge_fixtures import cafe_files, challenge_file, wait_scored

pytest.importorskip("fastapi")
from fastapi.testclient import TestClient  # noqa: E402

from lorisnb.cli import main  # noqa: E402
from lorisnb.io.datasets.paths import SAMPLE_DATA  # noqa: E402
from lorisnb.tools.challenge import store  # noqa: E402
from lorisnb.tools.challenge.app import create_app  # noqa: E402
from lorisnb.tools.challenge.config import read_challenge  # noqa: E402
from lorisnb.tools.challenge.scoring import COPY_ATE_M, groundtruth_copies  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]


def _tum_of_sequence(gt_file: Path, seq: int, yaw_deg: float = 0.0, shift_m: float = 0.0) -> bytes:
    """The poses of one ``seq:`` block of an OpenLORIS ground-truth file as TUM lines: positions
    moved by ``shift_m`` along x, orientations turned by ``yaw_deg`` about z."""
    lines, current = [], None
    half = np.radians(yaw_deg) / 2
    qz = np.array([0.0, 0.0, np.sin(half), np.cos(half)])  # xyzw
    for line in gt_file.read_text().splitlines():
        if line.startswith("seq:"):
            current = int(line.split(":")[1])
            continue
        parts = line.split()
        if current != seq or len(parts) != 8:
            continue
        t, x, y, z, *q = map(float, parts)
        x1, y1, z1, w1 = q
        x2, y2, z2, w2 = qz
        q = [w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2, w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
             w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2, w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2]  # fmt: skip
        lines.append(f"{parts[0]} {x + shift_m:.6f} {y:.6f} {z:.6f} " + " ".join(f"{v:.9f}" for v in q))
    return ("\n".join(lines) + "\n").encode()


def test_the_ground_truth_uploaded_is_refused_and_not_ranked(tmp_path, data):
    challenge = read_challenge(challenge_file(tmp_path, data))
    assert challenge.public_groundtruth is None  # the real data root: not lorisnb's own
    gt_file = data.root / "openloris-scene" / "groundtruth" / "gt_cafe_1.txt"
    app = create_app(challenge)
    engine = app.state.server.engine
    tokens = {t: store.add_team(engine, t, time.time() + 7000) for t in ("copier", "positions", "honest")}
    uploads = {
        "copier": [("files", ("gtcopy.txt", gt_file.read_bytes()))],  # the adversarial pass's upload
        # cafe-1's positions, as TUM, every orientation turned by 5 degrees (correct at phi 30: CR 1)
        "positions": [("files", ("cafe-1-1.txt", _tum_of_sequence(gt_file, 1, yaw_deg=5.0)))],
        "honest": [("files", (p.name, p.read_bytes())) for p in cafe_files(data, "ds-slam")],
    }
    with TestClient(app) as client:
        sids = {}
        for team, files in uploads.items():
            r = client.post("/api/submissions", files=files, headers={"Authorization": f"Bearer {tokens[team]}"})
            assert r.status_code == 201, r.text
            sids[team] = r.json()["id"]
        views = {team: wait_scored(client, sid) for team, sid in sids.items()}
        for team, words in (("copier", "gtcopy.txt: cafe-1's positions and orientations"),
                            ("positions", "cafe-1-1.txt: cafe-1's positions are the ground truth's")):  # fmt: skip
            view = views[team]
            assert view["status"] == "failed" and "refused, not ranked" in view["error"], view
            assert "holds the ground truth itself" in view["error"] and words in view["error"], view["error"]
            assert "rows" not in view and str(data.root) not in view["error"]
        assert views["honest"]["status"] == "scored"
        phases = client.get("/api/leaderboard").json()["phases"]
        for _ in range(100):
            if not any(p.get("updating") for p in phases):
                break
            time.sleep(0.2)
            phases = client.get("/api/leaderboard").json()["phases"]
        dev = next(p for p in phases if p["phase"] == "development")
        assert [r["team"] for r in dev["rows"]] == ["honest"] and dev["rows"][0]["position"] == 1
        admin = store.all_submissions(engine)
        assert {s["team"]: s["status"] for s in admin} == {
            "copier": "failed",
            "positions": "failed",
            "honest": "scored",
        }


def test_copies_are_told_from_estimates_by_every_pose(data):
    """The threshold: an estimate whose positions all lie within 0.1 mm of the ground truth after
    the alignment is a copy; one moved by a millimetre at one pose is not told from a very good
    estimate (the guide says so); a real estimate is none."""
    from lorisnb.tools.evaluation.runner import evaluate

    real = evaluate([cafe_files(data, "ds-slam")[0]], data_root=data, jobs=1, progress=False)
    assert groundtruth_copies(real.errors) == []
    e = real.errors[0].sequences[0]
    copy = replace(e, ate=np.zeros(e.matched))  # positions copied, orientations the estimate's
    found = groundtruth_copies([replace(real.errors[0], sequences=[copy])])
    assert len(found) == 1 and "cafe-1's positions are the ground truth's" in found[0], found
    near = copy.ate.copy()
    near[len(near) // 2] = 10 * COPY_ATE_M  # one pose a millimetre off: not told from an estimate
    assert groundtruth_copies([replace(real.errors[0], sequences=[replace(copy, ate=near)])]) == []


def test_a_challenge_on_lorisnb_s_sample_data_says_it_is_for_practice(tmp_path, monkeypatch, capsys):
    text = (ROOT / "teaching" / "challenge" / "class.toml").read_text()
    text = re.sub(r'groundtruth = "[^"]*"', f'groundtruth = "{SAMPLE_DATA}"', text)
    text = re.sub(r'folder = "[^"]*"', f'folder = "{tmp_path / "server"}"', text)
    path = tmp_path / "class.toml"
    path.write_text(text)
    challenge = read_challenge(path)
    assert "ships with lorisnb" in challenge.public_groundtruth and "for practice" in challenge.public_groundtruth
    with TestClient(create_app(challenge, score=False)) as client:
        page = client.get("/")
        assert page.status_code == 200 and 'id="practice"' in page.text and "for practice" in page.text
        assert str(SAMPLE_DATA) not in page.text  # no server path leaves the server
        assert "for practice" in client.get("/api/leaderboard").json()["practice"]
    import uvicorn

    monkeypatch.setattr(uvicorn, "run", lambda *a, **k: None)
    assert main(["serve", str(path), "--port", "8765"]) == 0
    err = capsys.readouterr().err
    assert "note: its ground truth is lorisnb's sample data" in err and "Ground truth the teams cannot have" in err
    # the bundled class challenge is that challenge
    assert read_challenge(ROOT / "teaching" / "challenge" / "class.toml").public_groundtruth is not None


def test_a_copy_of_a_hidden_sequence_is_refused_without_its_numbers(tmp_path, data):
    """A development upload (cafe-1 shown; cafe-2 hidden until the final closes) holding cafe-2's
    ground truth was refused saying "gt2.txt: cafe-2's positions ... (all 3605 matched poses ...)":
    a number of a hidden sequence's ground truth. Said now as the file, a copy, and nothing more;
    a copy of a shown sequence keeps its detail."""
    from lorisnb.errors import ValidationError
    from lorisnb.tools.challenge.board import team_error
    from lorisnb.tools.challenge.scoring import score_folder

    challenge = read_challenge(challenge_file(tmp_path, data))
    gt = (data.root / "openloris-scene" / "groundtruth" / "gt_cafe_1.txt").read_text()
    files = tmp_path / "sub" / "files"
    files.mkdir(parents=True)
    (files / "a.txt").write_bytes(cafe_files(data, "odom")[0].read_bytes())
    (files / "gt2.txt").write_text("scene: cafe\nframe: base_link\n" + gt[gt.index("seq: 2") :])
    views = [[("cafe", 1)], [("cafe", 1), ("cafe", 2)]]  # the development phase's: cafe-2 once the final closes
    with pytest.raises(ValidationError) as refused:  # the organizer's words: the sequence, its count of poses
        score_folder(files, challenge.data, challenge.spec, views=views)
    assert re.search(r"gt2\.txt: cafe-2's positions and orientations are the ground truth's \(all \d+ matched poses",
                     str(refused.value))  # fmt: skip
    # the team's, as shown: while cafe-2 is hidden, the file and a copy alone; once shown, the detail
    sub = dict(error=str(refused.value), phase="development")
    final = challenge.phase("final")
    assert team_error(sub, challenge, final.closes - 1) == (
        "refused, not ranked: this upload holds the ground truth itself, not an estimate "
        "(gt2.txt: a copy of the ground truth). Upload your system's output")  # fmt: skip
    assert team_error(sub, challenge, final.closes + 1) == str(refused.value)
