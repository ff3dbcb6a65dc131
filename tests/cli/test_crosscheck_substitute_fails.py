"""crosscheck --conventions where evo's substitute for a lorisnb definition cannot be computed (evo's
SE(3) for posyaw on a straight line or on 2 poses; evo's nearest stamps for lorisnb's interpolation
where no stamp is near): the statistics it leaves without evo's value are explained by the stated
definition (evo on lorisnb's pairs gives lorisnb's number), the others still compared, exit 0. The
whole command stopped with 'evo cannot evaluate this pair', blaming NaN poses the files do not have;
that hint is now given only when a file has NaN poses."""

from __future__ import annotations

import numpy as np
import pytest

from lorisnb.cli import main
from lorisnb.core.spec.evalspec import make_spec
from lorisnb.tools.peers.crosscheck_evo import crosscheck_evo, explained

GT, EST = "freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"


def _rows(path) -> np.ndarray:
    return np.loadtxt(path, comments="#")


@pytest.fixture
def line(data, tmp_path):
    """The fr1/xyz rgbdslam estimate with y = z = 0: a straight line, which posyaw aligns (a yaw about
    z and a shift) and evo's SE(3) cannot ('Degenerate covariance rank')."""
    e = _rows(data.tum / EST)
    e[:, 2:4] = 0.0
    path = tmp_path / "line.txt"
    np.savetxt(path, e, fmt="%.6f")
    return path


@pytest.mark.thorough
def test_posyaw_on_a_line_is_explained_by_the_stated_definition_and_exits_0(data, line, capsys):
    g = str(data.tum / GT)
    assert main(["crosscheck", g, str(line), "--format", "tum", "--conventions", "vio", "--rpe-frames", "1"]) == 0
    captured = capsys.readouterr()
    assert "error:" not in captured.err and "NaN" not in captured.err and "DISAGREE" not in captured.err
    assert "2 of 30 statistics agree" in captured.err
    assert "explained by a stated definition (28 of 30: evo has no value for 28;" in captured.err
    table = crosscheck_evo(g, line, make_spec("vio", rpe_delta=1, rpe_unit="f")).set_index("quantity")
    assert table.loc["matched", "agrees"] and table.loc["matched", "lorisnb"] == 786  # still compared
    assert table.loc["rpe_pairs", "agrees"] and table.loc["rpe_pairs", "lorisnb"] == 785  # (no alignment changes it)
    ate = table.loc["ate_rmse"]
    assert np.isnan(ate["evo"]) and abs(ate["lorisnb"] - 0.1574847193) < 1e-9  # lorisnb evaluate's 0.1575
    assert "posyaw" in ate["note"] and "Degenerate covariance rank" in ate["note"]
    assert ate["note"].endswith("explained: evo on lorisnb's pairs gives 0.1574847193")
    stats = table[~table.index.str.contains(":")].reset_index()
    assert (stats["agrees"] | explained(stats)).all()


@pytest.mark.thorough
def test_two_poses_under_posyaw_exit_0(data, tmp_path, capsys):
    e = tmp_path / "n2.txt"
    np.savetxt(e, _rows(data.tum / EST)[100:102], fmt="%.6f")
    assert main(["crosscheck", str(data.tum / GT), str(e), "--format", "tum", "--conventions", "vio"]) == 0
    err = capsys.readouterr().err
    assert "error:" not in err and "DISAGREE" not in err and "1 of 29 statistics agree" in err


@pytest.mark.thorough
def test_no_pair_in_evos_nearest_sync_is_explained_by_the_stated_association(data, tmp_path):
    """Ground truth at 10 Hz, every estimate stamp 50 ms after one: lorisnb interpolates (association
    interpolate), evo's nearest stamp within 10 ms finds no pair. Every row explained, none refused."""
    g = _rows(data.tum / GT)[::10]
    e = g.copy()
    e[:, 0] += 0.05
    np.savetxt(gt := tmp_path / "gt10.txt", g, fmt="%.6f")
    np.savetxt(est := tmp_path / "est50.txt", e, fmt="%.6f")
    table = crosscheck_evo(gt, est, make_spec("evo", association="interpolate"))
    stats = table[~table["quantity"].str.contains(":")]
    assert explained(stats).all() and stats["evo"].isna().all()
    matched = stats.set_index("quantity").loc["matched"]
    assert matched["lorisnb"] == 299 and "found no matching timestamps" in matched["note"]


@pytest.mark.thorough
def test_the_nan_hint_only_where_a_file_has_nan_poses(data, line, tmp_path, capsys):
    rows = line.read_text().splitlines()
    f = rows[9].split()
    rows[9] = " ".join([f[0], "nan", *f[2:]])
    nan = tmp_path / "nan.txt"
    nan.write_text("\n".join(rows) + "\n")
    assert main(["crosscheck", str(data.tum / GT), str(nan), "--format", "tum", "--conventions", "evo"]) == 1
    err = capsys.readouterr().err
    assert "error: evo cannot evaluate this pair: " in err
    assert f"{nan} (1 pose): lorisnb skips NaN poses, evo does not" in err
