"""Decisions over runs: reading run folders and tables (:mod:`.runs`), ``diff`` (did a candidate
regress? :mod:`.diff`), ``history`` (:mod:`.history`) and ``compare`` (:mod:`.comparison`), the
measured error rates of ``diff``'s verdict (:mod:`.calibration`, ``make calibrate``), and the one
rule that escapes a name received from others in every output (:mod:`.escape`). The statistics
behind them are :mod:`lorisnb.core.stats`.

May import: :mod:`lorisnb.tools.evaluation`, a report run's ``run.json``
(:mod:`lorisnb.tools.report.provenance`), the paper-ready tables ``compare`` writes
(:mod:`lorisnb.tools.report.tables`), the name of a report run's input-errors table
(:mod:`lorisnb.tools.notebook.start`), the one canonical form of a report's parameters that a
run records (:mod:`lorisnb.tools.notebook.params`), the figures ``history`` draws (:mod:`lorisnb.tools.figures.plotting`),
:mod:`lorisnb.io`, :mod:`lorisnb.core` and :mod:`lorisnb.errors`; the report, the notebooks and the
figures import this package too (docs/architecture.md, "Sub-packages that import each other").
"""
