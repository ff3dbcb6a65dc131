"""Short, useful reprs of the edge's objects (what a notebook cell shows for ``ev``)."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .evaluate import Evaluation


def _count(n: int, word: str) -> str:
    return f"{n} {word}{'' if n == 1 else 's'}"


def describe_evaluation(ev: Evaluation) -> str:
    """``<Evaluation: 12 files (3 algorithms, 4 scenes), 1 failed, 1 unscored; conventions: ...>``."""
    algorithms = {f.algorithm for f in ev.errors}
    scenes = {f.scene for f in ev.errors}
    parts = [
        f"{_count(len(ev.errors), 'file')} ({_count(len(algorithms), 'algorithm')}, {_count(len(scenes), 'scene')})"
    ]
    for n, word in ((len(ev.failures), "failed"), (len(ev.unscored), "unscored"), (len(ev.skipped), "skipped")):
        if n:
            parts.append(f"{n} {word}")
    conv = ev.conventions if len(ev.conventions) <= 100 else ev.conventions[:97] + "..."
    return f"<Evaluation: {', '.join(parts)}" + (f"; conventions: {conv}" if conv else "") + ">"
