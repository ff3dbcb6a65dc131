"""evo's pose relations as columns of the sequence table (``--relation R``, evo's ``-r R``): per
sequence, evo's statistics of the APE and of the RPE by relation R (:mod:`lorisnb.core.metrics.relations`),
on the aligned matched poses and the RPE pairs of the table."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np
import pandas as pd

from lorisnb.core.lifelong.scoring import as_files
from lorisnb.core.metrics.relations import (
    STATISTICS,
    ape_relation,
    check_relation,
    error_statistics,
    rpe_relation,
    unit_refusal,
)
from lorisnb.core.metrics.relations import change_unit as to_unit
from lorisnb.core.pipeline.model import FileErrors
from lorisnb.errors import ValidationError

#: Columns :func:`relation_columns` adds.
RELATION_COLUMNS = ["relation", *(f"ape_{s}" for s in STATISTICS), *(f"rpe_{s}" for s in STATISTICS)]


def relation_columns(
    errors: FileErrors | Iterable[FileErrors], relation: str, change_unit: str | None = None, **rpe: Any
) -> pd.DataFrame:
    """One row per sequence (in the order of :func:`lorisnb.core.lifelong.scoring.score`): ``relation`` and
    evo's statistics of the APE (``ape_*``) and of the RPE (``rpe_*``) by ``relation``, in ``change_unit``
    (evo's ``--change_unit``; None: the relation's own unit); ``rpe``:
    ``rpe_delta``, ``rpe_unit``, ``rpe_pairs``, ``rpe_all_pairs``, ``rpe_tolerance`` (the table's)."""
    relation = check_relation(relation)  # also where no sequence has a matched pose
    if change_unit is not None and unit_refusal(relation, change_unit) is not None:
        raise ValidationError(str(unit_refusal(relation, change_unit)))
    rows = []
    setting = (float(rpe.get("rpe_delta", 1.0)), str(rpe.get("rpe_unit", "s")), str(rpe.get("rpe_pairs", "reference")),
               rpe.get("rpe_all_pairs"), float(rpe.get("rpe_tolerance", 0.1)))  # fmt: skip
    for f in as_files(errors):  # per file and sequence, never per pose
        for e in f.sequences:
            row: dict[str, Any] = {"relation": relation}
            if e.matched and e.gt_quaternions is not None and e.est_quaternions is not None:
                ape = ape_relation(e.gt_positions, e.gt_quaternions, e.est_positions, e.est_quaternions, relation)
                i, j, _, _ = e.rpe(*setting)
                rel = rpe_relation(e.gt_positions, e.gt_quaternions, e.est_positions, e.est_quaternions, i, j, relation)
            else:
                ape = rel = np.zeros(0)
            ape, rel = to_unit(ape, relation, change_unit), to_unit(rel, relation, change_unit)
            row.update({f"ape_{k}": v for k, v in error_statistics(ape).items()})
            row.update({f"rpe_{k}": v for k, v in error_statistics(rel).items()})
            rows.append(row)
    return pd.DataFrame(rows, columns=RELATION_COLUMNS)


def repeated_relation_columns(
    errors: FileErrors | Iterable[FileErrors], relation: str, times: int, change_unit: str | None = None, **rpe: Any
) -> dict[str, np.ndarray]:
    """:func:`relation_columns` as arrays, each sequence's value repeated ``times`` times (the
    settings of a sweep, whose rows run sequence by sequence): threshold-free, as in ``evaluate``."""
    rel = relation_columns(errors, relation, change_unit, **rpe)
    return {c: np.repeat(rel[c].to_numpy(), times) for c in rel.columns}
