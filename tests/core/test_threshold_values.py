"""Threshold values and errors of the wrong type: refused with the package's ValidationError
saying what to pass, or taken as meant (an eps mapping names the inputs' scenes, not only
OpenLORIS')."""

from __future__ import annotations

import numpy as np
import pytest

import lorisnb as ln
from lorisnb.core.spec import validate
from lorisnb.errors import ValidationError


@pytest.fixture(scope="module")
def desk(data):
    return ln.evaluate_pairs(data.tum / "fr2_desk_ORB.txt", data.tum / "fr2_desk_groundtruth.txt", "tum")


def test_an_eps_mapping_names_the_scenes_of_the_inputs(desk):
    """As python.md and sweeps.md say (a pair's or a manifest's scene: fr2_desk); it was refused as
    'unknown scene'."""
    by_map = desk.sequences(eps={"fr2_desk": 0.01})
    assert by_map[["eps", "cr"]].values.tolist() == desk.sequences(eps=0.01)[["eps", "cr"]].values.tolist()
    assert ln.sweep(desk.errors, eps=[{"fr2_desk": 0.01}])["cr"].tolist() == by_map["cr"].tolist()
    with pytest.raises(ValidationError, match="gives no threshold for scene 'fr2_desk'"):
        desk.sequences(eps={"cafe": 1.0})
    with pytest.raises(ValidationError, match="lower case"):
        validate.eps_value({"Cafe": 1.0})
    with pytest.raises(ValidationError, match="an empty mapping"):
        validate.eps_value({})


def test_negative_zero_is_zero_and_bytes_are_refused(desk):
    assert str(desk.sequences(eps=-0.0)["eps"].iloc[0]) == "0.0"
    assert str(validate.threshold("phi", -0.0)) == "0.0"
    for name in ("eps", "phi", "delta", "tau"):
        with pytest.raises(ValidationError, match=r"\(bytes\): expected"):
            desk.sequences(**{name: b"3"})


def test_a_two_dimensional_grid_is_refused_showing_its_shape(desk):
    with pytest.raises(ValidationError, match=r"an array of shape \(2, 2\); expected a list of values"):
        ln.sweep(desk.errors, eps=np.array([[1, 3], [5, 7]]))


def test_evaluate_sessions_takes_a_preset_name_as_session_errors_does(data):
    gt, est = ln.read_tum(data.tum / "fr2_desk_groundtruth.txt"), ln.read_tum(data.tum / "fr2_desk_ORB.txt")
    a = ln.score(ln.evaluate_sessions(gt, est, "tum"))
    b = ln.score(ln.session_errors(gt, est, "tum"))
    assert a["ate_rmse"].tolist() == b["ate_rmse"].tolist()
    with pytest.raises(ValidationError, match="expected an EvalSpec .* or a preset name"):
        ln.evaluate_sessions(gt, est, 3)
