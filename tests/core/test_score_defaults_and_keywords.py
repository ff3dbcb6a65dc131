"""The tables of errors take the thresholds not given from the spec the errors were evaluated
under, as they take its RPE settings: ``ln.score(ev.errors)`` and ``ln.sweep(ev.errors)`` of
``ln.evaluate(path, eps=0.3, ...)`` scored at eps=inf, phi=inf, delta=1, tau=60 silently (CR 0.283
where ``ev.sequences()`` said 0.0). Every entry taking thresholds refuses a keyword it does not take
with the package's ValidationError naming those it takes (``score(epsilon=1)``, ``sweep(epsilon=[1])``,
``ev.scenes(foo=2)`` raised a bare TypeError). A finite number too large for a float (``"1e400"``)
is refused, not read as infinity (no threshold)."""

from __future__ import annotations

import math
import warnings
from decimal import Decimal

import numpy as np
import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.core.lifelong.scoring import pose_table
from lorisnb.core.lifelong.sweep import eps_at_cr
from lorisnb.core.spec import validate
from lorisnb.errors import ValidationError

SETTING = dict(eps=1.0, phi=10.0, delta=0.5, tau=10.0)
COLUMNS = ["eps", "phi", "delta", "tau", "cr", "cr_t", "cs_r", "c_ate_rmse"]


@pytest.fixture(scope="module")
def market(icra20):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ln.evaluate(icra20 / "per-seq" / "ds-slam" / "market-1-1.txt", jobs=1, **SETTING)


@pytest.fixture(scope="module")
def computed(data, icra20):
    r = ln.read_openloris(icra20 / "per-seq" / "ds-slam" / "market-1-1.txt")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ln.compute_errors(r, ln.load_groundtruth(r.scene, data_root=data.root))


def test_score_and_sweep_of_an_evaluations_errors_use_its_thresholds(market):
    table = market.sequences()[COLUMNS]
    assert table.iloc[0].to_dict() == pytest.approx(
        dict(SETTING, cr=0.1268154615988409, cr_t=0.12693099781162048, cs_r=0.9815201368608274,
             c_ate_rmse=0.6266228162044832), rel=1e-12,
    )  # fmt: skip
    pd.testing.assert_frame_equal(ln.score(market.errors)[COLUMNS], table)
    swept = ln.sweep(market.errors)
    pd.testing.assert_frame_equal(swept[COLUMNS], table)
    # one given, the others still the spec's
    one = ln.score(market.errors, eps=0.5).iloc[0]
    assert (one.eps, one.phi, one.delta, one.tau) == (0.5, 10.0, 0.5, 10.0)
    assert one.cr == pytest.approx(0.032877697621005945, rel=1e-12)
    grid = ln.sweep(market.errors, eps=[0.5, 1.0])
    assert grid[["phi", "delta", "tau"]].drop_duplicates().to_numpy().tolist() == [[10.0, 0.5, 10.0]]
    assert grid["cr"].tolist() == [one.cr, table.cr[0]]
    # the pose table and eps_at_cr too
    assert pose_table(market.errors)["correct"].sum() == market.poses()["correct"].sum() == 189
    at = eps_at_cr(market.errors, 0.1, market.durations()).iloc[0]
    assert (at.phi, at.delta) == (10.0, 0.5) and at.max_cr == pytest.approx(0.06690113591242626, rel=1e-12)


def test_errors_recording_no_thresholds_keep_the_defaults(computed, market):
    row = ln.score(computed).iloc[0]
    assert (row.eps, row.phi, row.delta, row.tau) == (math.inf, math.inf, 1.0, 60.0)
    assert row.cr == pytest.approx(0.2832288544283487, rel=1e-12)
    assert ln.sweep(computed)["cr"][0] == row.cr
    assert pose_table(computed)["correct"].all()
    at = eps_at_cr(computed, 0.1, market.durations()).iloc[0]
    assert (at.phi, at.delta) == (math.inf, 1.0)


def test_errors_of_different_thresholds_need_them_given(market, icra20):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        other = ln.evaluate(icra20 / "per-seq" / "ds-slam" / "market-1-2.txt", jobs=1, **{**SETTING, "eps": 3.0})
    both = market.errors + other.errors
    for call in (lambda **kw: ln.score(both, **kw), lambda **kw: ln.sweep(both, **kw)):
        with pytest.raises(
            ValidationError, match=r"^eps: the errors were computed under different thresholds; give it"
        ):
            call()
        table = call(eps=2.0)  # the others agree: the spec's
        assert table[["eps", "phi", "delta", "tau"]].drop_duplicates().to_numpy().tolist() == [[2.0, 10.0, 0.5, 10.0]]


@pytest.mark.parametrize(
    "call, listed",
    [
        (lambda ev: ln.score(ev.errors, eps=3, epsilon=1), "eps, phi, delta, tau, rpe_delta"),
        (lambda ev: ln.sweep(ev.errors, epsilon=[1]), "eps, phi, delta, tau, relative_to"),
        (lambda ev: ev.scenes(eps=1, foo=2), "eps, phi, delta, tau"),
        (lambda ev: ev.poses(eps=1, foo=2), "eps, phi"),
        (lambda ev: ev.sequences(epsilon=3), "eps, phi, delta, tau, rpe_delta"),
        (lambda ev: pose_table(ev.errors, foo=1), "eps, phi"),
        (lambda ev: eps_at_cr(ev.errors, 0.5, ev.durations(), foo=1), "target, durations, phi, delta"),
    ],
)
def test_every_entry_taking_thresholds_refuses_an_unknown_keyword_naming_the_known(market, call, listed):
    with pytest.raises(ValidationError, match=r"^(epsilon|foo): not a setting of .*; expected one of " + listed):
        call(market)


def test_an_unknown_keyword_near_a_known_one_is_named():
    with pytest.raises(ValidationError, match=r"^epss: not a setting of the scores \(did you mean 'eps'\?\)"):
        ln.score([], epss=1)


@pytest.mark.parametrize(
    "value",
    ["1e400", "-1e400", " 1E+400 ", 10**400, Decimal("1e400"), np.longdouble("1e400")],
    ids=["text", "negative", "spaced", "int", "decimal", "longdouble"],
)
def test_a_finite_number_too_large_for_a_float_is_refused_not_read_as_infinity(market, value):
    with pytest.raises(ValidationError, match=r"too large to be a number .*write 'inf' for no threshold"):
        validate.threshold("tau", value)
    with pytest.raises(ValidationError, match=r"^eps=.*too large to be a number"):
        ln.score(market.errors, eps=value)
    with pytest.raises(ValidationError, match=r"^phi=.*too large to be a number"):
        market.sequences(phi=value)
    with pytest.raises(ValidationError, match=r"^max_bytes=.*too large to be a number"):
        validate.positive("max_bytes", value, "bytes")


def test_infinity_spelled_inf_is_still_no_threshold():
    for value in ("inf", "Infinity", "+inf", math.inf, np.float32(np.inf), Decimal("Infinity"), np.array(np.inf)):
        assert validate.threshold("eps", value) == math.inf
    assert validate.threshold_list("eps", "1,inf") == [1.0, math.inf]
    with pytest.raises(ValidationError, match=r"too large to be a number"):
        validate.threshold_list("eps", "1,1e400")


def test_streamed_sweeps_use_the_errors_thresholds(market, tmp_path):
    """sweep_to_csv and sweep_to_parquet take the thresholds not given from the errors' spec, as
    sweep does (they scored at inf/inf/1/60 whatever the evaluation's spec)."""
    from lorisnb.tools import sweep_to_csv, sweep_to_parquet

    table = market.sequences()[COLUMNS]
    path, rows = sweep_to_csv(market.errors, tmp_path / "sweep.csv")
    assert rows == 1
    pd.testing.assert_frame_equal(pd.read_csv(path)[COLUMNS], table, check_dtype=False)
    path, rows = sweep_to_parquet(market.errors, tmp_path / "sweep", phi=[5.0, 10.0])
    streamed = pd.read_parquet(path).sort_values("phi")
    assert streamed[["eps", "delta", "tau"]].drop_duplicates().to_numpy().tolist() == [[1.0, 0.5, 10.0]]
    assert streamed["cr"].tolist()[1] == pytest.approx(table.cr[0], rel=1e-12)
