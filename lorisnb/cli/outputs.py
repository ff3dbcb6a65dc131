"""Outputs of the commands, checked before any work: distinct paths, the suffix each option writes,
overwrite rules, never an input (so a refused run leaves nothing behind); options a command cannot
use are refused."""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

from lorisnb.errors import OutputError, ValidationError
from lorisnb.io.readers.registry import FORMATS
from lorisnb.io.writers import check_dataset_target, overlap, refuse_not_a_file

#: Suffixes of the files a folder of inputs is walked for (every format's, :mod:`lorisnb.io.readers.registry`):
#: an output among the inputs with one of them would be read as an input by the next run.
INPUT_SUFFIXES = frozenset(x for f in FORMATS.values() for x in f.suffixes)


def check_output(
    out: str | None, inputs: list[str], force: bool, folder: bool = False, option: str = "--csv",
    force_does: str = "replace it",
) -> None:  # fmt: skip
    """Refuse an output before any work: an input of the command, a file in an input folder, a folder output that is, holds or lies in an input (:func:`overlap`), a
    folder for a file, an existing file or folder without --force (the message says what --force
    would do: ``force_does``, :data:`FORCE_DOES`), or a place that cannot be written."""
    if out is None:
        return
    if str(out).strip() == "":
        raise OutputError(f"{option}: an empty path; expected a {'folder' if folder else 'file'} name")
    if not folder and str(out).endswith(("/", os.sep)):  # pathlib drops the slash: outs/new.csv/ wrote a file
        raise OutputError(f"{option} {out}: ends in a slash, which names a folder; {option} writes a file: give its "
                          f"name without the slash ({str(out).rstrip('/' + os.sep) or out})")  # fmt: skip
    target = Path(out).resolve()
    for i in inputs:
        src = Path(i).resolve()
        if target == src:
            raise OutputError(f"{out} is an input of this command; choose another output file")
        if src.is_dir() and src in target.parents and (not folder or target.suffix.lower() in INPUT_SUFFIXES):
            # a file written among the inputs (a folder: overlap's, below): a later run reading the folder
            # finds it there (a result file by its suffix; run.json, diff's mark of a run folder; anything else)
            what = (f"ends in {target.suffix}, so it is (or would be read as) a result file"
                    if target.suffix.lower() in INPUT_SUFFIXES else "a later run reading that folder would find it "
                    "among the inputs (lorisnb writes nothing into a folder it reads)")  # fmt: skip
            raise OutputError(f"{option} {out} lies in the input folder {i} and {what}; choose another name or place")
    if target.is_dir() and not folder:
        raise OutputError(f"{out} is a folder; expected a file name for {option}")
    if not folder:  # a device, a pipe, a socket: never replaced (--csv /dev/null --force replaced the system's)
        refuse_not_a_file(out)
    hit = overlap(target, inputs) if folder else None
    if hit:
        raise OutputError(f"{option} {out} {hit[0]} the input {hit[1]} of this command; choose another output folder")
    if target.exists() and not force:
        raise OutputError(f"{out} exists; choose another name or pass --force to {force_does}")
    parent = target.parent
    while not parent.exists():
        parent = parent.parent
    if not os.access(parent, os.W_OK):
        raise OutputError(f"cannot write {out}: {parent} is not writable; choose another place")
    try:  # os.access answers yes to root everywhere (/proc, a full or read-only file system for some)
        fd, probe = tempfile.mkstemp(prefix=".lorisnb-probe-", dir=parent)
    except OSError as exc:
        raise OutputError(f"cannot write {out}: {parent}: {exc.strerror or exc}; choose another place") from None
    os.close(fd)
    os.unlink(probe)  # the file this check made, and nothing else


#: Options naming a file or folder a command reads (argparse names): an output never replaces them.
INPUT_OPTIONS = ("gt", "est", "times", "gt_times", "est_times", "manifest", "data")


def input_options(args: argparse.Namespace) -> list[str]:
    """The existing files and folders named by the input options (:data:`INPUT_OPTIONS`) of ``args``."""
    given = (getattr(args, k, None) for k in INPUT_OPTIONS)
    return [str(v) for v in given if isinstance(v, (str, os.PathLike)) and str(v).strip() and Path(v).exists()]


#: What ``--force`` does to an existing output, by the option's argparse name, where it does not replace
#: it: a folder of figures is written into (history --out), a Parquet dataset replaced whole only if
#: lorisnb wrote it (:func:`~lorisnb.io.writers.check_dataset_target`).
FORCE_DOES = {
    "out": "write into it (files of the same names replaced, every other file kept)",
    "parquet": "replace it (a Parquet dataset lorisnb wrote, whole)",
}

#: Folder options a command writes files into (never a file of that name, even with --force).
WRITTEN_INTO = ("out",)

#: The file name each output option needs (any case), by its argparse name.
OUTPUT_SUFFIXES: dict[str, tuple[str, ...]] = {
    "csv": (".csv",),
    "pairs_csv": (".csv",),
    "latex": (".tex",),
    "markdown": (".md",),
    "json": (".json",),  # diff's verdict: a --json notes.txt --force replaced any file with JSON
    "junit": (".xml",),
    "kitti_plot": (".png",),
    "summary_csv": (".csv",),
    "plot": (".png", ".svg", ".pdf"),
    "badge": (".svg",),  # diff's badge is SVG text: a --badge b.png held SVG
}


def check_outputs(args: argparse.Namespace, inputs: list[str], files: list[str], folders: tuple[str, ...] = ()) -> None:
    """Every output of a command checked together, first, so that a refused run leaves nothing
    behind: ``files`` and ``folders`` are the command's output options (argparse names, read from
    ``args``); no two of them may name one place, each gets :func:`check_output` (an input, a
    folder, an existing file without ``--force``, a place that cannot be written), a file option
    the suffix it writes (:data:`OUTPUT_SUFFIXES`), a folder option a folder name, and no file may
    lie inside a folder output. ``inputs`` are checked with every input option of ``args``
    (:func:`input_options`: ground truth, times files, manifest, data root)."""
    inputs = [*inputs, *input_options(args)]

    def opt(k: str) -> str:
        return "--" + k.replace("_", "-")

    given = [(k, str(getattr(args, k)), k in folders) for k in [*files, *folders] if getattr(args, k, None) is not None]
    seen: dict[Path, str] = {}
    for k, out, _ in given:
        target = Path(out).resolve()
        if target in seen:
            raise OutputError(f"{seen[target]} and {opt(k)} both name {out}; give each output its own file or folder")
        seen[target] = opt(k)
    for k, out, folder in given:
        if k in WRITTEN_INTO and Path(out).exists() and not Path(out).is_dir():
            raise OutputError(f"{opt(k)} {out}: a file; expected a folder to write into; choose another name")
        check_output(out, inputs, args.force, folder=folder, option=opt(k), force_does=FORCE_DOES.get(k, "replace it"))
        name = Path(out).name.lower()
        suffixes = OUTPUT_SUFFIXES.get(k)
        if not folder and suffixes and not name.endswith(suffixes):
            raise OutputError(f"{opt(k)} {out}: expected a {' or '.join(suffixes)} file name for what {opt(k)} writes")
        if folder and name.endswith((".csv", ".tex", ".md", ".txt")):
            raise OutputError(f"{opt(k)} {out}: expected a folder name, not a file name")
        if k == "parquet":  # what --force may replace: a dataset lorisnb wrote, nothing else
            check_dataset_target(out, args.force)
    for k, out, folder in given:
        inside = [(o, p) for o, p, f in given if not f and Path(out).resolve() in Path(p).resolve().parents]
        if folder and inside:
            raise OutputError(
                f"{opt(inside[0][0])} {inside[0][1]} lies inside the {opt(k)} folder {out}; write it elsewhere"
            )


def refuse_unused(args: argparse.Namespace, unused: dict[str, str]) -> None:
    """Options a command shares with ``evaluate`` but cannot apply: refused, naming what to use."""
    # given: any value but the option's absent one (None, or False of a flag): --tartanair-seed 0 too
    given = [
        (k, use) for k, use in unused.items() if getattr(args, k, None) is not None and getattr(args, k) is not False
    ]
    if given:
        k, use = given[0]
        raise ValidationError(f"--{k.replace('_', '-')}: not used by lorisnb {args.command}; use {use}")
