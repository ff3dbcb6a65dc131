"""Property-based robustness of every reader (issue #7): random and mutated files may only raise
lorisnb's own errors, each naming the file (and the line, when the problem is on a line).

The example budget and the seed are fixed (``derandomize=True``), so CI runs the same cases."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from helpers import errors_of
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lorisnb.errors import LorisError, LorisWarning, ParseError
from lorisnb.io import load_groundtruth, read_euroc, read_kitti, read_openloris, read_times, read_tum
from lorisnb.io.readers.ordslam import read_ordslam

FUZZ = settings(
    max_examples=200,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)

BAD_TOKENS = [
    b"abc",
    b"1.2.3",
    b"nan",
    b"NaN",
    b"inf",
    b"-inf",
    b"1e999",
    b"0x10",
    b"--1",
    b"",
    b"1e308",
    b"-1560000000.5",
    b"99999999999999999999",
    b"\xff\xfe",
    b"1,5",
    b"\xc3\xa9",
]


def _base_openloris(n: int = 12) -> list[bytes]:
    rng = np.random.default_rng(0)
    lines = [b"scene: cafe", b"frame: d400_color", b"seq: 1"]
    t0 = 1560004885.5
    for k in range(n):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        vals = [t0 + 0.1 * k, *rng.normal(size=3), *q]
        lines.append(" ".join(repr(float(v)) for v in vals).encode())
        if k == n // 2:
            lines.append(b"seq: 2")
    return lines


def _base_tum(n: int = 10) -> list[bytes]:
    return [b"# timestamp tx ty tz qx qy qz qw"] + [f"{1.0 + 0.1 * k} {k} 0 0 0 0 0 1".encode() for k in range(n)]


@st.composite
def mutated(draw, base):
    lines = list(base)
    for _ in range(draw(st.integers(0, 6))):
        op = draw(
            st.sampled_from(
                [
                    "truncate",
                    "extra",
                    "token",
                    "dup",
                    "swap",
                    "delete",
                    "empty_seq",
                    "garbage",
                    "huge",
                    "negative",
                    "blank",
                ]
            )
        )
        if not lines:
            lines.append(b"")
        i = draw(st.integers(0, len(lines) - 1))
        if op == "truncate":
            lines[i] = lines[i][: draw(st.integers(0, max(0, len(lines[i]) - 1)))]
        elif op == "extra":
            lines[i] = lines[i] + b" " + draw(st.sampled_from([b"1", b"2.5", b"x"]))
        elif op == "token":
            toks = lines[i].split() or [b""]
            toks[draw(st.integers(0, len(toks) - 1))] = draw(st.sampled_from(BAD_TOKENS))
            lines[i] = b" ".join(toks)
        elif op == "dup":
            lines.insert(i, lines[i])
        elif op == "swap":
            j = draw(st.integers(0, len(lines) - 1))
            lines[i], lines[j] = lines[j], lines[i]
        elif op == "delete":
            del lines[i]
        elif op == "empty_seq":
            lines.insert(i, b"seq: %d" % draw(st.integers(-2, 9)))
        elif op == "garbage":
            lines.insert(i, draw(st.binary(min_size=0, max_size=40)))
        elif op in ("huge", "negative"):
            toks = lines[i].split()
            if toks:
                toks[0] = b"1e300" if op == "huge" else b"-5.25"
                lines[i] = b" ".join(toks)
        else:
            lines.insert(i, b"   ")
    sep = draw(st.sampled_from([b"\n", b"\r\n"]))
    return sep.join(lines) + draw(st.sampled_from([b"", sep]))


def _check(exc: LorisError, path) -> None:
    assert isinstance(exc, LorisError)
    if isinstance(exc, ParseError):
        assert exc.path == str(path) and str(path) in str(exc)
        if exc.line is not None:
            assert exc.line >= 1 and f"line {exc.line}" in str(exc)


def _run(fn, path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LorisWarning)
        try:
            return fn(path)
        except LorisError as exc:
            _check(exc, path)
            return None


@pytest.fixture(scope="module")
def cafe_gt():
    return load_groundtruth("cafe")


@FUZZ
@given(data=mutated(_base_openloris()))
@pytest.mark.thorough  # 200 draws, each read and evaluated (2 s of CPU); random bytes, below, in the fast loop
def test_openloris_reader_and_evaluation(tmp_path_factory, cafe_gt, data):
    p = tmp_path_factory.mktemp("fz") / "fuzz.txt"
    p.write_bytes(data)
    f = _run(read_openloris, p)
    if f is not None:
        _run(lambda q: errors_of(q, cafe_gt, algorithm="fuzz"), p)


@FUZZ
@given(data=st.binary(max_size=300))
def test_openloris_reader_random_bytes(tmp_path_factory, data):
    p = tmp_path_factory.mktemp("fz") / "random.txt"
    p.write_bytes(data)
    _run(read_openloris, p)


@FUZZ
@given(data=mutated(_base_tum()))
@pytest.mark.thorough  # 200 draws through two readers (2.5 s of CPU)
def test_tum_and_ordslam_readers(tmp_path_factory, data):
    p = tmp_path_factory.mktemp("fz") / "tum.txt"
    p.write_bytes(data)
    _run(read_tum, p)
    _run(lambda q: read_ordslam(q, fps=30.0), p)
    _run(read_times, p)


@FUZZ
@given(data=mutated([b"1 0 0 0 0 1 0 0 0 0 1 0", b"1 0 0 1 0 1 0 0 0 0 1 0", b"0 -1 0 2 1 0 0 0 0 0 1 0"]))
@pytest.mark.thorough
def test_kitti_and_euroc_through_evo(tmp_path_factory, data):
    p = tmp_path_factory.mktemp("fz") / "kitti.txt"
    p.write_bytes(data)
    _run(read_kitti, p)
    _run(read_euroc, p)
    _run(lambda q: read_ordslam(q, fps=10.0), p)


def test_missing_headers_and_empty_file(tmp_path, cafe_gt):
    p = tmp_path / "empty.txt"
    for empty in (b"", b"\n  \n", b"\xef\xbb\xbf"):
        p.write_bytes(empty)
        with pytest.raises(ParseError, match="empty.txt: empty file; expected an OpenLORIS trajectory file"):
            errors_of(p, cafe_gt)
    p.write_bytes(b"seq: 1\n1 0 0 0 0 0 0 1\n")
    with pytest.raises(ParseError, match="no 'scene: NAME' header line"):
        errors_of(p, cafe_gt)
