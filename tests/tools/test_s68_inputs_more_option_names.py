"""Messages about a manifest's inputs name the manifest's keys, not the command line's options
(s68): the stamp-unit check takes the names of its caller (a manifest session's estimate in
nanoseconds said ``--format euroc``, which a manifest refuses), and the index pairing of KITTI
files without times names ``estimate_times`` / ``groundtruth_times``."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from lorisnb.core.alignment.index_pairs import by_index
from lorisnb.core.spec.evalspec import make_spec
from lorisnb.core.trajectory.units import check_stamp_units
from lorisnb.errors import EvaluationError, ValidationError
from lorisnb.io.readers.plain import read_trajectory
from lorisnb.tools.evaluation.runner import evaluate_manifest


@pytest.fixture(scope="module")
def xyz(fr1_xyz_groundtruth) -> Path:
    return fr1_xyz_groundtruth


def test_a_session_in_nanoseconds_names_estimate_format(tmp_path, xyz):
    rows = np.loadtxt(xyz, comments="#")[:300]
    (tmp_path / "res" / "algA").mkdir(parents=True)
    np.savetxt(tmp_path / "res" / "algA" / "xyz.txt", np.column_stack([np.round(rows[:, 0] * 1e9), rows[:, 1:]]),
               fmt=["%d"] + ["%.6f"] * 7)  # fmt: skip
    (tmp_path / "xyz_gt.txt").write_text(xyz.read_text())
    m = tmp_path / "m.toml"
    m.write_text('scene = "tum"\n[[session]]\nname = "xyz"\ngroundtruth = "xyz_gt.txt"\n')
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ev = evaluate_manifest(m, tmp_path / "res")
    (f,) = ev.failures
    assert "nanoseconds" in f.error
    assert f"estimate_format = 'euroc' in {m}" in f.error and "--format" not in f.error


def test_stamp_units_name_the_callers_options(xyz):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gt = read_trajectory(xyz, "tum")
    ns = type(gt).from_checked(gt.stamps * 1e9, gt.positions, gt.quaternions)
    with pytest.raises(EvaluationError, match=r"--format euroc"):  # the command line's, by default
        check_stamp_units(ns, gt, "e.txt")
    with pytest.raises(EvaluationError, match=r"estimate_format = 'euroc'") as caught:
        check_stamp_units(ns, gt, "e.txt", names={"format": "estimate_format = 'euroc'"})
    assert "--" not in str(caught.value)


def test_index_pairing_names_the_manifest_keys():
    spec = make_spec("evo", surface="manifest", max_diff=0.02)
    with pytest.raises(ValidationError) as caught:
        by_index(spec, surface="manifest")
    said = str(caught.value)
    assert said.startswith("max_diff: ") and "estimate_times and groundtruth_times" in said and "--" not in said
    with pytest.raises(ValidationError, match=r"max_diff \(--max-diff\): .*\(--est-times and --gt-times\)"):
        by_index(spec)  # the command line's words, as before
