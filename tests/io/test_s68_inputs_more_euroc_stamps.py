"""EuRoC nanosecond stamps read exactly (s68 finding 5): fr1_xyz's ground truth written as EuRoC gave
805 of its 3000 stamps one float step away from the TUM file's reading of the same decimals (the
stamp read as a float, 1.3e18 being past float64's whole numbers, then divided by 1e9). lorisnb's
reading now gives the TUM file's numbers bit for bit; evo's reading (``stamps="evo"``) stays evo's."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from lorisnb.errors import LorisWarning
from lorisnb.io.readers.plain import _read_euroc_whole, euroc_seconds, read_euroc, read_trajectory


def _as_euroc(tum_text: str) -> str:
    """The TUM file's rows as EuRoC rows: each stamp's decimals as whole nanoseconds (text only)."""
    rows = []
    for line in tum_text.splitlines():
        if not line.strip() or line.startswith("#"):
            continue
        stamp, x, y, z, qx, qy, qz, qw = line.split()
        whole, _, frac = stamp.partition(".")
        rows.append(f"{whole}{frac.ljust(9, '0')},{x},{y},{z},{qw},{qx},{qy},{qz}")
    return "#timestamp,p_x,p_y,p_z,q_w,q_x,q_y,q_z\n" + "\n".join(rows) + "\n"


@pytest.fixture(scope="module")
def fr1(data, tmp_path_factory):
    tum = data.tum / "freiburg1_xyz-groundtruth.txt"
    euroc = tmp_path_factory.mktemp("euroc") / "gt.csv"
    euroc.write_text(_as_euroc(tum.read_text()))
    return tum, euroc


def test_euroc_stamps_are_the_tum_files_bit_for_bit(fr1):
    tum, euroc = fr1
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LorisWarning)
        t = read_trajectory(tum, "tum")
        e = read_trajectory(euroc, "euroc")
        whole = _read_euroc_whole(euroc, False)  # the byte scanner's route (pipes, files with problems)
        evo = read_euroc(euroc, stamps="evo")
    assert len(t) == len(e) == 3000
    np.testing.assert_array_equal(e.stamps, t.stamps)
    np.testing.assert_array_equal(whole.stamps, t.stamps)
    ns = np.array([int(line.split(",")[0]) for line in euroc.read_text().splitlines()[1:]])
    np.testing.assert_array_equal(evo.stamps, np.divide(ns.astype(np.float64), 1e9))  # evo's own reading
    assert (evo.stamps != t.stamps).sum() == 805  # what evo's reading gives: one float step away


def test_euroc_stamps_as_evo_reads_them(fr1):
    fi = pytest.importorskip("evo.tools.file_interface")
    _, euroc = fr1
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        theirs = fi.read_euroc_csv_trajectory(str(euroc))
    np.testing.assert_array_equal(read_euroc(euroc, stamps="evo").stamps, theirs.timestamps)


def test_evaluations_of_the_same_trajectory_as_tum_and_euroc_agree(fr1, data):
    from lorisnb import evaluate_pairs

    tum, euroc = fr1
    est = data.tum / "freiburg1_xyz-rgbdslam.txt"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LorisWarning)
        a = evaluate_pairs([est], tum, fmt="tum", gt_fmt="tum", scene="xyz").sequences()
        b = evaluate_pairs([est], euroc, fmt="tum", gt_fmt="euroc", scene="xyz").sequences()
    numbers = [c for c in a.columns if a[c].dtype.kind == "f"]
    assert "ate_rmse" in numbers
    np.testing.assert_array_equal(a[numbers].to_numpy(), b[numbers].to_numpy())


@pytest.mark.parametrize(
    "ns",
    [0, 1, 999_999_999, 2**53 - 1, 2**53, 2**53 + 1, 1_305_031_102_175_304_000, 1_403_636_579_763_555_584,
     9_999_999_999_999_999_999, 12_345_678_901_234_567],
)  # fmt: skip
def test_seconds_are_the_decimals_nearest_float(ns):
    text = f"{ns},1\n-{ns},1\n".encode()
    buf = np.frombuffer(text, np.uint8)
    got = euroc_seconds(buf, np.array([0, text.index(b"\n") + 1]))
    want = float(f"{ns // 10**9}.{ns % 10**9:09d}")
    assert got is not None and got[0] == want and got[1] == -want


def test_random_stamps_of_every_size_are_exact():
    rng = np.random.default_rng(7)
    values = [int(v) for v in rng.integers(0, 2**62, 3000)] + [int(v) for v in rng.integers(0, 10**13, 3000)]
    text = "".join(f"{v},0\n" for v in values).encode()
    buf = np.frombuffer(text, np.uint8)
    starts = np.concatenate(([0], np.flatnonzero(buf == 10)[:-1] + 1))
    got = euroc_seconds(buf, starts)
    assert got is not None
    np.testing.assert_array_equal(got, [float(f"{v // 10**9}.{v % 10**9:09d}") for v in values])


@pytest.mark.parametrize("stamp", [b"1.4e18", b"+5", b"12x", b"123456789012345678901"])
def test_stamps_not_plain_whole_numbers_are_left_to_the_float_reading(stamp):
    assert euroc_seconds(np.frombuffer(stamp + b",1\n", np.uint8), np.array([0])) is None


def test_a_large_file_read_in_chunks_is_exact(tmp_path, monkeypatch):
    n = 40_000  # several chunks of the exact reading's stream
    ns = 1_403_636_579_763_555_584 + np.arange(n, dtype=np.int64) * 4_999_999
    rows = "".join(f" {v},{k % 7}.5,0,0,1,0,0,0\n" for k, v in enumerate(ns.tolist()))  # a space before the stamp
    f = tmp_path / "big.csv"
    f.write_text("#timestamp,p_x,p_y,p_z,q_w,q_x,q_y,q_z\n" + rows)
    from lorisnb.io.parsing import chunks

    monkeypatch.setattr(chunks, "CHUNK_BYTES", 1 << 16)
    t = read_euroc(f)
    np.testing.assert_array_equal(t.stamps, [float(f"{v // 10**9}.{v % 10**9:09d}") for v in ns.tolist()])
