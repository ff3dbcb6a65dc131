"""crosscheck --conventions: exit 0 when every difference from evo is explained by a stated
definition (listed), 1 only for a disagreement no definition explains."""

from __future__ import annotations

import pytest

import lorisnb.tools.peers.crosscheck_evo as cc
from lorisnb.cli import main
from lorisnb.tools.peers.crosscheck_evo import crosscheck_evo, explained

GT, EST = "fr2_desk_groundtruth.txt", "fr2_desk_ORB.txt"


@pytest.mark.thorough
def test_differences_by_definition_are_listed_and_exit_0(data, capsys):
    g, e = str(data.tum / GT), str(data.tum / EST)
    table = crosscheck_evo(g, e, "tum")
    why = explained(table)
    stats = table.set_index("quantity")
    assert not stats.loc["ate_rmse", "agrees"] and why[table["quantity"] == "ate_rmse"].all()
    assert why[table["quantity"] == "rpe_trans_rmse"].all()  # RPE in seconds: evo has no such unit
    assert main(["crosscheck", g, e, "--conventions", "tum"]) == 0
    err = capsys.readouterr().err
    assert "explained by a stated definition (29;" in err and "ate_rmse" in err and "DISAGREE" not in err


@pytest.mark.thorough
def test_an_unexplained_disagreement_exits_1_and_is_named(data, capsys, monkeypatch):
    """evo's ATE RMSE moved by 1 mm under evo's own preset (where no definition differs): unexplained."""
    real = cc.evo_statistics

    def off(*a, **k):
        out = real(*a, **k)
        out["ate_rmse"] += 1e-3
        return out

    monkeypatch.setattr(cc, "evo_statistics", off)
    g, e = str(data.tum / GT), str(data.tum / EST)
    table = crosscheck_evo(g, e, "evo")
    assert not explained(table)[~table["quantity"].str.contains(":")].any()
    assert not table.set_index("quantity").loc["ate_rmse", "agrees"]
    assert main(["crosscheck", g, e, "--conventions", "evo"]) == 1
    err = capsys.readouterr().err
    assert "DISAGREE, unexplained (1): ate_rmse" in err and "29 of 30 statistics agree" in err
