"""A manifest session's estimate is a file of each algorithm's folder: one written as an absolute
path or leaving the folder is refused (``estimate = "/etc/passwd"`` was read and called 'a link to
/etc/passwd', though no link); a link to nothing says the same inside and outside the results folder."""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import ParseError


def _manifest(tmp_path: Path, gt: Path) -> Path:
    """A manifest of one session (fr2_desk's ground truth ``gt``, beside it) and a results folder."""
    est = tmp_path / "results" / "orb"
    est.mkdir(parents=True, exist_ok=True)
    shutil.copy(tmp_path / "orb.txt", est / "desk.txt")
    m = tmp_path / "m.toml"
    m.write_text(f'name = "t"\nscene = "tum"\n[[session]]\nname = "desk"\ngroundtruth = "{gt.name}"\n')
    return m


@pytest.fixture
def est(tmp_path, data) -> Path:
    path = tmp_path / "orb.txt"
    shutil.copy(data.tum / "fr2_desk_ORB.txt", path)
    return path


def test_a_manifest_estimate_outside_the_algorithm_folder_is_refused(tmp_path, data, est):
    """``estimate = "/etc/passwd"`` was read and called 'a link to /etc/passwd' (it is not a link)."""
    shutil.copy(data.tum / "fr2_desk_groundtruth.txt", tmp_path / "gt.txt")
    m = _manifest(tmp_path, tmp_path / "gt.txt")
    for estimate in ("/etc/passwd", "../../../etc/passwd", ".."):
        m.write_text(m.read_text().split("[[session]]")[0]
                     + f'[[session]]\nname = "desk"\ngroundtruth = "gt.txt"\nestimate = "{estimate}"\n')  # fmt: skip
        with pytest.raises(
            ParseError, match=r"\[\[session\]\] desk: estimate = .* lies outside the algorithm's folder"
        ):
            ln.evaluate_manifest(m, tmp_path / "results")


def test_a_dangling_link_says_the_same_inside_and_outside(tmp_path, data, icra20):
    """A link to nothing outside the results folder said 'not a trajectory file as expected';
    one inside said 'which does not exist'."""
    res = tmp_path / "res" / "orb"
    res.mkdir(parents=True)
    good = icra20 / "per-seq" / "orbslam2_rgbd" / "cafe_1_1_orbslam2-original.txt"
    (res / good.name).symlink_to(good)
    (res / "cafe_1_2.txt").symlink_to(tmp_path / "moved" / "cafe_1_2.txt")  # outside res
    (res / "cafe_1_3.txt").symlink_to(res / "gone.txt")  # inside
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ev = ln.evaluate(tmp_path / "res", data_root=data)
    errors = sorted(f.error for f in ev.failures)
    assert len(errors) == 2 and all("which does not exist; expected" in e for e in errors)
    assert not any("not a trajectory file" in e for e in errors)


@pytest.mark.parametrize("kind", ["missing", "folder"])
def test_a_manifest_ground_truth_that_is_no_file_stops_the_call_before_any_work(tmp_path, data, est, kind, capsys):
    """A session's ground truth that is missing and one that is a folder are the same error, of the
    whole call, before anything is scored (a folder failed the whole algorithm, exit 1, while a missing
    file stopped the call, exit 2); the command line exits 2 for both."""
    gt = tmp_path / "gt.txt"
    if kind == "folder":
        gt.mkdir()
    m = _manifest(tmp_path, gt)
    what = "is a folder" if kind == "folder" else "not found"
    with pytest.raises(ParseError, match=rf"ground truth of session 'desk' {what}; expected a trajectory file"):
        ln.evaluate_manifest(m, tmp_path / "results")
    assert main(["evaluate", str(tmp_path / "results"), "--manifest", str(m), "--no-progress"]) == 2
    assert f"ground truth of session 'desk' {what}" in capsys.readouterr().err
