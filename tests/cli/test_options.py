"""Every command-line option takes effect or is refused (or noted), on every input kind: OpenLORIS
result files, a TUM pair, a manifest of sessions and a ROS bag pair. The options are enumerated from
the parser itself, so a new option without a case here fails ``test_every_option_has_a_case``."""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from helpers import write, write_bag

import lorisnb as ln
from lorisnb.cli import build_parser, main
from lorisnb.core.trajectory.poses import Trajectory

TUM = "tum-rgbd"

#: option -> (arguments with it, the arguments it is contrasted with). The option is honoured when
#: the two runs give different tables, or it is refused (exit 2, the option named), or noted.
CASES: dict[str, tuple[list[str], list[str]]] = {
    "--eps": (["--eps", "0.02"], []),
    "--phi": (["--phi", "0.5"], []),
    "--delta": (["--delta", "0.01"], []),
    "--tau": (["--tau", "0.5"], []),
    "--scale": (["--scale", "on"], []),
    "--per-seq": (["--per-seq"], ["--lifelong"]),
    "--lifelong": (["--lifelong"], ["--per-seq"]),
    "--official-interpolation": (["--official-interpolation"], []),
    "--official-lifelong": (["--official-lifelong"], []),  # cafe_x1's first sequence is empty
    "--repair-stamps": (["--repair-stamps"], []),
    "--keep-repeated": (["--keep-repeated"], []),
    "--conventions": (["--conventions", "tum"], []),
    "--association": (["--association", "nearest"], []),
    "--max-gap": (["--max-gap", "0.01"], []),
    "--max-diff": (["--association", "nearest", "--max-diff", "0.003"], ["--association", "nearest"]),
    "--t-offset": (["--t-offset", "0.3"], []),
    "--align": (["--align", "posyaw"], []),
    "--align-frames": (["--align-frames", "5"], []),
    "--rpe-delta": (["--rpe-delta", "3"], []),
    "--rpe-unit": (["--rpe-unit", "f"], []),
    "--relative": (["--relative"], []),
    "--trials-by": (["--trials-by", r"x(\d)"], []),
    "--scene": (["--scene", "somewhere"], []),
    # evo's options (issue 23)
    "--align-origin": (["--align-origin"], []),
    "--t-start": (["--t-start", "1560000100"], []),  # inside the OpenLORIS home sequence; after fr1_xyz
    "--t-end": (["--t-end", "1305031110"], []),  # inside fr1_xyz; before every OpenLORIS stamp
    "--project-to-plane": (["--project-to-plane", "xz"], []),
    "--downsample": (["--downsample", "50"], []),
    "--motion-filter": (["--motion-filter", "0.05", "5"], []),
    "--relation": (["--relation", "full"], []),
    # the KITTI metric's (issue 45): refused without --conventions kitti (tests/cli/test_kitti_conventions.py)
    "--kitti-precision": (["--kitti-precision", "double"], []),
    "--tartanair-scale": (["--tartanair-scale"], []),  # refused without --conventions tartanair
    "--tartanair-seed": (["--tartanair-seed", "3"], []),
    "--relative-lengths": (["--relative-lengths", "0.5,1"], []),
    "--change-unit": (["--relation", "trans_part", "--change-unit", "mm"], ["--relation", "trans_part"]),
    "--rpe-pairs": (["--rpe-unit", "m", "--rpe-pairs", "estimate"], ["--rpe-unit", "m"]),
    "--rpe-all-pairs": (["--rpe-unit", "m", "--rpe-all-pairs"], ["--rpe-unit", "m"]),
    "--rpe-consecutive": (["--rpe-consecutive"], []),
    "--rpe-tolerance": (
        ["--rpe-unit", "m", "--rpe-all-pairs", "--rpe-tolerance", "0.01"],
        ["--rpe-unit", "m", "--rpe-all-pairs"],
    ),
}
#: Options that say what to read (checked below: refused where they cannot apply), how to run, or
#: where to write (checked by their own tests: test_speed_scale, test_safety, test_data_and_cli).
READING = {"--gt", "--format", "--gt-format", "--manifest", "--topic", "--gt-topic", "--tf", "--gt-tf", "--gt-times",
           "--est-times", "--data", "--manifest-outside"}  # fmt: skip  # --manifest-outside: tests/io/test_manifest_reach.py
RUNNING = {"--jobs", "--scheduler", "--no-progress", "--csv", "--parquet", "--force", "--help", "--digits",
           "--kitti-plot"}  # fmt: skip
OWN = {  # options of one command, with their cases
    "sweep": {
        "--relative-to": (["--eps", "0.1", "--relative-to", "extent"], ["--eps", "0.1"]),
        "--columns": (["--columns", "all"], []),
    },
    "compare": {
        "--metric": (["--metric", "cs_r"], []),
        "--level": (["--level", "0.5"], []),
        "--alpha": (["--alpha", "0.5"], []),
        "--seed": ([], []),  # test_compare: seeds, tables
        "--pairs-csv": ([], []),
        "--power": (["--power", "0.5"], []),
        "--latex": ([], []),
        "--markdown": ([], []),  # test_stats: seeds, tables
    },  # fmt: skip
}


def _options(command: str) -> set[str]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices[command]
    return {o for a in sub._actions for o in a.option_strings if o.startswith("--")}


@pytest.mark.parametrize("command", ["evaluate", "sweep", "compare"])
def test_every_option_has_a_case(command):
    missing = _options(command) - set(CASES) - READING - RUNNING - set(OWN.get(command, {}))
    assert not missing, f"options of {command} without a case in tests/cli/test_options.py: {sorted(missing)}"


@pytest.fixture(scope="module")
def kinds(tmp_path_factory, data):
    """The same kind of work in four inputs: OpenLORIS files (a lifelong file with unpadded stamps and
    a per-sequence file), a TUM pair, a two-session manifest, a ROS 1 bag pair."""
    d = tmp_path_factory.mktemp("kinds")
    ol = d / "ol" / "maslam"
    ol.mkdir(parents=True)
    text = (data.icra20 / "lifelong" / "maslam" / "home.txt").read_text().splitlines(keepends=True)
    k = next(i for i, line in enumerate(text) if i > 40 and len(line.split()) in (8, 9))
    stamp, *pose = text[k].split()  # (an output time, then) the pose
    stalled = f"{float(stamp) + 0.01:.9f} {' '.join(pose)}\n"  # the tracker repeats its pose (--keep-repeated)
    write(ol, "home_x1.txt", "".join(text[: k + 1] + [stalled] + text[k + 1 :]))
    # a lifelong file whose first sequence is an empty block (--official-lifelong: then nothing is aligned)
    cafe = (data.icra20 / "lifelong" / "maslam" / "cafe.txt").read_text().splitlines(keepends=True)
    two = next(i for i, line in enumerate(cafe) if line.startswith("seq: 2"))
    write(
        ol, "cafe_x1.txt", "".join([*(line for line in cafe[:two] if not line[:1].isdigit()), *cafe[two : two + 400]])
    )
    gt = ln.read_tum(data.root / TUM / "freiburg1_xyz-groundtruth.txt")
    est = ln.read_tum(data.root / TUM / "freiburg1_xyz-rgbdslam.txt")
    half = len(est) // 2
    # a repeated pose (for --keep-repeated) in the pair's estimate
    lines = (data.root / TUM / "freiburg1_xyz-rgbdslam.txt").read_text().splitlines(keepends=True)
    body = [ln_ for ln_ in lines if not ln_.startswith("#")]
    pair = write(d, "pair/rgbd/est_x1.txt", "".join(body[:300] + [body[299]] + body[300:]))
    man = d / "man" / "rgbd_x1"  # a trial token in the algorithm's folder (--trials-by)
    man.mkdir(parents=True)
    # a repeated stamp (for --keep-repeated: evo's rule keeps both poses) in every input kind
    rep = np.insert(np.arange(len(est)), 100, 100)
    est = Trajectory.from_checked(est.stamps[rep], est.positions[rep], est.quaternions[rep])  # kept: no check
    half = len(est) // 2
    for k, sl in ((1, slice(0, half)), (2, slice(half, None))):
        sub = Trajectory.from_checked(est.stamps[sl], est.positions[sl], est.quaternions[sl])
        write(man, f"s{k}_x1.txt", "".join(f"{t} {' '.join(map(str, p))} {' '.join(map(str, q))}\n"
                                          for t, p, q in zip(sub.stamps.tolist(), sub.positions.tolist(),
                                                             sub.quaternions.tolist(), strict=True)))  # fmt: skip
    shutil.copy(data.root / TUM / "freiburg1_xyz-groundtruth.txt", d / "man" / "gt.txt")
    manifest = write(d, "man/m.toml", "lifelong = true\n"
                     "[[session]]\nname = 's1'\ngroundtruth = 'gt.txt'\nestimate = 's1_x1.txt'\n"
                     "[[session]]\nname = 's2'\ngroundtruth = 'gt.txt'\nestimate = 's2_x1.txt'\n")  # fmt: skip
    other = d / "man2"  # two algorithms over the same sessions, for compare
    shutil.copytree(d / "man", other)
    shutil.copytree(man, other / "noisy")
    for f in (other / "noisy").glob("s*_x1.txt"):
        rows = np.loadtxt(f)
        rows[:, 1:4] += np.random.default_rng(len(f.name)).normal(0, 0.03, (len(rows), 3))
        np.savetxt(f, rows, fmt="%.9f")
    (d / "bag" / "est").mkdir(parents=True)
    bag_gt = write_bag(d / "bag" / "gt.bag", gt, 1)
    bag_est = write_bag(d / "bag" / "est" / "est_x1.bag", est, 1, "nav_msgs/msg/Odometry", "/odom")
    return {
        "openloris": [str(d / "ol"), "--data", str(data.root)],
        "pair": [str(pair.parent.parent), "--gt", str(data.root / TUM / "freiburg1_xyz-groundtruth.txt")],
        "manifest": [str(d / "man"), "--manifest", str(manifest)],
        "two": [str(other), "--manifest", str(other / "m.toml")],
        "bag": [str(bag_est.parent), "--gt", str(bag_gt), "--format", "bag"],
    }


def _run(args: list[str], out: Path, capsys) -> tuple[int, str, str, pd.DataFrame | None]:
    capsys.readouterr()
    running = [] if args[0] == "crosscheck" else ["--no-progress", "--jobs", "1"]
    try:
        rc = main([*args, *running, "--csv", str(out), "--force"])
    except SystemExit as exc:
        rc = int(exc.code or 0)
    cap = capsys.readouterr()
    table = pd.read_csv(out).drop(columns=["spec"], errors="ignore") if rc in (0, 1) and out.exists() else None
    out.unlink(missing_ok=True)
    return rc, cap.out, cap.err, table


def _honoured(option: str, a: tuple, b: tuple) -> str:
    """How the option was honoured: 'refused', 'noted' or 'changed' (else an assertion fails)."""
    rc, out, err, table = a
    name = option.lstrip("-")
    if rc == 2:
        assert option in err or name in err or name.replace("-", "_") in err, (option, err)
        return "refused"
    assert rc in (0, 1), (option, err)
    if f"note: {option}" in err or f"{option} " in err.split("conventions:")[0]:
        return "noted"
    if option in ("--relative", "--relative-lengths"):
        assert out != b[1], "--relative printed nothing more"
        return "changed"
    assert table is not None and b[3] is not None, (option, err)
    same = table.shape == b[3].shape and table.equals(b[3])
    assert not same, f"{option} changed nothing and was not refused: {err[-500:]}"
    return "changed"


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["openloris", "pair", "manifest", "bag"])
def test_every_option_changes_the_result_or_is_refused(kind, kinds, tmp_path, capsys):
    base = kinds[kind]
    seen: dict[str, str] = {}
    for option, (with_it, contrast) in CASES.items():
        a = _run(["evaluate", *base, *with_it], tmp_path / "a.csv", capsys)
        b = _run(["evaluate", *base, *contrast], tmp_path / "b.csv", capsys)
        seen[option] = _honoured(option, a, b)
    # what must take effect where it means something (the rest may be refused)
    effective = {"--eps", "--phi", "--delta", "--tau", "--scale", "--conventions", "--association", "--t-offset",
                 "--align", "--align-frames", "--rpe-delta", "--rpe-unit", "--relative", "--trials-by"}  # fmt: skip
    assert {o for o in effective if seen[o] != "changed"} == set(), seen
    if kind == "openloris":
        assert seen["--repair-stamps"] == seen["--per-seq"] == seen["--official-interpolation"] == "changed", seen
        assert seen["--official-lifelong"] == "changed", seen
        assert seen["--scene"] == "refused"
    else:  # the official tool reads OpenLORIS result files only
        assert seen["--official-lifelong"] == "refused", seen
    if kind in ("pair", "bag"):
        assert seen["--scene"] == "changed" and seen["--repair-stamps"] == "refused", seen
    if kind == "manifest":
        assert seen["--per-seq"] == "changed", seen


@pytest.mark.parametrize("kind", ["openloris", "pair", "manifest", "bag"])
def test_reading_options_are_refused_where_they_cannot_apply(kind, kinds, tmp_path, capsys):
    base = kinds[kind]
    cases = {
        "--format": ["--format", "kitti"], "--gt-format": ["--gt-format", "euroc"], "--topic": ["--topic", "/x"],
        "--gt-topic": ["--gt-topic", "/x"], "--tf": ["--tf", "a:b"], "--gt-tf": ["--gt-tf", "a:b"],
        "--gt-times": ["--gt-times", str(tmp_path / "t.txt")], "--est-times": ["--est-times", str(tmp_path / "t.txt")],
        "--data": ["--data", str(tmp_path)],
    }  # fmt: skip
    for option, args in cases.items():
        if option in base or (kind in ("pair", "bag") and option in ("--format", "--gt-format")):
            continue  # what defines the kind, or a real choice of format (a wrong one fails the files)
        if kind == "bag" and option in ("--topic", "--gt-topic", "--tf", "--gt-tf"):
            continue  # they apply: a topic the bag lacks fails the file (test_pairs)
        rc, _, err, _ = _run(["evaluate", *base, *args], tmp_path / "a.csv", capsys)
        assert rc == 2 and option in err, (kind, option, rc, err[-300:])


def test_jobs_fan_out_every_input_kind(kinds, tmp_path, capsys, monkeypatch):
    import importlib

    evaluate_module = importlib.import_module("lorisnb.tools.evaluation.runner")

    seen = []
    real = evaluate_module.run_tasks
    monkeypatch.setattr(evaluate_module, "run_tasks", lambda fn, items, sizes, n, *a, **k: seen.append(n)
                        or real(fn, items, sizes, n, *a, **k))  # fmt: skip
    for kind in ("openloris", "pair", "manifest", "bag"):
        assert main(["evaluate", *kinds[kind], "--jobs", "2", "--no-progress"]) in (0, 1), kind
    assert seen == [2, 2, 2, 2]


@pytest.mark.parametrize("command", ["sweep", "compare"])
@pytest.mark.thorough
def test_options_of_sweep_and_compare(command, kinds, tmp_path, capsys):
    base = kinds["two"] + (["--eps", "0.03", "--phi", "3"] if command == "compare" else [])  # CR^inf: no alignment
    for option, (with_it, contrast) in OWN[command].items():
        if not with_it:
            continue  # outputs: test_stats and test_safety
        a = _run([command, *base, *with_it], tmp_path / "a.csv", capsys)
        b = _run([command, *base, *contrast], tmp_path / "b.csv", capsys)
        assert a[0] in (0, 1, 2), (option, a[2])
        assert a[0] == 2 or a[1] != b[1] or not (a[3] is not None and b[3] is not None and a[3].equals(b[3])), option
    # the shared options reach sweep and compare as they reach evaluate
    for option in ("--association", "--align", "--rpe-unit", "--max-gap"):
        with_it, contrast = CASES[option]
        a = _run([command, *base, *with_it], tmp_path / "a.csv", capsys)
        b = _run([command, *base, *contrast], tmp_path / "b.csv", capsys)
        if option == "--rpe-unit":  # no metric of compare's ranking, nor of sweep's default columns, depends on it
            assert a[0] == 2 and option in a[2], a[2][-300:]
            if command == "compare":
                continue
            a = _run([command, *base, *with_it, "--columns", "all"], tmp_path / "a.csv", capsys)  # its RPE columns
            b = _run([command, *base, *contrast, "--columns", "all"], tmp_path / "b.csv", capsys)
        assert a[0] in (0, 1) and a[3] is not None and not a[3].equals(b[3]), (command, option, a[2][-300:])


def test_crosscheck_refuses_options_of_other_formats(data, tmp_path, capsys):
    gt, est = (str(data.root / TUM / f) for f in ("fr2_desk_groundtruth.txt", "fr2_desk_ORB.txt"))
    for args in (["--seq", "2"], ["--data", str(data.root)], ["--times", gt], ["--gt-times", gt]):
        assert main(["crosscheck", gt, est, *args]) == 2
        assert args[0] in capsys.readouterr().err, args


@pytest.mark.thorough
def test_crosscheck_scale_auto_follows_the_algorithm(data, tmp_path, capsys):
    """--scale auto is Sim(3) only for monocular algorithms (dso, svo), not a truth test of the word."""
    gt = str(data.root / TUM / "fr2_desk_groundtruth.txt")
    src = data.root / TUM / "fr2_desk_ORB.txt"
    orb, dso = tmp_path / "orb.txt", tmp_path / "dso.txt"
    shutil.copy(src, orb)
    shutil.copy(src, dso)
    tables = {}
    for name, path, scale in (("orb", orb, "auto"), ("dso", dso, "auto"), ("se3", orb, "off")):
        assert main(["crosscheck", gt, str(path), "--scale", scale, "--csv", str(tmp_path / f"{name}.csv")]) in (0, 1)
        tables[name] = pd.read_csv(tmp_path / f"{name}.csv")
    assert tables["orb"].equals(tables["se3"]) and not tables["dso"].equals(tables["se3"])


def test_inputs_are_never_changed(data):
    """Loaders hand out fresh objects over read-only arrays; the core writes into no argument."""
    gt = ln.load_groundtruth("home", data)
    with pytest.raises(ValueError, match="read-only"):
        gt.sequences[1].positions[:] = 0.0
    original = gt.sequences[1].positions
    gt.sequences[1] = Trajectory(gt.sequences[1].stamps, original * 10, gt.sequences[1].quaternions)  # a user's edit
    again = ln.load_groundtruth("home", data)
    assert again is not gt and np.array_equal(again.sequences[1].positions, original)
    path = data.icra20 / "lifelong" / "maslam" / "home.txt"
    result = ln.read_openloris(path, warn=False)
    before = {s: (t.stamps.copy(), t.positions.copy(), t.quaternions.copy()) for s, t in result.sequences.items()}
    fe = ln.compute_errors(result, again)
    assert sorted(result.sequences) == sorted(before) and len(fe.sequences) == len(before)
    for s, (st, p, q) in before.items():
        t = result.sequences[s]
        assert np.array_equal(t.stamps, st) and np.array_equal(t.positions, p) and np.array_equal(t.quaternions, q)
    ate = ln.evaluate(path, data_root=data).sequences()["ate_rmse"].to_numpy()
    assert np.allclose(ate, ln.score(fe)["ate_rmse"].to_numpy(), equal_nan=True)  # the edited copy did not leak


#: crosscheck's options on a TUM pair: each changes the table, or is refused or fails naming why.
CROSSCHECK = {
    "--format": ["--format", "kitti"], "--est-format": ["--est-format", "kitti"], "--conventions": ["--conventions", "evo"],
    "--align": ["--conventions", "evo", "--align", "sim3"], "--topic": ["--topic", "/x"], "--gt-topic": ["--gt-topic", "/x"],
    "--scale": ["--scale", "on"], "--times": ["--times", "t.txt"], "--gt-times": ["--gt-times", "t.txt"],
    "--est-times": ["--est-times", "t.txt"], "--seq": ["--seq", "2"], "--rpe-frames": ["--rpe-frames", "3"],
    "--rpe-metres": ["--rpe-metres", "0.3"], "--all-pairs": ["--all-pairs"], "--data": ["--data", "."],
}  # fmt: skip


@pytest.mark.thorough
def test_every_crosscheck_option_changes_the_table_or_is_refused(data, tmp_path, capsys):
    missing = _options("crosscheck") - set(CROSSCHECK) - RUNNING
    assert not missing, f"options of crosscheck without a case in tests/cli/test_options.py: {sorted(missing)}"
    gt, est = (str(data.root / TUM / f) for f in ("freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"))
    base = _run(["crosscheck", gt, est], tmp_path / "b.csv", capsys)
    assert base[0] == 0 and base[3] is not None
    for option, args in CROSSCHECK.items():
        rc, out, err, table = _run(["crosscheck", gt, est, *args], tmp_path / "a.csv", capsys)
        if rc in (1, 2):  # refused (usage) or the files cannot be read that way: said, naming why
            assert "error" in err and (option in err or args[-1] in err or "kitti" in err.lower()), (option, err[-300:])
        else:
            assert table is not None and not table.equals(base[3]), f"crosscheck {option} changed nothing"


def test_openloris_reading_rules_reach_pairs(data, tmp_path):
    """An OpenLORIS file scored as a pair honours --repair-stamps and --keep-repeated as an OpenLORIS
    folder does (they were dropped by the pair reader)."""
    est = data.icra20 / "lifelong" / "maslam" / "home.txt"  # unpadded nanoseconds in seq 1
    gt = data.root / "openloris-scene" / "groundtruth" / "gt_home_1.txt"
    kw = dict(fmt="openloris")
    plain = ln.evaluate_pairs(est, gt, **kw).sequences()
    repaired = ln.evaluate_pairs(est, gt, repair_stamps=True, **kw).sequences()
    assert not plain[["matched", "ate_rmse"]].equals(repaired[["matched", "ate_rmse"]])
    with pytest.raises(ln.ValidationError, match="repair_stamps"):
        ln.evaluate_pairs(data.root / TUM / "fr2_desk_ORB.txt", data.root / TUM / "fr2_desk_groundtruth.txt",
                          repair_stamps=True)  # fmt: skip
