"""Manifest inputs (s70): a folder beside the algorithms' that holds no estimate by the manifest's
names was dropped without a word (exit 0); it is now decided as the route without a manifest
decides it (a close name: the algorithm it looks like, its sessions missing output; none: a
warning saying what it holds). A folder without files of the format asked is said to hold none of
that format, naming what it holds. A repeated session number names both sessions and which number
is implicit; two trial folders of one number (``trial1/``, ``trial01/``) are said to name one
trial; a ``trials_by`` matching no algorithm folder names the estimate files as they are on disk."""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import pytest
from helpers import run_cli as run

from lorisnb.core.stats.trials import check_duplicates
from lorisnb.errors import LorisWarning, ParseError, ValidationError
from lorisnb.io.datasets.manifest import read_manifest
from lorisnb.tools.evaluation.inputs import algorithm_folders, check_manifest_trials, result_files
from lorisnb.tools.evaluation.runner import evaluate_manifest

MANIFEST = """name = "two"
scene = "mix"
root = "gt"
[conventions]
preset = "tum"
[[session]]
name = "fr2_desk"
{seq}groundtruth = "fr2_desk.txt"
[[session]]
name = "fr1_xyz"
groundtruth = "fr1_xyz.txt"
"""


@pytest.fixture
def case(tmp_path, tum_folder) -> tuple[Path, Path, Path]:
    """(manifest, results folder, the TUM folder): ``res/orb`` holds both sessions' estimates (the
    real fr2_desk ORB and fr1_xyz RGBD-SLAM runs)."""
    (tmp_path / "gt").mkdir()
    shutil.copyfile(tum_folder / "fr2_desk_groundtruth.txt", tmp_path / "gt" / "fr2_desk.txt")
    shutil.copyfile(tum_folder / "freiburg1_xyz-groundtruth.txt", tmp_path / "gt" / "fr1_xyz.txt")
    (tmp_path / "m.toml").write_text(MANIFEST.format(seq=""))
    orb = tmp_path / "res" / "orb"
    orb.mkdir(parents=True)
    shutil.copyfile(tum_folder / "fr2_desk_ORB.txt", orb / "fr2_desk.txt")
    shutil.copyfile(tum_folder / "freiburg1_xyz-rgbdslam.txt", orb / "fr1_xyz.txt")
    return tmp_path / "m.toml", tmp_path / "res", tum_folder


def _quiet_manifest(m: Path, res: Path):
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        ev = evaluate_manifest(m, res)
    return ev, [str(x.message) for x in w if issubclass(x.category, LorisWarning)]


def test_a_folder_holding_only_a_close_name_is_the_algorithm_it_looks_like(case, capsys):
    m, res, tum = case
    (res / "crashed").mkdir()
    shutil.copyfile(tum / "fr2_desk_ORB.txt", res / "crashed" / "fr2-desk.txt")
    ev, said = _quiet_manifest(m, res)
    rows = ev.sequences().set_index(["algorithm", "seq"])
    assert rows.loc[("crashed", 1), "poses"] == 0 and rows.loc[("crashed", 1), "cr"] == 0.0
    assert rows.loc[("crashed", 2), "cr"] == 0.0
    assert rows.loc[("orb", 1), "poses"] == 2893 and rows.loc[("orb", 1), "cr"] == pytest.approx(0.85, abs=0.01)
    assert any("found fr2-desk.txt: a close name" in s for s in said)
    assert ev.exit_status() == 1
    rc, out, err = run(capsys, "evaluate", res, "--manifest", m)
    assert rc == 1
    assert "crashed" in out and "found fr2-desk.txt: a close name" in err


def test_folders_beside_the_algorithms_holding_nothing_of_theirs_are_named_with_what_they_hold(case, capsys):
    m, res, _ = case
    (res / "empty").mkdir()
    (res / "logsonly").mkdir()
    (res / "logsonly" / "run.log").write_text("segfault\n")
    (res / "orb" / "logs").mkdir()  # inside an algorithm's: not one
    with pytest.warns(LorisWarning) as w:
        folders = algorithm_folders(res, read_manifest(m))
    assert folders == [(res / "orb", res)]
    (said,) = [str(x.message) for x in w if "beside the algorithms" in str(x.message)]
    assert "2 folder(s) beside the algorithms' hold no result file" in said
    assert "they hold 1 .log file" in said and said.endswith("so they are in no table: empty, logsonly")
    rc, out, err = run(capsys, "evaluate", res, "--manifest", m)
    assert rc == 0
    assert "they hold 1 .log file), so they are in no table: empty, logsonly" in err
    assert "logs" not in err.replace("logsonly", "")


def test_no_algorithm_folder_but_a_close_name_says_the_name(case):
    m, res, tum = case
    shutil.rmtree(res / "orb")
    (res / "crashed").mkdir()
    shutil.copyfile(tum / "fr2_desk_ORB.txt", res / "crashed" / "fr2-desk.txt")
    with pytest.raises(ValidationError, match=r"no estimate named .* \(found .*crashed/fr2-desk\.txt: a close name"):
        algorithm_folders(res, read_manifest(m))


def test_a_folder_without_the_format_asked_names_what_it_holds(tmp_path, capsys):
    from tests.helpers import circle, write_bag

    res = tmp_path / "res"
    (res / "algA").mkdir(parents=True)
    (res / "algB").mkdir()
    gt = circle()
    write_bag(res / "algA" / "run.bag", gt, ros=1)
    (res / "algB" / "run.txt").write_text("1000.0 0 0 0 0 0 0 1\n")
    write_bag(tmp_path / "gt.bag", gt, ros=1)
    with pytest.warns(LorisWarning, match=r"hold no result file \(no \.bag, \.mcap or \.db3 file, the format read; "
                      r"they hold 1 \.txt file\), so they are in no table: algB$"):  # fmt: skip
        result_files([res], (".bag", ".mcap", ".db3"))
    rc, out, err = run(capsys, "evaluate", res, "--format", "bag", "--gt", tmp_path / "gt.bag", "--topic", "/pose",
                       "--gt-topic", "/pose")  # fmt: skip
    assert rc == 0, err
    assert "no .bag, .mcap or .db3 file, the format read; they hold 1 .txt file), so they are in no table: algB" in err
    assert "algA" in out


def test_a_repeated_session_number_names_both_sessions_and_the_implicit_one(case, capsys):
    m, res, _ = case
    m.write_text(MANIFEST.format(seq="seq = 2\n"))
    with pytest.raises(ParseError) as exc:
        read_manifest(m)
    assert exc.value.path == str(m) and exc.value.line == 8
    msg = exc.value.reason
    assert "[[session]] 1 ('fr2_desk'): seq = 2 on line 8" in msg
    assert "[[session]] 2 ('fr1_xyz'): no seq, so 2 by its position (the 2nd session)" in msg
    rc, _, err = run(capsys, "evaluate", res, "--manifest", m)
    assert rc == 2 and f"{m}, line 8: two sessions are numbered 2" in err


def test_two_trial_folders_of_one_number_are_said_to_name_one_trial(case, capsys, tum_folder):
    m, res, _ = case
    for d in ("trial1", "trial01"):
        shutil.copytree(res / "orb", res / "orb2" / d)
    shutil.rmtree(res / "orb")
    with pytest.raises(ValidationError, match=r"both name trial 1 \(trial01 and trial1 are one number\)") as exc:
        _quiet_manifest(m, res)
    assert "no trial number to tell them apart" not in str(exc.value)
    rc, _, err = run(capsys, "evaluate", res, "--manifest", m)
    assert rc == 2 and "orb2/trial01 and" in err and "both name trial 1" in err
    # the route without a manifest, and files of no trial number: as before
    flat = m.parent / "flat" / "orb"
    flat.mkdir(parents=True)
    for name in ("x_trial1.txt", "x_run_01.txt"):
        shutil.copyfile(tum_folder / "freiburg1_xyz-rgbdslam.txt", flat / name)
    rc, _, err = run(capsys, "evaluate", flat.parent, "--gt", m.parent / "gt" / "fr1_xyz.txt")
    assert rc == 2 and "both name trial 1 (run_01 and trial1 are one number)" in err

    def told(a: str, b: str, trial: int) -> str:
        with pytest.raises(ValidationError) as exc:
            check_duplicates([(a, ("", "o", "s", trial), (1,)), (b, ("", "o", "s", trial), (1,))])
        return str(exc.value)

    assert "no trial number to tell them apart" in told("o/x.txt", "o/y.txt", 0)
    assert "both name trial 0 (trial0 and trial00 are one number)" in told("o/x_trial0.txt", "o/x_trial00.txt", 0)
    assert "o/x.txt names no trial, which is read as trial 0" in told("o/x_trial0.txt", "o/x.txt", 0)
    # trial 1 read by a --trials-by (seed1/): the default tokens of other numbers are not named
    assert told("o/seed1/run_3/x.txt", "o/seed1/run_4/x.txt", 1).endswith("both name trial 1; renumber one of them "
                                                                          "so that each trial has its own number, "
                                                                          "or evaluate them separately")  # fmt: skip


def test_a_trials_by_matching_no_folder_names_the_estimate_files(case, capsys):
    m, res, _ = case
    for d in ("seed1", "seed2"):
        shutil.copytree(res / "orb", res / "algo" / d)
    shutil.rmtree(res / "orb")
    manifest = read_manifest(m)
    folders = algorithm_folders(res, manifest)
    check_manifest_trials(folders, manifest, r"seed(\d+)")  # matches: no error
    with pytest.raises(ValidationError) as exc:
        check_manifest_trials(folders, manifest, r"zzz(\d+)")
    msg = str(exc.value)
    assert f"{res / 'algo' / 'seed1' / 'fr2_desk.txt'}" in msg and "/x" not in msg.replace(str(res), "")
    assert "2 algorithm folder(s) and 4 estimate file(s)" in msg
    rc, _, err = run(capsys, "evaluate", res, "--manifest", m, "--trials-by", r"zzz(\d+)", "--no-progress")
    assert rc == 2 and "2 algorithm folder(s) and 4 estimate file(s)" in err  # the command's route names them too
    assert "seed1/x" not in err and "seed1/fr2_desk.txt" in err
