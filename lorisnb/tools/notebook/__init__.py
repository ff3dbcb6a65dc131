"""What the notebooks use: the one set-up call (:mod:`.start`), their parameters checked like any
option (:mod:`.params`), the threshold explorer's widgets (:mod:`.widgets`), the grids ``quick``
trims (:mod:`.grids`) and the indoor / outdoor tables (:mod:`.indoor_outdoor`).

May import: the other tools sub-packages, :mod:`lorisnb.io`, :mod:`lorisnb.core`.
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
