"""The leaderboard's account of its test: it said "paired permutation over sequences,
Holm-corrected within each scene" while the pairs are corrected as one family over every pair of
every scene of the phase (:func:`lorisnb.core.stats.inference.pairwise`); it now says what the
pairs themselves report."""

from __future__ import annotations

import json
import time

import pytest
from challenge_fixtures import challenge_file

pytest.importorskip("fastapi")

from lorisnb.io.datasets.paths import scene_durations  # noqa: E402
from lorisnb.tools.challenge.board import leaderboard  # noqa: E402
from lorisnb.tools.challenge.config import read_challenge  # noqa: E402
from lorisnb.tools.challenge.scoring import score_folder  # noqa: E402

FILES = {  # per-seq icra20 results of cafe-1, cafe-2 and home-1
    "odom": ["cafe-1-1-odom.txt", "cafe-1-2-odom.txt", "home-1-1-odom.txt"],
    "ds-slam": ["cafe-1-1.txt", "cafe-1-2.txt", " home-1-1.txt"],
    "orbslam2_rgbd": [
        "cafe_1_1_orbslam2-original.txt",
        "cafe_1_2_orbslam2-original.txt",
        "home_1_1_orbslam2-original.txt",
    ],
}


def test_the_board_says_the_holm_family_the_pairs_were_corrected_in(tmp_path, data):
    path = challenge_file(tmp_path, data, final_closed=True)
    text = path.read_text().replace(
        'name = "final"\nscenes = ["cafe"]', 'name = "final"\nscenes = ["cafe", "home"]\nsequences = { home = [1] }'
    )
    path.write_text(text)
    challenge = read_challenge(path)
    durations = scene_durations(challenge.scenes, challenge.data)
    subs = []
    for k, (team, names) in enumerate(FILES.items()):
        files = tmp_path / team / "files"
        files.mkdir(parents=True)
        for name in names:
            (files / name.strip()).write_bytes((data.icra20 / "per-seq" / team / name).read_bytes())
        result = score_folder(files, challenge.data, challenge.spec, groundtruth=tmp_path / "gt")
        assert result["failures"] == [], result["failures"]
        subs.append(dict(id=f"s{k}", team=team, team_id=k, phase="final", status="scored", created=time.time() + k,
                         result=json.dumps(result)))  # fmt: skip
    board = leaderboard(challenge, challenge.phase("final"), subs, durations, time.time())
    assert {r["scene"] for r in board["rows"]} == {"cafe", "home"}
    # 3 teams: 3 pairs in each of 2 scenes, one family of 6
    assert board["test"] == ("rank = 1 + the number of teams significantly better by paired permutation over "
                             "sequences, Holm over 6 pair(s) of 2 scene(s), alpha 0.05")  # fmt: skip
    assert "within each scene" not in board["test"]
