"""Per-scene aggregates of per-sequence tables, as in the paper's Fig. 2 and Fig. 3 and the
official ``evaluate_all.py``. Pure: the ground-truth durations are an argument
(:func:`durations_table` builds them from ground-truth files already read).

One implementation on numpy columns (:func:`aggregate_columns`, which the command line prints
without importing pandas) behind the DataFrame one (:func:`aggregate_scenes`). Sums and means are
compensated (Kahan) within each group as pandas' ``groupby`` sums them, in the order of the rows'
sequence numbers (then file names: :func:`_within`), not the table's row order: the same inputs give
the same numbers to the last bit whatever order they were given or evaluated in (``jobs``), and the
numbers pandas gave on a table in that order.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from lorisnb.core.pipeline.model import SCENE_COLUMNS, ResultFile
from lorisnb.core.trajectory.frames import SCENES
from lorisnb.core.trajectory.poses import time_spans
from lorisnb.errors import EvaluationError, ValidationError

if TYPE_CHECKING:
    import pandas as pd

DURATION_COLUMNS = ["scene", "seq", "gt_start", "gt_end", "gt_duration"]
#: The columns of a per-sequence table the aggregate reads.
USED = ["seq", "file", "matched", "c_matched", "correct_time", "track_time", "cs_r", "c_ate_rmse", "ate_rmse"]
Columns = Mapping[str, np.ndarray]


def durations_table(groundtruths: Mapping[str, ResultFile]) -> pd.DataFrame:
    """Ground-truth span of every sequence of each scene: first and last stamp and duration,
    seconds. ``groundtruths`` maps scene -> its ground-truth file."""
    return spans_table({scene: time_spans(gt.sequences) for scene, gt in groundtruths.items()})


def spans_columns(spans: Mapping[str, Mapping[int, tuple[float, float]]]) -> dict[str, np.ndarray]:
    """:data:`DURATION_COLUMNS` as numpy columns from the spans: scene -> sequence -> (first,
    last stamp, seconds)."""
    rows = [(scene, s, start, end) for scene, by_seq in spans.items() for s, (start, end) in by_seq.items()]
    start = np.array([r[2] for r in rows], float)
    end = np.array([r[3] for r in rows], float)
    return dict(
        scene=np.array([r[0] for r in rows], object), seq=np.array([r[1] for r in rows], np.int64),
        gt_start=start, gt_end=end, gt_duration=end - start,
    )  # fmt: skip


def spans_table(spans: Mapping[str, Mapping[int, tuple[float, float]]]) -> pd.DataFrame:
    """:func:`durations_table` from the spans alone: scene -> sequence -> (first, last stamp, seconds)."""
    import pandas as pd

    if not any(spans.values()):
        return pd.DataFrame(columns=DURATION_COLUMNS)
    return pd.DataFrame(spans_columns(spans), columns=DURATION_COLUMNS)


def aggregate_scenes(sequences: pd.DataFrame, durations: pd.DataFrame) -> pd.DataFrame:
    """Per algorithm and scene, as in the paper's Fig. 2 and Fig. 3:

    - ``cr``: sum of correct time / sum of the ground-truth durations of *all* the scene's
      sequences (a sequence the algorithm has no result for counts as not tracked);
    - ``cr_t``: sum of correct time / sum of tracked time (t_max - t0);
    - ``c_ate_rmse``: mean of per-sequence C-ATE RMSE weighted by their correct-pose counts (the
      paper's figure value); ``c_ate_rmse_pooled``: RMSE over all correct poses of the scene;
    - ``ate_rmse``: the same weighted mean of ATE RMSE over matched poses (Fig. 2's value);
    - ``cs_r``: the scene's CS-R, :func:`scene_mean` over *all* the scene's sequences, a sequence
      without output counting as a failed run (CS-R 0), as ``compare``, the report leaderboard and
      ``diff`` count it (:func:`lorisnb.core.lifelong.coverage.complete`);
    - ``cs_r_with_output``: mean CS-R over the sequences with output only (how quickly the
      algorithm re-localized where it ran; not the scene value).

    Args:
        sequences: a per-sequence table (:func:`lorisnb.core.lifelong.scoring.score` or a sweep).
        durations: :func:`durations_table` of the scenes in ``sequences``.

    Rows are grouped by ``suite``, ``algorithm``, ``scene`` and the thresholds (and ``eps_value``
    and ``trial`` where the table has them): :func:`aggregate_columns` on the table's columns
    (text columns factorized by pandas, as fast as its ``groupby``).
    """
    import pandas as pd

    _check_tables(sequences, durations)
    if sequences.empty:
        return pd.DataFrame(columns=SCENE_COLUMNS)
    columns: dict[str, Any] = {}
    for c in dict.fromkeys(KEYS + EXTRA_KEYS + USED):
        if c not in sequences.columns:
            continue
        col = sequences[c]
        if c in USED and c not in ("file", "seq"):
            columns[c] = col.to_numpy()
        else:  # a key: codes by pandas' hash table
            codes, uniques = pd.factorize(col, use_na_sentinel=False)
            columns[c] = Labels(np.asarray(codes, np.int64), np.asarray(uniques))
    out = aggregate_columns(columns, {c: durations[c].to_numpy() for c in ("scene", "seq", "gt_duration")})
    return pd.DataFrame(out)


def _check_tables(sequences: Any, durations: Any) -> None:
    """The two tables of :func:`aggregate_scenes` are DataFrames with the columns it reads (swapped,
    None or another table: a ValidationError saying what to pass)."""
    import pandas as pd

    for name, table, need, made_by in (
        ("sequences", sequences, [*KEYS, *USED], "Evaluation.sequences(), lorisnb.score or a sweep"),
        ("durations", durations, ["scene", "seq", "gt_duration"], "Evaluation.durations() or durations_table"),
    ):
        if not isinstance(table, pd.DataFrame):
            raise ValidationError(
                f"aggregate_scenes {name}: expected a DataFrame ({made_by}), got {type(table).__name__}"
            )
        absent = [c for c in need if c not in table.columns]
        if absent and not (name == "sequences" and table.empty and len(table.columns) == 0):
            raise ValidationError(
                f"aggregate_scenes {name}: no column {', '.join(absent[:4])}{', ...' if len(absent) > 4 else ''}; "
                f"expected the table of {made_by} (aggregate_scenes(sequences, durations), in that order)"
            )


def _check_durations(labels: Mapping[str, Labels], gt_scene: np.ndarray, gt_seq: np.ndarray) -> None:
    """Each (scene, sequence) once in the durations and every one of the table among them: a
    sequence missing gave a scene's CR over too short a duration, a repeated row over twice it."""
    pairs = list(zip(gt_scene.tolist(), np.asarray(gt_seq).tolist(), strict=True))
    held = set(pairs)
    if len(held) < len(pairs):
        counts: dict[tuple[Any, Any], int] = {}
        for pair in pairs:
            counts[pair] = counts.get(pair, 0) + 1
        again = sorted(f"{a}-{b}" for (a, b), k in counts.items() if k > 1)
        raise ValidationError(
            f"durations: {len(pairs) - len(held)} repeated row(s) ({', '.join(again[:5])}); expected one row per "
            "scene and sequence (Evaluation.durations(), not several concatenated)"
        )
    scene, seq = labels["scene"], labels["seq"]
    _, first = _groups([scene.codes, seq.codes])  # each (scene, sequence) of the table once
    table = set(zip(_strings(scene.at(first)).tolist(), seq.at(first).tolist(), strict=True))
    missing = sorted(f"{a}-{b}" for a, b in table - held if a in set(gt_scene.tolist()))
    if missing:
        raise ValidationError(
            f"durations: no row for sequence(s) {', '.join(missing[:8])}{', ...' if len(missing) > 8 else ''} of the "
            "table; expected the duration of every sequence of its scenes (Evaluation.durations())"
        )


KEYS = ["suite", "algorithm", "scene", "eps", "phi", "delta", "tau"]
EXTRA_KEYS = ["eps_value", "trial"]  # a sweep: eps as given; trials


@dataclass(frozen=True)
class Labels:
    """A column as integer codes (one per row) into its distinct values."""

    codes: np.ndarray
    uniques: np.ndarray

    @classmethod
    def of(cls, values: Any) -> Labels:
        """Codes of a column's values (equal values one code, every NaN one code, as
        ``groupby(dropna=False)``): numbers by sorting, other values by a dict, in the order they
        first appear."""
        if isinstance(values, Labels):
            return values
        v = np.asarray(values)
        if v.dtype.kind in "biuf":
            uniques, inverse = np.unique(v, return_inverse=True)
            return cls(inverse.reshape(-1).astype(np.int64), uniques)
        seen: dict[Any, int] = {}
        nan = object()
        codes = np.fromiter(
            (seen.setdefault(x if x == x else nan, len(seen)) for x in v.tolist()), np.int64, count=v.size
        )  # one dict lookup per row: the labels of a table, not poses
        uniques = np.empty(len(seen), object)
        uniques[:] = [np.nan if k is nan else k for k in seen]
        return cls(codes, uniques)

    def at(self, rows: np.ndarray) -> np.ndarray:
        """The values of these rows."""
        return self.uniques[self.codes[rows]]


def aggregate_columns(sequences: Mapping[str, Any], durations: Columns) -> dict[str, np.ndarray]:
    """:func:`aggregate_scenes` on numpy columns: ``sequences`` holds the grouping keys and
    :data:`USED` of a per-sequence table (rows in its order; a key may be given as
    :class:`Labels`), ``durations`` the ``scene``, ``seq`` and ``gt_duration`` of
    :func:`spans_columns`. Returns :data:`SCENE_COLUMNS` (then the extra keys present), one row
    per group, sorted by suite, algorithm, scene (the paper's order) and trial."""
    keys = KEYS + [c for c in EXTRA_KEYS if c in sequences]
    labels = {k: Labels.of(sequences[k]) for k in [*keys, "seq", "file"]}
    scene_names = _strings(labels["scene"].uniques)
    gt_scene = _strings(durations["scene"])
    missing = sorted(set(scene_names.tolist()) - set(gt_scene.tolist()))
    if missing:
        raise EvaluationError(f"no ground-truth durations for scene(s) {', '.join(missing)}; pass their durations")
    _check_durations(labels, gt_scene, durations["seq"])
    by = _setting_keys(labels, keys)
    _refuse_duplicates(labels, by)
    group, first = _groups([labels[k].codes for k in by])
    m = len(first)
    out: dict[str, Any] = {k: labels[k].at(first) for k in keys}
    if "eps" not in by:  # the setting's eps in metres where its sequences share one, else NaN
        eps = labels["eps"].codes
        lo, hi = np.full(m, np.iinfo(np.int64).max), np.full(m, -1)
        np.minimum.at(lo, group, eps)
        np.maximum.at(hi, group, eps)
        out["eps"] = np.where(lo == hi, np.asarray(out["eps"], float), np.nan)
    out["sequences"] = np.bincount(group, minlength=m).astype(np.int64)
    rows = _Sorted(group, m, _within(labels))
    matched, c_matched = np.asarray(sequences["matched"]), np.asarray(sequences["c_matched"])
    out["sequences_with_output"] = np.bincount(group, weights=has_output(matched), minlength=m).astype(np.int64)
    for name in ("matched", "c_matched", "correct_time", "track_time"):
        out[name] = _sums(rows, group, np.asarray(sequences[name]))
    d_group, d_first = _groups([Labels.of(gt_scene).codes])
    total, _ = _kahan(_Sorted(d_group, len(d_first)), np.asarray(durations["gt_duration"], float))
    by_scene = dict(zip(gt_scene[d_first].tolist(), total.tolist(), strict=True))
    count = dict(zip(gt_scene[d_first].tolist(), np.bincount(d_group).tolist(), strict=True))
    c_ate, ate = np.asarray(sequences["c_ate_rmse"], float), np.asarray(sequences["ate_rmse"], float)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        c_sq = _kahan(rows, np.where(c_matched > 0, c_ate**2 * c_matched, 0.0))[0]
        c_w = _kahan(rows, np.where(c_matched > 0, c_ate * c_matched, 0.0))[0]
        a_w = _kahan(rows, np.where(matched > 0, ate * matched, 0.0))[0]
        cs_sum, _ = _kahan(rows, np.asarray(sequences["cs_r"], float))
        g_scene = scene_names[labels["scene"].codes[first]]
        out["scene_sequences"] = np.array([count[s] for s in g_scene.tolist()], np.int64)  # one per group
        out["scene_duration"] = np.array([by_scene[s] for s in g_scene.tolist()], float)
        m_c, m_a = out["c_matched"], out["matched"]
        out["cr"] = scene_mean(out["correct_time"], out["scene_duration"])
        out["cr_t"] = scene_mean(out["correct_time"], out["track_time"])
        out["c_ate_rmse"] = scene_mean(c_w, m_c)
        out["c_ate_rmse_pooled"] = np.where(m_c > 0, np.sqrt(c_sq / m_c), np.nan)
        out["ate_rmse"] = scene_mean(a_w, m_a)
        out["cs_r"] = scene_mean(cs_sum, out["scene_sequences"])  # a sequence without output: CS-R 0
        out["cs_r_with_output"] = scene_mean(cs_sum, out["sequences_with_output"])  # failed rows' CS-R is 0
    order = _scene_order(out, "trial" in keys)
    return {c: np.asarray(out[c])[order] for c in SCENE_COLUMNS + keys[7:]}


def has_output(matched: Any) -> np.ndarray:
    """The one rule of "a sequence with output" (coverage in ``evaluate``, ``compare``, the report
    leaderboard and ``diff``; ``cs_r_with_output``): a row with at least one pose matched to the
    ground truth. A row with none (an empty file, a declared failed run, no pose inside the ground
    truth's span) is a failed run: it scores 0, as a sequence without a row does (paper, Sec. IV)."""
    return np.asarray(matched, float) > 0


def scene_mean(weighted_sum: Any, total_weight: Any) -> np.ndarray:
    """A scene value: the sum over its sequences of value x weight divided by the total weight of
    *all* the scene's sequences, NaN where that weight is 0. The one definition behind every scene
    value (:func:`aggregate_columns` for ``evaluate`` and ``Evaluation.scenes``,
    :func:`lorisnb.core.stats.inference.scene_means` for ``compare``, the report leaderboard and ``diff``).
    Weights (:data:`lorisnb.core.stats.inference.WEIGHTS`): CR ground-truth duration (paper Eq. 2: correct
    time over the scene's ground-truth time), CR-T tracked time (Eq. 3), C-ATE correct poses, CS-R
    1 per sequence (Eq. 4 averaged over the scene). A sequence without output is a failed run: value
    0 with its whole weight (its duration for CR, 1 for CS-R; tracked time and correct poses 0)."""
    s, w = np.asarray(weighted_sum, float), np.asarray(total_weight, float)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(w > 0, s / np.where(w > 0, w, 1.0), np.nan)


def _strings(values: Any) -> np.ndarray:
    """Values as Python strings in an object array (as ``astype(str)`` gives them)."""
    return np.array([str(v) for v in np.asarray(values, object).tolist()], object)


def _groups(codes: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Group number of every row by its codes in each column (groups numbered in the order they
    first appear, as ``groupby(sort=False)``), and the first row of each group."""
    code, size = codes[0], int(codes[0].max()) + 1 if codes[0].size else 1
    for more in codes[1:]:
        k = int(more.max()) + 1 if more.size else 1
        if size * k >= 2**62:  # the combined code would not fit: number the combinations so far
            _, code = np.unique(code, return_inverse=True)
            code, size = code.reshape(-1), int(code.max()) + 1
        code, size = code * k + more, size * k
    _, first, inverse = np.unique(code, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    return rank[inverse.reshape(-1)], first[order]


def _within(labels: Mapping[str, Labels]) -> list[np.ndarray]:
    """The order of the rows within a group that the sums follow: by sequence number, then by file
    name, so a scene's sums do not depend on the order of the table's rows (the order the inputs
    were given in, or their jobs finished in: they moved the last bit of a weighted mean); a group
    holds each sequence once (:func:`_refuse_duplicates`), so the order is complete. The bundled
    results given sorted, as a folder is listed, give the numbers their row order gave."""
    return [_rank(labels["seq"].uniques)[labels["seq"].codes],
            _rank(labels["file"].uniques, text=True)[labels["file"].codes]]  # fmt: skip


def _rank(values: np.ndarray, text: bool = False) -> np.ndarray:
    """The rank of each distinct value in sorted order: numbers by value (NaN last), else as text."""
    v = np.asarray(values)
    if not text and v.dtype.kind not in "biuf":
        try:
            v = np.asarray(v.tolist(), float)  # numbers held as objects (a pandas column's uniques)
        except (TypeError, ValueError):
            text = True
    if text:
        v = np.array(_strings(v).tolist(), dtype=str)
    return np.unique(v, return_inverse=True)[1].reshape(-1).astype(np.int64)


class _Sorted:
    """Rows sorted by group and each row's place within its group, shared by the sums: within a
    group in the order of the ``within`` keys (the first most significant), else in row order."""

    def __init__(self, group: np.ndarray, m: int, within: list[np.ndarray] | None = None) -> None:
        keys = [*(within or [])[::-1], group]  # lexsort: the last key most significant; stable
        self.m, self.order = m, np.lexsort(keys) if within else np.argsort(group, kind="stable")
        self.group = group[self.order]
        self.rank = np.arange(group.size) - np.searchsorted(self.group, np.arange(m))[self.group]


def _kahan(rows: _Sorted, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per group: the sum of its non-NaN values, compensated in row order exactly as pandas'
    ``group_sum`` and ``group_mean`` sum them, and how many there were. Vectorized over the
    groups, one step per row of the largest group (a few sequences per scene)."""
    g, v, m = rows.group, values[rows.order], rows.m
    total, comp, nobs = np.zeros(m), np.zeros(m), np.zeros(m, np.int64)
    for r in range(int(rows.rank.max()) + 1 if rows.rank.size else 0):
        at = np.flatnonzero(rows.rank == r)
        at = at[~np.isnan(v[at])]
        lab, val = g[at], v[at]
        y = val - comp[lab]
        t = total[lab] + y
        c = t - total[lab] - y
        comp[lab] = np.where(np.isfinite(c), c, 0.0)  # pandas: an infinite value leaves no compensation
        total[lab] = t
        nobs[lab] += 1
    return total, nobs


def _sums(rows: _Sorted, group: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Per-group sums: exact for integers, compensated (:func:`_kahan`) for floats."""
    if values.dtype.kind in "biu":
        out = np.zeros(rows.m, np.int64)
        np.add.at(out, group, values.astype(np.int64))
        return out
    return _kahan(rows, values.astype(float))[0]


def _scene_order(out: Mapping[str, np.ndarray], trials: bool) -> np.ndarray:
    """Row order: suite, algorithm (as text), scene in the paper's order (others last), trial;
    ties kept in the order the groups appeared (a stable sort, as pandas' ``sort_values``)."""
    rank = {s: i for i, s in enumerate(SCENES)}
    scene = np.array([rank.get(s, len(SCENES)) for s in _strings(out["scene"]).tolist()], np.int64)
    keys = [np.asarray(_strings(out["suite"]), str), np.asarray(_strings(out["algorithm"]), str), scene]
    if trials:
        keys.append(np.asarray(out["trial"]))
    return np.lexsort(keys[::-1])


def _setting_keys(labels: Mapping[str, Labels], keys: list[str]) -> list[str]:
    """The keys of a scene group: suite, algorithm, scene, trial and the threshold setting. Of eps
    the setting is the value as given (a sweep's ``eps_value``) where the table has it, else eps in
    metres, unless that is each sequence's own (``relative:F`` eps, a fraction of each sequence's
    size): a table whose sequences are each there once without it is one setting, whose scene
    rows sum all its sequences (eps NaN where they differ)."""
    if "eps_value" in keys:
        return [k for k in keys if k != "eps"]
    without = [k for k in keys if k != "eps"]
    group, _ = _groups([labels[k].codes for k in [*without, "seq"]])
    return without if (np.bincount(group) < 2).all() else keys


def _refuse_duplicates(labels: Mapping[str, Labels], keys: list[str]) -> None:
    """Two rows of one group for the same sequence: an error naming them."""
    group, _ = _groups([labels[k].codes for k in [*keys, "seq"]])
    sizes = np.bincount(group)
    if (sizes < 2).all():
        return
    dup = np.flatnonzero(sizes[group] > 1)
    d = dup[:1]
    same = dup[
        (labels["algorithm"].codes[dup] == labels["algorithm"].codes[d])
        & (labels["scene"].codes[dup] == labels["scene"].codes[d])
        & (labels["seq"].codes[dup] == labels["seq"].codes[d])
    ]
    files = list(dict.fromkeys(str(f) for f in labels["file"].at(same).tolist()))
    algorithm, scene, seq = (labels[k].at(d)[0] for k in ("algorithm", "scene", "seq"))
    raise EvaluationError(
        f"several results for {algorithm} {scene}-{seq} ({', '.join(files[:3])}); "
        "evaluate them in separate folders (suites)"
    )
