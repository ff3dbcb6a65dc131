"""Writers: OpenLORIS result files and tables, always through a temporary name moved into place,
never replacing an existing file unless asked.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import stat
import tempfile
from collections.abc import Callable, Iterable, Iterator, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from lorisnb.core.spec.validate import flag
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.errors import MissingDependencyError, OutputError, ValidationError

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
    _check_openloris(sequences, scene, frame, header)
    if Path(path).exists() and not flag("overwrite", overwrite):  # "no" is refused, never truth-tested
        raise OutputError(f"{path} exists; choose another name or pass overwrite=True to replace it")
    lines = [f"scene: {scene}", f"frame: {frame}"]
    extra = {str(k).strip(): str(v).strip() for k, v in (header or {}).items()}
    if any(t.meta.get("simulated") for t in sequences.values()):
        extra.setdefault("simulated", "true")
    lines += [f"{k}: {v}" for k, v in extra.items()]
    for seq, t in sorted(sequences.items()):
        lines.append(f"seq: {seq}")
        block = np.column_stack([t.stamps, t.positions, t.quaternions])
        lines += [" ".join(f"{v:.17g}" for v in row) for row in block]
    write_text("\n".join(lines) + "\n", path, force=True)


#: Header keys :func:`write_openloris` writes itself (``seq`` starts a sequence block).
OWN_KEYS = ("scene", "frame", "seq")


def _check_openloris(sequences: Any, scene: Any, frame: Any, header: Any) -> None:
    """What :func:`write_openloris` writes reads back as given: sequence numbers are integers
    (``True`` was written as ``seq: True``), header keys and values one line each (a newline in
    one wrote a line of its own: ``seq: 9`` added a sequence) and no key of the writer's own
    (``scene``, ``frame``: arguments; ``seq``: a block)."""
    if not isinstance(sequences, Mapping):
        raise ValidationError(
            f"sequences: expected a dict {{sequence number: Trajectory}}, got {type(sequences).__name__}"
        )
    for k, t in sequences.items():
        if isinstance(k, (bool, np.bool_)) or not isinstance(k, (int, np.integer)):
            raise ValidationError(f"sequences: key {k!r}: expected a sequence number (an integer, as 'seq: N' reads)")
        if not isinstance(t, Trajectory):
            raise ValidationError(f"sequences[{k}]: expected a Trajectory, got {type(t).__name__}")
    for name, value in (("scene", scene), ("frame", frame)):
        if not isinstance(value, str) or not value.strip() or "\n" in value or "\r" in value:
            raise ValidationError(f"{name}={value!r}: expected a name on one line")
    if header is None:
        return
    if not isinstance(header, Mapping):
        raise ValidationError(f"header: expected a dict of key -> value, got {type(header).__name__}")
    for k, v in header.items():
        key, text = str(k), str(v)
        if not isinstance(k, str) or not key.strip() or ":" in key or any(c in key for c in "\r\n#"):
            raise ValidationError(f"header key {k!r}: expected a word on one line (no ':' nor '#')")
        if key.strip().lower() in OWN_KEYS:
            raise ValidationError(
                f"header key {k!r}: written by write_openloris itself; pass it as its argument"
                + (" (scene=..., frame=...)" if key.strip().lower() != "seq" else " (the sequences' keys)")
            )
        if "\n" in text or "\r" in text:
            raise ValidationError(f"header[{k!r}]={text!r}: a value on one line (it wrote a line of its own)")


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


#: What an existing output name may be for ``--force`` to replace it: a regular file, or a link
#: (the link is replaced, never what it points to). Anything else is never replaced (:func:`not_a_file`).
_KINDS = {stat.S_IFCHR: "a character device", stat.S_IFBLK: "a block device", stat.S_IFIFO: "a named pipe",
          stat.S_IFSOCK: "a socket", stat.S_IFDIR: "a folder"}  # fmt: skip


def not_a_file(out: str | os.PathLike[str]) -> str | None:
    """What ``out`` is where it is neither a regular file nor a link nor absent (``a character
    device``, ``a named pipe``, ``a folder``...): an output never replaces it, ``--force`` or not.
    ``--csv /dev/null --force`` (as root) replaced the system's ``/dev/null`` with a regular file,
    and every later ``> /dev/null`` wrote into it."""
    try:
        mode = os.lstat(out).st_mode
    except OSError:
        return None
    return None if stat.S_ISREG(mode) or stat.S_ISLNK(mode) else _KINDS.get(stat.S_IFMT(mode), "not a regular file")


def refuse_not_a_file(out: str | os.PathLike[str]) -> None:
    """An :class:`OutputError` where the output ``out`` exists as something else than a file
    (:func:`not_a_file`), which no ``--force`` replaces."""
    kind = not_a_file(out)
    if kind is not None:
        raise OutputError(f"{out} is {kind}, not a file: lorisnb writes its outputs as files and never replaces "
                          f"{kind}, --force or not; choose another name")  # fmt: skip


def write_atomically(out: str | os.PathLike[str], write: Callable[[Path], object], force: bool = False) -> Path:
    """Call ``write(tmp)`` on a temporary name beside ``out``, then move it into place; refuse to
    replace an existing file unless ``force``, and anything that is not a file (a device, a pipe, a
    folder: :func:`not_a_file`) always; never leave the temporary file behind."""
    out = Path(out)
    refuse_not_a_file(out)
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


#: Rows of a part turned into CSV text at a time (:func:`write_csv_parts`): a sweep's part of 2 million
#: rows built as one text passed 2 GB (pyarrow's ArrowCapacityError from 32-bit string offsets), and
#: held it all in memory.
CSV_BATCH_ROWS = 100_000


def write_csv_parts(parts: Iterable[pd.DataFrame], out: str | os.PathLike[str], force: bool = False) -> Path:
    """Write tables with the same columns one after the other into one CSV file, holding one part
    at a time (a sweep larger than memory is streamed), through :func:`write_atomically`.

    The text is pandas' ``to_csv(index=False)`` dialect: a value quoted only when it holds a comma, a
    quote or a line break, ``True``/``False``, missing values empty, a whole float with ``.0`` (read
    back as a float). Where pyarrow is installed the lines are built by its compute functions
    (:func:`_arrow_lines`: 4-5x faster than pandas on a 200,000-row table; numbers in the shortest text that reads
    back to the same float, ``1e-07`` as Python writes it); without pyarrow, or for a column it does
    not convert (Python objects), pandas writes the part. ``pandas.read_csv`` reads back the same
    values either way (tested)."""

    def write(tmp: Path) -> None:
        header: list[str] | None = None
        with open(tmp, "wb") as f:
            for df in parts:
                names = [str(c) for c in df.columns]
                if header is None:
                    header = names
                    f.write(df.iloc[:0].to_csv(index=False, lineterminator="\n").encode())
                elif names != header:
                    raise OutputError(f"{out}: a part has columns {names}, the first had {header}")
                for start in range(0, len(df), CSV_BATCH_ROWS):  # a part of any size, in batches of rows
                    batch = df.iloc[start : start + CSV_BATCH_ROWS]
                    lines = _arrow_lines(batch)
                    f.write(
                        lines
                        if lines is not None
                        else batch.to_csv(index=False, header=False, lineterminator="\n").encode()
                    )

    return write_atomically(out, write, force)


def _arrow_lines(df: pd.DataFrame) -> bytes | None:
    """``df``'s rows as CSV lines in pandas' dialect (:func:`write_csv_parts`), built column by column
    with pyarrow's compute functions (no Python loop over rows); None without pyarrow or for a column
    it does not convert."""
    try:
        import pyarrow as pa
        import pyarrow.compute as pc
    except ImportError:
        return None
    if df.shape[1] < 2 or df.columns.duplicated().any():
        return None  # one column: pandas writes a missing value as "" (not an empty line); a name twice
    try:
        table = pa.Table.from_pandas(df, preserve_index=False)
    except (pa.ArrowInvalid, pa.ArrowTypeError, pa.ArrowNotImplementedError):
        return None
    big = pa.large_string()  # 64-bit offsets from the start: a column's text of any size (32-bit ones end at 2 GB)
    comma, empty, newline, point = (pa.scalar(v, big) for v in (",", "", "\n", ".0"))
    texts = []
    for column in table.columns:
        kind = column.type
        if pa.types.is_dictionary(kind):
            column, kind = column.cast(kind.value_type), kind.value_type
        if pa.types.is_boolean(kind):
            text = pc.if_else(column, pa.scalar("True", big), pa.scalar("False", big))
        elif pa.types.is_float64(kind):  # (float32: pandas writes its own shortest text, below)
            text = pc.cast(column, big)  # 3.0 as "3": given its ".0" below, as pandas writes it
            text = pc.if_else(pc.match_substring_regex(text, r"^-?[0-9]+$"), pc.binary_join_element_wise(text, point, empty),
                              text)  # fmt: skip
            # Python's repr writes magnitudes below 1e-4 or from 1e16 with an exponent, pyarrow from other
            # bounds: those values (few in real tables) written by repr, as pandas writes them all
            x = np.abs(column.to_numpy(zero_copy_only=False))
            exponent = pc.fill_null(pc.match_substring(text, "e"), False).to_numpy(zero_copy_only=False)
            odd = np.isfinite(x) & (((x < 1e-4) & (x > 0)) | (x >= 1e16) | exponent)
            if odd.any():
                values = column.to_numpy(zero_copy_only=False)[odd]
                text = pc.replace_with_mask(
                    text.combine_chunks(), pa.array(odd), pa.array([repr(float(v)) for v in values], big)
                )
        elif pa.types.is_integer(kind) or pa.types.is_string(kind) or pa.types.is_large_string(kind):
            text = pc.cast(column, big)
            if not pa.types.is_integer(kind):  # quoted as pandas quotes (csv.QUOTE_MINIMAL)
                quote = pa.scalar('"', big)
                quoted = pc.binary_join_element_wise(quote, pc.replace_substring(text, '"', '""'), quote, empty)
                text = pc.if_else(pc.match_substring_regex(text, '[,"\r\n]'), quoted, text)
        else:
            return None  # dates, lists...: pandas writes them
        texts.append(text)
    lines = pc.binary_join_element_wise(*texts, comma, null_handling="replace", null_replacement="")
    # each line with its end; the array's own bytes are then the lines end to end
    lines = pc.binary_join_element_wise(lines, empty, newline)
    lines = lines.combine_chunks() if isinstance(lines, pa.ChunkedArray) else lines
    ends = np.frombuffer(lines.buffers()[1], np.int64, len(lines) + 1, lines.offset * 8)
    return lines.buffers()[2][int(ends[0]) : int(ends[-1])].to_pybytes()


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


def overlap(
    target: str | os.PathLike[str], inputs: Iterable[str | os.PathLike[str]], resolve: bool = True
) -> tuple[str, str] | None:
    """How an output folder ``target`` meets the inputs: ``("is", input)``, ``("holds", input)``
    (the input lies inside it) or ``("lies in", input)`` (it lies inside an input folder, where a
    later run reading that folder would read it); None when it meets none. ``resolve``: compared
    where each really is (links resolved), else as written (made absolute only)."""
    where = (lambda p: Path(p).resolve()) if resolve else (lambda p: Path(os.path.abspath(p)))
    t = where(target)
    for i in inputs:
        src = where(i)
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


def remove_partial(tmp: Path, seconds: float = 10.0, settle: float = 0.5) -> None:
    """Remove an unfinished output folder lorisnb made, again while a process being stopped (a
    report's kernel) still writes in it, for up to ``seconds``: done once the folder has stayed
    gone for ``settle`` seconds (a SIGTERM'd report once left its ``.partial`` folder: rmtree met
    a file written after it listed the folder; and a writer not yet stopped made the folder again
    right after it was gone, on a loaded machine). Only on a failed run's way out."""
    import time

    deadline = time.monotonic() + seconds
    gone_since: float | None = None
    while True:
        shutil.rmtree(tmp, ignore_errors=True)
        now = time.monotonic()
        gone_since = None if tmp.exists() else (now if gone_since is None else gone_since)
        if (gone_since is not None and now - gone_since >= settle) or now > deadline:
            return
        time.sleep(0.05)
