"""Figures (matplotlib / seaborn): the paper's timelines, trajectories, sweeps (:mod:`.plotting`)
and repeated trials (:mod:`.trials`).

May import: :mod:`lorisnb.io`, :mod:`lorisnb.core`.
"""
