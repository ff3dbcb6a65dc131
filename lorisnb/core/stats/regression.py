"""Did a candidate run regress against a base run? The verdict of ``lorisnb diff``.

Both runs are per-sequence tables (:func:`lorisnb.core.lifelong.scoring.score`, with trials or not). A
sequence is matched by (suite, algorithm, scene, seq); with trials its value is the mean over them.

- **Per sequence**, every metric of :data:`METRICS`: the change and whether the candidate is
  worse by more than the metric's tolerance (:data:`DEFAULT_TOLERANCES`; an absolute amount in
  the metric's unit, or a share of the base value such as ``10%``). With at least two trials on
  each side, the two-sample permutation test of :mod:`lorisnb.core.stats.permutation` must also find
  the change (p <= alpha) unless the design cannot reach alpha (then ``decided_by`` says that the
  tolerance alone decided).
- **Per scene**, the scene values of :data:`lorisnb.core.stats.inference.WEIGHTS` (CR by duration, ...),
  both runs completed by :func:`lorisnb.core.lifelong.coverage.complete` with the base's sequences (a
  sequence the candidate lacks counts as a failed run); with trials, the stratified permutation
  test (trials relabelled within each sequence), Holm-corrected across the scenes of each
  algorithm and metric.
- A sequence the base has and the candidate lacks (``missing``) or scores with nothing matched
  (``failed``) is a regression whatever the tolerances. A candidate's new sequence is listed, not
  judged.

A value that is defined in the base and undefined (NaN) in the candidate (C-ATE once no pose is
correct) is worse. Identical runs give no change at all, so no regression.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd

from lorisnb.core.lifelong.coverage import complete, expected_from
from lorisnb.core.spec import validate
from lorisnb.core.stats.inference import WEIGHTS, holm, scene_means, with_trials
from lorisnb.core.stats.permutation import permutation_test
from lorisnb.core.stats.tolerances import DEFAULT_TOLERANCES
from lorisnb.errors import ValidationError

#: Metrics compared, each with +1 when larger is better and -1 when smaller is better.
METRICS: dict[str, int] = {
    "cr": 1, "cr_t": 1, "cs_r": 1, "ate_rmse": -1, "aoe_rmse": -1, "c_ate_rmse": -1, "c_aoe_rmse": -1,
    "rpe_trans_rmse": -1, "rpe_rot_rmse": -1,
}  # fmt: skip
#: The change a metric may worsen by before it is a regression: absolute (metric's unit) or "N%".
KEYS = ["suite", "algorithm", "scene", "seq"]


@dataclass(frozen=True)
class Tolerance:
    """How much worse a metric may get: ``amount`` in the metric's unit, or, when ``relative``, as
    a share of the base value."""

    amount: float
    relative: bool

    def of(self, base: float) -> float:
        return self.amount * abs(base) if self.relative else self.amount

    def __str__(self) -> str:
        return f"{100 * self.amount:g}%" if self.relative else f"{self.amount:g}"


def parse_tolerances(spec: str | Mapping[str, str | float] | None = None) -> dict[str, Tolerance]:
    """The defaults, updated by ``spec``: ``"cr=0.02,ate_rmse=0.05"`` or a mapping; a value is a
    non-negative number in the metric's unit or a percentage of the base value (``"5%"``)."""
    items: dict[str, str | float] = dict(DEFAULT_TOLERANCES)
    if isinstance(spec, str):
        parts = [p.strip() for p in spec.split(",")]
        if any(parts) and not all(parts):  # as every comma list: an empty item is refused, not dropped
            raise ValidationError(f"tolerance {spec!r}: an empty item between commas; expected METRIC=VALUE,...")
        given: set[str] = set()
        for part in filter(None, parts):
            name, sep, text = part.partition("=")
            if not sep:
                raise ValidationError(f"tolerance {part!r}: expected METRIC=VALUE, e.g. cr=0.02 or ate_rmse=5%")
            if name.strip() in given:  # the last would silently replace the first
                raise ValidationError(f"tolerance {spec!r}: {name.strip()} given twice; expected each metric once")
            given.add(name.strip())
            items[name.strip()] = text.strip()
    elif spec is not None:
        if not isinstance(spec, Mapping):
            raise ValidationError(f"tolerance: expected 'metric=value,...' or a mapping, got {type(spec).__name__}")
        items.update(spec)
    out = {}
    for name, value in items.items():
        if name not in METRICS:
            raise ValidationError(f"tolerance {name}: not a compared metric; expected one of {', '.join(METRICS)}")
        text = str(value).strip()
        m = re.fullmatch(r"([0-9.eE+-]+)\s*(%?)", text)
        try:
            amount = float(m.group(1)) if m else float("nan")
        except ValueError:
            amount = float("nan")
        if not np.isfinite(amount) or amount < 0 or isinstance(value, bool):
            raise ValidationError(
                f"tolerance {name}={value}: expected a non-negative number in the metric's unit or a percentage (5%)"
            )
        out[name] = Tolerance(amount / 100 if m and m.group(2) else amount, bool(m and m.group(2)))
    return out


def _per_sequence(table: pd.DataFrame) -> dict[tuple, pd.DataFrame]:
    t = with_trials(table)
    return {k: g for k, g in t.groupby(KEYS, sort=False, observed=True)}


def _judge(base: float, cand: float, sign: int, tol: Tolerance) -> tuple[float, str]:
    """(how much worse the candidate is, in the metric's unit, + = worse; status)."""
    if not np.isfinite(base):
        return np.nan, "ok"
    if not np.isfinite(cand):
        return np.inf, "regression"
    worse = sign * (base - cand)
    slack = tol.of(base) + 1e-12 * max(1.0, abs(base))
    return worse, "regression" if worse > slack else ("improvement" if -worse > slack else "ok")


def _test(base: list[np.ndarray], cand: list[np.ndarray], weights: np.ndarray, seed: int) -> tuple[float, float]:
    """(p, min_p) of the permutation test, when both sides have at least two trials everywhere."""
    if not base or min(min(len(x) for x in base), min(len(x) for x in cand)) < 2:
        return np.nan, np.nan
    res = permutation_test(base, cand, weights, rng=np.random.default_rng(seed))
    return res.pvalue, res.min_p


def sequence_changes(
    base: pd.DataFrame, cand: pd.DataFrame, tolerances: Mapping[str, Tolerance] | None = None, alpha: float = 0.05,
    seed: int = 0,
) -> pd.DataFrame:  # fmt: skip
    """One row per sequence of either run and metric (and one ``sequence`` row per sequence
    missing or failed in the candidate, or new in it): ``base``, ``cand`` (means over trials),
    ``worse_by``, ``tolerance``, ``trials_base``, ``trials_cand``, ``p``, ``min_p``, ``status``
    (``ok``, ``improvement``, ``regression``, ``missing``, ``failed``, ``new``) and ``decided_by``."""
    tols = parse_tolerances() if tolerances is None else dict(tolerances)
    seed = validate.seed(seed)
    b, c = _per_sequence(base), _per_sequence(cand)
    rows = []
    for key in list(b) + [k for k in c if k not in b]:
        label = dict(zip(KEYS, key, strict=True))
        gb, gc = b.get(key), c.get(key)
        if gb is None or gc is None or not len(gc):
            status = "new" if gb is None else "missing"
            rows.append(dict(label, metric="sequence", base="absent" if gb is None else "present",
                             cand="present" if gb is None else "missing", status=status, decided_by="coverage"))  # fmt: skip
            continue
        nothing_b = float(gb["matched"].sum()) == 0 if "matched" in gb else False
        if "matched" in gc and float(gc["matched"].sum()) == 0 and not nothing_b:
            rows.append(dict(label, metric="sequence", base="matched", cand="nothing matched", status="failed",
                             decided_by="coverage"))  # fmt: skip
        for metric, sign in METRICS.items():
            if metric not in gb.columns or metric not in gc.columns:
                continue
            xb, xc = gb[metric].to_numpy(float), gc[metric].to_numpy(float)
            vb = float(np.nanmean(xb)) if np.isfinite(xb).any() else np.nan
            vc = float(np.nanmean(xc)) if np.isfinite(xc).any() else np.nan
            worse, status = _judge(vb, vc, sign, tols[metric])
            p, floor = _test([xb[np.isfinite(xb)]], [xc[np.isfinite(xc)]], np.ones(1), seed)
            decided = "tolerance"
            if np.isfinite(p):
                if floor <= alpha:
                    decided = f"tolerance and permutation test (alpha {alpha})"
                    status = status if p <= alpha or status == "ok" else "ok"
                else:
                    decided = f"tolerance (trials cannot reach alpha {alpha}: smallest p {floor:.3g})"
            rows.append(dict(label, metric=metric, base=vb, cand=vc, worse_by=worse, tolerance=str(tols[metric]),
                             trials_base=len(xb), trials_cand=len(xc), p=p, min_p=floor, status=status,
                             decided_by=decided))  # fmt: skip
    cols = KEYS + ["metric", "base", "cand", "worse_by", "tolerance", "trials_base", "trials_cand", "p", "min_p",
                   "status", "decided_by"]  # fmt: skip
    return pd.DataFrame(rows, columns=cols)


def scene_changes(
    base: pd.DataFrame, cand: pd.DataFrame, tolerances: Mapping[str, Tolerance] | None = None, alpha: float = 0.05,
    seed: int = 0, expected: pd.DataFrame | None = None,
) -> pd.DataFrame:  # fmt: skip
    """One row per suite, algorithm, scene and scene metric: the scene values of both runs over the
    base's sequences (a sequence the candidate lacks counts as failed), ``worse_by``, the test
    across trials where both runs have them (``p``, ``min_p``, ``p_holm``: Holm across the scenes of
    each algorithm and metric), ``status`` and ``decided_by``. ``expected``: every ground-truth
    sequence of the scenes (``scene``, ``seq``, ``gt_duration``, as
    :func:`lorisnb.core.lifelong.aggregate.durations_table`), when known: a sequence no row of a run holds
    then counts as failed in its scene value, as in ``compare``; else the sequences of ``base``."""
    tols = parse_tolerances() if tolerances is None else dict(tolerances)
    seed = validate.seed(seed)
    expected = expected_from(base, *([] if expected is None else [expected]))
    b = with_trials(base)
    kept = set(zip(b["suite"], b["algorithm"], b["scene"], strict=True))
    c = with_trials(cand)
    c = c[
        np.array([k in kept for k in zip(c["suite"], c["algorithm"], c["scene"], strict=True)], bool)
    ]  # a mask, also when empty
    c = c[c.set_index(KEYS).index.isin(b.set_index(KEYS).index)]  # the base's sequences
    lost = kept - set(zip(c["suite"], c["algorithm"], c["scene"], strict=True))
    if lost:  # a scene without any output in the candidate: all its sequences failed
        gone = b[np.array([k in lost for k in zip(b["suite"], b["algorithm"], b["scene"], strict=True)], bool)]
        c = pd.concat([c, _failed_copy(gone)], ignore_index=True)
    fb, _ = complete(b, expected)
    fc, _ = complete(c, expected)
    rows = []
    for metric in (m for m in WEIGHTS if m in b.columns):
        vb = scene_means(fb, metric).set_index(["suite", "scene", "algorithm"])["value"]
        vc = scene_means(fc, metric).set_index(["suite", "scene", "algorithm"])["value"]
        block = []
        for (suite, scene, alg), v0 in vb.items():
            v1 = float(vc.get((suite, scene, alg), np.nan))
            worse, status = _judge(float(v0), v1, METRICS[metric], tols[metric])
            p, floor = _scene_test(fb, fc, suite, alg, scene, metric, seed)
            block.append(dict(suite=suite, algorithm=alg, scene=scene, seq=None, metric=metric, base=float(v0),
                              cand=v1, worse_by=worse, tolerance=str(tols[metric]), p=p, min_p=floor, status=status))  # fmt: skip
        for _, grp in pd.DataFrame(block).groupby(["suite", "algorithm"], sort=False) if block else []:
            adj = holm(grp["p"].to_numpy(float))
            for i, pa in zip(grp.index, adj, strict=True):
                r = block[i]
                r["p_holm"] = pa
                r["decided_by"] = "tolerance"
                if np.isfinite(pa):
                    if r["min_p"] * len(grp) <= alpha:
                        r["decided_by"] = f"tolerance and permutation test (Holm across scenes, alpha {alpha})"
                        r["status"] = r["status"] if pa <= alpha or r["status"] == "ok" else "ok"
                    else:
                        r["decided_by"] = f"tolerance (trials cannot reach alpha {alpha} after Holm)"
        rows += block
    cols = KEYS + ["metric", "base", "cand", "worse_by", "tolerance", "p", "min_p", "p_holm", "status", "decided_by"]
    return pd.DataFrame(rows, columns=cols)


def _failed_copy(rows: pd.DataFrame) -> pd.DataFrame:
    """The base's rows as failed runs (a candidate without any output for them)."""
    out = rows.copy()
    for col, v in (("cr", 0.0), ("cr_t", 0.0), ("cs_r", 0.0), ("matched", 0), ("correct_time", 0.0),
                   ("track_time", 0.0), ("c_matched", 0)):  # fmt: skip
        if col in out.columns:
            out[col] = v
    for col in ("c_ate_rmse", "ate_rmse", "aoe_rmse", "c_aoe_rmse"):
        if col in out.columns:
            out[col] = np.nan
    return out


def _scene_test(fb: pd.DataFrame, fc: pd.DataFrame, suite: str, alg: str, scene: str, metric: str, seed: int
                ) -> tuple[float, float]:  # fmt: skip
    """The stratified permutation test of one scene, base against candidate, when both have trials."""
    sel_b = fb[(fb["suite"] == suite) & (fb["algorithm"] == alg) & (fb["scene"] == scene)]
    sel_c = fc[(fc["suite"] == suite) & (fc["algorithm"] == alg) & (fc["scene"] == scene)]
    w_col = WEIGHTS[metric]
    xb, xc, w = [], [], []
    for seq, g in sel_b.groupby("seq", sort=True):
        h = sel_c[sel_c["seq"] == seq]
        vb, vc = g[metric].to_numpy(float), h[metric].to_numpy(float)
        vb, vc = vb[np.isfinite(vb)], vc[np.isfinite(vc)]
        if len(vb) and len(vc):
            xb.append(vb)
            xc.append(vc)
            w.append(1.0 if w_col is None else float(g[w_col].mean()))
    weights = np.array(w)
    if not len(weights) or not np.all(np.isfinite(weights)) or weights.sum() <= 0:
        return np.nan, np.nan
    return _test(xb, xc, weights, seed)


def verdict(sequences: pd.DataFrame, scenes: pd.DataFrame) -> dict:
    """The machine-readable verdict: ``verdict`` ("ok" or "regression"), ``regressions`` (objects
    with algorithm, scene, seq (null for a scene value), metric, base, cand, and suite, level,
    worse_by, tolerance, p), and counts."""
    bad = {"regression", "missing", "failed"}
    regs = []
    for level, t in (("sequence", sequences), ("scene", scenes)):
        for r in t[t["status"].isin(bad)].to_dict("records"):
            regs.append(dict(algorithm=r["algorithm"], scene=r["scene"], seq=_plain(r["seq"]), metric=r["metric"],
                             base=_plain(r["base"]), cand=_plain(r["cand"]), suite=r["suite"], level=level,
                             status=r["status"], worse_by=_plain(r.get("worse_by")),
                             tolerance=_plain(r.get("tolerance")), p=_plain(r.get("p")),
                             decided_by=r.get("decided_by")))  # fmt: skip
    counts = {s: int((sequences["status"] == s).sum()) for s in ("ok", "improvement", "regression", "missing",
                                                                   "failed", "new")}  # fmt: skip
    n_seq = sequences[["suite", "algorithm", "scene", "seq"]].drop_duplicates().shape[0] if len(sequences) else 0
    return dict(verdict="regression" if regs else "ok", regressions=regs, sequences=n_seq, counts=counts,
                regressed_sequences=len({(r["suite"], r["algorithm"], r["scene"], r["seq"]) for r in regs
                                         if r["level"] == "sequence"}))  # fmt: skip


def _plain(v: object) -> object:
    """JSON-friendly: NaN and infinity as None, numpy numbers as Python numbers."""
    if v is None or isinstance(v, str):
        return v
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    try:
        f = float(v)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return str(v)
    return f if np.isfinite(f) else None
