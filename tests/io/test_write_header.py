"""write_openloris writes what reads back as given: header keys and values on one line, no key of
its own, integer sequence numbers (a value 'v\\nseq: 9' added an empty sequence 9)."""

from __future__ import annotations

import pytest

import lorisnb as ln
from lorisnb.errors import ValidationError


@pytest.fixture(scope="module")
def maslam(icra20):
    return ln.read_openloris(icra20 / "lifelong" / "maslam" / "cafe.txt")


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(header={"note": "v\nseq: 9"}), "a value on one line"),
        (dict(header={"seq": "3"}), "written by write_openloris itself"),
        (dict(header={"scene": "home"}), r"pass it as its argument \(scene=..., frame=...\)"),
        (dict(header={"a\nb": "x"}), "a word on one line"),
        (dict(header={3: "x"}), "a word on one line"),
        (dict(scene="cafe\nseq: 9"), "a name on one line"),
    ],
)
def test_header_is_validated(maslam, tmp_path, kwargs, message):
    with pytest.raises(ValidationError, match=message):
        ln.write_openloris(tmp_path / "h.txt", dict(maslam.sequences), **{"scene": "cafe", **kwargs})
    assert not (tmp_path / "h.txt").exists()


def test_sequence_numbers_are_integers(maslam, tmp_path):
    with pytest.raises(ValidationError, match="key True: expected a sequence number"):
        ln.write_openloris(tmp_path / "k.txt", {True: maslam.sequences[1]}, scene="cafe")
    ln.write_openloris(tmp_path / "ok.txt", dict(maslam.sequences), scene="cafe", header={"note": "one line"})
    back = ln.read_openloris(tmp_path / "ok.txt")
    assert {k: len(v) for k, v in back.sequences.items()} == {k: len(v) for k, v in maslam.sequences.items()}
