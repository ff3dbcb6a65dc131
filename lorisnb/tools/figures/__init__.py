"""Figures (matplotlib / seaborn): the paper's timelines, trajectories, sweeps (:mod:`.plotting`)
repeated trials (:mod:`.trials`), the KITTI devkit's per-length plot (:mod:`.kitti`) and ov_eval's
per-axis errors with their 3-sigma bounds (:mod:`.consistency`).

May import: :mod:`lorisnb.io`, :mod:`lorisnb.core`.
"""
