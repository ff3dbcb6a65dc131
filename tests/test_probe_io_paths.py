"""Probes of the file readers on unusual inputs: every reading path (numpy, pandas in one call,
pandas on ranges, chunks) and pipes give the same numbers and the same errors."""

from __future__ import annotations

import os
import threading
import warnings

import numpy as np
import pytest

from lorisnb.errors import ParseError
from lorisnb.io import read_euroc, read_openloris, read_times, read_trajectory, read_tum

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
