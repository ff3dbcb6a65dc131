"""Figures (matplotlib / seaborn): the paper's timelines, trajectories, sweeps (:mod:`.plotting`),
repeated trials (:mod:`.trials`), the KITTI devkit's per-length plot (:mod:`.kitti`), ov_eval's
per-axis errors with their 3-sigma bounds (:mod:`.consistency`), and a figure's PNG rendered again
by redrawing only what changed (:mod:`.blit`).

May import: the one escape of a received name (:mod:`lorisnb.tools.decisions.escape`), the metrics'
labels (:mod:`lorisnb.tools.report.tables`), :mod:`lorisnb.io`, :mod:`lorisnb.core` and
:mod:`lorisnb.errors`; :mod:`lorisnb.tools.decisions` imports this package too (docs/architecture.md,
"Sub-packages that import each other").
"""
