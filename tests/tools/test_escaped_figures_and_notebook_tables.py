"""A name with a control character (a folder ``orb`` + ESC) reaches no figure lorisnb draws and no
table a notebook shows as the raw character: the figure functions draw it as the terminal shows it
(``orb\\x1b``), a notebook's tables (HTML and text) and prose show it escaped, and the tables the
Python API returns and the CSV files keep the name whole."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from matplotlib.text import Text

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.lifelong.sweep import rank_stability, sweep, sweep_scenes
from lorisnb.tools.figures.kitti import kitti_length_figure
from lorisnb.tools.figures.plotting import (
    plot_cr_heatmaps,
    plot_metric_vs_threshold,
    plot_normalized_accuracy,
    plot_rank_stability,
    plot_timeline,
    plot_trajectories,
)
from lorisnb.tools.figures.trials import plot_trials
from lorisnb.tools.notebook.output_gaps import delta_gain
from lorisnb.tools.notebook.prose import tracking_and_accuracy
from lorisnb.tools.notebook.start import figure_png, show_tables_escaped, shown_table

ESC = "orb\x1b"
SHOWN = "orb\\x1b"
FILES = ["cafe_1_1_orbslam2-original.txt", "cafe_1_2_orbslam2-original.txt"]


def _texts(fig) -> list[str]:
    return [t.get_text() for t in fig.findobj(Text)]


def _clean(fig) -> list[str]:
    texts = _texts(fig)
    assert all(t.replace("\n", "").isprintable() for t in texts), [t for t in texts if not t.isprintable()]
    return texts


@pytest.fixture(scope="module")
def ev(icra20, data, tmp_path_factory):
    """icra20's orbslam2_rgbd cafe files under a folder named orb + ESC, and vins_mono's under vins."""
    root = tmp_path_factory.mktemp("names") / "res"
    for alg, src in ((ESC, "orbslam2_rgbd"), ("vins", "vins_mono_color_imu_with_loop")):
        (root / alg).mkdir(parents=True)
        for f in sorted((icra20 / "per-seq" / src).glob("cafe*")):
            shutil.copy(f, root / alg / f.name)
    return ln.evaluate(root, data_root=data, progress=False)


def test_every_figure_draws_the_name_escaped(ev):
    assert ESC in set(ev.sequences()["algorithm"])  # the Python API's tables keep the name whole
    scenes = ev.scenes()
    fig = plot_timeline(ev.errors, ev.durations(), scenes, title="caller's title, a name in it: " + ESC)
    texts = _texts(fig)
    assert SHOWN in texts  # the row's name (a tick label)
    figure_png(fig)  # rendering escapes what is still not printable (a caller's title)
    assert "caller's title, a name in it: " + SHOWN in _clean(fig)
    orb = next(f for f in ev.errors if f.algorithm == ESC)
    assert any(t.startswith(SHOWN + ": ") for t in _clean(plot_trajectories(orb)))
    grid = sweep_scenes(sweep(ev.errors, [0.5, 1, 3], [10, 30], [1.0], [60.0]), ev.durations())
    assert SHOWN in _clean(plot_metric_vs_threshold(grid[grid["phi"] == 30], "eps"))  # the legend
    assert SHOWN in _clean(plot_cr_heatmaps(grid, "cafe"))  # a panel's title
    assert any(SHOWN in t for t in _clean(plot_trials(ev.sequences())))  # a tick label
    assert _clean(plot_rank_stability(rank_stability(grid[grid["phi"] == 30])))
    lengths = pd.DataFrame(dict(algorithm=[ESC] * 3, trial=0, file=["f\x1b.txt"] * 3, seq=[""] * 3,
                                length=[100.0, 200, 300], t_err=[1.0, 2, 3], r_err=[0.1, 0.2, 0.3], plotted=True))  # fmt: skip
    assert any(t.startswith(SHOWN + " (all)") for t in _clean(kitti_length_figure(lengths)))
    measures = pd.DataFrame(dict(dataset=["OpenLORIS"] * 2, group=[ESC, "b"], ate_pct_length=[1.0, 2.0]))
    published = pd.DataFrame(dict(dataset=["pub\x1b"], ate_pct_length=[1.5]))
    texts = _clean(plot_normalized_accuracy(measures, published))
    assert SHOWN in texts and "pub\\x1b (published)" in texts


def test_a_notebook_shows_tables_and_prose_escaped(ev):
    from IPython.core.interactiveshell import InteractiveShell

    table = ev.sequences()
    wide = table.pivot_table(index="algorithm", columns="seq", values="cr")  # a name as an index label
    shell = InteractiveShell.instance()
    try:
        show_tables_escaped()
        for shown in (table, wide, table["algorithm"]):
            out, _ = shell.display_formatter.format(shown)
            assert SHOWN in out["text/plain"] and "\x1b" not in json.dumps(out, ensure_ascii=False)
        html = shell.display_formatter.format(wide)[0]["text/html"]
        assert f"<th>{SHOWN}</th>" in html
    finally:
        InteractiveShell.clear_instance()
    assert ESC in set(table["algorithm"]) and ESC in wide.index  # the tables given keep the name whole
    assert list(shown_table(pd.DataFrame({"a\\b": ["x\\y", ESC]}, index=[ESC, "k"])).itertuples()) == [
        (SHOWN, "x\\\\y"),
        ("k", SHOWN),
    ]
    prose = tracking_and_accuracy(ev.scenes())
    assert f"`{SHOWN}`" in prose and "\x1b" not in prose
    _, _, text = delta_gain(ev.errors, ev.durations(), np.inf, np.inf, 1.0, 60.0, [1.0, 5.0])
    assert "\x1b" not in text


@pytest.mark.slow
def test_a_report_notebook_shows_no_control_character(tmp_path, icra20, data):
    res = tmp_path / "res" / ESC
    res.mkdir(parents=True)
    for f in FILES:
        shutil.copy(icra20 / "per-seq" / "orbslam2_rgbd" / f, res / f)
    out = tmp_path / "rep"
    rc = main(["report", "--out", str(out), "--results", str(tmp_path / "res"), "--data", str(data.root),
               "--notebooks", "per_sequence_benchmark", "--no-progress"])  # fmt: skip
    assert rc == 0
    page = next(Path(out).rglob("per_sequence_benchmark.html")).read_text(encoding="utf-8")
    assert "\x1b" not in page and SHOWN in page
    nb = next(Path(out).rglob("per_sequence_benchmark.ipynb")).read_text(encoding="utf-8")
    assert "\\u001b" not in nb and "\x1b" not in nb  # the outputs stored in the notebook too
    assert ESC in set(pd.read_csv(next(Path(out).rglob("sequences.csv")))["algorithm"])  # the data: whole
