"""Lifelong scoring as the paper defines it, from per-pose errors: per-sequence scores
(:mod:`.scoring`), per-scene aggregates (:mod:`.aggregate`), missing output and coverage
(:mod:`.missing`, :mod:`.coverage`), the timelines of Fig. 2/3 (:mod:`.timeline`), threshold
sweeps (:mod:`.sweep`) and CR surfaces (:mod:`.surfaces`).

May import: the other core sub-packages but :mod:`lorisnb.core.stats` (enforced).
"""
