"""Where the data is: OpenLORIS-Scene ground truth, the ``icra20_results``, TUM RGB-D files and
the published tables; and the ground truth read from there.

The data root is found, in this order, from

1. an explicit ``data_root`` argument (command line ``--data DIR``),
2. the environment variable ``LORISNB_DATA`` (set to a folder that is not a data root, it is an
   error: it is not passed over for the next place),
3. a ``shared/data`` folder beside the current folder or one of its parents (``../shared/data``
   seen from a checkout of lorisnb, or from its ``notebooks/`` folder), then beside the checkout
   lorisnb runs from, if it runs from one.

A root is a folder laid out like the shared data: ``openloris-scene/groundtruth/gt_<scene>_1.txt``,
``openloris-scene/icra20_results/{per-seq,lifelong}/<algorithm>/*.txt``, ``tum-rgbd/`` and
``published/``. When nothing is found, :class:`~lorisnb.errors.DataNotFoundError` lists every
place that was looked at and how to point lorisnb at the data.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING

from lorisnb.core.lifelong.aggregate import spans_table
from lorisnb.core.pipeline.model import ResultFile
from lorisnb.core.trajectory.frames import SCENES
from lorisnb.core.trajectory.poses import Trajectory, time_spans
from lorisnb.errors import DataNotFoundError, LorisError, ValidationError
from lorisnb.io.readers.openloris import read_openloris

if TYPE_CHECKING:
    import pandas as pd


def named_entry(folder: Path, name: str | os.PathLike[str]) -> Path:
    """The path ``name`` (a file name, or a relative path of names) gives in ``folder``, as written
    where that exists, else each part matched to the entry that is the same name in Unicode NFC form
    (:func:`lorisnb.core.spec.validate.label`: ``dése.txt`` written in a manifest, or a session
    ``café``, whose file a Mac saved as ``de`` and a combining accent, or the other way), else as
    written (absent: the caller says so). Every file a manifest names and every estimate of a
    session is found so."""
    from lorisnb.core.spec.validate import label

    path = Path(folder) / name
    if path.exists() or str(name).isascii():
        return path
    here = Path(folder)
    for part in Path(name).parts:
        if not os.path.lexists(here / part):
            want = label(part)
            try:
                same = sorted(e.name for e in here.iterdir() if label(e.name) == want)
            except OSError:
                return path
            if not same:
                return path
            part = same[0]
        here = here / part
    return here


ENV_VAR = "LORISNB_DATA"
#: The small teaching data shipped inside the package (``teaching/make_sample_data.py`` writes it).
SAMPLE_DATA = Path(__file__).resolve().parents[2] / "sample_data"
_MARKERS = ("openloris-scene", "tum-rgbd", "published")

DataRoot = str | os.PathLike[str]


def _candidates(path: DataRoot | None) -> list[tuple[str, Path]]:
    if path is not None:
        if str(path).strip() == "":
            return [("argument (empty)", Path(""))]
        return [("argument", Path(path).expanduser())]
    out: list[tuple[str, Path]] = []
    env = os.environ.get(ENV_VAR)
    if env:
        out.append((f"${ENV_VAR}", Path(env).expanduser()))
    here = Path.cwd()
    for folder in (here, *here.parents):
        out.append((f"shared/data beside {folder}", folder / "shared" / "data"))
    checkout = Path(__file__).resolve().parents[3]
    if (checkout / "pyproject.toml").is_file():  # running from a source checkout
        out.append(("beside the lorisnb checkout", checkout.parent / "shared" / "data"))
    return out


def _looks_like_root(p: Path) -> bool:
    return str(p) != "" and p.is_dir() and any((p / m).is_dir() for m in _MARKERS)


@dataclass(frozen=True)
class DataPaths:
    """Paths below one data root. Each accessor raises DataNotFoundError naming the missing path.

    Attributes:
        root: the data root.
        shown: the ground-truth sequences this data shows, ``(scene, seq)`` (None: every one), as
            far as telling them goes: the time-overlap check (:func:`groundtruth_spans`) names no
            other (a challenge phase's hidden sequences, scenes it does not rank)."""

    root: Path
    shown: frozenset[tuple[str, int]] | None = None

    def _need(self, p: Path, what: str, why: str = "") -> Path:
        if not p.exists():
            raise DataNotFoundError(
                f"{what} not found: looked for {p} (data root {self.root}). {why}"
                f"Point lorisnb at a folder laid out like ../shared/data with the data_root "
                f"argument (--data DIR) or the {ENV_VAR} environment variable."
            )
        return p

    @property
    def openloris(self) -> Path:
        return self._need(self.root / "openloris-scene", "OpenLORIS-Scene folder")

    def groundtruth(self, scene: str) -> Path:
        """``gt_<scene>_1.txt`` (base_link poses of every sequence of the scene). Missing, the
        error says why it may be (a scene name in another case or not OpenLORIS', office's ground
        truth not public) and which scenes this root has."""
        if not isinstance(scene, str):
            raise ValidationError(f"scene={scene!r}: expected an OpenLORIS scene name ({', '.join(SCENES)})")
        p = self.root / "openloris-scene" / "groundtruth" / f"gt_{scene}_1.txt"
        if p.exists():
            return p
        have = f"this data root ({self.root}) has the ground truth of {', '.join(self.scenes_with_groundtruth()) or 'no scene'}"
        if scene not in SCENES:  # a name, not the data: no word on where the data is
            case = f"scene names are lower case: {scene.lower()!r}" if scene.lower() in SCENES else ""
            raise DataNotFoundError(f"ground truth of scene {scene!r} not found: "
                                    f"{case or 'expected an OpenLORIS scene: ' + ', '.join(SCENES)}; {have}")  # fmt: skip
        why = "the office ground truth (motion capture) is not public; " if scene == "office" else ""
        try:
            return self._need(p, f"ground truth of scene {scene!r}", f"{(why + have)[:1].upper()}{(why + have)[1:]}. ")
        except DataNotFoundError as exc:
            exc.scene = scene  # what is missing, for the exit status (office's is expected to be)
            raise

    @property
    def icra20(self) -> Path:
        return self._need(self.root / "openloris-scene" / "icra20_results", "icra20_results folder")

    @property
    def extrinsics_json(self) -> Path:
        return self._need(self.root / "openloris-scene" / "extrinsics.json", "extrinsics.json")

    @property
    def tum(self) -> Path:
        return self._need(self.root / "tum-rgbd", "TUM RGB-D folder")

    @property
    def published(self) -> Path:
        return self._need(self.root / "published", "published tables folder")

    def scenes_with_groundtruth(self) -> list[str]:
        """The OpenLORIS scenes whose ground truth is in this root, in the paper's order."""
        d = self.root / "openloris-scene" / "groundtruth"
        return [s for s in SCENES if (d / f"gt_{s}_1.txt").is_file()]


def _state(where: Path) -> str:
    """Why ``where`` is no data root: a folder without the data, a file, or nothing there."""
    if where.is_dir():
        return "not a data root"
    return "a file, not a folder" if where.exists() else "does not exist"


def find_data(data_root: DataRoot | DataPaths | None = None) -> DataPaths:
    """Locate the data root (see the module docstring for the search order)."""
    if isinstance(data_root, DataPaths):
        return data_root
    if data_root is not None and not isinstance(data_root, (str, os.PathLike)):
        raise DataNotFoundError(
            f"data_root={data_root!r}: expected a folder path (str or pathlib.Path), or None to look in the usual places"
        )
    env = os.environ.get(ENV_VAR)  # set, but to no data root: said, not passed over for the next place
    if data_root is None and env and not _looks_like_root(Path(env).expanduser()):
        where = Path(env).expanduser()
        raise DataNotFoundError(
            f"{ENV_VAR}={env}: {_state(where)}. A data root holds "
            "openloris-scene/ (groundtruth/, icra20_results/), tum-rgbd/ or published/. Set it to one, unset it to "
            "use a shared/data folder beside the current folder, or pass data_root=... (command line: --data DIR)."
        )
    looked = []
    for how, cand in _candidates(data_root):
        if _looks_like_root(cand):
            return DataPaths(cand.resolve())
        looked.append(f"{cand} ({how}): {_state(cand) if str(cand) else 'does not exist'}")
    raise DataNotFoundError(  # one line: the command line shows a message's line breaks escaped, as "\n"
        "lorisnb could not find its data. It looked at: " + "; ".join(looked) + ". "
        f"A data root holds openloris-scene/ (groundtruth/, icra20_results/), tum-rgbd/ or "
        f"published/. Pass data_root=... (command line: --data DIR) or set {ENV_VAR}=DIR."
    )


def sample_data() -> DataPaths:
    """The small teaching data shipped inside lorisnb (about 1.4 MB, laid out like a data root):
    the cafe ground truth, a few icra20 results of cafe, a TUM RGB-D pair and the published
    tables. Only the primer and the labs fall back to it (``setup(..., sample=True)``); nothing
    else uses it unless asked (``data_root=sample_data()``)."""
    if not _looks_like_root(SAMPLE_DATA):
        raise DataNotFoundError(f"lorisnb's sample data is missing from {SAMPLE_DATA} (a broken install?)")
    return DataPaths(SAMPLE_DATA)


@lru_cache(maxsize=32)
def _read_gt_cached(path: str, mtime: float, size: int, remove_repeated: bool) -> ResultFile:
    gt = read_openloris(path, remove_repeated=remove_repeated, warn=False)
    for t in gt.sequences.values():  # shared by every caller: nobody may change it
        for a in (t.stamps, t.positions, t.quaternions, t.lines):
            if a is not None:
                a.setflags(write=False)
    return gt


def load_groundtruth(
    scene: str, data_root: DataRoot | DataPaths | None = None, remove_repeated: bool = True
) -> ResultFile:
    """The ground truth of an OpenLORIS scene (``gt_<scene>_1.txt``), read once and cached (until
    the file changes). Repeated poses are dropped from ground truth too, as the official tool does.
    Each call returns a new object whose arrays are read-only (they are shared with every other
    caller): copy an array to change it."""
    return read_groundtruth_file(find_data(data_root).groundtruth(scene), remove_repeated)


def read_groundtruth_file(path: str | os.PathLike, remove_repeated: bool = True) -> ResultFile:
    """An OpenLORIS ground-truth file (every ``seq:`` block), read once and cached as
    :func:`load_groundtruth` reads a scene's; a new object over read-only arrays each call."""
    path = Path(path)
    st = path.stat()
    gt = _read_gt_cached(str(path), st.st_mtime, st.st_size, remove_repeated)
    return replace(  # a fresh object over read-only arrays: a caller's edits never reach the next caller
        gt, header=dict(gt.header), header_lines=dict(gt.header_lines),
        sequences={k: Trajectory.from_checked(t.stamps, t.positions, t.quaternions, t.lines, dict(t.meta))
                   for k, t in gt.sequences.items()},
        seq_info={k: dict(v) for k, v in gt.seq_info.items()}, seq_lines=dict(gt.seq_lines),
        removed_repeats=dict(gt.removed_repeats), warnings=list(gt.warnings),
    )  # fmt: skip


def groundtruth_spans(
    data_root: DataRoot | DataPaths | None = None, remove_repeated: bool = True
) -> dict[str, tuple[float, float]]:
    """Time span (first, last stamp, seconds) of every ground-truth sequence the data shows
    (:attr:`DataPaths.shown`), by ``<scene>-<seq>``: what the time-overlap plausibility check
    compares against."""
    data = find_data(data_root)
    shown = data.shown
    spans: dict[str, tuple[float, float]] = {}
    for scene in data.scenes_with_groundtruth():
        if shown is not None and not any(s == scene for s, _ in shown):
            continue
        try:
            gt = load_groundtruth(scene, data, remove_repeated)
        except LorisError:
            continue
        spans.update({f"{scene}-{k}": span for k, span in time_spans(gt.sequences).items()
                      if shown is None or (scene, k) in shown})  # fmt: skip
    return spans


def scene_spans(
    scenes: Iterable[str], data_root: DataRoot | DataPaths | None = None, remove_repeated: bool = True
) -> dict[str, dict[int, tuple[float, float]]]:
    """First and last ground-truth stamp (seconds) of every sequence of each scene: scene ->
    sequence -> span (what :func:`lorisnb.core.lifelong.aggregate.spans_table` tabulates)."""
    return {s: time_spans(load_groundtruth(s, data_root, remove_repeated).sequences) for s in scenes}


def scene_durations(
    scenes: Iterable[str], data_root: DataRoot | DataPaths | None = None, remove_repeated: bool = True
) -> pd.DataFrame:
    """Ground-truth duration of every sequence of each scene (``lorisnb.core.lifelong.aggregate.durations_table``)."""
    return spans_table(scene_spans(scenes, data_root, remove_repeated))
