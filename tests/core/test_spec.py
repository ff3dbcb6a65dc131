"""The one evaluation spec: built by one function from every surface, with the same rules and
messages; recorded next to every output so a number can be reproduced; its checks run for every
input kind."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from helpers import write

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.spec.evalspec import PRESETS, EvalSpec, make_spec
from lorisnb.core.spec.table import spec_table
from lorisnb.core.trajectory.poses import Trajectory

TUM = "tum-rgbd"


def test_presets_are_values_of_the_spec():
    assert PRESETS["openloris"] == EvalSpec() == ln.Conventions()
    assert ln.Conventions.preset("tum") == make_spec("tum") == EvalSpec(association="nearest", preset_name="tum")
    assert make_spec("rpg").align == "sim3" and make_spec("vio").align == "posyaw"
    assert make_spec("tum", max_diff=0.01).explicit == {"max_diff"}


@pytest.mark.parametrize(
    "options, message",
    [
        (dict(association="closest"), "association=closest: expected one of interpolate, nearest"),
        (dict(max_gap=0), "max_gap=0: expected a positive number of seconds"),
        (dict(t_offset=float("nan")), "t_offset=nan: expected a finite number of seconds"),
        (dict(align="rotate"), "align=rotate: expected one of se3, sim3, posyaw, none, auto"),
        (dict(align_frames=2.5), "align_frames=2.5: expected a positive whole number of poses"),
        (dict(official_interpolation="false"), "official_interpolation='false' (str): expected True or False"),
        (dict(lifelong="no"), "lifelong='no' (str): expected True or False"),
        (dict(scale="maybe"), "scale=maybe: expected True, False, 'auto'"),
        (dict(scale=True, align="se3"), "scale True and align se3: give one"),
        (dict(eps="wide"), "eps=wide is not a number"),
        (dict(phi=-1), "phi=-1: expected a number of degrees >= 0"),
        (dict(rpe_unit="km"), "rpe_unit=km: expected one of s, m, f"),
        (dict(rpe_delta=1.5, rpe_unit="f"), "rpe_delta: expected a whole number of frames"),
        (dict(transform=np.eye(3)), "transform: expected a finite 4x4 matrix"),
        (dict(colour="red"), "colour: not an option of the evaluation spec"),
        (dict(mode=None), "mode=None: expected one of auto, per-seq, lifelong"),
    ],
)
def test_every_value_is_checked_once_with_the_same_message(options, message):
    with pytest.raises(ln.ValidationError) as exc:
        make_spec(None, **options)
    assert message in str(exc.value)


def test_the_same_rule_on_every_surface(tmp_path, data, capsys):
    """Python keywords, the command line, manifests and notebook parameters go through make_spec."""
    tum = str(data.root / TUM / "fr2_desk_ORB.txt")
    gt = str(data.root / TUM / "fr2_desk_groundtruth.txt")
    with pytest.raises(ln.ValidationError, match="max_diff: only for nearest association"):
        ln.evaluate_pairs(tum, gt, max_diff=0.01)
    assert main(["evaluate", tum, "--gt", gt, "--max-diff", "0.01", "--no-progress"]) == 2
    assert "--max-diff: only for nearest association (--association nearest)" in capsys.readouterr().err
    m = write(tmp_path, "m.toml", "lifelong = 'false'\n[[session]]\ngroundtruth = 'gt.txt'\n")
    with pytest.raises(ln.ParseError, match=r"m.toml, line 1: lifelong='false' \(str\): expected true or false \(TOML"):
        ln.read_manifest(m)
    m = write(
        tmp_path, "m2.toml", "[conventions]\nassociation = 'nearest'\nmax_gap = 0.1\n[[session]]\ngroundtruth = 'g'\n"
    )
    (tmp_path / "res").mkdir()
    write(tmp_path, "g", "1 0 0 0 0 0 0 1\n")
    with pytest.raises(ln.ParseError, match="m2.toml, line 3: max_gap: only for interpolation"):  # when it is read
        ln.evaluate_manifest(m, tmp_path / "res")
    with pytest.raises(ln.ValidationError, match="align_frames: nothing is fitted with align none"):
        ln.evaluate_pairs(tum, gt, align="none", align_frames=3)


def test_the_spec_is_recorded_with_every_table_and_reproduces_it(data, tmp_path):
    tum, gt = (str(data.root / TUM / f) for f in ("fr2_desk_ORB.txt", "fr2_desk_groundtruth.txt"))
    ev = ln.evaluate_pairs(tum, gt, "tum", max_diff=0.01, align="sim3", rpe_unit="f", rpe_delta=5)
    table = ev.sequences(eps=0.05, phi=5)
    spec = EvalSpec.parse(table["spec"].iloc[0])
    assert spec == make_spec(ev.spec, eps=np.inf, phi=np.inf)  # the table's spec carries no thresholds
    again = ln.evaluate_pairs(tum, gt, spec).sequences(eps=0.05, phi=5)
    pd.testing.assert_frame_equal(table, again)
    assert "nearest stamps within 0.01 s" in ev.conventions and "RPE over 5 f" in ev.conventions
    assert EvalSpec.parse(ev.spec.canonical()) == ev.spec
    assert repr(ev.spec) == "EvalSpec.preset('tum', max_diff=0.01, align='sim3', rpe_delta=5.0, rpe_unit='f')"


@pytest.mark.thorough
def test_thresholds_mean_the_same_in_every_command(data, tmp_path, capsys):
    """evaluate and compare take the spec's thresholds: the same CR for the same files and options."""
    src = str(data.icra20 / "lifelong" / "maslam")
    assert main(["evaluate", src, "--csv", str(tmp_path / "e.csv"), "--no-progress"]) == 0
    assert main(["compare", src, "--csv", str(tmp_path / "c.csv"), "--no-progress"]) == 0
    e, c = pd.read_csv(tmp_path / "e.csv"), pd.read_csv(tmp_path / "c.csv")
    assert e["eps"].eq(np.inf).all() and e["phi"].eq(np.inf).all()
    cr = c[c["metric"] == "cr"].set_index("scene")["value"]
    by_scene = ln.evaluate(src).scenes().set_index("scene")["cr"]
    assert np.allclose(cr.sort_index(), by_scene.loc[cr.index].sort_index())


def test_plausibility_checks_run_for_pairs(data):
    """The hints of OpenLORIS files (scale far from 1, stamps in other units) for any input kind."""
    gt = ln.read_tum(data.root / TUM / "fr2_desk_groundtruth.txt")
    est = ln.read_tum(data.root / TUM / "fr2_desk_ORB.txt")
    small = Trajectory(est.stamps, est.positions * 0.3, est.quaternions)
    fe = ln.session_errors({1: gt}, {1: small}, "tum")
    assert any("best-fitting scale is" in w and "--align sim3" in w for w in fe.warnings), fe.warnings
    nano = Trajectory(est.stamps * 1e9, est.positions, est.quaternions)
    fe = ln.session_errors({1: gt}, {1: nano}, "tum")
    assert fe.sequences[0].matched == 0 and any("look like nanoseconds" in w for w in fe.warnings), fe.warnings
    swapped = Trajectory(est.stamps, est.positions, np.roll(est.quaternions, 1, axis=1))
    fe = ln.session_errors({1: gt}, {1: swapped}, "tum")
    assert any("'qw qx qy qz'" in w for w in fe.warnings), fe.warnings


def test_manual_holds_the_spec_table():
    from pathlib import Path

    page = (Path(__file__).resolve().parents[2] / "docs" / "guide" / "evaluation-spec.md").read_text()
    assert spec_table() in page, "docs/guide/evaluation-spec.md: paste lorisnb.core.spec.table.spec_table() into it"
