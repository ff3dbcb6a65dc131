"""A ground truth's repeated stamps are said under every rule (s68 finding 6): under the evo preset
(``repeated='keep'``, every pose of a repeated stamp kept, as evo reads them) they were kept with no
note, while docs/guide/errors.md says a ground truth's repeated stamps give a warning. The numbers
stay evo's: only the note is new."""

from __future__ import annotations

import warnings

import pytest

from lorisnb.errors import LorisWarning
from lorisnb.io.readers.plain import read_tum


@pytest.fixture(scope="module")
def desk(data):
    gt, est = data.tum / "fr2_desk_groundtruth.txt", data.tum / "fr2_desk_ORB.txt"
    if not gt.is_file() or not est.is_file():
        pytest.skip("fr2_desk is not in the data")
    return gt, est


def test_fr2_desks_repeated_stamp_is_said_under_evo(desk):
    from lorisnb import evaluate_pairs

    gt, est = desk
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LorisWarning)
        evo = evaluate_pairs([est], gt, conventions="evo", scene="desk")
        own = evaluate_pairs([est], gt, scene="desk")
    said = [w for w in evo.warnings if str(gt) in w and "repeats" in w]
    assert len(said) == 1 and "line 10863" in said[0] and "repeated='keep'" in said[0]
    assert any(str(gt) in w and "line 10863" in w for w in own.warnings)  # as the default rule says it


def test_the_poses_kept_are_evos(desk):
    gt, _ = desk
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        kept = read_tum(gt, repeated="keep")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LorisWarning)
        dropped = read_tum(gt)
    assert len(kept) == len(dropped) + 1  # every pose kept, in file order, as evo reads them
    assert (kept.lines[1:] > kept.lines[:-1]).all()
    assert [str(w.message) for w in caught if "repeats" in str(w.message)]


def test_a_file_without_repeats_says_nothing(tmp_path):
    f = tmp_path / "t.txt"
    f.write_text("1 0 0 0 0 0 0 1\n2 1 0 0 0 0 0 1\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error", LorisWarning)
        assert len(read_tum(f, repeated="keep")) == 2
