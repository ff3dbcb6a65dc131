"""Tables of real results shared by the decision tests (diff, history, report runs): each evaluated
once a session from the bundled icra20 results; the modules take copies (a test that edits one
changes no other module's table)."""

from __future__ import annotations

import pandas as pd
import pytest

import lorisnb as ln

#: Three odom result files: two cafe sequences and one home sequence.
ODOM = ("cafe-1-1-odom.txt", "cafe-1-2-odom.txt", "home-1-1-odom.txt")


@pytest.fixture(scope="session")
def odom_sequences(icra20) -> pd.DataFrame:
    """The :data:`ODOM` files' sequences, named as a results folder's evaluation names them."""
    t = ln.evaluate([icra20 / "per-seq" / "odom" / f for f in ODOM], progress=False).sequences()
    return t.assign(file="odom/" + t["file"])


@pytest.fixture(scope="session")
def paper_sequences(icra20) -> pd.DataFrame:
    """One real run: the odom and orbslam2_rgbd per-seq results at the paper's thresholds."""
    ev = ln.evaluate([icra20 / "per-seq" / "odom", icra20 / "per-seq" / "orbslam2_rgbd"], progress=False)
    return ev.sequences(eps="paper", phi=30)
