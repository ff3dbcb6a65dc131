"""The compiled rotation kernel (``lorisnb/core/trajectory/_rotations.c``) against the numpy code it mirrors
(``lorisnb.core.trajectory.rotations._rotation_run``): the same quaternion and distance bits for every block
(exact, printed to 3-12 digits, noisy, far from any rotation, huge, zero, non-finite, ties), and
the same trajectories from real files read as KITTI."""

from __future__ import annotations

import shutil
import sysconfig

import numpy as np
import pytest
from helpers import use_parser
from scipy.spatial.transform import Rotation

from lorisnb.core.trajectory import rotations as matrices
from lorisnb.io import read_kitti, read_tum

needs_kernel = pytest.mark.skipif(matrices._kernel is None, reason="lorisnb.core.trajectory._rotations was not built")


def _compiler() -> str | None:
    cc = (sysconfig.get_config_var("CC") or "cc").split()[0]
    return shutil.which(cc)


def test_the_install_built_the_kernel_where_a_compiler_is():
    """setuptools builds the extension as optional: a machine with a C compiler must not lose it
    silently (the numpy code would give the same numbers, at about twice the time, holding the GIL)."""
    if _compiler() is None:
        pytest.skip("no C compiler here: the numpy code is used")
    assert matrices._kernel is not None, "reinstall (make bytecode): lorisnb/core/trajectory/_rotations.c was not built"


def _both(blocks: np.ndarray):
    with np.errstate(all="ignore"):
        q, off = matrices.rotation_blocks(blocks)
        kernel, matrices._kernel = matrices._kernel, None
        try:
            qn, offn = matrices.rotation_blocks(blocks)
        finally:
            matrices._kernel = kernel
    return (q, off), (qn, offn)


def _same_bits(a: np.ndarray, b: np.ndarray) -> None:
    nan = np.isnan(a)
    np.testing.assert_array_equal(nan, np.isnan(b))
    np.testing.assert_array_equal(a.view(np.uint64)[~nan], b.view(np.uint64)[~nan])


def _cases() -> dict[str, np.ndarray]:
    rng = np.random.default_rng(17)
    r = Rotation.random(30_000, random_state=19).as_matrix()
    cases = {"exact": r, "near exact": r + rng.normal(0, 1e-14, r.shape)}
    cases.update({f"{d} digits": np.round(r, d) for d in (3, 5, 6, 7, 9, 12)})
    cases["noise 1e-3"] = r + rng.normal(0, 1e-3, r.shape)
    cases["far"] = r + rng.normal(0, 0.3, r.shape)
    cases["random"] = rng.normal(0, 1, r.shape)
    odd = np.round(r, 6)
    odd[::3] = r[::3]  # exact and 6-digit blocks in one run
    odd[1::7] *= 1e200
    odd[2::11, 0, 0] = np.nan
    odd[3::13, 1, 2] = np.inf
    odd[4::17] = 0.0
    odd[5::19] = -r[5::19]  # reflections
    odd[6::23] *= 1.01
    cases["mixed and odd"] = odd
    turns = Rotation.from_euler(
        "xyz", [[a, b, c] for a in (0, 90, 180, -90) for b in (0, 90, 180) for c in (0, 45, 180)], degrees=True
    )
    cases["turns (ties of diagonal and trace)"] = np.concatenate([turns.as_matrix(), np.round(turns.as_matrix(), 6)])
    return cases


@needs_kernel
@pytest.mark.parametrize("name", list(_cases()))
def test_kernel_gives_the_numpy_codes_bits(name):
    (q, off), (qn, offn) = _both(_cases()[name])
    _same_bits(q, qn)
    _same_bits(off, offn)


@needs_kernel
@pytest.mark.parametrize("parser", ["pieces", "blocks", "chunks"])
@pytest.mark.thorough
def test_real_trajectories_read_as_kitti_the_same_with_and_without_the_kernel(data, tmp_path, monkeypatch, parser):
    """The TUM RGB-D ground truth and estimates, printed as KITTI blocks to 6 and 9 significant
    digits (as KITTI tools write them), read the same by either route, on pieces or in chunks."""
    use_parser(monkeypatch, parser)
    for name in ("fr2_desk_groundtruth.txt", "freiburg1_xyz-rgbdslam.txt", "fr2_desk_ORB.txt"):
        t = read_tum(data.tum / name)
        blocks = np.concatenate([Rotation.from_quat(t.quaternions).as_matrix(), t.positions[:, :, None]], axis=2)
        for digits in (6, 9):
            path = tmp_path / f"{name}.{digits}.kitti"
            np.savetxt(path, blocks.reshape(-1, 12), fmt=f"%.{digits - 1}e")
            with_kernel = read_kitti(path)
            kernel, matrices._kernel = matrices._kernel, None
            try:
                without = read_kitti(path)
            finally:
                matrices._kernel = kernel
            _same_bits(with_kernel.quaternions, without.quaternions)
            np.testing.assert_array_equal(with_kernel.positions, without.positions)
            printed = np.loadtxt(path).reshape(-1, 3, 4)[:, :, :3]
            scipy = Rotation.from_matrix(printed).as_quat()  # its SVD projection: ~3e-15 from the nearest rotation
            sign = np.sign((with_kernel.quaternions * scipy).sum(axis=1))[:, None]
            np.testing.assert_allclose(with_kernel.quaternions * sign, scipy, rtol=0, atol=1e-14)


@needs_kernel
def test_kernel_refuses_what_it_cannot_read():
    n = 5
    entries = [np.zeros(n) for _ in range(9)]
    thresholds = matrices._STEP_THRESHOLDS
    q, off = np.empty((n, 4)), np.empty(n)
    matrices._kernel(entries, thresholds, q, off)  # zero blocks: K + I = I, one from a rotation
    assert (q == [1, 0, 0, 0]).all() and (off == 1).all()
    with pytest.raises(ValueError, match="9 arrays"):
        matrices._kernel(entries[:8], thresholds, q, off)
    with pytest.raises(ValueError, match="float64"):
        matrices._kernel([e.astype(np.float32) for e in entries], thresholds, q, off)
    with pytest.raises(ValueError, match="20 contiguous"):
        matrices._kernel(entries, thresholds, np.empty((n + 1, 4)), off)
    with pytest.raises(ValueError, match="12 contiguous"):
        matrices._kernel(entries, thresholds[:5], q, off)
    with pytest.raises(ValueError, match="contiguous"):
        matrices._kernel(entries, thresholds, q, np.empty(2 * n)[::2])
