"""Where the data is: OpenLORIS-Scene ground truth, the ``icra20_results``, TUM RGB-D files and
the published tables.

The data root is found, in this order, from

1. an explicit ``path`` argument,
2. the environment variable ``LORISNB_DATA``,
3. ``../shared/data`` next to the project root (the checkout that holds ``lorisnb/``).

A root is a folder laid out like the shared data: ``openloris-scene/groundtruth/gt_<scene>_1.txt``,
``openloris-scene/icra20_results/{per-seq,lifelong}/<algorithm>/*.txt``, ``tum-rgbd/`` and
``published/``. When nothing is found, :class:`~lorisnb.errors.DataNotFoundError` lists every
place that was looked at and how to point lorisnb at the data.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from .errors import DataNotFoundError

ENV_VAR = "LORISNB_DATA"
PROJECT_ROOT = Path(__file__).resolve().parents[1]
_MARKERS = ("openloris-scene", "tum-rgbd", "published")


def _candidates(path: str | os.PathLike | None) -> list[tuple[str, Path]]:
    out: list[tuple[str, Path]] = []
    if path is not None:
        out.append(("argument", Path(path).expanduser()))
        return out
    env = os.environ.get(ENV_VAR)
    if env:
        out.append((f"${ENV_VAR}", Path(env).expanduser()))
    out.append(("next to the project root", PROJECT_ROOT.parent / "shared" / "data"))
    return out


def _looks_like_root(p: Path) -> bool:
    return p.is_dir() and any((p / m).is_dir() for m in _MARKERS)


@dataclass(frozen=True)
class DataPaths:
    """Paths below one data root. Each accessor raises DataNotFoundError naming the missing path."""

    root: Path

    def _need(self, p: Path, what: str) -> Path:
        if not p.exists():
            raise DataNotFoundError(
                f"{what} not found: looked for {p} (data root {self.root}). "
                f"Point lorisnb at a folder laid out like ../shared/data with the data_root "
                f"argument or the {ENV_VAR} environment variable."
            )
        return p

    @property
    def openloris(self) -> Path:
        return self._need(self.root / "openloris-scene", "OpenLORIS-Scene folder")

    @property
    def groundtruth_dir(self) -> Path:
        return self._need(self.root / "openloris-scene" / "groundtruth", "OpenLORIS ground-truth folder")

    def groundtruth(self, scene: str) -> Path:
        """``gt_<scene>_1.txt`` (base_link poses of every sequence of the scene)."""
        return self._need(self.root / "openloris-scene" / "groundtruth" / f"gt_{scene}_1.txt",
                          f"ground truth of scene {scene!r}")

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


def find_data(path: str | os.PathLike | None = None) -> DataPaths:
    """Locate the data root (see the module docstring for the search order)."""
    looked = []
    for how, cand in _candidates(path):
        if _looks_like_root(cand):
            return DataPaths(cand.resolve())
        looked.append(f"  - {cand} ({how}): " + ("not a data root" if cand.is_dir() else "does not exist"))
    raise DataNotFoundError(
        "lorisnb could not find its data. It looked at:\n" + "\n".join(looked) + "\n"
        f"A data root holds openloris-scene/ (groundtruth/, icra20_results/), tum-rgbd/ or "
        f"published/. Pass data_root=... (command line: --data DIR) or set {ENV_VAR}=DIR."
    )
