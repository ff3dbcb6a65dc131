"""crosscheck --conventions: exit 0 when every difference from evo is explained by a stated
definition (listed), 1 only for a disagreement no definition explains."""

from __future__ import annotations

import re

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
    assert (
        "explained by a stated definition (29 of 29: 15 differ from evo's value, evo has no value for 14; the "
        "conventions of preset tum are not evo's"
        in err
        and "ate_rmse" in err
        and "DISAGREE" not in err
    )
    assert "0 of 29 statistics agree" in err  # one count for every line: 0 agree + 29 explained of the 29


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
    assert "DISAGREE, unexplained (1 of 30): ate_rmse" in err and "29 of 30 statistics agree" in err


@pytest.mark.thorough
def test_options_that_depart_from_evos_preset_are_named_and_counts_add_up(data, capsys):
    """--conventions evo --align posyaw: the differences are explained by --align posyaw (evo has no
    position-and-yaw alignment), not by 'these conventions are not evo's ... --conventions evo gives
    evo's' (it was given); the statistics that agree and those explained add up to every statistic."""
    g, e = str(data.tum / GT), str(data.tum / EST)
    assert main(["crosscheck", g, e, "--conventions", "evo", "--align", "posyaw"]) == 0
    err = capsys.readouterr().err
    agree = re.search(r"(\d+) of (\d+) statistics agree", err)
    why = re.search(r"explained by a stated definition \((\d+) of (\d+): (\d+) differ from evo's value; --align "
                    r"posyaw departs from evo's conventions \(lorisnb aligns position and yaw", err)  # fmt: skip
    assert agree and why, err
    assert int(agree[1]) + int(why[1]) == int(agree[2]) == int(why[2]) and why[1] == why[3]
    assert "are not evo's" not in err and "DISAGREE" not in err


@pytest.mark.thorough
@pytest.mark.parametrize("preset", ["tum", "kitti", "vio"])
def test_a_wrong_number_is_not_explained_by_definitions_that_cannot_make_it(data, capsys, monkeypatch, preset):
    """lorisnb's ATE RMSE three times too large (a bug simulated in its table) under a preset whose
    definitions differ from evo's: every row's note starts 'definitions differ', and that alone made
    every row explained (exit 0). Now evo, computing on lorisnb's own pairs under those definitions,
    gives the true number: ATE RMSE is unexplained (exit 1), every other difference still explained."""
    import lorisnb.tools.evaluation.runner as runner

    real = runner.evaluate_pairs

    class Wrong:
        def __init__(self, ev):
            self.ev = ev

        def __getattr__(self, k):
            return getattr(self.ev, k)

        def sequences(self, *a, **k):
            t = self.ev.sequences(*a, **k).copy()
            t["ate_rmse"] = t["ate_rmse"] * 3
            return t

    g, e = str(data.tum / GT), str(data.tum / EST)
    assert main(["crosscheck", g, e, "--conventions", preset]) == 0  # the true numbers: every difference explained
    assert "DISAGREE" not in capsys.readouterr().err
    monkeypatch.setattr(runner, "evaluate_pairs", lambda *a, **k: Wrong(real(*a, **k)))
    table = crosscheck_evo(g, e, preset).set_index("quantity")
    assert table.loc["ate_rmse", "note"].startswith("definitions differ")
    assert "NOT explained: evo on lorisnb's pairs gives" in table.loc["ate_rmse", "note"]
    assert main(["crosscheck", g, e, "--conventions", preset]) == 1
    assert re.search(r"DISAGREE, unexplained \(1 of \d+\): ate_rmse\n", capsys.readouterr().err)


def _pair(tmp_path, unsorted: bool):
    """A ground truth and a noisy estimate (TUM, 10 Hz); ``unsorted``: estimate rows 5-6, 20-21, ...
    swapped, as a writer with two threads leaves them."""
    import numpy as np

    rng = np.random.default_rng(3)
    t = 100.0 + 0.1 * np.arange(120)
    xyz = np.c_[np.cos(t / 3), np.sin(t / 3), 0.01 * t]
    q = np.c_[np.zeros((len(t), 2)), np.sin(t / 6), np.cos(t / 6)]
    noisy = xyz + rng.normal(0, 0.01, xyz.shape)
    rows = [f"{s:.6f} {' '.join(f'{v:.9f}' for v in (*p, *r))}" for s, p, r in zip(t, noisy, q, strict=True)]
    if unsorted:
        for i in range(5, len(rows) - 1, 15):
            rows[i], rows[i + 1] = rows[i + 1], rows[i]
    gt, est = tmp_path / "gt.tum", tmp_path / "est.tum"
    gt.write_text(
        "".join(f"{s:.6f} {' '.join(f'{v:.9f}' for v in (*p, *r))}\n" for s, p, r in zip(t, xyz, q, strict=True))
    )
    est.write_text("\n".join(rows) + "\n")
    return str(gt), str(est)


@pytest.mark.thorough
def test_unsorted_stamps_explain_the_rpe_differences_and_nothing_else(tmp_path, capsys, monkeypatch):
    """An estimate whose stamps go backwards: lorisnb sorts it, evo keeps the file's order, so their RPE
    pairs differ (docs/guide/evo.md): the RPE rows are explained by that and the exit is 0 (it was
    'DISAGREE, unexplained (11 of 30)', exit 1); ATE, which the order does not change, still exits 1
    when it disagrees."""
    pytest.importorskip("evo")
    g, e = _pair(tmp_path, unsorted=True)
    table = crosscheck_evo(g, e, "evo").set_index("quantity")
    assert not table.loc["rpe_trans_rmse", "agrees"] and table.loc["ate_rmse", "agrees"]
    assert table.loc["rpe_trans_rmse", "note"].startswith("definitions differ: stamps go backwards in " + e)
    assert "definitions differ" not in table.loc["ate_rmse", "note"]
    assert main(["crosscheck", g, e, "--conventions", "evo"]) == 0
    err = capsys.readouterr().err
    assert "DISAGREE" not in err and "explained by a stated definition" in err
    assert "lorisnb sorts them, evo keeps the file's order, so the RPE pairs differ): rpe_trans_rmse" in err
    real = cc.evo_statistics

    def off(*a, **k):
        out = real(*a, **k)
        out["ate_rmse"] += 1e-3
        return out

    monkeypatch.setattr(cc, "evo_statistics", off)
    assert main(["crosscheck", g, e, "--conventions", "evo"]) == 1
    assert "DISAGREE, unexplained (1 of 30): ate_rmse" in capsys.readouterr().err


@pytest.mark.thorough
def test_an_rpe_disagreement_on_sorted_stamps_exits_1(tmp_path, capsys, monkeypatch):
    """The same pair in order agrees with evo throughout; evo's RPE moved by a little is unexplained."""
    pytest.importorskip("evo")
    g, e = _pair(tmp_path, unsorted=False)
    assert main(["crosscheck", g, e, "--conventions", "evo"]) == 0
    assert "30 of 30 statistics agree" in capsys.readouterr().err
    real = cc.evo_statistics

    def off(*a, **k):
        out = real(*a, **k)
        out["rpe_trans_rmse"] += 1e-3
        return out

    monkeypatch.setattr(cc, "evo_statistics", off)
    assert main(["crosscheck", g, e, "--conventions", "evo"]) == 1
    assert "DISAGREE, unexplained (1 of 30): rpe_trans_rmse" in capsys.readouterr().err


def test_inputs_that_do_not_fit_are_usage_errors_that_say_why(data, icra20, capsys):
    """An OpenLORIS result against another scene's ground truth said only "no estimate stamp lies
    within 0.5 s" (exit 1); a --seq the files lack exited 1; GT 'auto' on a TUM pair looked for a
    file named auto. Each is a usage error (exit 2) saying what to give."""
    est = str(icra20 / "per-seq" / "ds-slam" / "cafe-1-2.txt")
    home = str(data.root / "openloris-scene" / "groundtruth" / "gt_home_1.txt")
    cafe = str(data.root / "openloris-scene" / "groundtruth" / "gt_cafe_1.txt")
    assert main(["crosscheck", home, est, "--format", "openloris"]) == 2
    assert "is of scene cafe (its scene: header), the ground truth" in capsys.readouterr().err
    assert main(["crosscheck", cafe, est, "--format", "openloris", "--seq", "5"]) == 2
    assert "sequence 5 is not in both the result ([2])" in capsys.readouterr().err
    assert main(["crosscheck", "auto", est]) == 2
    assert "add --format openloris" in capsys.readouterr().err
    assert main(["crosscheck", cafe, est, "--format", "openloris"]) == 0  # the right one: compared
