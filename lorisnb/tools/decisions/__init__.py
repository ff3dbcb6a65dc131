"""Decisions over runs: reading run folders and tables (:mod:`.runs`), ``diff`` (did a candidate
regress? :mod:`.diff`), ``history`` (:mod:`.history`) and ``compare`` (:mod:`.comparison`). The
statistics behind them are :mod:`lorisnb.core.stats`.

May import: :mod:`lorisnb.tools.evaluation`, :mod:`lorisnb.io`, :mod:`lorisnb.core`.
"""
