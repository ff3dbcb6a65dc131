"""Where the modules of lorisnb 0.x's flat layout live now (the layout by idea of 2026-11-28): a
deprecation path. ``import lorisnb.core.scoring`` still works, gives the module at its new place
(``lorisnb.core.lifelong.scoring``) and warns with a :class:`DeprecationWarning` naming it. A former
module that is now a package of the same name (``lorisnb.core.spec``, ``lorisnb.tools.report``, ...)
exports the former module's public names itself and needs no entry here.
"""

from __future__ import annotations

import importlib
import importlib.machinery
import sys
import warnings
from types import ModuleType

MOVED: dict[str, str] = {
    "lorisnb.core._rotations": "lorisnb.core.trajectory._rotations",
    "lorisnb.core.aggregate": "lorisnb.core.lifelong.aggregate",
    "lorisnb.core.association": "lorisnb.core.alignment.association",
    "lorisnb.core.blocks": "lorisnb.core.trajectory.blocks",
    "lorisnb.core.checks": "lorisnb.core.pipeline.checks",
    "lorisnb.core.coverage": "lorisnb.core.lifelong.coverage",
    "lorisnb.core.difficulty": "lorisnb.core.metrics.difficulty",
    "lorisnb.core.evo_options": "lorisnb.core.conventions.evo_options",
    "lorisnb.core.evo_steps": "lorisnb.core.conventions.evo_steps",
    "lorisnb.core.evo_sync": "lorisnb.core.conventions.evo_sync",
    "lorisnb.core.frames": "lorisnb.core.trajectory.frames",
    "lorisnb.core.geometry": "lorisnb.core.alignment.geometry",
    "lorisnb.core.index_pairs": "lorisnb.core.alignment.index_pairs",
    "lorisnb.core.matrices": "lorisnb.core.trajectory.rotations",
    "lorisnb.core.missing": "lorisnb.core.lifelong.missing",
    "lorisnb.core.model": "lorisnb.core.pipeline.model",
    "lorisnb.core.permutation": "lorisnb.core.stats.permutation",
    "lorisnb.core.plausibility": "lorisnb.core.pipeline.plausibility",
    "lorisnb.core.power": "lorisnb.core.stats.power",
    "lorisnb.core.ranking": "lorisnb.core.stats.ranking",
    "lorisnb.core.regression": "lorisnb.core.stats.regression",
    "lorisnb.core.relation_table": "lorisnb.core.metrics.relation_table",
    "lorisnb.core.relations": "lorisnb.core.metrics.relations",
    "lorisnb.core.relative": "lorisnb.core.metrics.relative",
    "lorisnb.core.rpe": "lorisnb.core.metrics.pairs",
    "lorisnb.core.scoring": "lorisnb.core.lifelong.scoring",
    "lorisnb.core.spec_evo": "lorisnb.core.spec.evo",
    "lorisnb.core.spec_table": "lorisnb.core.spec.table",
    "lorisnb.core.steps": "lorisnb.core.pipeline.steps",
    "lorisnb.core.surfaces": "lorisnb.core.lifelong.surfaces",
    "lorisnb.core.sweep": "lorisnb.core.lifelong.sweep",
    "lorisnb.core.timeline": "lorisnb.core.lifelong.timeline",
    "lorisnb.core.tolerances": "lorisnb.core.stats.tolerances",
    "lorisnb.core.trials": "lorisnb.core.stats.trials",
    "lorisnb.core.units": "lorisnb.core.trajectory.units",
    "lorisnb.core.validate": "lorisnb.core.spec.validate",
    "lorisnb.io.bags": "lorisnb.io.readers.bags",
    "lorisnb.io.chunks": "lorisnb.io.parsing.chunks",
    "lorisnb.io.data": "lorisnb.io.datasets.paths",
    "lorisnb.io.evo_results": "lorisnb.io.readers.evo_results",
    "lorisnb.io.formats": "lorisnb.io.readers.plain",
    "lorisnb.io.manifest": "lorisnb.io.datasets.manifest",
    "lorisnb.io.openloris": "lorisnb.io.readers.openloris",
    "lorisnb.io.ordslam": "lorisnb.io.readers.ordslam",
    "lorisnb.io.ordslam_names": "lorisnb.io.datasets.ordslam_catalog",
    "lorisnb.io.pieces": "lorisnb.io.parsing.pieces",
    "lorisnb.io.published": "lorisnb.io.datasets.published",
    "lorisnb.io.ranges": "lorisnb.io.parsing.ranges",
    "lorisnb.io.reading_options": "lorisnb.io.readers.options",
    "lorisnb.io.registry": "lorisnb.io.readers.registry",
    "lorisnb.io.rows": "lorisnb.io.parsing.rows",
    "lorisnb.io.scanner": "lorisnb.io.parsing.scanner",
    "lorisnb.io.times": "lorisnb.io.readers.times",
    "lorisnb.io.whole": "lorisnb.io.parsing.whole",
    "lorisnb.tools.comparison": "lorisnb.tools.decisions.comparison",
    "lorisnb.tools.crosscheck": "lorisnb.tools.peers.crosscheck",
    "lorisnb.tools.crosscheck_evo": "lorisnb.tools.peers.crosscheck_evo",
    "lorisnb.tools.crosscheck_reading": "lorisnb.tools.peers.crosscheck_reading",
    "lorisnb.tools.diff": "lorisnb.tools.decisions.diff",
    "lorisnb.tools.evaluate": "lorisnb.tools.evaluation.runner",
    "lorisnb.tools.evo_bridge": "lorisnb.tools.peers.evo_bridge",
    "lorisnb.tools.evo_import": "lorisnb.tools.peers.evo_import",
    "lorisnb.tools.grids": "lorisnb.tools.notebook.grids",
    "lorisnb.tools.history": "lorisnb.tools.decisions.history",
    "lorisnb.tools.indoor_outdoor": "lorisnb.tools.notebook.indoor_outdoor",
    "lorisnb.tools.inputs": "lorisnb.tools.evaluation.inputs",
    "lorisnb.tools.jobs": "lorisnb.tools.evaluation.jobs",
    "lorisnb.tools.leaderboard": "lorisnb.tools.report.leaderboard",
    "lorisnb.tools.lean_imports": "lorisnb.tools.report.lean_imports",
    "lorisnb.tools.notebook_params": "lorisnb.tools.notebook.params",
    "lorisnb.tools.plotting": "lorisnb.tools.figures.plotting",
    "lorisnb.tools.pool": "lorisnb.tools.evaluation.pool",
    "lorisnb.tools.provenance": "lorisnb.tools.report.provenance",
    "lorisnb.tools.report_html": "lorisnb.tools.report.html",
    "lorisnb.tools.report_index": "lorisnb.tools.report.index",
    "lorisnb.tools.report_notebooks": "lorisnb.tools.report.notebooks",
    "lorisnb.tools.runs": "lorisnb.tools.decisions.runs",
    "lorisnb.tools.status": "lorisnb.tools.evaluation.status",
    "lorisnb.tools.streaming": "lorisnb.tools.evaluation.streaming",
    "lorisnb.tools.tables": "lorisnb.tools.report.tables",
    "lorisnb.tools.trial_plots": "lorisnb.tools.figures.trials",
    "lorisnb.tools.warm_kernels": "lorisnb.tools.report.kernels",
    "lorisnb.tools.widgets": "lorisnb.tools.notebook.widgets",
}


class _Alias:
    """Finds a former module's name and loads it as the module at its new place (one module object
    under both names, so that state and monkeypatching are shared). A meta path finder and loader
    by their methods (``find_spec``, ``create_module``, ``exec_module``): ``importlib.abc``, whose
    base classes add nothing here, costs every ``import lorisnb`` 14 ms (it imports
    ``importlib.resources``)."""

    def find_spec(self, fullname, path=None, target=None):  # noqa: ANN001
        if fullname not in MOVED:
            return None
        return importlib.machinery.ModuleSpec(fullname, self)  # type: ignore[arg-type]  # a loader by its methods

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType:
        new = MOVED[spec.name]
        warnings.warn(
            f"{spec.name} moved to {new}; import it from there (the old name goes in a later release)",
            DeprecationWarning,
            stacklevel=2,
        )
        module = importlib.import_module(new)
        self._spec = module.__spec__
        return module

    def exec_module(self, module: ModuleType) -> None:
        module.__spec__ = self._spec  # the import system set the alias's spec on the shared module


def install() -> None:
    """Adds the finder once (idempotent)."""
    if not any(isinstance(f, _Alias) for f in sys.meta_path):
        sys.meta_path.append(_Alias())
