"""crosscheck --format openloris on a lifelong file: the lifelong row names the sequence lorisnb
evaluate actually fitted (its own record, ``FileErrors.aligned_on``: the first sequence with matches,
not the first with poses), and is left out where that is the sequence compared (no difference to
show); a compared sequence that matches nothing is an error naming the file and the sequence, with
the sequences that do match."""

from __future__ import annotations

import re

import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.tools.peers.crosscheck import crosscheck_openloris

HOME = ("lifelong", "vins_mono_color_imu_with_loop", "home-1.txt")


@pytest.fixture
def first_nomatch(icra20, tmp_path):
    """vins_mono's lifelong home file with sequence 1's stamps moved 5000 s on: it matches nothing,
    so lorisnb aligns the file on sequence 2."""
    out, seq = [], None
    for line in icra20.joinpath(*HOME).read_text().splitlines():
        if m := re.match(r"seq:\s*(\d+)", line):
            seq = int(m[1])
        fields = line.split()
        if seq == 1 and len(fields) == 8:
            line = " ".join([f"{float(fields[0]) + 5000:.6f}", *fields[1:]])
        out.append(line)
    path = tmp_path / "home-1.txt"
    path.write_text("\n".join(out) + "\n")
    return path


def _lifelong_rows(table):
    return table[table["note"].str.contains("lifelong mode", regex=False)]


@pytest.mark.thorough
def test_the_lifelong_row_names_the_sequence_fitted(first_nomatch, data):
    with pytest.warns(ln.LorisWarning, match="lifelong alignment was computed on sequence 2"):
        table = crosscheck_openloris(first_nomatch, seq=3, data_root=data.root)
    life = _lifelong_rows(table)
    assert len(life) == 1
    row = life.iloc[0]
    assert row["note"].startswith("definitions differ: lorisnb lifelong mode aligns on sequence 2 (the first "
                                  "sequence with matches) and applies it to sequence 3")  # fmt: skip
    evaluated = ln.evaluate(first_nomatch, data_root=data.root, jobs=1).sequences().set_index("seq").loc[3, "ate_rmse"]
    assert row["lorisnb"] == pytest.approx(evaluated, abs=1e-12) and row["lorisnb"] == pytest.approx(1.50982, abs=1e-5)
    assert row["evo"] == pytest.approx(0.466396, abs=1e-6)  # evo aligns sequence 3 on itself


@pytest.mark.thorough
def test_no_lifelong_row_where_the_fitted_sequence_is_the_one_compared(first_nomatch, icra20, data):
    with pytest.warns(ln.LorisWarning):
        assert _lifelong_rows(crosscheck_openloris(first_nomatch, seq=2, data_root=data.root)).empty
    assert _lifelong_rows(crosscheck_openloris(icra20.joinpath(*HOME), data_root=data.root)).empty  # seq 1 on 1
    life = _lifelong_rows(crosscheck_openloris(icra20.joinpath(*HOME), seq=2, data_root=data.root)).iloc[0]
    assert "aligns on sequence 1 (the first sequence) and applies it to sequence 2" in life["note"]
    assert life["lorisnb"] == pytest.approx(4.290224, abs=1e-6)  # issue #2 reference: seq 2 ATE RMSE


@pytest.mark.thorough
def test_a_sequence_matching_nothing_names_file_sequence_and_the_sequences_that_match(first_nomatch, data, capsys):
    assert main(["crosscheck", "auto", str(first_nomatch), "--format", "openloris", "--data", str(data.root)]) == 1
    err = capsys.readouterr().err
    assert (
        f"error: {first_nomatch}, seq 1: no estimate stamp lies within 0.5 s of ground truth on both sides; "
        "estimate spans 1560005007.231..1560005153.490 s, ground truth 1560000002.614..1560000155.280 s; "
        "sequences 2, 3, 4, 5 of the file match the ground truth: cross-check one with --seq N (seq=N in Python)"
    ) in err
