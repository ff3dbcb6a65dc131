"""The streamed reader: its C-parser path and its exact numpy path give the same rows, line
numbers and special lines, on every bundled file and on awkward synthetic ones, whatever the chunk
size; errors name the same line either way."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import write

from lorisnb.errors import ParseError
from lorisnb.io import read_openloris, read_tum
from lorisnb.io.parsing.chunks import read_rows
from lorisnb.tools.evaluation.runner import result_files

WIDTHS = (8, 9)


def _read(path, **kw):
    return read_rows(
        path, WIDTHS, what="x", numbers="numbers", bad_width=lambda t, k: f"{k} fields", specials=True, **kw
    )


def _same_read(path, reference: dict, other: dict) -> ParseError | None:
    """Read ``path`` two ways: the same rows, or the same error (returned)."""
    try:
        expected = _read(path, **reference)
    except ParseError as exc:
        with pytest.raises(ParseError) as got:
            _read(path, **other)
        assert (got.value.line, got.value.reason) == (exc.line, exc.reason)
        return exc
    _same(_read(path, **other), expected)
    return None


def _same(a, b):
    k = min(len(a.columns), len(b.columns))  # columns past the widest line are all NaN, if present
    assert np.array_equal(a.columns[:k], b.columns[:k], equal_nan=True)
    assert np.isnan(a.columns[k:]).all() and np.isnan(b.columns[k:]).all()
    assert np.array_equal(a.lines, b.lines)
    assert a.specials == b.specials
    assert np.array_equal(a.ntok, b.ntok)


@pytest.mark.parametrize("arrow", [True, False], ids=["pyarrow", "pandas"])
@pytest.mark.thorough
def test_fast_path_equals_exact_path_on_every_bundled_file(data, monkeypatch, arrow):
    """Every bundled file by the C parser (pyarrow's, or pandas' in a process that has imported
    pandas and has no pyarrow) gives the exact scanner's rows, lines and special lines."""
    from lorisnb.io.parsing import chunks, pieces

    if arrow and not pieces.pyarrow_installed():
        pytest.skip("pyarrow is not installed")
    monkeypatch.setattr(chunks, "pandas_loaded", lambda: not arrow)
    monkeypatch.setattr(chunks, "pyarrow_installed", lambda: arrow)
    monkeypatch.setattr(pieces, "pyarrow_installed", lambda: arrow)
    files = [p for p, _ in result_files([data.icra20])] + [data.groundtruth(s) for s in ("cafe", "market")]
    for path in files:
        fast, exact = _read(path, fast_min_bytes=0), _read(path, fast_min_bytes=1 << 40)
        assert fast.parsed_in_c == len(fast.lines)  # the bundled files all take the C parser
        assert exact.parsed_in_c == 0
        _same(fast, exact)


AWKWARD = (
    "scene: cafe\r\nframe: d400_color\r\n\r\n# comment\r\nseq: 1\r\n"
    "1.5 2 0 0 0 0 0 1\r\n  \r\n1.6 1.61 2 0 0 0 0 0 1\r\n\r\nseq: 2\r\n"
    "2.0 nan nan nan nan nan nan nan\r\n2.1 1 1 1 0 0 0 1\r\n   2.2 2 1 1 0 0 0 1\n"
)


@pytest.mark.parametrize("chunk_bytes", [16, 64, 1 << 20])
def test_awkward_file_reads_the_same_in_any_chunking(tmp_path, chunk_bytes):
    path = write(tmp_path, "a.txt", AWKWARD)
    whole = _read(path, fast_min_bytes=1 << 40)
    parts = _read(path, chunk_bytes=chunk_bytes, fast_min_bytes=0)
    _same(whole, parts)
    assert whole.lines.tolist() == [6, 8, 11, 12, 13]
    assert whole.specials[0] == (1, "scene: cafe") and whole.specials[-1] == (10, "seq: 2")
    f = read_openloris(path, warn=False)
    assert sorted(f.sequences) == [1, 2] and len(f.sequences[2]) == 2  # the NaN pose is skipped


@pytest.mark.parametrize("chunk_bytes", [16, 64, 1 << 20])
def test_split_equals_the_joined_columns(tmp_path, chunk_bytes):
    """Rows.split (row-major groups of tokens, copied once from the chunks' blocks) holds what
    Rows.columns holds, NaN where a line lacks tokens, and lets the blocks go."""
    path = write(tmp_path, "a.txt", AWKWARD)
    columns = _read(path, chunk_bytes=chunk_bytes, fast_min_bytes=0).columns
    rows = _read(path, chunk_bytes=chunk_bytes, fast_min_bytes=0)
    groups = [slice(0, 1), slice(1, 4), slice(4, 9)]
    for got, g in zip(rows.split(groups), groups, strict=True):
        want = np.full((columns.shape[1], g.stop - g.start), np.nan)
        have = columns[g].T
        want[:, : have.shape[1]] = have
        assert got.flags.c_contiguous and np.array_equal(got, want, equal_nan=True)
    assert rows.blocks == []


@pytest.mark.parametrize(
    "later",
    [
        "2 1 1 1 0 0 0 1 ",
        "2  1 1 1 0 0 0 1",
        "2\t1 1 1 0 0 0 1",
        " 2 1 1 1 0 0 0 1",
        "9 2 1 1 1 0 0 0 1",
        "2 1 1 1 0 0 1",
    ],
    ids=["trailing-space", "double-space", "tab", "leading-space", "nine-fields", "seven-fields"],
)
def test_single_spaced_lines_then_other_spacing_read_as_the_exact_scanner_does(tmp_path, later):
    """The C parser splits on single spaces when the first line is single-spaced; any other
    spacing further on must give the exact scanner's rows (or the same error), never other numbers."""
    text = "seq: 1\n" + "".join(f"1.{k} 0.5 0.25 0 0 0 0 1\n" for k in range(50)) + later + "\n1.9 0 0 0 0 0 0 1\n"
    path = write(tmp_path, "s.txt", text)
    error = _same_read(path, dict(fast_min_bytes=1 << 40), dict(fast_min_bytes=0))
    assert (error is not None) == (later == "2 1 1 1 0 0 1")  # seven fields: the one error


def test_large_file_takes_fast_path_and_keeps_exact_lines(tmp_path):
    n = 50_000
    rng = np.random.default_rng(1)
    t = 1_560_000_000 + np.arange(n) * 0.0625 + rng.integers(0, 1000, n) * 1e-9
    rows = [f"{s:.9f} {x:.6f} 0 0 0 0 0 1" for s, x in zip(t, rng.normal(size=n), strict=True)]
    rows.insert(20_000, "")  # a blank line in the middle
    rows.insert(40_000, "# a comment")
    path = write(tmp_path, "big.txt", "# header\n" + "\n".join(rows) + "\n")
    traj = read_tum(path)
    assert len(traj) == n
    tokens = [r.split()[0] for r in rows if r and not r.startswith("#")]
    assert np.array_equal(traj.stamps, np.array([float(x) for x in tokens]))  # correctly rounded, as float()
    assert traj.lines[0] == 2 and traj.lines[-1] == n + 3
    bad = rows.copy()
    bad[45_000] = "1.0 2.0 oops 0 0 0 0 1"
    write(tmp_path, "bad.txt", "\n".join(bad) + "\n")
    with pytest.raises(ParseError, match=r"bad.txt, line 45001: 'oops' is not a number"):
        read_tum(tmp_path / "bad.txt")


def test_binary_data_after_the_first_chunk_is_refused_where_it_appears(tmp_path):
    text = "".join(f"{i}.0 0 0 0 0 0 0 1\n" for i in range(20_000))
    path = tmp_path / "mixed.txt"
    path.write_bytes(text.encode() + b"\0\1\2" * 100_000)
    with pytest.raises(ParseError, match=r"line 20001: binary data"):
        read_tum(path)


@pytest.mark.parametrize("fault", ["bad-number", "nul", "overlong", "no-final-newline"])
def test_later_chunks_read_on_threads_name_the_same_lines(tmp_path, fault, monkeypatch):
    """Past the first chunk a regular file is read and parsed on threads, each range on its own;
    rows, line numbers and errors are those of reading it whole."""
    from lorisnb.io.parsing import ranges

    monkeypatch.setattr(ranges, "LINE_LIMIT", 3000)
    rows = [f"seq: {k // 5000 + 1}" if k % 5000 == 0 else f"{k}.5 0.25 1 2 0 0 0 1" for k in range(30_000)]
    body = "\n".join(rows) + "\n"
    if fault == "bad-number":
        body = body.replace("\n21000.5 0.25", "\n21000.5 x0.25")
    elif fault == "nul":
        body = body.replace("\n22000.5 0.25", "\n22000.5 \0.25")
    elif fault == "overlong":
        body = body.replace("\n23000.5 0.25", "\n23000.5 " + "1" * 20_000)  # no line end for 5 chunks
    else:
        body = body[:-1]
    path = tmp_path / "t.txt"
    path.write_bytes(body.encode())
    if fault == "overlong":  # as one chunk after another would: no line end within a chunk is not text
        with pytest.raises(ParseError, match=r"t.txt, line 23001: a line longer than 3000 bytes"):
            _read(path, chunk_bytes=4096)
        return
    error = _same_read(path, dict(chunk_bytes=1 << 30), dict(chunk_bytes=4096))
    expected = {"bad-number": 21001, "nul": 22001, "no-final-newline": None}[fault]
    assert (error.line if error is not None else None) == expected
    if error is None:
        assert _read(path).lines[-1] == 30_000


@pytest.mark.parametrize("kind", ["uniform", "short-guess", "mixed-widths", "mixed-first-chunk"])
def test_rows_copied_into_their_arrays_as_read_equal_a_whole_read(tmp_path, monkeypatch, kind):
    """A large OpenLORIS file is copied into its stamp, position and quaternion arrays chunk by
    chunk as it is parsed (RowSink): the same trajectories as reading it in one chunk, when the
    first chunk's lines are longer than the rest (the row guess is short: the arrays grow) and when
    lines of 8 and 9 numbers mix, later (read again the general way) or in the first chunk."""
    from lorisnb.io.parsing import chunks

    rng = np.random.default_rng(5)
    lines = ["scene: cafe", "frame: d400_color"]
    for k in range(12_000):
        if k % 4000 == 0:
            lines.append(f"seq: {k // 4000 + 1}")
        x = rng.normal(size=3)
        if kind == "short-guess" and k < 1500:
            lines.append(
                f"{1560000000 + k * 0.05:.9f} {x[0]:.15f} {x[1]:.15f} {x[2]:.15f} 0.0000000000 0 0 1.000000000"
            )
        elif (kind == "mixed-widths" and k == 9000) or (kind == "mixed-first-chunk" and k == 0):
            t = 1560000000 + k * 0.05  # a 9-number line: its output time as in the real files (days later)
            lines.append(f"{t:.3f} {t + 8.6e6:.3f} {x[0]:.4f} {x[1]:.4f} {x[2]:.4f} 0 0 0 1")
        else:
            lines.append(f"{1560000000 + k * 0.05:.3f} {x[0]:.4f} {x[1]:.4f} {x[2]:.4f} 0 0 0 1")
        if k == 5000:
            lines.append(lines[-1])  # a repeated pose: dropped, as the official tool does
    path = write(tmp_path, "cafe.txt", "\n".join(lines) + "\n")
    whole = read_openloris(path, warn=False)
    monkeypatch.setattr(chunks, "CHUNK_BYTES", 4096)
    parts = read_openloris(path, warn=False)
    assert sorted(parts.sequences) == [1, 2, 3] and parts.removed_repeats == whole.removed_repeats == {1: 0, 2: 1, 3: 0}
    for s, t in whole.sequences.items():
        u = parts.sequences[s]
        for name in ("stamps", "positions", "quaternions", "lines"):
            np.testing.assert_array_equal(getattr(u, name), getattr(t, name))
        assert u.positions.flags.c_contiguous and u.quaternions.flags.c_contiguous
        held = u.stamps.base.size if u.stamps.base is not None else u.stamps.size
        assert held < 3 * 12_001  # the stamps hold no array of every token of the file


def test_a_large_file_without_poses_reads_as_empty_sequences(tmp_path, monkeypatch):
    from lorisnb.io.parsing import chunks

    monkeypatch.setattr(chunks, "CHUNK_BYTES", 4096)
    path = write(tmp_path, "cafe.txt", "scene: cafe\nseq: 1\n" + "# a comment, no pose\n" * 20_000)
    assert {k: len(t) for k, t in read_openloris(path, warn=False).sequences.items()} == {1: 0}


@pytest.mark.parametrize(
    "text",
    [
        b" 1  2   3\n  4 5\n",
        b"1 2\n\n   \n 7 8 \n",
        b"   ",
        b"\n \n",
        b"1\t  2\r\n  3  4\r\n",
        b"1 2 \n3  4  \r\n5 6   ",
        b" \r\n\n  x \n",
        b"",
    ],
)
def test_single_spaced_equals_collapsing_runs_then_stripping_line_starts_and_ends(text):
    """The numpy masks that make a chunk's spacing single give the text regular expressions give
    (runs of spaces made one, then the spaces a line starts or ends with dropped)."""
    import re

    from lorisnb.io.parsing.chunks import single_spaced

    one = re.sub(rb"(?m)^ +", b"", re.sub(rb"  +", b" ", text))
    assert single_spaced(text) == re.sub(rb"(?m) +(?=\r?$)", b"", one)


def test_right_aligned_lifelong_file_reads_the_numbers_float_reads(tmp_path, monkeypatch):
    """A right-aligned file (each field padded by runs of spaces, a space before each line) of
    many chunks, read on threads by the C parser: every number equals ``float`` of its token."""
    from lorisnb.io.parsing import chunks

    rng = np.random.default_rng(3)
    n = 20_000
    stamps = 1_560_000_000 + np.arange(n) * 0.0625
    pos = rng.normal(0, 20, (n, 3))
    quat = rng.normal(size=(n, 4))
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    lines = [f" {t:20.9f} {x:9.4f} {y:9.4f} {z:9.4f} {a:10.7f} {b:10.7f} {c:10.7f} {d:10.7f}\n"
             for t, (x, y, z), (a, b, c, d) in zip(stamps, pos, quat, strict=True)]  # fmt: skip
    path = write(tmp_path, "market.txt", "scene: market\nframe: base_link\nseq: 1\n" + "".join(lines))
    monkeypatch.setattr(chunks, "CHUNK_BYTES", 64 << 10)
    seq = read_openloris(path, warn=False).sequences[1]
    expected = np.array([[float(tok) for tok in line.split()] for line in lines])
    np.testing.assert_array_equal(seq.stamps, expected[:, 0])
    np.testing.assert_array_equal(seq.positions, expected[:, 1:4])
    np.testing.assert_array_equal(seq.quaternions, expected[:, 4:8])


@pytest.mark.parametrize("later", ["tabs", "spaces", "tab-run", "leading-tab"])
def test_tab_separated_lines_take_the_c_parser_and_read_as_the_exact_scanner(tmp_path, later):
    """Lines with one tab between fields (a TSV file) are parsed by the C parser, chunk by chunk
    (they were all read by the exact scanner: a million poses in 5.9 s against 0.5 s with spaces);
    a chunk whose lines are spaced otherwise further on reads as the exact scanner reads it."""
    rng = np.random.default_rng(7)
    rows = ["\t".join(f"{v:.9f}" for v in (1_560_000_000 + k * 0.05, *rng.normal(size=7))) for k in range(6000)]
    other = {"tabs": rows[4000], "spaces": rows[4000].replace("\t", " "), "tab-run": rows[4000].replace("\t", "\t\t", 1),
             "leading-tab": "\t" + rows[4000]}[later]  # fmt: skip
    rows[4000] = other
    path = write(tmp_path, "t.txt", "# stamp\ttx\tty\ttz\tqx\tqy\tqz\tqw\n" + "\n".join(rows) + "\n")
    fast = _read(path, fast_min_bytes=0, chunk_bytes=64 << 10)
    _same(fast, _read(path, fast_min_bytes=1 << 40, chunk_bytes=64 << 10))
    assert fast.parsed_in_c >= (len(rows) if later == "tabs" else len(rows) - 1000)
    np.testing.assert_array_equal(fast.columns[1], [float(r.split()[1]) for r in rows])


#: Files as writers lay them out, each read by the C parser in every chunk (each went to the exact
#: byte scanner, 10-17x the time: a million TUM poses 5.5 s with a space ending each line, 5.9 s with
#: tabs; 300,000 with a blank line every 100 lines 2.2 s, with a tab and a space between fields 1.45 s).
LAYOUTS = {
    "plain": lambda r, k: r + "\n",
    "trailing-space": lambda r, k: r + " \n",
    "crlf-trailing-spaces": lambda r, k: r + "  \r\n",
    "blank-lines": lambda r, k: ("\n" if k % 100 == 0 else "") + r + "\n",
    "tabs": lambda r, k: r.replace(" ", "\t") + "\n",
    "tab-and-space": lambda r, k: r.replace(" ", "\t ") + "\n",
    "right-aligned": lambda r, k: " " + r.replace(" ", "   ") + "\n",
}


@pytest.mark.parametrize("arrow", [True, False], ids=["pyarrow", "pandas"])
@pytest.mark.parametrize("layout", LAYOUTS)
def test_common_layouts_take_the_c_parser_and_read_as_the_exact_scanner(tmp_path, monkeypatch, layout, arrow):
    """Every chunk of a file laid out as writers lay them out is parsed by the C parser, pyarrow's
    (its spacing made single first where needed) or pandas' (in a process without pyarrow): the
    exact scanner's rows and lines."""
    from lorisnb.io.parsing import chunks, pieces

    if arrow and not pieces.pyarrow_installed():
        pytest.skip("pyarrow is not installed")
    monkeypatch.setattr(chunks, "pandas_loaded", lambda: not arrow)
    monkeypatch.setattr(chunks, "pyarrow_installed", lambda: arrow)
    monkeypatch.setattr(pieces, "pyarrow_installed", lambda: arrow)
    rng = np.random.default_rng(8)
    rows = [" ".join(f"{v:.9f}" for v in (1_560_000_000 + k * 0.05, *rng.normal(size=7))) for k in range(6000)]
    path = write(
        tmp_path, "t.txt", "# stamp tx ty tz qx qy qz qw\n" + "".join(LAYOUTS[layout](r, k) for k, r in enumerate(rows))
    )
    fast = _read(path, fast_min_bytes=0, chunk_bytes=64 << 10)
    _same(fast, _read(path, fast_min_bytes=1 << 40, chunk_bytes=64 << 10))
    assert fast.parsed_in_c == len(rows)
    np.testing.assert_array_equal(fast.columns[7], [float(r.split()[7]) for r in rows])


#: Where a file's special lines (comments, ``key: value`` lines, blank lines) lie: the C parser's
#: layout scans only the lines up to the last of them where no blank line follows (a result file's
#: header); each placement reads as the exact scanner reads it, in chunks of every size.
PLACEMENTS = {
    "header": lambda rows: "scene: cafe\nframe: d400_color\nseq: 1\n" + "".join(r + "\n" for r in rows),
    "comment-in-the-middle": lambda rows: "".join(r + "\n" + ("# halfway\n" if k == 700 else "") for k, r in enumerate(rows)),
    "seq-at-the-end": lambda rows: "seq: 1\n" + "".join(r + "\n" for r in rows) + "seq: 2\n" + rows[0] + "\n",
    "blank-after-the-header": lambda rows: "seq: 1\n" + "".join(r + "\n" + ("\n" if k == 900 else "") for k, r in enumerate(rows)),
    "blank-right-after-it": lambda rows: "seq: 1\n\n" + "".join(r + "\n" for r in rows),
    "crlf": lambda rows: "scene: cafe\r\nseq: 1\r\n" + "".join(r + "\r\n" for r in rows),
    "crlf-blank-after": lambda rows: "seq: 1\r\n" + "".join(r + ("\r\n\r\n" if k == 50 else "\r\n") for k, r in enumerate(rows)),
    "only-specials-then-rows": lambda rows: "".join(f"# comment {k}\n" for k in range(400)) + "".join(r + "\n" for r in rows),
}  # fmt: skip


@pytest.mark.parametrize("chunk_bytes", [4 << 10, 1 << 20])
@pytest.mark.parametrize("placement", PLACEMENTS)
def test_special_lines_anywhere_read_as_the_exact_scanner(tmp_path, placement, chunk_bytes):
    rng = np.random.default_rng(9)
    rows = [" ".join(f"{v:.9f}" for v in (1_560_000_000 + k * 0.05, *rng.normal(size=7))) for k in range(1500)]
    path = write(tmp_path, "t.txt", PLACEMENTS[placement](rows))
    fast = _read(path, fast_min_bytes=0, chunk_bytes=chunk_bytes)
    _same(fast, _read(path, fast_min_bytes=1 << 40, chunk_bytes=chunk_bytes))
    assert len(fast.lines) >= len(rows)
    assert fast.parsed_in_c == len(fast.lines)  # every chunk by the C parser
