"""The notebooks' prose that depends on the run is computed (:mod:`lorisnb.tools.notebook.prose`)
and shown by a code cell, not typed: a typed sentence naming the bundled data's algorithms and
scenes, a simulated verdict or the default RPE step was shown, wrong, on the user's results and at
other parameters."""

from __future__ import annotations

import nbformat
import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.tools.notebook.prose import (
    rank_reference_words,
    rpe_words,
    simulated_verdict,
    threshold_words,
    tracking_and_accuracy,
)
from lorisnb.tools.report.build import notebook_dir

S, D, T = "simulated: steady", "simulated: drifting", "simulated: twin of steady"


def _markdown(name: str) -> str:
    nb = nbformat.read(notebook_dir() / f"{name}.ipynb", as_version=4)
    return "\n".join(c.source for c in nb.cells if c.cell_type == "markdown")


@pytest.mark.parametrize(
    ("name", "typed"),
    [
        ("per_sequence_benchmark", ["ORB-SLAM2", "DS-SLAM", "ElasticFusion", "corridor and market",
                                    "on the\nOpenLORIS-Scene results behind Fig. 2"]),
        ("compare_algorithms", ["the drifting algorithm is separated", "share a rank"]),
        ("evaluate_my_results", ["over 1 s"]),
        # the section runs at the parameters' eps and phi, and the reference of the ranking may be a grid value
        ("threshold_sensitivity", ["With the paper's eps and phi", "with the ranking at the paper's\neps:"]),
    ],
)  # fmt: skip
def test_no_typed_claim_about_the_runs_results(name, typed):
    text = _markdown(name)
    assert not [t for t in typed if t in text]


def test_rpe_words_follow_the_spec():
    assert "over 1 s (pose pairs that far apart along the ground truth" in rpe_words(
        ln.make_spec(None, surface="notebook")
    )
    assert "over 5 m" in rpe_words(ln.make_spec(None, surface="notebook", rpe_delta=5, rpe_unit="m"))
    assert "over 1 frames (pose pairs that far apart along the estimate" in rpe_words(
        ln.make_spec("evo", surface="notebook")
    )


def _pairs(drift_s: bool, drift_t: bool, twins: bool) -> pd.DataFrame:
    return pd.DataFrame({"a": [D, D, S], "b": [S, T, T], "significant": [drift_s, drift_t, twins]})


@pytest.mark.parametrize(
    ("pairs", "said", "not_said"),
    [
        (_pairs(True, True, False), ["separated from both others", "share a rank"], ["false positive"]),
        (_pairs(False, False, False), ["separated from neither", "share a rank"], ["both others"]),  # sim_eps 5
        (_pairs(True, False, True), [f"from `{S}` only", "false positive"], ["share a rank"]),
    ],
)
def test_the_simulated_verdict_is_what_the_test_found(pairs, said, not_said):
    text = simulated_verdict(pairs, S, D, T, trials=6, alpha=0.05)
    assert all(s in text for s in said) and not any(s in text for s in not_said), text


def test_tracking_and_accuracy_names_the_inputs_algorithms():
    table = pd.DataFrame(
        {"scene": ["lab", "lab", "lab", "yard"], "algorithm": ["mine", "theirs", "odd", "mine"],
         "cr": [0.9, 0.5, 0.7, 1.0], "c_ate_rmse": [0.8, 0.1, 2.0, 0.3]}
    )  # fmt: skip
    text = tracking_and_accuracy(table)
    assert "lab: `mine` (CR 90.0 %, C-ATE RMSE 0.800 m) tracked longest; the most accurate was `theirs`" in text
    assert "least accurate was `odd`" in text
    # one algorithm: nothing to compare, and said (it was left out of the list silently)
    assert "* yard" not in text and "Not compared" in text and "yard (`mine` alone)" in text
    assert "no scene" in tracking_and_accuracy(table.iloc[3:])


def test_tracking_and_accuracy_calls_cr_at_finite_thresholds_a_correct_rate():
    """At finite eps or phi CR counts correct time only: "tracked longest" (true at infinite thresholds,
    per_sequence_benchmark's default) was said of the highest correct rate."""
    table = pd.DataFrame({"scene": ["lab", "lab"], "algorithm": ["mine", "theirs"], "cr": [0.9, 0.5],
                          "c_ate_rmse": [0.8, 0.1]})  # fmt: skip
    for eps, phi in ((1.0, float("inf")), (float("inf"), 30.0), ("paper", 30.0)):
        text = tracking_and_accuracy(table, eps, phi)
        assert "`mine` (CR 90.0 %, C-ATE RMSE 0.800 m) had the highest correct rate" in text
        assert "tracked longest" not in text
    assert "tracked longest" in tracking_and_accuracy(table, float("inf"), float("inf"))


def test_threshold_words_say_what_was_used():
    """threshold_sensitivity said "With the paper's eps and phi" whatever eps and phi were given."""
    assert threshold_words("paper", 30.0).startswith("the paper's eps (1, 3 or 5 m by scene) and phi = 30 deg")
    text = threshold_words(0.5, 20.0)
    assert text == "eps = 0.5 m and phi = 20 deg" and "paper" not in text
    assert threshold_words("relative:0.05", 30.0).startswith("eps = 0.05 of each sequence's extent")


def test_the_reference_ranking_is_named_as_used():
    """ "ranking at the paper's eps" was said where the grid lacks it and the reference became the nearest
    grid value; a scene with one algorithm (no ranking) was left out silently."""
    stability = pd.DataFrame({"scene": ["cafe", "cafe", "corridor"], "eps": [0.3, 1.0, 5.0],
                              "reference_eps": [1.0, 1.0, 5.0]})  # fmt: skip
    text = rank_reference_words(stability, ["cafe", "corridor", "home"])
    assert "cafe: 1 m, the grid value nearest the paper's 3 m (not in the grid)" in text
    assert "corridor: the paper's eps, 5 m" in text
    assert "Left out, with fewer than two algorithms to rank: home." in text
