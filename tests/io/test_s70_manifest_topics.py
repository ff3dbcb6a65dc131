"""A manifest's topic is one topic: ``estimate_topic = "/odom,/pose"`` (the command line's ``--topic
A,B``, a row per topic) was read as a topic named '/odom,/pose' and every bag failed with "no pose
topic '/odom,/pose'"; it is refused at the manifest's line, saying what to write."""

from __future__ import annotations

import shutil

import pytest

from lorisnb.cli import main
from lorisnb.errors import ParseError
from lorisnb.io.datasets.manifest import read_manifest

MANIFEST = """name = "bags"
root = "gt"
groundtruth_format = "tum"
estimate_format = "bag"
{key} = "{value}"

[[session]]
name = "fr1_xyz"
groundtruth = "fr1_xyz.txt"
"""


@pytest.mark.parametrize("key", ["estimate_topic", "groundtruth_topic"])
def test_a_comma_list_of_topics_is_refused_at_its_line(tmp_path, data, key, capsys):
    (tmp_path / "gt").mkdir()
    shutil.copyfile(data.tum / "freiburg1_xyz-groundtruth.txt", tmp_path / "gt" / "fr1_xyz.txt")
    text = MANIFEST.format(key=key, value="/odom, /pose")
    if key == "groundtruth_topic":  # a topic of a bag ground truth
        text = text.replace('groundtruth_format = "tum"', 'groundtruth_format = "bag"')
    m = tmp_path / "m.toml"
    m.write_text(text)
    with pytest.raises(ParseError, match=rf"line 5: {key} = '/odom, /pose': a manifest reads one topic per session"):
        read_manifest(m)
    (tmp_path / "res" / "orb").mkdir(parents=True)
    assert main(["evaluate", str(tmp_path / "res"), "--manifest", str(m), "--no-progress"]) == 2
    assert f"{key} = '/odom'" in capsys.readouterr().err  # what to write
    m.write_text(MANIFEST.format(key="estimate_topic", value="/odom"))
    assert read_manifest(m).estimate_topic == "/odom"  # one topic: read
