"""The command line as a CI script or a lab's nightly job uses it, on the real OpenLORIS results:
what each mistake did before (a plausible result with exit status 0, a silently dropped option,
a file replaced) and what it does now."""

from __future__ import annotations

import os
import shutil
import time
from pathlib import Path

import pandas as pd
import pytest
from helpers import as_trials

from lorisnb.cli import main

ORB = "per-seq/orbslam2_rgbd"
HOME = [f"home_1_{k}_orbslam2-original.txt" for k in range(1, 6)]
CAFE = [f"cafe_1_{k}_orbslam2-original.txt" for k in (1, 2)]


def _results(icra20: Path, root: Path, files: list[str], half: str | None = None) -> Path:
    """A results folder ``root/orb/`` of real ORB-SLAM2 files; ``half``: that file cut to its first
    half of lines (a run that lost track earlier: its CR drops)."""
    (root / "orb").mkdir(parents=True)
    for name in files:
        text = (icra20 / ORB / name).read_text()
        if name == half:
            lines = text.splitlines(keepends=True)
            text = "".join(lines[: len(lines) // 2])
        (root / "orb" / name).write_text(text)
    return root


def _rc(argv: list[str | Path]) -> int:
    try:
        return main([str(a) for a in argv])
    except SystemExit as exc:  # argparse's usage errors
        return int(exc.code or 0)


@pytest.mark.thorough
def test_history_tells_apart_nightly_tables_of_one_file_name(icra20, data, tmp_path, capsys):
    """A nightly job writes ``<date>/sequences.csv``: history named every run ``sequences.csv``,
    so the three runs became one column whose cells were arrays, the history CSV's ``run`` column
    could not tell them apart, and the scene value printed was the mean of the three runs. Each
    run is now named by as much of its path as tells it apart, with its own values."""
    good = _results(icra20, tmp_path / "good", HOME)
    worse = _results(icra20, tmp_path / "worse", HOME, half="home_1_4_orbslam2-original.txt")
    nights = []
    for k, results in enumerate((good, worse, good), start=1):
        table = tmp_path / f"night{k}" / "sequences.csv"
        table.parent.mkdir()
        assert _rc(["evaluate", results, "--data", data.root, "--no-progress", "--jobs", "1", "--csv", table]) == 0
        as_trials(table)  # three trials a night around the night's values
        stamp = time.time() - 86400 * (4 - k)  # ordered by modification time: night 1 oldest
        os.utime(table, (stamp, stamp))
        nights.append(table)
    capsys.readouterr()
    hist = tmp_path / "history.csv"
    rc = _rc(["history", *nights, "--metric", "cr", "--csv", hist])
    out = capsys.readouterr().out
    assert _rc(["diff", nights[1], nights[2]]) == rc  # the newest night against its baseline, as diff says
    capsys.readouterr()
    assert "night1/sequences.csv" in out and "night3/sequences.csv" in out and "[" not in out
    h = pd.read_csv(hist)
    assert list(h["run"]) == ["night1/sequences.csv", "night2/sequences.csv", "night3/sequences.csv"]
    assert h["value"].round(4).tolist() == [0.2712, 0.2290, 0.2712]  # home CR of each night, as evaluate prints it
    assert h["changed"].tolist() == [False, True, True] and h["first_change"].tolist() == [False, True, False]
    assert h["baseline"].fillna("").tolist() == ["", "night1/sequences.csv", "night2/sequences.csv"]
    assert (
        "orb home cr: first change in night2/sequences.csv against night1/sequences.csv (0.2712 -> 0.2290, worse)"
        in out
    )


@pytest.mark.parametrize(
    "argv, said",
    [
        (["history", "a.csv", "b.csv", "--metric", "cr", "--metric", "cs_r"], "--metric given twice"),
        (["history", "a.csv", "b.csv", "--metric", "cr", "cr"], "--metric: cr given twice in cr cr"),
        (["evaluate", "x", "--scale", "auto", "--scale", "off"], "--scale given twice"),
        (
            ["evaluate", "x", "--motion-filter", "0.1", "5", "--motion-filter", "0.2", "5"],
            "--motion-filter given twice",
        ),
        (["report", "--notebooks", "a", "b", "--notebooks", "c"], "--notebooks given twice"),
    ],
)
def test_an_option_of_several_values_given_twice_is_refused(argv, said, capsys):
    """``history --metric cr --metric cs_r`` followed cs_r alone (argparse keeps the last),
    ``--metric cr cr`` printed and wrote every cr row twice, ``--scale auto --scale off`` scored
    without a scale: all with exit status 0. Options of several values (or an optional value) are
    now refused when repeated, as options of one value are."""
    assert _rc(argv) == 2
    err = capsys.readouterr().err
    assert said in err
    assert "comma-separated" not in err  # the hint of lists written as one value is not theirs


def test_several_metrics_after_one_option_are_followed(icra20, data, tmp_path, capsys):
    results = _results(icra20, tmp_path / "r", CAFE)
    table = tmp_path / "t.csv"
    assert _rc(["evaluate", results, "--data", data.root, "--no-progress", "--jobs", "1", "--csv", table]) == 0
    capsys.readouterr()
    again = tmp_path / "t2.csv"  # a second night: with one run history judges nothing (exit 2)
    again.write_bytes(table.read_bytes())
    os.utime(again, (table.stat().st_mtime + 60,) * 2)
    assert _rc(["history", table, again, "--metric", "cr", "cs_r"]) == 0
    out = capsys.readouterr().out
    assert "cr per scene:" in out and "cs_r per scene:" in out and "cr_t per scene:" not in out


def test_diff_verdict_files_need_their_suffix(icra20, data, tmp_path, capsys):
    """``diff --json notes.txt --force`` replaced a file of the user's with the verdict, and
    ``--junit verdict.json`` wrote XML into a .json file; both are now refused before anything is
    read, and the file is left as it was."""
    base = _results(icra20, tmp_path / "base", CAFE)
    tb, tc = tmp_path / "b.csv", tmp_path / "c.csv"
    for table in (tb, tc):
        assert _rc(["evaluate", base, "--data", data.root, "--no-progress", "--jobs", "1", "--csv", table]) == 0
    notes = tmp_path / "notes.txt"
    notes.write_text("my notes\n")
    capsys.readouterr()
    assert _rc(["diff", tb, tc, "--json", notes, "--force"]) == 2
    assert "--json" in capsys.readouterr().err and notes.read_text() == "my notes\n"
    assert _rc(["diff", tb, tc, "--junit", tmp_path / "verdict.json"]) == 2
    assert "expected a .xml file name" in capsys.readouterr().err
    assert not (tmp_path / "verdict.json").exists()
    assert _rc(["diff", tb, tc, "--json", tmp_path / "V.JSON", "--junit", tmp_path / "v.xml"]) == 0
    assert (tmp_path / "V.JSON").is_file() and (tmp_path / "v.xml").is_file()


def _data_root_without(data, tmp_path: Path, scene: str) -> Path:
    """A data root like the real one whose ground truth of ``scene`` is missing (a partial copy)."""
    root = tmp_path / "partial data"
    gt = root / "openloris-scene" / "groundtruth"
    gt.mkdir(parents=True)
    (root / "openloris-scene" / "icra20_results").mkdir()
    for f in (data.root / "openloris-scene" / "groundtruth").glob("gt_*_1.txt"):
        if f.name != f"gt_{scene}_1.txt":
            os.symlink(f, gt / f.name)
    return root


def test_a_scene_whose_ground_truth_is_missing_from_the_data_is_not_scored(icra20, data, tmp_path, capsys):
    """A data root without ``gt_cafe_1.txt`` (a partial copy, a renamed file): every cafe file was
    skipped and left out of the table, the run exited 0, as for office (whose ground truth was
    never published). Such files now count as not scored: exit status 1, a ``not scored:`` line
    naming the missing file; office files are still skipped without counting."""
    results = _results(icra20, tmp_path / "results", CAFE + HOME)
    partial = _data_root_without(data, tmp_path, "cafe")
    argv = ["evaluate", results, "--no-progress", "--jobs", "1"]
    assert _rc([*argv, "--data", partial]) == 1
    cap = capsys.readouterr()
    assert "cafe" not in cap.out and "home" in cap.out  # the table holds what was scored
    lines = [x for x in cap.err.splitlines() if x.startswith("not scored:")]
    assert len(lines) == 2 and all("ground truth of scene 'cafe' not found" in x for x in lines)
    assert all("gt_cafe_1.txt" in x for x in lines)
    assert "5 file(s) evaluated, 0 failed, 2 not scored, 0 skipped" in cap.err
    assert _rc([*argv, "--data", data.root]) == 0  # the same files with the whole data: all scored
    capsys.readouterr()

    # office: no public ground truth, skipped as before, exit 0
    shutil.copy(icra20 / ORB / "office_1_1_orbslam2-original.txt", results / "orb")
    assert _rc([*argv, "--data", data.root]) == 0
    err = capsys.readouterr().err
    assert "skipped 1 file(s): ground truth of scene 'office' not found" in err and "not scored:" not in err
    assert "7 file(s) evaluated, 0 failed, 0 not scored, 1 skipped" in err

    # diff of two runs over the partial data: cafe compared in neither, so not a clean 0
    assert _rc(["diff", results, results, "--data", partial, "--no-progress", "--jobs", "1"]) == 1
    err = capsys.readouterr().err
    assert "2 input(s) of BASE and 2 of CAND could not be evaluated or were not scored" in err


def test_an_output_that_cannot_be_written_is_an_output_error(icra20, data, tmp_path, monkeypatch, capsys):
    """``--csv /proc/x.csv`` (any place the system refuses though ``os.access`` says yes, as it
    does to root) evaluated everything, then ended in a traceback with exit status 1, which a
    script reads as "an input failed". Now refused before any work (exit 2); a write failing
    later (a full disk) is one ``error:`` line with exit status 2, never a traceback."""
    results = _results(icra20, tmp_path / "r", CAFE)
    argv = ["evaluate", results, "--data", data.root, "--no-progress", "--jobs", "1"]
    if Path("/proc/self").is_dir():
        assert _rc([*argv, "--csv", "/proc/lorisnb-probe.csv"]) == 2
        cap = capsys.readouterr()
        assert "cannot write /proc/lorisnb-probe.csv" in cap.err and cap.out == ""  # before any work

    import lorisnb.io.writers as writers

    def full_disk(table, out, force=False):
        raise OSError(28, "No space left on device", str(out))

    monkeypatch.setattr(writers, "write_csv", full_disk)
    out = tmp_path / "t.csv"
    assert _rc([*argv, "--csv", out]) == 2
    err = capsys.readouterr().err
    assert f"error: {out}: No space left on device" in err and "Traceback" not in err
    assert not out.exists()


def test_an_unreadable_file_among_good_ones_is_said_once_on_the_command_line(icra20, data, tmp_path, capsys):
    """One broken file among good ones: exit status 1, the good files' rows on stdout, and on
    stderr one ``error:`` line naming the file and line; the Python callers' warning
    (``Evaluation.failures lists them ..., exit_status() is 1``) said it a second time, in terms
    of an API the command line's user does not call."""
    results = _results(icra20, tmp_path / "r", CAFE + HOME)
    (results / "orb" / HOME[2]).write_text("garbage\n")
    for extra in ([], ["--csv", tmp_path / "t.csv"]):
        assert _rc(["evaluate", results, "--data", data.root, "--no-progress", "--jobs", "1", *extra]) == 1
        cap = capsys.readouterr()
        assert sum(name in cap.out for name in CAFE + HOME) == 6 and HOME[2] not in cap.out
        assert [x for x in cap.err.splitlines() if HOME[2] in x] == [
            f"error: {results / 'orb' / HOME[2]}, line 1: 'garbage' has 1 fields; expected 8 or 9 numbers 'stamp "
            "[output_time] x y z qx qy qz qw', a 'key: value' line, a 'seq: N' line or a '#' comment"
        ]
        assert "Evaluation.failures" not in cap.err and "6 file(s) evaluated, 1 failed" in cap.err


@pytest.mark.thorough
def test_diff_prints_with_digits_and_names_a_real_regression(icra20, data, tmp_path, capsys):
    """``diff --digits N`` was refused with two tables ("evaluate options apply to result
    folders": it computes nothing) and ignored with two folders (4 decimals always). A run that
    lost track earlier on home 4 (its file cut in half) is a regression with exit status 1 and a
    line per metric; the same change the other way is an improvement of CR, not a failure of CR."""
    good = _results(icra20, tmp_path / "good", HOME)
    worse = _results(icra20, tmp_path / "worse", HOME, half="home_1_4_orbslam2-original.txt")
    tg, tw = tmp_path / "good.csv", tmp_path / "worse.csv"
    for results, table in ((good, tg), (worse, tw)):
        assert _rc(["evaluate", results, "--data", data.root, "--no-progress", "--jobs", "1", "--csv", table]) == 0
        as_trials(table)  # three trials a sequence around the same values: judged by the test, not the rerun band
    capsys.readouterr()
    assert _rc(["diff", tg, tw, "--digits", "2"]) == 1
    out = capsys.readouterr().out.splitlines()
    assert [x.split() for x in out if " home    4 " in x] == [
        ["orb", "home", "4", "cr", "0.53", "0.27", "0.26", "0.02", "regression"],
        ["orb", "home", "4", "cr_t", "0.53", "0.27", "0.26", "0.02", "regression"],
    ]
    assert "verdict: regression (1 sequence(s) regressed: orb home-4 cr, cr_t)" in out  # named, not only counted
    # two result folders are single runs: the halved sequence is no regression there (a single run can
    # tell only a sequence that stopped tracking from rerun noise), but the digits are the same
    assert _rc(["diff", good, worse, "--data", data.root, "--no-progress", "--jobs", "1", "--digits", "6"]) == 0
    cap = capsys.readouterr()
    assert "one run per side" in cap.out
    said = [x.split(":")[0] for x in cap.err.splitlines() if x.startswith("conventions")]
    assert said == [f"conventions of {good}", f"conventions of {worse}"]  # which run each line is about
    assert _rc(["diff", tw, tg, "--tolerance", "ate_rmse=50%,aoe_rmse=100%,c_ate_rmse=50%,c_aoe_rmse=100%,"
                "rpe_rot_rmse=50%"]) == 0  # fmt: skip
    out = capsys.readouterr().out
    assert "verdict: ok" in out and "improvement" in out


@pytest.mark.thorough
def test_history_says_when_a_run_lost_a_scene(icra20, data, tmp_path, capsys):
    """A nightly run that scored cafe but lost every home file (its job died half-way): history
    printed NaN in the table and "no value changed beyond its tolerance", where ``diff`` of the
    same two runs is a regression. The scene's value going missing is now its first change."""
    full = _results(icra20, tmp_path / "full", CAFE + HOME)
    cafe = _results(icra20, tmp_path / "cafe", CAFE)
    nights = []
    for k, results in enumerate((full, cafe, full), start=1):
        table = tmp_path / f"n{k}.csv"
        assert _rc(["evaluate", results, "--data", data.root, "--no-progress", "--jobs", "1", "--csv", table]) == 0
        stamp = time.time() - 86400 * (4 - k)
        os.utime(table, (stamp, stamp))
        nights.append(table)
    capsys.readouterr()
    assert _rc(["diff", nights[0], nights[1]]) == 1  # diff: five home sequences missing
    capsys.readouterr()
    hist = tmp_path / "history.csv"
    assert _rc(["history", *nights, "--metric", "cr", "c_ate_rmse", "--csv", hist]) == 0
    out = capsys.readouterr().out
    assert "orb home cr: first change in n2.csv against n1.csv (0.2712 -> no value, a sequence or trial lost)" in out
    assert (
        "orb home c_ate_rmse: first change in n2.csv against n1.csv (0.1414 -> no value, a sequence or trial lost)"
        in out
    )
    assert "cafe" not in "".join(x for x in out.splitlines() if "first change" in x)  # cafe did not change
    h = pd.read_csv(hist)
    home = h[(h["scene"] == "home") & (h["metric"] == "cr")]
    assert home["run"].tolist() == ["n1.csv", "n2.csv", "n3.csv"]
    assert home["value"].round(4).tolist()[::2] == [0.2712, 0.2712] and home["value"].isna().tolist()[1]
    assert home["changed"].tolist() == [False, True, False]


def test_sweep_writes_the_relation_it_names(data, tmp_path, capsys):
    """``sweep --relation trans_part`` named the relation in its ``conventions:`` line but wrote
    none of its columns (``ape_*``, ``rpe_*`` of evo's pose relation): the option was dropped.
    Each sweep row now carries them, equal to ``evaluate --relation``'s, in CSV and Parquet."""
    tum = data.root / "tum-rgbd"
    results = tmp_path / "r" / "orb"
    results.mkdir(parents=True)
    shutil.copy(tum / "fr2_desk_ORB.txt", results)
    argv = [results.parent, "--gt", tum / "fr2_desk_groundtruth.txt", "--relation", "trans_part", "--no-progress"]
    ev, sw = tmp_path / "ev.csv", tmp_path / "sw.csv"
    assert _rc(["evaluate", *argv, "--csv", ev]) == 0
    assert _rc(["sweep", *argv, "--eps", "0.01,0.1", "--csv", sw]) == 0
    assert "relation" in capsys.readouterr().err
    e, s = pd.read_csv(ev), pd.read_csv(sw)
    assert len(s) == 2 and s["ape_rmse"].round(6).tolist() == [0.008171] * 2  # ORB-SLAM2 on fr2/desk, metres
    for c in ("ape_rmse", "ape_max", "rpe_rmse", "rpe_mean"):
        assert (s[c] == e[c].iloc[0]).all(), c
    pytest.importorskip("pyarrow")
    assert _rc(["sweep", *argv, "--eps", "0.01,0.1", "--parquet", tmp_path / "pq"]) == 0
    assert (pd.read_parquet(tmp_path / "pq")["ape_rmse"] == e["ape_rmse"].iloc[0]).all()


@pytest.mark.parametrize("command, option", [("compare", ["--relation", "trans_part"]),
                                             ("diff", ["--relation", "trans_part"]), ("sweep", ["--relative"])])  # fmt: skip
def test_an_option_is_refused_where_nothing_uses_it(command, option, data, tmp_path, capsys):
    """``compare --relation R`` ranked CR and ``diff --relation R`` compared CR ... RPE, exit 0,
    with a ``conventions:`` line saying ``pose relation R (ape_*, rpe_* columns)``: neither uses
    evo's relation columns; ``sweep --relative`` printed no relative error. Refused now, naming
    the command that does."""
    tum = data.root / "tum-rgbd"
    results = tmp_path / "r" / "orb"
    results.mkdir(parents=True)
    shutil.copy(tum / "fr2_desk_ORB.txt", results)
    runs = [results.parent] * (2 if command == "diff" else 1)
    argv = [command, *runs, "--gt", tum / "fr2_desk_groundtruth.txt", *option, "--no-progress"]
    assert _rc(argv) == 2
    cap = capsys.readouterr()
    assert f"{option[0]}: not used by lorisnb {command}; use lorisnb evaluate" in cap.err and cap.out == ""
