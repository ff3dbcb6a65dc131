"""The per-pose errors of a sequence are read-only: what is computed from them is kept (the scores
of each threshold setting, RPE, the rotation lever), so ``ate[:] *= 10`` gave the old scores at a
setting asked before and the new ones at any other (``ev.sequences`` and ``ln.score`` against
``ln.sweep``). New errors come from ``dataclasses.replace``, which keeps nothing."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

import lorisnb as ln


def test_errors_cannot_be_edited_in_place_and_replace_gives_new_scores(icra20, data):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ev = ln.evaluate(icra20 / "per-seq" / "orbslam2_rgbd" / "cafe_1_1_orbslam2-original.txt", data_root=data)
    se = ev.errors[0].sequences[0]
    before = ev.sequences(eps=0.3, phi=10.0)["cr"].iloc[0]
    for name in ("stamps", "ate", "aoe", "est_positions", "gt_positions", "est_quaternions", "gt_quaternions"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(se, name)[:1] *= 10
    assert ev.sequences(eps=0.3, phi=10.0)["cr"].iloc[0] == before
    worse = dataclasses.replace(se, ate=np.asarray(se.ate) * 10)
    fe = dataclasses.replace(ev.errors[0], sequences=[worse])
    assert ln.score(fe, eps=0.3, phi=10.0)["cr"].iloc[0] < before
    assert ln.sweep(fe, eps=[0.3], phi=[10.0])["cr"].iloc[0] == ln.score(fe, eps=0.3, phi=10.0)["cr"].iloc[0]
