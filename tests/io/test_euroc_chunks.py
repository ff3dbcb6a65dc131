"""EuRoC CSV read in chunks by the C parser (straight into the arrays kept) gives what the byte
scanner over the whole file gives: the same poses and line numbers, and for a bad file the same
first problem (widths are checked on every row before any number)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from helpers import write

from lorisnb.errors import LorisWarning, ParseError
from lorisnb.io import read_euroc
from lorisnb.io.readers import plain as formats

HEADER = "timestamp,p_x,p_y,p_z,q_w,q_x,q_y,q_z"


def _rows(n: int, extra: int = 0) -> str:
    rng = np.random.default_rng(n)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    tail = "".join(f",{k}.5" for k in range(extra))
    return "".join(
        f"{1_403_636_579_758_555_392 + 5_000_000 * k},{rng.normal():.6f},{rng.normal():.6f},{rng.normal():.6f},"
        f"{q[k, 0]:.7f},{q[k, 1]:.7f},{q[k, 2]:.7f},{q[k, 3]:.7f}{tail}\n"
        for k in range(n)
    )


@pytest.mark.parametrize(
    "text",
    [
        "#" + HEADER + "\n" + _rows(50),
        HEADER + "\n" + _rows(50, extra=9),  # a header without '#', 17 columns as EuRoC's ground truth
        "# comment\n\n  " + HEADER + "\n" + _rows(20),
        "#" + HEADER + "\n" + "ROWS 120000",  # several chunks, read on threads (the rows made in the test)
        "#" + HEADER + "\n" + _rows(10) + "1403636579808555392,1,2,3,nan,0,0,0\n",  # a NaN pose skipped
        "  " + HEADER,  # only a header: no poses
    ],
)
def test_same_poses_as_the_whole_file_scanner(tmp_path, text):
    if text.endswith("ROWS 120000"):  # made here, not when the module is collected (1 s in every worker)
        text = text.removesuffix("ROWS 120000") + _rows(120_000)
    p = write(tmp_path, "data.csv", text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LorisWarning)
        got, want = read_euroc(p), formats._read_euroc_whole(p, warn=False)
    for name in ("stamps", "positions", "quaternions", "lines"):
        np.testing.assert_array_equal(getattr(got, name), getattr(want, name))
    assert got.quaternions.flags.c_contiguous and len(got) == len(want)


@pytest.mark.parametrize(
    ("text", "line", "message"),
    [
        ("#h\n" + _rows(3) + "1,2,3\n", 5, "has 3 fields"),
        (_rows(2) + HEADER + "\n" + _rows(2, extra=1), 4, "has 9 fields"),  # the width first, as before
        (_rows(2) + "1,2,3,4,x,0,0,1\n", 3, "'x' is not a number"),
    ],
)
def test_the_same_first_problem(tmp_path, text, line, message):
    p = write(tmp_path, "bad.csv", text)
    with pytest.raises(ParseError, match=f"bad.csv, line {line}: .*{message}"):
        read_euroc(p)
