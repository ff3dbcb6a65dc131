"""A notebook's output folder (``output_dir``): never one of its inputs (is, holds or lies in one),
refused in its first cell; and never a file in it that the notebook did not write replaced, while a
notebook run again into its own folder replaces its own files (:class:`lorisnb.tools.notebook.start.Outputs`,
its marker :data:`~lorisnb.tools.notebook.start.OUTPUTS_MARKER`)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import matplotlib.pyplot as plt
import pandas as pd
import pytest

from lorisnb.errors import OutputError, ValidationError
from lorisnb.tools.notebook.start import OUTPUTS_MARKER, RUN_MARKER, Outputs, setup

PRECIOUS = "my precious data\n"
TABLE = pd.DataFrame({"a": [1, 2], "b": [0.5, 0.25]})


def _figure():
    fig, ax = plt.subplots(figsize=(2, 1.5))
    ax.plot([0, 1], [0, 1])
    return fig


@pytest.fixture
def small(tmp_path, icra20) -> Path:
    """A results folder of one file (the notebook's bundled example), as a user's ``path``."""
    folder = tmp_path / "small" / "vins_mono_color_imu_with_loop"
    folder.mkdir(parents=True)
    shutil.copy(icra20 / "lifelong" / "vins_mono_color_imu_with_loop" / "home-1.txt", folder)
    return folder.parent


# --- a file the notebook did not write -------------------------------------------------------------


@pytest.mark.parametrize("kind", ["table", "input_errors", "figure"])
def test_a_users_file_of_the_same_name_is_never_replaced(tmp_path, kind):
    mine = tmp_path / "myout"
    mine.mkdir()
    name = {"table": "sequences.csv", "input_errors": "input_errors.csv", "figure": "timeline.svg"}[kind]
    (mine / name).write_text(PRECIOUS)
    out = Outputs(mine)
    with pytest.raises(OutputError, match=f"{name} exists and this notebook did not write it") as caught:
        {"table": lambda: out.table(TABLE, "sequences"), "input_errors": lambda: out.input_errors(TABLE),
         "figure": lambda: out.figure(_figure(), "timeline")}[kind]()  # fmt: skip
    assert "choose another output_dir" in str(caught.value) and "move" in str(caught.value)
    assert (mine / name).read_text() == PRECIOUS
    if kind == "figure":  # refused before any of its files was written (svg is the second of three)
        assert not (mine / "timeline.png").exists() and not (mine / "timeline.pdf").exists()


def test_a_notebook_run_again_into_its_own_folder_replaces_its_own_files(tmp_path):
    d = tmp_path / "out"
    for value in (1, 2):  # a second run, a second Outputs (a new kernel): its own files replaced
        out = Outputs(d, notebook="evaluate_my_results")
        out.table(TABLE.assign(a=value), "sequences")
        out.input_errors(TABLE.iloc[:0])
        out.figure(_figure(), "timeline")
        assert pd.read_csv(d / "sequences.csv")["a"].tolist() == [value, value]
        out.table(TABLE, "sequences")  # twice in one run, too
    listed = json.loads((d / OUTPUTS_MARKER).read_text())["files"]
    names = {"sequences.csv", "input_errors.csv", "timeline.png", "timeline.svg", "timeline.pdf"}
    assert listed == dict.fromkeys(names, "evaluate_my_results")
    assert {p.name for p in d.iterdir()} == names | {OUTPUTS_MARKER}


def test_other_files_in_the_output_folder_are_left_alone(tmp_path):
    """A folder holding the user's other files may be written into: only the names written count."""
    d = tmp_path / "out"
    d.mkdir()
    (d / "notes.txt").write_text(PRECIOUS)
    Outputs(d, notebook="lifelong_benchmark").table(TABLE, "sequences")
    assert (d / "notes.txt").read_text() == PRECIOUS and (d / "sequences.csv").is_file()


def test_another_notebooks_file_is_not_replaced(tmp_path):
    """Two notebooks given one output_dir: the second does not replace the first one's tables."""
    d = tmp_path / "out"
    Outputs(d, notebook="lifelong_benchmark").table(TABLE, "sequences")
    with pytest.raises(OutputError, match="written by the notebook lifelong_benchmark.*another output_dir"):
        Outputs(d, notebook="per_sequence_benchmark").table(TABLE.assign(a=9), "sequences")
    assert pd.read_csv(d / "sequences.csv")["a"].tolist() == [1, 2]
    Outputs(d, notebook="per_sequence_benchmark").table(TABLE, "scenes")  # a name of its own: written


def test_a_marker_that_is_not_lorisnbs_is_refused(tmp_path):
    d = tmp_path / "out"
    d.mkdir()
    (d / OUTPUTS_MARKER).write_text(PRECIOUS)
    with pytest.raises(OutputError, match=f"{OUTPUTS_MARKER}.*not a list of the files"):
        Outputs(d)
    assert (d / OUTPUTS_MARKER).read_text() == PRECIOUS


def test_an_output_dir_that_is_a_file_or_not_a_path_is_refused(tmp_path):
    (tmp_path / "f.csv").write_text(PRECIOUS)
    with pytest.raises(OutputError, match="is a file; expected a folder"):
        Outputs(tmp_path / "f.csv")
    for value in ("", "  ", 3):
        with pytest.raises(ValidationError, match="output_dir"):
            Outputs(value)  # type: ignore[arg-type]


def test_a_file_name_cannot_leave_the_output_folder(tmp_path):
    out = Outputs(tmp_path / "out")
    for name in ("../escaped", "/tmp/escaped", "a/../../escaped", ""):
        with pytest.raises(ValidationError, match="a file name"):
            out.table(TABLE, name)
    assert not (tmp_path / "escaped.csv").exists()


def test_in_a_reports_run_folder_a_figure_is_one_png_its_own_on_a_new_run(tmp_path):
    (tmp_path / RUN_MARKER).write_text("{}")
    d = tmp_path / "threshold_sensitivity"
    for _ in (1, 2):
        out = Outputs(d, notebook="threshold_sensitivity")
        assert out.in_report
        out.figure(_figure(), "cr_vs_eps")
    assert sorted(p.name for p in d.iterdir()) == [OUTPUTS_MARKER, "cr_vs_eps.png"]
    (d / "rank_stability.png").write_text(PRECIOUS)
    with pytest.raises(OutputError, match="rank_stability.png exists"):
        out.figure(_figure(), "rank_stability")


# --- the output folder and the inputs (setup: the parameters cell's check) ---------------------------


@pytest.mark.parametrize("where", ["is", "inside", "holds"])
def test_an_output_dir_meeting_the_input_path_is_refused_naming_both(tmp_path, data, small, where):
    output_dir = {"is": small, "inside": small / "out", "holds": tmp_path}[where]
    before = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*"))
    with pytest.raises(OutputError) as caught:
        setup("evaluate_my_results", data.root, output_dir, parameters=dict(path=str(small)))
    message = str(caught.value)
    relation = {"is": "is", "inside": "lies in", "holds": "holds"}[where]
    assert f"output_dir={output_dir} {relation} the input path={small}" in message
    assert "choose an output_dir outside" in message
    assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*")) == before  # nothing made, nothing written


def test_an_output_dir_in_a_results_dir_or_the_data_root_is_refused(tmp_path, data, small):
    with pytest.raises(OutputError, match=f"lies in the input results_dir={small}"):
        setup("lifelong_benchmark", data.root, small / "vins_mono_color_imu_with_loop",
              parameters=dict(results_dir=str(small)))  # fmt: skip
    with pytest.raises(OutputError, match=f"lies in the data root {data.root}"):
        setup("lifelong_benchmark", data.root, data.root / "openloris-scene" / "notebook-out")
    assert not (data.root / "openloris-scene" / "notebook-out").exists()


def test_setup_beside_the_inputs_writes_and_runs_again(tmp_path, data, small):
    """The normal case: an output folder beside the inputs, the same notebook run twice into it."""
    for _ in (1, 2):
        session = setup("evaluate_my_results", data.root, tmp_path / "out", parameters=dict(path=str(small)))
        session.out.table(TABLE, "sequences")
    assert json.loads((tmp_path / "out" / OUTPUTS_MARKER).read_text())["files"] == {
        "sequences.csv": "evaluate_my_results"
    }


def test_the_default_folder_takes_an_earlier_runs_files_as_the_notebooks_own(tmp_path, data, small, monkeypatch):
    """``results/notebooks/<name>`` is the notebook's own folder: files an earlier lorisnb wrote there
    without a marker are its earlier run's, replaced (a run with the default folder was refused after
    an upgrade); a folder the user names keeps the rule."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "notebooks").mkdir()  # a checkout's layout: results/notebooks/<name> is the default folder
    folder = tmp_path / "results" / "notebooks" / "evaluate_my_results"
    folder.mkdir(parents=True)
    (folder / "sequences.csv").write_text("a,b\n1,2\n")  # an earlier run's (the table's columns), no marker
    _figure().savefig(folder / "timeline.png")  # an earlier run's figure: matplotlib's
    session = setup("evaluate_my_results", data.root, None, parameters=dict(path=str(small)))
    assert session.out.dir.resolve() == folder.resolve()
    session.out.table(TABLE, "sequences")
    assert pd.read_csv(folder / "sequences.csv").equals(TABLE)
    session.out.figure(_figure(), "timeline")  # after the first write made the marker: still this run's to adopt
    named = tmp_path / "mine"
    named.mkdir()
    (named / "sequences.csv").write_text(PRECIOUS)
    with pytest.raises(OutputError, match="did not write it"):
        setup("evaluate_my_results", data.root, named, parameters=dict(path=str(small))).out.table(TABLE, "sequences")
    assert (named / "sequences.csv").read_text() == PRECIOUS


def _default_folder(tmp_path: Path, monkeypatch, name: str = "evaluate_my_results") -> Path:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "notebooks").mkdir()
    folder = tmp_path / "results" / "notebooks" / name
    folder.mkdir(parents=True)
    return folder


def test_the_default_folder_with_a_marker_replaces_only_the_files_it_lists(tmp_path, data, small, monkeypatch):
    """The tester's repro: results/notebooks/<name> holds a marker listing scenes.csv and the user's own
    sequences.csv beside it; the notebook must not replace sequences.csv (it did not write it)."""
    folder = _default_folder(tmp_path, monkeypatch)
    (folder / OUTPUTS_MARKER).write_text(
        json.dumps({"lorisnb": "0.3.0", "files": {"scenes.csv": "evaluate_my_results"}})
    )
    (folder / "sequences.csv").write_text("a,b\n9,9\n")  # even with the table's own columns: the marker rules
    _figure().savefig(folder / "timeline.png")
    marker = (folder / OUTPUTS_MARKER).read_text()
    # refused in the notebook's first cell (setup checks every file it always writes), before anything is written
    with pytest.raises(OutputError, match=r"sequences.csv exists and this notebook did not write it .*does not list"):
        setup("evaluate_my_results", data.root, None, parameters=dict(path=str(small)))
    assert (folder / "sequences.csv").read_text() == "a,b\n9,9\n"
    assert (folder / OUTPUTS_MARKER).read_text() == marker
    (folder / "sequences.csv").unlink()  # the user moves it away: a figure written on some inputs only is
    session = setup("evaluate_my_results", data.root, None, parameters=dict(path=str(small)))  # checked as written
    with pytest.raises(OutputError, match="timeline.png exists"):
        session.out.figure(_figure(), "timeline")
    session.out.table(TABLE, "scenes")  # listed: replaced
    assert "sequences.csv" not in json.loads((folder / OUTPUTS_MARKER).read_text())["files"]


@pytest.mark.parametrize("name, content", [("sequences.csv", PRECIOUS), ("timeline.png", PRECIOUS),
                                           ("timeline.svg", "<svg></svg>\n"), ("cr_table.md", "| mine |\n")])  # fmt: skip
def test_the_default_folder_without_a_marker_keeps_a_file_lorisnb_did_not_write(tmp_path, data, small, monkeypatch,
                                                                                  name, content):  # fmt: skip
    """Without a marker, a file is taken as an earlier run's only if it shows it is lorisnb's; the user's
    table (other columns), an image not from matplotlib, a file written through out.path (no way to know)
    are refused and kept."""
    folder = _default_folder(tmp_path, monkeypatch)
    (folder / name).write_text(content)
    out = setup("evaluate_my_results", data.root, None, parameters=dict(path=str(small))).out
    write = {".csv": lambda: out.table(TABLE, "sequences"), ".png": lambda: out.figure(_figure(), "timeline"),
             ".svg": lambda: out.figure(_figure(), "timeline"), ".md": lambda: out.path("cr_table.md")}  # fmt: skip
    with pytest.raises(OutputError, match=f"{name} exists and this notebook did not write it .*could have written"):
        write[Path(name).suffix]()
    assert (folder / name).read_text() == content


# --- the notebook itself, run with papermill ---------------------------------------------------------


def _papermill(tmp_path: Path, data, **params) -> None:
    import papermill as pm

    from lorisnb.tools.report.build import KERNEL_ARGS, kernel_env, notebook_dir
    from lorisnb.tools.report.notebooks import kernel_files, kernel_manager_class

    kernel_env()
    with kernel_files():
        pm.execute_notebook(
            str(notebook_dir() / "evaluate_my_results.ipynb"), str(tmp_path / "run.ipynb"),
            parameters={"quick": True, "data_root": str(data.root), **params}, kernel_name="python3",
            progress_bar=False, cwd=str(tmp_path), extra_arguments=KERNEL_ARGS,
            kernel_manager_class=kernel_manager_class(), execution_timeout=600,
        )  # fmt: skip


@pytest.mark.slow
def test_evaluate_my_results_keeps_a_users_file_and_reruns_into_its_own_folder(tmp_path, data, small):
    """The tester's commands: ``-p output_dir myout`` holding the user's sequences.csv is refused in
    the first cell (the file kept); ``-p output_dir`` the results folder is refused; a folder of its
    own is written, then written again by a second run."""
    from papermill.exceptions import PapermillExecutionError

    mine = tmp_path / "myout"
    mine.mkdir()
    (mine / "sequences.csv").write_text(PRECIOUS)
    with pytest.raises(PapermillExecutionError, match="sequences.csv exists and this notebook did not write it"):
        _papermill(tmp_path, data, path=str(small), output_dir=str(mine))
    assert (mine / "sequences.csv").read_text() == PRECIOUS
    with pytest.raises(PapermillExecutionError, match=f"output_dir={small} is the input path={small}"):
        _papermill(tmp_path, data, path=str(small), output_dir=str(small))
    assert sorted(p.name for p in small.iterdir()) == ["vins_mono_color_imu_with_loop"]
    own = tmp_path / "own"
    tables = []
    for _ in (1, 2):
        _papermill(tmp_path, data, path=str(small), output_dir=str(own))
        tables.append(pd.read_csv(own / "sequences.csv"))
    assert set(tables[0]["file"].map(lambda f: Path(f).name)) == {"home-1.txt"}
    pd.testing.assert_frame_equal(tables[0], tables[1])
    listed = json.loads((own / OUTPUTS_MARKER).read_text())["files"]
    assert {"sequences.csv", "scenes.csv", "relative.csv", "input_errors.csv", "timeline.png"} <= set(listed)
    assert set(listed) == {p.name for p in own.iterdir()} - {OUTPUTS_MARKER}


def test_an_output_dir_under_home_is_expanded_as_the_input_paths_are(tmp_path, data, small, monkeypatch):
    """``output_dir="~/x"`` made a folder literally named ``~`` in the current folder; it is the home
    folder's x, as ``path="~/..."`` is, and is checked against the inputs there."""
    home = tmp_path / "home"
    home.mkdir()
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.chdir(tmp_path)
    session = setup("evaluate_my_results", data.root, "~/x", parameters=dict(path=str(small)))
    session.out.table(TABLE, "sequences")
    assert session.out.dir == home / "x" and (home / "x" / "sequences.csv").is_file()
    assert not (tmp_path / "~").exists()
    shutil.copytree(small, home / "res")
    with pytest.raises(OutputError, match="output_dir=~/res/out lies in the input path=~/res"):
        setup("evaluate_my_results", data.root, "~/res/out", parameters=dict(path="~/res"))
