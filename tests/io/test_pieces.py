"""A plain file parsed in pieces on threads (:mod:`lorisnb.io.parsing.pieces`): public readers only
(pyarrow's CSV reader, pandas' ``read_csv`` without pyarrow) giving ``float``'s numbers, the real
TUM files read as the chunked reader reads them, and a forked child that reads after its parent
did."""

from __future__ import annotations

import ast
import multiprocessing
from pathlib import Path

import numpy as np
import pytest
from helpers import use_parser

from lorisnb.errors import ParseError
from lorisnb.io import read_tum
from lorisnb.io.parsing import pieces, whole


def test_no_private_attribute_of_pandas_is_used():
    """The pieces are parsed through public APIs only (issue 47): no attribute of the module's code
    reaches into pandas' engine, its reader or ``load_buffer``, and pandas' private modules are
    not imported."""
    tree = ast.parse(Path(pieces.__file__).read_text())
    attributes = {node.attr for node in ast.walk(tree) if isinstance(node, ast.Attribute)}
    assert not attributes & {"_engine", "_reader", "load_buffer", "trim_after_read"}
    modules = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)} | {
        a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names
    }
    assert not any("._" in m or m.startswith("_") for m in modules - {"__future__"} if m)


@pytest.mark.parametrize("arrow", [True, False])
def test_a_piece_gives_the_numbers_of_float_or_none(monkeypatch, arrow):
    """A piece's columns by pyarrow (or by pandas' ``read_csv`` without pyarrow) are Python's
    ``float`` of each token, to the last bit, and None where a line is not plain: a short or long
    line, a word, an empty line (skipped by both readers unless told), C's ``nan(...)`` (which
    pyarrow reads and ``float`` refuses), a lone CR (a line end for pyarrow)."""
    if arrow and not pieces.pyarrow_installed():
        pytest.skip("pyarrow is not installed")
    monkeypatch.setattr(pieces, "pyarrow_installed", lambda: arrow)
    rng = np.random.default_rng(5)
    values = rng.normal(scale=1e3, size=(400, 3))
    tokens = [[repr(float(v)) for v in row] for row in values] + [["inf", "-inf", "1e-320"], ["+1", "5.", ".5"]]
    text = ("\n".join(" ".join(row) for row in tokens) + "\n").encode()
    got = pieces.piece_columns(text, " ", 3)
    assert got is not None
    expected = np.array([[float(t) for t in row] for row in tokens])
    np.testing.assert_array_equal(np.column_stack(got), expected)
    if arrow:  # a nan token is a number, as float() reads it (pandas' C parser refuses it: read in chunks)
        assert np.isnan(pieces.piece_columns(b"nan 1 -NaN\n", " ", 3)).tolist() == [[True], [False], [True]]
    assert np.signbit(got[1][-2]) and got[2][-2] == 1e-320
    for bad in (b"1 2 3\n4 5\n", b"1 2 3\n4 5 x\n", b"1 2 3 4\n", b"1 2 3\n\n4 5 6\n", b"nan(1) 2 3\n",
                b"1 2 3\r4 5 6\n", b"1 2 3\n4 5 6\x1c\n", b"1 2 3\n4 5 6\n\n", b"\n1 2 3\n"):  # fmt: skip
        assert pieces.piece_columns(bad, " ", 3) is None, bad
    assert pieces.piece_columns(b"1,2.5,3\n", ",", 3) is not None


@pytest.mark.parametrize("parser", ["pieces", "read_csv", "blocks"])
def test_the_real_tum_files_read_in_pieces_as_in_chunks(data, monkeypatch, parser):
    """Every TUM file of the real data (788 to about 20,000 poses), in pieces of 4 KB on 3 threads
    (or in one piece parsed in blocks of 4 KB on pyarrow's threads), gives the trajectory of the
    chunked reader (the byte scanner, the reference of every route)."""
    if parser == "blocks" and not pieces.pyarrow_installed():
        pytest.skip("pyarrow is not installed")
    files = sorted(Path(data.tum).glob("*.txt"))
    assert len(files) == 4
    for path in files:
        read = use_parser(monkeypatch, parser)
        got = read_tum(path, warn=False)
        rows = sum(1 for line in path.read_text().splitlines() if line.strip() and not line.startswith("#"))
        if parser == "blocks":  # one parse, in as many blocks as 4 KB of lines make
            assert len(read) == 1 and read[0] >= path.stat().st_size // 4096 - 1
        else:
            assert len(read) == 1 and read[0] is not None and read[0][0] == rows  # every row, read in pieces
        monkeypatch.setattr(whole, "WHOLE_MAX_BYTES", 0)
        ref = read_tum(path, warn=False)
        monkeypatch.undo()
        for name in ("stamps", "positions", "quaternions", "lines"):
            np.testing.assert_array_equal(getattr(got, name), getattr(ref, name))
        assert len(got) > 700


def _read_in_child(path: str, out) -> None:
    out.put(len(read_tum(path, warn=False)))


def _threads_in_child(out) -> None:
    out.put(pieces.arrow_threads())


@pytest.mark.parametrize("method", ["fork", "spawn"])
def test_pyarrow_threads_parse_only_outside_a_pool_of_processes(method):
    """A process that ``multiprocessing`` started (a pool's worker, beside the others using the
    cores) parses on its calling thread; one that it did not (a script, the command line, a Jupyter
    kernel) on pyarrow's threads, where pyarrow has more than one."""
    if not pieces.pyarrow_installed():
        pytest.skip("pyarrow is not installed")
    if method not in multiprocessing.get_all_start_methods():
        pytest.skip(f"no {method} on this system")
    import pyarrow as pa

    assert pieces.arrow_threads() == (pa.cpu_count() > 1)  # pytest's process: not started by multiprocessing
    ctx = multiprocessing.get_context(method)
    out = ctx.Queue()
    child = ctx.Process(target=_threads_in_child, args=(out,))
    child.start()
    try:
        assert out.get(timeout=60) is False
    finally:
        child.join(60)


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
