"""Notebooks run with papermill as a lab runs them (``papermill NB out.ipynb -p NAME VALUE``), and
the report's pages: what a user gives wrong is refused in the notebook's first cell, by the checks
``lorisnb report`` uses, and a report's pages name the folder it lands in."""

from __future__ import annotations

from pathlib import Path

import nbformat
import pandas as pd
import papermill as pm
import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import ValidationError
from lorisnb.tools.notebook import start as notebook_module
from lorisnb.tools.report import build as report
from lorisnb.tools.report.build import KERNEL_ARGS, kernel_env, notebook_dir
from lorisnb.tools.report.notebooks import kernel_files, kernel_manager_class

DECLARED = '# Parameters\neps = "paper"  # ATE threshold\nphi = 30.0  # degrees\nscenes = None  # scenes\nquick = False  # trim\n'
SETUP = 'session = ln.setup("per_sequence_benchmark", data_root, output_dir, parameters=dict(eps=eps))'


@pytest.fixture(scope="module", autouse=True)
def _kernel_files():
    """The kernels' connection files and ipc sockets in one private folder removed at the end, as a
    report's (``kernel_files``), not loose in the temporary folder."""
    with kernel_files():
        yield


class _Shell:
    """What :func:`lorisnb.tools.notebook.start.setup` sees of a kernel: its namespace with ``In``."""

    def __init__(self, history: list[str], **namespace):
        self.user_ns = {"In": ["", *history], **namespace}


def _setup_in(monkeypatch, tmp_path, history, **namespace):
    import IPython

    monkeypatch.setattr(IPython, "get_ipython", lambda: _Shell(history, **namespace))
    root = namespace.get("data_root")
    return ln.setup("per_sequence_benchmark", root, tmp_path / "out", parameters=dict(eps=namespace.get("eps")))


def test_history_gives_declared_and_injected_names():
    from lorisnb.tools.notebook.params import papermill_parameters

    injected = "# Parameters\nepss = 3\nphi = 10\n"
    declared, given = papermill_parameters(["", DECLARED, injected, SETUP])
    assert list(declared) == ["eps", "phi", "scenes", "quick"] and declared["scenes"] == "None"
    assert given == ["epss", "phi"]
    assert papermill_parameters(["", DECLARED, SETUP]) == (declared, [])  # run by hand: nothing injected
    assert papermill_parameters(["", "x = 1\nprint(x)", SETUP]) is None  # not after a parameters cell


@pytest.mark.parametrize(
    ("injected", "values", "message"),
    [
        ("epss = 3", dict(epss=3), "epss not declared by per_sequence_benchmark"),  # a misspelt name
        ("quick = 'maybe'", dict(quick="maybe"), "quick='maybe'"),  # checked though not passed to setup
        ("eps = None", dict(eps=None), "-p eps null"),
        ("scenes = ['office']", dict(scenes=["office"]), "no ground truth for office"),
        (
            """scenes = '["cafe"]'""",
            dict(scenes='["cafe"]'),
            "a list written as text",
        ),  # papermill -p scenes '["cafe"]'
    ],
)
def test_papermill_parameters_refused_in_the_first_cell(monkeypatch, tmp_path, data, injected, values, message):
    namespace = dict(eps="paper", phi=30.0, scenes=None, quick=False, data_root=str(data.root), output_dir=None)
    with pytest.raises(ValidationError, match=message.replace("[", r"\[").replace("(", r"\(")):
        _setup_in(monkeypatch, tmp_path, [DECLARED, f"# Parameters\n{injected}\n", SETUP], **{**namespace, **values})


def test_declared_parameters_with_good_values_pass(monkeypatch, tmp_path, data):
    namespace = dict(
        eps=3.0, phi=30.0, scenes=["cafe", "office"], quick=True, data_root=str(data.root), output_dir=None
    )
    session = _setup_in(monkeypatch, tmp_path, [DECLARED, "# Parameters\neps = 3\nscenes = ['cafe', 'office']\n", SETUP],
                        **namespace)  # fmt: skip
    assert session.data.root == data.root and session.spec().eps == 3.0


def test_session_filters_refuse_a_name_that_is_in_no_input(tmp_path, data, icra20):
    session = notebook_module.Session(data, notebook_module.Outputs(tmp_path), "evo_crosscheck")
    assert session.filters(icra20 / "per-seq", "dso", "cafe") == (["dso"], ["cafe"])  # one name: a list of one
    with pytest.raises(ValidationError, match="'nope' name"):
        session.filters(icra20 / "per-seq", ["nope"], None)


def _fake_run(name, out_dir, parameters, timeout=1800, notebooks_dir=None):
    (out_dir / name).mkdir(parents=True, exist_ok=True)
    return report.NotebookRun(name)


def test_report_pages_name_the_folder_the_run_lands_in(tmp_path, monkeypatch, capsys):
    """Every report's pages were written under the temporary name and said the run was there, as if
    another run had taken the folder ('.run.partial-xyz (run appeared while this report ran')."""
    monkeypatch.setattr(report, "run_notebook", _fake_run)
    out = tmp_path / "run"
    assert main(["report", "--out", str(out), "--notebooks", "metrics_primer", "--no-progress"]) == 0
    assert "appeared" not in capsys.readouterr().err
    for page in ("index.html", "report.html"):
        text = (out / page).read_text()
        assert "Run folder <code>run</code>, written" in text
        assert "partial" not in text and "appeared while" not in text


# --- papermill, as a lab runs the shipped notebooks -----------------------------------------


def _first_cells(name: str, tmp_path: Path) -> Path:
    """The notebook up to its first cell after the parameters (where it checks them)."""
    nb = nbformat.read(notebook_dir() / f"{name}.ipynb", as_version=4)
    cells, seen = [], False
    for cell in nb.cells:
        cells.append(cell)
        if cell.cell_type == "code":
            if "parameters" in cell.metadata.get("tags", []):
                seen = True
            elif seen:
                break
    nb.cells = cells
    path = tmp_path / f"{name}_first.ipynb"
    nbformat.write(nb, path)
    return path


@pytest.mark.slow
@pytest.mark.parametrize(
    ("name", "params", "message"),
    [
        ("per_sequence_benchmark", dict(epss=3.0), "epss not declared by per_sequence_benchmark"),
        ("lifelong_benchmark", dict(scenes=["office"]), "no ground truth for office"),
        ("compare_algorithms", dict(metric="foo"), "metric=foo"),
        ("evo_crosscheck", dict(algorithms=["nope"]), "'nope' name"),
        ("indoor_vs_outdoor", dict(ordslam_fps=30), "ordslam_fps: only applies with -p ordslam_dir"),
    ],
)
def test_papermill_refuses_in_the_first_cell(tmp_path, data, name, params, message):
    kernel_env()
    with pytest.raises(pm.PapermillExecutionError) as info:
        pm.execute_notebook(
            str(_first_cells(name, tmp_path)), str(tmp_path / "out.ipynb"), kernel_name="python3",
            parameters=dict(quick=True, output_dir=str(tmp_path / "out"), **params), progress_bar=False,
            cwd=str(tmp_path), extra_arguments=KERNEL_ARGS, kernel_manager_class=kernel_manager_class(), execution_timeout=300,
        )  # fmt: skip
    assert info.value.ename == "ValidationError" and message in info.value.evalue


@pytest.mark.slow
def test_per_sequence_prose_quotes_odom_values_it_computed(tmp_path, data, icra20):
    """Its text said odom's CR 'is ~100 % in every scene', true only at infinite thresholds: at
    eps 0.5 m it is 0.27 in corridor. The notebook now shows odom's rows at its own thresholds."""
    kernel_env()
    out = tmp_path / "out"
    pm.execute_notebook(
        str(notebook_dir() / "per_sequence_benchmark.ipynb"), str(tmp_path / "nb.ipynb"), kernel_name="python3",
        parameters=dict(quick=True, output_dir=str(out), eps=0.5, phi=30.0, algorithms=["odom"], scenes=["corridor"]),
        progress_bar=False, cwd=str(tmp_path), extra_arguments=KERNEL_ARGS, kernel_manager_class=kernel_manager_class(), execution_timeout=300,
    )  # fmt: skip
    nb = nbformat.read(tmp_path / "nb.ipynb", as_version=4)
    assert not any("~100 %" in c.source for c in nb.cells if c.cell_type == "markdown")
    shown = [o for c in nb.cells if c.cell_type == "code" and 'algorithm"] == "odom"' in c.source for o in c.outputs]
    expected = ln.evaluate(icra20 / "per-seq" / "odom", data_root=data, scale="auto", mode="per-seq", jobs=1,
                           scenes=["corridor"]).scenes(eps=0.5, phi=30.0)  # fmt: skip
    assert round(float(expected["cr"].iloc[0]), 3) == pytest.approx(0.271)
    texts = [o.get("text", "") or o.get("data", {}).get("text/plain", "") for o in shown]  # the table, beside the prose
    assert shown and any(f"{expected['cr'].iloc[0]:.3f}" in t and "corridor" in t for t in texts), texts


@pytest.mark.parametrize(
    ("scenes", "said"),
    [(None, "corridor (5 sequences), home (5 sequences), market (3 sequences)"), (["cafe"], None)],
)
def test_report_names_scenes_with_ground_truth_that_no_result_file_is_of(tmp_path, monkeypatch, icra20, scenes, said):
    """One algorithm's results for cafe only: the leaderboard had cafe and nothing said that the
    other scenes with ground truth were never scored (the exit status was 0)."""
    monkeypatch.setattr(report, "run_notebook", _fake_run)
    results = tmp_path / "res" / "orbslam2_rgbd"
    results.mkdir(parents=True)
    for f in (icra20 / "per-seq" / "orbslam2_rgbd").glob("cafe_*"):
        (results / f.name).write_bytes(f.read_bytes())
    args = ["report", "--results", str(tmp_path / "res"), "--out", str(tmp_path / "run"), "--notebooks",
            "per_sequence_benchmark", "--no-progress", "--data", str(icra20.parents[1])]  # fmt: skip
    assert main(args + (["-p", "scenes", '["cafe"]'] if scenes else [])) == 0
    text = (tmp_path / "run" / "index.html").read_text()
    if said is None:  # the scenes asked for: nothing left out
        assert "No result file for" not in text
    else:
        assert f"No result file for {said} with ground truth: not scored, on no leaderboard." in text
    board = pd.read_csv(tmp_path / "run" / "findings" / "leaderboard.csv")
    assert board["scene"].tolist() == ["cafe"] and board["value"].round(4).tolist() == [0.4860]


@pytest.mark.slow
def test_indoor_vs_outdoor_prose_quotes_no_parameter_or_data_value(tmp_path, data):
    """Its text said the RPE 'is taken over `rpe_metres` = 5 m' whatever -p rpe_metres was, and
    quoted ratios of the data ('about 1 %', '10 to 20 times longer'): now printed from the run."""
    kernel_env()
    pm.execute_notebook(
        str(notebook_dir() / "indoor_vs_outdoor.ipynb"), str(tmp_path / "nb.ipynb"), kernel_name="python3",
        parameters=dict(quick=True, output_dir=str(tmp_path / "out"), rpe_metres=2.0), progress_bar=False,
        cwd=str(tmp_path), extra_arguments=KERNEL_ARGS, kernel_manager_class=kernel_manager_class(), execution_timeout=300,
    )  # fmt: skip
    nb = nbformat.read(tmp_path / "nb.ipynb", as_version=4)
    prose = "\n".join(c.source for c in nb.cells if c.cell_type == "markdown")
    assert "= 5 m" not in prose and "10 to 20 times" not in prose and "about 1 % of the path" not in prose
    printed = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code" for o in c.outputs)
    assert "RPE over rpe_metres = 2 m along the ground truth." in printed
    assert "OpenLORIS against TUM RGB-D (computed):" in printed
