"""The correct-pose sums (``scoring.row_sums``): a threshold setting alone is summed exactly as
its row of any grid, and one setting over a long sequence costs a few MB, not the grid's blocks.

The first fixed-shape version padded every product to 64 grid rows of the whole sequence: one
setting over a million poses held a 64 x 1M float block (512 MB, 512 bytes per pose against the
bench's 250-byte goal for a whole 1M-pose evaluation) and did 64 times the work."""

from __future__ import annotations

import tracemalloc

import hypothesis.extra.numpy as hnp
import hypothesis.strategies as st
import numpy as np
import pytest
from hypothesis import given, settings

from lorisnb.core.lifelong import scoring
from lorisnb.core.lifelong.scoring import row_sums


def _grid(rows: int, poses: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.random((rows, poses)) < 0.7, rng.random((poses, 3)) * 5.0


def test_one_setting_over_a_million_poses_holds_a_few_megabytes():
    sel, values = _grid(1, 1_000_000)
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        sums = row_sums(sel, values)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 8 << 20, f"{peak / 2**20:.0f} MiB"  # the blocks, not the sequence
    np.testing.assert_allclose(sums[0], values[sel[0]].sum(axis=0), rtol=1e-13)


def test_a_row_alone_is_its_row_in_any_grid_to_the_last_bit():
    poses = 2 * scoring.POSE_BLOCK + 123  # three blocks of poses, the last one shorter
    ROW_BLOCK = scoring.ROW_BLOCK
    sel, values = _grid(3 * ROW_BLOCK + 5, poses, seed=1)
    grid = row_sums(sel, values)
    for r in (0, 1, ROW_BLOCK - 1, ROW_BLOCK, 2 * ROW_BLOCK + 3, len(sel) - 1):
        assert np.array_equal(row_sums(sel[r : r + 1], values), grid[r : r + 1]), r
        assert np.array_equal(row_sums(sel[r : r + 2], values)[:1], grid[r : r + 1]), r
    np.testing.assert_allclose(grid, np.array([values[s].sum(axis=0) for s in sel]), rtol=1e-13)


def test_a_superset_of_poses_never_sums_to_less():
    sel, values = _grid(1, 3 * scoring.POSE_BLOCK, seed=2)
    nested = np.vstack([sel[0] & (np.arange(sel.shape[1]) % k == 0) for k in (7, 3, 1)])
    nested[1] |= nested[0]
    sums = row_sums(nested, values)
    assert (np.diff(sums, axis=0) >= 0).all()


@settings(max_examples=300, deadline=None)
@given(
    v=hnp.arrays(np.float64, st.integers(1, 300),
                 elements=st.one_of(st.floats(-1e6, 1e6), st.sampled_from([np.nan, np.inf, -np.inf, 0.0, 1.0]))),
    seed=st.integers(0, 2**32 - 1),
)  # fmt: skip
@pytest.mark.thorough
def test_masked_medians_equal_numpys_nanmedian_to_the_bit(v, seed):
    """The grid's medians (sorted once, the middle ranks found from running counts) are numpy's
    ``nanmedian`` of each row's selected values to the last bit: ties, NaN (left out), infinities,
    empty rows and rows selecting everything included."""
    import warnings

    from lorisnb.core.metrics.relations import _masked_medians

    rng = np.random.default_rng(seed)
    rows = rng.uniform(size=(6, v.size)) < rng.uniform(size=(6, 1))
    rows[0], rows[1] = False, True
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        want = np.nanmedian(np.where(rows, v, np.nan), axis=1)
    np.testing.assert_array_equal(_masked_medians(v, rows), want)
