"""Folders whose names hold a trial token beside other text (``slam_run1/``, ``slam_run2/``) are read
as trials of one name (``slam``): the convention stays (``orbslam2_run1/`` is a trial), and it is
said, with how to number the trials otherwise (issue s67). A folder that is the token alone
(``run_2/``) says what it is and is not named."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.stats.trials import trial_folders
from lorisnb.tools.decisions.runs import load_run


def test_folders_read_as_trials_of_one_name_are_named():
    notes = trial_folders(["slam_run1/cafe1-1.txt", "slam_run2/cafe1-1.txt", "run_1/x.txt", "orb/cafe_trial2.txt",
                           "algs/orbslam2_run1/a.txt", "algs/orbslam2_run2/a.txt"])  # fmt: skip
    assert len(notes) == 2
    assert notes[0].startswith("the folder(s) slam_run1/, slam_run2/ were read as trial(s) 1, 2 of one name, slam")
    assert "--trials-by REGEX" in notes[0]
    assert notes[1].startswith("the folder(s) orbslam2_run1/, orbslam2_run2/ were read as trial(s) 1, 2 of one "
                               "name, algs/orbslam2")  # fmt: skip
    assert trial_folders(["run_1/a.txt", "run_2/a.txt", "orb/cafe-trial-3.txt", "cafe1-1.txt"]) == []
    assert trial_folders(["slam_run1/a.txt", "slam_run2/a.txt"], r"^x(\d+)") == []  # the user's pattern numbers


@pytest.fixture(scope="module")
def merged(icra20, tmp_path_factory) -> Path:
    """Two real systems' outputs kept as slam_run1/ (orbslam2_rgbd) and slam_run2/ (vins), as the
    evaluation reads them: one algorithm, slam, trials 1 and 2, in a table."""
    root = tmp_path_factory.mktemp("names")
    for k, alg in ((1, "orbslam2_rgbd"), (2, "vins_mono_color_imu_with_loop")):
        (root / f"slam_run{k}").symlink_to(icra20 / "per-seq" / alg, target_is_directory=True)
    table = ln.evaluate(root, progress=False).sequences()
    assert set(table["algorithm"]) == {"slam"} and set(table["trial"]) == {1, 2}  # the convention, kept
    out = root.parent / "merged.csv"
    table.to_csv(out, index=False)
    return out


def test_a_run_read_as_trials_of_one_name_says_so_in_python_and_on_the_command_line(merged, capsys):
    run = load_run(merged)
    assert any("slam_run1/, slam_run2/ were read as trial(s) 1, 2 of one name, slam" in n for n in run.notes)
    main(["diff", str(merged), str(merged), "--no-progress"])
    out = capsys.readouterr()
    said = out.out + out.err
    assert "note: " in said and "slam_run1/, slam_run2/ were read as trial(s) 1, 2 of one name, slam" in said
    assert pd.read_csv(merged)["file"].str.startswith("slam_run").all()


def test_an_evaluation_says_which_folders_it_read_as_trials(icra20, tmp_path, capsys):
    """lorisnb evaluate and ln.evaluate of slam_run1/ and slam_run2/ (two systems' outputs) say they
    were read as trials 1 and 2 of slam (the evaluation merged them unsaid)."""
    for k, alg in ((1, "orbslam2_rgbd"), (2, "vins_mono_color_imu_with_loop")):
        (tmp_path / f"slam_run{k}").mkdir()
        src = icra20 / "per-seq" / alg
        name = sorted(p.name for p in src.glob("cafe*1*1*.txt") if p.is_file())[0]
        (tmp_path / f"slam_run{k}" / name).write_bytes((src / name).read_bytes())
    said = "slam_run1/, slam_run2/ were read as trial(s) 1, 2 of one name, slam"
    with pytest.warns(ln.LorisWarning, match="slam_run1/, slam_run2/ were read as trial"):
        ev = ln.evaluate(tmp_path, progress=False)
    assert any(said in n for n in ev.notes)
    assert main(["evaluate", str(tmp_path), "--no-progress"]) == 0
    assert said in capsys.readouterr().err
    plain = tmp_path.parent / f"{tmp_path.name}_plain"
    for k in (1, 2):  # folders that are the token alone say what they are: no note
        (plain / "slam" / f"run_{k}").mkdir(parents=True)
        for f in (tmp_path / f"slam_run{k}").iterdir():
            (plain / "slam" / f"run_{k}" / f.name).write_bytes(f.read_bytes())
    assert not any("were read as trial" in n for n in ln.evaluate(plain, progress=False).notes)


def test_a_manifest_evaluation_says_which_folders_it_read_as_trials(data, tmp_path):
    """A manifest's algorithm folders slam_run1/ and slam_run2/ are trials 1 and 2 of slam, as a
    folder of result files is: said in the evaluation's notes, as ln.evaluate says it."""
    gt, est = data.tum / "freiburg1_xyz-groundtruth.txt", data.tum / "freiburg1_xyz-rgbdslam.txt"
    if not gt.is_file() or not est.is_file():
        pytest.skip("no tum-rgbd data")
    (tmp_path / "gt.txt").write_bytes(gt.read_bytes())
    for k in (1, 2):
        (tmp_path / "res" / f"slam_run{k}").mkdir(parents=True)
        (tmp_path / "res" / f"slam_run{k}" / "a.txt").write_bytes(est.read_bytes())
    (tmp_path / "m.toml").write_text('name = "t"\nscene = "s"\ngroundtruth_format = "tum"\nestimate_format = "tum"\n'
                                     '[[session]]\nname = "a"\ngroundtruth = "gt.txt"\n')  # fmt: skip
    with pytest.warns(ln.LorisWarning, match="slam_run1/, slam_run2/ were read as trial"):
        ev = ln.evaluate_manifest(tmp_path / "m.toml", tmp_path / "res")
    assert any("slam_run1/, slam_run2/ were read as trial(s) 1, 2 of one name, slam" in n for n in ev.notes)
