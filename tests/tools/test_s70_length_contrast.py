"""indoor_vs_outdoor's sentence on path lengths is computed from the ground truth, not typed: which
dataset's paths are longer, and by how much, follows the numbers (an ORDSLAM folder of long paths
turns it round)."""

from __future__ import annotations

import warnings

import pandas as pd
import pytest

from lorisnb.errors import LorisWarning
from lorisnb.io.datasets.published import ORDSLAM_MEAN_LENGTH_M
from lorisnb.tools.notebook import indoor_outdoor


@pytest.fixture(scope="module")
def stats(data) -> pd.DataFrame:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LorisWarning)
        return indoor_outdoor.openloris_stats(data, ["market", "corridor", "home"])


def test_the_bundled_lengths_against_the_papers_mean(stats):
    med = stats.groupby("group")["length_m"].median()
    text = indoor_outdoor.length_contrast(stats)
    lo, hi = sorted([med["market"] / ORDSLAM_MEAN_LENGTH_M, med["corridor"] / ORDSLAM_MEAN_LENGTH_M])
    assert lo > 5  # the real loops: far longer than 12 m
    assert f"market {med['market']:.0f} m and corridor {med['corridor']:.0f} m" in text
    assert f"{lo:.1f} to {hi:.1f} times as long" in text and "the paper's mean" in text


def test_a_folder_of_longer_paths_turns_the_sentence_round(stats):
    longer = pd.DataFrame(dict(dataset="ORDSLAM", group="scenario 6", length_m=[300.0, 400.0, 500.0]))
    text = indoor_outdoor.length_contrast(pd.concat([stats, longer], ignore_index=True))
    assert "ORDSLAM 400 m (median of your folder's 3 sequences)" in text
    assert "shorter" in text and "times as long" not in text


def test_no_scene_to_compare_is_said(stats):
    assert "no path length to compare" in indoor_outdoor.length_contrast(stats[stats["group"] == "home"])
