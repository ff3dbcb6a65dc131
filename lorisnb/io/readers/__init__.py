"""Readers of every trajectory format: the format registry (:mod:`.registry`), plain TUM / KITTI /
EuRoC files (:mod:`.plain`), OpenLORIS result files (:mod:`.openloris`), ORDSLAM (:mod:`.ordslam`),
ROS bags (:mod:`.bags`), trajectories with pose covariances (:mod:`.covariance`), times files
(:mod:`.times`), evo result zips (:mod:`.evo_results`), and which reading options apply to which
format (:mod:`.options`).

May import: :mod:`lorisnb.io.parsing`, the ORDSLAM catalog :mod:`lorisnb.io.datasets.ordslam_catalog`,
:mod:`lorisnb.core` and :mod:`lorisnb.errors`.
"""
