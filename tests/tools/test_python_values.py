"""Values given in Python and in manifests are checked as the command line checks them: a yes/no
string is refused, never truth-tested; an argument that cannot apply is refused, never dropped; a
manifest value of the wrong type is refused, never turned into text; a table pair scored with other
settings is not compared. Each case gave a plausible result (or a traceback) before."""

from __future__ import annotations

import shutil

import pandas as pd
import pytest
from helpers import write

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import ValidationError
from lorisnb.io.writers import write_openloris
from lorisnb.tools.decisions.diff import diff_tables
from lorisnb.tools.evaluation.runner import evaluate_manifest

GT, EST = "freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"


def test_yes_no_strings_are_refused_by_readers_and_writers(icra20, tmp_path):
    """``repair_stamps="no"`` turned the repair on (maslam cafe seq 1: 97.2 m of path became 27.4 m);
    ``overwrite="no"`` replaced a file lorisnb did not write."""
    cafe = icra20 / "lifelong" / "maslam" / "cafe.txt"
    for kw in ({"repair_stamps": "no"}, {"remove_repeated": "false"}, {"warn": "yes"}):
        with pytest.raises(ln.ValidationError, match=f"{next(iter(kw))}=.*expected True or False"):
            ln.read_openloris(cafe, **kw)
    with pytest.raises(ln.ValidationError, match="repair_stamps='no'"):
        ln.read_trajectory(cafe, "openloris", seq=1, repair_stamps="no")
    mine = write(tmp_path, "precious.txt", "mine\n")
    seq = ln.read_trajectory(cafe, "openloris", seq=1)
    with pytest.raises(ln.ValidationError, match="overwrite='no'"):
        write_openloris(mine, {1: seq}, "cafe", overwrite="no")
    assert mine.read_text() == "mine\n"


def test_read_trajectory_refuses_what_cannot_apply(data, icra20):
    """``seq``, ``stamps``, ``topic`` and ``tf`` were dropped without a word on a TUM file; a bool or a
    string ``seq`` read another block or gave a misleading message; a number as path a TypeError."""
    tum = data.tum / EST
    for kw, said in (({"seq": 7}, "seq: only for openloris files"), ({"stamps": [1.0]}, "stamps: only for kitti"),
                     ({"topic": "/x"}, "topic: only for bag files"), ({"tf": "a:b"}, "tf: only for bag files")):  # fmt: skip
        with pytest.raises(ln.ValidationError, match=said):
            ln.read_trajectory(tum, "tum", **kw)
    cafe = icra20 / "lifelong" / "maslam" / "cafe.txt"
    for seq in (True, "2", 1.0):
        with pytest.raises(ln.ValidationError, match="expected the whole number of a 'seq: N' block"):
            ln.read_trajectory(cafe, "openloris", seq=seq)
    with pytest.raises(ln.ValidationError, match="expected the path of a trajectory file"):
        ln.read_trajectory(5)
    with pytest.raises(ln.ValidationError, match="trials_by=5: expected a regular expression"):
        ln.evaluate_pairs([tum], data.tum / GT, trials_by=5)
    with pytest.raises(ln.ValidationError, match="manifest=5"):
        evaluate_manifest(5, data.tum)


MANIFEST = """name = "probe"
root = "{root}"
{top}
[conventions]
association = "nearest"
{conventions}
[[session]]
name = "xyz"
groundtruth = "{gt}"
{session}
"""


@pytest.mark.parametrize(
    ("top", "conventions", "session", "said"),
    [
        ('openloris = "false"', "", "", "openloris = 'false': expected true or false"),
        ('scene = ["a"]', "", "", "scene = \\['a'\\]: expected a string"),
        ("", "", "scene = 3", "\\[\\[session\\]\\] 1: scene = 3: expected a string"),
        ("", "", "estimate = 3", "estimate = 3: expected a string"),
        ("eps = 0.1", "eps = 0.2", "", "eps is given at the top and in \\[conventions\\]; give it once"),
        ("lifelong = true", "lifelong = false", "", "lifelong is given at the top and in \\[conventions\\]"),
        ("", "transform = 1", "", "transform is given in the \\[transform\\] table"),
        ("", "surface = 'cli'", "", "surface is not an option of the evaluation spec"),
        ("[transform]\ntranslation = [true, 0, 0]", "", "", "\\[transform\\]: expected translation = \\[x, y, z\\]"),
    ],
)
def test_manifest_values_of_the_wrong_type_are_refused(data, tmp_path, top, conventions, session, said):
    """``openloris = "false"`` turned the manifest into the OpenLORIS evaluation, ``scene = ["a"]``
    became the scene "['a']", ``translation = [true, 0, 0]`` a 1 m offset, and eps in [conventions]
    and at the top a TypeError traceback."""
    if top.startswith("[transform]"):  # a table goes after the top-level keys and [conventions]
        conventions, top = conventions + "\n" + top, ""
    text = MANIFEST.format(root=data.tum, gt=GT, top=top, conventions=conventions, session=session)
    m = write(tmp_path, "m.toml", text)
    with pytest.raises(ln.ParseError, match=said):
        ln.read_manifest(m)


def test_a_manifest_session_that_matches_nothing_is_not_scored(data, tmp_path, capsys):
    """A session whose stamps match no ground-truth stamp (a clock offset) exited 0 beside a session
    that matched; the same file as a pair exits 1. Both say it now, exit status 1."""
    res = tmp_path / "res" / "algo"
    res.mkdir(parents=True)
    shutil.copy(data.tum / EST, res / "xyz.txt")
    rows = [r.split() for r in (data.tum / EST).read_text().splitlines() if r[:1] != "#"]
    (res / "late.txt").write_text("".join(f"{float(r[0]) + 1000:.6f} {' '.join(r[1:])}\n" for r in rows))
    text = MANIFEST.format(root=data.tum, gt=GT, top="", conventions="", session="")
    text += f'[[session]]\nname = "late"\ngroundtruth = "{GT}"\n'
    m = write(tmp_path, "m.toml", text)
    ev = evaluate_manifest(m, tmp_path / "res", progress=False)
    assert ev.exit_status() == 1
    assert [f.error for f in ev.unscored] == [f"{res}: session(s) [2] matched no ground-truth stamp in time"]
    assert main(["evaluate", str(tmp_path / "res"), "--manifest", str(m), "--no-progress"]) == 1
    assert "1 not scored" in capsys.readouterr().err


def test_diff_tables_refuses_tables_of_other_settings_from_python(icra20):
    """``diff_tables`` compared a table at eps paper with one at eps 1 and called it a regression;
    the command line refused them. ``alpha=2`` and ``alpha=True`` were accepted."""
    odom = icra20 / "per-seq" / "odom"
    a = ln.evaluate(odom, eps="paper", progress=False).sequences()
    b = ln.evaluate(odom, eps=1, progress=False).sequences()
    with pytest.raises(ln.ValidationError, match="not comparable .*: cafe, home: eps = 3.0 in BASE against 1.0"):
        diff_tables(a, b)
    for alpha in (2, True):
        with pytest.raises(ln.ValidationError, match="alpha="):
            diff_tables(a, a, alpha=alpha)
    assert diff_tables(a, a).verdict["verdict"] == "ok"
    assert isinstance(diff_tables(a, pd.DataFrame(columns=a.columns)).sequences, pd.DataFrame)


def test_an_rpe_tolerance_without_evo_all_pairs_is_refused_by_every_table(data):
    """The command line and the spec refuse ``rpe_tolerance`` without evo's all pairs; ``score``,
    ``Evaluation.sequences`` and ``sweep`` accepted it and ignored it."""
    ev = ln.evaluate_pairs([data.tum / EST], data.tum / GT, progress=False)
    for call in (lambda: ev.sequences(rpe_tolerance=0.2), lambda: ln.score(ev.errors, rpe_tolerance=0.2),
                 lambda: ln.sweep(ev.errors, rpe_tolerance=0.2)):  # fmt: skip
        with pytest.raises(ln.ValidationError, match="rpe_tolerance: only for evo's all pairs"):
            call()
    with_tol = ev.sequences(rpe_tolerance=0.2, rpe_all_pairs=True, rpe_unit="m")
    assert with_tol["rpe_trans_rmse"].iloc[0] > 0


def test_numpy_values_are_read_as_python_values(data, icra20):
    """``np.True_`` was the number 1 for eps, phi, ``max_diff``, ... while Python's True was refused;
    ``scale=np.int64(1)`` was refused while ``scale=1`` was Sim(3); complex stamps lost their
    imaginary part; ``compare_table(metric="CR")`` was refused while ``--metric CR`` was not."""
    import numpy as np

    from lorisnb.tools.decisions.comparison import compare_table

    for name in ("eps", "phi", "delta", "tau", "max_diff", "t_offset"):
        with pytest.raises(ln.ValidationError, match=f"{name}=(np.)?True_?: expected .*a number"):
            ln.make_spec("tum", **{name: np.True_})
    assert ln.make_spec("openloris", scale=np.int64(1)).align == ln.make_spec("openloris", scale=1).align == "sim3"
    with pytest.raises(ln.ValidationError, match="values of type complex128; expected real numbers"):
        ln.Trajectory(np.array([1.0, 2.0], complex), np.zeros((2, 3)), np.tile([0, 0, 0, 1.0], (2, 1)))
    ev = ln.evaluate(icra20 / "per-seq" / "odom", progress=False)
    assert compare_table(ev.sequences(), ev.durations(), "CR").algorithms["metric"].iloc[0] == "cr"
    with pytest.raises(ln.ValidationError, match="durations: expected a DataFrame"):
        compare_table(ev.sequences(), None)
    with pytest.raises(ln.ValidationError, match="max_bytes=1e9 is not|max_bytes="):
        ln.sweep(ev.errors, max_bytes=[1])
    for kw, said in (({"fractions": 0.1}, "non-empty list"), ({"fractions": (2,)}, "at most 1"),
                     ({"lengths": [-1]}, "expected a positive number")):  # fmt: skip
        with pytest.raises(ln.ValidationError, match=said):
            ev.relative(**kw)


def test_a_pair_scene_is_a_name(data):
    """``scene=5`` put an ``np.int64`` in the scene column."""
    for scene in (5, "", ["a"]):
        with pytest.raises(ln.ValidationError, match="expected a scene name"):
            ln.evaluate_pairs([data.tum / EST], data.tum / GT, scene=scene, progress=False)


def test_evaluate_takes_conventions_as_the_other_evaluations_do(icra20, data):
    """``conventions=`` (the README's Python examples) was a ValidationError for ``evaluate`` alone."""
    f = icra20 / "per-seq" / "orbslam2_rgbd" / "cafe_1_1_orbslam2-original.txt"
    a = ln.evaluate(f, conventions="tum", data_root=data.root, jobs=1).sequences()
    b = ln.evaluate(f, "tum", data_root=data.root, jobs=1).sequences()
    assert a["ate_rmse"][0] == b["ate_rmse"][0] and a["spec"][0] == b["spec"][0]
    assert a["ate_rmse"][0] != ln.evaluate(f, data_root=data.root, jobs=1).sequences()["ate_rmse"][0]
    with pytest.raises(ValidationError, match="spec and conventions: give one"):
        ln.evaluate(f, "tum", conventions="evo", data_root=data.root)
