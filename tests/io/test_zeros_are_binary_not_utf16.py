"""A file of NUL bytes (a result file pre-allocated and never written, ``head -c 1M /dev/zero``) is
binary data, not "text in UTF-16 or UTF-32 ... save it as UTF-8": only a byte-order mark or NULs
alternating with ASCII text are wide text (adversarial finding 7)."""

from __future__ import annotations

import pytest

from lorisnb.errors import ParseError
from lorisnb.io import read_tum

TUM = "tum-rgbd"


@pytest.mark.parametrize("size", [16, 4096, 200_000])
def test_zeros_are_binary_data(tmp_path, size):
    p = tmp_path / "zeros.txt"
    p.write_bytes(b"\0" * size)
    with pytest.raises(ParseError, match=r"zeros.txt, line 1: binary data \(a NUL byte\)") as exc:
        read_tum(p)
    assert "UTF-16" not in str(exc.value)


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-le", "utf-16-be", "utf-32", "utf-32-le"])
def test_a_real_trajectory_in_wide_text_is_still_said_to_be_text(data, tmp_path, encoding):
    text = (data.root / TUM / "fr2_desk_ORB.txt").read_text()
    p = tmp_path / "wide.txt"
    p.write_bytes(text.encode(encoding))
    with pytest.raises(ParseError, match=r"wide.txt, line 1: text in UTF-16 or UTF-32 .*save it as UTF-8"):
        read_tum(p)


def test_a_real_trajectory_with_a_stray_nul_is_binary(data, tmp_path):
    lines = (data.root / TUM / "fr2_desk_ORB.txt").read_bytes().splitlines(keepends=True)
    p = tmp_path / "nul.txt"
    p.write_bytes(b"".join(lines[:5]) + b"\0" + b"".join(lines[5:]))
    with pytest.raises(ParseError, match=r"nul.txt, line 6: binary data \(a NUL byte\)"):
        read_tum(p)


def test_wide_text_after_a_long_text_part_is_told_from_its_first_nul(data, tmp_path):
    """Past the first chunks (a NUL found 9 MB into the file), the bytes around that NUL tell wide
    text from binary data, and the line named is that NUL's."""
    text = (data.root / TUM / "fr2_desk_ORB.txt").read_bytes()
    lines = text.splitlines(keepends=True)
    head = b"".join(lines) * (9 * 2**20 // len(text) + 1)
    n = head.count(b"\n")
    wide = tmp_path / "wide_late.txt"
    wide.write_bytes(head + b"".join(lines[:50]).decode().encode("utf-16-le"))
    with pytest.raises(ParseError, match=rf"wide_late.txt, line {n + 1}: text in UTF-16 or UTF-32"):
        read_tum(wide)
    binary = tmp_path / "binary_late.txt"
    binary.write_bytes(head + bytes(range(256)) * 64)
    with pytest.raises(ParseError, match=rf"binary_late.txt, line {n + 1}: binary data \(a NUL byte\)"):
        read_tum(binary)
