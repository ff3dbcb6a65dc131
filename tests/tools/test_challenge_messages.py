"""What the server tells a team when scoring fails: never advice on running lorisnb with other data
(``--data``, ``LORISNB_DATA``) nor the scenes the private data root holds, and no row named for no
file; the organizer's views keep the full text."""

from __future__ import annotations

import json
import time

import pytest
from challenge_fixtures import challenge_file

from lorisnb.io.datasets.paths import scene_durations
from lorisnb.tools.challenge.board import submission_view, team_text
from lorisnb.tools.challenge.config import read_challenge
from lorisnb.tools.challenge.scoring import score_folder

pytest.importorskip("fastapi")


def test_a_team_is_not_told_to_reconfigure_the_server(tmp_path, data):
    """An OpenLORIS file of office (no ground truth on the server; refused at upload since, but
    here scored directly): the failure said 'Point lorisnb at ... (--data DIR) or the LORISNB_DATA
    environment variable', listed the data root's scenes, and came with a second row named ''."""
    challenge = read_challenge(challenge_file(tmp_path, data))
    files = tmp_path / "sub" / "files"
    files.mkdir(parents=True)
    src = data.icra20 / "per-seq" / "orbslam2_rgbd" / "office_1_1_orbslam2-original.txt"
    (files / "x.txt").write_bytes(src.read_bytes())
    result = score_folder(files, challenge.data, challenge.spec)
    full = " ".join(f["error"] for f in result["failures"])
    assert "LORISNB_DATA" in full  # the organizer's text (export) keeps it
    sub = dict(id="s", team="t", phase="development", status="scored", created=time.time(), finished=time.time(),
               files=json.dumps(["x.txt"]), bytes=1, result=json.dumps(result),
               error="ground truth of scene 'office' not found: looked for <ground truth>/x (data root <ground truth>). "
                     "this data root has the ground truth of corridor, home. Point lorisnb at a folder with --data DIR")  # fmt: skip
    view = submission_view(sub, challenge, scene_durations(challenge.scenes, challenge.data), time.time())
    shown = json.dumps(view)
    for word in ("LORISNB_DATA", "--data", "data root", "corridor", "home", "market", "Point lorisnb"):
        assert word not in shown, (word, shown)
    assert [f["file"] for f in view["failures"]] == ["x.txt"]
    assert view["failures"][0]["error"] == ("office is not one of this challenge's scenes; it ranks cafe: upload "
                                            "result files of those")  # fmt: skip
    assert view["error"].startswith("office is not one of this challenge's scenes")


def test_advice_on_other_data_is_left_out(tmp_path, data):
    challenge = read_challenge(challenge_file(tmp_path, data))
    text = ("icra20_results folder not found: looked for <ground truth>/x (data root <ground truth>). Point lorisnb "
            "at a folder laid out like ../shared/data with the data_root argument (--data DIR) or the LORISNB_DATA "
            "environment variable.")  # fmt: skip
    assert team_text(text, challenge) == "icra20_results folder not found: looked for <ground truth>/x"
    assert team_text("seq 2: no pose matched.", challenge) == "seq 2: no pose matched."
    assert team_text("ground truth of scene 'cafe' not found: ...", challenge).endswith("tell the organizers")


@pytest.mark.parametrize(
    ("text", "shown"),
    [
        ("cafe-1: its AOE comes from the alignment more than from the estimate. Evaluate a longer run, or align on "
         "the first pose (--align-frames 1, align_frames=1).",
         "cafe-1: its AOE comes from the alignment more than from the estimate. Evaluate a longer run"),
        ("cafe-1: the alignment was fitted on 2 poses, so its rotation is arbitrary (the official tool aligns all the "
         "same: the numbers may differ); check this sequence's output, or evaluate it with the conventions of pairs "
         "(--align-frames 1, --align none).",
         "cafe-1: the alignment was fitted on 2 poses, so its rotation is arbitrary (the official tool aligns all the "
         "same: the numbers may differ); check this sequence's output"),
        ("no SE(3) alignment can be determined: 2 poses, so the rotation about them is arbitrary; align on more poses "
         "(--align-frames N with N >= 3 poses not on one line), on the first pose's orientation (--align-frames 1), "
         "or not at all (--align none)",
         "no SE(3) alignment can be determined: 2 poses, so the rotation about them is arbitrary"),
        ("a.txt and b.txt both hold x cafe-1, with no trial number to tell them apart; name the trials "
         "(cafe_trial1.txt, run_2/, ...) or give --trials-by REGEX (trials_by= in Python) whose group is the trial "
         "number, or evaluate them separately",
         "a.txt and b.txt both hold x cafe-1, with no trial number to tell them apart; name the trials "
         "(cafe_trial1.txt, run_2/, ...), or evaluate them separately"),
        ("x.txt: 3 stamps look like nanoseconds written without zero padding; as written they are out of order. Read "
         "with repair_stamps=True (command line --repair-stamps) to fix them; off by default so that the official "
         "tool's numbers stay reproducible",
         "x.txt: 3 stamps look like nanoseconds written without zero padding; as written they are out of order"),
        ("positions or orientations differ (by 2 deg); or not.", "positions or orientations differ (by 2 deg); or not."),
        # option advice inside a parenthesis of ';' clauses: only that clause goes, the parenthesis balanced
        ("cafe-1-1.txt: stamps in different units: the estimate's stamps look like nanoseconds (median stamp "
         "1.56e+18; a EuRoC CSV read as TUM text? --format euroc; or divide the stamps by 1e9), but the ground "
         "truth's stamps are seconds. Nothing was compared.",
         "cafe-1-1.txt: stamps in different units: the estimate's stamps look like nanoseconds (median stamp "
         "1.56e+18; divide the stamps by 1e9), but the ground truth's stamps are seconds. Nothing was compared"),
        ("x: stamps in different units: the estimate's stamps are pose indices 0, 1, 2, ... (a KITTI file read "
         "without its times: give --est-times FILE), but the ground truth's stamps are seconds; give both files "
         "their times (--est-times and --gt-times), or neither to pair two KITTI files by index. Nothing was compared.",
         "x: stamps in different units: the estimate's stamps are pose indices 0, 1, 2, ..., but the ground truth's "
         "stamps are seconds. Nothing was compared"),
        ("x: the stamps of both files look like nanoseconds (estimate: median stamp 1e+18; ground truth: median "
         "stamp 1e+18), but lorisnb's times are seconds: EuRoC CSV files read as TUM text? (--format euroc / "
         "--gt-format euroc); else divide the stamps of both by 1e9. Nothing was compared.",
         "x: the stamps of both files look like nanoseconds (estimate: median stamp 1e+18; ground truth: median "
         "stamp 1e+18), but lorisnb's times are seconds: EuRoC CSV files read as TUM text? else divide the stamps "
         "of both by 1e9. Nothing was compared"),
        ("x.txt: looks like a EuRoC CSV (--gt-format euroc for the ground truth; fmt='euroc' or lorisnb.read_euroc "
         "in Python)", "x.txt: looks like a EuRoC CSV"),
        ("seq 2: too few pairs; give a smaller delta (--rpe-frames / --rpe-metres; rpe_deltas= in Python)",
         "seq 2: too few pairs; give a smaller delta"),
        ("the step is the RPE delta (--rpe-delta with --rpe-unit; rpe_delta= and rpe_unit= in Python)",
         "the step is the RPE delta"),
        ("gt: is a folder; expected the ground truth as a TUM file (a folder is a ground truth only as a ROS 2 bag, "
         "--gt-format bag)", "gt: is a folder; expected the ground truth as a TUM file"),
        ("x: no stamps (--est-times, --gt-times or --times; stamps= in Python). Give the file of the poses' stamps "
         "there", "x: no stamps. Give the file of the poses' stamps there"),
    ],
)  # fmt: skip
def test_a_team_is_not_advised_options_it_cannot_pass(tmp_path, data, text, shown):
    """A team uploads files: the spec's options are the organizers'. Advice to pass an option
    (--align-frames, --align none, --trials-by, --repair-stamps, or their Python keywords) is left
    out of what it sees, the rest of the message kept (its other alternatives too)."""
    challenge = read_challenge(challenge_file(tmp_path, data))
    said = team_text(text, challenge)
    assert said == shown
    assert "--" not in said and "=" not in said


def test_a_parenthesis_of_option_advice_leaves_its_sentence(tmp_path, data):
    """A sentence holding option advice in a parenthesis only was dropped whole, and a scored
    file's only note became 'the server could not score this file'."""
    challenge = read_challenge(challenge_file(tmp_path, data))
    text = "home-1.txt, seq 3: the first pose is 2.1 s after the ground truth starts (see --align-frames)."
    assert team_text(text, challenge) == "home-1.txt, seq 3: the first pose is 2.1 s after the ground truth starts"
    two = "seq 2: few poses matched (pass align_frames=1 in Python); widen the bracket, or drop it (--max-gap 0)."
    assert team_text(two, challenge) == "seq 2: few poses matched; widen the bracket"


@pytest.mark.parametrize(("scale", "unit"), [(1e9, "nanoseconds"), (None, "nanoseconds")])
def test_a_stamp_unit_failure_reads_whole(tmp_path, data, scale, unit):
    """A TUM file of cafe-1 with its stamps in nanoseconds (or 1e300): the team read "...look like
    nanoseconds (median stamp 1.56e+18; Nothing was compared", cut at the ';' inside the parenthesis."""
    challenge = read_challenge(challenge_file(tmp_path, data, final_closed=True))
    rows = [line.split() for line in (data.icra20 / "per-seq" / "odom" / "cafe-1-1-odom.txt").read_text().splitlines()
            if line[:1].isdigit()]  # fmt: skip
    stamp = (lambda s: str(int(float(s) * scale))) if scale else (lambda s: "1e300")
    sub = tmp_path / "sub"
    (sub / "files").mkdir(parents=True)
    (sub / "files" / "cafe-1-1.txt").write_text("".join(" ".join([stamp(r[0]), *r[1:]]) + "\n" for r in rows))
    plain = {"cafe-1-1.txt": dict(format="tum", scene="cafe", seq=1)}
    result = score_folder(sub / "files", challenge.data, challenge.spec, plain=plain, groundtruth=tmp_path / "gt")
    [failure] = result["failures"]
    assert "--format euroc" in failure["error"]  # the organizer's text keeps the option
    said = team_text(failure["error"], challenge)
    median = "1.56e+18" if scale else "1e+300"
    assert said == (f"stamps in different units: the estimate's stamps look like {unit} (median stamp {median}; "
                    "divide the stamps by 1e9), but the ground truth's stamps are seconds. Nothing was compared")  # fmt: skip
