"""``sweep``'s first line counts its rows as sequences times settings: it said '154 file(s) x 4 eps x
2 phi' over 1728 rows (the lifelong files hold several sequences each), factors that multiply to
1232; the same for the Parquet route."""

from __future__ import annotations

import math
import re

import pytest

from lorisnb.cli import main


@pytest.mark.parametrize("out", ["", "csv", "parquet"])
def test_the_header_factors_multiply_to_the_rows(icra20, data, tmp_path, capsys, out):
    args = ["sweep", str(icra20 / "lifelong" / "orbslam2_t265"), str(icra20 / "per-seq" / "odom"),
            "--data", str(data.root), "--eps", "0.3,1,3", "--phi", "10,30", "--no-progress"]  # fmt: skip
    if out:
        args += [f"--{out}", str(tmp_path / f"s.{out}")]
    assert main(args) == 0
    head = capsys.readouterr().out.splitlines()[0]
    m = re.fullmatch(r"(\d+) rows: (\d+) sequence\(s\) of (\d+) file\(s\) x (.*)", head)
    assert m, head
    factors = [int(f.split()[0]) for f in m.group(4).split(" x ")]
    rows, sequences, files = int(m.group(1)), int(m.group(2)), int(m.group(3))
    assert rows == sequences * math.prod(factors) and sequences > files  # lifelong files: several sequences
