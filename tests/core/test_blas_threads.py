"""The numbers do not depend on how many threads BLAS runs: one process, a pool of processes and a
Dask worker (which runs BLAS on one thread) write the same table to the last digit, as the README's
"Many files" promises. A matrix-vector product's threads each sum a share of the poses, so the sums
behind correct time, C-ATE, C-AOE and C-RPE took their last digits from the thread count
(``lorisnb.core.lifelong.scoring.row_sums``)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest


@pytest.mark.parametrize("name", ["market-1-3-odom.txt"])
@pytest.mark.thorough
def test_one_and_two_blas_threads_write_the_same_table(tmp_path, icra20, name):
    path = next((icra20 / "per-seq").rglob(name))
    tables = []
    for threads in ("1", "2"):
        out = tmp_path / f"t{threads}.csv"
        env = dict(os.environ, OPENBLAS_NUM_THREADS=threads, OMP_NUM_THREADS=threads, MKL_NUM_THREADS=threads)
        cmd = [sys.executable, "-m", "lorisnb.cli", "evaluate", str(path), "--data", str(icra20.parents[1]), "--csv",
               str(out), "--no-progress", "--rpe-delta", "10", "--rpe-unit", "frames"]  # fmt: skip
        subprocess.run(cmd, env=env, check=True, capture_output=True)
        tables.append(out.read_bytes())
    assert b"c_ate_rmse" in tables[0] and tables[0] == tables[1]
