"""lorisnb's own exception and warning types.

Every error that lorisnb raises on bad input is a :class:`LorisError`; its message says what was
wrong, where (file and line when there is one) and what to do. The core never prints: warnings
are issued with :func:`warnings.warn` under a :class:`LorisWarning` category, so notebooks show
them and the command line reports them.
"""

from __future__ import annotations

import os


class LorisError(Exception):
    """Base class of every error lorisnb raises on purpose."""


class ParseError(LorisError, ValueError):
    """A file could not be read: names the file, the line (1-based) and what was expected."""

    def __init__(self, path: str | os.PathLike[str], line: int | None, message: str):
        self.path = str(path)
        self.line = line
        self.reason = message
        where = f"{self.path}, line {line}" if line is not None else self.path
        super().__init__(f"{where}: {message}")


class DataNotFoundError(LorisError, FileNotFoundError):
    """Data (ground truth, results, extrinsics) could not be found; lists where it looked.
    ``scene``: the OpenLORIS scene whose ground truth is missing, where that is what is missing."""

    scene: str | None = None


class FrameError(LorisError, ValueError):
    """An unknown sensor frame or scene, or no extrinsics for that pair."""


class EvaluationError(LorisError, ValueError):
    """An evaluation could not be carried out as asked (for example, nothing to align on)."""


class OutputError(LorisError, OSError):
    """An output could not be written where asked (it exists, it is an input, a folder, or the
    place is not writable); says what to do instead."""


class ValidationError(LorisError, ValueError):
    """A user value (argument, option, notebook parameter, widget value) is not acceptable; says
    which value, what was given and what is expected."""


class MissingDependencyError(LorisError, ImportError):
    """An optional part of lorisnb needs a package that is not installed; names the extra to
    install (``pip install 'lorisnb[notebooks]'``)."""


class LorisWarning(UserWarning):
    """Something in the input deserves a look, but the evaluation went on."""


class FailedInputsWarning(LorisWarning):
    """Inputs of an evaluation failed (could not be read or evaluated) and are in no table: in
    Python, where nothing else would say so (``Evaluation.failures`` lists them with the reason).
    The command line prints each as an ``error:`` line instead."""


class AnswerError(LorisError, AssertionError):
    """A learner's answer to an exercise (``lorisnb.tools.teaching``) is not right: says what is
    wrong, with the numbers, and hints at the typical mistake. An AssertionError, so a grader
    (nbgrader, pytest) counts it as a failed test."""
