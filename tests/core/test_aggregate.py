"""The per-scene aggregate on numpy columns (:func:`lorisnb.core.lifelong.aggregate.aggregate_columns`)
gives pandas' numbers to the last bit: compared with the pandas ``groupby`` implementation it
replaced (kept below as the oracle, as it stood before issue 27) on the bundled results, on
sweeps with trials, and on awkward tables (NaN, no correct pose, unknown scenes, duplicates)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.core.lifelong import aggregate
from lorisnb.core.lifelong.sweep import sweep
from lorisnb.core.pipeline.model import SCENE_COLUMNS
from lorisnb.core.trajectory.frames import SCENES
from lorisnb.errors import EvaluationError, ValidationError


def _pandas_aggregate(sequences: pd.DataFrame, durations: pd.DataFrame) -> pd.DataFrame:
    """``aggregate_scenes`` as written with pandas' groupby before issue 27 (lorisnb 7224ec8), with
    one fix: a categorical scene column (sweep tables) was sorted by its categories' order, not
    the paper's (``c.map(order)`` keeps a Categorical); the values are mapped here. Since then: a
    sequence "with output" has a matched pose (``sequences_with_output``; ``cs_r_with_output`` is
    the mean over those, no longer over rows with nothing matched)."""
    total = durations.groupby("scene")["gt_duration"].sum()
    nseq = durations.groupby("scene")["seq"].count()
    keys = ["suite", "algorithm", "scene", "eps", "phi", "delta", "tau"]
    keys += [c for c in ("eps_value", "trial") if c in sequences.columns]
    df = sequences.copy()
    df["_c_sq"] = np.where(df["c_matched"] > 0, df["c_ate_rmse"] ** 2 * df["c_matched"], 0.0)
    df["_c_w"] = np.where(df["c_matched"] > 0, df["c_ate_rmse"] * df["c_matched"], 0.0)
    df["_a_w"] = np.where(df["matched"] > 0, df["ate_rmse"] * df["matched"], 0.0)
    df["_out"] = (df["matched"] > 0).astype(int)
    g = df.groupby(keys, sort=False, dropna=False, observed=True)
    out = g.agg(
        sequences=("seq", "count"), matched=("matched", "sum"), c_matched=("c_matched", "sum"),
        correct_time=("correct_time", "sum"), track_time=("track_time", "sum"), sequences_with_output=("_out", "sum"),
        _cs_sum=("cs_r", "sum"), _c_sq=("_c_sq", "sum"), _c_w=("_c_w", "sum"), _a_w=("_a_w", "sum"),
    ).reset_index()  # fmt: skip
    out["scene_sequences"] = out["scene"].astype(str).map(nseq).astype(int)
    out["scene_duration"] = out["scene"].astype(str).map(total)
    with np.errstate(invalid="ignore", divide="ignore"):
        out["cr"] = out["correct_time"] / out["scene_duration"]
        out["cr_t"] = np.where(out["track_time"] > 0, out["correct_time"] / out["track_time"], np.nan)
        out["c_ate_rmse"] = np.where(out["c_matched"] > 0, out["_c_w"] / out["c_matched"], np.nan)
        out["c_ate_rmse_pooled"] = np.where(out["c_matched"] > 0, np.sqrt(out["_c_sq"] / out["c_matched"]), np.nan)
        out["ate_rmse"] = np.where(out["matched"] > 0, out["_a_w"] / out["matched"], np.nan)
        out["cs_r"] = out["_cs_sum"] / out["scene_sequences"]  # a sequence without output counts 0
        out["cs_r_with_output"] = np.where(out["sequences_with_output"] > 0,
                                           out["_cs_sum"] / out["sequences_with_output"], np.nan)  # fmt: skip
    order = {s: i for i, s in enumerate(SCENES)}
    out = out.drop(columns=["_c_sq", "_c_w", "_a_w", "_cs_sum"])[SCENE_COLUMNS + keys[7:]]
    out = out.sort_values(
        ["suite", "algorithm", "scene"] + (["trial"] if "trial" in out.columns else []),
        key=lambda c: c.astype(object).map(order) if c.name == "scene" else (c if c.name == "trial" else c.astype(str)),
    )
    return out.reset_index(drop=True)


def _same(table: pd.DataFrame, durations: pd.DataFrame) -> pd.DataFrame:
    got, want = ln.aggregate_scenes(table, durations), _pandas_aggregate(table, durations)
    assert list(got.columns) == list(want.columns) and len(got) == len(want)
    for c in want.columns:
        a, b = got[c].to_numpy(), want[c].to_numpy()
        if b.dtype.kind == "f":
            assert a.dtype.kind == "f" and np.array_equal(a, b, equal_nan=True), c  # to the last bit
        else:
            assert [str(v) for v in a] == [str(v) for v in b], c
            assert a.dtype.kind == b.dtype.kind, c
    return got


@pytest.mark.thorough
def test_scene_aggregate_equals_pandas_on_the_bundled_results(icra20):
    ev = ln.evaluate(icra20, progress=False)
    for eps, phi in ((np.inf, np.inf), ("paper", 30.0), (0.05, 5.0)):
        got = _same(ev.sequences(eps, phi), ev.durations())
        assert (got["cr"] > 0).any() and got["scene"].isin(SCENES).all()


def test_sweep_with_trials_and_eps_labels_equals_pandas(icra20):
    ev = ln.evaluate(icra20 / "lifelong", progress=False)
    table = sweep(ev.errors, [0.1, "paper", 1.0], [10.0, 30.0], [0.5, 1.0])
    assert "eps_value" in table.columns
    _same(table, ev.durations())
    trials = pd.concat([table.assign(trial=k, cr=table["cr"] * (1 + k / 7)) for k in (2, 1, 3)], ignore_index=True)
    trials["correct_time"] = trials["correct_time"] * 1.000000001 ** trials["trial"]
    _same(trials, ev.durations())


def test_awkward_tables_equal_pandas_and_duplicates_are_refused():
    rng = np.random.default_rng(2)
    n = 60
    table = pd.DataFrame(
        dict(
            suite=rng.choice(["", "lab"], n), algorithm=rng.choice(["b", "a", "c10", "c9"], n),
            scene=rng.choice(["market", "cafe", "garden", "attic"], n), eps=0.5, phi=30.0, delta=1.0, tau=60.0,
            seq=np.arange(n), file=[f"f{k}.txt" for k in range(n)],
            matched=rng.integers(0, 5000, n) * (rng.uniform(size=n) > 0.2), c_matched=rng.integers(0, 3, n) * rng.integers(0, 5000, n),
            correct_time=rng.uniform(0, 100, n) * 1e-3 ** rng.integers(0, 3, n), track_time=rng.uniform(-1, 100, n),
            cs_r=np.where(rng.uniform(size=n) < 0.3, np.nan, rng.uniform(size=n)),
            c_ate_rmse=np.where(rng.uniform(size=n) < 0.2, np.nan, rng.lognormal(size=n)),
            ate_rmse=rng.lognormal(size=n),
        )
    )  # fmt: skip
    table.loc[table["matched"] == 0, ["c_matched", "correct_time", "cs_r"]] = 0  # a failed run, as scored
    spans = {
        s: {k: (0.0, float(rng.uniform(10, 300))) for k in range(n + 5)} for s in ("market", "cafe", "garden", "attic")
    }  # every sequence of the table has its duration (and each scene more, without a row: not tracked)
    durations = aggregate.spans_table(spans)
    got = _same(table, durations)
    assert (got["cs_r_with_output"].isna() == (got["sequences_with_output"] == 0)).all()  # no output: no mean
    assert (got["cs_r"] <= got["cs_r_with_output"].fillna(0) + 1e-12).all()  # missing sequences count 0
    assert list(got["scene"][got["algorithm"] == "a"].drop_duplicates())[:2] == ["cafe", "market"]  # the paper's order
    twice = pd.concat([table, table.iloc[[7]]], ignore_index=True)
    with pytest.raises(EvaluationError, match=r"several results for .* \(f7\.txt\)"):
        ln.aggregate_scenes(twice, durations)
    with pytest.raises(EvaluationError, match="no ground-truth durations for scene"):
        ln.aggregate_scenes(table, aggregate.spans_table({"cafe": spans["cafe"]}))
    assert ln.aggregate_scenes(table.iloc[:0], durations).columns.tolist() == SCENE_COLUMNS


def test_durations_must_hold_each_sequence_of_the_table_once(icra20):
    """Durations missing a sequence of the table gave the scene's CR over too short a time;
    repeated rows over twice it: both refused naming the sequences. Tables of another kind (None,
    the two swapped) are a ValidationError, not a KeyError."""
    ev = ln.evaluate(icra20 / "per-seq" / "ds-slam", progress=False)
    seq, durations = ev.sequences(eps=1, phi=10), ev.durations()
    first = durations.iloc[0]
    with pytest.raises(ValidationError, match=rf"no row for sequence\(s\) {first.scene}-{first.seq} of the table"):
        ln.aggregate_scenes(seq, durations.iloc[1:])
    with pytest.raises(ValidationError, match=r"repeated row\(s\) \(cafe-1, cafe-2"):
        ln.aggregate_scenes(seq, pd.concat([durations, durations]))
    with pytest.raises(ValidationError, match="durations: expected a DataFrame"):
        ln.aggregate_scenes(seq, None)
    with pytest.raises(ValidationError, match="in that order"):
        ln.aggregate_scenes(durations, seq)
    ok = ln.aggregate_scenes(seq, durations)
    assert (ok["scene_sequences"] == ok["scene"].map(durations["scene"].value_counts())).all()
