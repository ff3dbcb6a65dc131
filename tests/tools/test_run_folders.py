"""Report run folders as diff, history and verify read them: what makes two runs not comparable
(only what changes the numbers, every differing key named), a sequence read once however many of
the run's tables hold it, damaged run.json and tables refused with the file and what was expected
(never a traceback), verify noticing a file added to a folder the run read, and report outputs and
parameters refused before anything runs."""

from __future__ import annotations

import json
import shutil

import pandas as pd
import pytest
from helpers import run_cli as run

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import DataNotFoundError
from lorisnb.tools.decisions.runs import load_run, spec_differences
from lorisnb.tools.report.provenance import checksums, input_files, run_record, verify_run, write_run_json

#: The tables a report run holds the same sequences in (the report's own, then the notebooks').
TABLES = ("findings/sequences.csv", "per_sequence_benchmark/sequences.csv", "lifelong_benchmark/sequences.csv")


@pytest.fixture(scope="module")
def results(tmp_path_factory, icra20):
    """A results folder of two algorithms, three real sequences."""
    root = tmp_path_factory.mktemp("res")
    for alg, name in (("orbslam2_rgbd", "cafe_1_1_orbslam2-original.txt"),
                      ("orbslam2_rgbd", "home_1_2_orbslam2-original.txt"), ("odom", "cafe-1-1-odom.txt")):  # fmt: skip
        (root / alg).mkdir(exist_ok=True)
        shutil.copy(icra20 / "per-seq" / alg / name, root / alg / name)
    return root


@pytest.fixture(scope="module")
def table(results, data):
    return ln.evaluate(results, data_root=data, progress=False).sequences()


def spec(source, **values):
    base = {"eps": "paper", "phi": 30.0, "delta": 1.0, "tau": 60.0, "scale": "auto", "metric": "cr", "alpha": 0.05,
            "level": 0.95, "seed": 0, "source": str(source)}  # fmt: skip
    return {"description": "OpenLORIS conventions in words " + "x" * 200, "values": {**base, **values}}


def make_run(folder, table, spec_, roots=(), data_root=None, **meta):
    """A report run folder as ``lorisnb report`` writes it: run.json and the same per-sequence table
    in each of :data:`TABLES`."""
    for name in TABLES:
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        table.to_csv(folder / name, index=False)
    inputs = checksums(input_files(roots), data_root)
    record = run_record(["lorisnb", "report"], spec_, data_root, inputs, {"per_sequence_benchmark": "ok"}, roots)
    write_run_json(folder, {**record, **meta})
    return folder


@pytest.mark.thorough
def test_runs_over_other_folders_compare_and_differences_are_named(tmp_path, table, capsys):
    a = make_run(tmp_path / "a", table, spec(tmp_path / "resA"))
    b = make_run(tmp_path / "b", table, spec(tmp_path / "elsewhere" / "resB", alpha=0.01, seed=3, level=0.9))
    assert spec_differences(load_run(a), load_run(b)) == []  # where results live, the leaderboard's tests
    rc, out, err = run(capsys, "diff", a, b)
    assert rc == 0 and "verdict: ok" in out, err
    rc, out, _ = run(capsys, "history", a, b)
    assert rc == 0 and "not comparable" not in out
    c = make_run(tmp_path / "c", table, spec(tmp_path / "resA", eps=1.0, repeated="keep"))
    rc, _, err = run(capsys, "diff", a, c)
    # each differing key named whole, after a long description
    assert rc == 2 and 'spec eps: "paper" in ' in err and "spec repeated: (not set) in " in err and '"keep" in' in err
    rc, out, _ = run(capsys, "history", a, c)
    assert rc == 2 and "not comparable: c" in out and "spec eps" in out  # the newest run unjudged: never 0


@pytest.mark.thorough
def test_a_sequence_is_one_row_however_many_tables_hold_it(tmp_path, table, capsys):
    a = make_run(tmp_path / "a", table, spec(tmp_path))
    r = load_run(a)
    assert len(r.table) == len(table) == 3 and set(r.table["table"]) == {"findings/sequences.csv"}
    rc, out, _ = run(capsys, "diff", a, a)
    assert rc == 0 and "3 sequence(s)" in out
    b = make_run(tmp_path / "b", table[table["algorithm"] != "odom"], spec(tmp_path))
    rc, out, _ = run(capsys, "diff", a, b, "--json", tmp_path / "d.json")
    verdict = json.loads((tmp_path / "d.json").read_text())
    assert rc == 1 and verdict["regressed_sequences"] == 1 and verdict["sequences"] == 3
    missing = [x for x in verdict["regressions"] if x["status"] == "missing" and x["level"] == "sequence"]
    assert [(x["algorithm"], x["scene"], x["seq"]) for x in missing] == [("odom", "cafe", 1)]
    rc, out, _ = run(capsys, "history", a, b, "--csv", tmp_path / "h.csv", "--metric", "cr")
    h = pd.read_csv(tmp_path / "h.csv")
    # 2 runs x 4 series (odom and orbslam2, cafe and home); b lost odom: no value there, and history
    # exits 1 as diff does, the newest run having lost a sequence against its baseline
    assert rc == 1 and len(h) == 2 * 4
    # the report's own findings are the run: a notebook's table (other thresholds, simulated
    # algorithms) adds nothing; a run whose run.json records the report's own evaluation but that
    # lost its findings is refused naming them (the notebooks' tables hold other settings); a run
    # that recorded none (no leaderboard evaluated) is read from its notebooks'
    (a / "findings" / "sequences.csv").write_text(table.iloc[:1].to_csv(index=False))
    assert len(load_run(a).table) == 1
    (a / "findings" / "sequences.csv").unlink()
    with pytest.raises(DataNotFoundError, match="findings/sequences.csv: no such file; the run's run.json records"):
        load_run(a)
    write_run_json(a, {**json.loads((a / "run.json").read_text()), "spec": {"description": None, "values": {}}})
    assert len(load_run(a).table) == 3


RUN_JSON_DAMAGE = {
    "inputs": ([1, 2], '"inputs" is [1, 2]; expected an object path -> SHA-256'),
    "spec": ("eps 3", '"spec" is "eps 3"; expected an object'),
    "notebooks": (["a"], '"notebooks" is ["a"]; expected an object'),
    "command": ("lorisnb report", '"command" is "lorisnb report"; expected a list of strings'),
    "data_root": (5, '"data_root" is 5; expected a folder path or null'),
    "created": ({"t": 1}, '"created" is {"t": 1}; expected an ISO 8601 time'),
    "lorisnb_version": ([0, 3], '"lorisnb_version" is [0, 3]; expected a version string or null'),
    "commit": (1, '"commit" is 1; expected a git commit or null'),
    "input_roots": ("res", '"input_roots" is "res"; expected a list of paths'),
}


@pytest.mark.parametrize("key", list(RUN_JSON_DAMAGE))
@pytest.mark.thorough
def test_damaged_run_json_is_refused_by_every_reader(tmp_path, table, capsys, key):
    good = make_run(tmp_path / "good", table, spec(tmp_path))
    bad = tmp_path / "bad"
    shutil.copytree(good, bad)
    value, message = RUN_JSON_DAMAGE[key]
    record = json.loads((bad / "run.json").read_text())
    (bad / "run.json").write_text(json.dumps({**record, key: value}))
    for args in (["verify", bad], ["diff", good, bad], ["history", good, bad]):
        rc, _, err = run(capsys, *args)
        assert rc == 2 and f"{bad / 'run.json'}: {message}" in err, (args, err)
    (bad / "run.json").write_text("[1, 2]")
    rc, _, err = run(capsys, "verify", bad)
    assert rc == 2 and "a JSON list; expected an object" in err


def test_text_in_a_number_column_is_refused_with_file_and_line(tmp_path, table, capsys):
    good = make_run(tmp_path / "good", table, spec(tmp_path))
    bad = make_run(tmp_path / "bad", table.assign(cr=["0.5", "abc", "0.1"]), spec(tmp_path))
    for command in ("diff", "history"):
        rc, _, err = run(capsys, command, good, bad)
        assert rc == 2 and f"{bad / TABLES[0]}, line 3: column cr: 'abc' is not a number" in err, err
    table.assign(cs_r=["x"] * 3).to_csv(tmp_path / "t.csv", index=False)
    rc, _, err = run(capsys, "history", tmp_path / "t.csv")
    assert rc == 2 and "line 2: column cs_r: 'x'" in err


def test_verify_notices_files_added_to_the_folders_read(tmp_path, results, table, capsys):
    res = tmp_path / "res"
    shutil.copytree(results, res)
    r = make_run(tmp_path / "run", table, spec(res), roots=[res])  # absolute paths: read only below --results
    rc, _, err = run(capsys, "verify", r)
    assert rc == 2 and "outside the run folder and the roots given here" in err
    rc, _, err = run(capsys, "verify", r, "--results", res)
    assert rc == 0 and "all 3 input file(s) unchanged" in err
    extra = res / "orbslam2_rgbd" / "home_1_3_orbslam2-original.txt"
    shutil.copy(res / "orbslam2_rgbd" / "home_1_2_orbslam2-original.txt", extra)
    assert verify_run(r, {"results": res}) == [(str(extra.resolve()), "added")]
    rc, out, err = run(capsys, "verify", r, "--results", res)
    assert rc == 1 and f"added: {extra.resolve()}" in out and "1 file(s) added" in err
    extra.unlink()
    (res / "odom" / "cafe-1-1-odom.txt").unlink()
    rc, out, _ = run(capsys, "verify", r, "--results", res)
    assert rc == 1 and "missing: " in out and "cafe-1-1-odom.txt" in out
    record = json.loads((r / "run.json").read_text())  # a run of an earlier lorisnb: says what it cannot check
    del record["input_roots"]
    (r / "run.json").write_text(json.dumps(record))
    rc, _, err = run(capsys, "verify", r, "--results", res)
    assert rc == 1 and "no input_roots" in err


@pytest.mark.parametrize("where", ["out in results", "out in an algorithm folder", "results in out", "same"])
def test_report_output_overlapping_the_results_is_refused_first(tmp_path, results, capsys, monkeypatch, where):
    import lorisnb.tools.report.build as report

    monkeypatch.setattr(report, "run_notebook", lambda *a, **k: pytest.fail("a notebook ran"))
    res = tmp_path / "res"
    shutil.copytree(results, res)
    out = {"out in results": res / "rep", "out in an algorithm folder": res / "odom" / "rep", "same": res,
           "results in out": tmp_path}[where]  # fmt: skip
    before = sorted(p for p in tmp_path.rglob("*"))
    rc, _, err = run(capsys, "report", "--results", res, "--out", out, "--no-progress", "--force")
    refused = (
        f"--force will not replace {out}" if out.exists() else f"--out {out}"
    )  # an existing folder: by --force's rule
    assert rc == 2 and refused in err and str(res) in err, err
    assert sorted(p for p in tmp_path.rglob("*")) == before


def test_folder_outputs_inside_an_input_folder_are_refused(tmp_path, results, capsys):
    res = tmp_path / "res"
    shutil.copytree(results, res)
    rc, _, err = run(capsys, "evaluate", res, "--parquet", res / "table", "--no-progress")
    assert rc == 2 and "--parquet" in err and "lies in the input" in err
    assert not (res / "table").exists()


@pytest.mark.parametrize(
    "name, value, message",
    [
        ("alpha", "2", "alpha=2: expected a probability between 0 and 1"),
        ("alpha", "0", "alpha=0: expected a probability between 0 and 1"),
        ("alpha", "-0.5", "alpha=-0.5: expected a probability"),
        ("level", "1.5", "level=1.5: expected a probability"),
        ("metric", "foo", "metric=foo: expected one of cr, cr_t, c_ate_rmse, cs_r"),
        ("seed", "-1", "seed=-1: expected a whole number >= 0"),
        ("seed", "1.5", "seed=1.5: expected a whole number >= 0"),
        ("trials_by", "'trial'", "expected a group around the trial number"),
    ],
)
def test_report_parameters_are_checked_before_anything_runs(tmp_path, capsys, monkeypatch, name, value, message):
    import lorisnb.tools.report.build as report

    monkeypatch.setattr(report, "run_notebook", lambda *a, **k: pytest.fail("a notebook ran"))
    out = tmp_path / "run"
    rc, _, err = run(capsys, "report", "--out", out, "--notebooks", "compare_algorithms", "-p", name, value,
                     "--no-progress")  # fmt: skip
    assert rc == 2 and message in err, err
    assert list(tmp_path.iterdir()) == []


def test_compare_and_diff_use_the_same_validators(results, capsys):
    for args in (["compare", results, "--alpha", "2"], ["compare", results, "--seed", "-1"],
                 ["diff", results, results, "--alpha", "2"]):  # fmt: skip
        with pytest.raises(SystemExit) as exc:
            main([*map(str, args), "--no-progress"])
        err = capsys.readouterr().err
        assert exc.value.code == 2 and ("alpha=2: expected a probability between 0 and 1" in err
                                        or "seed=-1: expected a whole number >= 0" in err)  # fmt: skip


@pytest.mark.thorough
def test_report_results_are_the_leaderboards_input_whatever_notebooks_run(tmp_path, results, monkeypatch):
    """--results with a notebook that does not declare results_dir: the leaderboard, run.json's
    inputs and the overlap check are about the results folder, not the bundled icra20 results."""
    import lorisnb.tools.report.build as report

    monkeypatch.setattr(report, "run_notebook", lambda name, out_dir, *a, **k: report.NotebookRun(name))
    out, runs = report.run_report(
        tmp_path / "run", {}, ["metrics_primer"], progress=False, results=results, absolute_paths=True
    )
    record = json.loads((out / "run.json").read_text())
    assert record["spec"]["values"]["source"] == str(results)
    assert record["input_roots"][0] == str(results.resolve())
    assert sorted(k for k in record["inputs"] if k.startswith(str(results.resolve()))) == sorted(
        str(p.resolve()) for p in results.rglob("*.txt")
    )
    board = pd.read_csv(out / "findings" / "sequences.csv")
    assert sorted(set(board["algorithm"])) == ["odom", "orbslam2_rgbd"] and len(board) == 3
