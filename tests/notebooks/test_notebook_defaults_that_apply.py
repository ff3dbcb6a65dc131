"""A notebook's default for a parameter its run does not use is not refused, and a default that
cannot apply to the inputs resolves to what does:

* ``lorisnb report --results res --data DATA --notebooks compare_algorithms``, DATA holding only
  cafe and home ground truth: compare_algorithms failed with "-p sim_scene corridor: the data root
  ... holds no ground truth for corridor", though its simulated section is off with results_dir and
  nobody gave -p sim_scene. A value given for it while the section is off is refused (it would be
  ignored), one given while it runs is still checked against the data.
* ``evaluate_my_results`` on a TUM pair (-p path, -p groundtruth) failed at its default eps "paper";
  its default is now what applies (the paper's for OpenLORIS results, the spec's otherwise), while
  an explicit ``-p eps paper`` on a TUM pair is still refused with its clear message.
"""

from __future__ import annotations

import json
import shutil

import pytest

from lorisnb.cli import main
from lorisnb.errors import ValidationError
from lorisnb.io.datasets.paths import find_data
from lorisnb.tools.notebook.params import check_parameters, refuse_scenes_without_groundtruth


@pytest.fixture
def cafe_home(tmp_path, data):
    """A data root holding only the cafe and home ground truth (a path with a space and an accent)."""
    root = tmp_path / "da ta é"
    src = data.root / "openloris-scene"
    (root / "openloris-scene" / "groundtruth").mkdir(parents=True)
    for name in ("LICENSE.txt", "extrinsics.json"):
        shutil.copy(src / name, root / "openloris-scene" / name)
    for scene in ("cafe", "home"):
        shutil.copy(src / "groundtruth" / f"gt_{scene}_1.txt", root / "openloris-scene" / "groundtruth")
    return root


def _results(tmp_path, icra20):
    res = tmp_path / "res"
    for alg in ("orbslam2_rgbd", "odom"):
        shutil.copytree(icra20 / "per-seq" / alg, res / alg)
    return res


def test_compare_algorithms_on_your_results_ignores_the_simulated_sections_default_scene(
    tmp_path, icra20, cafe_home, monkeypatch
):
    res = _results(tmp_path, icra20)
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "runs" / "r1"
    main(["report", "--results", "res", "--data", cafe_home.name, "--out", str(out), "--no-progress",
          "--notebooks", "compare_algorithms", "-p", "quick", "true"])  # fmt: skip
    assert json.loads((out / "run.json").read_text())["notebooks"] == {"compare_algorithms": "ok"}
    ranking = (out / "compare_algorithms" / "ranking.csv").read_text()
    assert "orbslam2_rgbd" in ranking and "odom" in ranking and "simulated:" not in ranking
    assert res.exists()


def test_a_sim_scene_given_is_checked_when_the_section_runs_and_refused_when_it_does_not(cafe_home):
    from lorisnb.tools.notebook.params import simulated_on

    data = find_data(cafe_home)
    declared = {n: {"default": None} for n in ("results_dir", "simulated", "sim_scene", "sim_trials", "sim_eps")}
    mine = {"results_dir": str(cafe_home), "sim_scene": "corridor"}  # the notebook's default, with results_dir
    refuse_scenes_without_groundtruth(mine, data)  # the section is off: its default loads nothing
    with pytest.raises(ValidationError, match="-p sim_scene corridor: the data root .* holds no ground truth"):
        refuse_scenes_without_groundtruth({**mine, "simulated": True}, data)  # on: it would load corridor
    with pytest.raises(ValidationError, match="-p sim_scene corridor: the data root"):
        refuse_scenes_without_groundtruth({"results_dir": None, "sim_scene": "corridor"}, data)  # bundled data
    for name, value in (("sim_scene", "home"), ("sim_trials", 3), ("sim_eps", 0.5)):  # given, off: ignored
        with pytest.raises(ValidationError, match=rf"-p {name}: only applies to the simulated section of "
                           r"compare_algorithms, which is off \(results_dir is given\); give -p simulated true"):  # fmt: skip
            check_parameters({"results_dir": str(cafe_home), name: value}, declared, ["compare_algorithms"])
    with pytest.raises(ValidationError, match=r"off \(simulated is false\)"):
        check_parameters({"simulated": False, "sim_trials": 3}, declared, ["compare_algorithms"])
    ok = check_parameters({"results_dir": str(cafe_home), "simulated": True, "sim_scene": "Home"}, declared,
                          ["compare_algorithms"])  # fmt: skip
    assert ok["sim_scene"] == "home"
    assert simulated_on({}) and not simulated_on({"results_dir": "x"}) and simulated_on({"results_dir": "x",
                                                                                          "simulated": True})  # fmt: skip


def test_evaluate_my_results_on_a_tum_pair_scores_at_the_eps_that_applies(tmp_path, data, capsys):
    tum = data.root / "tum-rgbd"
    pair = ["-p", "path", str(tum / "fr2_desk_ORB.txt"), "-p", "groundtruth", str(tum / "fr2_desk_groundtruth.txt")]
    out = tmp_path / "r2"
    main(["report", "--out", str(out), "--no-progress", "--notebooks", "evaluate_my_results", *pair])
    assert json.loads((out / "run.json").read_text())["notebooks"] == {"evaluate_my_results": "ok"}
    import pandas as pd

    row = pd.read_csv(out / "evaluate_my_results" / "sequences.csv").iloc[0]
    assert row["eps"] == float("inf") and row["phi"] == 30.0 and row["matched"] == 2333  # lorisnb evaluate's
    assert row["cr"] == pytest.approx(0.8346408402127511, abs=1e-9)
    out = tmp_path / "r3"  # an explicit paper eps on a TUM pair: refused before any notebook runs (exit 2,
    # no run folder), saying what to give, as evaluate and Python refuse it
    rc = main(["report", "--out", str(out), "--no-progress", "--notebooks", "evaluate_my_results", *pair, "-p", "eps",
               "paper"])  # fmt: skip
    assert rc == 2 and not out.exists()
    err = capsys.readouterr().err
    assert "eps='paper': the paper's 1/3/5 m are for the OpenLORIS scenes; scene 'fr2_desk' is not one" in err, err


def test_evaluate_my_results_default_eps_is_the_papers_for_openloris_inputs_only(data, monkeypatch):
    tum = data.root / "tum-rgbd"
    monkeypatch.setenv("TUM_ROOT", str(tum))
    from lorisnb.tools.notebook.params import default_eps

    assert default_eps(None) == "paper"  # the bundled example, your OpenLORIS files
    assert default_eps(None, tum / "fr2_desk_groundtruth.txt", None, "tum") is None  # the spec's: inf
    assert default_eps(None, "gt_cafe_1.txt", None, "openloris") == "paper"
    assert default_eps(None, None, "openloris") == "paper" and default_eps(None, None, "tum-fr1-office") is None
    assert default_eps(0.3, tum / "fr2_desk_groundtruth.txt") == 0.3 and default_eps("paper", "gt.txt") == "paper"
