"""CSV tables are written in pandas' ``to_csv(index=False)`` text, byte for byte, whether pandas or
pyarrow's compute functions build the lines (:func:`lorisnb.io.writers.write_csv_parts`): a whole
float keeps its ``.0`` (so ``eps`` 3.0 is read back as a float, as a ``diff`` message quotes it), small
and large magnitudes take Python's exponent form, text is quoted only where it must be."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from lorisnb.io.writers import write_csv, write_csv_parts


def _table(n: int, seed: int) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    x = rng.standard_normal(n) * 10.0 ** rng.integers(-22, 22, n)
    x[rng.integers(0, n, n // 10)] = np.round(x[rng.integers(0, n, n // 10)])  # whole floats
    x[rng.integers(0, n, n // 20)] = np.nan
    x[:8] = [0.0, -0.0, 1e-4, 9.99e-5, 1e16, 9.999e15, np.inf, -np.inf]
    words = np.array(["cafe", "home, 2", 'say "hi"', "two\nlines", "", "x"], dtype=object)
    return pd.DataFrame({
        "x": x, "whole": np.round(x), "n": np.arange(n), "ok": rng.uniform(size=n) < 0.5,
        "scene": pd.Categorical(words[rng.integers(0, len(words), n)]),
        "label": pd.array(np.where(rng.uniform(size=n) < 0.1, None, words[rng.integers(0, len(words), n)]), dtype="string"),
        "count": pd.array(np.where(rng.uniform(size=n) < 0.1, None, rng.integers(0, 9, n)), dtype="Int64"),
        "f32": np.float32(x),
    })  # fmt: skip


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.thorough
def test_csv_text_is_pandas_to_csv_byte_for_byte(tmp_path, seed):
    df = _table(20_000, seed)
    for k, cols in enumerate(
        (list(df.columns), ["x", "whole", "n", "ok", "scene", "label", "count"], ["x"], ["label"])
    ):
        out = write_csv(df[cols], tmp_path / f"{seed}-{k}.csv")
        assert out.read_bytes() == df[cols].to_csv(index=False).encode(), cols


def test_odd_tables_are_written_as_pandas_writes_them(tmp_path):
    """A column name twice, names that are numbers, time stamps: pandas' text too."""
    for k, df in enumerate((
        pd.DataFrame([[1.0, 2.0, "a"]], columns=["x", "x", "s"]),
        pd.DataFrame({1: [1.5, np.nan], 2: [2.5, 3.0]}),
        pd.DataFrame({"a": [1.5, 2.0], "t": pd.to_datetime(["2026-01-01 10:00", "2026-11-28 00:00"], utc=True)}),
    )):  # fmt: skip
        assert write_csv(df, tmp_path / f"{k}.csv").read_bytes() == df.to_csv(index=False).encode()


def test_parts_are_one_table_and_read_back_as_written(tmp_path):
    df = _table(5_000, 3).drop(columns=["f32"])
    out = write_csv_parts([df.iloc[:1234], df.iloc[1234:1234], df.iloc[1234:]], tmp_path / "parts.csv")
    assert out.read_bytes() == df.to_csv(index=False).encode()
    back = pd.read_csv(out, keep_default_na=False, na_values=[""])
    assert back["whole"].dtype == np.float64 and back["n"].dtype == np.int64 and back["ok"].dtype == bool
    np.testing.assert_array_equal(back["x"].to_numpy(), df["x"].to_numpy())


def test_a_part_of_any_size_is_written_in_batches_of_rows(tmp_path, monkeypatch):
    """``lorisnb sweep --csv`` over a lifelong file (2 million rows in one part) built the part's text
    whole and passed pyarrow's 2 GB of 32-bit string offsets: ArrowCapacityError, a traceback. A part
    is written in batches of :data:`~lorisnb.io.writers.CSV_BATCH_ROWS` rows (here 1,000, with a limit of
    1,000 rows standing for the 2 GB), the same text as pandas'."""
    pa = pytest.importorskip("pyarrow")
    from lorisnb.io import writers

    real, seen = writers._arrow_lines, []

    def limited(df):
        seen.append(len(df))
        if len(df) > 1_000:  # what a text past 2 GB did
            raise pa.lib.ArrowCapacityError("Result may exceed offset capacity for this type")
        return real(df)

    monkeypatch.setattr(writers, "_arrow_lines", limited)
    monkeypatch.setattr(writers, "CSV_BATCH_ROWS", 1_000, raising=False)
    df = _table(4_500, 4).drop(columns=["f32"])
    out = write_csv_parts([df.iloc[:3_200], df.iloc[3_200:]], tmp_path / "big.csv")
    assert out.read_bytes() == df.to_csv(index=False).encode()
    assert max(seen) == 1_000 and sum(seen) == len(df)
