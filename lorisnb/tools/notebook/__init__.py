"""What the notebooks use: the one set-up call (:mod:`.start`), their parameters checked like any
option (:mod:`.params`), the threshold explorer's widgets (:mod:`.widgets`), the grids ``quick``
trims (:mod:`.grids`), the indoor / outdoor tables (:mod:`.indoor_outdoor`), the numbers of the
``compare_algorithms`` notebook (:mod:`.comparison`), what makes CR grow with ``delta``
(:mod:`.output_gaps`) and the sentences of their prose that depend on the run (:mod:`.prose`).

May import: :mod:`lorisnb.tools.evaluation`, :mod:`lorisnb.tools.decisions`, :mod:`lorisnb.tools.figures`,
the leaderboard (:mod:`lorisnb.tools.report.leaderboard`) and a report's portable paths
(:mod:`lorisnb.tools.report.portable`), :mod:`lorisnb.io`, :mod:`lorisnb.core`, :mod:`lorisnb.errors` and
lorisnb's version (:mod:`lorisnb._version`); the report and the decisions import this package too
(docs/architecture.md, "Sub-packages that import each other").
"""

from typing import TYPE_CHECKING

from lorisnb._lazy import attach

if TYPE_CHECKING:
    from lorisnb.tools.notebook.start import (
        FIGURE_FORMATS,
        INPUT_ERRORS_CSV,
        OUTPUTS_MARKER,
        RUN_MARKER,
        Outputs,
        Session,
        check_notebook_parameters,
        check_output_dir,
        compact_png,
        default_output_dir,
        figure_png,
        notebook_inputs,
        setup,
        show_figure,
        show_inputs,
        show_tables_escaped,
        shown_table,
        warnings_table,
    )

__getattr__, __dir__ = attach(__name__)

__all__ = [
    "FIGURE_FORMATS",
    "INPUT_ERRORS_CSV",
    "OUTPUTS_MARKER",
    "Outputs",
    "RUN_MARKER",
    "Session",
    "check_notebook_parameters",
    "check_output_dir",
    "compact_png",
    "default_output_dir",
    "figure_png",
    "notebook_inputs",
    "setup",
    "show_figure",
    "show_inputs",
    "show_tables_escaped",
    "shown_table",
    "warnings_table",
]
