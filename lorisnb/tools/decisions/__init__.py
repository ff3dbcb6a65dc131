"""Decisions over runs: reading run folders and tables (:mod:`.runs`), ``diff`` (did a candidate
regress? :mod:`.diff`), ``history`` (:mod:`.history`) and ``compare`` (:mod:`.comparison`), and the
one rule that escapes a name received from others in every output (:mod:`.escape`). The statistics
behind them are :mod:`lorisnb.core.stats`.

May import: :mod:`lorisnb.tools.evaluation`, :mod:`lorisnb.io`, :mod:`lorisnb.core`.
"""
