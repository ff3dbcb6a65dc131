"""lorisnb diff: two versions of an algorithm built from the bundled results (issue 25, must show),
tables and report runs as inputs, the verdict files, and history over runs."""

from __future__ import annotations

import json
import os
import shutil
import xml.etree.ElementTree as ET

import numpy as np
import pandas as pd
import pytest

from lorisnb.cli import main
from lorisnb.core.stats.regression import parse_tolerances, scene_changes, sequence_changes
from lorisnb.errors import ValidationError

ALGORITHMS = ("odom", "orbslam2_rgbd")
#: The sequences version B changes: (algorithm, file, scene, seq, what).
CHANGED = [
    ("odom", "home-1-2-odom.txt", "home", 2, "drop"),
    ("odom", "corridor-1-3-odom.txt", "corridor", 3, "noise"),
    ("orbslam2_rgbd", "cafe_1_1_orbslam2-original.txt", "cafe", 1, "drop+noise"),
    ("orbslam2_rgbd", "home_1_5_orbslam2-original.txt", "home", 5, "noise"),
]


def pose_lines(lines: list[str]) -> list[int]:
    """Indices of pose lines (8 or 9 numbers) of an OpenLORIS file."""
    out = []
    for i, line in enumerate(lines):
        parts = line.split()
        if len(parts) in (8, 9):
            try:
                [float(p) for p in parts]
            except ValueError:
                continue
            out.append(i)
    return out


def modified(text: str, what: str, seed: int) -> str:
    """The file with every pose dropped and/or 1.5 m of position noise: changes a single run per side
    can tell from rerun noise (a sequence with no output at all, an error several times larger)."""
    lines = text.splitlines()
    poses = pose_lines(lines)
    rng = np.random.default_rng(seed)
    if "noise" in what:
        for i in poses:
            parts = lines[i].split()
            xyz = np.array(parts[-7:-4], float) + rng.normal(0, 1.5, 3)
            parts[-7:-4] = [f"{v:.6f}" for v in xyz]
            lines[i] = " ".join(parts)
    if "drop" in what:
        n = len(poses)
        gone = set(poses[int(0.0 * n) : n])
        lines = [line for i, line in enumerate(lines) if i not in gone]
    return "\n".join(lines) + "\n"


@pytest.fixture(scope="module")
def versions(tmp_path_factory, icra20):
    """Version A: the bundled per-seq results of two algorithms; version B: the same with a dropped
    stretch and noise on the sequences of CHANGED."""
    root = tmp_path_factory.mktemp("versions")
    a, b = root / "A", root / "B"
    for alg in ALGORITHMS:
        shutil.copytree(icra20 / "per-seq" / alg, a / alg)
        shutil.copytree(icra20 / "per-seq" / alg, b / alg)
    for k, (alg, name, _, _, what) in enumerate(CHANGED):
        f = b / alg / name
        f.write_text(modified(f.read_text(), what, seed=k))
    return a, b


def run(capsys, *args) -> tuple[int, str, str]:
    rc = main(["diff", *map(str, args), "--no-progress"])
    out = capsys.readouterr()
    return rc, out.out, out.err


@pytest.mark.thorough
def test_diff_flags_exactly_the_changed_sequences(versions, tmp_path, capsys):
    """Must show (issue 25): diff flags exactly the sequences changed, exits 1; identical runs exit 0."""
    a, b = versions
    js, junit = tmp_path / "verdict.json", tmp_path / "verdict.xml"
    rc, out, _ = run(capsys, a, b, "--json", js, "--junit", junit)
    assert (
        rc == 1
        and "verdict: regression (4 sequence(s) regressed: odom home-2 failed; orbslam2_rgbd cafe-1 failed; "
        "odom corridor-3 ate_rmse, c_ate_rmse, rpe_trans_rmse; and 1 more)"
        in out  # the regressed ones named too
    )
    verdict = json.loads(js.read_text())
    assert verdict["verdict"] == "regression"
    flagged = {(r["algorithm"], r["scene"], r["seq"]) for r in verdict["regressions"] if r["seq"] is not None}
    assert flagged == {(alg, scene, seq) for alg, _, scene, seq, _ in CHANGED}
    for r in verdict["regressions"]:
        assert {"algorithm", "scene", "seq", "metric", "base", "cand"} <= set(r)
    by = {(r["algorithm"], r["scene"], r["seq"], r["metric"]): r for r in verdict["regressions"]}
    dropped = by[("odom", "home", 2, "sequence")]  # every pose gone: the sequence failed (no output)
    assert dropped["status"] in ("failed", "missing")
    noisy = by[("odom", "corridor", 3, "ate_rmse")]  # 1.5 m noise per axis on a 0.22 m ATE RMSE
    assert noisy["base"] == pytest.approx(0.2183, abs=1e-4) and noisy["cand"] > 2.0
    values = [r for r in verdict["regressions"] if r["metric"] != "sequence" and r["level"] == "sequence"]
    assert values and all("single run per side: no significance claimed" in r["decided_by"] for r in values)
    cases = ET.parse(junit).getroot().iter("testcase")
    failed = {(c.get("classname"), c.get("name")) for c in cases if c.find("failure") is not None}
    assert {("odom.home", "home-2"), ("odom.corridor", "corridor-3"), ("orbslam2_rgbd.cafe", "cafe-1"),
            ("orbslam2_rgbd.home", "home-5")} <= failed  # fmt: skip
    assert all(name.endswith("(scene)") for _, name in failed - {(f"{a}.{s}", f"{s}-{q}") for a, _, s, q, _ in CHANGED})

    rc, out, _ = run(capsys, a, a, "--json", tmp_path / "same.json")
    assert rc == 0 and "verdict: ok" in out
    same = json.loads((tmp_path / "same.json").read_text())
    assert same["verdict"] == "ok" and same["regressions"] == [] and same["counts"]["ok"] > 0


@pytest.mark.thorough
def test_diff_of_tables_and_a_missing_sequence(versions, tmp_path, capsys):
    a, b = versions
    ta, tb = tmp_path / "a.csv", tmp_path / "b.csv"
    for src, out in ((a, ta), (b, tb)):
        assert main(["evaluate", str(src), "--eps", "paper", "--phi", "30", "--csv", str(out), "--no-progress"]) == 0
    capsys.readouterr()
    rc, _, _ = run(capsys, ta, ta)
    assert rc == 0
    rc, out, _ = run(capsys, ta, tb, "--json", tmp_path / "t.json")
    flagged = {(r["algorithm"], r["scene"], r["seq"]) for r in json.loads((tmp_path / "t.json").read_text())["regressions"]
               if r["seq"] is not None}  # fmt: skip
    assert rc == 1 and flagged == {(alg, scene, seq) for alg, _, scene, seq, _ in CHANGED}
    # a sequence present in BASE and missing in CAND is a regression
    cand = pd.read_csv(ta)
    cand = cand[~((cand["algorithm"] == "odom") & (cand["scene"] == "market") & (cand["seq"] == 1))]
    cand.to_csv(tmp_path / "lacking.csv", index=False)
    rc, out, _ = run(capsys, ta, tmp_path / "lacking.csv", "--json", tmp_path / "m.json")
    regs = json.loads((tmp_path / "m.json").read_text())["regressions"]
    assert rc == 1 and {(r["scene"], r["seq"], r["metric"], r["cand"]) for r in regs if r["seq"] is not None} == {
        ("market", 1, "sequence", "missing")
    }
    scene_cr = [r for r in regs if r["seq"] is None and r["metric"] == "cr"]  # counted as failed in the scene
    assert len(scene_cr) == 1 and scene_cr[0]["cand"] < scene_cr[0]["base"] - 0.1
    # other thresholds: refused, not compared
    other = tmp_path / "other.csv"
    assert main(["evaluate", str(a), "--eps", "1", "--phi", "30", "--csv", str(other), "--no-progress"]) == 0
    capsys.readouterr()
    rc, _, err = run(capsys, ta, other)
    assert rc == 2 and "not comparable" in err and "eps" in err
    # only what differs (eps paper: 3 m in cafe and home, 5 m in corridor and market), scenes grouped
    assert (f"cafe, home: eps = 3.0 in {ta} against 1.0 in {other}; corridor, market: eps = 5.0 in {ta} against "
            f"1.0 in {other}. Compare") in err  # fmt: skip
    # history over bare tables: ordered by modification time, the change found, other thresholds marked
    for k, f in enumerate((ta, tb, other)):
        os.utime(f, (1.7e9 + 100 * k, 1.7e9 + 100 * k))
    hist = tmp_path / "history.csv"
    # the newest run (other.csv, other thresholds) has no baseline: nothing judged, exit 2 (it was 0)
    assert main(["history", str(other), str(tb), str(ta), "--metric", "cr", "--csv", str(hist)]) == 2
    out = capsys.readouterr().out
    assert "newest run other.csv: no earlier run is comparable with it" in out and "nothing judged (exit 2" in out
    assert "ordered by modification time" in out
    assert (
        "orbslam2_rgbd cafe cr: first change in b.csv against a.csv (0.4860 -> 0.0985, a sequence or trial lost)" in out
    )
    h = pd.read_csv(hist)
    assert list(h.drop_duplicates("run")["run"]) == ["a.csv", "b.csv", "other.csv"]
    mark = h.drop_duplicates("run").set_index("run")
    assert mark.loc["b.csv", "comparable"] and not mark.loc["other.csv", "comparable"]
    assert "eps" in mark.loc["other.csv", "not_comparable"]
    # a run with other thresholds between two comparable runs hides nothing (issue 44): b.csv is
    # compared with a.csv, its last comparable run, finds the change, and history exits 1 as diff does
    for k, f in enumerate((ta, other, tb)):
        os.utime(f, (1.7e9 + 100 * k, 1.7e9 + 100 * k))
    assert main(["history", str(other), str(tb), str(ta), "--metric", "cr", "--csv", str(hist), "--force"]) == 1
    out = capsys.readouterr().out
    assert "b.csv: 2023-11-14T22:16:40+00:00, against a.csv" in out
    assert "not comparable: b.csv with the run before it" in out and "compared with a.csv instead" in out
    assert "orbslam2_rgbd cafe cr: first change in b.csv against a.csv" in out
    assert "newest run b.csv against a.csv: regression" in out
    assert main(["diff", str(ta), str(tb), "--no-progress"]) == 1  # the same pair, the same verdict
    capsys.readouterr()
    rc, _, err = run(capsys, ta, tb, "--scale")  # an evaluate option cannot apply to tables
    assert rc == 2 and "--scale" in err
    rc, _, err = run(capsys, ta, tb, "--tolerance", "cr=-1")
    assert rc == 2 and "tolerance cr=-1" in err
    # a damaged table: named, with the line of a number no evaluation gives (cr 1.7 said "ok")
    damaged = pd.read_csv(ta)
    damaged.loc[2, "cr"] = 1.7
    damaged.to_csv(tmp_path / "cr17.csv", index=False)
    rc, _, err = run(capsys, ta, tmp_path / "cr17.csv")
    assert rc == 2 and f"{tmp_path / 'cr17.csv'}, line 4: column cr: 1.7 is not a rate between 0 and 1" in err
    damaged = pd.read_csv(ta)
    damaged.loc[0, "ate_rmse"] = -0.5
    damaged.to_csv(tmp_path / "neg.csv", index=False)
    rc, _, err = run(capsys, tmp_path / "neg.csv", ta)
    assert rc == 2 and "line 2: column ate_rmse: -0.5 is not an RMSE >= 0" in err
    twice = pd.read_csv(ta)  # one sequence's row twice: which table says so
    pd.concat([twice, twice.iloc[[3]]]).to_csv(tmp_path / "twice.csv", index=False)
    rc, _, err = run(capsys, ta, tmp_path / "twice.csv")
    assert (
        rc == 2 and f"error: {tmp_path / 'twice.csv'}, line 32: " in err and "has several rows (lines 5 and 32)" in err
    )


@pytest.mark.slow
def test_tables_of_other_specs_name_only_the_keys_that_differ(icra20, tmp_path, capsys):
    """Two tables of one folder, one aligned as ``lorisnb report`` aligns monocular systems
    (``--scale auto``): refused as not comparable, naming the one spec key that differs and the
    option that sets it, not both specs whole."""
    se3, auto = tmp_path / "se3.csv", tmp_path / "auto.csv"
    for out, more in ((se3, []), (auto, ["--scale", "auto"])):
        assert main(["evaluate", str(icra20 / "per-seq" / "dso"), "--csv", str(out), "--no-progress", *more]) == 0
    capsys.readouterr()
    rc, _, err = run(capsys, se3, auto)
    assert rc == 2
    assert f'cafe, corridor, home, market: spec align: "se3" in {se3} against "auto" in {auto}. Compare' in err
    assert "--scale auto" in err and '"association"' not in err


def test_a_table_that_lost_its_spec_column_is_not_comparable_with_one_that_has_it(icra20, tmp_path, capsys):
    """A table scored with --scale whose spec column was dropped (by hand, or by another tool) against
    one scored SE(3): refused naming the column, not judged ok (its ATE was half the base's)."""
    import pandas as pd

    se3, sim3 = tmp_path / "se3.csv", tmp_path / "sim3.csv"
    for out, more in ((se3, []), (sim3, ["--scale", "on"])):
        assert main(["evaluate", str(icra20 / "per-seq" / "dso"), "--csv", str(out), "--no-progress", *more]) == 0
    pd.read_csv(sim3).drop(columns=["spec"]).to_csv(tmp_path / "nospec.csv", index=False)
    capsys.readouterr()
    rc, _, err = run(capsys, se3, tmp_path / "nospec.csv")
    assert rc == 2 and f"spec recorded in {se3}, not in {tmp_path / 'nospec.csv'}" in err, err
    rc, _, err = run(capsys, tmp_path / "nospec.csv", tmp_path / "nospec.csv")  # neither records it: as they are
    assert rc == 0, err


def test_a_spec_key_one_table_lacks_is_its_default(icra20, tmp_path, capsys):
    """A table written before a spec key existed (its spec JSON lacks the key) against a run whose
    spec holds that key at its default: comparable (every archived run was "not comparable", exit
    2, once a key was added), for every key the spec has, defaults taken from the spec itself; a
    value other than the default against the missing key is still refused, naming the key."""
    from lorisnb.core.spec.evalspec import EvalSpec
    from lorisnb.tools.decisions.runs import setting_differences, unset_defaults

    new = tmp_path / "new.csv"
    assert main(["evaluate", str(icra20 / "per-seq" / "dso"), "--csv", str(new), "--no-progress"]) == 0
    capsys.readouterr()
    table = pd.read_csv(new)
    spec = json.loads(table["spec"].iloc[0])
    for key in EvalSpec().to_dict():  # every current key (and a future one as it is added)
        if key not in spec:
            continue
        old = table.assign(spec=json.dumps({k: v for k, v in spec.items() if k != key}))
        assert setting_differences(old, table) == [] and setting_differences(table, old) == [], key
    old = tmp_path / "old.csv"
    table.assign(spec=json.dumps({k: v for k, v in spec.items() if k != "repair_stamps"})).to_csv(old, index=False)
    rc, out, err = run(capsys, old, new)
    assert rc == 0 and "verdict: ok" in out, err
    other = tmp_path / "other.csv"
    table.assign(spec=json.dumps({**spec, "repair_stamps": True})).to_csv(other, index=False)
    rc, _, err = run(capsys, old, other)
    assert rc == 2 and f"spec repair_stamps: (not set) in {old} against true in {other}" in err, err
    assert '"association"' not in err
    # run.json specs likewise (history, diff --baseline last-comparable of report runs)
    a, b = {"preset": "tum", "association": "nearest"}, {"preset": "tum"}
    assert unset_defaults(a, b) == (b, b)  # the preset's default: tum associates the nearest stamps
    assert unset_defaults({"preset": "openloris", "association": "nearest"}, {"preset": "openloris"})[0] != {
        "preset": "openloris"
    }
    # a setting column a table lacks is its default too; one that is not the default is named
    assert setting_differences(table.drop(columns=["official_interpolation"]), table) == []
    official = table.assign(official_interpolation=True, spec=json.dumps({**spec, "official_interpolation": True}))
    said = setting_differences(table, official)
    assert said == ["cafe, corridor, home, market: spec official_interpolation: false in BASE against true in CAND"]


def test_diff_of_report_runs_and_history(versions, tmp_path, capsys):
    """Two report run folders (run.json + per-sequence CSV tables), then history over three runs."""
    a, b = versions
    runs = []
    for k, (src, version) in enumerate(((a, "0.3.0"), (b, "0.3.0"), (b, "0.4.0"))):
        folder = tmp_path / f"run-{k}"
        (folder / "per_sequence_benchmark").mkdir(parents=True)
        assert main(["evaluate", str(src), "--eps", "paper", "--phi", "30", "--no-progress",
                     "--csv", str(folder / "per_sequence_benchmark" / "sequences.csv")]) == 0  # fmt: skip
        meta = dict(command=["lorisnb", "report"], lorisnb_version=version, commit="abc", spec={"eps": "paper", "phi": 30},
                    data_root="/data", created=f"2026-11-0{k + 1}T02:00:00+00:00",
                    inputs={"/data/openloris-scene/groundtruth/gt_home_1.txt": "e3b0" * 16}, notebooks={})  # fmt: skip
        (folder / "run.json").write_text(json.dumps(meta))
        runs.append(folder)
    capsys.readouterr()
    rc, out, _ = run(capsys, runs[0], runs[1], "--json", tmp_path / "r.json")
    flagged = {(r["algorithm"], r["scene"], r["seq"]) for r in json.loads((tmp_path / "r.json").read_text())["regressions"]
               if r["seq"] is not None}  # fmt: skip
    assert rc == 1 and flagged == {(alg, scene, seq) for alg, _, scene, seq, _ in CHANGED}
    changed = json.loads((runs[2] / "run.json").read_text())
    changed["spec"] = {"eps": 1, "phi": 30}
    (tmp_path / "spec.json").write_text(json.dumps(changed))
    odd = tmp_path / "odd-run"
    shutil.copytree(runs[2], odd)
    (odd / "run.json").write_text(json.dumps(changed))
    rc, _, err = run(capsys, runs[0], odd)
    assert rc == 2 and "spec" in err

    regt = tmp_path / "run-3"  # the ground truth changed under the same version
    shutil.copytree(runs[2], regt)
    meta = json.loads((runs[2] / "run.json").read_text())
    meta.update(
        created="2026-11-04T02:00:00+00:00", inputs={"/data/openloris-scene/groundtruth/gt_home_1.txt": "ff" * 32}
    )
    (regt / "run.json").write_text(json.dumps(meta))
    csv, figs = tmp_path / "history.csv", tmp_path / "figures"
    rc = main(["history", str(runs[2]), str(regt), str(runs[0]), str(runs[1]), "--csv", str(csv), "--out", str(figs)])
    out = capsys.readouterr().out
    assert rc == 2 and "newest run run-3: no earlier run is comparable with it" in out  # nothing judged
    h = pd.read_csv(csv)
    assert list(h.drop_duplicates("run")["run"]) == ["run-0", "run-1", "run-2", "run-3"]  # by run.json's time
    assert (
        "ground truth changed: gt_home_1.txt"
        in h.drop_duplicates("run").set_index("run").loc["run-3", "not_comparable"]
    )
    cafe = h[(h["algorithm"] == "orbslam2_rgbd") & (h["scene"] == "cafe") & (h["metric"] == "cr")].set_index("run")
    assert cafe.loc["run-1", "value"] < cafe.loc["run-0", "value"] - 0.3  # its first sequence stopped tracking
    assert cafe.loc["run-1", "changed"] and not cafe.loc["run-0", "changed"]  # the first run where it changed
    assert cafe.loc["run-1", "status"] == "missing" and cafe.loc["run-1", "baseline"] == "run-0"  # cafe 1 lost
    assert cafe.loc["run-2", "comparable"] == False and "lorisnb_version" in cafe.loc["run-2", "not_comparable"]  # noqa: E712
    assert "first change" in out and (figs / "history_cr.png").is_file() and (figs / "history_cr.svg").is_file()


@pytest.mark.thorough
def test_diff_of_report_runs_counts_the_inputs_their_findings_did_not_score(versions, tmp_path, capsys):
    """A report run lists the inputs its own evaluation could not score in
    ``findings/input_errors.csv``: diff of such a run exits 1, as diff of its result folder does
    (and as the report itself did); a skipped input (no ground truth for its scene) does not count."""
    a, _ = versions
    folder = tmp_path / "run"
    (folder / "findings").mkdir(parents=True)
    assert main(["evaluate", str(a), "--no-progress", "--csv", str(folder / "findings" / "sequences.csv")]) == 0
    meta = dict(command=["lorisnb", "report"], lorisnb_version="0.3.0", commit="abc", spec={}, data_root="/data",
                created="2026-11-01T02:00:00+00:00", inputs={}, notebooks={})  # fmt: skip
    (folder / "run.json").write_text(json.dumps(meta))
    errors = folder / "findings" / "input_errors.csv"
    errors.write_text("file,status,kind,error\n/r/odom/office-1.txt,skipped,no-groundtruth,no ground truth\n")
    capsys.readouterr()
    rc, _, err = run(capsys, folder, folder)
    assert rc == 0, err
    errors.write_text(errors.read_text() + "/r/odom/cafe-1.txt,not scored,no-overlap,no estimate stamp falls inside\n")
    rc, out, err = run(capsys, folder, folder)
    # nothing regressed, inputs lost: "incomplete", as the exit status says (it printed "verdict: ok")
    assert rc == 1 and "verdict: incomplete (2 input(s) not scored" in out and "1 input(s) of BASE and 1 of CAND" in err


@pytest.mark.thorough
def test_scene_values_of_diff_and_history_are_the_leaderboards(tmp_path, icra20, data, capsys):
    """Scene values counted only the sequences some row held: with home's sequences 3-5 lacking
    for every algorithm, diff and history gave home CR 0.0341 where evaluate, compare and the
    leaderboard give 0.0197 (2 of 5). And a report run was read from every notebook's table (other
    thresholds, simulated algorithms: 380 sequences for 216): it is the report's own findings."""
    import lorisnb as ln

    res = tmp_path / "res"
    for alg in ALGORITHMS:
        (res / alg).mkdir(parents=True)
        for f in sorted((icra20 / "per-seq" / alg).iterdir()):
            if f.name.replace("_", "-").startswith(("home-1-1", "home-1-2", "cafe")):
                shutil.copy(f, res / alg / f.name)
    ev = ln.evaluate(res, data_root=data.root, jobs=1)
    scenes = ev.scenes().set_index(["algorithm", "scene"])
    assert list(scenes.xs("home", level="scene")["scene_sequences"]) == [5, 5]  # home: 5 sequences, 2 with output
    # a report run: the findings, and a notebook's table at other thresholds with a simulated algorithm
    run = tmp_path / "run"
    (run / "findings").mkdir(parents=True)
    (run / "per_sequence_benchmark").mkdir()
    ev.sequences().to_csv(run / "findings" / "sequences.csv", index=False)
    ev.durations().to_csv(run / "findings" / "durations.csv", index=False)
    other = ev.sequences(eps=1.0, phi=30.0).assign(algorithm=lambda t: "simulated: " + t["algorithm"])
    other.to_csv(run / "per_sequence_benchmark" / "sequences.csv", index=False)
    meta = dict(command=["lorisnb", "report"], lorisnb_version="0.3.0", commit="abc", spec={}, data_root="/data",
                created="2026-11-01T02:00:00+00:00", inputs={}, notebooks={})  # fmt: skip
    (run / "run.json").write_text(json.dumps(meta))
    for base in (res, run):  # a result folder and a report run: the same scene values as evaluate's
        out = tmp_path / f"d-{base.name}.csv"
        capsys.readouterr()
        assert main(["diff", str(base), str(base), "--csv", str(out), "--no-progress"]) == 0, capsys.readouterr().err
        d = pd.read_csv(out)
        rows = d[(d["level"] == "scene") & d["metric"].isin(["cr", "cs_r"])]
        for r in rows.itertuples():
            assert r.base == pytest.approx(scenes.loc[(r.algorithm, r.scene), r.metric], rel=1e-12), r
        assert len(rows) == 2 * len(scenes)
        seq = d[d["level"] == "sequence"].drop_duplicates(["algorithm", "scene", "seq"])
        assert len(seq) == len(ev.sequences())  # the findings only, not the notebook's simulated rows
    hist = tmp_path / "history.csv"
    assert main(["history", str(run), "--csv", str(hist)]) == 2  # one run: its values, nothing judged
    h = pd.read_csv(hist)
    h = h[h["metric"] == "cr"].set_index(["algorithm", "scene"])["value"]
    assert set(h.index) == set(scenes.index)
    for key, v in h.items():
        assert v == pytest.approx(scenes.loc[key, "cr"], rel=1e-12)


def test_regression_core_on_trials():
    """Three trials a side: a shift the tolerance allows is no regression; a shift beyond it on every
    trial is one, found by the t-test with the trials' pooled spread, at sequence and scene level;
    identical trials change nothing."""
    rows = []
    for run_, shift in (("base", 0.0), ("small", -0.01), ("big", -0.2)):
        for seq in (1, 2, 3, 4, 5):
            for trial, noise in enumerate((0.0, 0.01, -0.01), start=1):
                rows.append(dict(run=run_, suite="", algorithm="x", scene="home", seq=seq, trial=trial,
                                 cr=0.8 + shift + noise + 0.01 * seq, gt_duration=100.0, matched=100))  # fmt: skip
    t = pd.DataFrame(rows)
    base = t[t["run"] == "base"]
    tol = parse_tolerances("cr=0.02")
    same = sequence_changes(base, base, tol)
    assert (same["status"] == "ok").all()
    small = sequence_changes(base, t[t["run"] == "small"], tol)
    assert (small["status"] == "ok").all()
    big = sequence_changes(base, t[t["run"] == "big"], tol)
    assert set(big.loc[big["metric"] == "cr", "status"]) == {"regression"}
    assert big["decided_by"].str.contains("t-test of the change beyond the tolerance \\(3 vs 3 trials").all()
    assert (big["p_adj"] < 1e-6).all()
    scenes = scene_changes(base, t[t["run"] == "big"], tol)
    row = scenes[scenes["metric"] == "cr"].iloc[0]
    assert row["status"] == "regression" and row["p_adj"] < 0.01 and "Holm over the diff's" in row["decided_by"]
    with pytest.raises(ValidationError, match="not a compared metric"):
        parse_tolerances("speed=3")
    assert str(parse_tolerances("ate_rmse=5%")["ate_rmse"]) == "5%"
    # one value given twice in one list kept the last silently; an empty item was dropped
    with pytest.raises(ValidationError, match="cr given twice; expected each metric once"):
        parse_tolerances("cr=0.5,cr=0.1")
    for empty in ("cr=0.1,,cs_r=0.1", "cr=0.1,"):
        with pytest.raises(ValidationError, match="an empty item between commas"):
            parse_tolerances(empty)
    # a rate's tolerance of 1 or more (100 %) let nothing regress: diff cr=2 passed every night (exit 0)
    for never in ("cr=2", "cr_t=1", "cs_r=100%", "cr=250%"):
        with pytest.raises(ValidationError, match="is a rate between 0 and 1, so no drop would ever exceed it"):
            parse_tolerances(never)
    assert parse_tolerances("cr=0.99,ate_rmse=300%")["ate_rmse"].amount == 3.0  # an error may triple


@pytest.mark.thorough
def test_diff_in_python(versions):
    """The same verdict through Python: two Evaluations' tables and lorisnb.tools.decisions.diff.diff_tables."""
    import lorisnb as ln
    from lorisnb.tools.decisions.diff import diff_tables

    a, b = (ln.evaluate(v).sequences(eps="paper", phi=30) for v in versions)
    d = diff_tables(a, b, "cr=0.02,ate_rmse=10%")
    flagged = {(r["algorithm"], r["scene"], r["seq"]) for r in d.verdict["regressions"] if r["seq"] is not None}
    assert d.regressed and flagged == {(alg, scene, seq) for alg, _, scene, seq, _ in CHANGED}
    assert not diff_tables(a, a).regressed
    with pytest.raises(ValidationError, match="tolerance cr=x"):
        diff_tables(a, b, {"cr": "x"})


@pytest.mark.thorough
def test_diff_with_an_empty_or_broken_side(versions, tmp_path, capsys):
    """An empty BASE said "verdict: ok" (every CAND sequence "new"), exit 0; an empty CAND folder,
    or one whose every file is broken (the usual CI failure), crashed with a KeyError (pandas
    selecting columns by an empty list). Now: an empty BASE compares nothing, exit 1 with why; an
    empty or broken CAND fails every BASE sequence, exit 1."""
    a, _ = versions
    empty = tmp_path / "empty"
    empty.mkdir()
    rc, out, err = run(capsys, empty, a)
    assert rc == 1 and "verdict" not in out
    assert f"error: BASE {empty} holds no scored sequence (1 input(s) could not be evaluated or were not scored): " \
        "nothing was compared" in err  # fmt: skip
    broken = tmp_path / "broken" / "odom"
    broken.mkdir(parents=True)
    for f in (a / "odom").iterdir():
        (broken / f.name).write_text("")
    for cand in (empty, broken.parent):
        rc, out, err = run(capsys, a, cand)
        assert rc == 1 and "Traceback" not in err and "verdict: regression" in out
        flagged = int(out.split("verdict: regression (")[1].split()[0])
        assert flagged == int(out.split(" sequence(s); per metric")[0].split()[-1])  # every BASE sequence
