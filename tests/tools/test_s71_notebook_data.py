"""The primer's data and thresholds: a ``LORISNB_DATA`` the user set is honoured or refused with
find_data's message, never passed over for the sample data shipped with lorisnb (which is used only
when neither ``data_root`` nor ``LORISNB_DATA`` is set and no shared/data folder is found); and the
real-estimates section is scored at the notebook's phi, its prose saying which thresholds it used."""

from __future__ import annotations

import warnings
from pathlib import Path

import pandas as pd
import pytest

from lorisnb.errors import DataNotFoundError
from lorisnb.io.datasets import paths
from lorisnb.io.datasets.paths import SAMPLE_DATA
from lorisnb.tools.notebook.start import setup

PRIMER = dict(quick=True, scene="cafe", eps=1.0, phi=30.0, delta=1.0, tau=60.0, seed=0)


def _setup(tmp_path: Path, data_root=None):
    with warnings.catch_warnings():  # setup silences lorisnb's warnings for the notebook's process
        return setup("metrics_primer", data_root, tmp_path / "out", sample=True, parameters=PRIMER)


@pytest.mark.parametrize("where", ["missing", "empty folder", "file"])
def test_a_wrong_lorisnb_data_is_refused_not_replaced_by_the_sample(tmp_path, monkeypatch, capsys, where):
    env = tmp_path / "given"
    if where == "empty folder":
        env.mkdir()
    elif where == "file":
        env.write_text("not data\n")
    state = {"missing": "does not exist", "empty folder": "not a data root", "file": "a file, not a folder"}[where]
    monkeypatch.setenv("LORISNB_DATA", str(env))
    with pytest.raises(DataNotFoundError, match=rf"LORISNB_DATA={env}: {state}\. A data root holds"):
        _setup(tmp_path)
    assert "sample data" not in capsys.readouterr().out
    assert not (tmp_path / "out").exists()


def test_a_wrong_data_root_is_refused(tmp_path, monkeypatch):
    monkeypatch.delenv("LORISNB_DATA", raising=False)
    with pytest.raises(DataNotFoundError, match="could not find its data"):
        _setup(tmp_path, tmp_path / "nowhere")


def test_the_sample_only_when_nothing_is_named_and_nothing_found(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv("LORISNB_DATA", raising=False)
    shared = tmp_path / "shared" / "data"  # the only place looked at: nothing there
    monkeypatch.setattr(paths, "_candidates", lambda data_root: [("beside the current folder", shared)])
    session = _setup(tmp_path)
    assert session.data.root == SAMPLE_DATA.resolve()
    printed = capsys.readouterr().out
    assert ("no data_root given, LORISNB_DATA not set and no shared/data folder found: using the small sample "
            "data shipped with lorisnb (cafe scene only)") in printed  # fmt: skip
    monkeypatch.setenv("LORISNB_DATA", "")  # set empty: unset, as find_data reads it
    assert _setup(tmp_path).data.root == SAMPLE_DATA.resolve()


def test_a_good_lorisnb_data_is_used(tmp_path, monkeypatch, capsys, data):
    monkeypatch.setenv("LORISNB_DATA", str(data.root))
    assert _setup(tmp_path).data.root == data.root.resolve()
    assert "sample data" not in capsys.readouterr().out


@pytest.mark.slow
@pytest.mark.xdist_group("notebooks")
def test_real_estimates_at_the_notebooks_phi_and_said(tmp_path, data, monkeypatch):
    """With -p phi 10 the real-estimates table is scored at 10 degrees (the paper's eps of cafe, the
    notebook's delta and tau), and the sentence under it says so, with the numbers of that table."""
    import nbformat
    import papermill as pm
    from helpers import temp_dir_left_as_found

    from lorisnb.tools.report.build import KERNEL_ARGS, kernel_env, notebook_dir
    from lorisnb.tools.report.notebooks import kernel_files, kernel_manager_class

    kernel_env()
    monkeypatch.setenv("LORISNB_DATA", str(data.root))
    out = tmp_path / "out"
    with temp_dir_left_as_found(), kernel_files():  # the kernel's connection files: in a folder removed after
        pm.execute_notebook(str(notebook_dir() / "metrics_primer.ipynb"), str(tmp_path / "primer.ipynb"),
                            parameters=dict(quick=True, phi=10.0, tau=30.0, output_dir=str(out)),
                            kernel_name="python3", progress_bar=False, cwd=str(tmp_path), extra_arguments=KERNEL_ARGS,
                            kernel_manager_class=kernel_manager_class(), execution_timeout=900)  # fmt: skip
    real = pd.read_csv(out / "real_estimates.csv")
    assert set(real["phi"]) == {10.0} and set(real["eps"]) == {3.0} and set(real["tau"]) == {30.0}
    nb = nbformat.read(tmp_path / "primer.ipynb", as_version=4)
    text = "".join(o.get("data", {}).get("text/markdown", "") for c in nb.cells for o in c.get("outputs", []))
    assert ("Real estimates are judged at the paper's eps of their scene, 3 m for cafe (this notebook's eps = 1 m "
            "applies to the simulated examples above), and at this notebook's phi = 10 degrees, delta = 1 s and "
            "tau = 30 s (the paper's phi is 30 degrees).") in text  # fmt: skip
    orb = real.set_index(["algorithm", "seq"]).loc[("orbslam2_rgbd", 1)]
    assert f"ORB-SLAM2 on cafe-1: CR {orb['cr']:.3f}, ATE RMSE {orb['ate_rmse']:.3f} m." in text
