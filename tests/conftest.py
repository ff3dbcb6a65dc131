"""Shared fixtures: the real data in ../shared/data (never copied into the repository)."""

from __future__ import annotations

import atexit
import os
import shutil
import tempfile
import warnings
from pathlib import Path

import matplotlib
import pytest
from hypothesis import settings
from hypothesis.configuration import set_hypothesis_home_dir

matplotlib.use("Agg")

from lorisnb.errors import DataNotFoundError, LorisWarning  # noqa: E402
from lorisnb.io import find_data  # noqa: E402

# nothing of hypothesis in the checkout (.hypothesis/): the tests leave the tree as they found it
_HYPOTHESIS_HOME = tempfile.mkdtemp(prefix="lorisnb-hypothesis-")
atexit.register(shutil.rmtree, _HYPOTHESIS_HOME, ignore_errors=True)
set_hypothesis_home_dir(_HYPOTHESIS_HOME)
settings.register_profile("lorisnb", database=None)
settings.load_profile("lorisnb")


@pytest.fixture(scope="session")
def data():
    """The real data (``LORISNB_DATA`` or ../shared/data); tests that need it skip, saying what is
    missing, where it cannot be found."""
    try:
        return find_data()
    except DataNotFoundError as exc:
        pytest.skip(f"the real data is not here: {exc}")


@pytest.fixture(scope="session")
def icra20(data) -> Path:
    return data.icra20


@pytest.fixture(autouse=True)
def _quiet_lorisnb_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LorisWarning)
        yield


os.environ.setdefault("MPLBACKEND", "Agg")
