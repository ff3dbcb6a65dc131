"""Test helpers: synthetic trajectories and a small OpenLORIS-format fixture (no ../shared/data
needed), and the few lines that read a real result file with its ground truth."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from lorisnb.core import FileErrors, ResultFile, Trajectory, compute_errors
from lorisnb.io import load_groundtruth, read_openloris, scene_durations


def write(tmp_path: Path, name: str, text: str | bytes) -> Path:
    """Write ``text`` to ``tmp_path/name`` (folders created) and return the path."""
    p = tmp_path / name
    p.parent.mkdir(parents=True, exist_ok=True)
    if isinstance(text, bytes):
        p.write_bytes(text)
    else:
        p.write_text(text)
    return p


def errors_of(
    path: str | os.PathLike[str] | ResultFile,
    groundtruth: ResultFile | None = None,
    *,
    data_root=None,
    remove_repeated: bool = True,
    repair_stamps: bool = False,
    **kw,
) -> FileErrors:
    """Read a result file and compute its errors against its scene's ground truth (raises on bad
    input, unlike lorisnb.evaluate, which collects failures)."""
    if isinstance(path, ResultFile):
        result = path
    else:
        result = read_openloris(path, remove_repeated=remove_repeated, warn=False, repair_stamps=repair_stamps)
    gt = groundtruth if groundtruth is not None else load_groundtruth(result.scene, data_root, remove_repeated)
    kw.setdefault("algorithm", result.path.parent.name)
    return compute_errors(result, gt, **kw)


def durations_of(*files: FileErrors):
    """Ground-truth durations of the scenes of ``files`` (from the shared data)."""
    return scene_durations(sorted({f.scene for f in files}))


def circle(n: int = 200, rate_hz: float = 10.0, radius_m: float = 5.0, t0: float = 1000.0) -> Trajectory:
    """A synthetic ground truth: a robot driving a circle at constant speed, heading along the path."""
    t = t0 + np.arange(n) / rate_hz
    ang = np.linspace(0, 2 * np.pi, n, endpoint=False)
    pos = np.column_stack([radius_m * np.cos(ang), radius_m * np.sin(ang), np.zeros(n)])
    rot = Rotation.from_euler("z", (ang + np.pi / 2)[:, None])
    return Trajectory.from_rotations(t, pos, rot)


def perturbed(gt: Trajectory, position_m: float = 0.0, yaw_deg: float = 0.0, seed: int = 0) -> Trajectory:
    """``gt`` with white position noise (std per axis, metres) and a constant yaw error."""
    rng = np.random.default_rng(seed)
    pos = gt.positions + rng.normal(0, position_m, gt.positions.shape) if position_m else gt.positions.copy()
    rot = Rotation.from_euler("z", yaw_deg, degrees=True) * gt.rotations() if yaw_deg else gt.rotations()
    return Trajectory.from_rotations(gt.stamps.copy(), pos, rot)


def openloris_text(sequences: dict[int, Trajectory], scene: str = "cafe", frame: str = "base_link") -> str:
    """A small file in OpenLORIS format (``scene:``, ``frame:``, ``seq: N`` blocks)."""
    lines = [f"scene: {scene}", f"frame: {frame}"]
    for s, t in sorted(sequences.items()):
        lines.append(f"seq: {s}")
        lines += [" ".join(f"{v:.9f}" for v in row) for row in np.column_stack([t.stamps, t.positions, t.quaternions])]
    return "\n".join(lines) + "\n"


def openloris_fixture(tmp_path: Path) -> tuple[Path, Path]:
    """A ground truth (two sequences of a circle) and an estimate file in OpenLORIS format, written
    to ``tmp_path``: (ground-truth path, estimate path). The estimate of seq 1 has 0.05 m noise,
    seq 2 a 40-degree yaw error from its 100th pose on."""
    gt1, gt2 = circle(), circle(t0=2000.0)
    est2 = perturbed(gt2)
    rot = est2.rotations()
    wrong = Rotation.from_euler("z", 40, degrees=True)
    q = np.vstack([rot[:100].as_quat(), (wrong * rot[100:]).as_quat()])
    est2 = Trajectory(est2.stamps, est2.positions, q)
    gt = write(tmp_path, "gt_cafe_1.txt", openloris_text({1: gt1, 2: gt2}))
    est = write(tmp_path, "synthetic/cafe.txt", openloris_text({1: perturbed(gt1, 0.05), 2: est2}))
    return gt, est
