"""The note on a file's repeated stamps names the rule it applied and who shares it, in the words of
the command that read the file, on fr1/xyz's RGBD-SLAM estimate (real data) with a line repeated:

- the readers keep the last pose of a repeated stamp, as the OpenLORIS tool and TUM's associate.py do
  (the rule of the openloris, tum, kitti and tartanair conventions): the note said "as the official
  tool does", which a user of ``--conventions kitti`` or ``tartanair`` read as the devkit's or
  tartanair_tools';
- ``lorisnb consistency`` keeps one pose a stamp where ov_eval, its peer, keeps every row: its note
  said the same "as the official tool does" and now says that ov_eval keeps every row;
- "sorted them" only when a stamp goes backwards (a file in order with a repeated stamp is not sorted).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from helpers import synthetic_covariances, write_ov_eval_file

from lorisnb.cli import main
from lorisnb.errors import LorisWarning
from lorisnb.io.parsing.scanner import DROP_PEERS, repeated_peer_clause
from lorisnb.io.readers.plain import read_trajectory, read_tum

GT, EST = "freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"
PEERS = "kept the last pose of each repeated stamp, as the OpenLORIS tool and TUM's associate.py do"


def _notes(path: Path, **kw) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        read_trajectory(path, "tum", **kw)
    return [str(w.message) for w in caught if "not increasing" in str(w.message)]


@pytest.fixture(scope="module")
def lines(data) -> list[str]:
    return (data.tum / EST).read_text().splitlines()


@pytest.fixture
def repeated(lines, tmp_path) -> Path:
    """The estimate, in order, with its 101st pose line written twice (the same stamp twice)."""
    body = [s for s in lines if s and not s.startswith("#")]
    path = tmp_path / "repeated.txt"
    path.write_text("\n".join(body[:101] + body[100:]) + "\n")
    return path


@pytest.fixture
def backwards(lines, tmp_path) -> Path:
    """The estimate with its 101st and 102nd pose lines swapped (a stamp going backwards)."""
    body = [s for s in lines if s and not s.startswith("#")]
    body[100], body[101] = body[101], body[100]
    path = tmp_path / "backwards.txt"
    path.write_text("\n".join(body) + "\n")
    return path


def test_a_file_in_order_with_a_repeated_stamp_is_not_said_sorted(repeated, data):
    (note,) = _notes(repeated)
    assert note.endswith(f"first at line 102: 1305031105.659104109 repeats after 1305031105.659104109); {PEERS}"), note
    assert "sorted" not in note and "official tool" not in note
    est = read_tum(data.tum / EST, warn=False)
    t = read_tum(repeated, warn=False)
    assert len(t) == len(est) == 788  # one pose of the repeated stamp kept (the two lines are the same)
    np.testing.assert_array_equal(t.positions, est.positions)


def test_a_stamp_going_backwards_is_said_sorted(backwards):
    (note,) = _notes(backwards)
    assert note.endswith(
        f"first at line 102: 1305031105.659104109 goes backwards after 1305031105.698235035); sorted them and {PEERS}"
    ), note
    (kept,) = _notes(backwards, repeated="keep")  # every pose kept: the rule says so, sorted as before
    assert kept.endswith("); sorted them and kept every pose of a repeated stamp in file order (repeated='keep')")


def test_the_keep_rule_is_unchanged_for_a_file_in_order(repeated):
    (note,) = _notes(repeated, repeated="keep")
    assert note.endswith("first at line 102: 1305031105.659104109 repeats after 1305031105.659104109); kept every pose of a repeated stamp in file order "
                         "(repeated='keep')")  # fmt: skip
    assert len(read_tum(repeated, warn=False, repeated="keep")) == 789  # the 788 poses and the repeated line


def test_a_caller_names_its_own_peer_for_the_block_only(repeated):
    with repeated_peer_clause("; ov_eval keeps every row"):
        (inside,) = _notes(repeated)
    assert inside.endswith("); kept the last pose of each repeated stamp; ov_eval keeps every row"), inside
    with pytest.raises(RuntimeError), repeated_peer_clause("; elsewhere"):
        raise RuntimeError
    (after,) = _notes(repeated)
    assert after.endswith(PEERS) and PEERS.endswith(DROP_PEERS)


@pytest.mark.parametrize("conventions", ["kitti", "tartanair", "tum", "openloris"])
def test_evaluate_names_the_rule_its_conventions_share(conventions, repeated, data, capsys):
    assert main(["evaluate", str(repeated), "--gt", str(data.tum / GT), "--conventions", conventions]) == 0
    err = capsys.readouterr().err
    said = [s for s in err.splitlines() if "not increasing" in s]
    assert len(said) == 1 and said[0].endswith(PEERS), said
    assert "official tool" not in said[0]


def test_consistency_says_ov_eval_keeps_every_row(repeated, data, tmp_path, capsys):
    est = read_tum(repeated, warn=False, repeated="keep")
    co, cp = synthetic_covariances(est.stamps)
    with_cov = write_ov_eval_file(tmp_path / "est.txt", est, co, cp)
    for path in (repeated, with_cov):  # a TUM estimate (no covariances) and one in ov_eval's layout
        assert main(["consistency", str(path), str(data.tum / GT), "--align", "se3"]) == 0
        err = capsys.readouterr().err
        said = [s for s in err.splitlines() if "not increasing" in s]
        assert len(said) == 1, err
        assert said[0].endswith(
            "); kept the last pose of each repeated stamp; ov_eval keeps every row (docs/guide/consistency.md)"
        ), said
        assert "official tool" not in said[0] and "associate.py" not in said[0] and "sorted" not in said[0]
    (after,) = _notes(repeated)  # the command's words stay in the command
    assert after.endswith(PEERS)
