"""The command line under random combinations of options, valid and not (hypothesis, fixed seed
and budget): every run ends with an exit status and a message, never a traceback."""

from __future__ import annotations

import pytest
from helpers import write
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lorisnb.cli import main
from lorisnb.tools.report import build as report

ORB = "per-seq/orbslam2_rgbd/cafe_1_1_orbslam2-original.txt"

THRESHOLDS = ["1", "0", "-1", "inf", "INF", "paper", "Paper", "nan", "abc", "", "1e400", "3,5", ",", "0.5,paper"]
SCALES = ["auto", "on", "off", "maybe", "SE3", "1", ""]


@pytest.fixture(scope="module")
def inputs(tmp_path_factory, icra20):
    d = tmp_path_factory.mktemp("cli")
    good = write(d, "tree/orb/cafe.txt", (icra20 / ORB).read_bytes())
    write(d, "tree/broken/cafe-2.txt", "scene: cafe\nframe: d400_color\nseq: 2\n5 0 0 0 0 0 0 0\n")
    paths = {
        "good": str(good),
        "tree": str(d / "tree"),
        "missing": str(d / "nope.txt"),
        "empty": str(write(d, "empty.txt", "")),
        "binary": str(write(d, "bin.txt", bytes(range(256)))),
        "blank": "",
        "tum": str(write(d, "t.txt", "1 0 0 0 0 0 0 1\n2 1 0 0 0 0 0 1\n3 1 1 0 0 0 0 1\n4 2 1 1 0 0 0 1\n")),
    }
    return d, paths


def _options(draw, paths, out_dir, command):
    args = [command]
    if command in ("evaluate", "sweep"):
        args += draw(st.lists(st.sampled_from(list(paths.values())), min_size=1, max_size=2))
        for opt in ("--eps", "--phi", "--delta", "--tau"):
            if draw(st.booleans()):
                args += [opt, draw(st.sampled_from(THRESHOLDS))]
        if draw(st.booleans()):
            args += ["--scale", draw(st.sampled_from(SCALES))]
        args += draw(
            st.lists(
                st.sampled_from(
                    [
                        "--per-seq",
                        "--lifelong",
                        "--official-interpolation",
                        "--keep-repeated",
                        "--repair-stamps",
                        "--force",
                    ]
                ),
                max_size=3,
            )
        )
        if command == "sweep" and draw(st.booleans()):
            args += ["--relative-to", draw(st.sampled_from(["extent", "length", "size"]))]
        if draw(st.booleans()):  # pairs and manifests
            args += draw(st.sampled_from([
                ["--gt", paths["tum"]], ["--gt", paths["missing"]], ["--gt", paths["good"]], ["--gt", paths["binary"]],
                ["--manifest", "openloris"], ["--manifest", "tum-fr1-office"], ["--manifest", paths["tum"]],
                ["--gt", paths["tum"], "--manifest", "openloris"],
            ]))  # fmt: skip
            for opt, pool in (
                ("--format", ["tum", "kitti", "euroc", "openloris", "bag", "csv"]),
                ("--gt-format", ["tum", "openloris", "kitti"]),
                ("--conventions", ["tum", "rpg", "vio", "openloris", "evo"]),
                ("--association", ["nearest", "interpolate", "closest"]),
                ("--align", ["se3", "sim3", "posyaw", "none", "yaw"]),
                ("--align-frames", ["1", "2", "0", "-1", "x"]),
                ("--max-diff", ["0.02", "0", "nan"]),
                ("--t-offset", ["0.1", "-5", "inf", "x"]),
                ("--eps", ["relative:0.05", "relative:-1", "relative:x"]),
                ("--topic", ["/pose"]),
                ("--tf", ["map:base", "map"]),
            ):
                if draw(st.booleans()):
                    args += [opt, draw(st.sampled_from(pool))]
            if draw(st.booleans()):
                args += ["--relative"]
    elif command == "crosscheck":
        args += [draw(st.sampled_from(list(paths.values()))), draw(st.sampled_from(list(paths.values())))]
        if draw(st.booleans()):
            args += ["--format", draw(st.sampled_from(["tum", "kitti", "euroc", "openloris", "csv"]))]
        for opt, pool in (
            ("--rpe-frames", ["0", "1", "-3", "x", "2.5"]),
            ("--rpe-metres", ["1", "0", "nan"]),
            ("--times", [paths["tum"], paths["missing"]]),
            ("--seq", ["1", "9", "x"]),
        ):
            if draw(st.booleans()):
                args += [opt, draw(st.sampled_from(pool))]
    else:
        args += ["--notebooks", draw(st.sampled_from(["metrics_primer", "lifelong_benchmark", "nope"]))]
        for _ in range(draw(st.integers(0, 2))):
            args += [
                "-p",
                draw(st.sampled_from(["eps", "esp", "delta", "scale", "quick"])),
                draw(st.sampled_from(THRESHOLDS + SCALES)),
            ]
        if draw(st.booleans()):
            args += ["--force"]
    if draw(st.booleans()):
        opt = "--out" if command == "report" else "--csv"
        args += [opt, draw(st.sampled_from([str(out_dir / "o.csv"), str(out_dir), "", paths["good"]]))]
    args += ["--no-progress"] if command in ("evaluate", "sweep", "report") else []
    return args


@settings(max_examples=120, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
@given(data=st.data())
@pytest.mark.thorough
def test_cli_never_ends_in_a_traceback(inputs, monkeypatch, data, capsys):
    d, paths = inputs
    monkeypatch.chdir(d)  # a report without --out goes to ./results/run-*: here, not in the checkout
    before = {p: open(p, "rb").read() for p in (paths["good"], paths["tum"])}
    monkeypatch.setattr(
        report,
        "run_notebook",
        lambda name, out_dir, parameters, timeout=1800, notebooks_dir=None: report.NotebookRun(name),
    )
    command = data.draw(st.sampled_from(["evaluate", "sweep", "crosscheck", "report"]))
    args = _options(data.draw, paths, d / "out", command)
    try:
        rc = main(args)
    except SystemExit as exc:  # argparse: a usage error, with its message
        rc = exc.code
    captured = capsys.readouterr()
    assert rc in (0, 1, 2), (args, captured.err)
    assert "Traceback" not in captured.err, args
    if rc == 2:
        assert "error" in captured.err, (args, captured.err)
    assert before == {p: open(p, "rb").read() for p in before}, f"an input changed: {args}"
