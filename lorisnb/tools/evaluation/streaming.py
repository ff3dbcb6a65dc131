"""Sweeps larger than memory, streamed to a Parquet dataset or a CSV file one group of files at a time."""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any, TypeVar

import pandas as pd

from lorisnb.core.lifelong.scoring import OF_SPEC, thresholds_of
from lorisnb.core.lifelong.sweep import MAX_SWEEP_BYTES, check_sweep_size, sweep, sweep_groups
from lorisnb.core.pipeline.model import FileErrors
from lorisnb.core.spec.validate import choice, flag, threshold_list
from lorisnb.io.writers import write_csv_parts, write_parquet_parts

T = TypeVar("T")


def sweep_to_parquet(
    errors: FileErrors | Iterable[FileErrors],
    out: str | os.PathLike[str],
    eps: Any = OF_SPEC,
    phi: Any = OF_SPEC,
    delta: Any = OF_SPEC,
    tau: Any = OF_SPEC,
    *,
    relative_to: str | None = None,
    columns: str = "metrics",
    force: bool = False,
    progress: bool = False,
    max_bytes: float = MAX_SWEEP_BYTES,
    on_part: Any = None,
    rpe_delta: float = OF_SPEC,
    rpe_unit: str = OF_SPEC,
    fmt: str = "parquet",
    **rpe: Any,
) -> tuple[Path, int]:
    """The table of :func:`lorisnb.core.lifelong.sweep.sweep` (same columns, same values: ``columns``
    is its ``"metrics"`` by default, ``"all"`` for every column of ``score``), written to a
    Parquet dataset partitioned by algorithm, one group of files (suite, algorithm, scene, trial)
    at a time: memory holds one group's rows, never the whole table. Each group must fit in
    ``max_bytes`` (refused up front, with the size it would need, otherwise).

    Args:
        eps, phi, delta, tau: as :func:`~lorisnb.core.lifelong.sweep.sweep`'s: each not given is the
            one value of the spec the errors were evaluated under (the same for every group).
        rpe: ``rpe_pairs``, ``rpe_all_pairs``, ``rpe_tolerance`` (see :func:`lorisnb.core.lifelong.sweep.sweep`).
        on_part: called with each group's table before it is written (for example to keep its
            scene aggregate); a DataFrame it returns is written instead of the table.
        fmt: ``"parquet"`` (a dataset) or ``"csv"`` (one file, :func:`lorisnb.io.writers.write_csv_parts`;
            use :func:`sweep_to_csv`).

    Returns:
        the dataset's path and the number of rows written.
    """
    progress = flag("progress", progress)
    fmt = choice("fmt", fmt, ("parquet", "csv"))
    groups = sweep_groups(errors)
    given = dict(eps=eps, phi=phi, delta=delta, tau=tau)
    if relative_to is not None and eps is OF_SPEC:
        given.pop("eps")  # the spec's metres are no fraction: sweep's own rule (every pose correct)
    spec = thresholds_of([f for g in groups for f in g], given)  # one setting for all groups, checked together
    eps, phi, delta, tau = (
        (spec[k],) if k in given and v is OF_SPEC else v
        for k, v in (("eps", eps), ("phi", phi), ("delta", delta), ("tau", tau))
    )
    shape = tuple(
        1 if v is OF_SPEC else len(threshold_list(n, v))
        for n, v in (("eps", eps), ("phi", phi), ("delta", delta), ("tau", tau))
    )
    for g in groups:  # every group checked before anything is written
        check_sweep_size(g, shape, columns, max_bytes, streamed=True)  # type: ignore[arg-type]
    rows = 0

    def parts() -> Iterator[pd.DataFrame]:
        nonlocal rows
        bar = None
        if progress:
            from tqdm.auto import tqdm

            bar = tqdm(total=len(groups), desc="sweeping", unit="group")
        try:
            for g in groups or [[]]:  # no file scored: an empty table, its header still written
                table = sweep(
                    g, eps, phi, delta, tau, relative_to=relative_to, columns=columns, max_bytes=max_bytes,
                    rpe_delta=rpe_delta, rpe_unit=rpe_unit, **rpe,
                )  # fmt: skip
                rows += len(table)
                if on_part is not None:
                    replaced = on_part(table)
                    table = replaced if isinstance(replaced, pd.DataFrame) else table
                yield table
                if bar is not None:
                    bar.update()
        finally:
            if bar is not None:
                bar.close()

    if fmt == "csv":
        return write_csv_parts(one_ahead(parts()), out, force=force), rows
    return write_parquet_parts(one_ahead(parts()), out, force=force), rows


def one_ahead(items: Iterator[T]) -> Iterator[T]:
    """``items``, each computed on a thread while the one before is consumed: a sweep's next group
    is scored while its last one is written (they overlap where numpy's and pyarrow's C code runs
    without the GIL). Memory holds two parts; an error of ``items`` is raised where its item would be.
    Measured on the whole icra20 tree, 100 eps x 100 phi to CSV (2 shared cores): 54 s one after
    the other, 42 s overlapped (``make bench``'s sweep row)."""
    done = object()
    with ThreadPoolExecutor(max_workers=1, thread_name_prefix="lorisnb-ahead") as pool:
        pending = pool.submit(next, items, done)
        while True:
            item = pending.result()
            if item is done:
                return
            pending = pool.submit(next, items, done)
            yield item  # type: ignore[misc]


def sweep_to_csv(errors: FileErrors | Iterable[FileErrors], out: str | os.PathLike[str], *args: Any,
                 **kwargs: Any) -> tuple[Path, int]:  # fmt: skip
    """:func:`sweep_to_parquet`'s table streamed to one CSV file (same arguments): one group of
    files in memory at a time, in pandas' CSV text (:func:`lorisnb.io.writers.write_csv_parts`)."""
    return sweep_to_parquet(errors, out, *args, fmt="csv", **kwargs)
