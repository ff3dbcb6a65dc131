"""Probes of the file readers on unusual inputs: every reading path (numpy, pandas in one call,
pandas on pieces, chunks) and pipes give the same numbers and the same errors."""

from __future__ import annotations

import os
import threading
import warnings

import numpy as np
import pytest
from helpers import PARSERS, use_parser

from lorisnb.errors import ParseError
from lorisnb.io import read_euroc, read_kitti, read_openloris, read_times, read_trajectory, read_tum

ROWS = 3000


def _tum_text(n: int = ROWS) -> bytes:
    """``n`` TUM lines (about 90 KB per 1000 lines: more than a pipe's 64 KB buffer)."""
    rng = np.random.default_rng(11)
    stamps = 1.56e9 + np.cumsum(rng.uniform(0.01, 0.05, n))
    pos = rng.normal(0, 20, (n, 3))
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    rows = np.column_stack([stamps, pos, q])
    return "".join(" ".join(repr(float(v)) for v in row) + "\n" for row in rows).encode()


def _piped(data: bytes) -> tuple[str, int]:
    """A path to a pipe fed ``data`` on a thread (as the shell's ``<(cat file)`` gives) and the
    pipe's reading end (close it after)."""
    r, w = os.pipe()

    def feed() -> None:
        try:
            for i in range(0, len(data), 1 << 16):
                os.write(w, data[i : i + (1 << 16)])
        except BrokenPipeError:
            pass
        finally:
            os.close(w)

    threading.Thread(target=feed, daemon=True).start()
    return f"/proc/self/fd/{r}", r


def _euroc_text(tum: bytes) -> bytes:
    lines = ["#timestamp [ns],p_x,p_y,p_z,q_w,q_x,q_y,q_z"]
    for line in tum.decode().splitlines():
        t, x, y, z, qx, qy, qz, qw = line.split()
        lines.append(",".join([str(round(float(t) * 1e6) * 1000), x, y, z, qw, qx, qy, qz]))
    return ("\n".join(lines) + "\n").encode()


@pytest.mark.skipif(not os.path.isdir("/proc/self/fd"), reason="needs /proc/self/fd")
@pytest.mark.parametrize("reader", ["tum", "trajectory", "euroc", "kitti_times"])
def test_a_pipe_is_read_once_whole(tmp_path, reader):
    """A pipe (``<(cat file)``, a FIFO) has no position and gives its bytes once: it was refused
    with an OSError traceback ("Illegal seek") or its first 64 KB were taken by a look at the
    format and the rest read from mid-line. Now it reads as the file does."""
    tum = _tum_text()
    data = {"tum": tum, "trajectory": tum, "euroc": _euroc_text(tum), "kitti_times": tum[:0]}[reader]
    if reader == "kitti_times":
        data = "".join(f"{k * 0.1:.6f}\n" for k in range(ROWS)).encode()
    read = {"tum": read_tum, "trajectory": read_trajectory, "euroc": read_euroc, "kitti_times": read_times}[reader]
    plain = tmp_path / "file.txt"
    plain.write_bytes(data)
    path, fd = _piped(data)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            got, want = read(path), read(plain)
    finally:
        os.close(fd)
    if reader == "kitti_times":
        np.testing.assert_array_equal(got, want)
        return
    assert len(got.stamps) == ROWS
    for name in ("stamps", "positions", "quaternions", "lines"):
        np.testing.assert_array_equal(getattr(got, name), getattr(want, name))


@pytest.mark.skipif(not os.path.isdir("/proc/self/fd"), reason="needs /proc/self/fd")
def test_an_openloris_pipe_out_of_order_is_read_once(tmp_path):
    """Stamps out of order made the OpenLORIS reader read the file's digits again: from a pipe,
    nothing (or, a FIFO, a wait for ever). Now a pipe's out-of-order stamps are sorted with the
    usual warning, and ``repair_stamps`` on a pipe is refused by name."""
    lines = _tum_text(1000).decode().splitlines()
    lines[500], lines[501] = lines[501], lines[500]
    data = ("scene: cafe\nframe: base_link\nseq: 1\n" + "\n".join(lines) + "\n").encode()
    path, fd = _piped(data)
    try:
        with pytest.warns(Warning, match="not increasing"):
            got = read_openloris(path).sequences[1]
    finally:
        os.close(fd)
    assert len(got.stamps) == 1000 and (np.diff(got.stamps) > 0).all()
    path, fd = _piped(data)
    try:
        with pytest.raises(ParseError, match="not a pipe"):
            read_openloris(path, repair_stamps=True)
    finally:
        os.close(fd)


@pytest.mark.parametrize("parser", PARSERS)
@pytest.mark.parametrize("token", ["1560000059_5", "1_000", "0_5"])
@pytest.mark.thorough
def test_a_number_with_an_underscore_is_refused_on_every_path(tmp_path, monkeypatch, parser, token):
    """Python's ``float`` reads ``1_000`` as 1000 (PEP 515), and so did the byte scanner every path
    falls back to: a stamp ``1560000059_5`` became 15600000595 (a pose sorted to the end, with
    only an out-of-order warning). No trajectory writer puts ``_`` in a number: now the line is
    named, as pandas' and numpy's parsers would."""
    use_parser(monkeypatch, parser)
    lines = _tum_text().decode().splitlines()
    lines[2500] = " ".join([token, *lines[2500].split()[1:]])
    path = tmp_path / "traj.txt"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ParseError) as info:
        read_tum(path)
    assert info.value.line == 2501
    assert f"'{token}' is not a number" in info.value.reason
    times = tmp_path / "times.txt"
    times.write_text("".join(f"{k}.5\n" for k in range(20)) + "2_1\n")
    with pytest.raises(ParseError, match="'2_1' is not a number") as info:
        read_times(times)
    assert info.value.line == 21


@pytest.mark.parametrize("parser", PARSERS)
def test_a_euroc_nan_stamp_is_named_as_not_finite(tmp_path, monkeypatch, parser):
    """A EuRoC row stamped ``nan`` was refused as "stamp nan has a fraction; expected whole
    nanoseconds ... a TUM file (stamps in seconds)": a wrong diagnosis. Now: not finite."""
    use_parser(monkeypatch, parser)
    rows = _euroc_text(_tum_text()).decode().splitlines()
    rows[2001] = "nan" + rows[2001][rows[2001].index(",") :]
    path = tmp_path / "data.csv"
    path.write_text("\n".join(rows) + "\n")
    with pytest.raises(ParseError) as info:
        read_euroc(path)
    assert (info.value.line, info.value.reason) == (2002, "timestamp nan is not finite; expected whole nanoseconds")


@pytest.mark.parametrize("parser", PARSERS)
@pytest.mark.parametrize(
    "case,line,reason",
    [
        ("nan", 1502, "stamp nan is not finite; expected a times file, one stamp in seconds per line"),
        ("back", 1503, "stamp 150.0 goes backwards after 150.1; expected increasing stamps, one per pose (KITTI's "
         "times.txt)"),
        ("repeat", 1502, "stamp 149.9 repeats after 149.9; expected increasing stamps, one per pose (KITTI's times.txt)"),
        ("empty", None, "empty file; expected a times file, one stamp in seconds per line"),
    ],
)  # fmt: skip
@pytest.mark.thorough
def test_a_bad_kitti_times_file_is_named_with_its_line(tmp_path, monkeypatch, parser, case, line, reason):
    """A times file's NaN or out-of-order stamp was reported against the pose file, with no line
    ("the stamps given for this KITTI file are not strictly increasing"; "stamp 1501 given ...":
    its index, not its line when the file has comments), and an empty times file as "expected a
    trajectory file". Now the times file and the line are named."""
    from scipy.spatial.transform import Rotation

    use_parser(monkeypatch, parser)
    rng = np.random.default_rng(2)
    mats = np.concatenate([Rotation.random(ROWS, rng).as_matrix(), rng.normal(size=(ROWS, 3, 1))], axis=2)
    poses = tmp_path / "poses.txt"
    np.savetxt(poses, mats.reshape(ROWS, 12), fmt="%.17g")
    stamps = [f"{k * 0.1:.1f}" for k in range(ROWS)]
    if case == "nan":
        stamps[1500] = "nan"
    elif case == "back":
        stamps[1500], stamps[1501] = stamps[1501], stamps[1500]
    elif case == "repeat":
        stamps[1500] = stamps[1499]
    times = tmp_path / "times.txt"
    times.write_text("" if case == "empty" else "# times\n" + "\n".join(stamps) + "\n")
    with pytest.raises(ParseError) as info:
        read_kitti(poses, stamps=times)
    assert (info.value.path, info.value.line, info.value.reason) == (str(times), line, reason)
    if case == "repeat":  # repeated stamps are kept with repeated="keep"; a stamp going back is not
        got = read_kitti(poses, stamps=times, repeated="keep")
        assert got.stamps[1500] == got.stamps[1499] == 149.9 and len(got.stamps) == ROWS


def test_the_spans_told_are_those_the_data_shows(data):
    """The time-overlap check's other spans are the sequences the data shows (a challenge phase's:
    ``DataPaths.shown``), never a hidden sequence nor another scene's; without ``shown`` every one."""
    from dataclasses import replace

    from lorisnb.io.datasets.paths import find_data, groundtruth_spans

    every = groundtruth_spans(data.root)
    assert {"cafe-1", "home-1", "market-1"} <= set(every)
    shown = replace(find_data(data.root), shown=frozenset({("home", 3), ("home", 4)}))
    assert groundtruth_spans(shown) == {k: every[k] for k in ("home-3", "home-4")}
