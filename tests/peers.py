"""The peers' own code, for tests that run it: kept OUTSIDE the repository (their licences differ
from lorisnb's, and tests use no network), in ``$LORISNB_PEERS`` or ``~/.cache/lorisnb/peers``.
A test that needs a peer missing there skips, saying how to fetch it (once, by hand):

- ``kitti_devkit/``: the KITTI odometry devkit's C++ (``evaluate_odometry.cpp``, ``matrix.h``,
  ``matrix.cpp``, ``mail.h``; GPL), e.g. from the devkit zip of cvlibs.net (``devkit/cpp``) or
  github.com/TurtleZhong/ORB_SLAM2_Evaluation at 152c8641ef7f6a549add6d881bc9fc90cead666a
  (``devkit/cpp``: the devkit's metric code unchanged, its ``eval()`` paths edited).
- ``kitti-odom-eval/``: github.com/Huangying-Zhan/kitti-odom-eval at
  4b850b0815dcd28edef893ca3422125b04a02397 (MIT): its Python evaluator and real KITTI poses
  (``dataset/kitti_odom/gt_poses/00..10.txt``, ``result/example_1/09.txt`` and ``10.txt``: a
  learned visual odometry's estimates).

``git clone URL DIR && git -C DIR checkout COMMIT`` into the peers folder does it.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

#: peer -> (a file that must exist in it, where to get it)
PEERS = {
    "kitti_devkit": ("evaluate_odometry.cpp", "the KITTI odometry devkit's devkit/cpp folder"),
    "kitti-odom-eval": ("kitti_odometry.py", "github.com/Huangying-Zhan/kitti-odom-eval"),
    "tartanair_tools": ("evaluation/tartanair_evaluator.py", "github.com/castacks/tartanair_tools"),
}


def peers_root() -> Path:
    return Path(os.environ.get("LORISNB_PEERS") or Path.home() / ".cache" / "lorisnb" / "peers")


def peer(name: str) -> Path:
    """The folder of peer ``name`` (see the module docstring); skips the test when it is missing."""
    must, where = PEERS[name]
    folder = peers_root() / name
    if not (folder / must).is_file():
        pytest.skip(f"{name} is not in {peers_root()} (LORISNB_PEERS): fetch {where} there (see tests/peers.py)")
    return folder
