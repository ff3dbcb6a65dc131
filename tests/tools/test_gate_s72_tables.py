"""Damaged tables are refused naming where: a ``spec`` cell that is no JSON object (it was compared as
text: the same damaged cell in both tables judged "ok", exit 0; in one table the whole JSON printed),
a damaged value of a Parquet table or dataset folder with its row and file (only CSV named its line).
A note on a table's scene values says where ``LORISNB_DATA`` points when it is set to no data root.
Tolerances: metric names in any case, and an error's tolerance that lets it double or more warned."""

from __future__ import annotations

from functools import partial

import pandas as pd
import pytest
from helpers import run_cli

from lorisnb.errors import ParseError, ValidationError
from lorisnb.io.writers import write_csv
from lorisnb.tools.decisions.diff import diff_tables
from lorisnb.tools.decisions.runs import load_run, setting_differences

run = partial(run_cli, joined=True)


@pytest.fixture(scope="module")
def table(odom_sequences):
    return odom_sequences.copy()


@pytest.mark.parametrize("cell", ['{"bogus', "[1, 2]", "nan"])
def test_a_spec_that_is_no_json_object_is_a_damaged_table(tmp_path, table, capsys, cell):
    bad = table.assign(spec=cell)
    write_csv(bad, tmp_path / "a.csv")
    write_csv(bad, tmp_path / "b.csv")
    rc, out, err = run(capsys, "diff", tmp_path / "a.csv", tmp_path / "b.csv")
    assert rc == 2, out  # '{"bogus' in both tables: verdict ok, exit 0
    assert f"{tmp_path / 'a.csv'}, line 2: column spec:" in err and "expected a per-sequence table" in err


def test_a_spec_is_never_printed_whole(tmp_path, table, capsys):
    spec = table["spec"].iloc[0]
    assert len(spec) > 100
    one = table.copy()
    one.loc[1, "spec"] = spec[:-1]  # cut short: no JSON
    write_csv(one, tmp_path / "one.csv")
    write_csv(table, tmp_path / "good.csv")
    rc, out, err = run(capsys, "diff", tmp_path / "good.csv", tmp_path / "one.csv")
    assert rc == 2
    assert f"{tmp_path / 'one.csv'}, line 3: column spec:" in err
    assert spec[:-1] not in err and f"({len(spec) - 1} characters)" in err
    # in Python, DataFrames whose specs are no JSON: named by their beginning only
    said = "; ".join(setting_differences(table, table.assign(spec="x" * 200)))
    assert "x" * 60 not in said and "(200 characters)" in said
    with pytest.raises(ValidationError) as exc:
        diff_tables(table.assign(spec="y" * 300), table.assign(spec="x" * 300))
    assert "x" * 60 not in str(exc.value) and "y" * 60 not in str(exc.value)


def test_a_damaged_parquet_value_names_its_row_and_file(tmp_path, table, capsys):
    pytest.importorskip("pyarrow")
    bad = table.copy()
    bad["cr"] = bad["cr"].astype(str)
    bad.loc[2, "cr"] = "abc"
    bad.to_parquet(tmp_path / "bad.parquet", index=False)
    with pytest.raises(ParseError) as exc:
        load_run(tmp_path / "bad.parquet")
    assert "row 3 of the table (counted from 1): column cr: 'abc' is not a number" in str(exc.value)
    # a dataset folder: the file holding the row, and the row there
    ds = tmp_path / "ds.pq"
    two = pd.concat([table, table.assign(algorithm="orb", file="orb/" + table["file"])], ignore_index=True)
    two.to_parquet(ds, partition_cols=["algorithm"], index=False)
    part = next((ds / "algorithm=orb").glob("*.parquet"))
    rows = pd.read_parquet(part)
    rows.loc[1, "cr"] = float("nan")
    rows.to_parquet(part, index=False)
    with pytest.raises(ParseError) as exc:
        load_run(ds)
    assert f"row 2 of algorithm=orb/{part.name} (counted from 1): column cr: nan is not a rate" in str(exc.value)
    rc, _, err = run(capsys, "history", tmp_path / "bad.parquet", ds)
    assert rc == 2 and f"row 2 of algorithm=orb/{part.name}" in err


def test_the_note_says_where_lorisnb_data_points(tmp_path, table, capsys, monkeypatch):
    write_csv(table, tmp_path / "a.csv")
    write_csv(table, tmp_path / "b.csv")
    monkeypatch.setenv("LORISNB_DATA", str(tmp_path / "nonexist"))
    rc, _, err = run(capsys, "diff", tmp_path / "a.csv", tmp_path / "b.csv")
    assert rc == 0, err
    assert f"LORISNB_DATA is set to {tmp_path / 'nonexist'}, which does not exist" in err
    (tmp_path / "empty").mkdir()
    monkeypatch.setenv("LORISNB_DATA", str(tmp_path / "empty"))
    rc, _, err = run(capsys, "diff", tmp_path / "a.csv", tmp_path / "b.csv")
    assert rc == 0 and "which is not a data root" in err


def test_tolerance_metric_names_in_any_case(tmp_path, table, capsys):
    from lorisnb.core.stats.regression import parse_tolerances

    assert parse_tolerances("CR=0.1,Ate_RMSE=5%") == parse_tolerances("cr=0.1,ate_rmse=5%")
    assert parse_tolerances({"CR": 0.1})["cr"].amount == 0.1
    with pytest.raises(ValidationError, match="given twice"):
        parse_tolerances("cr=0.1,CR=0.2")
    with pytest.raises(ValidationError, match="no regression could be found"):
        parse_tolerances("CR=2")
    write_csv(table, tmp_path / "a.csv")
    rc, out, err = run(capsys, "diff", tmp_path / "a.csv", tmp_path / "a.csv", "--tolerance", "CR=0.1")
    assert rc == 0 and "cr 0.1" in out, err  # refused: "not a compared metric"
    rc, out, err = run(capsys, "history", tmp_path / "a.csv", "--tolerance", "CR=0.1")
    assert "not a compared metric" not in err


def test_an_error_tolerance_that_lets_it_double_is_warned(tmp_path, table, capsys):
    from lorisnb.core.stats.regression import parse_tolerances
    from lorisnb.tools.decisions.diff import wide_tolerances

    median = float(table["ate_rmse"].median())
    assert wide_tolerances(parse_tolerances()) == []  # the defaults
    said = wide_tolerances(parse_tolerances("ate_rmse=1000%"))
    assert len(said) == 1 and "lets ate_rmse grow 11-fold" in said[0]
    assert wide_tolerances(parse_tolerances(f"ate_rmse={median / 2}"), table) == []
    said = wide_tolerances(parse_tolerances(f"ate_rmse={median * 3}"), table)
    assert len(said) == 1 and "grow 4-fold at BASE's median ate_rmse" in said[0]
    write_csv(table, tmp_path / "a.csv")
    rc, _, err = run(capsys, "diff", tmp_path / "a.csv", tmp_path / "a.csv", "--tolerance", "ate_rmse=10")
    assert rc == 0 and "warning: tolerance ate_rmse=10: lets ate_rmse grow" in err
    rc, _, err = run(capsys, "history", tmp_path / "a.csv", "--tolerance", "rpe_rot_rmse=100%")
    assert "warning: tolerance rpe_rot_rmse=100%: lets rpe_rot_rmse grow 2-fold" in err
