"""Association in time and alignment in space: the ground truth interpolated at estimate stamps
(:mod:`.association`), pairing by index (:mod:`.index_pairs`), and rigid / similarity fits and
quaternion algebra (:mod:`.geometry`).

May import: :mod:`lorisnb.core.trajectory`, :mod:`lorisnb.core.spec` and :mod:`lorisnb.errors`; no
metric, pipeline, scoring or statistics (enforced).
"""
