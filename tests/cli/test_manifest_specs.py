"""A manifest's spec on every route: an ``openloris = true`` manifest's thresholds, mode and
``[conventions]`` apply (what cannot apply is refused), ``sweep --manifest`` sweeps the manifest's
thresholds by default, ``--conventions`` over a manifest keeps its thresholds and mode on the
command line as in Python, and ``[conventions] mode`` takes every mode, in any case. Each used to
be dropped or refused on one route only."""

from __future__ import annotations

import shutil

import pandas as pd
import pytest
from helpers import write

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import ParseError

COLUMNS = ["cr", "cr_t", "cs_r", "ate_rmse", "c_ate_rmse", "aoe_rmse", "matched", "eps", "phi", "mode"]


def _results(tmp_path, icra20):
    """Two real per-sequence result files of one algorithm (ORB-SLAM2 RGB-D, cafe)."""
    folder = tmp_path / "results" / "orbslam2_rgbd"
    folder.mkdir(parents=True)
    for name in ("cafe_1_1_orbslam2-original.txt", "cafe_1_2_orbslam2-original.txt"):
        shutil.copy(icra20 / "per-seq" / "orbslam2_rgbd" / name, folder / name)
    return tmp_path / "results"


def _csv(tmp_path, name, *argv):
    out = tmp_path / f"{name}.csv"
    code = main([*argv, "--no-progress", "--csv", str(out)])
    return code, (pd.read_csv(out) if out.exists() else None)


def test_an_openloris_manifest_applies_its_thresholds_mode_and_conventions(tmp_path, icra20, data):
    results = _results(tmp_path, icra20)
    m = write(tmp_path, "ol.toml", 'openloris = true\neps = 0.5\nphi = 10.0\nlifelong = false\n'
              '[conventions]\nmax_gap = 0.2\nofficial_interpolation = true\n')  # fmt: skip
    options = ["--eps", "0.5", "--phi", "10", "--per-seq", "--max-gap", "0.2", "--official-interpolation"]
    code_m, by_manifest = _csv(tmp_path, "m", "evaluate", str(results), "--manifest", str(m), "--data", str(data.root))
    code_o, by_options = _csv(tmp_path, "o", "evaluate", str(results), *options, "--data", str(data.root))
    assert code_m == code_o == 0
    pd.testing.assert_frame_equal(by_manifest[COLUMNS], by_options[COLUMNS])
    assert set(by_manifest["eps"]) == {0.5} and set(by_manifest["phi"]) == {10.0}
    # Python: the same numbers, and the options given there still go over the manifest's
    py = ln.evaluate_manifest(m, results, data_root=data.root).sequences()
    pd.testing.assert_frame_equal(py[COLUMNS].reset_index(drop=True), by_manifest[COLUMNS], check_dtype=False)
    assert set(ln.evaluate_manifest(m, results, data_root=data.root, eps=1.0).sequences()["eps"]) == {1.0}
    default = ln.evaluate(results, data_root=data.root).sequences()
    assert not default["aoe_rmse"].equals(py["aoe_rmse"])  # the official interpolation's slips changed AOE


@pytest.mark.parametrize(
    ("text", "named"),
    [
        ('root = "."', "root"),
        ("[transform]\ntranslation = [1.0, 0.0, 0.0]", "transform"),
        ('[[session]]\ngroundtruth = "gt.txt"', "session"),
        ('[conventions]\npreset = "evo"', "preset"),
        ('[conventions]\nalignn = "sim3"', "alignn"),
        ('eps = "not-a-number"', "eps"),
    ],
)
def test_an_openloris_manifest_refuses_what_cannot_apply(tmp_path, icra20, data, text, named):
    results = _results(tmp_path, icra20)
    m = write(tmp_path, "ol.toml", f"openloris = true\n{text}\n")
    with pytest.raises(ParseError, match=named):
        ln.read_manifest(m)
    out = tmp_path / "out.csv"
    assert main(["evaluate", str(results), "--manifest", str(m), "--data", str(data.root), "--csv", str(out)]) == 2
    assert not out.exists()


TUM = """
name = "two tum"
scene = "tum"
root = "{root}"
lifelong = false
eps = 0.05
phi = 5.0
[conventions]
preset = "tum"
[[session]]
name = "fr2_desk"
groundtruth = "fr2_desk_groundtruth.txt"
[[session]]
name = "fr1_xyz"
groundtruth = "freiburg1_xyz-groundtruth.txt"
"""


def _tum(tmp_path, data):
    folder = tmp_path / "results" / "algo"
    folder.mkdir(parents=True)
    shutil.copy(data.tum / "fr2_desk_ORB.txt", folder / "fr2_desk.txt")
    shutil.copy(data.tum / "freiburg1_xyz-rgbdslam.txt", folder / "fr1_xyz.txt")
    return write(tmp_path, "tum.toml", TUM.format(root=data.tum)), tmp_path / "results"


def test_sweep_with_a_manifest_sweeps_its_thresholds_by_default(tmp_path, data):
    m, results = _tum(tmp_path, data)
    code_e, evaluated = _csv(tmp_path, "e", "evaluate", str(results), "--manifest", str(m))
    code_s, swept = _csv(tmp_path, "s", "sweep", str(results), "--manifest", str(m))
    assert code_e == code_s == 0
    assert set(swept["eps"]) == {0.05} and set(swept["phi"]) == {5.0}
    pd.testing.assert_frame_equal(swept[["seq", "cr", "cr_t", "cs_r"]], evaluated[["seq", "cr", "cr_t", "cs_r"]])
    assert 0.0 < evaluated["cr"].min() < 1.0  # the thresholds matter here: inf would give 1
    _, given = _csv(tmp_path, "g", "sweep", str(results), "--manifest", str(m), "--eps", "0.1,0.2")
    assert sorted(set(given["eps"])) == [0.1, 0.2] and set(given["phi"]) == {5.0}  # a list given: the grid


def test_conventions_over_a_manifest_keep_its_thresholds_and_mode_on_every_route(tmp_path, data):
    m, results = _tum(tmp_path, data)
    code, cli = _csv(tmp_path, "c", "evaluate", str(results), "--manifest", str(m), "--conventions", "evo",
                     "--align", "se3")  # fmt: skip
    py = ln.evaluate_manifest(m, results, conventions="evo", align="se3").sequences()
    assert code == 0
    assert list(cli["mode"]) == list(py["mode"]) == ["per-seq", "per-seq"]
    assert set(cli["eps"]) == {0.05} and set(cli["phi"]) == {5.0}
    cols = ["seq", "ate_rmse", "aoe_rmse", "matched", "cr", "eps", "phi"]
    pd.testing.assert_frame_equal(cli[cols], py[cols].reset_index(drop=True), check_dtype=False)
    # evo's association (its nearest rule within 0.01 s), not the manifest's tum preset
    tum = ln.evaluate_manifest(m, results).sequences()
    assert list(py["matched"]) != list(tum["matched"])


@pytest.mark.parametrize(("mode", "expected"), [("lifelong", "lifelong"), ("auto", "auto"), ("Per-Seq", "per-seq")])
def test_a_manifest_mode_is_any_mode_in_any_case(tmp_path, data, mode, expected):
    text = (
        TUM.format(root=data.tum)
        .replace("lifelong = false\n", "")
        .replace("[conventions]\n", f'[conventions]\nmode = "{mode}"\n')
    )
    spec = ln.read_manifest(write(tmp_path, "m.toml", text)).spec
    assert spec.mode == expected
    both = text.replace('name = "two tum"', 'name = "two tum"\nlifelong = true')  # lifelong and another mode
    if expected == "lifelong":
        assert ln.read_manifest(write(tmp_path, "both.toml", both)).spec.mode == "lifelong"
    else:
        with pytest.raises(ParseError, match="give one"):
            ln.read_manifest(write(tmp_path, "both.toml", both))


@pytest.mark.parametrize("openloris", [False, True])
@pytest.mark.parametrize(
    ("key", "where"), [("lifelong", "top"), ("official_interpolation", "conventions"), ("rpe_all_pairs", "conventions")]
)
def test_a_quoted_boolean_in_a_manifest_is_told_in_toml_spelling(tmp_path, openloris, key, where):
    """``lifelong = "false"`` (a string) is refused; the message spells the two values as TOML does
    (``true or false``, without quotes), not as Python does (it said "expected True or False")."""
    head = "openloris = true\n" if openloris else 'scene = "xyz"\nroot = "."\n'
    body = f'{key} = "false"\n' if where == "top" else f'[conventions]\n{key} = "false"\n'
    sessions = "" if openloris else '[[session]]\nname = "a"\ngroundtruth = "a.txt"\n'
    m = write(tmp_path, "m.toml", head + (body + sessions if where == "top" else sessions + body))
    with pytest.raises(
        ParseError, match=rf"{key}='false' \(str\): expected true or false \(TOML booleans, without quotes\)"
    ):
        ln.read_manifest(m)
