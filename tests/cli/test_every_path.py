"""One evaluation whatever the path: random combinations of spec options run on the real data through
the Python API, the command line (evaluate, sweep, compare), manifests (``[conventions]``) and a Dask
cluster on loopback must give the same tables number by number, the same ``conventions:`` line, and
be accepted or refused alike, with the same message.

Found by this probe and fixed:

- evo's time window (``t_start``/``t_end``) gave a sequence's CR over the window but its scene's CR
  (``Evaluation.scenes``, the command line's per-scene table, sweeps' scene rows) over the whole
  ground truth: one fr2_desk sequence scored CR 0.834 and its scene 0.582; ``compare``, ``diff`` and
  the report's leaderboard weighted the rows by yet other durations.
- ``motion_filter`` (and ``downsample``) shortened a sequence's ground-truth time to the poses the
  filter kept (which depends on the sensor frame the ground truth is moved to), so the scene's CR
  and ``compare``'s value differed from the rows' (0.072971 against 0.072811 on orbslam2_t265 cafe).
- a preset with the built-in OpenLORIS manifest was refused with three different messages, each
  saying OpenLORIS files are "scored with the official conventions", while ``lorisnb evaluate
  FILES --conventions tum`` scores them under ``tum``: now one message, naming that route.
"""

from __future__ import annotations

import random
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import LorisError, ParseError, ValidationError

FR2 = ("fr2_desk_ORB.txt", "fr2_desk_groundtruth.txt")
METRICS = ["poses", "matched", "ate_rmse", "aoe_rmse", "c_ate_rmse", "correct_time", "cr", "cr_t", "cs_r",
           "gt_duration", "rpe_trans_rmse", "rpe_rot_rmse"]  # fmt: skip


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


def _fr2(data):
    return str(data.tum / FR2[0]), str(data.tum / FR2[1])


def _same_numbers(a: pd.DataFrame, b: pd.DataFrame, columns=METRICS) -> None:
    assert len(a) == len(b) and len(a)
    for c in columns:
        x, y = a[c].to_numpy(float), b[c].to_numpy(float)
        assert ((x == y) | (np.isnan(x) & np.isnan(y))).all(), (c, x, y)


# --- the scene's time is its sequences' time -------------------------------------------------------


def test_a_time_window_gives_the_scene_the_cr_of_its_one_sequence(data):
    est, gt = _fr2(data)
    t0 = float(ln.read_trajectory(gt, "tum").stamps[0])
    ev = ln.evaluate_pairs(est, gt, "tum", eps=0.05, jobs=1, t_start=t0 + 30)
    row, scene = ev.sequences().iloc[0], ev.scenes().iloc[0]
    assert row["gt_duration"] == pytest.approx(69.3397, abs=1e-3)
    assert row["cr"] == pytest.approx(0.8339, abs=1e-4)
    assert scene["cr"] == pytest.approx(row["cr"], rel=1e-12)  # was 0.582: the whole 99.4 s ground truth
    assert ev.durations()["gt_duration"].tolist() == pytest.approx([row["gt_duration"]], rel=1e-12)
    ev = ln.evaluate_pairs(est, gt, "tum", eps=0.05, jobs=1, t_end=t0 + 50)
    assert ev.scenes()["cr"].iloc[0] == pytest.approx(ev.sequences()["cr"].iloc[0], rel=1e-12)  # was 0.353 vs 0.702


@pytest.mark.parametrize("thinning", [{"motion_filter": (0.05, 2.0)}, {"downsample": 100}])
def test_thinning_the_poses_keeps_the_sequence_time(data, thinning):
    est, gt = _fr2(data)
    whole = ln.evaluate_pairs(est, gt, "tum", eps=0.05, jobs=1).sequences()["gt_duration"].iloc[0]
    ev = ln.evaluate_pairs(est, gt, "tum", eps=0.05, jobs=1, **thinning)
    row = ev.sequences().iloc[0]
    assert row["gt_duration"] == whole == pytest.approx(99.3645, abs=1e-4)  # motion filter: was 99.1346
    assert ev.scenes()["cr"].iloc[0] == pytest.approx(row["cr"], rel=1e-12)


def test_compare_ranks_the_scene_value_evaluate_prints_under_a_motion_filter(data, tmp_path, capsys):
    results = tmp_path / "res"
    for alg, name in (("ds-slam", "cafe-1-1.txt"), ("orbslam2_t265", "cafe_1_orbslam2-original.txt")):
        suite = "lifelong" if alg == "orbslam2_t265" else "per-seq"
        (results / suite / alg).mkdir(parents=True, exist_ok=True)
        (results / suite / alg / name).symlink_to(data.icra20 / suite / alg / name)
    opts = ["--motion-filter", "0.05", "2", "--jobs", "1", "--no-progress", "--data", str(data.root)]
    assert main(["compare", str(results), *opts, "--csv", str(tmp_path / "c.csv")]) == 0
    capsys.readouterr()
    ev = ln.evaluate(results, data_root=data.root, jobs=1, motion_filter=(0.05, 2.0))
    both = pd.read_csv(tmp_path / "c.csv").merge(ev.scenes(), on=["suite", "algorithm", "scene"])
    assert len(both) == 2
    assert both["value"].to_numpy() == pytest.approx(both["cr"].to_numpy(), rel=1e-12, abs=1e-15)
    t265 = both[both["algorithm"] == "orbslam2_t265"].iloc[0]
    assert t265["cr"] == pytest.approx(0.072811, abs=1e-6)  # compare said 0.072971: rows over thinned durations


def test_a_manifest_session_without_estimate_counts_only_its_time_in_the_window(data, tmp_path):
    est, gt = data.tum / "freiburg1_xyz-rgbdslam.txt", data.tum / "freiburg1_xyz-groundtruth.txt"
    (tmp_path / "alg").mkdir()
    (tmp_path / "alg" / "xyz.txt").write_text(est.read_text())
    toml = tmp_path / "m.toml"
    toml.write_text(f'name = "two"\nscene = "two"\n[conventions]\npreset = "tum"\n'
                    f'[[session]]\nname = "xyz"\ngroundtruth = "{gt}"\n'
                    f'[[session]]\nname = "desk"\ngroundtruth = "{data.tum / FR2[1]}"\n')  # fmt: skip
    t0 = float(ln.read_trajectory(gt, "tum").stamps[0])
    ev = ln.evaluate_manifest(toml, tmp_path, jobs=1, eps=0.05, t_start=t0 + 5, t_end=t0 + 20)
    rows = ev.sequences().set_index("seq")
    assert rows.loc[2, "matched"] == 0 and rows.loc[2, "gt_duration"] == 0.0  # desk lies after the window
    assert rows.loc[1, "gt_duration"] == pytest.approx(15.0, abs=0.02)
    assert ev.scenes()["cr"].iloc[0] == pytest.approx(rows.loc[1, "cr"], rel=1e-12)


# --- a preset with the built-in OpenLORIS evaluation: one message -------------------------------------


def test_a_preset_with_the_openloris_manifest_is_refused_alike_naming_the_route_that_takes_it(data, tmp_path, capsys):
    src = data.icra20 / "per-seq" / "odom" / "cafe-1-1-odom.txt"
    said = []
    assert main(["evaluate", str(src), "--manifest", "openloris", "--conventions", "tum", "--no-progress"]) == 2
    said.append(capsys.readouterr().err.strip().splitlines()[-1].removeprefix("error: "))
    with pytest.raises(ValidationError) as exc:
        ln.evaluate_manifest("openloris", src, conventions="tum")
    said.append(str(exc.value))
    toml = tmp_path / "m.toml"
    toml.write_text('openloris = true\n[conventions]\npreset = "tum"\n')
    with pytest.raises(ParseError) as exc2:
        ln.evaluate_manifest(toml, src)
    said.append(str(exc2.value).removeprefix(f"{toml}: "))
    tails = {s.split(": ", 1)[1] for s in said}
    assert len(tails) == 1, said
    assert "lorisnb evaluate FILES --conventions tum" in said[0] and "official conventions" in said[0]
    ok = ln.evaluate(src, "tum", data_root=data.root, jobs=1)  # the route it names does take it
    assert ok.spec.association == "nearest" and len(ok.errors) == 1


# --- the property: random options, every path, the same numbers ---------------------------------------


def _draw(rng: random.Random, t0: float) -> dict:
    o: dict = {}
    pick = [
        ("conventions", ["openloris", "tum", "rpg", "vio", "evo"]), ("eps", [0.0, 0.02, 0.05, "relative:0.05", "inf"]),
        ("phi", [2, 5, 30]), ("delta", [0.5, 2.5]), ("tau", [10, 120]),
        ("align", ["se3", "sim3", "posyaw", "none", "scale", "origin"]), ("scale", ["auto", "on", "off"]),
        ("align_frames", [2, 50]), ("association", ["interpolate", "nearest", "evo-nearest", "evo-interpolate"]),
        ("max_diff", [0.01, 0.05]), ("max_gap", [0.1, 1.0]), ("t_offset", [0.01]), ("keep_repeated", [True]),
        ("rpe", [(2, "m"), (5, "frames"), (10, "deg")]), ("rpe_pairs", ["estimate"]), ("rpe_all_pairs", [True, False]),
        ("relation", ["full", "angle_deg", "point_distance"]), ("mode", ["per-seq", "lifelong"]),
        ("project_to_plane", ["xy"]), ("downsample", [300]), ("motion_filter", [(0.05, 2.0)]),
        ("t_start", [t0 + 10]), ("t_end", [t0 + 60]),
    ]  # fmt: skip
    for name, values in pick:
        if rng.random() < 0.25:
            o[name] = rng.choice(values)
    if "rpe" in o:
        o["rpe_delta"], o["rpe_unit"] = o.pop("rpe")
    if "scale" in o and "align" in o:
        del o["scale"]
    return o


def _cli(o: dict) -> list[str]:
    out: list[str] = []
    for k, v in o.items():
        if k == "scale":
            out += ["--scale", v]
        elif k == "keep_repeated":
            out.append("--keep-repeated")
        elif k == "mode":
            out.append(f"--{v}")
        elif k == "rpe_all_pairs":
            out.append("--rpe-all-pairs" if v else "--rpe-consecutive")
        elif k == "motion_filter":
            out += ["--motion-filter", str(v[0]), str(v[1])]
        else:
            out.append(f"--{k.replace('_', '-')}={v}")
    return out


def _python(o: dict) -> tuple[str | None, dict]:
    kw = dict(o)
    if "scale" in kw:
        kw["scale"] = {"auto": "auto", "on": True, "off": False}[kw["scale"]]
    return kw.pop("conventions", None), kw


def _toml(o: dict, gt: str) -> str:
    preset, kw = _python(o)
    lines = ['name = "probe"', 'scene = "fr2"', "[conventions]"] + ([f'preset = "{preset}"'] if preset else [])
    for k, v in kw.items():
        if isinstance(v, bool):
            v = "true" if v else "false"
        elif isinstance(v, str):
            v = "inf" if v == "inf" else f'"{v}"'
        elif isinstance(v, tuple):
            v = f"[{v[0]}, {v[1]}]"
        lines.append(f"{k} = {v}")
    return "\n".join(lines) + f'\n[[session]]\nname = "fr2"\ngroundtruth = "{gt}"\n'


def _message(text: str) -> str:
    """A refusal without the way each surface spells an option (``--max-diff`` is ``max_diff``)."""
    import re

    text = text.strip().splitlines()[-1] if text.strip() else ""
    text = re.sub(r"^(lorisnb \w+: )?(error: )?(argument [^:]+: )?(\S+\.toml(, line \d+)?: )?", "", text)
    text = re.sub(r" \([\w, ]+: set by the manifest \S+\)$", "", text)  # where a manifest's option came from
    text = re.sub(r"--([a-z-]+)", lambda m: m.group(1).replace("-", "_"), text)
    return text.replace("per_seq/lifelong", "mode").replace("keep_repeated", "repeated")


def _one_draw(o: dict, data, tmp_path: Path, capsys) -> list[str]:
    """The same evaluation through Python, evaluate, sweep and a manifest (Python and command line);
    what differs, one line each."""
    est, gt = _fr2(data)
    folder = tmp_path / "res" / "fr2"
    folder.mkdir(parents=True)
    (folder / "fr2.txt").symlink_to(est)
    toml = tmp_path / "m.toml"
    toml.write_text(_toml(o, gt))
    preset, kw = _python(o)
    o_mode = dict(o) if "mode" in o else {**o, "mode": "per-seq"}  # a manifest is per session unless it says
    paths = {
        "python": lambda: ln.evaluate_pairs(str(folder / "fr2.txt"), gt, _python(o_mode)[0], jobs=1, scene="fr2",
                                            **_python(o_mode)[1]),
        "manifest-python": lambda: ln.evaluate_manifest(toml, tmp_path / "res", jobs=1),
    }  # fmt: skip
    got: dict[str, tuple[str, object]] = {}
    for name, call in paths.items():
        try:
            got[name] = ("ok", call())
        except LorisError as exc:
            got[name] = ("refused", _message(str(exc)))
    pair = [str(folder / "fr2.txt"), "--gt", gt, "--scene", "fr2", "--jobs", "1", "--no-progress"]
    commands = {
        "evaluate": ["evaluate", *pair, *_cli(o_mode)],
        "sweep": ["sweep", *pair, *_cli(o_mode), "--columns", "all"],  # the RPE options apply to its RPE columns
        "manifest-cli": ["evaluate", str(tmp_path / "res"), "--manifest", str(toml), "--jobs", "1", "--no-progress"],
    }
    for name, argv in commands.items():
        csv = tmp_path / f"{name}.csv"
        capsys.readouterr()
        try:
            code = main([*argv, "--csv", str(csv)])
        except SystemExit as exc:
            code = exc.code
        err = capsys.readouterr().err
        line = next((x for x in err.splitlines() if x.startswith("conventions:")), "")
        got[name] = ("ok", (pd.read_csv(csv), line.removeprefix("conventions: "))) if code in (0, 1) else (
            "refused", _message(err))  # fmt: skip
    problems = []
    if len({status for status, _ in got.values()}) > 1:
        return [f"accepted by some paths, refused by others: { {k: v for k, v in got.items()} }"]
    if got["python"][0] == "refused":
        said = {k: v for k, v in got.items()}
        return [] if len(set(said.values())) == 1 else [f"refused with different messages: {said}"]
    ev = got["python"][1]
    table = ev.sequences()
    for name in ("manifest-python", "evaluate", "sweep", "manifest-cli"):
        other = got[name][1]
        seq = other.sequences() if name == "manifest-python" else other[0]
        if table.empty or seq.empty:  # the file failed (e.g. too few poses to align on): on every path alike
            if not (table.empty and seq.empty):
                problems.append(f"{name}: {len(seq)} rows, Python {len(table)}")
            elif name == "manifest-python" and [f.error for f in ev.failures] != [f.error for f in other.failures]:
                problems.append(f"{name}: failures {other.failures} vs {ev.failures}")
            continue
        try:
            _same_numbers(table, seq, [c for c in METRICS if c in seq.columns])
        except AssertionError as exc:
            problems.append(f"{name}: {exc}")
        line = other.conventions if name == "manifest-python" else other[1]
        if name != "sweep" and line != ev.conventions:
            problems.append(f"{name}: conventions line {line!r} vs {ev.conventions!r}")
        spec = set(seq["spec"]) if "spec" in seq else set()
        if name != "sweep" and spec != set(table["spec"]):
            problems.append(f"{name}: spec {spec} vs {set(table['spec'])}")
    scenes = ev.scenes()
    if len(scenes) and not np.allclose(scenes["cr"], table["cr"], rtol=1e-12, atol=0, equal_nan=True):
        problems.append(f"scene CR {scenes['cr'].tolist()} vs the sequence's {table['cr'].tolist()}")
    return problems


def _run_draws(seeds, data, tmp_path, capsys) -> None:
    t0 = float(ln.read_trajectory(_fr2(data)[1], "tum").stamps[0])
    found = []
    for seed in seeds:
        o = _draw(random.Random(seed), t0)
        where = tmp_path / f"draw{seed}"
        where.mkdir()
        found += [f"seed {seed} {o}: {p}" for p in _one_draw(o, data, where, capsys)]
    assert not found, "\n".join(found)


@pytest.mark.thorough
def test_random_options_give_the_same_numbers_on_every_path(data, tmp_path, capsys):
    _run_draws(range(6), data, tmp_path, capsys)


@pytest.mark.slow
def test_many_random_options_give_the_same_numbers_on_every_path(data, tmp_path, capsys):
    _run_draws(range(6, 80), data, tmp_path, capsys)


@pytest.mark.slow
def test_random_options_give_the_same_numbers_on_a_dask_cluster(data, tmp_path, capsys):
    distributed = pytest.importorskip("distributed")
    results = tmp_path / "res"
    for suite, alg, name in (("per-seq", "ds-slam", "cafe-1-1.txt"), ("per-seq", "dso", "home-1-3-all.txt"),
                             ("lifelong", "orbslam2_t265", "cafe_1_orbslam2-original.txt")):  # fmt: skip
        (results / suite / alg).mkdir(parents=True, exist_ok=True)
        (results / suite / alg / name).symlink_to(data.icra20 / suite / alg / name)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, protocol="tcp",
                                  host="127.0.0.1", dashboard_address=None) as cluster:  # fmt: skip
        with distributed.Client(cluster) as client:
            for seed in range(12):
                o = _draw(random.Random(seed), 1560004885.0)
                preset, kw = _python(o)
                try:
                    one = ln.evaluate(results, preset, data_root=data.root, jobs=1, **kw)
                except LorisError:
                    continue
                many = ln.evaluate(results, preset, data_root=data.root, executor=client.get_executor(), **kw)
                _same_numbers(one.sequences(), many.sequences())
                csv = tmp_path / f"{seed}.csv"
                code = main(["evaluate", str(results), *_cli(o), "--scheduler", cluster.scheduler_address,
                             "--data", str(data.root), "--csv", str(csv), "--no-progress"])  # fmt: skip
                assert code in (0, 1)
                assert f"conventions: {one.conventions}" in capsys.readouterr().err
                _same_numbers(one.sequences(), pd.read_csv(csv))


# --- the report's leaderboard: a preset's alignment holds, as on every other path -----------------------


@pytest.mark.parametrize("preset", ["evo", "tum", "vio"])
def test_the_report_leaderboard_scores_a_preset_as_evaluate_and_the_notebook_do(data, preset):
    from lorisnb.tools.notebook.params import evaluation_spec
    from lorisnb.tools.report.leaderboard import leaderboard_spec

    spec = leaderboard_spec({"conventions": preset})
    notebook = evaluation_spec({"conventions": preset, "scale": None})  # evaluate_my_results' parameters
    assert spec == notebook == ln.make_spec(preset)  # the leaderboard aligned by 'auto' (scale auto over the preset)
    dso = data.icra20 / "per-seq" / "dso" / "home-1-3-all.txt"
    board = ln.evaluate(dso, spec, data_root=data.root, jobs=1).sequences()
    command = ln.evaluate(dso, preset, data_root=data.root, jobs=1).sequences()
    _same_numbers(board, command)
    assert leaderboard_spec({}).align == "auto"  # without a choice of alignment: scale auto, as the paper


# --- a value refused is refused alike, whichever path; one accepted is read alike -----------------------

BAD_VALUES = [("rpe_tolerance", -1), ("rpe_delta", 0), ("rpe_unit", "km"), ("rpe_pairs", "both"), ("eps", -1),
              ("phi", 200), ("downsample", 0), ("align", "sim4"), ("max_diff", -0.1), ("t_start", "x")]  # fmt: skip


@pytest.mark.parametrize(("name", "value"), BAD_VALUES)
def test_a_bad_value_gets_one_message_on_every_path(data, tmp_path, capsys, name, value):
    est, gt = str(data.tum / "freiburg1_xyz-rgbdslam.txt"), str(data.tum / "freiburg1_xyz-groundtruth.txt")
    said = {}
    with pytest.raises(ValidationError) as exc:
        ln.evaluate_pairs(est, gt, jobs=1, **{name: value})
    said["evaluate_pairs"] = str(exc.value)
    if name.startswith("rpe_"):  # a table's own RPE step: Evaluation.sequences
        ev = ln.evaluate_pairs(est, gt, jobs=1)
        with pytest.raises(ValidationError) as exc:
            ev.sequences(**{name: value})
        said["sequences"] = str(exc.value)
        for fn in (ln.score, ln.sweep):  # the core's own entry points: the same rules (they had theirs)
            with pytest.raises(ValidationError) as exc:
                fn(ev.errors, **{name: value})
            said[fn.__name__] = str(exc.value)
    toml = tmp_path / "m.toml"
    shown = f'"{value}"' if isinstance(value, str) else value
    toml.write_text(f'name = "x"\n[conventions]\n{name} = {shown}\n[[session]]\nname = "a"\ngroundtruth = "{gt}"\n')
    with pytest.raises(ParseError) as exc2:
        ln.read_manifest(toml)
    said["manifest"] = str(exc2.value)
    with pytest.raises(SystemExit):
        main(["evaluate", est, "--gt", gt, f"--{name.replace('_', '-')}={value}", "--no-progress"])
    said["command line"] = capsys.readouterr().err
    assert len({_message(m) for m in said.values()}) == 1, said


def test_a_table_reads_an_rpe_unit_as_the_spec_does(data):
    est, gt = str(data.tum / "freiburg1_xyz-rgbdslam.txt"), str(data.tum / "freiburg1_xyz-groundtruth.txt")
    spec = ln.evaluate_pairs(est, gt, jobs=1, rpe_delta=10, rpe_unit="d").sequences()  # evo's -u d: degrees
    table = ln.evaluate_pairs(est, gt, jobs=1).sequences(rpe_delta=10, rpe_unit="d")  # was refused: 'd' unknown
    assert table["rpe_rot_rmse"].iloc[0] == spec["rpe_rot_rmse"].iloc[0] == pytest.approx(0.920387, abs=1e-6)
    errors = ln.evaluate_pairs(est, gt, jobs=1).errors
    scored = ln.score(errors, rpe_delta=10, rpe_unit="d")  # the core's entry points refused 'd'
    assert scored["rpe_rot_rmse"].iloc[0] == spec["rpe_rot_rmse"].iloc[0]
    assert len(ln.sweep(errors, [0.1, 1.0], rpe_delta=10, rpe_unit="d", columns="all")) == 2
    with pytest.raises(ValidationError, match="rpe_delta: the RPE is in the table of columns='all'"):
        ln.sweep(errors, [0.1, 1.0], rpe_delta=10)  # the default columns: no RPE to apply it to
    assert table["spec"].iloc[0] == spec["spec"].iloc[0] and '"rpe_unit":"deg"' in spec["spec"].iloc[0]


def test_a_session_that_cannot_be_aligned_is_named_as_its_pair_is(data, tmp_path):
    gt = data.tum / "freiburg1_xyz-groundtruth.txt"
    (tmp_path / "res" / "alg").mkdir(parents=True)
    est = tmp_path / "res" / "alg" / "xyz.txt"
    est.write_text((data.tum / "freiburg1_xyz-rgbdslam.txt").read_text())
    (tmp_path / "res" / "alg" / "desk.txt").write_text((data.tum / FR2[0]).read_text())
    toml = tmp_path / "m.toml"
    toml.write_text(f'name = "two"\n[[session]]\nname = "xyz"\ngroundtruth = "{gt}"\n'
                    f'[[session]]\nname = "desk"\ngroundtruth = "{data.tum / FR2[1]}"\n')  # fmt: skip
    manifest = ln.evaluate_manifest(toml, tmp_path / "res", jobs=1, align_frames=2)  # too few poses to fit SE(3)
    pair = ln.evaluate_pairs(est, gt, jobs=1, align_frames=2)
    assert [f.error for f in manifest.failures] == [f.error for f in pair.failures]  # was '.../res/alg: no SE(3)...'
    assert pair.failures[0].error.startswith(f"{est}: no SE(3) alignment can be determined: only 2 matched")


@pytest.mark.parametrize("openloris", [False, True])
def test_an_option_the_manifest_set_is_refused_naming_the_manifest(data, tmp_path, capsys, openloris):
    gt = data.tum / "freiburg1_xyz-groundtruth.txt"
    toml = tmp_path / "m.toml"
    if openloris:  # [conventions] max_gap, then nearest association on the call: max_gap cannot apply
        toml.write_text("openloris = true\n[conventions]\nmax_gap = 0.1\n")
        results, over, flag, key = data.icra20 / "per-seq" / "odom", {"association": "nearest"}, "nearest", "max_gap"
    else:  # [conventions] nearest within 0.05 s, then interpolation on the call: max_diff cannot apply
        toml.write_text(f'name = "x"\n[conventions]\nassociation = "nearest"\nmax_diff = 0.05\n'
                        f'[[session]]\nname = "xyz"\ngroundtruth = "{gt}"\n')  # fmt: skip
        (tmp_path / "res" / "alg").mkdir(parents=True)
        (tmp_path / "res" / "alg" / "xyz.txt").write_text((data.tum / "freiburg1_xyz-rgbdslam.txt").read_text())
        results, over, flag, key = tmp_path / "res", {"association": "interpolate"}, "interpolate", "max_diff"
    with pytest.raises(ValidationError) as exc:
        ln.evaluate_manifest(toml, results, jobs=1, **over)
    python = str(exc.value)
    assert main(["evaluate", str(results), "--manifest", str(toml), "--association", flag, "--no-progress"]) == 2
    command = capsys.readouterr().err
    said = f"({key}: set by the manifest {toml})"
    assert python.endswith(said) and said in command  # it named --max-diff, which was not on the command line
    assert _message(python) == _message(command)
