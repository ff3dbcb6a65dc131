"""A report run against its baseline (``lorisnb report --baseline DIR``): the newest earlier run in
DIR comparable with this one (:func:`lorisnb.tools.decisions.history.last_comparable`), ``diff``'s
verdict of this run against it (:mod:`lorisnb.core.stats.regression`), what changed (regressions,
improvements, trade-offs, new algorithms, the earlier runs passed over as not comparable, the
inputs this run could not score) and a trend figure of CR per scene over the last comparable runs.
Written into the run's ``findings/`` (``since_baseline.json``, ``trend_cr.svg``) for the front page,
which shows it offline like the rest."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from lorisnb.errors import ValidationError
from lorisnb.io.writers import naming
from lorisnb.tools.decisions.diff import diff_tables
from lorisnb.tools.decisions.history import comparability, earlier_runs, history_table, last_comparable, plot_history
from lorisnb.tools.decisions.runs import Run, load_run
from lorisnb.tools.report.provenance import sha256

#: How many comparable runs (this one included) the trend figure shows.
TREND_RUNS = 10


def baseline_files(base: Run, folder: str | os.PathLike[str]) -> dict[str, str]:
    """The files the verdict against the baseline ``base`` read (:meth:`Run.sources`), each by its
    path below the folder of earlier runs ``folder`` (``/``-separated) -> SHA-256: the report's
    run.json records them below its ``{baseline}`` root, so that ``verify --root baseline DIR``
    tells a baseline edited, replaced or removed since the verdict."""
    top = os.path.abspath(folder)
    out = {}
    for f in base.sources():
        rel = os.path.relpath(os.path.abspath(f), top)
        if rel != os.pardir and not rel.startswith(os.pardir + os.sep):  # below the folder (always, as listed)
            out[Path(rel).as_posix()] = sha256(f)
    return out


def since_baseline(run_dir: Path, folder: str | os.PathLike[str], name: str | None = None, trend: int = TREND_RUNS
                   ) -> dict[str, Any]:  # fmt: skip
    """What changed since the baseline, for a run folder that holds ``run.json`` and its findings;
    written as ``findings/since_baseline.json`` (and the trend as ``findings/trend_cr.svg``).
    ``name``: the run's name where its folder is still a temporary one."""
    this = load_run(run_dir)
    if name:
        this.path = run_dir.parent / name
    try:
        base, fits = last_comparable(folder, this)
    except ValidationError as exc:  # none comparable (a new lorisnb, spec or ground truth), or no run yet: this
        # run is written all the same, saying so, and starts a new series (it was thrown away, every night)
        if not Path(folder).is_dir():
            raise
        out: dict[str, Any] = dict(baseline=None, no_baseline=str(exc), verdict=None, passed_over=[],
                                   failed_inputs=sorted(this.unscored), trend=None)  # fmt: skip
        findings = run_dir / "findings"
        findings.mkdir(exist_ok=True)
        with naming(findings / "since_baseline.json"):  # a full disk names the file
            (findings / "since_baseline.json").write_text(
                json.dumps(out, indent=2, default=str) + "\n", encoding="utf-8"
            )
        return out
    unread: list[tuple[str, str]] = []
    passed = [dict(run=r.name, why="; ".join(comparability(r, this))) for r in earlier_runs(folder, unread)
              if r.path.resolve() != Path(this.path).resolve() and comparability(r, this)]  # fmt: skip
    passed += [dict(run=name, why=f"not read as a run: {why}") for name, why in unread]
    known = [r.expected for r in (base, this) if r.expected is not None]
    import pandas as pd

    d = diff_tables(base.table, this.table, names=(f"baseline {base.name}", "this run"),
                    expected=pd.concat(known, ignore_index=True) if known else None)  # fmt: skip
    new_algs = sorted(set(this.table["algorithm"]) - set(base.table["algorithm"]))
    out = dict(baseline=base.name, baseline_label=base.label, baseline_created=base.created.isoformat()
               if base.created else None, verdict=d.verdict, new_algorithms=new_algs, passed_over=passed,
               failed_inputs=sorted(this.unscored), trend=None, warnings=this.warnings,
               baseline_files=baseline_files(base, folder))  # fmt: skip
    runs = [*fits[-(trend - 1) :], this]
    h, _ = history_table(runs, ["cr"])
    fig = plot_history(h, "cr")
    findings = run_dir / "findings"
    findings.mkdir(exist_ok=True)
    with naming(findings / "trend_cr.svg"):
        fig.savefig(findings / "trend_cr.svg", format="svg", metadata={"Date": None})
    import matplotlib.pyplot as plt

    plt.close(fig)
    out["trend"] = "findings/trend_cr.svg"
    with naming(findings / "since_baseline.json"):
        (findings / "since_baseline.json").write_text(json.dumps(out, indent=2, default=str) + "\n", encoding="utf-8")
    return out
