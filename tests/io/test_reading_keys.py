"""Keys and reading options that used to be ignored: a typo in any table of a manifest, a topic
together with a TF chain (command line, Python, manifest), topics and chains on text files. Each is
refused where the user wrote it, naming the file, the table, the key and the keys known."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import write, write_bag

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import ParseError, ValidationError
from lorisnb.io.readers.bags import read_bag
from lorisnb.tools.evaluation.runner import evaluate_manifest, evaluate_pairs

GT = "freiburg1_xyz-groundtruth.txt"
MANIFEST = """
name = "xyz"
scene = "xyz"
root = "{root}"
{top}
[[session]]
name = "xyz"
groundtruth = "{gt}"
{extra}
"""


def _manifest(tmp_path, data, top: str = "", extra: str = "", name: str = "m.toml"):
    return write(tmp_path, name, MANIFEST.format(root=data.tum, gt=GT, top=top, extra=extra))


@pytest.mark.parametrize(
    ("where", "top", "extra", "key", "near"),
    [
        ("[transform]", "", "[transform]\nrotation = [0.0, 0.0, 0.0, 1.0]", "rotation", None),
        ("[transform]", "", "[transform]\nquaternions = [0.0, 0.0, 0.0, 1.0]", "quaternions", "quaternion"),
        ("[transform]", "", "[transform]\ntranslaton = [1.0, 0.0, 0.0]", "translaton", "translation"),
        ("[[session]] 1", "", 'estimte = "x.txt"', "estimte", "estimate"),
        ("", 'estimate_fromat = "tum"', "", "estimate_fromat", "estimate_format"),
    ],
)
def test_an_unknown_key_in_any_table_is_refused_with_its_nearest_known_key(
    data, tmp_path, where, top, extra, key, near
):
    m = _manifest(tmp_path, data, top, extra)
    with pytest.raises(ParseError) as info:
        ln.read_manifest(m)
    msg = str(info.value)
    line = next(
        n for n, text in enumerate(m.read_text().splitlines(), 1) if text.startswith(key)
    )  # where it is written
    assert f"{m}, line {line}: {where}{': ' if where else ''}unknown key {key!r}" in msg
    assert (f"did you mean {near!r}" in msg) if near else "did you mean" not in msg
    # the command line says the same, exit status 2, nothing scored
    out = tmp_path / "out.csv"
    assert main(["evaluate", str(tmp_path), "--manifest", str(m), "--csv", str(out)]) == 2
    assert not out.exists()


def test_a_transform_that_is_not_a_table_is_refused(data, tmp_path):
    m = _manifest(tmp_path, data, "transform = [1.0, 0.0, 0.0]")
    with pytest.raises(ParseError, match=r"\[transform\] table"):
        ln.read_manifest(m)


def test_a_correct_transform_still_changes_the_numbers(data, tmp_path):
    """The key check refuses typos only: the known keys keep their effect (a 90 degree yaw of the
    body frame moves every pose's orientation error by 90 degrees, without alignment)."""
    write(tmp_path, "res/slam/xyz.txt", (data.tum / "freiburg1_xyz-rgbdslam.txt").read_bytes())
    s = np.sqrt(0.5)
    aoe = []
    for k, extra in enumerate(("", f"[transform]\nquaternion = [0.0, 0.0, {s}, {s}]")):
        m = _manifest(
            tmp_path, data, f'{extra}\n[conventions]\nassociation = "nearest"\nalign = "none"', name=f"{k}.toml"
        )
        aoe.append(evaluate_manifest(m, tmp_path / "res").sequences()["aoe_mean"].iloc[0])
    assert abs(aoe[1] - aoe[0]) > 45


def test_a_topic_and_a_tf_chain_together_are_refused_everywhere(tmp_path, data):
    t = ln.read_tum(data.tum / GT)
    bag = write_bag(tmp_path / "b.bag", t, 1, tf=("world", "odom", "base"))
    # Python: the bag holds both, and either alone reads the same poses
    np.testing.assert_allclose(read_bag(bag, topic="/pose").positions, read_bag(bag, tf="world:base").positions,
                               atol=1e-9)  # fmt: skip
    with pytest.raises(ValidationError, match="not both"):
        read_bag(bag, topic="/pose", tf="world:base")
    with pytest.raises(ValidationError, match="not both"):
        evaluate_pairs(bag, data.tum / GT, fmt="bag", gt_fmt="tum", topic="/pose", tf="world:base")
    # the command line: a usage error (2) before anything is read, for either side
    for args in (["--topic", "/pose", "--tf", "world:base"],):
        rc = main(["evaluate", str(bag), "--gt", str(data.tum / GT), "--format", "bag", "--gt-format", "tum", *args])
        assert rc == 2
    rc = main(["evaluate", str(data.tum / GT), "--gt", str(bag), "--format", "tum", "--gt-format", "bag",
               "--gt-topic", "/pose", "--gt-tf", "world:base"])  # fmt: skip
    assert rc == 2


@pytest.mark.parametrize("key", ["estimate_topic", "estimate_tf", "groundtruth_topic", "groundtruth_tf"])
def test_bag_keys_of_a_manifest_of_text_files_are_refused(data, tmp_path, key):
    value = '"/pose"' if key.endswith("topic") else '"world:base"'
    m = _manifest(tmp_path, data, f"{key} = {value}")
    with pytest.raises(ParseError, match=f"{key}: only for bag files") as info:
        ln.read_manifest(m)
    assert str(m) in str(info.value)


def test_a_manifest_topic_and_tf_chain_together_are_refused(data, tmp_path):
    m = _manifest(tmp_path, data, 'estimate_format = "bag"\nestimate_topic = "/pose"\nestimate_tf = "world:base"')
    with pytest.raises(ParseError, match="estimate_topic and estimate_tf both given"):
        ln.read_manifest(m)
