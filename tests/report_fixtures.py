"""A lab's own results folder with trials, made from the bundled icra20 per-seq results in a
temporary folder: trial 1 is the file as published, trials 2 and 3 lose the last 10 % and 25 % of
their pose lines (a tracker that stopped early), so the trials differ the way real runs do."""

from __future__ import annotations

from pathlib import Path

#: algorithm folder -> bundled file names of cafe seq 1, cafe seq 2 and home seq 1
FILES = {
    "orb": ["cafe_1_1_orbslam2-original.txt", "cafe_1_2_orbslam2-original.txt", "home_1_1_orbslam2-original.txt"],
    "odom": ["cafe-1-1-odom.txt", "cafe-1-2-odom.txt", "home-1-1-odom.txt"],
}
SOURCE = {"orb": "orbslam2_rgbd", "odom": "odom"}
KEEP = {1: 1.0, 2: 0.9, 3: 0.75}  # share of pose lines each trial keeps


def truncated(text: str, keep: float) -> str:
    lines = text.splitlines(keepends=True)
    poses = [i for i, line in enumerate(lines) if line[:1].isdigit()]
    cut = poses[int(len(poses) * keep)] if keep < 1 else len(lines)
    return "".join(lines[:cut])


def trial_results(root: Path, icra20: Path) -> Path:
    """``root/<alg>/<scene>_<seq>_trial<k>.txt`` for the algorithms of :data:`FILES`; returns root."""
    for alg, names in FILES.items():
        for name, label in zip(names, ["cafe_1", "cafe_2", "home_1"], strict=True):
            text = (icra20 / "per-seq" / SOURCE[alg] / name).read_text()
            for k, keep in KEEP.items():
                p = root / alg / f"{label}_trial{k}.txt"
                p.parent.mkdir(parents=True, exist_ok=True)
                p.write_text(truncated(text, keep))
    return root
