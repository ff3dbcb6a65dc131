"""Inputs of an evaluation that exclude each other, in one registry read by every surface that
takes them: the command line (:func:`lorisnb.cli.commands._run_evaluation` refuses ``--gt`` with
``--manifest``) and the notebooks and the report (:data:`lorisnb.tools.notebook.params.EXCLUSIVE`,
checked by :func:`lorisnb.tools.notebook.params.check_values`). A new pair is added here once.
Plain data, no imports: the command line reads it before anything heavy is loaded."""

from __future__ import annotations

from typing import NamedTuple

__all__ = ["EXCLUSIVE_INPUTS", "Exclusive", "option_refusal"]


class Exclusive(NamedTuple):
    """Two inputs of which one is given: their parameter names (notebooks, Python), their
    command-line options, and why they exclude each other (the surface using one would ignore the
    other)."""

    names: tuple[str, str]
    options: tuple[str, str]
    why: str


EXCLUSIVE_INPUTS: tuple[Exclusive, ...] = (
    Exclusive(("groundtruth", "manifest"), ("--gt", "--manifest"), "a manifest names the ground truth of each session"),
)


def option_refusal(pair: Exclusive) -> str:
    """The command line's refusal of both options of ``pair`` given:
    ``--gt and --manifest: give one (a manifest names the ground truth of each session)``."""
    return f"{pair.options[0]} and {pair.options[1]}: give one ({pair.why})"
