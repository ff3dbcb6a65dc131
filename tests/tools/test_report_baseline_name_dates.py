"""``report --baseline DIR`` chooses its baseline by time as ``history`` orders runs; where the
earlier runs' names hold dates in another order than their times (a copy reset them), it warns
naming the run taken as the baseline, as ``diff --baseline last-comparable`` and ``history`` do
(it said nothing), and ``findings/since_baseline.json`` keeps the warning."""

from __future__ import annotations

import json
import os

from test_portable_runs import fake_notebook, lab

from lorisnb.cli import main


def test_report_baseline_warns_of_dates_in_names_against_times(tmp_path, data, icra20, monkeypatch, capsys):
    import lorisnb.tools.report.build as report

    here = lab(tmp_path / "lab", data, icra20)
    monkeypatch.setattr(report, "run_notebook", fake_notebook)
    night = ["report", "--results", here / "res", "--data", here / "data", "--notebooks", "compare_algorithms",
             "--no-progress", "--out"]  # fmt: skip
    nightly = here / "nightly"
    for k, name in enumerate(("2026-01-05", "2026-01-04")):  # 2026-01-05 copied: its run.json older
        assert main([*map(str, night), str(nightly / name)]) == 0
        meta = json.loads((nightly / name / "run.json").read_text())
        meta["created"] = None  # ordered by run.json's modification time
        (nightly / name / "run.json").write_text(json.dumps(meta))
        os.utime(nightly / name / "run.json", (1.7e9 + 1000 * k, 1.7e9 + 1000 * k))
    capsys.readouterr()
    rc = main([*map(str, night[:-1]), "--baseline", str(nightly), "--gate", "--out", str(tmp_path / "tonight")])
    err = " ".join(capsys.readouterr().err.split())
    assert rc == 0 and "gate: ok since the baseline 2026-01-04" in err, err
    assert (
        "warning: runs ordered by modification time contradict the dates in their names: 2026-01-05 (named "
        "2026-01-05) is ordered before 2026-01-04 (named 2026-01-04), so 2026-01-04 is taken as the baseline"
    ) in err
    since = json.loads((tmp_path / "tonight" / "findings" / "since_baseline.json").read_text())
    assert since["baseline"] == "2026-01-04" and "contradict the dates" in since["warnings"][0]
    page = (tmp_path / "tonight" / "index.html").read_text()
    assert (
        "Warning: runs ordered by modification time contradict the dates in their names" in page
    )  # the front page too
