"""Rankings that say what the data can and cannot separate: algorithms ordered by a scene metric
with ties where the test of :func:`lorisnb.core.stats.inference.pairwise` finds no difference, and how a
ranking holds up over a grid of thresholds and the trials together."""

from __future__ import annotations

import numpy as np
import pandas as pd

from lorisnb.core.lifelong.aggregate import aggregate_scenes
from lorisnb.core.stats.inference import pairwise, scene_means, with_trials
from lorisnb.core.trajectory.frames import PAPER_EPS, PAPER_PHI


def ranking(
    table: pd.DataFrame, metric: str = "cr", alpha: float = 0.05, seed: int = 0, pairs: pd.DataFrame | None = None
) -> pd.DataFrame:
    """Algorithms of each scene ordered by ``metric``, with ``rank`` = 1 + the number of
    algorithms significantly better by the one test of :func:`lorisnb.core.stats.inference.pairwise`
    (Holm-corrected), so algorithms the data cannot separate share a rank; ``tied_with`` names
    them, ``better_than`` names those it beats. ``value`` is the scene value of
    :func:`lorisnb.core.stats.inference.confidence_intervals` (weighted mean over the sequences of each
    sequence's mean over trials). Give ``pairs`` (the pairwise table) to reuse it."""
    better_high = metric != "c_ate_rmse"
    pairs = pairwise(table, metric, alpha=alpha, seed=seed) if pairs is None else pairs
    values = scene_means(table, metric)
    rows = []
    for (suite, scene), s in values.groupby(["suite", "scene"], sort=False):
        p = pairs[(pairs["suite"] == suite) & (pairs["scene"] == scene)]
        for alg, value in zip(s["algorithm"], s["value"], strict=True):
            mine = p[(p["a"] == alg) | (p["b"] == alg)]
            other = np.where(mine["a"] == alg, mine["b"], mine["a"])
            beaten = [o for o, w in zip(other, mine["better"], strict=True) if w == o]
            beats = [o for o, w in zip(other, mine["better"], strict=True) if w == alg]
            tied = [o for o, w in zip(other, mine["better"], strict=True) if w == ""]
            rows.append(dict(suite=suite, scene=scene, metric=metric, algorithm=alg, value=float(value),
                             rank=1 + len(beaten), tied_with=", ".join(sorted(tied)),
                             better_than=", ".join(sorted(beats))))  # fmt: skip
    out = pd.DataFrame(
        rows, columns=["suite", "scene", "metric", "algorithm", "value", "rank", "tied_with", "better_than"]
    )
    if out.empty:
        return out
    return out.sort_values(["suite", "scene", "rank", "value"], ascending=[True, True, True, not better_high])


def robust_ranking(sweep_table: pd.DataFrame, durations: pd.DataFrame, metric: str = "cr",
                   reference: tuple[float, float] | None = None) -> tuple[pd.DataFrame, pd.DataFrame]:  # fmt: skip
    """Rankings over a grid of thresholds and the trials together, from a sweep
    (:func:`lorisnb.core.lifelong.sweep.sweep`, eps x phi) of several algorithms.

    Returns:
        first: per scene and algorithm, the share of (eps, phi, trial) cases in which it ranks
            first by the scene ``metric`` (algorithms tied at the top all count as first).
        region: per scene, eps and phi, whether the ranking by the mean over trials equals the
            ranking at ``reference`` (default: the paper's eps for the scene and phi 30 deg), and
            Kendall's tau between the two.
    """
    from scipy import stats as sps  # here, not at the top: scipy.stats takes half a second to import

    t = with_trials(sweep_table)
    t = t.astype({c: str for c in ("algorithm", "scene", "suite", "file") if c in t.columns})
    if "eps_value" in t.columns:
        t["eps_value"] = t["eps_value"].astype(str)
    scenes = aggregate_scenes(t, durations)
    sign = -1.0 if metric == "c_ate_rmse" else 1.0
    keys = ["suite", "scene", "eps", "phi", "trial"]
    scenes["_score"] = sign * scenes[metric].fillna(-np.inf if sign > 0 else np.inf)
    top = scenes.groupby(keys, sort=False)["_score"].transform("max")
    best = scenes[np.isclose(scenes["_score"], top, rtol=0, atol=1e-12) | (scenes["_score"] == top)]
    cases = scenes.groupby(["suite", "scene"])[keys[2:]].apply(lambda d: len(d.drop_duplicates()))
    first = best.groupby(["suite", "scene", "algorithm"]).size().rename("firsts").reset_index()
    first["cases"] = first.set_index(["suite", "scene"]).index.map(cases).to_numpy()
    first["share_first"] = first["firsts"] / first["cases"]
    mean = scenes.groupby(["suite", "scene", "eps", "phi", "algorithm"])["_score"].mean().reset_index()
    rows = []
    for (suite, scene), g in mean.groupby(["suite", "scene"], sort=False):
        ref_eps, ref_phi = reference if reference is not None else (PAPER_EPS.get(scene, np.nan), PAPER_PHI)
        grid_eps = np.unique(g["eps"].to_numpy(float))
        grid_phi = np.unique(g["phi"].to_numpy(float))
        e0 = grid_eps[np.argmin(np.abs(grid_eps - ref_eps))]
        p0 = grid_phi[np.argmin(np.abs(grid_phi - ref_phi))]
        ref = g[(g["eps"] == e0) & (g["phi"] == p0)].set_index("algorithm")["_score"]
        ref_order = list(ref.sort_values(ascending=False).index)
        for (eps, phi), s in g.groupby(["eps", "phi"], sort=True):
            cur = s.set_index("algorithm")["_score"].reindex(ref.index)
            order = list(cur.sort_values(ascending=False).index)
            kt = sps.kendalltau(ref.to_numpy(), cur.to_numpy()).statistic if len(ref) > 1 else np.nan
            rows.append(dict(suite=suite, scene=scene, eps=float(eps), phi=float(phi), reference_eps=float(e0),
                             reference_phi=float(p0), same_ranking=order == ref_order, kendall_tau=kt))  # fmt: skip
    return first.sort_values(["suite", "scene", "share_first"], ascending=[True, True, False]), pd.DataFrame(rows)
