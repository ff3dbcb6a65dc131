"""diff and history on tables and runs as the s70 tester made them: a table whose algorithm's scene
mixes two specs or thresholds is refused when read, naming the keys; run.json spec values recorded
before report parameters were canonical compare with today's; a renamed algorithm is named; a table
given to evaluate/compare is a usage error; the note on a scene without ground truth says why."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.errors import ParseError, ValidationError
from lorisnb.tools.decisions.diff import diff_tables, rename_notes, renamed
from lorisnb.tools.decisions.history import load_runs, newest_verdict, renames_said
from lorisnb.tools.decisions.runs import Run, load_run, spec_differences, table_expected

ALGS = ["orbslam2_rgbd", "vins_mono_color_imu_with_loop"]


def lorisnb(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "lorisnb.cli", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True, timeout=600)  # fmt: skip


@pytest.fixture(scope="module")
def tables(icra20):
    """The per-sequence table of two algorithms in cafe and home (se3), and orbslam2's home rows
    aligned with Sim(3) and scored at eps 3 m, phi 30 deg."""
    source = icra20 / "per-seq"
    ev = ln.evaluate(source, algorithms=ALGS, scenes=["cafe", "home"], progress=False)
    sim3 = ln.evaluate(source / "orbslam2_rgbd", scenes=["home"], align="sim3", progress=False).sequences()
    return ev.sequences(), sim3, ev.sequences(3.0, 30.0), ev.sequences("relative:0.05")


def _swap(table: pd.DataFrame, other: pd.DataFrame, seq: int = 2) -> pd.DataFrame:
    """``table`` with orbslam2's home-``seq`` row taken from ``other``."""
    pick = (table["algorithm"] == "orbslam2_rgbd") & (table["scene"] == "home") & (table["seq"] == seq)
    row = other[(other["algorithm"] == "orbslam2_rgbd") & (other["scene"] == "home") & (other["seq"] == seq)]
    return pd.concat([table[~pick], row[table.columns]]).reset_index(drop=True)


def test_a_table_mixing_two_specs_in_a_scene_is_refused_naming_the_key(tables, tmp_path):
    plain, sim3, _, _ = tables
    mixed = _swap(plain, sim3)
    path = tmp_path / "mixed.csv"
    mixed.to_csv(path, index=False)
    with pytest.raises(ParseError) as err:
        load_run(path)
    text = str(err.value)
    assert 'spec align: "se3" against "sim3"' in text and "orbslam2_rgbd home" in text
    assert "line 15" in text and "score every row with one spec" in text and '"association"' not in text
    plain.to_csv(tmp_path / "plain.csv", index=False)
    for pair in (["mixed.csv", "mixed.csv"], ["plain.csv", "mixed.csv"]):  # it was "ok", exit 0, against itself
        r = lorisnb("diff", *pair, cwd=tmp_path)
        assert r.returncode == 2 and 'spec align: "se3" against "sim3"' in r.stderr, r.stderr
        assert '"association"' not in r.stderr
    r = lorisnb("history", "plain.csv", "mixed.csv", cwd=tmp_path)  # history reads tables through the same check
    assert r.returncode == 2 and 'spec align: "se3" against "sim3"' in r.stderr, r.stderr
    with pytest.raises(ValidationError, match='CAND holds two settings for orbslam2_rgbd home: spec align: "se3" '
                                              'against "sim3"'):  # fmt: skip
        diff_tables(plain, mixed)


def test_a_table_mixing_thresholds_is_refused_and_a_relative_eps_is_not(tables, tmp_path):
    plain, _, at3, relative = tables
    path = tmp_path / "mixed_eps.csv"
    _swap(plain, at3).to_csv(path, index=False)
    with pytest.raises(ParseError, match="orbslam2_rgbd home: eps = inf against 3; phi = inf against 30.0"):
        load_run(path)
    relative.to_csv(tmp_path / "relative.csv", index=False)  # eps in metres differs per sequence: one setting
    assert relative.groupby(["algorithm", "scene"])["eps"].nunique().max() > 1
    assert len(load_run(tmp_path / "relative.csv").table) == len(relative)


def test_algorithms_of_one_scene_may_differ_and_not_comparable_names_the_keys(tables, icra20):
    """Two specs in one table, one per algorithm (a monocular system with Sim(3)): read; against a
    table scored otherwise, the message names the key that differs, never the specs whole."""
    plain, _, _, _ = tables
    vins = ln.evaluate(icra20 / "per-seq" / ALGS[1], scenes=["cafe", "home"], align="sim3", progress=False)
    both = pd.concat([plain[plain["algorithm"] == ALGS[0]], vins.sequences()[plain.columns]], ignore_index=True)
    with pytest.raises(ValidationError) as err:
        diff_tables(plain, both)
    text = str(err.value)
    assert 'spec align: "se3" in BASE against "se3"/"sim3" in CAND' in text and '"association"' not in text


def _report_run(folder: Path, table: pd.DataFrame, scale: object) -> Path:
    """A report run as lorisnb report writes it (run.json and findings/sequences.csv), its spec's
    ``scale`` recorded as given."""
    (folder / "findings").mkdir(parents=True)
    table.to_csv(folder / "findings" / "sequences.csv", index=False)
    values = {"align": "sim3", "preset": "openloris", "eps": "inf", "phi": "inf", "delta": 1.0, "tau": 60.0,
              "rpe_unit": "s", "metric": "cr", "scale": scale, "source": "{results}"}  # fmt: skip
    record = {"command": ["lorisnb", "report", "-p", "scale", str(scale)], "lorisnb_version": "0.3.0", "commit": None,
              "spec": {"description": "OpenLORIS", "values": values}, "data_root": None,
              "created": "2026-01-01T03:00:00+00:00", "inputs": {}, "notebooks": {}}  # fmt: skip
    (folder / "run.json").write_text(json.dumps(record))
    return folder


@pytest.mark.parametrize("old", ["on", "Yes", 1])
def test_runs_recording_scale_as_typed_compare_with_canonical_ones(tables, tmp_path, old):
    plain = tables[0]
    a = load_run(_report_run(tmp_path / "old", plain, old))
    b = load_run(_report_run(tmp_path / "new", plain, True))
    assert spec_differences(a, b) == []  # it said: spec scale: "on" in old against true in new
    off = load_run(_report_run(tmp_path / "off", plain, False))
    assert [x.split(" in ")[0] for x in spec_differences(a, off)] == [f"spec scale: {json.dumps(True)}"]
    r = lorisnb("diff", "old", "new", cwd=tmp_path)
    assert r.returncode == 0 and "verdict: ok" in r.stdout, r.stderr


def test_a_renamed_algorithm_is_named_in_diff_and_history(tables, tmp_path):
    plain = tables[0]
    new = plain.assign(algorithm=plain["algorithm"].replace({ALGS[0]: "orbslam2_v2"}))
    d = diff_tables(plain, new)
    assert d.regressed and renamed(d) == [("", ALGS[0], "orbslam2_v2", 7)]  # the verdict kept: missing is missing
    note = rename_notes(d, "BASE", "CAND")[0]
    assert "orbslam2_v2 in CAND holds exactly the 7 sequence(s) orbslam2_rgbd had in BASE" in note
    assert "rename it back" in note and "--baseline" in note
    # one sequence fewer: not exactly the lost ones, not named
    fewer = new[~((new["algorithm"] == "orbslam2_v2") & (new["scene"] == "home") & (new["seq"] == 5))]
    assert renamed(diff_tables(plain, fewer)) == []
    plain.to_csv(tmp_path / "n1.csv", index=False)
    plain.to_csv(tmp_path / "n2.csv", index=False)
    new.to_csv(tmp_path / "n3.csv", index=False)
    new.to_csv(tmp_path / "n4.csv", index=False)
    r = lorisnb("diff", "n1.csv", "n3.csv", cwd=tmp_path)
    assert r.returncode == 1 and "orbslam2_v2 in CAND n3.csv holds exactly the 7 sequence(s)" in r.stderr
    runs = load_runs([tmp_path / f"n{k}.csv" for k in range(1, 5)])
    said = renames_said(runs, {k: diff_tables(runs[k - 1].table, runs[k].table) for k in (1, 2, 3)})
    assert len(said) == 1 and "orbslam2_v2 in n3.csv" in said[0] and "new series from n3.csv" in said[0]
    r = lorisnb("history", "n1.csv", "n2.csv", "n3.csv", "n4.csv", cwd=tmp_path)
    assert "note: orbslam2_v2 in n3.csv holds exactly the 7 sequence(s) orbslam2_rgbd had in n2.csv" in r.stdout
    assert not any("renamed?" in x for x in newest_verdict(runs[:2], {1: diff_tables(plain, plain)})[1])


def test_a_table_given_to_compare_is_a_usage_error(tables, tmp_path):
    tables[0].to_csv(tmp_path / "one.csv", index=False)
    for command in ("compare", "evaluate"):
        r = lorisnb(command, "one.csv", "one.csv", cwd=tmp_path)  # it read the header as poses: exit 1
        assert r.returncode == 2, r.stderr
        assert "a per-sequence table lorisnb wrote" in r.stderr and "lorisnb diff BASE CAND" in r.stderr
        assert "8 or 9 numbers" not in r.stderr


def test_office_without_ground_truth_is_said_as_it_is(tables, tmp_path, data):
    plain = tables[0]
    office = plain.copy()
    office.loc[(office["algorithm"] == ALGS[0]) & (office["scene"] == "home") & (office["seq"] == 2), "scene"] = (
        "office"
    )
    notes: list[str] = []
    expected = table_expected(office, tmp_path / "t.csv", notes)
    assert notes == [f"{tmp_path / 't.csv'}: scene values of office count only the sequences the table holds (the "
                     "office ground truth (motion capture) is not public)"]  # fmt: skip
    assert expected is not None and sorted(set(expected["scene"])) == ["cafe", "home"]  # the others still counted
    assert "set LORISNB_DATA" not in notes[0]


def test_run_objects_compare_by_canonical_values(tables):
    plain = tables[0]
    runs = [Run(Path(n), "report", plain, {"spec": {"values": {"scale": s, "rpe_unit": u, "source": n}}})
            for n, s, u in (("a", "on", "M"), ("b", True, "m"))]  # fmt: skip
    assert spec_differences(*runs) == []
