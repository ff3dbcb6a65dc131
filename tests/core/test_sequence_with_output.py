"""One rule of "a sequence with output" (a matched pose, :func:`lorisnb.core.lifelong.aggregate.has_output`):
``evaluate``'s per-scene coverage, ``compare``'s (:func:`lorisnb.core.lifelong.coverage.complete`), the
report leaderboard and ``cs_r_with_output`` agree. ``evaluate`` counted a session whose estimate has
no pose in the ground truth's span as covered ("2/2") while the leaderboard said 1/2."""

from __future__ import annotations

import pytest
from helpers import write

from lorisnb.cli import main
from lorisnb.core.lifelong.coverage import complete
from lorisnb.tools.evaluation.runner import evaluate_manifest
from lorisnb.tools.report.leaderboard import findings

GT, EST = "freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"


def test_a_session_without_a_matched_pose_is_not_covered_anywhere(data, tmp_path, capsys):
    est = (data.tum / EST).read_text()
    late = "".join(  # the same run stamped an hour later: no pose inside the ground truth's span
        f"{float(line.split()[0]) + 3600:.4f} {line.split(' ', 1)[1]}\n"
        for line in est.splitlines()
        if line.strip() and not line.startswith("#")
    )
    for alg, second in (("slam", late), ("other", est)):
        write(tmp_path, f"res/{alg}/a.txt", est)
        write(tmp_path, f"res/{alg}/b.txt", second)
    m = write(tmp_path, "m.toml", f'scene = "xyz"\nroot = "{data.tum}"\n[conventions]\npreset = "tum"\n'
              f'[[session]]\nname = "a"\ngroundtruth = "{GT}"\n[[session]]\nname = "b"\ngroundtruth = "{GT}"\n')  # fmt: skip
    ev = evaluate_manifest(m, tmp_path / "res")
    table = ev.sequences()
    slam_matched = table.loc[table["algorithm"] == "slam", "matched"]
    assert slam_matched.min() == 0 and slam_matched.max() > 500
    scenes = ev.scenes()
    slam = scenes[scenes["algorithm"] == "slam"].iloc[0]
    assert (slam["sequences"], slam["sequences_with_output"], slam["scene_sequences"]) == (2, 1, 2)
    assert slam["cs_r_with_output"] == pytest.approx(2 * slam["cs_r"])  # one of two sequences has output
    _, cover = complete(table, ev.durations())
    assert dict(zip(cover["algorithm"], cover["sequences"], strict=True)) == {"slam": 1, "other": 2}
    assert cover.loc[cover["algorithm"] == "slam", "missing_seqs"].iloc[0] == "2"
    board = findings(table, ev.durations(), "cr").board
    assert dict(zip(board["algorithm"], board["coverage"], strict=True)) == {"slam": "1/2", "other": "2/2"}
    main(["evaluate", str(tmp_path / "res"), "--manifest", str(m)])
    lines = [ln for ln in capsys.readouterr().out.splitlines() if " xyz " in f" {ln} " and "/2" in ln]
    assert any(" slam " in f" {ln} " and " 1/2 " in f" {ln} " for ln in lines), lines
    assert any(" other " in f" {ln} " and " 2/2 " in f" {ln} " for ln in lines), lines


def test_a_sequence_lacking_some_trials_has_output_and_its_missing_trials_are_named():
    """With trials, a sequence one of whose trials has output is covered; the trials it lacks are
    failed runs of those trials, named as such (it was "no output for sequence(s) 1, 3, 4, 5 (1 of
    5)" for a sequence 3 that has trial 1)."""
    import pandas as pd

    from lorisnb.core.lifelong.coverage import coverage_notes

    rows = [("orb", 2, t) for t in (1, 2, 3)] + [("orb", 3, 1)] + [("vins", s, 1) for s in range(1, 6)]
    table = pd.DataFrame(
        [dict(algorithm=a, scene="home", seq=s, trial=t, matched=100, cr=0.5, gt_duration=10.0) for a, s, t in rows]
    )
    expected = pd.DataFrame(dict(scene="home", seq=range(1, 6), gt_duration=10.0))
    full, cover = complete(table, expected)
    orb = cover[cover["algorithm"] == "orb"].iloc[0]
    assert (orb["sequences"], orb["missing_seqs"], orb["missing_trials"]) == (2, "1, 4, 5", "3: 2, 3")
    added = full[(full["algorithm"] == "orb") & full["missing"]]
    assert sorted(zip(added["seq"], added["trial"], strict=True)) == [
        (s, t) for s in (1, 3, 4, 5) for t in (1, 2, 3) if (s, t) not in {(3, 1)}
    ]
    notes = coverage_notes(cover)
    assert any(
        "orb has no output for home sequence(s) 1, 4, 5 (output for 2 of its 5 sequences)" in n for n in notes
    ), notes
    assert any("orb lacks trials of home (sequence: trials) 3: 2, 3" in n for n in notes), notes
    assert cover[cover["algorithm"] == "vins"].iloc[0]["missing_trials"] == ""
