"""The typical mistakes of the labs, each with the hint a learner gets when an answer matches it
(the one registry of them; re-exported by :mod:`lorisnb.tools.teaching`)."""

from __future__ import annotations

#: The typical mistakes, each with the hint a learner gets when their answer matches it.
MISTAKES: dict[str, str] = {
    "and_or": "a pose is correct only if BOTH errors are small: (ATE <= eps) AND (AOE <= phi), Eq. (1); "
    "'or' (|) accepts a pose that is right in one error only",
    "elementwise": "on numpy arrays use & and | (element-wise), not Python's `and` / `or`, and put each "
    "comparison in parentheses: (ate_m <= eps) & (aoe_deg <= phi)",
    "swapped": "eps (metres) bounds the ATE and phi (degrees) the AOE; the two thresholds are swapped",
    "fraction": "CR, CR-T and CS-R are fractions between 0 and 1, not percentages",
    "ate_only": "the orientation condition is missing: Eq. (1) also needs AOE <= phi",
    "aoe_only": "the position condition is missing: Eq. (1) also needs ATE <= eps",
    "inclusive": "Eq. (1) is inclusive: a pose exactly at the threshold (ATE == eps) is correct; use <=, not <",
    "degrees_radians": "degrees vs radians: AOE and phi are both in degrees in lorisnb; converting one of them "
    "with np.radians (or np.degrees) compares numbers in different units",
    "delta_cap": "forgot the delta cap: each pose holds until the next one but at most delta seconds, "
    "min(t_{k+1} - t_k, delta) (Eq. 2); without it a tracker that stops outputting keeps earning time",
    "cr_vs_crt": "CR vs CR-T: CR divides the correct time by the whole sequence, t_max - t_min (Eq. 2); "
    "dividing by t_max - t0 (time after the first pose) gives CR-T (Eq. 3)",
    "crt_vs_cr": "CR-T vs CR: CR-T divides by the time after the first output pose, t_max - t0 (Eq. 3); "
    "dividing by t_max - t_min gives CR (Eq. 2)",
    "poses_not_time": "CR is a share of TIME, not of poses: weight each correct pose by the time it holds, "
    "min(t_{k+1} - t_k, delta), and divide by the sequence's duration",
    "gt_span": "the denominator is the ground truth's span, t_max - t_min, not the span of the estimate's own stamps",
    "held_backward": "each pose holds FORWARD, until the next pose: min(t_{k+1} - t_k, delta), not the time since "
    "the previous pose",
    "held_delta": "delta is a cap, not the time a pose holds: each pose holds until the next one, "
    "min(t_{k+1} - t_k, delta), often much less than delta",
    "delta_cut": "a pose whose next one comes more than delta later still holds for delta seconds: "
    "min(t_{k+1} - t_k, delta) caps its time, it does not drop it",
    "absolute_time": "stamps are absolute times (OpenLORIS: seconds since 1970): a duration is a difference of two "
    "stamps, t0 - t_min or t_max - t_min, never one stamp alone",
    "nan": "NaN comes from 0 / 0, or from a mean or maximum of no values (np.mean of an empty selection): find where "
    "your formula divides or averages; Eq. (1)-(4) are a comparison, a sum over a duration, an exponential",
    "gap_last_pose": "the last pose before the gap still holds for delta seconds into it (Eq. 2)",
    "wrong_poses_count": "only correct poses earn time: multiply each pose's held time by c_k (0 or 1)",
    "last_pose": "the last pose holds too: its next time is t_{N+1} = t_max, and it is capped at delta like the others",
    "coarse_grid": "your eps reaches the target but is not the smallest: refine the grid of eps you scanned, "
    "or use lorisnb.core.lifelong.sweep.eps_at_cr, which is exact",
    "first_pose": "CS-R is 0 when the first pose is wrong: Eq. (4) multiplies by c(p_0); a system that "
    "re-localizes to a wrong place must not score",
    "tau_inverted": "the exponent is -(t0 - t_min) / tau (Eq. 4): the waiting time over the time factor, not the "
    "other way round",
    "tau_sign": "the exponent is negative, exp(-(t0 - t_min) / tau): waiting longer must lower the score",
    "linear": "CS-R decays exponentially, exp(-(t0 - t_min) / tau) (Eq. 4), not linearly",
    "alignment": "per-sequence vs lifelong alignment: in a lifelong run all sequences share one alignment, "
    "fitted on the first sequence; aligning each sequence on itself hides a wrong re-localization",
    "phi_ignored": "the orientation threshold phi applies too: a pose needs AOE <= phi to count",
    "percent": "a percentage is 100 x the ratio",
    "extent_vs_length": "normalize by the distance travelled (path length), not by the size of the area (extent)",
    "rmse_vs_mean": "RMSE is the root of the mean SQUARE, sqrt(mean(ATE^2)) (the `ate_rmse` column), not the mean "
    "ATE (`ate_mean`): squaring weighs large errors more",
    "signature": "the checks call your function with the exercise's argument names, by keyword (`ate_m=...`): keep "
    "them as the exercise writes them; a renamed, missing or extra argument is not found",
    "c_ate": "use the ATE RMSE over all matched poses here, not the C-ATE over correct poses only",
    "timeline_label": "in the timeline the percentage at the top left of a row is the algorithm's CR over the scene; "
    "the number at the bottom right is its C-ATE RMSE, in metres, not a rate",
}
