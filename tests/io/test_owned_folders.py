"""Output folders are replaced only when lorisnb created them (lorisnb.io.writers.replace_folder),
as the teaching kit's book.py and slides.py use it: a user's folder given as the output is refused
and kept as it was (the trial's `book.py mythesis` deleted chapter1.tex and mythesis-src/)."""

from __future__ import annotations

import pytest

from lorisnb.errors import OutputError
from lorisnb.io.writers import check_owned_folder, replace_folder

MARKER = ".lorisnb-teaching"


def _built(tmp_path, name, text):
    d = tmp_path / name
    d.mkdir()
    (d / "index.html").write_text(text)
    return d


def test_a_folder_lorisnb_did_not_create_is_refused_and_kept(tmp_path):
    mine = tmp_path / "mythesis"
    mine.mkdir()
    (mine / "chapter1.tex").write_text("two years of work")
    with pytest.raises(OutputError, match=r"mythesis exists and lorisnb did not create it \(no \.lorisnb-teaching"):
        check_owned_folder(mine, MARKER)
    with pytest.raises(OutputError, match="choose another output folder"):
        replace_folder(_built(tmp_path, "b1", "new"), mine, MARKER)
    assert (mine / "chapter1.tex").read_text() == "two years of work"
    assert sorted(p.name for p in mine.iterdir()) == ["chapter1.tex"]
    a_file = tmp_path / "notes.md"
    a_file.write_text("notes")
    with pytest.raises(OutputError):
        replace_folder(_built(tmp_path, "b2", "new"), a_file, MARKER)
    assert a_file.read_text() == "notes"


def test_a_folder_it_created_is_replaced_and_nothing_is_left_beside_it(tmp_path):
    out = tmp_path / "site" / "book"
    replace_folder(_built(tmp_path, "b1", "first"), out, MARKER)
    assert (out / "index.html").read_text() == "first" and (out / MARKER).is_file()
    (out / "stale.html").write_text("from the first build")
    replace_folder(_built(tmp_path, "b2", "second"), out, MARKER)
    assert sorted(p.name for p in out.iterdir()) == [MARKER, "index.html"]
    assert (out / "index.html").read_text() == "second"
    assert sorted(p.name for p in out.parent.iterdir()) == ["book"]
    assert not (tmp_path / "b1").exists() and not (tmp_path / "b2").exists()
