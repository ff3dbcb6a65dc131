"""An option the spec refuses is refused before any input is read (the reference's "exit 2: nothing
is read or written then"): ``--kitti-plot`` without ``--conventions kitti`` was refused only after
every input had been read and evaluated (2 s of work on the icra20 tree)."""

from __future__ import annotations

import lorisnb.tools.evaluation.runner as runner
from lorisnb.cli import main


def test_kitti_plot_without_the_kitti_conventions_is_refused_before_any_input_is_read(
    icra20, tmp_path, capsys, monkeypatch
):
    read = []
    monkeypatch.setattr(runner, "evaluate", lambda *a, **k: read.append(a) or (_ for _ in ()).throw(AssertionError))
    out = tmp_path / "plots"
    rc = main(["evaluate", str(icra20 / "per-seq" / "odom"), "--kitti-plot", str(out), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and "--kitti-plot: the KITTI metric's plot, only with --conventions kitti" in err, err
    assert read == [] and not out.exists()
    assert "conventions:" not in err  # the evaluation never started


def test_a_simulated_value_given_with_results_is_refused_before_the_report_runs(icra20, tmp_path, capsys):
    """``report --results DIR -p sim_scene home``: compare_algorithms' simulated section is off on
    one's own results, so the value cannot apply; it was refused inside the notebook, after the
    report's own evaluation had run."""
    out = tmp_path / "run"
    rc = main(["report", "--results", str(icra20 / "per-seq"), "--notebooks", "compare_algorithms", "-p", "sim_scene",
               "home", "--out", str(out), "--no-progress"])  # fmt: skip
    err = capsys.readouterr().err
    assert rc == 2 and "-p sim_scene: only applies to the simulated section" in err and "results_dir is given" in err
    assert not out.exists() and not list(tmp_path.glob(".run.partial-*"))
