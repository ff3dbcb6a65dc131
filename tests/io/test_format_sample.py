"""The format registry's sample of a file's beginning (:func:`lorisnb.io.readers.registry.sample`):
its quick first look at 4 KB gives the same sample as looking at all 64 KB, whatever the lines, and
every file of the bundled data is recognised as its format."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lorisnb.io.readers import registry

LINES = st.one_of(
    st.lists(st.floats(-1e6, 1e6, allow_nan=False), min_size=1, max_size=17).map(lambda v: " ".join(map(repr, v))),
    st.lists(st.integers(-(10**19), 10**19), min_size=1, max_size=12).map(lambda v: ",".join(map(str, v))),
    st.sampled_from(["# timestamp tx ty tz", "#timestamp [ns],p_x", "", "   ", "scene: cafe", "seq: 2", "a,b,c"]),
    st.text(alphabet=st.characters(blacklist_categories=["Cs"]), max_size=300),  # any text, unicode spaces too
    st.integers(3000, 6000).map(lambda n: "1 " * n),  # a line across the 4 KB mark
)
ENDS = st.sampled_from(["\n", "\r\n", "\r"])


@settings(max_examples=200, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(LINES, ENDS), max_size=80), st.booleans())
def test_first_look_gives_the_whole_look(tmp_path_factory, lines, bom):
    data = ("\ufeff" if bom else "").encode() + "".join(a + b for a, b in lines).encode("utf-8", "surrogatepass")
    whole = registry._sample(data[: registry.SAMPLE_BYTES], len(data) >= registry.SAMPLE_BYTES)
    quick = registry.sample_bytes(data)
    assert (quick.comments, quick.rows, quick.commas) == (whole.comments, whole.rows, whole.commas)
    assert registry.recognise(quick) == registry.recognise(whole)
    path = tmp_path_factory.mktemp("sample") / "f.txt"
    path.write_bytes(data)
    read = registry.sample(path)
    assert read is not None and (read.comments, read.rows, read.commas) == (whole.comments, whole.rows, whole.commas)
    text = data.decode("utf-8", "replace").lstrip("\ufeff")  # tokens as a regular expression splits them
    for row in whole.rows:
        assert row == tuple(t for t in re.split(r"[\s,]+", " ".join(row)) if t)
    assert all(line.strip() in text for line in whole.comments)


def test_bundled_files_recognised(data):
    icra = sorted(Path(data.icra20).rglob("*.txt"))
    tum = sorted(Path(data.tum).glob("*.txt"))
    if not icra or not tum:
        pytest.skip("the bundled icra20 results or TUM pairs are not here")
    assert {str(f): registry.recognise(registry.sample(f)) for f in icra} == {str(f): ["openloris"] for f in icra}
    assert {str(f): registry.recognise(registry.sample(f)) for f in tum} == {str(f): ["tum"] for f in tum}


@pytest.mark.parametrize("width", range(195, 215))
@pytest.mark.parametrize("end", ["\n", "\r\n", "é\n"])
def test_twentieth_line_across_the_first_look(tmp_path, width, end):
    """Rows of about 200 bytes put the 20th across the 4 KB mark (a multi-byte character or a CRLF
    cut there too): it is read whole, as when looking at all of the sample."""
    row = ("1.5 " * 60)[: width - len(end.encode())].rstrip() + end
    data = ("# timestamp\n" + row * 40).encode()
    quick = registry.sample_bytes(data)
    assert len(quick.rows) == registry.SAMPLE_LINES
    assert quick.rows[-1] == quick.rows[0]
    (tmp_path / "f.txt").write_bytes(data)
    read = registry.sample(tmp_path / "f.txt")
    whole = registry._sample(data, False)
    for s in (quick, read):
        assert s is not None and (s.comments, s.rows, s.commas) == (whole.comments, whole.rows, whole.commas)
