"""The size of the sample data shipped in the package, as the teaching guide and the teaching
README state it, is the size of its files (they said 1.4 MB of 1.71 MB)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("page", ["docs/guide/teaching.md", "teaching/README.md"])
def test_the_stated_sample_size_is_its_files(page):
    files = [p for p in (ROOT / "lorisnb" / "sample_data").rglob("*") if p.is_file() and "__pycache__" not in p.parts]
    size_mb = sum(p.stat().st_size for p in files) / 1e6
    stated = re.findall(r"([\d.]+) MB sample shipped in the package", (ROOT / page).read_text())
    assert stated and all(float(s) == round(size_mb, 1) for s in stated), (stated, size_mb)
