"""The pose readers' look at each piece as it is parsed (``formats.rows_fit``): where it finds
nothing, the rows skip ``check_rows``; wherever it flags rows, ``check_rows`` decides. Either way
a TUM or EuRoC file reads exactly as with ``check_rows`` on every row (arrays, notes, errors), on
every route a plain file can take, with the problems in late pieces and on the thresholds."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from helpers import PARSERS, use_parser, write

from lorisnb.core.trajectory.poses import QUAT_EPS
from lorisnb.errors import ParseError
from lorisnb.io import read_euroc, read_tum
from lorisnb.io.readers import plain as formats

N = 1000
EDGE = float(np.sqrt(QUAT_EPS))


def _rows() -> np.ndarray:
    rng = np.random.default_rng(21)
    q = rng.normal(size=(N, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    return np.column_stack([np.arange(N) * 0.05 + 1.0, rng.normal(0, 3, (N, 3)), q])


def _set(row: int, cols: slice | int, value: object):
    def edit(rows: np.ndarray) -> np.ndarray:
        rows[row, cols] = value
        return rows

    return edit


CASES = {
    "clean": lambda r: r,
    "NaN position, late": _set(900, 1, np.nan),
    "inf quaternion, late": _set(950, 5, np.inf),
    "zero quaternion, late": _set(800, slice(4, 8), 0.0),
    "quaternion too large": _set(700, slice(4, 8), 1e200),
    "norm just at the floor": _set(600, slice(4, 8), [EDGE * (1 + 1e-12), 0, 0, 0]),
    "norm just under the floor": _set(600, slice(4, 8), [EDGE * (1 - 1e-9), 0, 0, 0]),
    "sums overflow, numbers finite": _set(slice(10, 12), 1, 1.5e308),
    "NaN stamp": _set(500, 0, np.nan),
    "stamps backwards": _set(300, 0, 0.5),
}


def _text(rows: np.ndarray, fmt: str) -> str:
    if fmt == "tum":
        return "".join(" ".join(repr(float(v)) for v in r) + "\n" for r in rows)
    lines = ["#timestamp,p_x,p_y,p_z,q_w,q_x,q_y,q_z\n"]
    for r in rows:
        stamp = "nan" if np.isnan(r[0]) else str(int(round(r[0] * 1e9)))
        lines.append(",".join([stamp, *(repr(float(v)) for v in (*r[1:4], r[7], *r[4:7]))]) + "\n")
    return "".join(lines)


def _outcome(path, fmt: str):
    read = read_tum if fmt == "tum" else read_euroc
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            t = read(path)
        except ParseError as exc:
            return str(exc)
    return t, [str(w.message) for w in caught]


@pytest.mark.parametrize("parser", PARSERS)
@pytest.mark.parametrize("fmt", ["tum", "euroc"])
@pytest.mark.thorough
def test_a_pieces_look_reads_as_check_rows_on_every_row(tmp_path, monkeypatch, parser, fmt):
    use_parser(monkeypatch, parser)
    real_fit, real_check = formats.rows_fit, formats.check_rows
    checked: list[int] = []
    monkeypatch.setattr(formats, "check_rows", lambda *a: checked.append(len(a[1])) or real_check(*a))
    for name, edit in CASES.items():
        path = write(tmp_path, f"{name}.{fmt}", _text(edit(_rows()), fmt))
        checked.clear()
        fast = _outcome(path, fmt)
        skipped = not checked
        monkeypatch.setattr(formats, "rows_fit", lambda *p: [*real_fit(*p)[:3], np.ones(len(real_fit(*p)[3]), bool)])
        try:
            slow = _outcome(path, fmt)
        finally:
            monkeypatch.setattr(formats, "rows_fit", real_fit)
        whole = fmt == "euroc" and name == "NaN stamp"  # not whole nanoseconds: EuRoC's whole-file reader says so
        assert bool(checked) != whole, name  # flagged everywhere: check_rows looked
        if isinstance(fast, str) or isinstance(slow, str):
            assert fast == slow, name
            continue
        for attr in ("stamps", "positions", "quaternions", "lines"):
            np.testing.assert_array_equal(getattr(fast[0], attr), getattr(slow[0], attr), err_msg=f"{name}: {attr}")
        assert fast[1] == slow[1], name
        assert skipped == (name in ("clean", "stamps backwards") or whole), name  # nothing for check_rows to see


def test_the_cases_are_what_they_say():
    """The cases reach check_rows' every outcome: a note, each error, and rows kept at the floor."""
    got = {}
    for name, edit in CASES.items():
        rows = edit(_rows())
        finite = np.isfinite(rows).all(axis=1)
        nq = np.einsum("ij,ij->i", rows[finite, 4:], rows[finite, 4:])
        got[name] = (int((~finite).sum()), bool((nq < QUAT_EPS).any()), bool(np.isinf(nq).any()))
    assert got["NaN position, late"] == (1, False, False)
    assert got["zero quaternion, late"][1] and got["norm just under the floor"][1]
    assert not got["norm just at the floor"][1] and got["quaternion too large"][2]
