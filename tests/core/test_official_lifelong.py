"""A lifelong file whose first sequence matches nothing, and the warnings about the sequence a
lifelong alignment was fitted on, against the official OpenLORIS-Scene tool.

The inputs are made here from the bundled cafe and home ground truth with a fixed seed (the helpers of
``test_official_stress``). REFERENCE holds the official tool's numbers on exactly these files
(``benchmark/evaluate.py`` of openloris-scene-tools ce6a4839f618bf036d3f3dbae14561bfc7413641, run as
in ``test_official_stress``'s docstring, at eps 3 m, phi 30 deg, delta 1 s, tau 60 s).

When the first ``seq:`` block matches no ground-truth stamp (its stamps shifted away, or an empty,
failed block), the official ``transform_world_frame`` returns before fitting: no sequence is aligned,
and the second sequence, left in its own world frame, scores ATE 20 m and CR 0. lorisnb aligns on
the first sequence with matches by default (ATE 0.05 m, CR 1) and says so; ``official_lifelong``
(``--official-lifelong``) gives the official numbers. With Sim(3), a first sequence of one matched
pose stops the official tool (``umeyama_align`` divides by the estimate's zero spread: a NaN scale, then
``LinAlgError: Array must not contain infs or NaNs``); lorisnb's warning says so.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from test_official_stress import _estimate, _file, _rot

import lorisnb as ln
from lorisnb.errors import LorisWarning

SEED = 20270301
EPS, PHI = 3.0, 30.0


def _cases(data_root) -> dict[str, str]:
    """name -> file text of each input, from the real ground truth."""
    rng = np.random.default_rng(SEED)
    cafe = ln.load_groundtruth("cafe", data_root=data_root).sequences
    home = ln.load_groundtruth("home", data_root=data_root).sequences
    world = (_rot(rng, 40), rng.normal(size=3) * 3)
    st1, p1, q1 = _estimate(rng, cafe[1], np.arange(0, len(cafe[1]), 3), 0.0, 0.03, 1.0, world)
    st2, p2, q2 = _estimate(rng, cafe[2], np.arange(0, len(cafe[2]), 2), 0.0, 0.03, 1.0, world)
    empty = (np.zeros(0), np.zeros((0, 3)), np.zeros((0, 4)))
    blocks = [(s, *_estimate(rng, home[s], np.arange(0, len(home[s]), 2), 0.003, 0.02, 0.7, world))
              for s in (1, 2, 3)]  # fmt: skip
    blocks[0] = (1, *(x[100:101] for x in blocks[0][1:]))  # one matched pose
    return {
        "first_nomatch": _file("cafe", [(1, st1 + 5000.0, p1, q1), (2, st2, p2, q2)]),
        "first_empty": _file("cafe", [(1, *empty), (2, st2, p2, q2)]),
        "first_three": _file("cafe", [(1, st1[50:53], p1[50:53], q1[50:53]), (2, st2, p2, q2)]),
        "home_first1": _file("home", blocks),
    }


@pytest.fixture(scope="module")
def cases(data, tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("official_lifelong")
    out = {}
    for name, text in _cases(data.root).items():
        (folder / f"{name}.txt").write_text(text)
        out[name] = folder / f"{name}.txt"
    return out


def _evaluate(path: Path, data, **kw):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        ev = ln.evaluate(path, data_root=data.root, jobs=1, **kw)
    return ev, [str(w.message) for w in caught if issubclass(w.category, LorisWarning)]


def test_lever_warning_names_the_sequence_the_alignment_was_fitted_on(cases, data):
    """The lifelong alignment is fitted on sequence 1 (3 poses: no lever); sequence 2's AOE is large:
    the warning is about sequence 2's AOE and names sequence 1's 3 matched positions as such."""
    _, said = _evaluate(cases["first_three"], data)
    lever = [s for s in said if "hold the alignment's rotation by a lever" in s]
    assert len(lever) == 1
    assert ", seq 2: its median AOE" in lever[0]
    assert "the alignment was fitted on seq 1, whose 3 matched positions" in lever[0]


def test_few_poses_warning_names_file_and_sequence(cases, data):
    """The 'fitted on all of only N matched poses' warning names FILE, seq N as every other does."""
    _, said = _evaluate(cases["first_three"], data)
    few = [s for s in said if "alignment is fitted on all of only 3 matched poses" in s]
    assert len(few) == 1 and few[0].startswith(f"{cases['first_three']}, seq 1: the se3 alignment")


def test_degenerate_warning_under_sim3_says_the_official_tool_stops(cases, data):
    """One matched pose in the first sequence: under SE(3) the official tool aligns with its own
    arbitrary rotation; under Sim(3) it stops (LinAlgError). The warning says which."""
    _, sim3 = _evaluate(cases["home_first1"], data, scale=True)
    _, se3 = _evaluate(cases["home_first1"], data, scale=False)
    (a,) = [s for s in sim3 if "so its rotation is arbitrary" in s]
    (b,) = [s for s in se3 if "so its rotation is arbitrary" in s]
    assert "seq 1:" in a and "LinAlgError" in a and "aligns all the same" not in a
    assert "--align-frames 1, --align none" not in a  # refused with Sim(3): a scale needs 2 poses
    assert "aligns all the same, with its own arbitrary rotation" in b and "LinAlgError" not in b
