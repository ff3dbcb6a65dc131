"""Manifest sessions as an adversarial tester found them: a session listed twice in two spellings
(a name in NFC and NFD, ``x.txt`` and ``./x.txt``, two names of one file on disk) scored one file
twice; a ROS 2 bag folder was refused as a session's ground truth; ``estimate = "sub/x.txt"`` was
found only when another session's file lay at the top of the algorithm's folder; errors about a
manifest's own values named no manifest, or only the command line's flag."""

from __future__ import annotations

import re
import shutil
import unicodedata
from pathlib import Path

import pytest
from helpers import write_bag

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import ParseError
from lorisnb.io.datasets import manifest
from lorisnb.io.datasets.manifest import read_manifest
from lorisnb.tools.evaluation.inputs import holds_any

NFC = unicodedata.normalize("NFC", "café")
NFD = unicodedata.normalize("NFD", "café")


@pytest.fixture
def xyz(data, tmp_path) -> Path:
    """fr1/xyz's ground truth copied into a manifest's folder, ``m/gt/xyz_gt.txt``."""
    gt = tmp_path / "m" / "gt" / "xyz_gt.txt"
    gt.parent.mkdir(parents=True)
    shutil.copy(data.root / "tum-rgbd" / "freiburg1_xyz-groundtruth.txt", gt)
    return gt


def _manifest(xyz: Path, sessions: list[dict[str, str]], head: str = "", name: str = "lab.toml") -> Path:
    body = "".join(
        "[[session]]\n" + "".join(f'{k} = "{v}"\n' for k, v in s.items()) + 'groundtruth = "gt/xyz_gt.txt"\n'
        for s in sessions
    )
    p = xyz.parent.parent / name
    p.write_text(head + body, encoding="utf-8")
    return p


def _results(tmp_path: Path, data, files: list[str]) -> Path:
    """results/algA with fr1/xyz's rgbdslam estimate at each of ``files``."""
    res = tmp_path / "res"
    for f in files:
        (res / "algA" / f).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(data.root / "tum-rgbd" / "freiburg1_xyz-rgbdslam.txt", res / "algA" / f)
    return res


def _cli(capsys, *args: str) -> tuple[int, str]:
    rc = main(["evaluate", *map(str, args), "--no-progress"])
    return rc, capsys.readouterr().err


# 1. a session listed twice, in two spellings


def test_a_name_in_nfc_and_in_nfd_is_one_session_listed_twice(tmp_path, data, xyz, capsys):
    m = _manifest(xyz, [{"name": NFC}, {"name": NFD}])
    said = f"lab.toml, line 5: [[session]] 1 ('{NFC}') and [[session]] 2 ('{NFD}') have the same name, 'caf\\xe9' and "
    with pytest.raises(ParseError, match=re.escape(said + "'cafe\\u0301', one name in two Unicode forms")):
        read_manifest(m)
    res = _results(tmp_path, data, [NFD + ".txt"])
    rc, err = _cli(capsys, res, "--manifest", m)
    assert rc == 2 and "one name in two Unicode forms" in err and "[[session]] 1" in err and "[[session]] 2" in err


@pytest.mark.parametrize("other", ["./xyz.txt", ".//xyz.txt", "xyz.txt"])
def test_two_spellings_of_one_estimate_file_are_one_session_listed_twice(tmp_path, data, xyz, capsys, other):
    m = _manifest(xyz, [{"name": "a", "estimate": "xyz.txt"}, {"name": "b", "estimate": other}])
    how = "" if other == "xyz.txt" else f", 'xyz.txt' and '{other}', two spellings of one file"
    with pytest.raises(ParseError, match=r"line 7: \[\[session\]\] 1 \('a'\) and \[\[session\]\] 2 \('b'\) have the "
                       "same estimate file" + how.replace(".", r"\.")):  # fmt: skip
        ln.evaluate_manifest(m, _results(tmp_path, data, ["xyz.txt"]))
    rc, err = _cli(capsys, tmp_path / "res", "--manifest", m)
    assert rc == 2 and "same estimate file" in err and "lab.toml, line 7" in err


def test_two_estimates_naming_one_file_on_disk_are_refused(tmp_path, data, xyz, capsys):
    """Names the manifest cannot tell apart (a link, or a file system that ignores case) are found
    to be one file where the estimates are looked up."""
    m = _manifest(xyz, [{"name": "a", "estimate": "xyz.txt"}, {"name": "b", "estimate": "other.txt"}])
    res = _results(tmp_path, data, ["xyz.txt"])
    (res / "algA" / "other.txt").symlink_to("xyz.txt")
    with pytest.raises(ParseError, match=r"sessions 1 \('a', estimate = 'xyz.txt'\) and 2 \('b', estimate = "
                       r"'other.txt'\) name one file in .*algA"):  # fmt: skip
        ln.evaluate_manifest(m, res)
    rc, err = _cli(capsys, res, "--manifest", m)
    assert rc == 2 and "name one file in" in err
    (res / "algA" / "other.txt").unlink()
    shutil.copy(res / "algA" / "xyz.txt", res / "algA" / "other.txt")  # two files: two sessions, scored
    got = ln.evaluate_manifest(m, res).sequences()
    assert len(got) == 2 and got["matched"].tolist() == [int(got["matched"].iloc[0])] * 2 > [0, 0]


def test_a_lone_dotted_estimate_is_found_and_named_without_its_dot(tmp_path, data, xyz, capsys):
    m = _manifest(xyz, [{"name": "a", "estimate": "./xyz.txt"}])
    assert read_manifest(m).sessions[0].estimate == "xyz.txt"
    got = ln.evaluate_manifest(m, _results(tmp_path, data, ["xyz.txt"])).sequences()
    assert got["matched"].iloc[0] > 700
    m = _manifest(xyz, [{"name": "a", "estimate": "./nothere.txt"}])
    rc, err = _cli(capsys, tmp_path / "res", "--manifest", m)
    assert rc == 2 and "no estimate named nothere.txt in it" in err


# 2. a ROS 2 bag folder as a session's ground truth


def test_a_ros2_bag_folder_is_a_sessions_ground_truth_with_the_bag_format(tmp_path, data, xyz, capsys):
    traj = ln.read_trajectory(xyz, "tum")
    write_bag(xyz.parent / "xyz_gt_ros2", traj, 2, topic="/gt")
    (xyz.parent / "plain").mkdir()
    head = 'groundtruth_format = "bag"\ngroundtruth_topic = "/gt"\n'
    m = xyz.parent.parent / "bag.toml"
    m.write_text(head + '[[session]]\nname = "xyz"\ngroundtruth = "gt/xyz_gt_ros2"\n')
    s = read_manifest(m).sessions[0]
    assert manifest.groundtruth_refusal(s) is None
    res = _results(tmp_path, data, ["xyz.txt"])
    got = ln.evaluate_manifest(m, res).sequences()
    tum = ln.evaluate_pairs([res / "algA" / "xyz.txt"], xyz).sequences()
    assert got["matched"].iloc[0] == tum["matched"].iloc[0] > 700
    assert got["ate_rmse"].iloc[0] == pytest.approx(tum["ate_rmse"].iloc[0], rel=1e-6)
    rc, err = _cli(capsys, res, "--manifest", m)
    assert rc == 0, err
    # other folders stay refused: not a bag, or not read as one
    m.write_text(head + '[[session]]\nname = "xyz"\ngroundtruth = "gt/plain"\n')
    assert "without metadata.yaml" in str(manifest.groundtruth_refusal(read_manifest(m).sessions[0]))
    rc, err = _cli(capsys, res, "--manifest", m)
    assert rc == 2 and "ground truth of session 'xyz' is a folder" in err
    m.write_text('[[session]]\nname = "xyz"\ngroundtruth = "gt/xyz_gt_ros2"\n')
    assert "groundtruth_format = 'bag'" in str(manifest.groundtruth_refusal(read_manifest(m).sessions[0]))
    rc, err = _cli(capsys, res, "--manifest", m)
    assert rc == 2 and "is a folder" in err


# 3. an estimate below the algorithm's folder


def test_an_estimate_below_the_folder_is_found_however_the_others_lie(tmp_path, data, xyz, capsys):
    m = _manifest(xyz, [{"name": "xyz", "estimate": "sub/xyz.txt"}])
    res = _results(tmp_path, data, ["sub/xyz.txt"])
    assert holds_any(res / "algA", ["sub/xyz.txt"]) and holds_any(res / "algA", ["SUB/./xyz.txt"])
    assert not holds_any(res / "algA", ["sub/other.txt"]) and not holds_any(res, ["sub/xyz.txt"])
    got = ln.evaluate_manifest(m, res).sequences()
    assert got["algorithm"].tolist() == ["algA"] and got["matched"].iloc[0] > 700
    rc, err = _cli(capsys, res, "--manifest", m)
    assert rc == 0, err
    # a folder on the way to a session's estimate is no algorithm of its own
    m = _manifest(xyz, [{"name": "a", "estimate": "xyz.txt"}, {"name": "b", "estimate": "sub/xyz.txt"}])
    _results(tmp_path, data, ["xyz.txt"])
    got = ln.evaluate_manifest(m, res).sequences()
    assert got["algorithm"].tolist() == ["algA", "algA"] and got["file"].nunique() == 1


# 4. a manifest's own values: the file, the line, the table and the key


@pytest.mark.parametrize(
    ("conventions", "said"),
    [
        ("kitti_precision = 'double'", r"\[conventions\] kitti_precision = 'double': only for the KITTI metric "
                                       r"\(\[conventions\] preset = 'kitti'\)"),
        ("official_lifelong = true", r"\[conventions\] official_lifelong = true: .*a manifest is not an input"),
        ("tartanair_seed = 3", r"\[conventions\] tartanair_seed = 3: only for TartanAir's metrics"),
        ("repair_stamps = true", r"\[conventions\] repair_stamps = true: only OpenLORIS result files .* the "
                                 r"manifest's estimates are tum files"),
        ("eps = 'paper'", r"\[conventions\] eps = 'paper': the paper's 1/3/5 m are for the OpenLORIS scenes; scene "
                          r"'lab' is not one"),
    ],
)  # fmt: skip
def test_a_manifests_own_value_that_cannot_apply_names_the_file_line_and_key(
    tmp_path, data, xyz, capsys, conventions, said
):
    m = _manifest(xyz, [{"name": "xyz"}], head=f"[conventions]\n{conventions}\n\n")
    with pytest.raises(ParseError, match=r"lab.toml, line 2: " + said):
        read_manifest(m)
    rc, err = _cli(capsys, _results(tmp_path, data, ["xyz.txt"]), "--manifest", m)
    assert rc == 2 and "lab.toml, line 2: [conventions]" in err and not err.startswith("error: --")


def test_eps_paper_at_the_top_is_named_there_and_is_kept_for_openloris_scenes(data, xyz):
    m = _manifest(xyz, [{"name": "xyz"}], head="eps = 'paper'\n")
    with pytest.raises(ParseError, match=r"line 1: eps = 'paper': the paper's"):
        read_manifest(m)
    m = _manifest(xyz, [{"name": "xyz"}], head="eps = 'paper'\nscene = 'cafe'\n[conventions]\npreset = 'kitti'\n"
                  "kitti_precision = 'double'\n")  # fmt: skip
    assert read_manifest(m).spec.eps == "paper"
