"""Provenance of a report run: ``run.json`` (the command line, lorisnb's version and git commit,
the evaluation spec, the data root, when, a SHA-256 of every input file, and each notebook's
status), and :func:`verify_run`, which re-checks the inputs' checksums and the listing of the
folders they came from.

``run.json`` keys (read by ``lorisnb diff`` and ``lorisnb history`` too; keep them):
``command`` (argv list), ``lorisnb_version``, ``commit`` (git commit of the lorisnb checkout, or
null when lorisnb is installed from a wheel), ``spec`` (``description``: the evaluation's
conventions in words; ``values``: thresholds eps, phi, delta, tau, the scale mode, the
conventions, the metric and test settings of the leaderboard), ``data_root``, ``created`` (ISO
8601, UTC), ``inputs`` (path -> sha256; relative paths are below ``data_root``), ``notebooks``
(name -> status), ``input_roots`` (the files and folders whose listing gave ``inputs``, so that
:func:`verify_run` notices a file added to them; absent in runs of lorisnb 0.x before it),
``roots`` (root name -> its absolute path, or null where the run is portable: see
:mod:`lorisnb.tools.report.portable`; absent in runs before named roots), ``baseline_inputs``
(a run made against a baseline: the files of the earlier run its verdict read, path -> sha256,
below ``{baseline}``; :func:`with_baseline`).

In a portable run (the default) the paths of ``inputs``, ``input_roots`` and ``data_root`` are
written ``{name}/inside`` below a named root (``{data}``, ``{results}``...), and :func:`verify_run`
reads them below the folders its caller names for those roots, never below a folder the file
names: a received run.json cannot make verify read outside the run folder and those roots.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import os
import re
import stat
import subprocess
import sys
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from lorisnb._version import __version__
from lorisnb.core.spec import validate
from lorisnb.errors import LorisError, ParseError, ValidationError
from lorisnb.io.writers import naming
from lorisnb.tools.report.portable import command_by_root, mark, resolve_key, root_key, split_key

RUN_JSON = "run.json"
KEYS = ("command", "lorisnb_version", "commit", "spec", "data_root", "created", "inputs", "notebooks")


def sha256(path: Path, chunk: int = 1 << 20) -> str:
    """The SHA-256 of a regular file's bytes, hex; a FIFO or a device (bytes without end, or never
    any) is a :class:`~lorisnb.errors.ValidationError` naming it, never waited on
    (:func:`open_regular`)."""
    h = hashlib.sha256()
    with open_regular(path) as f:
        while block := f.read(chunk):
            h.update(block)
    return h.hexdigest()


#: What :func:`verify_run` says of an input, or of an entry of a folder the run read, that is neither a
#: file nor a folder (a FIFO, a device: never opened, whatever its name).
NOT_A_FILE = "not a regular file"

#: Why a run folder's FIFO, device or socket is not read (the end of :func:`run_file`'s message).
NOT_REGULAR = ("not a regular file (a FIFO, a device): a run folder lorisnb writes holds none (a received run?); it "
               "was not read. Remove it, or copy the run again from where it came")  # fmt: skip


def open_regular(path: Path) -> Any:
    """``path`` opened for reading in binary, if it is a regular file: checked before it is opened
    (a FIFO waits for a writer when opened, a device has no end) and again on what was opened (it
    may have been replaced meanwhile), opened without waiting; else a
    :class:`~lorisnb.errors.ValidationError` naming it."""
    if not stat.S_ISREG(os.stat(path).st_mode):
        raise ValidationError(f"{path}: {NOT_REGULAR}")
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise ValidationError(f"{path}: {NOT_REGULAR}")
        if hasattr(os, "set_blocking"):
            os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def read_run_file(folder: str | os.PathLike[str], path: Path) -> bytes:
    """The bytes of ``path``, a file of the run folder ``folder``, read once :func:`run_file` has
    found it inside the folder and a regular file (:func:`open_regular`)."""
    with open_regular(run_file(folder, path)) as f:
        data: bytes = f.read()
    return data


def git_commit(start: Path | None = None) -> str | None:
    """The commit of the git checkout lorisnb runs from (None when it is not one, or git is missing)."""
    here = start or Path(__file__).resolve().parents[3]
    if not (here / ".git").exists():
        return None
    try:
        out = subprocess.run(
            ["git", "-C", str(here), "rev-parse", "HEAD"], capture_output=True, text=True, timeout=10, check=False
        )
    except (OSError, subprocess.TimeoutExpired):
        return None
    commit = out.stdout.strip()
    return commit if out.returncode == 0 and len(commit) == 40 else None


def input_files(roots: Iterable[Path], resolve: bool = True, inside: Iterable[Path] | None = None) -> list[Path]:
    """Every regular file of ``roots`` (files, or folders walked as an evaluation walks them:
    :func:`~lorisnb.tools.evaluation.inputs.walk`, linked folders followed, only those leading
    into ``inside`` when given), hidden files left out, sorted, each once; resolved (a link to a
    file: its target) unless not ``resolve``."""
    return _listing(roots, resolve, inside)[0]


def _listing(
    roots: Iterable[Path], resolve: bool = True, inside: Iterable[Path] | None = None
) -> tuple[list[Path], list[Path], list[Path]]:
    """:func:`input_files`, the linked folders of ``roots`` left unwalked because they lead
    outside ``inside`` (as found, not resolved; hidden ones left out as hidden files are), and the
    entries that are neither a file nor a folder (a FIFO, a device, a socket: never opened; as found)."""
    from lorisnb.tools.evaluation.inputs import walk

    allowed = None if inside is None else [Path(f) for f in inside]
    found: dict[Path, None] = {}
    unwalked: dict[Path, None] = {}
    odd: dict[Path, None] = {}
    for root in roots:
        if root.is_file():
            found[root.resolve() if resolve else root] = None
        elif root.is_dir():
            for f in sorted(walk(root, allowed), key=lambda f: f.path):
                p = f.path
                if any(part.startswith(".") for part in p.relative_to(root).parts):
                    continue
                if f.kind == "folder":
                    if allowed is not None and p.is_symlink() and not _inside(Path(f.real), allowed):
                        unwalked[p] = None
                elif p.is_file():
                    found[p.resolve() if resolve else p] = None
                elif f.kind == "other":
                    odd[p] = None
    return sorted(found), sorted(unwalked), sorted(odd)


def _key(path: Path, data_root: Path | Mapping[str, Path] | None) -> str:
    if isinstance(data_root, Mapping):
        return root_key(path, data_root)
    if data_root is not None:
        try:
            return path.relative_to(data_root.resolve()).as_posix()
        except ValueError:
            pass
    return str(path)


def checksums(files: Iterable[Path], data_root: Path | Mapping[str, Path] | None) -> dict[str, str]:
    """path -> sha256; paths below ``data_root`` relative to it, others absolute; with named
    roots (name -> folder), ``{name}/inside`` (:func:`~lorisnb.tools.report.portable.root_key`)."""
    return {_key(p, data_root): sha256(p) for p in files}


def run_record(
    command: list[str],
    spec: Mapping[str, Any],
    data_root: Path | None,
    inputs: Mapping[str, str],
    notebooks: Mapping[str, str],
    roots: Iterable[Path] = (),
    named: Mapping[str, Path] | None = None,
    absolute: bool = True,
) -> dict[str, Any]:
    """The content of ``run.json`` (see the module docstring); ``roots``: the files and folders
    whose listing gave the inputs (:func:`input_files`); ``named``: the named roots (name ->
    folder) the keys of ``inputs`` were written below, recorded by name only unless ``absolute``
    (then every path is absolute), and so is each root ``command`` names (``--data ../data``:
    ``--data {data}``, :func:`~lorisnb.tools.report.portable.command_by_root`)."""
    if named is not None:
        if not absolute:  # each root by its name, however it was typed (--data ../data, --results reslink)
            command = command_by_root(command, named)
        record = run_record(command, spec, data_root, inputs, notebooks, (), None)
        record["data_root"] = (str(data_root) if absolute else mark("data")) if data_root is not None else None
        record["input_roots"] = [str(r.resolve()) if absolute else root_key(r, named) for r in roots]
        record["roots"] = {k: str(v.resolve()) if absolute else None for k, v in named.items()}
        return record
    return {
        "command": list(command),
        "lorisnb_version": __version__,
        "commit": git_commit(),
        "spec": dict(spec),
        "data_root": str(data_root) if data_root is not None else None,
        # to the microsecond: a baseline is a run made before CAND (lorisnb.tools.decisions.history.not_before),
        # and two runs of one second (a scripted report and its --baseline run) were one time, the baseline passed over
        "created": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="microseconds"),
        "inputs": dict(inputs),
        "notebooks": dict(notebooks),
        "input_roots": [_key(r.resolve(), data_root) for r in roots],
    }


def with_baseline(record: Mapping[str, Any], folder: Path, files: Mapping[str, str], absolute: bool) -> dict[str, Any]:
    """``record`` (the content of ``run.json``) of a run made against a baseline (``report
    --baseline DIR``) with ``baseline_inputs``: the files of the earlier run its verdict read
    (``files``: path below the folder of earlier runs ``folder`` -> SHA-256,
    :func:`lorisnb.tools.report.baseline.baseline_files`) below the named root ``{baseline}``
    (absolute paths with ``absolute``), that root added to ``roots``. :func:`verify_run` checks
    them where its caller says where that root is."""
    keys = {(os.path.join(os.path.abspath(folder), rel) if absolute else f"{mark('baseline')}/{rel}"): h
            for rel, h in files.items()}  # fmt: skip
    roots = {**(record.get("roots") or {}), "baseline": str(folder.resolve()) if absolute else None}
    command = record.get("command")
    if not absolute and isinstance(command, list):  # --baseline DIR by its root's name, however it was typed
        command = command_by_root(command, {"baseline": Path(os.path.abspath(folder))})
    return {**record, "command": command, "baseline_inputs": keys, "roots": roots}


def write_run_json(run_dir: Path, record: Mapping[str, Any]) -> Path:
    out = run_dir / RUN_JSON
    with naming(out):  # a full disk names the file
        out.write_text(json.dumps(record, indent=2, default=str) + "\n", encoding="utf-8")
    return out


class _DuplicateKey(ValueError):
    """A JSON object naming one key twice (:func:`load_json`)."""


class _HugeNumber(ValueError):
    """A JSON integer of more digits than Python converts (:func:`load_json`)."""


def _int(text: str) -> int:
    """A JSON integer, or :class:`_HugeNumber` where it has more digits than Python converts
    (:func:`sys.get_int_max_str_digits`, 4,300 by default), which ``int`` would refuse with a
    ValueError asking to raise that limit."""
    limit = sys.get_int_max_str_digits() if hasattr(sys, "get_int_max_str_digits") else 0
    if limit and len(text.lstrip("-")) > limit:
        raise _HugeNumber(len(text.lstrip("-")))
    return int(text)


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in pairs:
        if k in out:
            raise _DuplicateKey(k)
        out[k] = v
    return out


def load_json(data: bytes | str, f: str | os.PathLike[str], expected: str) -> Any:
    """The JSON value of ``data``, the bytes of the file ``f`` of a run (run.json, its marker) as a
    received run may hold them: anything that is not the JSON lorisnb writes (not UTF-8, not JSON,
    nested too deeply for Python's parser, an object naming a key twice, where readers would
    disagree on which is meant, an integer of more digits than Python reads) is a
    :class:`~lorisnb.errors.ParseError` ``f: not valid JSON (...); expected`` ``expected``. Every
    error Python's parser raises on hostile bytes is one of those: a ValueError (not UTF-8, not
    JSON, an integer too long), a RecursionError (nesting), a MemoryError (a file too large for
    this machine); a float too large is read as infinity, which the checks of each key refuse."""
    try:
        text = data.decode("utf-8") if isinstance(data, bytes) else data
        return json.loads(text, object_pairs_hook=_no_duplicates, parse_int=_int)
    except _DuplicateKey as exc:
        why = f"the key {json.dumps(str(exc.args[0]))[:80]} given twice in one object"
    except _HugeNumber as exc:
        why = f"an integer of {exc.args[0]} digits, more than can be read; no file lorisnb writes holds one"
    except RecursionError:
        why = "nested too deeply to be read"
    except MemoryError:
        why = "too large to be read into memory"
    except ValueError as exc:  # not UTF-8 (UnicodeDecodeError), not JSON (JSONDecodeError), any other value refused
        why = str(exc)
    raise ParseError(f, None, f"not valid JSON ({why}); expected {expected}")


def _is_str_map(v: Any) -> bool:
    return isinstance(v, dict) and all(isinstance(x, str) for x in v.values())


def _is_text_or_null(v: Any) -> bool:
    return v is None or isinstance(v, str)


def _is_path(v: Any) -> bool:
    """A path as run.json writes one: text without a NUL byte (no file system takes one)."""
    return isinstance(v, str) and "\x00" not in v


def _is_file_path(v: Any) -> bool:
    """A file's path as run.json writes one: a path (:func:`_is_path`), not empty, not ending in a
    separator (a folder's)."""
    return _is_path(v) and v != "" and not v.endswith(("/", os.sep))


def _is_path_map(v: Any) -> bool:
    return _is_str_map(v) and all(map(_is_file_path, v))


_SHA256 = re.compile(r"[0-9a-f]{64}")


def _is_digest(v: Any) -> bool:
    """A SHA-256 as :func:`sha256` writes it: 64 hexadecimal digits, lower case."""
    return isinstance(v, str) and _SHA256.fullmatch(v) is not None


def check_digests(record: Mapping[str, Any], f: str | os.PathLike[str]) -> None:
    """A :class:`~lorisnb.errors.ParseError` naming run.json (``f``) if a checksum of its ``inputs`` or
    ``baseline_inputs`` is no SHA-256 as lorisnb writes one: a damaged run.json, whose input would
    otherwise be reported "changed" (:func:`read_run_json` checks it for every command that reads a
    run: verify compares checksums with files, diff and history with each other)."""
    for key in ("inputs", "baseline_inputs"):
        bad = next(([k, v] for k, v in (record.get(key) or {}).items() if not _is_digest(v)), None)
        if bad is not None:
            shown = json.dumps(bad, default=str)
            shown = shown if len(shown) <= 80 else shown[:77] + "..."
            raise ParseError(f, None, f'"{key}" holds {shown}; expected an object path -> SHA-256 (64 hexadecimal '
                             "digits, as lorisnb writes it): a damaged run.json, not a changed input")  # fmt: skip


def _is_absolute_path(v: Any) -> bool:
    return _is_path(v) and os.path.isabs(v)


#: What each key of run.json must hold: (check, what is expected in words).
SHAPES: dict[str, tuple[Any, str]] = {
    "command": (lambda v: isinstance(v, list) and all(isinstance(x, str) for x in v), "a list of strings"),
    "lorisnb_version": (_is_text_or_null, "a version string or null"),
    "commit": (_is_text_or_null, "a git commit or null"),
    "label": (_is_text_or_null, "the name of the code under test or null"),
    "spec": (
        lambda v: (
            isinstance(v, dict) and isinstance(v.get("values", {}), dict) and _is_text_or_null(v.get("description"))
        ),
        'an object {"description": text, "values": {...}}',
    ),  # fmt: skip
    "data_root": (lambda v: v is None or _is_path(v), "a folder path or null"),
    "created": (_is_text_or_null, "an ISO 8601 time"),
    "inputs": (
        _is_path_map,
        "an object path -> SHA-256, each the path of a file (not empty, not ending in /, without a NUL byte)",
    ),
    "notebooks": (_is_str_map, "an object notebook name -> status"),
    "input_roots": (lambda v: isinstance(v, list) and all(map(_is_path, v)), "a list of paths (without a NUL byte)"),
    "baseline_inputs": (
        _is_path_map,
        "an object path -> SHA-256, each the path of a file (not empty, not ending in /, without a NUL byte)",
    ),
    "dirty": (lambda v: v is None or isinstance(v, bool), "true, false or null (whether the checkout had changes)"),
    "roots": (
        lambda v: isinstance(v, dict) and all(x is None or _is_absolute_path(x) for x in v.values()),
        "an object root name -> null, or its folder on the machine the run was made on (a run made with "
        "--absolute-paths): expected an absolute folder",
    ),
}


def read_run_json(run: str | os.PathLike[str]) -> dict[str, Any]:
    """``run.json`` of a run folder (or the file itself), every key checked (:data:`SHAPES`); a
    :class:`~lorisnb.errors.ParseError` naming the file and what was expected if it is not one."""
    p = Path(run)
    f = p / RUN_JSON if p.is_dir() else p
    if not os.path.lexists(f) or os.path.isdir(f):
        raise LorisError(f"{p}: no {RUN_JSON} here; expected a run folder written by lorisnb report")
    record = load_json(read_run_file(f.parent, f), f, "the run.json lorisnb report writes")
    if not isinstance(record, dict):
        raise ParseError(f, None, f"a JSON {type(record).__name__}; expected an object with the keys {', '.join(KEYS)}")
    missing = [k for k in KEYS if k not in record]
    if missing:
        raise ParseError(f, None, f"lacks key(s) {', '.join(missing)}; expected the run.json lorisnb report writes")
    for key, (ok, expected) in SHAPES.items():
        if key in record and not ok(record[key]):
            value = record[key]
            culprit = None  # in a map or list of paths of the right type: the entry that is not one
            if key in ("inputs", "baseline_inputs") and isinstance(value, dict):
                culprit = next(
                    ([k, v] for k, v in value.items() if not (_is_file_path(k) and isinstance(v, str))), None
                )
            elif key == "roots" and isinstance(value, dict):
                culprit = next(([k, v] for k, v in value.items() if not (v is None or _is_absolute_path(v))), None)
            elif key == "input_roots" and isinstance(value, list):
                culprit = next((x for x in value if not _is_path(x)), None)
            shown = json.dumps(value if culprit is None else culprit, default=str)
            shown = shown if len(shown) <= 80 else shown[:77] + "..."
            where = f'"{key}" holds' if culprit is not None else f'"{key}" is'
            raise ParseError(f, None, f"{where} {shown}; expected {expected}")
    check_digests(record, f)  # every reader: a checksum that is no SHA-256 is a damaged run.json
    created_of(record, f)  # a time that is none, a spec value no spec has: refused by every reader alike
    check_spec_values(record.get("spec"), f)
    return record


def created_of(meta: Mapping[str, Any], file: str | os.PathLike[str]) -> _dt.datetime | None:
    """run.json's ``created``: None where it is null (the run is then ordered by the file's time),
    else an ISO 8601 time (UTC where it names no zone); any other text is a damaged run.json,
    refused naming the file and the key as its other keys are (:func:`read_run_json`)."""
    value = meta.get("created")
    if value is None:
        return None
    try:
        t = _dt.datetime.fromisoformat(str(value).replace("Z", "+00:00"))
    except ValueError:
        shown = json.dumps(value)
        shown = shown if len(shown) <= 80 else shown[:77] + "..."
        raise ParseError(file, None, f'"created" is {shown}; expected an ISO 8601 time as lorisnb report writes it '
                         "(2026-02-01T03:00:00+00:00) or null; a damaged or edited run.json?") from None  # fmt: skip
    return t if t.tzinfo else t.replace(tzinfo=_dt.timezone.utc)


def check_spec_values(spec: Any, file: str | os.PathLike[str]) -> None:
    """run.json's ``spec`` (read from ``file``) checked by :func:`spec_problem`: a value no spec has
    is a damaged run.json, refused with a :class:`~lorisnb.errors.ParseError` naming the file and
    the key, never reported as two specs that differ (:func:`read_run_json`)."""
    problem = spec_problem(spec)
    if problem:
        raise ParseError(file, None, f'"spec" values: {problem}; no run lorisnb makes has it (a damaged or edited '
                         "run.json?): make the run again")  # fmt: skip


def spec_problem(spec: Any) -> str | None:
    """What is wrong with the values of a recorded evaluation spec (run.json's ``spec``, or its
    ``values``, a table's ``spec`` cell) by the spec's own rules
    (:func:`lorisnb.core.spec.evalspec.make_spec`: an eps of NaN or -1 is no spec's), naming the
    key; None when nothing is. Keys this lorisnb does not know (a run of another version) are left
    to the comparison, which names them; so are those of the spec's command-line spellings
    (``scale``: :data:`~lorisnb.core.spec.evalspec.ALIASES`)."""
    from lorisnb.core.spec.evalspec import ALIASES, PRESETS, SPEC_NAMES, make_spec

    values = spec.get("values", spec) if isinstance(spec, dict) else None
    if not isinstance(values, dict):
        return None
    preset = values.get("preset")
    known = {k: v for k, v in values.items() if k in SPEC_NAMES and k not in ALIASES}
    try:
        make_spec(preset if isinstance(preset, str) and preset in PRESETS else None, **known)
    except ValidationError as exc:
        return str(exc)
    return None


#: A root's name as a run writes it (``{data}``, ``{groundtruth}``): letters, digits and ``_``.
ROOT_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def root_name_problem(name: str) -> str | None:
    """Why ``name`` cannot name a root given to :func:`verify_run` (``verify --root NAME DIR``), or
    None: not a root's name as a run writes it, or ``run`` (the run folder itself, which verify
    finds)."""
    if name == "run":
        return ("{run} is the run folder itself, which verify finds (RUN); give the root's name as run.json "
                "writes it, without braces (data, results, groundtruth, baseline...)")  # fmt: skip
    if not ROOT_NAME.fullmatch(name):
        return ("not a root's name (letters, digits and _, not starting with a digit); give it as run.json writes "
                "it, without braces (data, results, groundtruth, baseline...)")  # fmt: skip
    return None


def roots_used(record: Mapping[str, Any]) -> set[str]:
    """The names of the roots a run's ``run.json`` (``record``) reads anything below, or records."""
    keys = [*(record.get("inputs") or {}), *(record.get("input_roots") or []), *(record.get("baseline_inputs") or {})]
    if isinstance(record.get("data_root"), str):
        keys.append(record["data_root"])
    named = {n[0] for n in map(split_key, keys) if n is not None}
    return (named | set(record.get("roots") or {})) - {"run"}


def unchecked_baseline(record: Mapping[str, Any], roots: Mapping[str, Any]) -> int:
    """How many files of the run's baseline (``baseline_inputs``) :func:`verify_run` leaves
    unchecked with ``roots``: all of them unless ``roots`` names the ``baseline`` folder."""
    return 0 if "baseline" in roots else len(record.get("baseline_inputs") or {})


def _inside(p: Path, folders: Iterable[Path]) -> bool:
    return any(p == f or f in p.parents for f in folders)


def _as_spelled_here(path: Path) -> Path:
    """``path``, or where it does not exist, the file whose every part has the same name in Unicode
    NFC form (``algé`` written in NFD by one machine, in NFC by another copy)."""
    if path.exists() or str(path).isascii():
        return path
    from lorisnb.io.datasets.paths import named_entry

    return named_entry(Path(path.anchor), str(path.relative_to(path.anchor)))


def where_it_is(path: Path) -> Path:
    """``path`` absolute as it was found, no link on the way followed (a file of a folder linked into
    the results folder is named there, not where the link leads), as
    :func:`~lorisnb.tools.report.portable.root_key` writes it into run.json."""
    return Path(os.path.abspath(path))


def run_folder(run: str | os.PathLike[str]) -> Path:
    """The run folder of ``run``: a run folder, or its run.json (the folder holding it)."""
    p = Path(run)
    return p if p.is_dir() else p.parent


def run_file(folder: str | os.PathLike[str], path: Path) -> Path:
    """``path``, a file (or folder) of the run folder ``folder``, if it lies inside it (links
    resolved) and is a regular file or a folder; else a :class:`~lorisnb.errors.ValidationError`
    naming it. Every file a command reads from a run folder it received (run.json, its marker,
    pages, notebooks, tables) passes here: a link in it that leads elsewhere is refused, never
    read, and no message quotes what it leads to; a FIFO or a device (which a reader would wait on
    for ever, or read without end) is refused without being opened. A path that does not exist
    passes (the caller says what is missing)."""
    inside = Path(folder).resolve()
    if not _inside(path.resolve(), [inside]):
        raise ValidationError(f"{path}: a link leading outside the run folder {folder}; a run folder lorisnb writes "
                              "holds none (a received run?): nothing outside it is read. Replace the link by the "
                              "file, if you trust it")  # fmt: skip
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return path
    if not (stat.S_ISREG(mode) or stat.S_ISDIR(mode)):
        raise ValidationError(f"{path}: {NOT_REGULAR}")
    return path


def links_out(folder: str | os.PathLike[str]) -> list[Path]:
    """Every link below ``folder`` (a file's or a folder's, not followed) that leads outside it, or
    nowhere: what :func:`run_file` refuses, listed before anything is read or written."""
    inside = Path(folder).resolve()
    out = []
    for top, dirs, files in os.walk(folder):
        for n in files + dirs:
            p = Path(top) / n
            if p.is_symlink() and not _inside(p.resolve(), [inside]):
                out.append(p)
    return sorted(out)


def refuse_links_out(folder: str | os.PathLike[str]) -> None:
    """A :class:`~lorisnb.errors.ValidationError` naming the links of the run folder ``folder`` that
    lead outside it or nowhere (:func:`links_out`; its marker and ``index.html`` first, by
    :func:`run_file`, as render checks them), if it holds any: a received run whose pages,
    tables or notebooks are links to files elsewhere (``index.html`` -> another file,
    ``findings/leaderboard.csv`` -> ``/etc/passwd``) is no run lorisnb wrote, whatever its marker
    says; nothing is read through them."""
    from lorisnb.tools.notebook.start import RUN_MARKER

    for name in (RUN_MARKER, "index.html"):  # the files render reads first: refused as render refuses them
        if os.path.lexists(Path(folder) / name):
            run_file(folder, Path(folder) / name)
    out = links_out(folder)
    if out:
        shown = ", ".join(str(p.relative_to(folder)) for p in out[:5]) + (f" and {len(out) - 5} more" * (len(out) > 5))
        raise ValidationError(f"{folder}: holds {len(out)} link(s) leading outside it ({shown}); a run folder lorisnb "
                              "writes holds none (a received run?), so it is not checked: nothing was read through "
                              "them. Replace each link by its file, if you trust it, or copy the run again from where "
                              "it came")  # fmt: skip


def verify_run(
    run: str | os.PathLike[str], roots: Mapping[str, str | os.PathLike[str]] | None = None
) -> list[tuple[str, str]]:
    """Re-check every input of a run: a list of (path, 'changed', 'missing', 'added', 'outside'
    or :data:`NOT_A_FILE`: a FIFO or a device in place of an input or in a folder it read, not
    opened); empty if all inputs still have their recorded SHA-256 and the folders the report
    read (``input_roots``, listed as the report listed them, :func:`input_files`) hold no other
    file.

    Args:
        run: the run folder (or its run.json).
        roots: where the run's named roots are here (name -> folder: ``data``, ``results``...).
            ``{name}/inside`` keys are read below them; a key relative to no root (a run of an
            earlier lorisnb) below ``roots["data"]``; an absolute key (a run made with
            ``--absolute-paths``) below the folder run.json's ``roots`` records for a root named
            here is read below that root here (the run was moved), else only if it lies inside
            one of ``roots`` or the run folder.

    The files of the earlier run a run's verdict was made against (``baseline_inputs``, ``report
    --baseline``) are checked where ``roots`` names the ``baseline`` folder, else not (the caller
    says so: :func:`unchecked_baseline`).

    Nothing outside the run folder and ``roots`` is read, whatever run.json says: a root it names
    elsewhere is a :class:`~lorisnb.errors.ValidationError` before any file is read, and a file
    found through a link that leads outside is listed as 'outside', unread. A run folder holding a
    link that leads outside it (or nowhere: :func:`links_out`) is refused before anything is read,
    as render refuses it: a run folder lorisnb writes holds none, and its marker cannot tell a file
    from a link to another file of the same name."""
    folder = run_folder(run)
    refuse_links_out(folder)
    record = read_run_json(run)
    run_json = folder / RUN_JSON if Path(run).is_dir() else Path(run)
    check_digests(record, run_json)
    given = {k: Path(v).resolve() for k, v in (roots or {}).items()}
    for name, p in given.items():
        if not p.exists():
            raise ValidationError(f"--{name if name in ('data', 'results') else 'root ' + name} {p}: no such folder")
        if name in ("data", "results") and not p.is_dir():  # another root may be a file (--root groundtruth gt.txt)
            raise ValidationError(f"--{name} {p}: a file; expected the folder of the run's {name} here")
    allowed = [folder.resolve(), *given.values()]

    def readable(p: Path) -> bool:  # where it really is: a link leading out of them is listed, never followed
        return _inside(p.resolve(), allowed)

    given.setdefault("run", folder.resolve())
    # a run made with --absolute-paths: each root's folder on the machine it was made on, innermost first
    recorded = sorted(((k, Path(os.path.normpath(v))) for k, v in (record.get("roots") or {}).items()
                       if v is not None and os.path.isabs(v)), key=lambda r: -len(r[1].parts))  # fmt: skip

    def moved(key: str) -> tuple[str, Path, Path | None] | None:
        """(root name, its recorded folder, the file below that root here or None where the root is
        not given) for an absolute key below a root run.json records; None below none of them."""
        p = Path(os.path.normpath(key))
        for name, was in recorded:
            if p == was or was in p.parents:
                return name, was, (given[name] / p.relative_to(was) if name in given else None)
        return None

    def as_recorded(p: Path) -> Path:
        """A file found here below a root given here, as the run keyed it: below that root's
        recorded folder (a moved --absolute-paths run), else as it is."""
        for name, was in recorded:
            if name in given and (p == given[name] or given[name] in p.parents):
                return was / p.relative_to(given[name])
        return p

    def place(key: str, what: str = "a file") -> Path:
        """Where the input ``key`` (``what`` it is: a file, or a folder or file the run listed) is here."""
        named = split_key(key)
        if named is None and not Path(key).is_absolute():  # an earlier run's key, below its data root
            if "data" not in given:
                raise ValidationError(f"{key}: run.json reads it below the run's data root; give the data root here "
                                      "with --data DIR")  # fmt: skip
            return resolve_key(f"{mark('data')}/{key}", given) or Path(key)
        below = moved(key) if named is None else None
        if below is not None and below[2] is not None:  # a moved --absolute-paths run: below that root here
            return below[2]
        p = resolve_key(key, given)
        if p is None:
            name = named[0] if named else ""
            option = f"--{name} DIR" if name in ("data", "results") else f"--root {name} DIR"
            env = " (verify takes roots from its command line only, not from LORISNB_DATA)" if name == "data" else ""
            raise ValidationError(f"{key}: run.json reads it below the root {mark(name)}; say where that root is "
                                  f"here with {option}{env}")  # fmt: skip
        if not _inside(Path(os.path.abspath(p)), allowed):
            if below is not None:  # below a root the run records by its folder there: say where that root is here
                name = below[0]
                option = f"--{name} DIR" if name in ("data", "results") else f"--root {name} DIR"
                raise ValidationError(f"{key}: run.json names {what} outside the run folder and the roots given here, "
                                      "by an absolute path of the machine the run was made on (a run made with "
                                      f"--absolute-paths), below its root {mark(name)} ({below[1]}); say where that "
                                      f"root is here with {option}")  # fmt: skip
            if named is None:
                raise ValidationError(f"{key}: run.json names {what} outside the run folder and the roots given here, "
                                      "by an absolute path of the machine the run was made on, below none of the roots "
                                      "it records (an edited run.json?); verify reads only those. If it is at that "
                                      "path here, give the folder holding it with --root NAME DIR; else verify "
                                      "cannot check it here: make the run again without --absolute-paths")  # fmt: skip
            raise ValidationError(f"{key}: run.json names {what} outside the run folder and the roots given here; "
                                  "verify reads only those: give a folder holding it with --data, --results or --root, "
                                  "if you trust it")  # fmt: skip
        return p

    inputs = {key: _as_spelled_here(place(key)) for key in sorted(record["inputs"])}
    problems = []
    listed = []
    for r in record.get("input_roots", []):  # a folder it read: walked only where it lies inside those given
        p = place(r, "a folder (or file) the run listed")
        if not os.path.lexists(p):  # a folder the run read is gone: nothing below it was seen, so none is said
            problems.append((r, "missing"))
        elif p.exists() and not readable(p):
            problems.append((r, "outside"))
        else:
            listed.append(p)
    sums = dict(record["inputs"])
    if "baseline" in given:  # the earlier run a verdict was made against: checked where the caller names its folder
        sums.update(record.get("baseline_inputs") or {})
        inputs.update({key: _as_spelled_here(place(key)) for key in sorted(record.get("baseline_inputs") or {})})
    for key, p in inputs.items():
        if p.is_dir() and readable(p):  # run.json lists files only: a damaged one, not an input changed
            raise ParseError(run_json, None, f"the input {json.dumps(key)} is a folder here ({p}); expected the path of "
                             "a file: run.json lists each file a run read, with its SHA-256 (a damaged or edited "
                             "run.json?). Copy the run again from where it came")  # fmt: skip
        if os.path.exists(p) and not p.is_file():  # a FIFO or a device where the input was: there, never opened
            problems.append((key, NOT_A_FILE))
        elif not p.is_file():
            problems.append((key, "missing"))
        elif not readable(p):
            problems.append((key, "outside"))
        elif sha256(p) != sums[key]:
            problems.append((key, "changed"))
    if "input_roots" in record:
        # keys as the run wrote them: below named roots, absolute (--absolute-paths) or below the data root (earlier
        # runs), compared in Unicode NFC (a folder copied by a Mac or rsync may spell algé otherwise)
        named = any(split_key(k) for k in [*record["inputs"], *record["input_roots"]])
        style: Mapping[str, Path] | Path | None = given if named else None if "roots" in record else given.get("data")

        def key_of(f: Path) -> str:  # absolute keys: a file below a root given here, as keyed where the run was made
            return _key(as_recorded(f), None) if style is None else _key(f, style)

        # each file found is matched to a recorded input by its key as written; a key recorded in another Unicode
        # spelling (NFD there, NFC here) stands for the one file of that name here only where its own spelling
        # is not here: two files whose names differ only so are two files, and the one not recorded is added
        exact = set(record["inputs"])
        recorded_keys = {validate.label(k) for k in exact}
        respelled: dict[str, list[str]] = {}
        for k in exact:
            respelled.setdefault(validate.label(k), []).append(k)
        keyed: dict[str, bool] = {}
        files, unwalked, odd = _listing(listed, resolve=False, inside=allowed)  # a linked folder leading elsewhere:
        for p in unwalked:  # listed, not walked (a folder of estimates linked in from elsewhere since the run)
            key = key_of(where_it_is(p))
            below = (validate.label(key) + "/", validate.label(str(where_it_is(p))) + "/")
            if not any(k.startswith(below) for k in recorded_keys):  # its recorded inputs are listed 'outside' already
                keyed[key] = False
        matched: set[str] = set()
        unmatched: list[tuple[Path, bool, list[str]]] = []
        for p in files:
            inside = readable(p)
            forms = [where_it_is(p), p.parent.resolve() / p.name] + ([p.resolve()] if inside else [])
            keys = [key_of(f) for f in forms]  # as the report keys it; as earlier ones did
            hit = exact.intersection(keys)
            if hit:
                matched |= hit
            else:
                unmatched.append((p, inside, keys))
        for p, inside, keys in unmatched:  # in another spelling: the recorded key whose own spelling is not here
            free = [k for label in dict.fromkeys(map(validate.label, keys)) for k in respelled.get(label, [])
                    if k not in matched]  # fmt: skip
            if free:
                matched.add(free[0])
            else:
                keyed[key_of(where_it_is(p))] = inside
        problems += [(key, "added" if keyed[key] else "outside") for key in sorted(keyed)]
        problems += [(key_of(where_it_is(p)), NOT_A_FILE) for p in odd]
    return sorted(set(problems))
