"""A manifest received from someone else reads ground truth only inside its own folder and its
root (links resolved), unless --manifest-outside / outside=True says otherwise, and no error
quotes a file outside them."""

from __future__ import annotations

import shutil

import pytest

from lorisnb.cli import main
from lorisnb.errors import ParseError
from lorisnb.io.datasets.manifest import read_manifest

SECRET = "secret-first-line 1 2 3\n"


def manifest(folder, groundtruth, root="."):
    folder.mkdir(parents=True, exist_ok=True)
    p = folder / "lab.toml"
    p.write_text(
        f'root = "{root}"\nestimate_format = "tum"\n[[session]]\nname = "desk"\ngroundtruth = "{groundtruth}"\n'
    )
    return p


@pytest.fixture
def secret(tmp_path):
    p = tmp_path / "private" / "notes.txt"
    p.parent.mkdir()
    p.write_text(SECRET)
    return p


@pytest.mark.parametrize("how", ["dotdot", "absolute", "link"])
def test_ground_truth_outside_the_manifest_folder_and_root_is_refused_unread(tmp_path, secret, capsys, how):
    folder = tmp_path / "shared" / "m"
    gt = {"dotdot": "../../private/notes.txt", "absolute": str(secret), "link": "gt.txt"}[how]
    m = manifest(folder, gt)
    if how == "link":
        (folder / "gt.txt").symlink_to(secret)
    with pytest.raises(ParseError, match="groundtruth lies outside the manifest's folder, its root"):
        read_manifest(m)
    res = tmp_path / "res" / "alg"
    res.mkdir(parents=True)
    (res / "desk.txt").write_text("1 0 0 0 0 0 0 1\n")
    rc = main(["evaluate", str(res.parent), "--manifest", str(m), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and "outside the manifest's folder" in err and "secret-first-line" not in err
    assert read_manifest(m, outside=True).sessions[0].groundtruth.name in ("notes.txt", "gt.txt")
    rc = main(["evaluate", str(res.parent), "--manifest", str(m), "--manifest-outside", "--no-progress"])
    assert "outside the manifest's folder" not in capsys.readouterr().err  # read, as asked


def test_ground_truth_in_the_root_or_the_manifest_folder_is_read(tmp_path, data, capsys):
    tum = data.root / "tum-rgbd"
    m = manifest(tmp_path / "m", "fr2_desk_groundtruth.txt", root=str(tum))
    assert read_manifest(m).sessions[0].groundtruth == (tum / "fr2_desk_groundtruth.txt").resolve()
    shutil.copy(tum / "fr2_desk_groundtruth.txt", tmp_path / "m" / "gt.txt")
    read_manifest(manifest(tmp_path / "m", "gt.txt"))
    res = tmp_path / "res" / "orb"
    res.mkdir(parents=True)
    shutil.copy(tum / "fr2_desk_ORB.txt", res / "desk.txt")
    rc = main(["evaluate", str(res.parent), "--manifest", str(m), "--no-progress"])
    out = capsys.readouterr().out
    assert rc == 0 and "orb" in out and "1/1" in out  # the session scored


def test_manifest_outside_needs_a_manifest(capsys, tmp_path):
    rc = main(["evaluate", str(tmp_path), "--manifest-outside", "--no-progress"])
    assert rc == 2 and "--manifest-outside: applies to" in capsys.readouterr().err


def test_a_root_written_in_the_manifest_elsewhere_is_refused_one_from_the_environment_is_not(
    tmp_path, secret, monkeypatch, capsys
):
    m = manifest(tmp_path / "shared" / "m", "notes.txt", root=str(secret.parent))
    with pytest.raises(ParseError, match="root = .* lies outside the manifest's folder"):
        read_manifest(m)
    monkeypatch.setenv("LAB_ROOT", str(secret.parent))  # the user's own setting: trusted
    m = manifest(tmp_path / "shared" / "m", "notes.txt", root="${LAB_ROOT}")
    assert read_manifest(m).sessions[0].groundtruth == secret.resolve()
