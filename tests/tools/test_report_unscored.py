"""Inputs the report did not score: index.html lists every one (path, status, reason) and counts
them as the terminal does; an algorithm whose only file in a scene failed ran once (trials 1)."""

from __future__ import annotations

import html
import re

import pandas as pd
import pytest
from helpers import write

from lorisnb.io.datasets.paths import find_data
from lorisnb.tools.decisions.runs import unscored_inputs
from lorisnb.tools.report.index import write_index
from lorisnb.tools.report.leaderboard import report_findings

PER_SEQ = "per-seq"


def _results(root, icra20):
    s = icra20 / PER_SEQ
    for name in ("cafe-1-1.txt", "cafe-1-2.txt"):
        write(root, f"algA/{name}", (s / "ds-slam" / name).read_bytes())
    for name in ("cafe_1_1_orbslam2-original.txt", "cafe_1_2_orbslam2-original.txt"):
        write(root, f"algB/{name}", (s / "orbslam2_rgbd" / name).read_bytes())
    shifted = [  # every stamp 1e6 s later: no overlap with the ground truth
        f"{float(line.split()[0]) + 1e6:.6f} {' '.join(line.split()[1:])}" if line[:1].isdigit() else line
        for line in (s / "ds-slam" / "market-1-1.txt").read_text().splitlines()
    ]
    write(root, "algA/market-1-1.txt", "\n".join(shifted) + "\n")
    text = (s / "orbslam2_rgbd" / "market_1_1_orbslam2-original.txt").read_text()
    write(root, "algB/market_1_9_orbslam2-original.txt", text.replace("seq: 1", "seq: 9", 1))  # no such sequence
    write(root, "algB/office_1_1.txt", (s / "orbslam2_rgbd" / "office_1_1_orbslam2-original.txt").read_bytes())
    return root


def test_every_unscored_input_is_listed_with_its_path_and_reason(tmp_path, icra20, data):
    source = _results(tmp_path / "res", icra20)
    f, ev, values = report_findings(source, find_data(data.root), {})
    run = tmp_path / "run"
    (run / "findings").mkdir(parents=True)
    failures = ev.failures_table()
    failures.to_csv(run / "findings" / "input_errors.csv", index=False)
    counted = unscored_inputs(run)  # what the terminal counts
    assert len(counted) == 2
    page = write_index(run, [], {}, findings=f, spec={}, failures=failures).read_text()
    assert "could not be evaluated or scored (2)" in page
    text = html.unescape(page)
    for file, reason in counted.items():
        assert file in text and reason in text  # the whole path and the whole reason
    assert "not scored" in text and "no estimate stamp falls inside" in text
    skipped = failures[~failures["status"].isin(["failed", "not scored"])]
    for file in skipped["file"]:  # skipped on purpose (a scene without ground truth): listed apart, with its path
        assert str(file) in text
    # the leaderboard: algB's only market file failed, so it ran once there, as compare counts it
    board = f.board.set_index(["scene", "algorithm"])
    assert board.loc[("market", "algB"), "trials"] == 1 and pd.api.types.is_integer_dtype(f.board["trials"])
    assert len(skipped) == 1 and not re.search(r"<td>nan</td>", page)


def test_a_scene_filter_without_ground_truth_is_refused_before_anything_runs(tmp_path, icra20, data, monkeypatch,
                                                                             capsys):  # fmt: skip
    """-p scenes naming only a scene the results hold but the data has no ground truth for (office):
    nothing could be scored, so the report refuses it up front (exit 2), saying why."""
    from lorisnb.cli import main
    from lorisnb.tools.report import build as report

    source = _results(tmp_path / "res", icra20)
    started: list = []
    monkeypatch.setattr(report, "run_notebook", lambda name, *a, **k: started.append(name) or report.NotebookRun(name))
    out = tmp_path / "run"
    args = ["report", "--results", str(source), "--out", str(out), "--data", str(data.root), "--no-progress"]
    assert main([*args, "-p", "scenes", '["office"]']) == 2
    err = capsys.readouterr().err
    assert "office" in err and "no ground truth" in err and "cafe" in err
    assert not started and sorted(p.name for p in tmp_path.iterdir()) == ["res"]
    # a filter keeping one scene with ground truth runs (office is skipped as usual)
    assert main([*args, "-p", "scenes", '["office", "cafe"]', "--notebooks", "per_sequence_benchmark"]) in (0, 1)
    assert started and (out / "index.html").exists()


def test_the_per_sequence_values_show_every_sequence_with_ground_truth(tmp_path, icra20, data):
    """home has 5 sequences with ground truth; the results cover seq 1 only: the table behind the
    leaderboard (coverage 1/5) has a column for each of the 5, the missing ones marked 'no output'."""
    from report_fixtures import trial_results

    source = trial_results(tmp_path / "mine", icra20)
    f, ev, _ = report_findings(source, find_data(data.root), {})
    run = tmp_path / "run"
    run.mkdir()
    page = write_index(run, [], {}, findings=f, spec={}, per_sequence=ev.sequences(), expected=ev.spans()).read_text()
    home = page.split("<h4 id='seq--home'>")[1].split("</table>")[0]
    assert [f"seq {k}" in home for k in range(1, 6)] == [True] * 5
    assert home.count("no output") == 2 * 4  # two algorithms, four sequences without output each
    cafe = page.split("<h4 id='seq--cafe'>")[1].split("</table>")[0]
    assert "no output" not in cafe and "seq 2" in cafe


@pytest.mark.slow
def test_compare_algorithms_reports_its_failed_inputs_as_the_other_notebooks(tmp_path, icra20, data):
    """compare_algorithms writes input_errors.csv through the session as the other notebooks do, so
    the report counts its failed inputs ('ok, N input file(s) failed or not scored') instead of a plain 'ok'."""
    from lorisnb.tools.report.notebooks import run_one

    source = _results(tmp_path / "res", icra20)
    write(source, "algA/cafe-1-3.txt", "scene: cafe\nseq: 1\nnot a pose line\n")  # a broken file
    run = run_one("compare_algorithms", tmp_path / "run", {"results_dir": str(source), "data_root": str(data.root),
                                                           "quick": True})  # fmt: skip
    assert run.status == "ok", run.error
    table = pd.read_csv(tmp_path / "run" / "compare_algorithms" / "input_errors.csv")
    assert run.input_errors == int(table["status"].isin(["failed", "not scored"]).sum()) >= 3
    assert any("cafe-1-3.txt" in f for f in table["file"])
