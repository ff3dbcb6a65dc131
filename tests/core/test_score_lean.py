"""score(..., stats=False): the paper's metrics without the error statistics, the same values."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.core.lifelong.scoring import score
from lorisnb.core.pipeline.model import STAT_COLUMNS
from lorisnb.errors import ValidationError


def test_without_statistics_the_other_columns_are_the_same_to_the_last_bit(icra20):
    """On real icra20 results (two algorithms, two scenes), every column but the statistics equals
    the full table's bit for bit, and the statistics are left out."""
    ev = ln.evaluate(icra20 / "lifelong", algorithms=["maslam", "orbslam2_t265"], scenes=["home", "office"],
                     progress=False)  # fmt: skip
    full = score(ev.errors, "paper", 30.0, 1.0, 60.0)
    lean = score(ev.errors, "paper", 30.0, 1.0, 60.0, stats=False)
    assert not set(STAT_COLUMNS) & set(lean.columns) and set(STAT_COLUMNS) <= set(full.columns)
    assert len(lean) == len(full) > 4 and (lean["cr"] > 0).any()
    pd.testing.assert_frame_equal(lean, full[list(lean.columns)], check_exact=True)
    num = lean.select_dtypes("number").to_numpy(float)
    assert np.array_equal(num, full[lean.select_dtypes("number").columns].to_numpy(float), equal_nan=True)


def test_stats_takes_only_true_or_false(icra20):
    ev = ln.evaluate(icra20 / "lifelong", algorithms=["maslam"], scenes=["home"], progress=False)
    with pytest.raises(ValidationError, match="stats='no'"):
        score(ev.errors, stats="no")  # type: ignore[arg-type]
