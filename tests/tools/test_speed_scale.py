"""Parallel evaluation: in local processes and on a Dask cluster the results equal one process's."""

from __future__ import annotations

import time

import numpy as np
import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.cli import main


def _same(a: ln.Evaluation, b: ln.Evaluation) -> None:
    ta, tb = a.sequences(eps="paper", phi=30), b.sequences(eps="paper", phi=30)
    pd.testing.assert_frame_equal(ta, tb)
    assert [f.path for f in a.failures] == [f.path for f in b.failures]
    assert [f.path for f in a.skipped] == [f.path for f in b.skipped]
    for fa, fb in zip(a.errors, b.errors, strict=True):
        for ea, eb in zip(fa.sequences, fb.sequences, strict=True):
            np.testing.assert_array_equal(ea.ate, eb.ate)
            np.testing.assert_array_equal(ea.aoe, eb.aoe)


@pytest.mark.thorough
def test_local_processes_equal_one_process(icra20):
    src = icra20 / "per-seq"
    _same(ln.evaluate(src, jobs=1, scale="auto"), ln.evaluate(src, jobs=2, scale="auto"))


def test_durations_come_from_the_workers_and_equal_reading_the_ground_truth(icra20):
    """Scene durations (the CR denominators) are the spans the workers saw, not a second read of
    every ground truth in the parent; they equal reading it."""
    from lorisnb.core.lifelong.aggregate import durations_table
    from lorisnb.io import load_groundtruth

    ev = ln.evaluate(icra20 / "lifelong", jobs=2, progress=False)
    assert all(f.groundtruth_spans for f in ev.errors)
    scenes = list(dict.fromkeys(ev.durations()["scene"]))
    assert set(scenes) == {f.scene for f in ev.errors} and len(scenes) > 1
    expected = durations_table({s: load_groundtruth(s) for s in scenes})
    pd.testing.assert_frame_equal(ev.durations(), expected)


@pytest.mark.thorough
def test_row_blocks_and_threads_give_the_same_numbers(icra20, monkeypatch):
    """Long per-pose computations run in row blocks, on threads (lorisnb.core.trajectory.blocks): every
    error, RPE included, is the same whatever the block size and thread count."""
    from lorisnb.core.trajectory import blocks

    path = icra20 / "lifelong" / "maslam" / "market.txt"  # 3 sequences, about 11,000 poses
    whole = ln.evaluate(path, jobs=1, progress=False, official_interpolation=False)
    monkeypatch.setattr(blocks, "BLOCK_ROWS", 7)
    with blocks.threads(3):
        small = ln.evaluate(path, jobs=1, progress=False)
        official = ln.evaluate(path, jobs=1, progress=False, official_interpolation=True)
    monkeypatch.setattr(blocks, "BLOCK_ROWS", 1 << 20)
    official_whole = ln.evaluate(path, jobs=1, progress=False, official_interpolation=True)
    for a, b in ((whole, small), (official_whole, official)):
        assert sum(e.matched for e in a.errors[0].sequences) > 1000
        for ea, eb in zip(a.errors[0].sequences, b.errors[0].sequences, strict=True):
            for name in ("ate", "aoe", "est_positions", "gt_positions", "est_quaternions", "gt_quaternions"):
                np.testing.assert_array_equal(getattr(ea, name), getattr(eb, name))
            for x, y in zip(ea.rpe(), eb.rpe(), strict=True):
                np.testing.assert_array_equal(x, y)
    # the statistics of the tables, computed side by side on threads (blocks.each): the same numbers
    from lorisnb.core.lifelong.scoring import score_rows

    alone = score_rows(whole.errors)
    monkeypatch.setattr(blocks, "BLOCK_ROWS", 7)  # each sequence's arrays long enough for threads
    with blocks.threads(3):
        beside = score_rows(whole.errors)
    assert len(alone) == 3 and "ate_median" in alone[0] and "c_rpe_rot_max" in alone[0]
    for ra, rb in zip(alone, beside, strict=True):
        assert ra.keys() == rb.keys()
        for key in ra:
            np.testing.assert_array_equal(np.asarray(ra[key]), np.asarray(rb[key]), err_msg=key)


def test_releasing_the_result_gives_the_same_errors(icra20, data):
    """compute_errors(release=result.sequences.pop), as evaluate() calls it to let a long file's poses
    go sequence by sequence (the edge drops its own object; the core writes into nothing): the same
    errors, every sequence released once, the last only after the frame checks would have looked."""
    from lorisnb.core.pipeline.sessions import compute_errors

    path = icra20 / "lifelong" / "maslam" / "market.txt"
    gt = ln.load_groundtruth("market", data)
    kept_input = ln.read_openloris(path, warn=False)
    kept = compute_errors(kept_input, gt, other_spans={})
    assert sorted(kept_input.sequences) == [1, 2, 3]  # without release, the input is left as it was
    result = ln.read_openloris(path, warn=False)
    released: list[int] = []
    consumed = compute_errors(
        result, gt, other_spans={}, release=lambda s: released.append(result.sequences.pop(s) and s)
    )
    assert len(kept.sequences) == 3 and list(result.sequences) == [] and sorted(released) == [1, 2, 3]
    for a, b in zip(kept.sequences, consumed.sequences, strict=True):
        for name in ("ate", "aoe", "est_positions", "est_quaternions"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert kept.warnings == consumed.warnings


def test_bad_jobs_and_executor(icra20):
    with pytest.raises(ln.ValidationError, match="jobs=0"):
        ln.evaluate(icra20 / "per-seq" / "odom", jobs=0)
    with pytest.raises(ln.ValidationError, match="concurrent.futures.Executor"):
        ln.evaluate(icra20 / "per-seq" / "odom", executor="dask")


@pytest.mark.slow
def test_dask_cluster_equals_one_process(icra20, tmp_path, capsys):
    distributed = pytest.importorskip("distributed")
    src = icra20 / "lifelong"
    serial = ln.evaluate(src, jobs=1)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            _same(serial, ln.evaluate(src, executor=client.get_executor()))
            out = tmp_path / "dask.csv"
            assert main(["evaluate", str(src), "--scheduler", cluster.scheduler_address, "--csv", str(out),
                         "--no-progress"]) == 0  # fmt: skip
    pd.testing.assert_frame_equal(pd.read_csv(out), pd.read_csv(_csv_of(serial, tmp_path)))


@pytest.mark.slow
def test_a_cluster_elsewhere_reads_the_files_named_here(data, tmp_path, monkeypatch, capsys):
    """Relative paths were sent as typed, and each worker opened them in its own folder: a file of
    that name there was scored instead (wrong numbers, exit 0), or none was found. A trailing "/"
    of the address passed the check and failed in distributed; a scheduler without a worker hung."""
    import shutil

    distributed = pytest.importorskip("distributed")
    here, there = tmp_path / "here", tmp_path / "there"
    here.mkdir()
    there.mkdir()
    shutil.copy(data.tum / "fr2_desk_ORB.txt", here / "est.txt")
    shutil.copy(data.tum / "fr2_desk_groundtruth.txt", here / "gt.txt")
    shutil.copy(data.tum / "freiburg1_xyz-rgbdslam.txt", there / "est.txt")  # a decoy where the workers start
    shutil.copy(data.tum / "freiburg1_xyz-groundtruth.txt", there / "gt.txt")
    monkeypatch.chdir(there)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        monkeypatch.chdir(here)
        local = ln.evaluate_pairs("est.txt", "gt.txt", jobs=1).sequences()
        with distributed.Client(cluster) as client:
            remote = ln.evaluate_pairs("est.txt", "gt.txt", executor=client.get_executor()).sequences()
        pd.testing.assert_frame_equal(remote, local)
        out = here / "dask.csv"
        assert main(["evaluate", "est.txt", "--gt", "gt.txt", "--scheduler", cluster.scheduler_address + "/",
                     "--csv", "dask.csv", "--no-progress"]) == 0  # fmt: skip
        pd.testing.assert_frame_equal(
            pd.read_csv(out), pd.read_csv(_csv_of(ln.evaluate_pairs("est.txt", "gt.txt"), tmp_path))
        )
        (here / "bad.txt").write_text("1 2 3\n")  # an error names the file as given here, not by its absolute path
        assert main(["evaluate", "bad.txt", "--gt", "gt.txt", "--scheduler", cluster.scheduler_address,
                     "--no-progress"]) == 1  # fmt: skip
        err = capsys.readouterr().err
        assert "error: bad.txt, line 1" in err and str(here) not in err, err
    with distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=None) as empty:
        t0 = time.monotonic()
        assert (
            main(["evaluate", "est.txt", "--gt", "gt.txt", "--scheduler", empty.scheduler_address, "--no-progress"])
            == 2
        )
        assert "the scheduler has no worker" in capsys.readouterr().err and time.monotonic() - t0 < 30


def _csv_of(ev: ln.Evaluation, tmp_path) -> str:
    p = tmp_path / "serial.csv"
    ev.sequences().to_csv(p, index=False)
    return str(p)


@pytest.mark.slow  # waits for the connection timeout (10 s)
def test_unreachable_scheduler_is_a_clear_error(icra20, capsys):
    pytest.importorskip("distributed")
    assert (
        main(["evaluate", str(icra20 / "per-seq" / "odom"), "--scheduler", "tcp://127.0.0.1:9", "--no-progress"]) == 2
    )
    assert "cannot reach the Dask scheduler" in capsys.readouterr().err


@pytest.mark.thorough
def test_parquet_dataset_has_the_csv_columns_and_values(icra20, tmp_path, capsys):
    pytest.importorskip("pyarrow")
    src = [str(icra20 / "per-seq" / "odom"), str(icra20 / "per-seq" / "dso")]
    pq, csv = tmp_path / "seq.parquet", tmp_path / "seq.csv"
    assert main(["evaluate", *src, "--parquet", str(pq), "--csv", str(csv), "--no-progress"]) == 0
    assert sorted(p.name for p in pq.iterdir()) == [".lorisnb-table", "algorithm=dso", "algorithm=odom"]
    a = pd.read_parquet(pq)
    b = pd.read_csv(csv).fillna({"suite": ""})  # the CSV reads the empty suite back as NaN
    assert set(a.columns) == set(b.columns)
    key = ["algorithm", "file", "seq"]
    a = a.astype({"algorithm": str}).sort_values(key).reset_index(drop=True)[list(b.columns)]
    b = b.sort_values(key).reset_index(drop=True)
    pd.testing.assert_frame_equal(a, b, check_dtype=False)
    assert main(["evaluate", *src, "--parquet", str(pq), "--no-progress"]) == 2  # exists, no --force
    assert main(["evaluate", *src, "--parquet", str(pq), "--force", "--no-progress"]) == 0
    (pq / "notes.txt").write_text("mine")
    assert main(["evaluate", *src, "--parquet", str(pq), "--force", "--no-progress"]) == 2  # not ours alone any more
    assert (pq / "notes.txt").read_text() == "mine"
    assert main(["sweep", *src, "--eps", "1,3", "--parquet", str(tmp_path / "sw"), "--no-progress"]) == 0
    assert len(pd.read_parquet(tmp_path / "sw")) == 2 * len(b)


def test_parquet_force_never_replaces_a_foreign_dataset(icra20, tmp_path, capsys):
    pytest.importorskip("pyarrow")
    foreign = tmp_path / "theirs"
    pd.DataFrame({"a": [1, 2]}).to_parquet(foreign, partition_cols=["a"])
    before = sorted(p.relative_to(foreign) for p in foreign.rglob("*"))
    assert (
        main(["evaluate", str(icra20 / "per-seq" / "odom"), "--parquet", str(foreign), "--force", "--no-progress"]) == 2
    )
    assert "lorisnb did not write it" in capsys.readouterr().err
    assert sorted(p.relative_to(foreign) for p in foreign.rglob("*")) == before


@pytest.mark.thorough
def test_a_sweep_too_large_for_memory_streams_to_parquet_with_the_same_rows(icra20, tmp_path, capsys):
    from lorisnb.core.lifelong.sweep import sweep, sweep_bytes, sweep_groups
    from lorisnb.tools.evaluation.streaming import sweep_to_parquet

    ev = ln.evaluate(icra20 / "lifelong", scale="auto", jobs=1)
    grid = (np.geomspace(0.1, 10, 12), [10.0, 30.0, 90.0], [0.5, 1.0], [30.0, 60.0])
    full = sweep(ev.errors, *grid, columns="all")
    whole = sweep_bytes(ev.errors, (12, 3, 2, 2), "all")
    largest = max(sweep_bytes(g, (12, 3, 2, 2), "all") for g in sweep_groups(ev.errors))
    assert largest < whole / 2
    small = (largest + whole) / 2  # the whole table would not fit, each group does
    with pytest.raises(ln.ValidationError, match=r"GiB .* --parquet DIR; Python: lorisnb.tools.sweep_to_parquet"):
        sweep(ev.errors, *grid, columns="all", max_bytes=small)
    with pytest.raises(ln.ValidationError, match=r"streamed, each group of files \(one algorithm, scene and trial: "
                       r".*\) must fit: use fewer thresholds$"):  # fmt: skip  # --parquet given: not advised again
        sweep_to_parquet(ev.errors, tmp_path / "tiny", *grid, columns="all", max_bytes=largest / 2)
    path, rows = sweep_to_parquet(ev.errors, tmp_path / "big", *grid, columns="all", max_bytes=small)
    assert rows == len(full)
    back = pd.read_parquet(path)
    keys = ["algorithm", "scene", "seq", "eps", "phi", "delta", "tau"]
    a = full.astype({"algorithm": str, "scene": str}).sort_values(keys).reset_index(drop=True)
    b = back.astype({"algorithm": str, "scene": str}).sort_values(keys).reset_index(drop=True)[a.columns]
    for col in ("cr", "cr_t", "cs_r", "c_ate_rmse", "correct_time", "rpe_trans_rmse"):
        np.testing.assert_array_equal(a[col].to_numpy(), b[col].to_numpy())
    # the command line streams with --parquet alone, and prints the scene summary
    args = ["sweep", str(icra20 / "lifelong" / "maslam"), "--eps", "0.5,1,2", "--phi", "10,30"]
    assert main([*args, "--parquet", str(tmp_path / "cli"), "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "rows:" in out and "cr_t" in out
    assert len(pd.read_parquet(tmp_path / "cli")) == len(sweep(ln.evaluate(args[1]).errors, [0.5, 1, 2], [10, 30]))


def test_lent_threads_belong_to_the_thread_that_lent_them():
    """blocks.threads(n) lends n threads to the computations of the thread that lent them; another
    thread (a file's parsing thread converting its piece, a block's own thread) runs its blocks one
    after another on itself, not in a pool inside the pool."""
    import threading
    import time
    from concurrent.futures import ThreadPoolExecutor

    from lorisnb.core.trajectory import blocks

    def where() -> tuple[int, set[int], set[int]]:
        ran: set[int] = set()
        gave: set[int] = set()

        def fn(lo: int, hi: int) -> None:
            ran.add(threading.get_ident())
            time.sleep(0.005)  # long enough that a pool's threads share the blocks

        def each_fn() -> None:
            gave.add(threading.get_ident())
            time.sleep(0.005)

        blocks.blockwise(fn, 12, block=1)
        blocks.each(each_fn, each_fn, each_fn, rows=blocks.BLOCK_ROWS)
        return threading.get_ident(), ran, gave

    with blocks.threads(3):
        me, ran, gave = where()
        with ThreadPoolExecutor(1) as pool:
            other, ran_there, gave_there = pool.submit(where).result()
    assert len(ran) > 1 and me not in ran and len(gave) > 1
    assert ran_there == gave_there == {other}
    assert where()[1:] == ({me}, {me})  # none lent any more


def test_a_cluster_that_loses_every_worker_is_an_error_not_a_hang(monkeypatch):
    """Every worker of the cluster killed mid-run: evaluate --scheduler waited for ever, its bar
    frozen, nothing said. A cluster with no worker for SCHEDULER_TIMEOUT seconds is an error naming
    it and the tasks left; one that keeps a worker is waited for."""
    import threading
    from concurrent.futures import ThreadPoolExecutor

    from lorisnb.tools.evaluation import pool

    monkeypatch.setattr(pool, "SCHEDULER_TIMEOUT", 1.5)
    release = threading.Event()
    with ThreadPoolExecutor(2) as threads:
        stuck = pool.WatchedExecutor(threads, lambda: 0, "--scheduler tcp://127.0.0.1:1")
        t0 = time.monotonic()
        with pytest.raises(ln.EvaluationError, match=r"tcp://127.0.0.1:1: the cluster has had no worker for 1.5 s, 2 "
                           r"task\(s\) of 2 left waiting"):  # fmt: skip
            pool.run_tasks(release.wait, [30.0, 30.0], [1, 1], 2, stuck, desc="x", unit="file")
        assert time.monotonic() - t0 < 10
        release.set()
        alive = pool.WatchedExecutor(threads, lambda: 1, "--scheduler tcp://127.0.0.1:1")
        assert pool.run_tasks(abs, [-1.0, -2.0], [1, 1], 2, alive, desc="x", unit="file") == [1.0, 2.0]
