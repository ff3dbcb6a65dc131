"""A trial folder that holds no result file (the trial's run wrote nothing, or its files were not
copied) is a failed input. Every algorithm lacked it, so ``compare`` inferred the expected trials
from the others and passed with exit 0 on two trials of three; now the folder is among the
failures, named with what it holds, and every command exits 1. A folder named like a trial beside
files that carry their trial in their own names (logs) is no trial folder. Real data: icra20
results laid out as trials."""

from __future__ import annotations

import shutil

import pandas as pd
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


def test_compare_counts_an_empty_trial_folder_as_a_failed_run_of_every_sequence(tmp_path, icra20, data):
    """An empty ``odom/run_3/`` is odom's trial 3 without output: a failed run of every sequence
    (CR 0, its duration counted), as a trial 3 that wrote one file scored below one that wrote none
    before (0.197 against 0.271 in a helper's tree). Its peer is expected three trials too."""
    from lorisnb.tools.decisions.comparison import compare_table

    res = tmp_path / "res"
    _trials(res, icra20, "below")
    ev = ln.evaluate(res, data_root=data)
    two = compare_table(ev.sequences(), ev.durations())
    (res / "odom" / "run_3").mkdir()
    with pytest.warns(FailedInputsWarning):
        ev = ln.evaluate(res, data_root=data)
    assert ev.failures[0].trials == (("", "odom", 3),)
    three = compare_table(ev.sequences(), ev.durations(), lost=[t for f in ev.failures for t in f.trials])
    before, after = (r.algorithms.set_index("algorithm")["value"] for r in (two, three))
    assert after.to_dict() == pytest.approx((before * 2 / 3).to_dict(), rel=1e-9)
    assert three.exit_status == 1 and any("odom" in x and "3" in x for x in three.lacking)


def test_a_trial_named_in_the_folder_and_the_file_is_one_trial(tmp_path, icra20, data):
    """``orb/trial2/home_1_1_trial2.txt``: each trial was read as an algorithm ``trial2`` (the
    folder's token stayed in the path); two different numbers are refused, naming both."""
    res = tmp_path / "res"
    src = next((icra20 / "per-seq" / "odom").glob("home*1*1*.txt"))
    for k in (1, 2):
        (res / "odom" / f"trial{k}").mkdir(parents=True)
        shutil.copy(src, res / "odom" / f"trial{k}" / f"home-1-1_trial{k}.txt")
    table = ln.evaluate(res, data_root=data).sequences()
    assert set(table["algorithm"]) == {"odom"} and sorted(table["trial"]) == [1, 2]
    shutil.move(res / "odom" / "trial2" / "home-1-1_trial2.txt", res / "odom" / "trial2" / "home-1-1_trial5.txt")
    with pytest.raises(ln.ValidationError, match=r"names two trials, 'trial2' \(trial 2\) and 'trial5' \(trial 5\)"):
        ln.evaluate(res, data_root=data)


def test_a_file_linked_into_each_trial_folder_is_a_copy_in_each_not_a_crash(tmp_path, icra20, data):
    """Links to one file in trial1/ to trial3/ were counted once (as one input named three times),
    so trials 2 and 3 became failed runs and a pair was called significant; each link is a trial
    now, and the trials are copies of one run, counted once, as byte copies are."""
    from lorisnb.tools.decisions.comparison import compare_table

    res = tmp_path / "res"
    (res / "keep").mkdir(parents=True)
    src = next((icra20 / "per-seq" / "odom").glob("home*1*1*.txt"))
    shutil.copy(src, res / "keep" / "home-1-1.txt")
    for k in (1, 2, 3):
        (res / "odom" / f"trial{k}").mkdir(parents=True)
        (res / "odom" / f"trial{k}" / "home-1-1.txt").symlink_to(res / "keep" / "home-1-1.txt")
    ev = ln.evaluate(res / "odom", data_root=data)
    assert sorted(ev.sequences()["trial"]) == [1, 2, 3] and ev.exit_status() == 0
    assert compare_table(ev.sequences(), ev.durations()).lacking == ()


def test_trial_folders_given_as_inputs_are_told_to_give_their_parent(tmp_path, icra20, data):
    """``compare ab/trial1 ab/trial2`` was told to name the trials or give --trials-by, which
    fails too (trial tokens are read below the folders given)."""
    src = next((icra20 / "per-seq" / "odom").glob("home*1*1*.txt"))
    for k in (1, 2):
        (tmp_path / f"trial{k}" / "odom").mkdir(parents=True)
        shutil.copy(src, tmp_path / f"trial{k}" / "odom" / src.name)
    with pytest.raises(ln.ValidationError, match=r"\(trial1, trial2\) are in the names of the folders given"):
        ln.evaluate([tmp_path / "trial1", tmp_path / "trial2"], data_root=data)
    assert sorted(ln.evaluate(tmp_path, data_root=data).sequences()["trial"]) == [1, 2]


def test_trials_expected_say_where_the_peer_has_them(icra20):
    """B (two trials) was told to expect 3 'as A has in this scene' where A had trial 3 in another
    scene only (and was itself told it lacks trial 3 there)."""
    from lorisnb.core.lifelong.coverage import complete

    ev = ln.evaluate([icra20 / "per-seq" / "odom", icra20 / "per-seq" / "orbslam2_rgbd"], progress=False)
    t = ev.sequences()
    t = t[t["scene"].isin(["cafe", "home"])]
    a, b = (t[t["algorithm"] == x] for x in ("odom", "orbslam2_rgbd"))
    rows = [a.assign(trial=k) for k in (1, 2)] + [a[a["scene"] == "home"].assign(trial=3)]
    rows += [b.assign(trial=k) for k in (1, 2)]
    _, cover = complete(pd.concat(rows, ignore_index=True), ev.durations(), peers=True)
    why = cover.set_index(["algorithm", "scene"])["trials_expected"]
    assert why["orbslam2_rgbd", "cafe"] == "3, as odom has in the scenes of its suite"
    assert why["orbslam2_rgbd", "home"] == "3, as odom has in this scene"
