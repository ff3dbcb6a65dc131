"""The report's parts that need no kernel: the leaderboard and its sentences on real results
(bundled, and a results folder with trials), the notebooks' order and problems, run.json and
``lorisnb verify``, and the offline HTML (no remote script, widgets made static, one-file copy)."""

from __future__ import annotations

import json
import shutil

import nbformat
import numpy as np
import pandas as pd
import pytest
from report_fixtures import trial_results

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import ValidationError
from lorisnb.tools.report.html import WIDGET_NOTE, export_html, single_file, static_widgets
from lorisnb.tools.report.leaderboard import BOARD_COLUMNS, findings
from lorisnb.tools.report.notebooks import available_notebooks, notebook_problem
from lorisnb.tools.report.provenance import KEYS, checksums, run_record, verify_run, write_run_json


@pytest.fixture(scope="module")
def per_seq(icra20):
    ev = ln.evaluate(icra20 / "per-seq", scale="auto")
    return ev, ev.sequences("paper", 30)


@pytest.mark.thorough
def test_leaderboard_on_the_bundled_results(per_seq):
    ev, table = per_seq
    f = findings(table, ev.durations())
    assert list(f.board.columns) == BOARD_COLUMNS
    assert set(f.board["scene"]) == {"cafe", "corridor", "home", "market"}  # office has no ground truth
    board = f.board.set_index(["scene", "algorithm"])
    # odom covers every cafe sequence: its CR with interval equals the paper's scene CR (aggregate_scenes)
    scenes = ev.scenes("paper", 30).set_index(["scene", "algorithm"])
    assert board.loc[("cafe", "odom"), "coverage"] == "2/2"
    assert board.loc[("cafe", "odom"), "value"] == pytest.approx(scenes.loc[("cafe", "odom"), "cr"], abs=1e-12)
    assert board.loc[("cafe", "dso"), "coverage"] == "1/2"  # dso has no cafe-1-2 output
    assert board.loc[("corridor", "vins_mono_fisheye_imu_with_loop"), "coverage"] == "1/5"
    finite = f.board.dropna(subset=["low", "high"])
    assert len(finite) > 0.8 * len(f.board)
    assert ((finite["low"] <= finite["value"] + 1e-12) & (finite["value"] <= finite["high"] + 1e-12)).all()
    # single runs on 2..5 sequences: no paired test reaches 0.05 (smallest p 2/2^n), so no scene separates
    assert (f.board["rank"] == 1).all()
    for (_suite, scene), text in f.sentences.items():
        assert text.startswith(f"In {scene}") and "cannot tell it apart" in text and "smallest possible p" in text
    assert "Output missing on some sequences: dso (1/2)" in f.sentences[("", "cafe")]
    assert "alpha 0.05" in f.test and "Holm" in f.test
    # the pairs' own correction: one Holm family over every pair of every scene (it said "within each scene")
    assert "within each scene" not in f.test and f"Holm over {len(f.pairs)} pair(s) of 4 scene(s)" in f.test
    for _, g in f.board.groupby(["suite", "scene"]):  # best value first within the rank
        assert g["value"].is_monotonic_decreasing


def test_leaderboard_with_trials(tmp_path, icra20):
    ev = ln.evaluate(trial_results(tmp_path / "mine", icra20))
    table = ev.sequences("paper", 30)
    f = findings(table, ev.durations())
    board = f.board.set_index(["scene", "algorithm"])
    assert (f.board["trials"] == 3).all()
    assert board.loc[("cafe", "orb"), "coverage"] == "2/2" and board.loc[("home", "orb"), "coverage"] == "1/5"
    # the scene value: each sequence's mean over trials, weighted by the sequence's duration
    g = table[(table["algorithm"] == "odom") & (table["scene"] == "cafe")]
    per_seq = g.groupby("seq").agg(cr=("cr", "mean"), w=("gt_duration", "mean"))
    assert board.loc[("cafe", "odom"), "value"] == pytest.approx(np.average(per_seq["cr"], weights=per_seq["w"]))
    assert "2 sequence(s) x up to 3 trials" in f.sentences[("", "cafe")]
    assert (
        "Output missing on some sequences: " in f.sentences[("", "home")] and "orb (1/5)" in f.sentences[("", "home")]
    )


def _nb(path, source="x = 1", params=True, kernel=True):
    nb = nbformat.v4.new_notebook()
    cell = nbformat.v4.new_code_cell("x = 1")
    if params:
        cell.metadata["tags"] = ["parameters"]
    nb.cells = [cell, nbformat.v4.new_code_cell(source)]
    if kernel:
        nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    nbformat.write(nb, path)
    return path


def test_notebooks_dir_order_and_problems(tmp_path):
    d = tmp_path / "nbs"
    d.mkdir()
    _nb(d / "zeta.ipynb")
    _nb(d / "metrics_primer.ipynb")  # named like a shipped notebook: first
    (d / "alpha.ipynb").write_text("{ not json")
    _nb(d / "no_kernel.ipynb", kernel=False)
    _nb(d / "no_params.ipynb", params=False)
    assert available_notebooks(d) == ["metrics_primer", "alpha", "no_kernel", "no_params", "zeta"]
    assert "invalid JSON" in notebook_problem(d / "alpha.ipynb")
    assert "no kernelspec" in notebook_problem(d / "no_kernel.ipynb")
    assert "no cell tagged 'parameters'" in notebook_problem(d / "no_params.ipynb")
    assert notebook_problem(d / "zeta.ipynb") is None
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(ValidationError, match="no .ipynb file"):
        available_notebooks(empty)


def test_empty_notebooks_dir_is_a_usage_error(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    rc = main(["report", "--notebooks-dir", str(tmp_path / "empty"), "--out", str(tmp_path / "run"), "--no-progress"])
    assert rc == 2 and "no .ipynb file" in capsys.readouterr().err
    assert not (tmp_path / "run").exists()


def test_run_json_and_verify(tmp_path, data, capsys):
    root = tmp_path / "data"
    shutil.copytree(data.root / "openloris-scene" / "groundtruth", root / "openloris-scene" / "groundtruth")
    gt = root / "openloris-scene" / "groundtruth" / "gt_cafe_1.txt"
    outside = tmp_path / "mine" / "orb" / "cafe.txt"
    outside.parent.mkdir(parents=True)
    outside.write_bytes((data.icra20 / "per-seq" / "orbslam2_rgbd" / "cafe_1_1_orbslam2-original.txt").read_bytes())
    inputs = checksums([gt, outside], root)
    assert set(inputs) == {"openloris-scene/groundtruth/gt_cafe_1.txt", str(outside.resolve())}
    assert inputs["openloris-scene/groundtruth/gt_cafe_1.txt"] == checksums([gt], None)[str(gt)]
    run = tmp_path / "run"
    run.mkdir()
    record = run_record(["lorisnb", "report"], {"description": "d", "values": {"eps": "paper"}}, root, inputs,
                        {"per_sequence_benchmark": "ok"})  # fmt: skip
    assert tuple(record) == (*KEYS, "input_roots") and record["lorisnb_version"] == ln.__version__
    write_run_json(run, record)
    assert json.loads((run / "run.json").read_text())["inputs"] == inputs
    assert main(["verify", str(run), "--data", str(root), "--results", str(outside.parent)]) == 0
    assert "all 2 input file(s) unchanged" in capsys.readouterr().err
    outside.write_text(outside.read_text().replace("seq: 1", "seq: 1\n# edited"))
    gt.unlink()
    problems = {("openloris-scene/groundtruth/gt_cafe_1.txt", "missing"), (str(outside.resolve()), "changed")}
    assert set(verify_run(run, {"data": root, "results": outside.parent})) == problems
    assert main(["verify", str(run), "--data", str(root), "--results", str(outside.parent)]) == 1
    out = capsys.readouterr()
    assert f"changed: {outside.resolve()}" in out.out and "missing: openloris-scene" in out.out
    assert main(["verify", str(tmp_path)]) == 2 and "no run.json" in capsys.readouterr().err


def test_static_widgets_and_offline_export(tmp_path):
    nb = nbformat.v4.new_notebook()
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    nb.metadata["widgets"] = {"application/vnd.jupyter.widget-state+json": {"state": {}}}
    view = "application/vnd.jupyter.widget-view+json"
    cell = nbformat.v4.new_code_cell("print('hidden code')")
    cell.outputs = [
        nbformat.v4.new_output("display_data", {view: {"model_id": "a"}, "text/plain": "evaluating:   0%|  | 0/9"}),
        nbformat.v4.new_output("display_data", {view: {"model_id": "b"}, "text/plain": "VBox(children=(...))"}),
        nbformat.v4.new_output("stream", text="a printed line\n"),
    ]
    nb.cells = [nbformat.v4.new_markdown_cell("# Title"), cell]
    static = static_widgets(nbformat.from_dict(json.loads(json.dumps(nb))))
    outs = static.cells[1].outputs
    assert len(outs) == 2 and outs[0]["data"] == {"text/plain": WIDGET_NOTE} and "widgets" not in static.metadata
    path = tmp_path / "nb" / "page.ipynb"
    path.parent.mkdir()
    nbformat.write(nb, path)
    page = export_html(path, css="../notebook.css").read_text()
    assert "<script src" not in page and "cdn" not in page.lower() and "require.js" not in page
    assert '<details class="lorisnb-code">' in page and "hidden code" in page and WIDGET_NOTE in page
    assert 'href="../notebook.css"' in page and "a printed line" in page
    # one exporter serves every page of a process: a second notebook's page holds its own cells and
    # style, and the first page exported again is the same, byte for byte
    other = tmp_path / "nb2" / "other.ipynb"
    other.parent.mkdir()
    nb2 = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("print('second notebook')")])
    nb2.metadata["kernelspec"] = nb.metadata["kernelspec"]
    nbformat.write(nb2, other)
    page2 = export_html(other).read_text()
    assert "second notebook" in page2 and "hidden code" not in page2 and "../notebook.css" not in page2
    assert "<title>other</title>" in page2 and "<title>page</title>" in page
    assert export_html(path, css="../notebook.css").read_text() == page


def test_single_file_inlines_images(tmp_path):
    (tmp_path / "nb").mkdir()
    png = b"\x89PNG\r\n\x1a\n" + b"0" * 32
    (tmp_path / "nb" / "fig.png").write_bytes(png)
    (tmp_path / "index.html").write_text(
        "<p><a href='nb/fig.png'><img src='nb/fig.png'></a> <a href='#x'>here</a> <a href='nb/page.html'>page</a></p>"
    )
    text = single_file(tmp_path / "index.html", tmp_path / "report.html").read_text()
    import base64

    assert f"data:image/png;base64,{base64.b64encode(png).decode()}" in text
    assert "src='nb/fig.png'" not in text and "href='nb/page.html'" not in text and "href='#x'" in text


def test_leaderboard_of_an_empty_table():
    f = findings(pd.DataFrame(), pd.DataFrame(columns=["scene", "seq"]))
    assert f.board.empty and f.sentences == {}


def test_a_run_folder_is_readable_and_records_its_provenance(tmp_path, monkeypatch):
    """With the notebooks themselves replaced (they run in the slow tests): run.json with its keys,
    the umask's permissions (not owner-only), index.html and report.html."""
    import os
    import stat

    from lorisnb.tools.report import build as report

    monkeypatch.setattr(report, "run_notebook", lambda name, out_dir, parameters, timeout=1800, notebooks_dir=None:
                        report.NotebookRun(name))  # fmt: skip
    old = os.umask(0o027)
    try:
        run_dir, _ = report.run_report(tmp_path / "run", {}, ["metrics_primer"], progress=False, command=["x"])
    finally:
        os.umask(old)
    assert stat.S_IMODE(run_dir.stat().st_mode) == 0o750
    record = json.loads((run_dir / "run.json").read_text())
    assert (
        tuple(record) == (*KEYS, "input_roots", "roots", *(["dirty"] if record["commit"] else []))
        and record.get("dirty") in ((True, False, None) if record["commit"] else (None,))
        and record["command"] == ["x"]
        and record["notebooks"] == {"metrics_primer": "ok"}
    )
    assert "{data}/openloris-scene/groundtruth/gt_cafe_1.txt" in record["inputs"]
    index = (run_dir / "index.html").read_text()
    assert "No leaderboard" in index and (run_dir / "report.html").exists()
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValidationError, match="no result files in it"):
        report.run_report(tmp_path / "other", {}, progress=False, results=tmp_path / "empty")
    assert not (tmp_path / "other").exists()
    (tmp_path / "mine" / "orb").mkdir(parents=True)
    (tmp_path / "mine" / "orb" / "cafe.txt").write_text("scene: cafe\n")
    shutil.copytree(tmp_path / "mine", tmp_path / "theirs")  # -p results_dir without result files is refused first
    with pytest.raises(ValidationError, match="two folders"):
        report.run_report(tmp_path / "other", {"results_dir": str(tmp_path / "theirs")}, progress=False,
                          results=tmp_path / "mine")  # fmt: skip
    # output_dir is the report's to set (each notebook's folder of the run): given, it was recorded and ignored
    with pytest.raises(ValidationError, match="-p output_dir: the report sets"):
        report.run_report(tmp_path / "other", {"output_dir": str(tmp_path / "elsewhere")}, progress=False)
    assert not (tmp_path / "other").exists() and not (tmp_path / "elsewhere").exists()


def test_the_rank_sentence_says_pairs_of_copied_trials_were_not_tested(tmp_path, icra20, data):
    """Trials that are byte copies of one run: no pair is tested, and the sentence said so by pasting
    the pair's test name ('significantly better by none: trials are copies of one run, Holm ...')."""
    import shutil
    import warnings

    for alg in ("odom", "orbslam2_rgbd"):
        for run in ("run_1", "run_2"):
            shutil.copytree(icra20 / "per-seq" / alg, tmp_path / "res" / alg / run)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ev = ln.evaluate(tmp_path / "res", data_root=data)
    f = findings(ev.sequences(), ev.durations())
    assert "by none:" not in f.test and "by no test," in f.test, f.test
    assert "pair(s) not tested: the trials of one of their algorithms are copies of one run" in f.test


def test_a_sequence_missing_a_trial_is_marked_in_the_per_sequence_table(tmp_path, icra20, data):
    """The front page's per-sequence table is the mean over a sequence's trials, while the leaderboard
    counts a missing trial as a failed run: a sequence with fewer trials than its algorithm's others
    says so ('1 of 2 trials'), or its values did not add up to the leaderboard's."""
    import shutil
    import warnings

    from lorisnb.tools.report.index import _per_sequence

    src = icra20 / "per-seq" / "odom"
    shutil.copytree(src, tmp_path / "res" / "odom" / "run_1")
    (tmp_path / "res" / "odom" / "run_2").mkdir()
    first = sorted(src.glob("cafe*"))[0]
    shutil.copy(first, tmp_path / "res" / "odom" / "run_2" / first.name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ev = ln.evaluate(tmp_path / "res", data_root=data)
    table = ev.sequences()
    cafe = table[table["scene"] == "cafe"]
    text = _per_sequence(cafe, "cr", [1, 2], None, "", "cafe")
    assert "trials" not in text.loc["odom", "seq 1"]
    seq2 = cafe[cafe["seq"] == 2]["cr"].mean()
    assert text.loc["odom", "seq 2"] == f"{seq2:.3f} (1 of 2 trials)", text
