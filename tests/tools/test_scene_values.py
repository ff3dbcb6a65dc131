"""One scene value for every path (trial finding 3): ``evaluate``'s scene table, ``Evaluation.scenes``,
``compare``, the report leaderboard and ``diff`` give a scene's CS-R (and CR) through
:func:`lorisnb.core.lifelong.aggregate.scene_mean`, a sequence without output counting as a failed run
(CS-R 0), on real results with sequences missing."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.tools.report.leaderboard import findings

ORB = "home_1_{}_orbslam2-original.txt"


@pytest.fixture
def partial(tmp_path, icra20):
    """odom complete; orb without home sequences 2, 4 and 5 (2 of 5 with output)."""
    res = tmp_path / "results"
    shutil.copytree(icra20 / "per-seq" / "odom", res / "odom")
    shutil.copytree(icra20 / "per-seq" / "orbslam2_rgbd", res / "orb")
    for n in (2, 4, 5):
        (res / "orb" / ORB.format(n)).unlink()
    return res


def _printed_scene_row(out: str, algorithm: str, scene: str) -> dict[str, str]:
    lines = out[out.index("per scene (") :].splitlines()[1:]
    header = lines[0].split()
    for line in lines[1:]:
        cells = line.split()
        if cells[:2] == [algorithm, scene]:
            return dict(zip(header[-len(cells) :], cells, strict=True))
    raise AssertionError(f"no printed scene row for {algorithm} {scene}:\n{out}")


@pytest.mark.thorough
def test_every_path_gives_the_same_scene_cs_r_with_missing_sequences(partial, tmp_path, capsys):
    ev = ln.evaluate(partial, progress=False)
    table, durations = ev.sequences(eps="paper", phi=30), ev.durations()
    scenes = ev.scenes(eps="paper", phi=30).set_index(["algorithm", "scene"])
    home = scenes.loc[("orb", "home")]
    seq_cs_r = table[(table["algorithm"] == "orb") & (table["scene"] == "home")].set_index("seq")["cs_r"]
    assert sorted(seq_cs_r.index) == [1, 3] and home["scene_sequences"] == 5
    # the paper's scene value: every sequence of the scene, the three without output failed runs (CS-R 0)
    assert home["cs_r"] == pytest.approx(seq_cs_r.sum() / 5, rel=1e-12)
    assert home["cs_r_with_output"] == pytest.approx(seq_cs_r.mean(), rel=1e-12)
    assert home["cs_r"] < 0.45 < 0.9 < home["cs_r_with_output"]  # two different numbers, two names

    assert main(["evaluate", str(partial), "--eps", "paper", "--phi", "30", "--no-progress"]) == 0
    printed = _printed_scene_row(capsys.readouterr().out, "orb", "home")
    assert float(printed["cs_r"]) == pytest.approx(home["cs_r"], abs=5e-5) and printed["coverage"] == "2/5"

    csv = tmp_path / "cmp.csv"
    assert (
        main(
            [
                "compare",
                str(partial),
                "--eps",
                "paper",
                "--phi",
                "30",
                "--metric",
                "cs_r",
                "--csv",
                str(csv),
                "--no-progress",
            ]
        )
        == 0
    )
    capsys.readouterr()
    cmp = pd.read_csv(csv).set_index(["algorithm", "scene"])
    board = findings(table, durations, "cs_r").board.set_index(["algorithm", "scene"])
    for (alg, scene), row in scenes.iterrows():  # every algorithm and scene, not only the one lacking
        assert cmp.loc[(alg, scene), "value"] == pytest.approx(row["cs_r"], rel=1e-12, abs=1e-15)
        assert board.loc[(alg, scene), "value"] == pytest.approx(row["cs_r"], rel=1e-12, abs=1e-15)
    for metric in ("cr", "cr_t", "c_ate_rmse"):  # the other scene values agree the same way
        values = findings(table, durations, metric).board.set_index(["algorithm", "scene"])["value"]
        np.testing.assert_allclose(values.loc[scenes.index], scenes[metric], rtol=1e-12)


@pytest.mark.thorough
def test_diff_scene_cs_r_is_evaluates(partial, tmp_path, icra20, capsys):
    """diff's scene CS-R of a candidate lacking sequences is the candidate's evaluate value."""
    base = tmp_path / "base"
    shutil.copytree(icra20 / "per-seq" / "orbslam2_rgbd", base / "orb")
    out = tmp_path / "d.json"
    assert (
        main(
            [
                "diff",
                str(base),
                str(partial / "orb"),
                "--eps",
                "paper",
                "--phi",
                "30",
                "--json",
                str(out),
                "--no-progress",
            ]
        )
        == 1
    )
    capsys.readouterr()
    verdict = json.loads(out.read_text())
    row = next(
        r for r in verdict["regressions"]
        if r["seq"] is None and r["scene"] == "home" and r["metric"] == "cs_r"
    )  # fmt: skip
    want = ln.evaluate(partial / "orb", progress=False).scenes(eps="paper", phi=30)
    want = want.set_index("scene").loc["home"]
    assert float(row["cand"]) == pytest.approx(want["cs_r"], rel=1e-12)
    assert row["algorithm"] == "orb" and row["base"] > row["cand"]
