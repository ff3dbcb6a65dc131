"""Checks that teach: the graders of the labs in ``teaching/`` (see ``teaching/README.md``).

Each ``check_*`` function compares a learner's answer (a function they wrote, or a number they
predicted or read off) with lorisnb's own numbers. A right answer prints a line starting with ``✓``
and returns True; a wrong one raises :class:`~lorisnb.errors.AnswerError` (an ``AssertionError``, so
nbgrader and pytest count a failed test) saying what is wrong (too high or too low, and by roughly
how much, never the reference number a learner could type in), and a hint naming the typical
mistake when the answer is what that mistake gives (:data:`MISTAKES`).

- :mod:`._checks`: the formulas (Eq. 1-4) and plain numbers and choices;
- :mod:`._labs`: lab answers whose reference lorisnb computes from the lab's inputs (so that the
  student version's test cells hold no solution);
- :mod:`._prose`: the labs' data (:func:`lab_data`: the same for students and the grader) and the
  explanations shown after a check, computed from the lab's parameters;
- :mod:`._grading`: how a formula check grades a learner's function, and :mod:`._mistakes`: the
  typical mistakes and their hints (the one registry of them);
- :mod:`.autograde`: one returned lab notebook graded so that the grade holds, :mod:`.gradebook`: a
  class graded and its grades written for an LMS, :mod:`.sandbox`: a student's code run in a sandbox
  (its child process: :mod:`._sandbox_child`, which imports nothing of lorisnb), and
  :mod:`.errorrates`: how often lab 1's grader is wrong.

May import: the data root's lookup (:mod:`lorisnb.io.datasets.paths`), :mod:`lorisnb.core`,
:mod:`lorisnb.errors` and :mod:`lorisnb` itself (only for the folder it is installed in, which a
sandbox is given or kept from); never the report or the command line.
"""

import sys
from types import ModuleType

from lorisnb.errors import AnswerError
from lorisnb.tools.teaching._checks import (
    CORRECTNESS_CASES,
    CR_CASES,
    CSR_CASES,
    cases_from,
    check_choice,
    check_correct_rate,
    check_correct_rate_tracking,
    check_correctness,
    check_cs_r,
    check_value,
)
from lorisnb.tools.teaching._labs import (
    check_alignment_cr,
    check_ate_percent,
    check_best_cr,
    check_eps_at_cr,
    check_silent_sequences,
)
from lorisnb.tools.teaching._mistakes import MISTAKES
from lorisnb.tools.teaching._prose import (
    explain_ate_percent,
    explain_gap,
    explain_wrong_reloc,
    lab_data,
    lab_variant,
    wrong_reloc_question,
)

__all__ = [
    "CORRECTNESS_CASES", "CR_CASES", "CSR_CASES", "MISTAKES", "cases_from", "check_alignment_cr", "check_ate_percent",
    "check_best_cr", "check_choice", "check_correct_rate", "check_correct_rate_tracking", "check_correctness",
    "check_cs_r", "check_eps_at_cr", "check_silent_sequences", "check_value", "explain_ate_percent", "explain_gap",
    "explain_wrong_reloc", "lab_data", "lab_variant", "wrong_reloc_question",
]  # fmt: skip


class _Checks(ModuleType):
    """This module, whose checks and cases an answer cell cannot replace: ``teach.check_value =
    lambda *a, **k: True`` would pass every later check (the learner's notebook and the grader's
    run share one kernel). Rebinding ``teach`` itself, or the private modules, is not prevented."""

    def __setattr__(self, name: str, value: object) -> None:
        if name in __all__ and name in self.__dict__:
            raise AnswerError(
                f"✗ lorisnb.tools.teaching.{name} cannot be replaced: the checks grade your answers. "
                "Remove this assignment and answer the question instead."
            )
        super().__setattr__(name, value)

    def __delattr__(self, name: str) -> None:
        if name in __all__:
            raise AnswerError(f"✗ lorisnb.tools.teaching.{name} cannot be removed: the checks grade your answers.")
        super().__delattr__(name)


sys.modules[__name__].__class__ = _Checks
