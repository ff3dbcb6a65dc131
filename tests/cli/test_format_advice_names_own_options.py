"""The advice on a file in another format names options the command printing it really has:
``consistency`` has only ``--gt-format`` (it advised ``--format tum``), ``crosscheck`` has
``--format`` (the ground truth, and the estimate) and ``--est-format`` (it advised ``--gt-format``), a
manifest names its formats in its own keys (``--format`` is refused with ``--manifest``); evaluate's
pairs keep the readers' advice (adversarial finding 7)."""

from __future__ import annotations

import shutil

import pytest

from lorisnb.cli import build_parser, main

TUM = "tum-rgbd"


def _err(argv: list[str], capsys) -> tuple[int, str]:
    capsys.readouterr()
    rc = main(argv)
    return rc, capsys.readouterr().err


def _options(command: str) -> set[str]:
    parser = build_parser()
    sub = parser._subparsers._group_actions[0].choices[command]  # argparse has no public accessor
    return {o for a in sub._actions for o in a.option_strings}


@pytest.mark.parametrize("fmt", ["openloris", "kitti", "euroc"])
def test_consistency_advises_its_gt_format(data, fmt, capsys):
    est, gt = str(data.root / TUM / "fr2_desk_ORB.txt"), str(data.root / TUM / "fr2_desk_groundtruth.txt")
    rc, err = _err(["consistency", est, gt, "--gt-format", fmt], capsys)
    assert rc == 1
    assert "this looks like a TUM trajectory file" in err and "read it with --gt-format tum (fmt='tum'" in err
    assert "--format tum" not in err
    assert "--gt-format" in _options("consistency") and "--format" not in _options("consistency")


def test_crosscheck_advises_its_own_options(data, capsys):
    est, gt = str(data.root / TUM / "fr2_desk_ORB.txt"), str(data.root / TUM / "fr2_desk_groundtruth.txt")
    rc, err = _err(["crosscheck", gt, est, "--format", "kitti"], capsys)  # the ground truth is read first
    assert rc == 1 and "read it with --format tum (fmt='tum'" in err and "--gt-format" not in err, err
    rc, err = _err(["crosscheck", gt, est, "--est-format", "euroc"], capsys)
    assert rc == 1 and "fr2_desk_ORB.txt: expected the euroc format" in err, err
    assert "read it with --est-format tum (fmt='tum'" in err and "--gt-format" not in err, err
    assert {"--format", "--est-format"} <= _options("crosscheck") and "--gt-format" not in _options("crosscheck")


def test_a_manifest_run_advises_the_manifest_keys(data, tmp_path, capsys):
    (tmp_path / "orb").mkdir()
    shutil.copy(data.root / TUM / "fr2_desk_ORB.txt", tmp_path / "orb" / "desk.txt")
    shutil.copy(data.root / TUM / "fr2_desk_groundtruth.txt", tmp_path / "gt.txt")
    (tmp_path / "m.toml").write_text('estimate_format = "euroc"\n[[session]]\nname = "desk"\ngroundtruth = "gt.txt"\n'
                                     'estimate = "desk.txt"\n')  # fmt: skip
    rc, err = _err(["evaluate", str(tmp_path / "orb"), "--manifest", str(tmp_path / "m.toml"), "--no-progress"], capsys)
    assert rc == 1
    assert "read it with estimate_format = 'tum' in the manifest (fmt='tum'" in err  # the estimate's key: its side
    assert "groundtruth_format" not in err
    assert "--format" not in err.split("conventions:")[1]


def test_a_pair_keeps_the_readers_advice(data, capsys):
    est, gt = str(data.root / TUM / "fr2_desk_ORB.txt"), str(data.root / TUM / "fr2_desk_groundtruth.txt")
    rc, err = _err(["evaluate", est, "--gt", gt, "--gt-format", "kitti", "--no-progress"], capsys)
    assert rc == 1 and "read it with --format tum (--gt-format tum for the ground truth;" in err, err
