"""The orientation check names a quaternion-order mistake only where the input's format allows one
(:attr:`lorisnb.io.readers.registry.Format.quaternions`). A TUM file read ``qx qy qz qw`` whose
orientations fit with the components moved the other way (a ground truth in TartanAir's NED frame
against a camera-frame estimate, aligned without rotation) was told its quaternions were written
``qw qx qy qz`` and to rewrite it as a EuRoC CSV; a KITTI file (matrices) was told to write
``qx qy qz qw``. Real data: fr1/xyz's ground truth and RGBD-SLAM's estimate."""

from __future__ import annotations

import warnings

import numpy as np
from scipy.spatial.transform import Rotation

import lorisnb as ln
from lorisnb.errors import LorisWarning

#: TartanAir's camera-to-NED axes (x_ned = z_cam, y_ned = x_cam, z_ned = y_cam).
CAM2NED = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


def _write_tum(path, stamps, positions, quaternions):
    rows = [
        " ".join(repr(float(v)) for v in (s, *p, *q)) for s, p, q in zip(stamps, positions, quaternions, strict=True)
    ]
    path.write_text("\n".join(rows) + "\n")


def _notes(est, gt, **options) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        ln.evaluate_pairs(est, gt, progress=False, **options)
    return [str(w.message) for w in caught if issubclass(w.category, LorisWarning)]


def test_a_ned_groundtruth_is_told_as_another_frame_not_a_quaternion_order(data, tmp_path):
    gt = ln.read_tum(data.tum / "freiburg1_xyz-groundtruth.txt")
    r = Rotation.from_matrix(CAM2NED)
    ned = tmp_path / "gt_ned.txt"  # T P T^-1: the ground truth's poses in NED axes
    _write_tum(ned, gt.stamps, gt.positions @ CAM2NED.T, (r * Rotation.from_quat(gt.quaternions) * r.inv()).as_quat())
    notes = _notes(data.tum / "freiburg1_xyz-rgbdslam.txt", ned, fmt="tum", gt_fmt="tum", spec="tartanair")
    said = [n for n in notes if "moved one place" in n]
    assert len(said) == 1 and "which no quaternion order explains (its format writes 'qx qy qz qw'" in said[0]
    assert "another frame than the ground truth's" in said[0]
    assert not any("quaternions look like" in n or "timestamp_ns" in n for n in notes), notes


def test_a_tum_file_written_w_first_is_still_told_its_order(data, tmp_path):
    est = ln.read_tum(data.tum / "freiburg1_xyz-rgbdslam.txt")
    f = tmp_path / "wxyz.txt"  # 'stamp x y z qw qx qy qz' in a TUM file
    _write_tum(f, est.stamps, est.positions, np.roll(est.quaternions, 1, axis=1))
    notes = _notes(f, data.tum / "freiburg1_xyz-groundtruth.txt", fmt="tum", gt_fmt="tum")
    assert any("the quaternions look like 'qw qx qy qz' instead of 'qx qy qz qw'" in n and "real part last" in n
               for n in notes), notes  # fmt: skip
    assert not any("moved one place" in n for n in notes)


def test_a_kitti_file_is_never_told_to_reorder_quaternions(data, tmp_path):
    """KITTI files hold matrices: rotations that fit with a quaternion's components moved are
    another frame's, said as such (the old note told it to write 'stamp x y z qx qy qz qw')."""
    est = ln.read_tum(data.tum / "freiburg1_xyz-rgbdslam.txt")
    moved = Rotation.from_quat(np.roll(est.quaternions, 1, axis=1)).as_matrix()  # written w first, as matrices
    blocks = np.concatenate([moved, est.positions[:, :, None]], axis=2).reshape(-1, 12)
    f = tmp_path / "est.kitti"
    f.write_text("\n".join(" ".join(repr(float(v)) for v in row) for row in blocks) + "\n")
    times = tmp_path / "times.txt"
    times.write_text("\n".join(repr(float(s)) for s in est.stamps) + "\n")
    notes = _notes(f, data.tum / "freiburg1_xyz-groundtruth.txt", fmt="kitti", gt_fmt="tum", est_times=times)
    assert not any("quaternions look like" in n for n in notes), notes
    said = [n for n in notes if "moved one place" in n]
    assert len(said) == 1 and "its format writes no quaternion" in said[0], notes
