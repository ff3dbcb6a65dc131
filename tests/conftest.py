"""Shared fixtures: the real data in ../shared/data (never copied into the repository)."""

from __future__ import annotations

import atexit
import fcntl
import os
import shutil
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

import matplotlib
import pytest
from hypothesis import settings
from hypothesis.configuration import set_hypothesis_home_dir

matplotlib.use("Agg")

# pytest keeps the test modules it rewrote (its assertions) in tests/**/__pycache__ (git ignores them),
# also where PYTHONDONTWRITEBYTECODE is set (as on many CI machines): there every worker rewrote all
# 260 modules at each run (a collection of 31 s, 13 s with them kept, on 2 cores). This process only:
# the commands the tests run keep the environment's setting.
sys.dont_write_bytecode = False

from lorisnb.errors import DataNotFoundError, LorisWarning  # noqa: E402
from lorisnb.io import find_data  # noqa: E402
from lorisnb.tools.report.lean_imports import jsonschema_without_iri_grammars  # noqa: E402

# as in lorisnb's own processes: jsonschema (nbformat's) without the 38 IRI grammars it compiles at
# import, about 2 s of each test worker's collection for a format no test checks
jsonschema_without_iri_grammars()

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


@pytest.fixture(scope="session")
def tum_folder(data) -> Path:
    """The TUM RGB-D folder of the real data (the fr2_desk pair, the fr1_xyz ground truth)."""
    root = data.root / "tum-rgbd"
    if not (root / "fr2_desk_ORB.txt").is_file():
        pytest.skip(f"no TUM pair in {root}")
    return root


@pytest.fixture(scope="session")
def fr1_xyz_groundtruth(data) -> Path:
    """The fr1_xyz ground truth of the real data (TUM format)."""
    path = data.root / "tum-rgbd" / "freiburg1_xyz-groundtruth.txt"
    if not path.is_file():
        pytest.skip(f"{path} is not in the data")
    return path


ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session")
def teaching_python() -> Path:
    """The teaching kit's environment (.venv-teach, layered on .venv), made as a fresh clone's first
    `make student` makes it, once for every test process (a lock: pytest-xdist's workers share it)."""
    with open(ROOT / ".venv" / ".teaching-lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        made = subprocess.run(
            ["make", "-C", str(ROOT), "-o", ".venv/.installed-stamp", ".venv-teach/.installed-stamp"],
            capture_output=True, text=True, timeout=1800,
        )  # fmt: skip
    assert made.returncode == 0, made.stdout[-3000:] + made.stderr[-3000:]
    return ROOT / ".venv-teach" / "bin" / "python"


@pytest.fixture(params=["kernel", "numpy"])
def rotation_route(request, monkeypatch) -> str:
    """Rotation blocks' quaternions by the compiled kernel (``lorisnb.core.trajectory._rotations``, skipped
    where the install built none) or by the numpy code it mirrors."""
    from lorisnb.core.trajectory import rotations as matrices

    if request.param == "kernel" and matrices._kernel is None:
        pytest.skip("lorisnb.core.trajectory._rotations was not built (no C compiler at install)")
    if request.param == "numpy":
        monkeypatch.setattr(matrices, "_kernel", None)
    return request.param


@pytest.fixture(autouse=True)
def _quiet_lorisnb_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LorisWarning)
        yield


os.environ.setdefault("MPLBACKEND", "Agg")


@pytest.hookimpl(optionalhook=True)  # a hook of pytest-xdist's
def pytest_xdist_make_scheduler(config, log):
    """``--dist loadgroup`` (the Makefile's) with a module for the group of every test that names none:
    a module's tests run on one worker, so its module-scoped fixtures (an evaluation of the bundled
    results, a compiled peer) are made once, not on each worker its tests were spread over. On 2 cores
    this took the fast tests' CPU from 274 s to 260 s (the workers' shares 115 s and 109 s). Tests
    grouped by ``xdist_group`` (the notebooks, the graders) keep their groups; test ids are unchanged."""
    if config.getvalue("dist") != "loadgroup":
        return None
    from xdist.scheduler import LoadGroupScheduling

    class GroupOrModule(LoadGroupScheduling):
        def _split_scope(self, nodeid: str) -> str:
            group = super()._split_scope(nodeid)
            return group if group != nodeid else nodeid.split("::", 1)[0]

    return GroupOrModule(config, log)
