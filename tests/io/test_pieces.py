"""A plain file parsed in pieces on threads (:mod:`lorisnb.io.parsing.pieces`): pandas' buffer route where
the installed pandas has it, parsers kept between pieces and reads without one piece's numbers
reaching another's, the real TUM files read as the chunked reader reads them, and a forked child
that reads after its parent did."""

from __future__ import annotations

import multiprocessing
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from helpers import use_parser

from lorisnb.errors import ParseError
from lorisnb.io import read_tum
from lorisnb.io.parsing import pieces, whole


def test_the_buffer_route_is_taken_where_pandas_has_it():
    """pandas 3.1 parses a buffer with no GIL held (its threaded ``read_csv`` does): where it is
    installed, lorisnb's pieces take that route (else each piece is a ``read_csv`` call), and the
    check gives the numbers of ``read_csv``."""
    major, minor = (int(v) for v in pd.__version__.split(".")[:2])
    if (major, minor) < (3, 1):
        pytest.skip(f"pandas {pd.__version__} has no buffer route: pieces are read by read_csv")
    assert pieces.buffers_work()


@pytest.mark.parametrize("buffers", [True, False])
def test_a_kept_parser_leaves_the_numbers_it_gave_before(buffers):
    """A thread keeps its parser for the next piece: the columns of one piece stay as they were
    after the same parser reads a longer one (they are copied into place later, in file order),
    and after a piece it refuses (a file that is not plain) it reads the next plain one."""
    if buffers and not pieces.buffers_work():
        pytest.skip("this pandas has no buffer route")
    rng = np.random.default_rng(5)
    first, second = rng.normal(size=(50, 3)), rng.normal(size=(400, 3))
    text = [("\n".join(" ".join(repr(float(v)) for v in row) for row in a) + "\n").encode() for a in (first, second)]
    parser = pieces._Parser(" ", 3, buffers)
    got = parser.columns(text[0])
    again = parser.columns(text[1])
    assert got is not None and again is not None
    np.testing.assert_array_equal(np.column_stack(got), first)  # repr round-trips: the exact numbers
    np.testing.assert_array_equal(np.column_stack(again), second)
    assert parser.columns(b"1 2 3\n4 5\n") is None  # a short line: not plain, whichever route
    assert parser.columns(b"1 2 3\n4 5 x\n") is None
    assert parser.columns(b"1 2 3 4\n") is None
    again = parser.columns(text[0])  # a parser that refused a piece reads the next (it broke, once)
    assert again is not None
    np.testing.assert_array_equal(np.column_stack(again), first)


@pytest.mark.parametrize("parser", ["pieces", "read_csv"])
def test_the_real_tum_files_read_in_pieces_as_in_chunks(data, monkeypatch, parser):
    """Every TUM file of the real data (788 to about 20,000 poses), in pieces of 4 KB on 3 threads,
    gives the trajectory of the chunked reader (the byte scanner, the reference of every route)."""
    files = sorted(Path(data.tum).glob("*.txt"))
    assert len(files) == 4
    for path in files:
        read = use_parser(monkeypatch, parser)
        got = read_tum(path, warn=False)
        rows = sum(1 for line in path.read_text().splitlines() if line.strip() and not line.startswith("#"))
        assert len(read) == 1 and read[0] is not None and read[0][0] == rows  # every row, read in pieces
        monkeypatch.setattr(whole, "WHOLE_MAX_BYTES", 0)
        ref = read_tum(path, warn=False)
        monkeypatch.undo()
        for name in ("stamps", "positions", "quaternions", "lines"):
            np.testing.assert_array_equal(getattr(got, name), getattr(ref, name))
        assert len(got) > 700


def _read_in_child(path: str, out) -> None:
    out.put(len(read_tum(path, warn=False)))


def test_a_forked_child_reads_in_pieces(tmp_path, monkeypatch):
    """The parse threads are started once per process: a child forked after its parent read a file
    starts its own (the parent's are not there) instead of waiting for them for ever."""
    if "fork" not in multiprocessing.get_all_start_methods():
        pytest.skip("no fork on this system")
    use_parser(monkeypatch, "pieces")
    rng = np.random.default_rng(2)
    rows = np.column_stack(
        [1000 + np.arange(3000) * 0.1, rng.normal(size=(3000, 3)), np.tile([0, 0, 0, 1.0], (3000, 1))]
    )
    path = tmp_path / "traj.txt"
    path.write_text("\n".join(" ".join(repr(float(v)) for v in row) for row in rows) + "\n")
    assert len(read_tum(path, warn=False)) == 3000  # the parent's threads started
    ctx = multiprocessing.get_context("fork")
    out = ctx.Queue()
    child = ctx.Process(target=_read_in_child, args=(str(path), out))
    child.start()
    child.join(60)
    alive = child.is_alive()
    if alive:
        child.kill()
    assert not alive and child.exitcode == 0 and out.get(timeout=5) == 3000


@pytest.mark.parametrize("parser", ["pieces", "read_csv"])
def test_a_plain_file_after_one_that_is_not_is_still_read_in_pieces(tmp_path, monkeypatch, parser):
    """A file with a bad number late on is refused by a piece (the chunked reader names its line);
    the plain files read after it are read in pieces again, by the same threads, with their
    numbers (a parser that refused a piece refused every piece after it: each later file went the
    slow way, silently)."""
    read = use_parser(monkeypatch, parser)
    rng = np.random.default_rng(4)
    rows = np.column_stack(
        [1000 + np.arange(2000) * 0.1, rng.normal(size=(2000, 3)), np.tile([0, 0, 0, 1.0], (2000, 1))]
    )
    lines = [" ".join(repr(float(v)) for v in row) for row in rows]
    good, bad = tmp_path / "good.txt", tmp_path / "bad.txt"
    good.write_text("\n".join(lines) + "\n")
    bad.write_text("\n".join(lines[:1500] + [lines[1500].replace(" ", " x", 1)] + lines[1501:]) + "\n")
    with pytest.raises(ParseError) as err:
        read_tum(bad, warn=False)
    assert err.value.line == 1501 and read == [None]
    for _ in range(6):  # every thread's parser used again
        got = read_tum(good, warn=False)
        np.testing.assert_array_equal(got.positions, rows[:, 1:4])
    assert len(read) == 7 and all(r is not None and r[0] == 2000 for r in read[1:])


def test_a_file_whose_arrays_the_system_refuses_is_read_in_chunks(data, monkeypatch):
    """The arrays of a file read in pieces are reserved for as many rows as it could hold: where the
    system refuses that much (a large file on a small machine), the chunked reader reads it, with
    the same numbers."""
    path = Path(data.tum) / "fr2_desk_groundtruth.txt"
    expected = read_tum(path, warn=False)
    read = use_parser(monkeypatch, "pieces")

    def refuse(parts, capacity):
        raise MemoryError(f"cannot reserve {capacity} rows")

    monkeypatch.setattr(pieces, "_arrays", refuse)
    got = read_tum(path, warn=False)
    assert read == [None]  # the pieces gave up, the chunked reader read it
    for name in ("stamps", "positions", "quaternions", "lines"):
        np.testing.assert_array_equal(getattr(got, name), getattr(expected, name))
