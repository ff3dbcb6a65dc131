"""Manifest inputs (s68): KITTI estimates with their times files (``estimate_times``,
``groundtruth_times``), and a session whose estimate cannot be read failing alone."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from lorisnb.errors import ParseError
from lorisnb.io.datasets.manifest import read_manifest
from lorisnb.tools.evaluation.runner import evaluate_manifest


@pytest.fixture(scope="module")
def xyz(fr1_xyz_groundtruth) -> Path:
    return fr1_xyz_groundtruth


def _kitti(gt: Path, folder: Path, n: int = 300) -> tuple[Path, Path]:
    """The first ``n`` poses of a TUM ground truth written as KITTI poses and a times file."""
    rows = np.loadtxt(gt, comments="#")[:n]
    R = Rotation.from_quat(rows[:, 4:8]).as_matrix()
    m = np.concatenate([R, rows[:, 1:4, None]], axis=2).reshape(n, 12)
    folder.mkdir(parents=True, exist_ok=True)
    np.savetxt(folder / "xyz.txt", m, fmt="%.9f")
    times = folder.parent / "times.txt"
    times.write_text("".join(f"{t:.6f}\n" for t in rows[:, 0]))
    return folder / "xyz.txt", times


def _manifest(tmp_path: Path, gt: Path, extra: str = "") -> Path:
    (tmp_path / "xyz_gt.txt").write_text(gt.read_text())
    path = tmp_path / "m.toml"
    path.write_text(
        'scene = "tum"\nestimate_format = "kitti"\n[conventions]\npreset = "evo"\n'
        f'[[session]]\nname = "xyz"\ngroundtruth = "xyz_gt.txt"\n{extra}'
    )
    return path


def test_kitti_estimates_with_their_times_file_are_scored(tmp_path, xyz):
    _kitti(xyz, tmp_path / "res" / "algK")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ev = evaluate_manifest(_manifest(tmp_path, xyz, 'estimate_times = "res/times.txt"\n'), tmp_path / "res")
    assert not ev.failures
    (seq,) = ev.errors[0].sequences
    assert seq.poses == 300 and seq.matched == 300
    assert float(np.max(seq.ate)) < 1e-6  # the ground truth itself


def test_kitti_without_times_names_the_manifest_key(tmp_path, xyz):
    _kitti(xyz, tmp_path / "res" / "algK")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ev = evaluate_manifest(_manifest(tmp_path, xyz), tmp_path / "res")
    (f,) = ev.failures
    assert "estimate_times = 'FILE'" in f.error and "--est-times" not in f.error


def test_times_keys_are_checked_as_the_command_line_checks_them(tmp_path, xyz):
    path = _manifest(tmp_path, xyz, 'groundtruth_times = "times.txt"\n')
    with pytest.raises(ParseError, match=r"line 8: \[\[session\]\] 1 \('xyz'\): groundtruth_times: only for kitti"):
        read_manifest(path)
    path.write_text(path.read_text().replace("groundtruth_times", "estimate_times").replace("times.txt", "../x.txt"))
    with pytest.raises(ParseError, match="estimate_times lies outside"):
        read_manifest(path)


def test_a_session_that_cannot_be_read_fails_alone(tmp_path, xyz):
    (tmp_path / "xyz_gt.txt").write_text(xyz.read_text())
    (tmp_path / "m.toml").write_text(
        '[[session]]\nname = "a"\ngroundtruth = "xyz_gt.txt"\n[[session]]\nname = "b"\ngroundtruth = "xyz_gt.txt"\n'
    )
    alg = tmp_path / "res" / "algX"
    alg.mkdir(parents=True)
    lines = [ln for ln in xyz.read_text().splitlines() if not ln.startswith("#")]
    (alg / "a.txt").write_text("\n".join(lines) + "\n")
    lines[49] = lines[49].replace(".", "x", 1)
    (alg / "b.txt").write_text("\n".join(lines) + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ev = evaluate_manifest(tmp_path / "m.toml", tmp_path / "res")
    (f,) = ev.failures
    assert f.path.name == "b.txt" and "line 50" in f.error
    (errors,) = ev.errors  # algX is in the table, with its good session
    assert [(s.seq, s.matched) for s in errors.sequences] == [(1, len(lines))]
    assert ev.exit_status() == 1


@pytest.mark.parametrize(
    ("where", "key", "value", "line"),
    [(None, "eps", '"0.05"', 1), ("conventions", "tau", '"60"', 3), ("conventions", "rpe_delta", '" 1"', 3)],
)
def test_a_number_in_quotes_is_refused(tmp_path, where, key, value, line):
    (tmp_path / "gt.txt").write_text("0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n")
    body = f"{key} = {value}\n" if where is None else ""
    body += '[conventions]\npreset = "evo"\n' + (f"{key} = {value}\n" if where else "")
    (tmp_path / "m.toml").write_text(body + '[[session]]\nname = "a"\ngroundtruth = "gt.txt"\n')
    with pytest.raises(ParseError, match=rf"line {line}: .*{key} = .*: a number in quotes is text; write it without"):
        read_manifest(tmp_path / "m.toml")


def test_documented_words_stay_accepted(tmp_path):
    (tmp_path / "gt.txt").write_text("0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n")
    (tmp_path / "m.toml").write_text('eps = "relative:0.1"\n[[session]]\nname = "a"\ngroundtruth = "gt.txt"\n')
    assert read_manifest(tmp_path / "m.toml").spec.eps == "relative:0.1"
