"""Every number diff and history read from a per-sequence table passes one rule (runs.read_table):
a NaN CR hand-edited into a table is refused as CR 12.4 is, with the file and line, rather than
judged a regression worse by infinity; NaN errors stay accepted where the evaluation writes them
(no matched pose)."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import ParseError
from lorisnb.tools.decisions.runs import load_run, read_table


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
