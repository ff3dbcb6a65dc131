"""What docs/guide/reports.md says of the findings/ tables' names: kept unescaped, in Unicode NFC; a
folder stored in NFD is not found by the label as written, and is by
:func:`lorisnb.io.datasets.paths.named_entry` (each part matched in NFC)."""

from __future__ import annotations

import os
import shutil
import unicodedata

import lorisnb as ln
from lorisnb.io.datasets.paths import named_entry

ORB = "cafe_1_1_orbslam2-original.txt"


def test_a_file_stored_in_nfd_is_found_by_its_nfc_label(tmp_path, icra20, data):
    nfd = unicodedata.normalize("NFD", "algé")
    (tmp_path / "res" / nfd).mkdir(parents=True)
    shutil.copy(icra20 / "per-seq" / "orbslam2_rgbd" / ORB, tmp_path / "res" / nfd / ORB)
    table = ln.evaluate(tmp_path / "res", data_root=data, progress=False).sequences()
    (alg,), (file,) = set(table["algorithm"]), set(table["file"])
    assert alg == "algé" == unicodedata.normalize("NFC", alg) and file == f"algé/{ORB}"  # NFC, no escape
    if not os.path.exists(tmp_path / "res" / "algé"):  # a disk that keeps the NFD name (not macOS's APFS)
        assert not os.path.exists(tmp_path / "res" / file)
    assert named_entry(tmp_path / "res", file) == tmp_path / "res" / nfd / ORB
