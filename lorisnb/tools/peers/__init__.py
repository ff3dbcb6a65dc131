"""The peers' own tools: a bridge to evo (:mod:`.evo_bridge`), evo's result zips as tables
(:mod:`.evo_import`), the cross-checks of lorisnb against evo (:mod:`.crosscheck`,
:mod:`.crosscheck_evo`, :mod:`.crosscheck_reading`), and one pair under every peer's preset side by
side (:mod:`.every_number`).

May import: :mod:`lorisnb.tools.evaluation`, the optional-dependency check :mod:`lorisnb.tools._extras`,
:mod:`lorisnb.io`, :mod:`lorisnb.core` and :mod:`lorisnb.errors`; evo only when called.
"""
