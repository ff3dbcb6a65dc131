"""Numeric text parsing shared by every reader: the byte scanner (:mod:`.scanner`), whole files
(:mod:`.whole`), pieces on threads (:mod:`.pieces`, :mod:`.ranges`) and streamed chunks
(:mod:`.chunks`, :mod:`.rows`).

May import: :mod:`lorisnb.core` and :mod:`lorisnb.errors`; no reader or dataset (enforced).
"""
