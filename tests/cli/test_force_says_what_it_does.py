"""An existing output is refused with what --force would do to it: a file is replaced, history's
--out folder is written into (its other files kept: the message said "replace it"), a Parquet
dataset replaced whole; history --out naming a file is refused before any work, --force or not
(it failed after the work with 'File exists')."""

from __future__ import annotations

import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.io.writers import write_csv


@pytest.fixture(scope="module")
def tables(tmp_path_factory, icra20):
    root = tmp_path_factory.mktemp("tables")
    t = ln.evaluate(icra20 / "per-seq" / "odom" / "cafe-1-1-odom.txt", progress=False).sequences()
    return write_csv(t, root / "a.csv"), write_csv(t, root / "b.csv")


def test_history_out_an_existing_folder_says_force_writes_into_it(tmp_path, tables, capsys):
    a, b = tables
    out = tmp_path / "figs"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    assert main(["history", str(a), str(b), "--out", str(out), "--metric", "cr"]) == 2
    err = capsys.readouterr().err
    assert f"error: {out} exists; choose another name or pass --force to write into it (files of the same names " \
        "replaced, every other file kept)" in err  # fmt: skip
    assert main(["history", str(a), str(b), "--out", str(out), "--metric", "cr", "--force"]) == 0
    assert (out / "notes.txt").read_text() == "mine" and (out / "history_cr.svg").is_file()  # as it said


@pytest.mark.parametrize("force", [[], ["--force"]])
def test_history_out_naming_a_file_is_refused_before_any_work(tmp_path, tables, capsys, force):
    a, b = tables
    out = tmp_path / "figs"
    out.write_text("a file")
    assert main(["history", str(a), str(b), "--out", str(out), *force]) == 2
    out_, err = capsys.readouterr()
    assert f"error: --out {out}: a file; expected a folder to write into; choose another name" in err
    assert out_ == "" and out.read_text() == "a file"


def test_a_file_output_is_replaced_and_says_so(tmp_path, tables, capsys):
    a, b = tables
    (tmp_path / "v.json").write_text("{}")
    assert main(["diff", str(a), str(b), "--json", str(tmp_path / "v.json")]) == 2
    assert "exists; choose another name or pass --force to replace it" in capsys.readouterr().err


def test_a_parquet_dataset_is_replaced_whole(tmp_path, tables, capsys):
    pytest.importorskip("pyarrow")
    a, b = tables
    out = tmp_path / "d"
    assert main(["diff", str(a), str(b), "--parquet", str(out)]) == 0
    assert main(["diff", str(a), str(b), "--parquet", str(out)]) == 2
    err = capsys.readouterr().err
    assert "exists; choose another name or pass --force to replace it (a Parquet dataset lorisnb wrote, whole)" in err
