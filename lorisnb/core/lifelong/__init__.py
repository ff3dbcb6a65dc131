"""Lifelong scoring as the paper defines it, from per-pose errors: per-sequence scores
(:mod:`.scoring`), per-scene aggregates (:mod:`.aggregate`), missing output and coverage
(:mod:`.missing`, :mod:`.coverage`), the timelines of Fig. 2/3 (:mod:`.timeline`), threshold
sweeps (:mod:`.sweep`) and CR surfaces (:mod:`.surfaces`).

May import: :mod:`lorisnb.core.alignment`, :mod:`lorisnb.core.metrics`, :mod:`lorisnb.core.pipeline`,
:mod:`lorisnb.core.spec`, :mod:`lorisnb.core.trajectory` and :mod:`lorisnb.errors`; never
:mod:`lorisnb.core.stats` (enforced).
"""
