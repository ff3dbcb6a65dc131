"""Shared fixtures: the real data in ../shared/data (never copied into the repository)."""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")

from lorisnb.errors import LorisWarning  # noqa: E402
from lorisnb.io import find_data  # noqa: E402


@pytest.fixture(scope="session")
def data():
    return find_data()


@pytest.fixture(scope="session")
def icra20(data) -> Path:
    return data.icra20


@pytest.fixture(autouse=True)
def _quiet_lorisnb_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LorisWarning)
        yield


os.environ.setdefault("MPLBACKEND", "Agg")
