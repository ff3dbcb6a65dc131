"""Writers: OpenLORIS result files and tables, always through a temporary name moved into place,
never replacing an existing file unless asked.
"""

from __future__ import annotations

import contextlib
import io
import os
import shutil
import tempfile
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from lorisnb.core.spec.validate import flag
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.errors import MissingDependencyError, OutputError

if TYPE_CHECKING:
    import pandas as pd


def write_openloris(
    path: str | os.PathLike,
    sequences: dict[int, Trajectory],
    scene: str,
    frame: str = "base_link",
    header: dict[str, str] | None = None,
    overwrite: bool = False,
) -> None:
    """Write trajectories as an OpenLORIS result file (a simulated one says ``simulated: true`` in
    its header). Written to a temporary name and moved into place; an existing file is kept unless
    ``overwrite``."""
    if Path(path).exists() and not flag("overwrite", overwrite):  # "no" is refused, never truth-tested
        raise OutputError(f"{path} exists; choose another name or pass overwrite=True to replace it")
    lines = [f"scene: {scene}", f"frame: {frame}"]
    extra = dict(header or {})
    if any(t.meta.get("simulated") for t in sequences.values()):
        extra.setdefault("simulated", "true")
    lines += [f"{k}: {v}" for k, v in extra.items()]
    for seq, t in sorted(sequences.items()):
        lines.append(f"seq: {seq}")
        block = np.column_stack([t.stamps, t.positions, t.quaternions])
        lines += [" ".join(f"{v:.17g}" for v in row) for row in block]
    write_text("\n".join(lines) + "\n", path, force=True)


@contextlib.contextmanager
def naming(out: str | os.PathLike[str]) -> Iterator[None]:
    """An :class:`OSError` raised inside names the output ``out`` when the system named no file
    (a full disk, ENOSPC, or a quota, EDQUOT, is raised by ``write()`` with no file name), or
    named the temporary file it is written under: "No space left on device" alone does not say
    which output could not be written."""
    try:
        yield
    except OSError as exc:
        name_output(exc, out)
        raise


def name_output(exc: BaseException, out: str | os.PathLike[str]) -> None:
    """:func:`naming`'s rule for one exception: an :class:`OSError` without a file name, or with
    a temporary one, is given ``out``'s."""
    if isinstance(exc, OSError) and not isinstance(exc, OutputError):
        if exc.filename is None or ".tmp-" in str(exc.filename) or ".partial-" in str(exc.filename):
            exc.filename = str(out)


def write_atomically(out: str | os.PathLike[str], write: Callable[[Path], object], force: bool = False) -> Path:
    """Call ``write(tmp)`` on a temporary name beside ``out``, then move it into place; refuse to
    replace an existing file unless ``force``; never leave the temporary file behind."""
    out = Path(out)
    if out.exists() and not force:
        raise OutputError(f"{out} exists; choose another name or pass --force to replace it")
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.tmp-{os.getpid()}")
    try:
        with naming(out):
            write(tmp)
            os.replace(tmp, out)
    finally:
        tmp.unlink(missing_ok=True)
    return out


def write_csv(df: pd.DataFrame, out: str | os.PathLike[str], force: bool = False) -> Path:
    """Write a table as CSV (:func:`write_csv_parts` with one part)."""
    return write_csv_parts([df], out, force)


def write_csv_parts(parts: Iterable[pd.DataFrame], out: str | os.PathLike[str], force: bool = False) -> Path:
    """Write tables with the same columns one after the other into one CSV file, holding one part
    at a time (a sweep larger than memory is streamed), through :func:`write_atomically`.

    The text is pyarrow's CSV writer's where pyarrow is installed (numbers in the shortest text
    that reads back to the same float, text quoted, ``true``/``false``, missing values empty),
    about 10x faster than pandas' ``to_csv`` on large tables; the header is plain (a name quoted
    only where it needs it). Without pyarrow, or for a part pyarrow cannot convert (Python objects),
    pandas writes it. Either way ``pandas.read_csv`` reads back the same values."""

    def write(tmp: Path) -> None:
        import csv

        header: list[str] | None = None
        with open(tmp, "wb") as f:
            for df in parts:
                names = [str(c) for c in df.columns]
                if header is None:
                    header = names
                    line = io.StringIO()
                    csv.writer(line, lineterminator="\n").writerow(names)
                    f.write(line.getvalue().encode())
                elif names != header:
                    raise OutputError(f"{out}: a part has columns {names}, the first had {header}")
                table = _arrow_table(df)
                if table is None:
                    f.write(df.to_csv(index=False, header=False, lineterminator="\n").encode())
                else:
                    import pyarrow.csv as pa_csv

                    pa_csv.write_csv(table, f, pa_csv.WriteOptions(include_header=False))

    return write_atomically(out, write, force)


def _arrow_table(df: pd.DataFrame) -> object | None:
    """``df`` as a pyarrow table for the CSV writer, or None (no pyarrow, or a column of Python
    objects it does not convert)."""
    try:
        import pyarrow as pa
    except ImportError:
        return None
    try:
        return pa.Table.from_pandas(df, preserve_index=False)
    except (pa.ArrowInvalid, pa.ArrowTypeError, pa.ArrowNotImplementedError):
        return None


def write_text(text: str, out: str | os.PathLike[str], force: bool = False) -> Path:
    """Write text, UTF-8 (:func:`write_atomically`)."""
    return write_atomically(out, lambda p: p.write_text(text, encoding="utf-8"), force)


#: A hidden file in every Parquet dataset lorisnb writes; ``--force`` replaces only such datasets.
TABLE_MARKER = ".lorisnb-table"


def write_parquet(
    df: pd.DataFrame, out: str | os.PathLike[str], partition_by: str = "algorithm", force: bool = False
) -> Path:
    """Write a table as a Parquet dataset (a folder, one sub-folder per ``partition_by`` value,
    e.g. ``algorithm=orbslam2_rgbd/``), with the same columns as the CSV. Built beside ``out`` and
    moved into place; an existing ``out`` is replaced only with ``force`` and only if it is a
    dataset lorisnb wrote (:data:`TABLE_MARKER`) holding nothing else. Needs pyarrow (``pip install 'lorisnb[parquet]'``)."""
    return write_parquet_parts([df], out, partition_by, force)


def _plain(df: pd.DataFrame) -> pd.DataFrame:
    """Categorical columns as their values, so that every part of a dataset has the same schema."""
    import pandas as pd

    cats = [c for c in df.columns if isinstance(df[c].dtype, pd.CategoricalDtype)]
    return df.astype({c: df[c].cat.categories.dtype for c in cats}) if cats else df


def overlap(target: str | os.PathLike[str], inputs: Iterable[str | os.PathLike[str]]) -> tuple[str, str] | None:
    """How an output folder ``target`` meets the inputs: ``("is", input)``, ``("holds", input)``
    (the input lies inside it) or ``("lies in", input)`` (it lies inside an input folder, where a
    later run reading that folder would read it); None when it meets none."""
    t = Path(target).resolve()
    for i in inputs:
        src = Path(i).resolve()
        if t == src:
            return "is", str(i)
        if t in src.parents:
            return "holds", str(i)
        if src in t.parents:
            return "lies in", str(i)
    return None


def check_dataset_target(out: str | os.PathLike[str], force: bool) -> None:
    """Refuse a Parquet dataset's place before anything is written: an existing ``out`` without
    ``force``, or with it one lorisnb did not write (no :data:`TABLE_MARKER`) or holding other files."""
    out = Path(out)
    if not out.exists():
        return
    if not force:
        raise OutputError(f"{out} exists; choose another name or pass --force to replace it")
    files = [p for p in out.rglob("*") if p.is_file()] if out.is_dir() else [out]
    foreign = [p for p in files if p.suffix != ".parquet" and p.name != TABLE_MARKER]
    if foreign or not (out / TABLE_MARKER).is_file():
        what = f"it holds other files ({foreign[0].name})" if foreign else "lorisnb did not write it"
        raise OutputError(f"--force will not replace {out}: {what}; choose another name")


def write_parquet_parts(
    parts: Iterable[pd.DataFrame], out: str | os.PathLike[str], partition_by: str = "algorithm", force: bool = False
) -> Path:
    """Write tables one after the other into one Parquet dataset (as :func:`write_parquet`), each
    part as its own file in its partition's folder: a table larger than memory is streamed, part
    by part, and only one part is held at a time. Nothing is left behind if a part fails."""
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise MissingDependencyError("writing Parquet needs pyarrow: pip install 'lorisnb[parquet]'") from None
    out = Path(out)
    check_dataset_target(out, force)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.tmp-", dir=out.parent))
    try:
        with naming(out):
            data = tmp / "data"
            data.mkdir()
            for n, df in enumerate(parts):
                if partition_by not in df.columns:
                    pq.write_table(
                        pa.Table.from_pandas(_plain(df), preserve_index=False), data / f"part-{n:05d}.parquet"
                    )
                    continue
                df = _plain(df)
                for value, group in df.groupby(partition_by, observed=True, sort=False):
                    folder = data / f"{partition_by}={value}"
                    folder.mkdir(exist_ok=True)
                    table = pa.Table.from_pandas(group.drop(columns=[partition_by]), preserve_index=False)
                    pq.write_table(table, folder / f"part-{n:05d}.parquet")
            (data / TABLE_MARKER).write_text("written by lorisnb\n")  # hidden: Parquet readers skip it
            if out.exists():
                shutil.rmtree(out)
            os.rename(data, out)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return out


def check_owned_folder(out: str | os.PathLike[str], marker: str) -> None:
    """Refuse, before anything is built, to replace an existing ``out`` that does not hold the
    file ``marker`` (written by the tool that made it): lorisnb replaces only what it created."""
    out = Path(out)
    if out.exists() and not (out.is_dir() and (out / marker).is_file()):
        raise OutputError(
            f"{out} exists and lorisnb did not create it (no {marker} file in it); it is left as it is: "
            "choose another output folder"
        )


def replace_folder(built: str | os.PathLike[str], out: str | os.PathLike[str], marker: str) -> Path:
    """Move the finished folder ``built`` to ``out`` with ``marker`` in it, replacing an earlier
    ``out`` only when it holds ``marker`` (:func:`check_owned_folder`, checked again here)."""
    built, out = Path(built), Path(out)
    check_owned_folder(out, marker)
    (built / marker).write_text("created by lorisnb; this folder is replaced by the next build\n")
    out.parent.mkdir(parents=True, exist_ok=True)
    old = Path(tempfile.mkdtemp(prefix=f".{out.name}.old-", dir=out.parent))
    try:
        if out.exists():
            os.replace(out, old / out.name)
        try:
            shutil.move(str(built), str(out))
        except BaseException:
            if (old / out.name).exists() and not out.exists():
                os.replace(old / out.name, out)  # the earlier build back in place
            raise
    finally:
        shutil.rmtree(old, ignore_errors=True)
    return out


def remove_partial(tmp: Path, seconds: float = 10.0) -> None:
    """Remove an unfinished output folder lorisnb made, again while a process being stopped (a
    report's kernel) still writes in it, for up to ``seconds`` (a SIGTERM'd report once left its
    ``.partial`` folder: rmtree met a file written after it listed the folder)."""
    import time

    deadline = time.monotonic() + seconds
    while True:
        shutil.rmtree(tmp, ignore_errors=True)
        if not tmp.exists() or time.monotonic() > deadline:
            return
        time.sleep(0.1)
