"""Each public reader refuses a file plainly in another format, naming it and the option that reads
it, as ``read_trajectory`` and the evaluations do: ``read_tum`` once read a EuRoC CSV without a word
(its nanosecond stamps taken as seconds, its ``w x y z`` as ``x y z w``), ``read_euroc`` a TUM file
whose stamps are whole numbers (seconds taken as nanoseconds)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import lorisnb as ln
from lorisnb.errors import ParseError


def _rows(path: Path, n: int = 400) -> list[list[str]]:
    rows = [line.split() for line in path.read_text().splitlines() if line.strip() and not line.startswith("#")]
    return rows[:n]


@pytest.fixture(scope="module")
def files(data, tmp_path_factory) -> dict[str, Path]:
    """fr2_desk's ground truth in each format (the same poses), and a TUM file of whole-second stamps."""
    src = data.tum / "fr2_desk_groundtruth.txt"
    rows = _rows(src)
    out = tmp_path_factory.mktemp("formats")
    tum = out / "gt.txt"
    tum.write_text("".join(" ".join(r) + "\n" for r in rows))
    euroc = out / "gt.csv"
    with open(euroc, "w") as f:
        f.write("#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z []\n")
        for r in rows:
            whole, _, frac = r[0].partition(".")
            f.write(",".join([whole + (frac + "0" * 9)[:9], *r[1:4], r[7], *r[4:7]]) + "\n")
    kitti = out / "gt_kitti.txt"
    from scipy.spatial.transform import Rotation

    a = np.array(rows, float)
    m = np.concatenate([Rotation.from_quat(a[:, 4:8]).as_matrix(), a[:, 1:4, None]], axis=2).reshape(-1, 12)
    np.savetxt(kitti, m, fmt="%.12e")
    whole = out / "whole_seconds.txt"  # stamps 0, 1, 2, ...: TUM, 8 numbers, whole
    whole.write_text("".join(" ".join([str(k), *r[1:]]) + "\n" for k, r in enumerate(rows)))
    return dict(tum=tum, euroc=euroc, kitti=kitti, whole=whole)


def test_each_format_read_by_its_own_reader(files):
    tum, euroc = ln.read_tum(files["tum"]), ln.read_euroc(files["euroc"])
    assert len(tum.stamps) == len(euroc.stamps) == 400
    assert 1.3e9 < tum.stamps[0] < 1.4e9 and np.allclose(euroc.stamps, tum.stamps, rtol=0, atol=1e-6)
    assert np.array_equal(euroc.positions, tum.positions)
    assert np.allclose(euroc.quaternions, tum.quaternions, atol=1e-12)
    kitti = ln.read_kitti(files["kitti"])
    assert np.allclose(kitti.positions, tum.positions, atol=1e-9)


@pytest.mark.parametrize(
    ("reader", "given", "looks", "option"),
    [
        ("read_tum", "euroc", "a EuRoC CSV file", "fmt='euroc'"),
        ("read_tum", "kitti", "a KITTI pose file", "fmt='kitti'"),
        ("read_kitti", "tum", "a TUM trajectory file", "fmt='tum'"),
        ("read_kitti", "euroc", "a EuRoC CSV file", "fmt='euroc'"),
        ("read_euroc", "tum", "a TUM trajectory file", "fmt='tum'"),
        ("read_euroc", "whole", "a TUM trajectory file", "fmt='tum'"),
        ("read_euroc", "kitti", "a KITTI pose file", "fmt='kitti'"),
    ],
)
def test_a_reader_refuses_another_formats_file_naming_it(files, reader, given, looks, option):
    with pytest.raises(ParseError) as exc:
        getattr(ln, reader)(files[given])
    text = str(exc.value)
    assert str(files[given]) in text and f"this looks like {looks}" in text and option in text
    fmt = reader.removeprefix("read_")
    with pytest.raises(ParseError) as same:
        ln.read_trajectory(files[given], fmt)
    if "line" not in text:  # read without an error of the reader's own (a line of the wrong width, ...): refused
        assert str(same.value) == text  # by the one check read_trajectory makes, with its message


def test_files_another_reader_would_take_are_refused_without_a_word_first(files):
    """The files a reader read without an error (a EuRoC CSV as TUM, whole-second TUM stamps as
    nanoseconds): refused as read_trajectory refuses them, with no warning of the reading before."""
    for reader, given, want in ((ln.read_tum, "euroc", "euroc"), (ln.read_euroc, "whole", "tum")):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            with pytest.raises(ParseError, match=rf"expected the .* format .*read it with --format {want}\b"):
                reader(files[given])


def test_the_other_readers_errors_keep_their_line(files):
    """Where a reader refuses the file itself its own error is kept: the line and its width."""
    with pytest.raises(ParseError, match=r"line 1: .* has 12 fields; .*this looks like a KITTI pose file"):
        ln.read_tum(files["kitti"])
    with pytest.raises(ParseError, match=r"line 1: stamp \d+\.\d+ has a fraction.*this looks like a TUM"):
        ln.read_euroc(files["tum"])


@pytest.mark.parametrize(
    "header",
    [
        "# timestamp tx ty tz qx qy qz qw",
        "#timestamp,tx,ty,tz,qx,qy,qz,qw",
        "# timestamp",
        "# timestamp(s) x y z qx qy qz qw",
        "",
    ],
)
def test_comma_separated_tum_under_a_timestamp_header_is_tum(files, tmp_path, header):
    """A TUM file written with commas under a ``# timestamp ...`` header (seconds, ``qx qy qz qw``)
    is TUM: read_tum read it as EuRoC's and refused it, read_euroc took its seconds as nanoseconds."""
    rows = _rows(files["tum"])
    path = tmp_path / "commas.csv"
    path.write_text((header + "\n" if header else "") + "".join(",".join(r) + "\n" for r in rows))
    got, want = ln.read_tum(path), ln.read_tum(files["tum"])
    assert np.array_equal(got.stamps, want.stamps) and np.array_equal(got.quaternions, want.quaternions)
    assert np.array_equal(ln.read_trajectory(path, "tum").positions, want.positions)
    with pytest.raises(ParseError, match=r"this looks like a TUM trajectory file.*--format tum"):
        ln.read_euroc(path)


@pytest.mark.parametrize(
    ("header", "stamps"),
    [
        ("#timestamp [ns],p_x,p_y,p_z,q_w,q_x,q_y,q_z", "ns"),
        ("timestamp_ns,p_x,p_y,p_z,q_w,q_x,q_y,q_z", "ns"),
        ("#timestamp,x,y,z,qw,qx,qy,qz", "seconds in ns"),  # whole seconds as nanoseconds: 10 digits
        ("#timestamp", "seconds in ns"),
    ],
)
def test_euroc_headers_say_euroc(files, tmp_path, header, stamps):
    """EuRoC's layout (integer nanoseconds, ``w x y z``) under each header it comes with is EuRoC,
    also where its stamps are too short to be nanoseconds since 1970 on their own."""
    rows = _rows(files["tum"])
    path = tmp_path / "euroc.csv"
    stamp = (
        (lambda k, r: str(k * 1_000_000_000))
        if stamps == "seconds in ns"
        else (lambda k, r: r[0].replace(".", "") + "000")
    )
    path.write_text(
        header + "\n" + "".join(",".join([stamp(k, r), *r[1:4], r[7], *r[4:7]]) + "\n" for k, r in enumerate(rows))
    )
    got, want = ln.read_euroc(path), ln.read_tum(files["tum"])
    assert np.array_equal(got.positions, want.positions) and np.allclose(got.quaternions, want.quaternions, atol=1e-12)
    assert np.array_equal(ln.read_trajectory(path, "euroc").positions, want.positions)
    with pytest.raises(ParseError, match=r"this looks like a EuRoC CSV file.*--format euroc"):
        ln.read_tum(path)


@pytest.mark.parametrize(("given", "looks", "option"), [("tum", "a TUM trajectory file", "--format tum"),
                                                        ("euroc", "a EuRoC CSV file", "--format euroc"),
                                                        ("kitti", "a KITTI pose file", "--format kitti")])  # fmt: skip
def test_read_openloris_of_another_format_names_it(files, given, looks, option):
    """read_openloris of a TUM, EuRoC or KITTI file: its own error on the line, and what the file is
    (it said only 'pose line before any seq: N line')."""
    with pytest.raises(ParseError, match=r"line \d+: .*") as exc:
        ln.read_openloris(files[given])
    text = str(exc.value)
    assert text.count(f"this looks like {looks}") == 1 and option in text


HEADERS = [  # (header lines, stamps, quaternion order written, the format it is)
    (
        ["# timestamp tx ty tz qx qy qz qw"],
        "ns",
        "xyzw",
        "tum",
    ),  # TUM's header over ns stamps: TUM (its unit said later)
    (["#timestamp_ns,tx,ty,tz,qx,qy,qz,qw"], "ns", "xyzw", "tum"),
    (["# timestamp [ns] tx ty tz qx qy qz qw"], "ns", "xyzw", "tum"),
    ([], "ns float", "wxyz", "euroc"),  # numpy.savetxt's '%.18e': 1.305031098665900032e+18
    (["#time,x,y,z,qw,qx,qy,qz"], "relative ns", "wxyz", "euroc"),
    (["#stamp[ns],x,y,z,qw,qx,qy,qz"], "relative ns", "wxyz", "euroc"),
    (["# a", "# b", "# c", "#timestamp [ns],p_x,p_y,p_z,q_w,q_x,q_y,q_z"], "relative ns", "wxyz", "euroc"),
    (["timestamp_ns,px,py,pz,qw,qx,qy,qz"], "relative ns", "wxyz", "euroc"),
]


@pytest.mark.parametrize(("header", "stamps", "order", "fmt"), HEADERS)
def test_a_header_naming_the_quaternion_order_decides(files, tmp_path, header, stamps, order, fmt):
    """Which format a comma-separated file is: the quaternion order its header names decides (a
    TUM header over nanosecond stamps was taken for EuRoC, its x y z w then read as w x y z: AOE
    165 deg, no warning); without one, stamps of 1e15 or more in any notation, or a header saying ns
    (also after other comment lines, or without '#'), say EuRoC."""
    from lorisnb.io.readers import registry

    rows = _rows(files["tum"])
    t0 = float(rows[0][0])

    def stamp(r: list[str]) -> str:
        s = float(r[0])
        if stamps == "ns float":
            return f"{s * 1e9:.18e}"
        return str(round((s - t0) * 1e9)) if stamps == "relative ns" else r[0].replace(".", "") + "000"

    def pose(r: list[str]) -> list[str]:
        return [*r[1:4], *r[4:8]] if order == "xyzw" else [*r[1:4], r[7], *r[4:7]]

    path = tmp_path / "poses.csv"
    path.write_text("".join(h + "\n" for h in header) + "".join(",".join([stamp(r), *pose(r)]) + "\n" for r in rows))
    assert registry.recognise(registry.sample(path)) == [fmt]
    want = ln.read_tum(files["tum"])
    got = ln.read_tum(path) if fmt == "tum" else ln.read_euroc(path)
    assert np.allclose(got.quaternions, want.quaternions, atol=1e-12) and np.array_equal(got.positions, want.positions)
    other = ln.read_euroc if fmt == "tum" else ln.read_tum
    with pytest.raises(ParseError, match=rf"--format {fmt}\b"):
        other(path)
