"""The default tolerances and rerun spreads of ``lorisnb diff`` (:mod:`lorisnb.core.stats.regression`),
in a module of their own so that the command line's parser (its help text) does not import pandas."""

from __future__ import annotations

from lorisnb.core.alignment.geometry import MIN_LEVER as _LEVER

#: How much worse each metric may get before it is a regression: an amount in the metric's unit, or
#: a share of the base value (``10%``). A change is a regression when the data show it *beyond* this
#: amount (the rule of :mod:`lorisnb.core.stats.regression`).
DEFAULT_TOLERANCES: dict[str, str] = {
    "cr": "0.02", "cr_t": "0.02", "cs_r": "0.02", "ate_rmse": "10%", "aoe_rmse": "10%", "c_ate_rmse": "10%",
    "c_aoe_rmse": "10%", "rpe_trans_rmse": "10%", "rpe_rot_rmse": "10%",
}  # fmt: skip

#: The spread of one rerun (standard deviation of a run's value about the system's mean) taken at
#: the least: "rate" for CR, CR-T and CS-R (in CR units), "log" for the errors (ATE, AOE, RPE; the
#: log of the ratio, 0.1 is about 10 %). From the 20 real rerun pairs of the icra20 results (the
#: median |change| over sqrt(2) x 0.674): with trials, half of it is added to every comparison's
#: own spread (:mod:`lorisnb.core.stats.regression`).
RERUN_SPREAD: dict[str, float] = {"rate": 0.017, "log": 0.19}

#: How far beyond its tolerance a change of a single run per side must go to be a regression, by
#: level and metric (on the judged scale: CR units for the rates, the log of the ratio for the
#: errors). Measured by ``make calibrate`` on noise-only single-run diffs of reruns of the icra20
#: outputs (the noise of their real rerun pairs): each night's largest change of each metric, its
#: 95th percentile, all scaled by one factor (1.18) so that in 95 % of the nights no metric at any
#: level goes beyond its band. Real reruns of one sequence can flip between tracking and not (CR
#: 0.16 against 0.999 in one real pair): a single run cannot tell a sequence's CR drop from rerun
#: noise (its band is above 1), only a sequence that stopped tracking altogether (nothing matched,
#: always a regression), a scene-wide drop of CR by more than 0.23 (the band 0.21 plus the
#: tolerance 0.02), or an ATE 6.8 times as large.
SINGLE_RUN_BAND: dict[str, dict[str, float]] = {
    "sequence": {"cr": 1.01, "cr_t": 1.16, "cs_r": 0.55, "ate_rmse": 1.82, "aoe_rmse": 2.44, "c_ate_rmse": 1.74,
                 "c_aoe_rmse": 2.36, "rpe_trans_rmse": 0.96, "rpe_rot_rmse": 0.61},
    "scene": {"cr": 0.21, "cr_t": 0.3, "cs_r": 0.12, "c_ate_rmse": 0.85},
}  # fmt: skip

#: Fewer matched poses than this in the base (or, for the errors, in either run) and a sequence is
#: too little to judge: an alignment on a handful of poses is unstable.
MIN_MATCHED = 50

#: :data:`lorisnb.core.alignment.geometry.MIN_LEVER` (metres), kept here with the gate's other tolerances.
MIN_LEVER = _LEVER
