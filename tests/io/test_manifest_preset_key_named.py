"""A bad ``preset`` in a manifest's ``[conventions]`` table is named by its key and file, not as the
command line's ``conventions=`` (adversarial finding 7); a preset in another case is read."""

from __future__ import annotations

import shutil

import pytest

from lorisnb.errors import ParseError
from lorisnb.io.datasets.manifest import read_manifest

TUM = "tum-rgbd"


def _manifest(tmp_path, data, preset: str):
    shutil.copy(data.root / TUM / "fr2_desk_groundtruth.txt", tmp_path / "gt.txt")
    p = tmp_path / "m.toml"
    p.write_text(f'[conventions]\npreset = "{preset}"\n[[session]]\nname = "desk"\ngroundtruth = "gt.txt"\n')
    return p


def test_a_bad_preset_names_its_key(tmp_path, data):
    with pytest.raises(
        ParseError, match=r"m.toml, line 2: \[conventions\] preset=tumm: expected one of openloris, tum"
    ):
        read_manifest(_manifest(tmp_path, data, "tumm"))


def test_a_preset_in_another_case_is_read(tmp_path, data):
    m = read_manifest(_manifest(tmp_path, data, "TUM"))
    assert m.spec.preset_name == "tum" and m.spec.association == "nearest"
