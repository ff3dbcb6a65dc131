"""A clean build of lorisnb prints no setuptools warning caused by the project's own files
(pyproject.toml's license table, its experimental ext-modules table, a data folder Python can
import that is not a listed package); the wheel still holds the sample data and the kernel."""

from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.slow


def test_building_the_wheel_warns_of_nothing_in_the_projects_files(tmp_path):
    src = tmp_path / "src"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(".git", "build", "*.egg-info", "results", ".*cache*",
                                                             "*.so", "__pycache__", ".ci"))  # fmt: skip
    out = subprocess.run([sys.executable, "-m", "pip", "wheel", ".", "-w", str(tmp_path / "dist"), "--no-deps",
                          "--no-build-isolation", "-v"], cwd=src, capture_output=True, text=True, check=True)  # fmt: skip
    log = out.stdout + out.stderr
    warned = [line for line in log.splitlines() if "Warning" in line or "deprecated" in line.lower()]
    assert warned == [], "\n".join(warned)
    names = zipfile.ZipFile(next((tmp_path / "dist").glob("lorisnb-*.whl"))).namelist()
    assert "lorisnb/sample_data/openloris-scene/groundtruth/gt_cafe_1.txt" in names
    assert any(n.startswith("lorisnb/sample_data/published/") for n in names)
    assert any(n.startswith("lorisnb/core/trajectory/_rotations") and n.endswith(".so") for n in names)
    assert "lorisnb/notebooks/compare_algorithms.ipynb" in names
    meta = next(n for n in names if n.endswith(".dist-info/METADATA"))
    text = zipfile.ZipFile(next((tmp_path / "dist").glob("lorisnb-*.whl"))).read(meta).decode()
    assert "License-Expression: MIT" in text
