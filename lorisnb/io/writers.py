"""Writers: OpenLORIS result files and tables, always through a temporary name moved into place,
never replacing an existing file unless asked.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd

from ..core.trajectory import Trajectory
from ..errors import OutputError


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
    if Path(path).exists() and not overwrite:
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


def write_atomically(out: str | os.PathLike[str], write: Callable[[Path], object], force: bool = False) -> Path:
    """Call ``write(tmp)`` on a temporary name beside ``out``, then move it into place; refuse to
    replace an existing file unless ``force``; never leave the temporary file behind."""
    out = Path(out)
    if out.exists() and not force:
        raise OutputError(f"{out} exists; choose another name or pass --force to replace it")
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.tmp-{os.getpid()}")
    try:
        write(tmp)
        os.replace(tmp, out)
    finally:
        tmp.unlink(missing_ok=True)
    return out


def write_csv(df: pd.DataFrame, out: str | os.PathLike[str], force: bool = False) -> Path:
    """Write a table as CSV (:func:`write_atomically`)."""
    return write_atomically(out, lambda p: df.to_csv(p, index=False), force)


def write_text(text: str, out: str | os.PathLike[str], force: bool = False) -> Path:
    """Write text, UTF-8 (:func:`write_atomically`)."""
    return write_atomically(out, lambda p: p.write_text(text, encoding="utf-8"), force)
