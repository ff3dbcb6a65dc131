"""A run folder or table received damaged or edited is refused naming the file, the line or key and
what was expected, by diff and history as by Python (runs.load_run, read_table): run.json's
``created`` that is no time, a spec value no spec has (eps NaN or -1: it was reported as two specs
that differ), a run whose ``findings`` folder is missing or a link leading out of it (the notebooks'
tables were read in its place: "spec mode differs"); a CSV table whose shape pandas would have
quietly repaired (a second column of one name, a short row, an extra field shifting every column),
a yes-or-no cell of 1, a value rounded in the message, a line counted at a carriage return."""

from __future__ import annotations

import json
import os
import re

import numpy as np
import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import DataNotFoundError, ParseError, ValidationError
from lorisnb.io.writers import write_csv
from lorisnb.tools.decisions.runs import DURATIONS, FIRST_TABLE, load_run, read_table
from lorisnb.tools.report.provenance import KEYS

ODOM = ("cafe-1-1-odom.txt", "cafe-1-2-odom.txt", "home-1-1-odom.txt")


@pytest.fixture(scope="module")
def table(icra20):
    return ln.evaluate([icra20 / "per-seq" / "odom" / f for f in ODOM], progress=False).sequences()


def report_run(folder, table, **changes):
    """A report run folder as lorisnb report writes it (findings and run.json), with ``changes`` to
    run.json; ``spec`` values as evaluate recorded them."""
    (folder / "findings").mkdir(parents=True)
    write_csv(table, folder / FIRST_TABLE)
    write_csv(table[["scene", "seq", "gt_duration"]], folder / DURATIONS)
    values = {**json.loads(table["spec"].iloc[0]), "eps": "inf", "phi": "inf", "delta": 1.0, "tau": 60.0}
    meta = {k: None for k in KEYS} | {"command": ["lorisnb", "report"], "lorisnb_version": "0.3.0",
                                      "created": "2026-11-01T02:00:00+00:00", "inputs": {}, "notebooks": {},
                                      "spec": {"description": "d", "values": {**values, "source": "{results}"}}}  # fmt: skip
    for key, value in changes.items():
        if key.startswith("spec_"):
            meta["spec"]["values"][key[5:]] = value
        else:
            meta[key] = value
    (folder / "run.json").write_text(json.dumps(meta))
    return folder


def refused_everywhere(capsys, good, bad, message):
    """``message`` in the error of diff (either side) and history, exit status 2; and from Python."""
    for command in (["diff", good, bad], ["diff", bad, good], ["history", good, bad]):
        rc = main([*map(str, command), "--no-progress"] if command[0] == "diff" else [*map(str, command)])
        err = capsys.readouterr().err
        assert rc == 2 and message in err and "Traceback" not in err, err


# -- run.json ------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "changes, message",
    [
        ({"created": "garbage"}, '"created" is "garbage"; expected an ISO 8601 time'),
        ({"created": "2026-13-45"}, '"created" is "2026-13-45"; expected an ISO 8601 time'),
        ({"created": 5}, '"created" is 5; expected an ISO 8601 time'),
        ({"spec_eps": "nan"}, '"spec" values: eps=nan: expected'),
        ({"spec_eps": -1}, '"spec" values: eps=-1: expected'),
        ({"spec_delta": 0}, '"spec" values: delta=0: expected'),
        ({"spec_align": "banana"}, '"spec" values: align=banana: expected one of'),
    ],
)
def test_a_damaged_run_json_is_refused_naming_the_file_and_key(tmp_path, table, capsys, changes, message):
    good = report_run(tmp_path / "good", table)
    bad = report_run(tmp_path / "bad", table, **changes)
    assert load_run(good).created.year == 2026
    with pytest.raises(ParseError, match=re.escape(message)) as exc:
        load_run(bad)
    assert exc.value.path == str(bad / "run.json")
    refused_everywhere(capsys, good, bad, f"{bad / 'run.json'}: {message}")


def test_a_run_json_without_created_is_ordered_by_its_time(tmp_path, table):
    run = load_run(report_run(tmp_path / "run", table, created=None))
    assert run.created_from == "modification time of run.json"


def test_a_received_version_is_escaped_by_history(tmp_path, table, capsys):
    a = report_run(tmp_path / "a", table)
    b = report_run(tmp_path / "b", table, lorisnb_version="0.3.0\x1b]0;T\x07", created="2026-11-02T02:00:00+00:00")
    assert main(["history", str(a), str(b)]) == 2  # another version: b has no baseline, nothing judged
    out = capsys.readouterr().out
    assert "b: 2026-11-02T02:00:00+00:00, lorisnb 0.3.0\\x1b]0;T\\x07" in out
    assert "\x1b" not in out and "\x07" not in out


# -- findings ------------------------------------------------------------------------------------


def test_a_run_without_its_findings_names_them(tmp_path, table, capsys):
    """The notebooks' tables (other settings) were read in the findings' place: "spec mode differs"."""
    good = report_run(tmp_path / "good", table)
    bad = report_run(tmp_path / "bad", table)
    notebook = bad / "per_sequence_benchmark"
    notebook.mkdir()
    write_csv(table.assign(spec=table["spec"].str.replace('"mode":"auto"', '"mode":"per-seq"')), notebook / "s.csv")
    (bad / FIRST_TABLE).unlink()
    with pytest.raises(DataNotFoundError, match=f"{re.escape(str(bad / FIRST_TABLE))}: no such file"):
        load_run(bad)
    refused_everywhere(capsys, good, bad, f"{bad / FIRST_TABLE}: no such file")
    for f in (bad / "findings").iterdir():
        f.unlink()
    (bad / "findings").rmdir()
    refused_everywhere(capsys, good, bad, f"{bad / 'findings'}: no such folder")
    elsewhere = tmp_path / "elsewhere"
    report_run(elsewhere, table)
    for target in (elsewhere / "findings", tmp_path / "nowhere"):  # a link leading out of the run, or nowhere
        if (bad / "findings").is_symlink():
            (bad / "findings").unlink()
        os.symlink(target, bad / "findings")
        with pytest.raises(ValidationError, match="findings: a link leading outside the run folder"):
            load_run(bad)
        refused_everywhere(capsys, good, bad, f"{bad / 'findings'}: a link leading outside the run folder")


def test_a_run_that_evaluated_nothing_itself_is_read_from_its_notebooks(tmp_path, table):
    """A run.json whose spec records no evaluation of the report's own (no findings written): its
    notebooks' tables are the run, as before."""
    run = tmp_path / "run"
    (run / "nb").mkdir(parents=True)
    write_csv(table, run / "nb" / "s.csv")
    meta = {k: None for k in KEYS} | {"command": [], "spec": {"description": None, "values": {}}, "inputs": {},
                                      "notebooks": {}}  # fmt: skip
    (run / "run.json").write_text(json.dumps(meta))
    assert len(load_run(run).table) == len(table)


def test_a_tables_spec_cell_no_spec_has_is_refused_naming_the_line(tmp_path, table, capsys):
    """A damaged ``spec`` cell was reported as two specs that differ (not comparable)."""
    good, bad = write_csv(table, tmp_path / "good.csv"), tmp_path / "bad.csv"
    edited = table.copy()
    edited.loc[1, "spec"] = edited.loc[1, "spec"].replace('"align":"se3"', '"align":"banana"')
    assert edited.loc[1, "spec"] != table.loc[1, "spec"]
    write_csv(edited, bad)
    with pytest.raises(ParseError, match="line 3: column spec: align=banana: expected one of"):
        read_table(bad)
    refused_everywhere(capsys, good, bad, f"{bad}, line 3: column spec: align=banana: expected one of")


# -- CSV tables ----------------------------------------------------------------------------------


def edit_lines(path, edit):
    text = path.read_text(encoding="utf-8").split("\n")
    path.write_text("\n".join(edit(text)), encoding="utf-8")


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda t: [t[0]] + [x + ",7" for x in t[1:] if x], "line 2: the row has {n1} field(s) against the header's {n}"),
        (lambda t: [t[0], t[1], ",".join(t[2].split(",")[:10]), *t[3:]], "line 3: the row has 10 field(s) against the header's {n}"),
        (lambda t: [t[0] + ",cr"] + [x + ",0.5" for x in t[1:] if x], "line 1: column 'cr' is named twice in the header (fields {cr} and {n1})"),
        (lambda t: [t[0], t[1], t[2] + "\r,x", *t[3:]], "line 3: a carriage return outside a quoted cell"),
    ],
)  # fmt: skip
def test_a_table_pandas_would_repair_is_refused_naming_the_line(tmp_path, table, capsys, edit, message):
    good, bad = write_csv(table, tmp_path / "good.csv"), write_csv(table, tmp_path / "bad.csv")
    edit_lines(bad, edit)
    n = len(table.columns)
    message = message.format(n=n, n1=n + 1, cr=list(table.columns).index("cr") + 1)
    with pytest.raises(ParseError, match=re.escape(message)):
        read_table(bad)
    refused_everywhere(capsys, good, bad, f"{bad}, {message}")


@pytest.mark.parametrize(
    "column, value, message",
    [
        ("cs_r", 1.0000001, "1.0000001 is not a rate between 0 and 1"),  # not "1 is not a rate"
        ("cr", -1e-12, "-1e-12 is not a rate"),
        ("first_correct", 1, "'1' is not True or False (as lorisnb evaluate writes a yes or no)"),
        ("first_correct", "1.0", "'1.0' is not True or False"),
        ("official_interpolation", 0, "'0' is not True or False"),
    ],
)
def test_a_cell_is_shown_as_written_and_judged_by_its_columns_type(tmp_path, table, capsys, column, value, message):
    good, bad = write_csv(table, tmp_path / "good.csv"), tmp_path / "bad.csv"
    edited = table.astype({column: object})
    edited.loc[1, column] = value
    edited[column] = edited[column].map(lambda v: v if isinstance(v, str) else repr(v))
    write_csv(edited, bad)
    with pytest.raises(ParseError, match=re.escape(f"line 3: column {column}: {message}")):
        read_table(bad)
    refused_everywhere(capsys, good, bad, f"{bad}, line 3: column {column}: {message}")


def test_yes_or_no_cells_as_evaluate_and_parquet_write_them_are_read(tmp_path, table):
    write_csv(table, tmp_path / "t.csv")
    assert read_table(tmp_path / "t.csv")["first_correct"].tolist() == table["first_correct"].tolist()
    t = table.assign(first_correct=[str(v).upper() for v in table["first_correct"]])  # any case, as pandas reads it
    write_csv(t, tmp_path / "upper.csv")
    assert read_table(tmp_path / "upper.csv")["first_correct"].tolist() == table["first_correct"].tolist()


def test_the_line_named_is_the_files_after_carriage_returns_in_quoted_cells(tmp_path, table, capsys):
    """A folder name with a carriage return is one quoted cell on one line (``grep -n``, editors): the
    refused row's line was counted as if each carriage return began a line."""
    names = ["cr\rOVER", "a\r\rb", "tab\talg"]
    edited = table.assign(algorithm=names, file=[f"{n}/x.txt" for n in names])
    edited.loc[2, "cr"] = np.nan
    bad = write_csv(edited, tmp_path / "bad.csv")
    lines = bad.read_bytes().split(b"\n")
    assert lines[3].startswith(b"tab\talg,")  # the file's fourth line
    with pytest.raises(ParseError, match="line 4: column cr: nan"):
        read_table(bad)
    assert main(["diff", str(bad), str(bad)]) == 2 and f"{bad}, line 4: column cr: nan" in capsys.readouterr().err
    assert pd.read_csv(write_csv(edited.assign(cr=0.5), tmp_path / "ok.csv"))["algorithm"].tolist() == names
    assert read_table(tmp_path / "ok.csv")["algorithm"].tolist() == names
