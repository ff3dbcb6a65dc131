"""A trial folder that holds no result file (the trial's run wrote nothing, or its files were not
copied) is a failed input. Every algorithm lacked it, so ``compare`` inferred the expected trials
from the others and passed with exit 0 on two trials of three; now the folder is among the
failures, named with what it holds, and every command exits 1. A folder named like a trial beside
files that carry their trial in their own names (logs) is no trial folder. Real data: icra20
results laid out as trials."""

from __future__ import annotations

import shutil

import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import FailedInputsWarning


def _trials(res, icra20, layout: str, trials=(1, 2)) -> None:
    for k in trials:
        for alg, name in (("odom", "home-1-1.txt"), ("orbslam2_rgbd", "home-1-1.txt")):
            src = next((icra20 / "per-seq" / alg).glob("home*1*1*.txt"))
            where = res / f"trial{k}" / alg if layout == "above" else res / alg / f"run_{k}"
            where.mkdir(parents=True, exist_ok=True)
            shutil.copy(src, where / name)


@pytest.mark.parametrize("layout", ["above", "below"])
def test_an_empty_trial_folder_is_a_failed_input(tmp_path, icra20, data, layout):
    res = tmp_path / "res"
    _trials(res, icra20, layout)
    empty = res / "trial3" if layout == "above" else res / "odom" / "run_3"
    empty.mkdir()
    (empty / "crash.log").write_text("segfault\n")
    with pytest.warns(FailedInputsWarning, match=r"1 of 5 inputs could not be evaluated"):
        ev = ln.evaluate(res, data_root=data)
    assert [(f.path, f.kind) for f in ev.failures] == [(empty, "empty-trial")]
    assert "it holds 1 .log file" in ev.failures[0].error
    assert ev.exit_status() == 1
    assert sorted(set(ev.sequences()["trial"])) == [1, 2]  # the tables hold what was read


def test_compare_and_evaluate_exit_1_and_name_the_folder(tmp_path, icra20, data, capsys):
    res = tmp_path / "res"
    _trials(res, icra20, "above")
    (res / "trial3" / "odom").mkdir(parents=True)  # the topmost empty trial folder is named, not its algorithm
    for command in ("evaluate", "compare"):
        assert main([command, str(res), "--data", str(data.root), "--no-progress"]) == 1
        err = capsys.readouterr().err
        assert f"error: {res / 'trial3'}: a trial folder that holds no result file" in err
        assert "beside the algorithms" not in err


def test_full_trials_and_log_folders_are_no_failure(tmp_path, icra20, data):
    res = tmp_path / "res"
    _trials(res, icra20, "above", trials=(1, 2, 3))
    ev = ln.evaluate(res, data_root=data)
    assert ev.failures == [] and ev.exit_status() == 0
    files = tmp_path / "files"  # trials in the file names: a run_1/ of logs beside them is no trial
    (files / "odom" / "run_1").mkdir(parents=True)
    (files / "odom" / "run_1" / "log.txt.bak").write_text("x\n")
    src = next((icra20 / "per-seq" / "odom").glob("home*1*1*.txt"))
    for k in (1, 2):
        shutil.copy(src, files / "odom" / f"home-1-1_trial{k}.txt")
    ev = ln.evaluate(files, data_root=data)
    assert ev.failures == [] and ev.exit_status() == 0
