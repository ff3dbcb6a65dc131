"""The one-call reading of plain files (:mod:`lorisnb.io.parsing.whole`): the same trajectories, line
numbers and errors as the chunked reader on every kind of file, taken exactly when the file is
plain; and the rotation blocks of matrix files converted exactly as scipy converts them."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from helpers import use_parser, write

from lorisnb.core.trajectory.poses import written_blocks
from lorisnb.errors import ParseError
from lorisnb.io import read_euroc, read_kitti, read_tum
from lorisnb.io.parsing import pieces, whole

N = 3000
LIMIT = whole.WHOLE_MAX_BYTES


def _tum_lines(rng, n=N):
    stamps = 1.56e9 + np.cumsum(rng.uniform(0.01, 0.05, n))
    pos = rng.normal(0, 20, (n, 3))
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    fmt = ["%.9f", "%.17g", "%.4f", "%r"]
    return [" ".join(fmt[(k + j) % 4] % float(v) for j, v in enumerate([stamps[k], *pos[k], *q[k]])) for k in range(n)]


def _variants():
    rng = np.random.default_rng(7)
    body = _tum_lines(rng)
    head = "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n"
    yield "plain", "\n".join(body) + "\n", True
    yield "header", head + "\n".join(body) + "\n", True
    yield "crlf", "\r\n".join(body) + "\r\n", True
    yield "no final newline", "\n".join(body), True
    yield "commas", "\n".join(b.replace(" ", ",") for b in body) + "\n", True
    yield "blank line at the end", "\n".join(body) + "\n\n", False
    yield "comment further on", "\n".join(body[:2000] + ["# pause"] + body[2000:]) + "\n", False
    yield "blank line further on", "\n".join(body[:2000] + [""] + body[2000:]) + "\n", False
    yield "a tab further on", "\n".join(body[:2500] + [body[2500].replace(" ", "\t", 1)] + body[2501:]) + "\n", False
    yield "runs of spaces", "\n".join(b.replace(" ", "  ") for b in body) + "\n", False
    yield "nan pose", "\n".join(body[:100] + [body[100].split()[0] + " nan" * 7] + body[101:]) + "\n", False
    yield "bad number", "\n".join(body[:2999] + [body[2999].replace(" ", " x", 1)]) + "\n", False
    yield "short line", "\n".join(body[:1500] + [" ".join(body[1500].split()[:5])] + body[1501:]) + "\n", False
    yield "cr only", "\r".join(body) + "\r", False
    # a lone CR (pandas ends a line there) whose extra row a line of spaces or a blank line makes up
    # for: read with a pose dropped or a line number off, once; now the line is named everywhere
    glued = body[:299] + [body[299] + "\r" + body[300]] + body[301:]
    yield "lone cr, a line of spaces", "\n".join(glued[:700] + ["   "] + glued[700:]) + "\n", False
    yield "lone cr, blank lines", "\n".join([""] + glued[:599] + [""] + glued[599:]) + "\n", False
    yield "a byte float refuses", "\n".join(body[:50] + [body[50] + "\x1c"] + body[51:]) + "\n", False
    short_end = body[:100] + ["x" + body[100]] + body[101:-1] + [" ".join(body[-1].split()[:7])]
    yield "bad number, then a short line", "\n".join(short_end) + "\n", False
    yield "bom", "\ufeff" + "\n".join(body) + "\n", False


def _read_both(monkeypatch, read, path):
    """``read(path)`` in one call where the file allows and with the chunked reader: both results
    (or both errors), and whether the one call was taken."""
    taken = []
    real = whole.read_whole

    def spy(*a, **k):
        got = real(*a, **k)
        taken.append(got is not None)
        return got

    monkeypatch.setattr(whole, "read_whole", spy)
    monkeypatch.setattr("lorisnb.io.parsing.chunks.read_whole", spy)
    out = []
    for limit in (LIMIT, 0):
        monkeypatch.setattr(whole, "WHOLE_MAX_BYTES", limit)
        try:
            out.append(read(path))
        except ParseError as exc:
            out.append((exc.line, exc.reason))
    return out, taken[0]


def _same(a, b):
    if isinstance(a, tuple) or isinstance(b, tuple):
        assert a == b
        return
    for name in ("stamps", "positions", "quaternions", "lines"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    kept = written_blocks(a)  # a KITTI file's blocks as written, however they are held
    assert (kept is None) == (written_blocks(b) is None)
    if kept is not None:
        np.testing.assert_array_equal(kept, written_blocks(b))
    assert a.positions.flags.c_contiguous and a.quaternions.flags.c_contiguous
    assert a.stamps.flags.writeable and a.positions.flags.writeable


@pytest.mark.parametrize("parser", ["pandas", "blocks", "numpy", "pieces", "read_csv"])
@pytest.mark.parametrize("name,text,plain", list(_variants()), ids=[v[0] for v in _variants()])
@pytest.mark.thorough
def test_tum_file_reads_the_same_in_one_call_or_in_chunks(tmp_path, monkeypatch, name, text, plain, parser):
    """Every one-call parser: the piece parser in one piece, numpy's, and pieces on threads, by
    pyarrow or by pandas' ``read_csv`` (see :func:`helpers.use_parser`)."""
    ranged = use_parser(monkeypatch, parser)
    path = tmp_path / "traj.txt"
    path.write_bytes(text.encode())
    (one, chunked), taken = _read_both(monkeypatch, lambda p: read_tum(p, warn=False), path)
    reads_nan = parser == "numpy" or (parser in ("pandas", "blocks", "pieces") and pieces.pyarrow_installed())
    assert taken == (plain or (reads_nan and name == "nan pose"))  # numpy and pyarrow read nan; pandas refuses it
    _same(one, chunked)
    if name == "bad number":
        assert one[0] == N  # the line, counted from the file's first
    lone = "a carriage return (CR) without a line feed"  # named: it read as "has 16 fields"
    expected = {"lone cr, a line of spaces": (300, lone), "lone cr, blank lines": (301, lone), "cr only": (1, lone),
                "a byte float refuses": (51, "is not a number"), "bad number, then a short line": (101, "not a number")}  # fmt: skip
    if name in expected:  # the first problem in file order, on every path
        assert one[0] == expected[name][0] and expected[name][1] in one[1]
    if name == "header":
        assert one.lines[0] == 3 and one.lines[-1] == N + 2
    if parser in ("pieces", "read_csv") and plain:  # read on pieces, not by another path
        assert len(ranged) == 1 and ranged[0] is not None and ranged[0][0] == N
    if parser == "blocks" and plain and pieces.pyarrow_installed():  # the one piece in blocks on pyarrow's threads
        assert ranged and ranged[0] > 1


@pytest.mark.parametrize("parser", ["pandas", "blocks", "numpy", "pieces", "read_csv"])
def test_euroc_and_kitti_read_the_same_in_one_call_or_in_chunks(tmp_path, monkeypatch, parser, rotation_route):
    ranged = use_parser(monkeypatch, parser)
    rng = np.random.default_rng(3)
    n = 2000
    stamps = 1403636579758555392 + np.arange(n) * 5_000_000
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    pos = rng.normal(0, 5, (n, 3))
    rows = [
        ",".join([str(s), *(repr(float(v)) for v in (*p, *w)), "0,0,0"]) for s, p, w in zip(stamps, pos, q, strict=True)
    ]
    path = write(tmp_path, "data.csv", "#timestamp,p_x,p_y,p_z,q_w,q_x,q_y,q_z,v_x,v_y,v_z\n" + "\n".join(rows) + "\n")
    (one, chunked), taken = _read_both(monkeypatch, lambda p: read_euroc(p, warn=False), path)
    assert taken
    _same(one, chunked)
    np.testing.assert_array_equal(one.stamps, stamps / 1e9)
    np.testing.assert_array_equal(one.quaternions, q[:, [1, 2, 3, 0]])
    on_pieces = parser in ("pieces", "read_csv")
    if parser == "blocks" and pieces.pyarrow_installed():  # in one call and in chunks: in blocks on pyarrow's threads
        assert len(ranged) == 2 and min(ranged) > 1
        ranged.clear()
    assert [r[0] for r in ranged] == ([n] if on_pieces else [])  # EuRoC's one call was on pieces

    from scipy.spatial.transform import Rotation

    mats = np.concatenate([Rotation.from_quat(q).as_matrix(), pos[:, :, None]], axis=2).reshape(n, 12)
    kitti = write(tmp_path, "poses.txt", "\n".join(" ".join(f"{v:.6e}" for v in m) for m in mats) + "\n")
    (one, chunked), taken = _read_both(monkeypatch, read_kitti, kitti)
    assert taken
    _same(one, chunked)
    if parser == "blocks" and pieces.pyarrow_installed():  # KITTI's too, quaternions block by block
        assert len(ranged) == 2 and min(ranged) > 1
        ranged.clear()
    assert [r[0] for r in ranged] == ([n, n] if on_pieces else [])  # KITTI's too, quaternions on the threads
    printed = np.loadtxt(kitti).reshape(n, 3, 4)
    np.testing.assert_allclose(one.quaternions, Rotation.from_matrix(printed[:, :, :3]).as_quat(), rtol=0, atol=5e-15)
    np.testing.assert_array_equal(written_blocks(one), printed[:, :, :3])  # the numbers as printed, each
    np.testing.assert_array_equal(written_blocks(one.subset(np.arange(1, n, 3))), printed[1::3, :, :3])


@pytest.mark.parametrize("parser", ["pandas", "blocks", "numpy", "pieces", "read_csv"])
def test_kitti_block_not_a_rotation_named_by_its_line_on_every_path(tmp_path, monkeypatch, parser, rotation_route):
    """The quaternions of a KITTI file are computed on each piece as it is read: a block that is
    no rotation, in a late piece, is still named by its line in the file."""
    ranged = use_parser(monkeypatch, parser)
    rows = ["1 0 0 %d 0 1 0 0 0 0 1 0" % k for k in range(3000)]
    rows[2345] = "1 0 0 1 0 1 0 0 0 0 1.01 0"  # a scaled block
    path = write(tmp_path, "poses.txt", "# KITTI\n" + "\n".join(rows) + "\n")
    (one, chunked), taken = _read_both(monkeypatch, read_kitti, path)
    assert taken and one == chunked and one[0] == 2347 and "not a rotation" in one[1]
    blocks = parser == "blocks" and pieces.pyarrow_installed()  # the block after the first, too
    assert len(ranged) == (1 if parser in ("pieces", "read_csv") else 2 if blocks else 0)
    assert not blocks or min(ranged) > 1


@pytest.mark.parametrize("parser", ["pieces", "read_csv"])
@pytest.mark.parametrize("which", ["first", "later"])
def test_pieces_a_failing_piece_neither_hangs_nor_passes(tmp_path, monkeypatch, parser, which):
    """An error on one piece's thread that is not a parse error (say the disk), in the first piece
    or a later one, reaches the caller once the other threads have stopped (none reads the file
    after the reader closes it); the next read works."""
    import os
    import threading
    import time

    from lorisnb.io.parsing import pieces

    use_parser(monkeypatch, parser)
    path = tmp_path / "traj.txt"
    path.write_text("\n".join(_tum_lines(np.random.default_rng(1))) + "\n")
    real, calls, closed = pieces._read, [], []

    reading = threading.Event()

    def flaky(fd, lo, hi):
        calls.append(lo)
        if (lo == 0) == (which == "first"):
            reading.wait(5)  # fails while another thread reads a piece
            raise OSError("the disk went away")
        reading.set()
        time.sleep(0.1)  # a slow read, still going when the failing piece fails
        try:
            os.fstat(fd)
        except OSError:
            closed.append(lo)
        return real(fd, lo, hi)

    monkeypatch.setattr(pieces, "_read", flaky)
    with pytest.raises(OSError, match="disk went away"):
        read_tum(path, warn=False)
    time.sleep(0.2)
    assert calls and not closed
    monkeypatch.setattr(pieces, "_read", real)
    assert len(read_tum(path, warn=False)) == N


def _polar_quaternions(m: np.ndarray) -> np.ndarray:
    """The oracle: quaternions of the rotations nearest to blocks ``m`` (the orthogonal polar
    factor), by Newton's iteration ``X <- (X + X^-T) / 2`` in extended precision (np.longdouble),
    then Markley's branch in extended precision; an independent route to what SVD projection
    computes."""
    x = m.astype(np.longdouble)
    for _ in range(10):
        a, b, c = x[:, 0], x[:, 1], x[:, 2]
        cof = np.stack([np.cross(b, c), np.cross(c, a), np.cross(a, b)], axis=1)  # the cofactor matrix
        x = (x + cof / np.einsum("ni,ni->n", a, cof[:, 0])[:, None, None]) / 2
    tr = x[:, 0, 0] + x[:, 1, 1] + x[:, 2, 2]
    q = np.stack(
        [
            [1 + 2 * x[:, 0, 0] - tr, x[:, 0, 1] + x[:, 1, 0], x[:, 0, 2] + x[:, 2, 0], x[:, 2, 1] - x[:, 1, 2]],
            [x[:, 0, 1] + x[:, 1, 0], 1 + 2 * x[:, 1, 1] - tr, x[:, 1, 2] + x[:, 2, 1], x[:, 0, 2] - x[:, 2, 0]],
            [x[:, 0, 2] + x[:, 2, 0], x[:, 1, 2] + x[:, 2, 1], 1 + 2 * x[:, 2, 2] - tr, x[:, 1, 0] - x[:, 0, 1]],
            [x[:, 2, 1] - x[:, 1, 2], x[:, 0, 2] - x[:, 2, 0], x[:, 1, 0] - x[:, 0, 1], 1 + tr],
        ]
    )  # (branch, component, n)
    branch = np.argmax(np.stack([x[:, 0, 0], x[:, 1, 1], x[:, 2, 2], tr]), axis=0)
    q = q[branch, :, np.arange(len(x))]
    return q / np.sqrt((q * q).sum(axis=1))[:, None]


def test_rotation_blocks_nearest_rotation_and_scipy(rotation_route):
    """Blocks that are rotations within 1e-12 get scipy's ``Rotation.from_matrix`` quaternions to
    the last bit (Markley's method, in every branch). Other blocks (6-digit KITTI files, noise up
    to the readers' tolerance) get the quaternion of the nearest rotation: within 5e-16 of an
    extended-precision polar decomposition, and of scipy's within 5e-15 (its SVD route is ~3e-15
    from the oracle), with scipy's sign but for exact ties of the two largest components. Planar
    6-digit blocks, which scipy does not project (their rows are orthogonal, their norms within
    its 1e-5), get the nearest rotation too: scipy is ~1e-8 off there. The distance from a
    rotation is the larger of max |R R^T - I| and |det R - 1|."""
    from scipy.spatial.transform import Rotation

    from lorisnb.core.trajectory.rotations import rotation_blocks

    rng = np.random.default_rng(11)
    exact = np.concatenate(
        [
            Rotation.random(20_000, random_state=1).as_matrix(),
            Rotation.from_euler("xyz", [[0, 0, 10], [179, 0, 0], [0, 179, 0], [0, 0, 179]], degrees=True).as_matrix(),
        ]
    )
    q, _ = rotation_blocks(exact)
    np.testing.assert_array_equal(q, Rotation.from_matrix(exact).as_quat())
    near = exact + rng.normal(0, 1e-14, exact.shape)
    np.testing.assert_array_equal(rotation_blocks(near)[0], Rotation.from_matrix(near).as_quat())
    rounded6 = np.round(exact, 6)
    for m, largest in (
        (rounded6, 3e-6),
        (np.round(exact, 3), 3e-3),
        (exact + rng.normal(0, 1e-9, exact.shape), 1e-8),
        (exact + rng.normal(0, 2e-4, exact.shape), 2e-3),
    ):
        q, off = rotation_blocks(m)
        assert 0 < off.max() < largest
        truth = _polar_quaternions(m)
        aligned = q * np.sign((q * truth).sum(axis=1))[:, None]
        assert np.abs(aligned - truth).max() < 5e-16
        theirs = Rotation.from_matrix(m).as_quat()
        same_sign = (q * theirs).sum(axis=1) > 0
        top2 = np.sort(np.abs(q), axis=1)[:, -2:]
        assert (same_sign | (top2[:, 1] - top2[:, 0] < 1e-12)).all()  # flipped only at ties
        planar = (np.abs(m) == 0).sum(axis=(1, 2)) >= 4  # the Euler blocks about one axis
        scipy_err = np.abs(theirs * np.sign((theirs * truth).sum(axis=1))[:, None] - truth).max(axis=1)
        assert scipy_err[~planar].max() < 5e-15
        np.testing.assert_allclose(q[same_sign & ~planar], theirs[same_sign & ~planar], rtol=0, atol=5e-15)
        if m is rounded6:  # scipy's slip on planar blocks, which this does not share
            assert scipy_err[planar].max() > 1e-9
        gram = np.abs(m @ np.swapaxes(m, 1, 2) - np.eye(3)).max(axis=(1, 2))
        np.testing.assert_allclose(off, np.maximum(gram, np.abs(np.linalg.det(m) - 1)), rtol=1e-6, atol=1e-15)
    import lorisnb.core.trajectory.blocks as blocks

    q, off = rotation_blocks(m)  # each block's numbers do not depend on the blocks run with it
    run, blocks.BLOCK_ROWS = blocks.BLOCK_ROWS, 1000
    try:
        np.testing.assert_array_equal(rotation_blocks(m)[0], q)
        np.testing.assert_array_equal(rotation_blocks(m[::-1])[0], q[::-1])
    finally:
        blocks.BLOCK_ROWS = run
    tilted = exact[:3] * 1.01
    assert (rotation_blocks(tilted)[1] > 0.02).all()
    assert rotation_blocks(np.zeros((0, 3, 3)))[0].shape == (0, 4)


def test_rotation_entries_of_a_files_columns_as_rotation_blocks(rotation_route):
    """Blocks given entry by entry (a parser's separate columns: contiguous, strided, float32)
    get the quaternions and distances of the same blocks as one (N, 3, 3) array, to the last bit."""
    from scipy.spatial.transform import Rotation

    from lorisnb.core.trajectory.rotations import rotation_blocks, rotation_entries

    m = np.round(Rotation.random(40_000, random_state=3).as_matrix(), 6)
    m[::7] = Rotation.random(len(m[::7]), random_state=4).as_matrix()  # exact rotations mixed in
    q, off = rotation_blocks(m)
    columns = [[np.ascontiguousarray(m[:, i, j]) for j in range(3)] for i in range(3)]
    qc, offc = rotation_entries(columns)
    np.testing.assert_array_equal(qc, q)
    np.testing.assert_array_equal(offc, off)
    columns[1][2] = np.repeat(m[:, 1, 2], 2)[::2]  # a strided column
    np.testing.assert_array_equal(rotation_entries(columns)[0], q)
    m32 = m.astype(np.float32)
    np.testing.assert_array_equal(
        rotation_entries([[m32[:, i, j] for j in range(3)] for i in range(3)])[0], rotation_blocks(m32)[0]
    )


def test_power_steps_bring_the_error_below_the_last_bit():
    """The power steps a block ``off`` from a rotation takes: the fewest ``s`` (1 to 12) with
    ``(off / 2) ** (s + 1)`` below 2**-56, by the closed form ``ceil(56 ln 2 / -ln(off / 2)) - 1``
    (12 at 0.25 or more, or NaN); the same counts as the thresholds the runs compare against."""
    from lorisnb.core.trajectory.rotations import power_steps

    rng = np.random.default_rng(2)
    off = np.concatenate(
        [10 ** rng.uniform(-17, 0, 100_000), [1e-300, 1e-12, 1e-6, 1e-3, 0.2499, 0.25, 0.5, np.nan, np.inf]]
    )
    with np.errstate(divide="ignore", invalid="ignore"):
        closed = np.ceil(56 * np.log(2) / -np.log(off / 2)) - 1
    expected = np.where((off > 0) & (off < 0.25), closed, 12).clip(1, 12)
    np.testing.assert_array_equal(power_steps(off), expected)
    assert list(power_steps(np.array([1e-6, 1e-3]))) == [2, 5]  # 6-digit blocks, the readers' tolerance
    s = power_steps(off).astype(float)
    fine = (off > 0) & (s < 12)  # 12 at most: blocks that far are refused anyway
    assert ((off[fine] / 2) ** (s[fine] + 1) < 2.0**-56).all()
    assert ((s[fine] == 1) | ((off[fine] / 2) ** s[fine] >= 2.0**-56)).all()


def test_rotation_blocks_the_same_for_any_memory_order_threads_and_mixed_runs(rotation_route):
    """KITTI's one-call read hands the parser's column-major numbers to the rotation step and runs
    it on threads: every block's quaternion and distance are those of the block alone (exact,
    6- and 3-digit, noisy and non-finite blocks mixed in one run)."""
    from scipy.spatial.transform import Rotation

    import lorisnb.core.trajectory.blocks as blocks
    from lorisnb.core.trajectory.rotations import rotation_blocks

    rng = np.random.default_rng(5)
    r = Rotation.random(40_000, random_state=7).as_matrix()
    m = np.concatenate([r[:10_000], np.round(r[10_000:20_000], 6), np.round(r[20_000:30_000], 3), r[30_000:] + 1e-4])
    m = m[rng.permutation(len(m))]
    m[5], m[7] = np.nan, m[7] * 1e300
    with np.errstate(all="ignore"):
        q, off = rotation_blocks(m)
        column_major = np.asfortranarray(np.concatenate([m, np.zeros((len(m), 3, 1))], axis=2).reshape(-1, 12))
        view = column_major.reshape(-1, 3, 4)[:, :, :3]  # as read_kitti sees pandas' block: no copy
        assert np.shares_memory(view, column_major)
        with blocks.threads(2):
            qf, offf = rotation_blocks(view)
        one = [rotation_blocks(m[i : i + 1]) for i in (0, 1, 2, 9, 10_001, 39_999)]
    np.testing.assert_array_equal(qf, q)
    np.testing.assert_array_equal(offf, off)
    for i, (qi, oi) in zip((0, 1, 2, 9, 10_001, 39_999), one, strict=True):
        np.testing.assert_array_equal(qi[0], q[i])
        np.testing.assert_array_equal(oi[0], off[i])
    assert np.isnan(q[5]).all() and not off[7] <= 1e-3
    # ties between the diagonal and the trace (90 and 180 degree turns): Markley's branch is the
    # first largest, as scipy's np.argmax picks it, to the last bit
    turns = Rotation.from_euler("xyz", list(itertools.product([0, 45, 90, 180, -90], repeat=3)), degrees=True)
    blocks_ = turns.as_matrix()
    np.testing.assert_array_equal(rotation_blocks(blocks_)[0], Rotation.from_matrix(blocks_).as_quat())
