"""KITTI files written with few decimals (``np.savetxt(fmt='%.3f')``): their rotation blocks are off
by up to about 1.4e-3, past the reader's tolerance, and were refused as "not a rotation" although
the KITTI devkit, kitti-odom-eval and evo score them. A block that is a rotation rounded to the
decimals written is now read (its nearest rotation, the blocks kept as written for the devkit's
conventions), said once per file; a block that rounding cannot explain is refused as before, its
message naming how far it is off."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from lorisnb.core.trajectory.poses import written_blocks
from lorisnb.errors import LorisWarning, ParseError
from lorisnb.io import read_kitti, read_tum
from lorisnb.io.readers.plain import ROTATION_TOLERANCE, rounded_rotations


def _kitti(data, tmp_path, decimals: int):
    """fr2/desk's real ground truth as a KITTI file printed with ``decimals`` decimals."""
    gt = read_tum(data.tum / "fr2_desk_groundtruth.txt", warn=False)
    mats = np.concatenate([Rotation.from_quat(gt.quaternions).as_matrix(), gt.positions[:, :, None]], axis=2)
    path = tmp_path / f"poses_{decimals}.txt"
    np.savetxt(path, mats.reshape(-1, 12), fmt=f"%.{decimals}f")
    return path, np.loadtxt(path).reshape(-1, 3, 4)


@pytest.mark.parametrize("decimals", [3, 4])
def test_a_file_of_few_decimals_is_read_as_its_rotations(data, tmp_path, decimals):
    path, printed = _kitti(data, tmp_path, decimals)
    blocks = printed[:, :, :3]
    off = np.abs(np.einsum("nij,nkj->nik", blocks, blocks) - np.eye(3)).max(axis=(1, 2))
    assert (off > ROTATION_TOLERANCE).sum() > 100 or decimals > 3  # 3 decimals: refused, "line N: not a rotation"
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        traj = read_kitti(path)
    said = [str(w.message) for w in seen if issubclass(w.category, LorisWarning)]
    if decimals == 3:
        assert len(said) == 1 and "written with 3 decimals" in said[0] and str(path) in said[0]
    assert len(traj) == len(printed)
    np.testing.assert_array_equal(written_blocks(traj), blocks)  # composed as written under --conventions kitti
    nearest = Rotation.from_matrix(blocks).as_matrix()  # scipy's nearest rotation (an SVD per block)
    np.testing.assert_allclose(Rotation.from_quat(traj.quaternions).as_matrix(), nearest, atol=1e-12)


def test_two_decimals_are_too_coarse_for_a_rotation(data, tmp_path):
    path, _ = _kitti(data, tmp_path, 2)
    with pytest.raises(ParseError, match=r"not a rotation .*off by .*write 6 or more"):
        read_kitti(path)


def test_a_block_rounding_cannot_explain_is_still_refused_saying_how_far_off(tmp_path):
    rows = ["1.000 0.000 0.000 %d.000 0.000 1.000 0.000 0.000 0.000 0.000 1.000 0.000" % k for k in range(50)]
    rows[30] = "1.000 0.000 0.000 1.000 0.000 1.000 0.000 0.000 0.000 0.000 1.002 0.000"  # scaled by 2 half-units
    path = tmp_path / "scaled.txt"
    path.write_text("\n".join(rows) + "\n")
    with pytest.raises(ParseError, match=r"line 31: not a rotation") as err:
        read_kitti(path)
    assert "off by 0.004" in str(err.value)


def test_rounded_rotations_tells_rounding_from_a_scale():
    rng = np.random.default_rng(4)
    rot = Rotation.random(20000, random_state=rng.integers(1 << 31)).as_matrix()
    for d in (3, 4, 6):
        b = np.round(rot, d)
        q = Rotation.from_matrix(b).as_quat()
        ok, decimals = rounded_rotations(b.reshape(-1, 9), q)
        assert ok.all() and (decimals <= d).all()
    for scaled in (np.diag([1, 1, 1.01]), np.diag([1, 1, 1.002]), np.diag([1, 1, -1.0])):
        q = Rotation.from_matrix(np.eye(3)).as_quat()[None]
        assert not rounded_rotations(scaled.reshape(1, 9), q)[0][0]
