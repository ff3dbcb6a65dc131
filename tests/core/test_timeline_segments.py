"""The timeline's segments (:func:`lorisnb.core.lifelong.timeline.timeline_table`) against the scores
at the same thresholds, on real icra20 results."""

from __future__ import annotations

import numpy as np
import pytest

import lorisnb as ln
from lorisnb.core.lifelong.scoring import score
from lorisnb.core.lifelong.timeline import timeline_table


@pytest.mark.parametrize("eps, phi, delta", [("paper", 30.0, 1.0), (5.0, 60.0, 0.5), (0.01, 1.0, 5.0)])
def test_correct_segments_add_up_to_the_correct_time(icra20, eps, phi, delta):
    """Each sequence's correct segments last its correct time (Eq. 2's numerator, as score has it),
    every segment of a sequence lies in its span in order, and each sequence has one first pose."""
    ev = ln.evaluate(icra20 / "lifelong", algorithms=["maslam", "orbslam2_t265"], scenes=["home", "office"],
                     progress=False)  # fmt: skip
    seg, first = timeline_table(ev.errors, eps, phi, delta)
    table = score(ev.errors, eps, phi, delta, stats=False).set_index(["algorithm", "scene", "seq"])
    keys = ["algorithm", "scene", "seq"]
    done = seg[seg["correct"]].assign(d=seg["end"] - seg["start"]).groupby(keys)["d"].sum()
    held = done.reindex(table.index, fill_value=0.0)
    assert np.allclose(held, table["correct_time"], rtol=1e-12, atol=1e-9)
    assert (held < table["gt_duration"] + 1e-9).all()
    assert (table["correct_time"] > 0).sum() >= (0 if eps == 0.01 else 2)  # 1 cm: hardly a pose correct
    assert (seg["end"] > seg["start"]).all() and (seg["start"] >= 0).all()
    for _, s in seg.groupby(keys):
        assert (np.diff(s["start"].to_numpy()) > 0).all()
    assert len(first) == int((table["matched"] > 0).sum()) and first["correct"].dtype == bool
    assert list(seg.dtypes.astype(str)) == ["str", "str", "int64", "str", "int64", "float64", "float64", "bool"]
