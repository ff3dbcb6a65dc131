"""A manifest's values refused with the file, the line, the table and the key (value checks and the
rules between values, when the manifest is read), format names in any case as ``--format`` takes
them, and a session's ``seq`` a positive whole number, as ``--seq`` is."""

from __future__ import annotations

import re

import pytest
from helpers import write

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import ParseError
from lorisnb.io.datasets.manifest import read_manifest

BASE = """name = "test"
scene = "tumtest"
groundtruth_format = "tum"
estimate_format = "tum"
eps = 0.1

[conventions]
association = "nearest"
max_diff = 0.02
align = "se3"

[[session]]
name = "a"
groundtruth = "gt.txt"
"""


def _manifest(tmp_path, old: str, new: str):
    write(tmp_path, "gt.txt", "1.0 0 0 0 0 0 0 1\n2.0 1 0 0 0 0 0 1\n")
    assert old in BASE
    return write(tmp_path, "m.toml", BASE.replace(old, new, 1))


def _line_of(path, text: str) -> int:
    return next(n for n, line in enumerate(path.read_text().splitlines(), 1) if line.startswith(text))


@pytest.mark.parametrize(
    ("old", "new", "written", "says"),
    [
        ('scene = "tumtest"', 'scene = ["a"]', "scene =", r": scene = \['a'\]: expected a string"),
        (
            'align = "se3"',
            'align = "se3"\neps = 0.5',
            "eps = 0.5",
            r": eps is given at the top and in \[conventions\]",
        ),
        (
            'align = "se3"',
            'align = "se3"\ndelta = 0',
            "delta = 0",
            r": delta=0: expected a number of seconds > 0",
        ),
        (
            "max_diff = 0.02",
            "max_diff = 0.02\nmax_gap = 0.3",
            "max_gap",
            r": max_gap: only for interpolation; nearest association uses max_diff",
        ),
        (
            "eps = 0.1",
            'eps = 0.1\n[transform]\ntranslation = [0, 0, "x"]\nquaternion = [0, 0, 0, 1]',
            "translation",
            r": \[transform\]: expected translation = .*; translation = \[0, 0, 'x'\] is not 3 finite numbers",
        ),
        ("eps = 0.1", "eps = 0.1\n[transform]\nmatrix = 1", "matrix", r": \[transform\]: unknown key 'matrix'"),
        (
            'name = "a"',
            'name = "a"\nseq = 0',
            "seq = 0",
            r": \[\[session\]\] 1 \('a'\): seq = 0: expected a positive whole number",
        ),
        (
            'name = "a"',
            'name = "a"\nseq = -1',
            "seq = -1",
            r": \[\[session\]\] 1 \('a'\): seq = -1: expected a positive whole number",
        ),
        (
            'align = "se3"',
            'align = "se3"\nkitti_precision = "double"',
            "kitti_precision",
            r": \[conventions\] kitti_precision = 'double': only for the KITTI metric \(\[conventions\] preset = 'kitti'\)",
        ),
    ],
)
def test_every_refused_manifest_value_names_its_line_table_and_key(tmp_path, old, new, written, says):
    m = _manifest(tmp_path, old, new)
    with pytest.raises(ParseError) as err:
        read_manifest(m)
    assert re.search(rf"m\.toml, line {_line_of(m, written)}{says}", str(err.value)), str(err.value)


def test_max_gap_beside_nearest_is_refused_when_read_not_when_evaluated(tmp_path):
    """It passed read_manifest and failed at evaluation, in the command line's words (--max-gap)."""
    m = _manifest(tmp_path, "max_diff = 0.02", "max_diff = 0.02\nmax_gap = 0.3")
    with pytest.raises(ParseError, match=r"m\.toml, line \d+: max_gap: only for interpolation") as err:
        read_manifest(m)
    assert "--max-gap" not in str(err.value)
    assert main(["evaluate", str(tmp_path), "--manifest", str(m), "--no-progress"]) == 2


def test_format_names_of_a_manifest_in_any_case(tmp_path):
    m = _manifest(tmp_path, 'groundtruth_format = "tum"', 'groundtruth_format = "TUM"')
    got = read_manifest(m)
    assert (got.groundtruth_format, got.sessions[0].groundtruth_format) == ("tum", "tum")
    m = _manifest(tmp_path, 'name = "a"', 'name = "a"\ngroundtruth_format = "Kitti"')
    assert read_manifest(m).sessions[0].groundtruth_format == "kitti"
    m = _manifest(tmp_path, 'estimate_format = "tum"', 'estimate_format = "kitty"')
    with pytest.raises(ParseError, match=r"m\.toml, line 4: estimate_format = 'kitty': expected one of tum"):
        read_manifest(m)


def test_a_positive_seq_is_kept(tmp_path):
    m = _manifest(tmp_path, 'name = "a"', 'name = "a"\nseq = 3')
    assert read_manifest(m).sessions[0].seq == 3


def test_eps_paper_over_a_custom_manifest_is_refused_before_anything_is_read(tmp_path):
    """evaluate_manifest(..., eps='paper') returned exit_status() 0 while each table raised."""
    m = _manifest(tmp_path, "eps = 0.1", "")
    (tmp_path / "res" / "alg").mkdir(parents=True)
    with pytest.raises(ln.ValidationError, match="eps='paper': the paper's 1/3/5 m are for the OpenLORIS scenes; "
                       "scene 'tumtest' is not one"):  # fmt: skip
        ln.evaluate_manifest(m, tmp_path / "res", eps="paper")
    code = main(["evaluate", str(tmp_path / "res"), "--manifest", str(m), "--eps", "paper", "--no-progress"])
    assert code == 2


def test_a_preset_over_a_manifest_says_which_of_its_conventions_it_replaced(data, tmp_path, capsys):
    """--conventions over a manifest replaces its [conventions] (its thresholds, transform and mode
    stay): the values it set that are then not used were dropped unsaid (max_gap = 0.3 under the
    openloris preset vanished). They are named in a note, on the command line and in Python; a preset
    that keeps them (tum's nearest within 0.02 s, se3) says nothing."""
    gt = data.tum / "freiburg1_xyz-groundtruth.txt"
    est = data.tum / "freiburg1_xyz-rgbdslam.txt"
    if not gt.is_file() or not est.is_file():
        pytest.skip("no tum-rgbd data")
    write(tmp_path, "gt.txt", gt.read_text())
    write(tmp_path, "res/algA/a.txt", est.read_text())
    m = write(tmp_path, "m.toml", BASE)
    said = "its [conventions] association = 'nearest' (now 'interpolate') not used: the conventions given over it"
    assert main(["evaluate", str(tmp_path / "res"), "--manifest", str(m), "--conventions", "openloris",
                 "--no-progress"]) == 0  # fmt: skip
    assert said in capsys.readouterr().err
    with pytest.warns(ln.LorisWarning, match=re.escape(said)):
        ev = ln.evaluate_manifest(m, tmp_path / "res", conventions="openloris")
    assert any(said in n for n in ev.notes)
    assert main(["evaluate", str(tmp_path / "res"), "--manifest", str(m), "--conventions", "tum", "--no-progress"]) == 0
    assert "not used: the conventions given over it" not in capsys.readouterr().err
    assert not any("not used" in n for n in ln.evaluate_manifest(m, tmp_path / "res").notes)
