"""A scene's means do not depend on the order of the per-sequence rows: the weighted sums of
``c_ate_rmse``, ``c_ate_rmse_pooled`` and ``ate_rmse`` once followed the table's row order (the order
the inputs were given in, or their jobs finished in) and differed in the last bit (2.2e-16 for odom's
corridor and home in the ICRA'20 results)."""

from __future__ import annotations

import random

import numpy as np
import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.core.lifelong.aggregate import aggregate_scenes

SUMMED = ["c_ate_rmse", "c_ate_rmse_pooled", "ate_rmse", "cr", "cr_t", "cs_r", "correct_time", "track_time"]


def _same(a: pd.DataFrame, b: pd.DataFrame) -> None:
    assert list(a.columns) == list(b.columns)
    assert a[["algorithm", "scene"]].equals(b[["algorithm", "scene"]])
    for c in SUMMED:
        x, y = a[c].to_numpy(float), b[c].to_numpy(float)
        assert np.array_equal(x, y, equal_nan=True), (c, x - y)  # to the last bit


@pytest.fixture(scope="module")
def odom(icra20):
    files = sorted((icra20 / "per-seq" / "odom").glob("*.txt"))
    assert len(files) >= 10
    return files, ln.evaluate(files, scale="auto", jobs=1)


def test_rows_in_any_order_give_the_same_scene_means(odom):
    _, ev = odom
    table, durations = ev.sequences(eps="paper", phi=30), ev.durations()
    want = aggregate_scenes(table, durations)
    corridor = want[want.scene == "corridor"].iloc[0]
    assert corridor.sequences == 5 and 0 < corridor.ate_rmse < 10 and 0 < corridor.cr < 1
    for seed in range(6):  # the row orders that moved the last bit of corridor's and home's means
        order = list(range(len(table)))
        random.Random(seed).shuffle(order)
        _same(aggregate_scenes(table.iloc[order].reset_index(drop=True), durations), want)
    _same(aggregate_scenes(table.iloc[::-1].reset_index(drop=True), durations), want)


def test_inputs_given_in_another_order_and_jobs_give_the_same_scenes(odom):
    files, ev = odom
    again = ln.evaluate(files[::-1], scale="auto", jobs=2)
    _same(again.scenes(eps="paper", phi=30), ev.scenes(eps="paper", phi=30))
