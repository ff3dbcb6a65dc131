"""Every value diff and history read from a per-sequence table passes one rule (runs.read_table):
a NaN CR hand-edited into a table is refused as CR 12.4 is, with the file and line, rather than
judged a regression worse by infinity; NaN errors stay accepted where the evaluation writes them
(no matched pose). So are the keys (seq, trial, algorithm, scene), the weights of the scene values
(ground-truth and tracked durations), the rotation lever, the yes-or-no columns and the thresholds;
a table without a column the verdict reads is refused naming it, not a KeyError."""

from __future__ import annotations

import json
import re
import shutil

import numpy as np
import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import ParseError
from lorisnb.tools.decisions.runs import load_run, read_table
from lorisnb.tools.report.provenance import KEYS


@pytest.fixture(scope="module")
def table(tmp_path_factory, icra20, data):
    root = tmp_path_factory.mktemp("res")
    for alg, name in (("orbslam2_rgbd", "cafe_1_1_orbslam2-original.txt"), ("odom", "cafe-1-1-odom.txt"),
                      ("odom", "home-1-1-odom.txt")):  # fmt: skip
        (root / alg).mkdir(exist_ok=True)
        shutil.copy(icra20 / "per-seq" / alg / name, root / alg / name)
    return ln.evaluate(root, data_root=data, progress=False).sequences()


@pytest.mark.parametrize(
    "column, value, expected",
    [
        ("cr", np.nan, "nan is not a rate between 0 and 1"),
        ("cr", 12.4, "12.4 is not a rate between 0 and 1"),
        ("cs_r", -0.1, "-0.1 is not a rate"),
        ("ate_rmse", np.nan, "nan is not an RMSE >= 0 (NaN only where matched is 0)"),
        ("ate_rmse", np.inf, "inf is not an RMSE"),
        ("c_ate_rmse", -1.0, "-1 is not an RMSE"),
        ("matched", -3, "-3 is not a count"),
        ("matched", 2.5, "2.5 is not a count"),
    ],
)
@pytest.mark.thorough
def test_a_value_no_evaluation_writes_is_refused_in_python_and_on_the_command_line(
    tmp_path, table, capsys, column, value, expected
):
    good, bad = tmp_path / "good.csv", tmp_path / "bad.csv"
    table.to_csv(good, index=False)
    edited = table.copy()
    edited[column] = edited[column].astype(float)
    edited.loc[1, column] = value
    edited.to_csv(bad, index=False)
    assert len(read_table(good)) == 3
    with pytest.raises(
        ParseError, match=f"line 3: column {column}: " + expected.replace("(", r"\(").replace(")", r"\)")
    ):
        read_table(bad)
    for command in (["diff", good, bad], ["history", good, bad]):
        rc = main([*map(str, command)])
        err = capsys.readouterr().err
        assert rc == 2 and f"{bad}, line 3: column {column}: {expected}" in err, err


def test_nan_errors_where_nothing_was_matched_are_read_as_written(tmp_path, table):
    """A sequence without a matched pose (as the evaluation writes it: CR 0, errors NaN) is read."""
    none = table.copy()
    for c in ("ate_rmse", "aoe_rmse", "c_ate_rmse", "c_aoe_rmse"):
        none.loc[0, c] = np.nan
    none.loc[0, ["matched", "c_matched", "cr", "cr_t", "cs_r"]] = 0
    none.to_csv(tmp_path / "t.csv", index=False)
    got = read_table(tmp_path / "t.csv")
    assert np.isnan(got.loc[0, "ate_rmse"]) and got.loc[0, "cr"] == 0
    assert load_run(tmp_path / "t.csv").table.shape[0] == 3


@pytest.mark.parametrize(
    "column, value, expected",
    [
        ("seq", np.nan, "nan is not a sequence number (a whole number >= 0)"),
        ("seq", "x", "'x' is not a number"),
        ("seq", 1.5, "1.5 is not a sequence number"),
        ("trial", "t", "'t' is not a number"),
        ("trial", -1, "-1 is not a trial number"),
        ("gt_duration", np.nan, "nan is not a duration in seconds (finite, >= 0)"),
        ("track_time", -5.0, "-5 is not a duration in seconds"),
        ("rotation_lever", -5.0, "-5 is not a lever in metres >= 0 (NaN only where matched is 0)"),
        ("rpe_pairs", "abc", "'abc' is not a number"),
        ("first_correct", "maybe", "'maybe' is not True or False"),
        ("official_interpolation", "maybe", "'maybe' is not True or False"),
        ("eps", -1.0, "eps=-1.0: expected a number of metres >= 0"),
        ("tau", np.nan, "tau=nan: expected a number of seconds, not NaN"),
        ("algorithm", np.nan, "an empty cell is not an algorithm name"),
        ("scene", "", "an empty cell is not a scene name"),
    ],
)
@pytest.mark.thorough
def test_every_column_the_verdict_reads_passes_the_rule(tmp_path, table, capsys, column, value, expected):
    """Keys (seq, trial, labels), the scene values' weights, the lever and flags the verdict reads,
    and the thresholds, checked as the rates are: refused with the file and line, not a regression
    judged on a NaN key, a negative weight, nor a traceback."""
    good, bad = tmp_path / "good.csv", tmp_path / "bad.csv"
    table.assign(trial=0).to_csv(good, index=False)
    edited = table.assign(trial=0)
    edited[column] = edited[column].astype(object)
    edited.loc[1, column] = value
    edited.to_csv(bad, index=False)
    with pytest.raises(ParseError, match=f"line 3: column {column}: " + re.escape(expected)):
        read_table(bad)
    for command in (["diff", good, bad], ["history", good, bad]):
        rc = main([*map(str, command)])
        err = capsys.readouterr().err
        assert rc == 2 and f"{bad}, line 3: column {column}: {expected}" in err, err


@pytest.mark.parametrize("column", ["matched", "c_matched", "gt_duration", "track_time", "cr_t", "cs_r", "c_ate_rmse"])
def test_a_table_without_a_column_the_verdict_reads_is_refused_naming_it(tmp_path, table, capsys, column):
    good, bad = tmp_path / "good.csv", tmp_path / "bad.csv"
    table.to_csv(good, index=False)
    table.drop(columns=[column]).to_csv(bad, index=False)
    with pytest.raises(ParseError, match=f"lacks column\\(s\\) {column};"):
        read_table(bad)
    for command in (["diff", good, bad], ["diff", bad, good], ["history", good, bad]):
        rc = main([*map(str, command)])
        err = capsys.readouterr().err
        assert rc == 2 and f"error: {bad}: lacks column(s) {column}" in err, err


def test_a_report_runs_table_of_durations_passes_the_rule_too(tmp_path, table):
    run = tmp_path / "run"
    (run / "findings").mkdir(parents=True)
    minimal = {k: None for k in KEYS} | {"command": [], "spec": {"values": {}}, "inputs": {}, "notebooks": {}}
    (run / "run.json").write_text(json.dumps(minimal))
    table.to_csv(run / "findings" / "sequences.csv", index=False)
    durations = table[["scene", "seq", "gt_duration"]].copy()
    durations.to_csv(run / "findings" / "durations.csv", index=False)
    assert load_run(run).expected is not None
    durations.loc[0, "gt_duration"] = np.nan
    durations.to_csv(run / "findings" / "durations.csv", index=False)
    with pytest.raises(ParseError, match="durations.csv, line 2: column gt_duration: nan is not a duration"):
        load_run(run)


def test_the_line_named_is_the_files_line_when_a_name_holds_a_newline(tmp_path, table, capsys):
    """A folder name with a newline is written as a quoted cell over two lines: the refused value's
    line is counted in the file, not as row + 2."""
    edited = table.assign(algorithm=["orb\nslam", "odom", "odom"], file=["orb\nslam/x.txt", "a.txt", "b.txt"])
    edited.loc[2, "cr"] = np.nan
    bad = tmp_path / "bad.csv"
    edited.to_csv(bad, index=False)
    assert bad.read_text().splitlines()[5].startswith("odom,b.txt")  # the header, 2 + 2 lines, then line 6
    with pytest.raises(ParseError, match="line 6: column cr: nan"):
        read_table(bad)
    rc = main(["diff", str(bad), str(bad)])
    assert rc == 2 and f"{bad}, line 6: column cr: nan" in capsys.readouterr().err
