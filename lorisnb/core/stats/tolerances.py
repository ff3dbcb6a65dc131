"""The default tolerances of ``lorisnb diff`` (:mod:`lorisnb.core.stats.regression`), in a module of
their own so that the command line's parser (its help text) does not import pandas."""

from __future__ import annotations

#: How much worse each metric may get before it is a regression: an amount in the metric's unit, or
#: a share of the base value (``10%``).
DEFAULT_TOLERANCES: dict[str, str] = {
    "cr": "0.02", "cr_t": "0.02", "cs_r": "0.02", "ate_rmse": "10%", "aoe_rmse": "10%", "c_ate_rmse": "10%",
    "c_aoe_rmse": "10%", "rpe_trans_rmse": "10%", "rpe_rot_rmse": "10%",
}  # fmt: skip
