"""A TF chain follows ``repeated`` as a pose topic does: under evo's rule (``repeated="keep"``, the
evo preset, ``--keep-repeated``) every transform of a repeated stamp is a pose. It kept only the last
whatever the rule, so the same poses scored differently read from /tf (788 poses, ATE 0.047 m) and
from a pose topic or a TUM file (820 poses, 0.062 m)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from helpers import write_bag

import lorisnb as ln


@pytest.fixture(scope="module")
def repeated(data, tmp_path_factory):
    """fr1_xyz's estimate with 30 poses repeating a stamp (moved 5 cm), as TUM text and a ROS 1 bag
    holding it both as a pose topic and as a TF chain."""
    lines = (data.tum / "freiburg1_xyz-rgbdslam.txt").read_text().splitlines()
    rows = [x.split() for x in lines if x and not x.startswith("#")]
    out = []
    for k, r in enumerate(rows):
        out.append(" ".join(r))
        if k % 25 == 5:
            out.append(" ".join([r[0], repr(float(r[1]) + 0.05), *r[2:]]))
    folder = tmp_path_factory.mktemp("tf")
    text = folder / "est.txt"
    text.write_text("\n".join(out) + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        keep = ln.read_tum(text, repeated="keep")
    return text, write_bag(folder / "est.bag", keep, ros=1, tf=("map", "odom", "cam"))


@pytest.mark.parametrize("rule", ["keep", "drop"])
def test_a_tf_chain_follows_repeated_as_a_pose_topic(repeated, rule):
    text, bag = repeated
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tum = ln.read_tum(text, repeated=rule)
        topic = ln.read_trajectory(bag, "bag", topic="/pose", repeated=rule)
        chain = ln.read_trajectory(bag, "bag", tf="map:cam", repeated=rule)
    assert len(chain) == len(topic) == len(tum) == (788 + 32 if rule == "keep" else 788)  # 32 stamps repeated
    assert np.array_equal(chain.stamps, topic.stamps)
    assert np.allclose(chain.positions, topic.positions, atol=1e-9)
    assert np.allclose(np.abs((chain.quaternions * topic.quaternions).sum(axis=1)), 1.0, atol=1e-9)


def test_the_same_poses_score_the_same_from_tf_under_evos_rule(repeated, data):
    text, bag = repeated
    gt = data.tum / "freiburg1_xyz-groundtruth.txt"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = ln.evaluate_pairs(text, gt, conventions="evo").sequences()
        b = ln.evaluate_pairs(bag, gt, conventions="evo", fmt="bag", gt_fmt="tum", tf="map:cam").sequences()
    assert a["poses"].iloc[0] == b["poses"].iloc[0] == 820
    assert b["ate_rmse"].iloc[0] == pytest.approx(a["ate_rmse"].iloc[0], rel=1e-9)


def test_crosscheck_of_a_tf_chain_without_tf2_py_says_what_to_do(repeated, data, capsys):
    """evo reads a TF chain only with ROS's tf2_py: crosscheck said ModuleNotFoundError in a
    traceback; now an error naming the bag, what evo lacks and what to do instead (exit 2)."""
    import importlib.util

    from lorisnb.cli import main

    if importlib.util.find_spec("tf2_py") is not None:
        pytest.skip("tf2_py is installed here: evo reads TF chains")
    _, bag = repeated
    rc = main(["crosscheck", str(bag), str(bag), "--format", "bag", "--topic", "/tf:map.cam", "--gt-topic", "/pose"])
    err = capsys.readouterr().err
    assert rc == 2 and str(bag) in err and "tf2_py" in err and "--tf parent:child" in err and "Traceback" not in err
