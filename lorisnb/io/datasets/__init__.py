"""The datasets: where the data root is and its ground truth (:mod:`.paths`), multi-session
manifests (:mod:`.manifest`), the ORDSLAM scenario catalog (:mod:`.ordslam_catalog`) and the
papers' published numbers (:mod:`.published`).

May import: :mod:`lorisnb.io.readers`, :mod:`lorisnb.core` and :mod:`lorisnb.errors`.
"""
