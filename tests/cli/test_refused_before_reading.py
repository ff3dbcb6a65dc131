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
