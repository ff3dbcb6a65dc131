"""docs/architecture.md walks ``--eps`` from the command line to the metric: the command line and
Python part at step 3. ``lorisnb evaluate`` runs the runner with ``keep_poses=False`` and
``statistics=False``, each worker scores the errors at the spec's eps where it computed them and lets
each pose's errors go, and the command reads those scores with ``Evaluation.sequence_rows``;
``ln.evaluate(..., eps=3)`` keeps the errors, so ``ev.sequences(eps=0.1)`` scores them again. The page
said that eps was not used before ``Evaluation.sequences()`` scored the errors, true of neither
path. On a real icra20 file (DS-SLAM cafe-1-1, its one sequence)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import EvaluationError
from lorisnb.tools.evaluation import runner

ROOT = Path(__file__).resolve().parents[2]
#: CR of DS-SLAM's cafe-1-1 at eps 3 m and 0.1 m (phi inf, delta 1 s, the openloris preset)
CR_EPS3, CR_EPS01 = 0.16339012524508534, 0.12585307037716797


@pytest.fixture
def cafe(icra20) -> Path:
    return icra20 / "per-seq" / "ds-slam" / "cafe-1-1.txt"


def test_the_command_line_scores_eps_in_the_workers_and_lets_the_poses_go(cafe, data, monkeypatch, capsys):
    seen = {}

    def evaluate(*args, **kw):
        seen["kw"] = kw
        seen["ev"] = ev = real(*args, **kw)
        rows = ev.sequence_rows
        monkeypatch.setattr(ev, "sequence_rows", lambda *a, **k: seen.setdefault("read", rows(*a, **k)))
        return ev

    real = runner.evaluate
    monkeypatch.setattr(runner, "evaluate", evaluate)
    code = main(["evaluate", "--data", str(data.root), "--eps", "3", "--no-progress", str(cafe)])
    out = capsys.readouterr().out
    assert code == 0
    assert seen["kw"]["statistics"] is False and seen["kw"]["keep_poses"] is False
    ev = seen["ev"]
    assert ev.poses_let_go()  # scores_only: the per-pose errors stayed in the worker
    assert [r["cr"] for r in seen["read"]] == pytest.approx([CR_EPS3])  # the table printed: the workers' scores
    assert "0.1634" in out.split("per scene")[0]
    with pytest.raises(EvaluationError, match="let go"):
        ev.sequences(eps=0.1)  # no other setting: the errors are gone


def test_python_keeps_the_errors_and_scores_another_eps_without_reading_again(cafe, data):
    ev = ln.evaluate([cafe], eps=3, data_root=data.root)
    assert not ev.poses_let_go()
    assert ev.sequences()["cr"].tolist() == pytest.approx([CR_EPS3])
    assert ev.sequences(eps=0.1)["cr"].tolist() == pytest.approx([CR_EPS01])
    lean = ln.evaluate([cafe], eps=3, data_root=data.root, statistics=False, keep_poses=False)
    assert lean.sequence_rows(stats=False)[0]["cr"] == pytest.approx(CR_EPS3)
    with pytest.raises(EvaluationError, match="let go"):
        lean.sequences(eps=0.1)


def test_the_walk_says_where_the_two_paths_part():
    text = (ROOT / "docs" / "architecture.md").read_text()
    walk = text[text.index("## One option from the command line") :]
    step3 = walk[walk.index("3. **The evaluation**") : walk.index("4. **Scoring**")]
    assert "has not been used yet" not in walk
    for said in ("keep_poses=False", "statistics=False", "scores_only", "Evaluation.sequence_rows", "job.spec.eps"):
        assert said in step3, said
    assert re.search(r"\*\*In Python\*\*, `ln.evaluate\(\.\.\., eps=3\)` keeps the per-pose errors", step3)
