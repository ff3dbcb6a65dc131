"""A received manifest's ``root = "${PYENV_ROOT}"`` counted as a dataset folder (any variable ending
in ``_ROOT`` did): ``groundtruth = "version"`` read ``~/.pyenv/version`` and quoted it ("'3.11.7' has
1 fields"), and a refusal listed that folder among the allowed places. Only the dataset variables
lorisnb knows (its built-in manifests' ``EUROC_ROOT``, ``TUM_ROOT``, and ``LORISNB_DATA``) and those
the user lists in ``LORISNB_DATASET_VARIABLES`` name a dataset's folder; a root under another is
refused, naming the variable and how to allow it, and nothing of the folder is read or shown."""

from __future__ import annotations

import shutil
import tomllib
from pathlib import Path

import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.io.datasets import manifest as mf
from lorisnb.io.datasets.manifest import read_manifest


def _lab(tmp_path, data, root: str, groundtruth: str):
    """A manifest received in ``mf/`` (root and ground truth as given) and a results folder of
    ORB-SLAM's fr2_desk estimate, as the tester's ``man/`` folder."""
    (tmp_path / "mf").mkdir()
    m = tmp_path / "mf" / "lab.toml"
    m.write_text(f'name = "t"\nscene = "s"\nroot = "{root}"\ngroundtruth_format = "tum"\nestimate_format = "tum"\n'
                 f'[conventions]\nassociation = "nearest"\n[[session]]\nname = "fr2_desk"\n'
                 f'groundtruth = "{groundtruth}"\nestimate = "fr2_desk_ORB.txt"\n')  # fmt: skip
    (tmp_path / "res" / "alg").mkdir(parents=True)
    shutil.copy(data.root / "tum-rgbd" / "fr2_desk_ORB.txt", tmp_path / "res" / "alg")
    return m


@pytest.fixture
def pyenv(tmp_path):
    """A tool's folder outside the manifest's and the data's, named by its own *_ROOT variable."""
    folder = tmp_path / "home" / ".pyenv"
    folder.mkdir(parents=True)
    (folder / "version").write_text("3.11.7\n")
    return folder


def test_a_variable_ending_in_root_that_names_no_dataset_is_refused_unread(tmp_path, data, pyenv, monkeypatch, capsys):
    monkeypatch.setenv("PYENV_ROOT", str(pyenv))
    monkeypatch.delenv("LORISNB_DATASET_VARIABLES", raising=False)
    m = _lab(tmp_path, data, "${PYENV_ROOT}", "version")
    monkeypatch.chdir(tmp_path)
    rc = main(["evaluate", "res", "--manifest", "mf/lab.toml", "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2, err
    assert (f"error: mf/lab.toml: root = '${{PYENV_ROOT}}' (PYENV_ROOT is not a dataset folder's variable lorisnb "
            "knows: EUROC_ROOT, TUM_ROOT, LORISNB_DATA; if it names your dataset's folder, allow it: "
            "LORISNB_DATASET_VARIABLES=PYENV_ROOT) lies outside the manifest's folder and lorisnb's data root "
            f"({m.parent.resolve()}, {data.root.resolve()})") in err, err  # fmt: skip
    assert "3.11.7" not in err and str(pyenv) not in err
    with pytest.raises(ln.ParseError, match="allow it: LORISNB_DATASET_VARIABLES=PYENV_ROOT"):
        read_manifest(m)  # the Python API alike
    assert read_manifest(m, outside=True).sessions[0].groundtruth == pyenv / "version"  # --manifest-outside: yours


def test_a_variable_the_user_lists_names_a_dataset_folder(tmp_path, data, monkeypatch, capsys):
    """``LORISNB_DATASET_VARIABLES=LAB_ROOT``: a root under ``$LAB_ROOT`` is read, and scores as the pair does."""
    lab = tmp_path / "lab-data"
    lab.mkdir()
    shutil.copy(data.root / "tum-rgbd" / "fr2_desk_groundtruth.txt", lab / "gt.txt")
    monkeypatch.setenv("LAB_ROOT", str(lab))
    m = _lab(tmp_path, data, "${LAB_ROOT}", "gt.txt")
    monkeypatch.delenv("LORISNB_DATASET_VARIABLES", raising=False)
    with pytest.raises(ln.ParseError, match="LAB_ROOT is not a dataset folder's variable"):
        read_manifest(m)
    monkeypatch.setenv("LORISNB_DATASET_VARIABLES", "KITTI_ROOT, LAB_ROOT")
    ev = ln.evaluate_manifest(m, tmp_path / "res", progress=False, jobs=1)
    pair = ln.evaluate_pairs(tmp_path / "res" / "alg" / "fr2_desk_ORB.txt", lab / "gt.txt", "tum", progress=False)
    row, ref = ev.sequences().iloc[0], pair.sequences().iloc[0]
    assert row["matched"] == ref["matched"] == 2223 and row["ate_rmse"] == pytest.approx(ref["ate_rmse"], rel=1e-12)
    assert 0.005 < row["ate_rmse"] < 0.02
    monkeypatch.setenv("LORISNB_DATASET_VARIABLES", "LAB-ROOT")
    rc = main(["evaluate", str(tmp_path / "res"), "--manifest", str(m), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and "LORISNB_DATASET_VARIABLES='LAB-ROOT': 'LAB-ROOT' is not an environment variable's name" in err


def test_the_known_dataset_variables_are_those_of_the_built_in_manifests(tmp_path, data, monkeypatch):
    """Every built-in manifest's root variable is known (TUM_ROOT=... needs nothing more), and a
    manifest of one's own with ``root = "${TUM_ROOT}"`` reads inside that folder."""
    from lorisnb.io.datasets.manifest import DATASET_VARIABLES

    used = set()
    for toml in sorted((Path(mf.__file__).parents[2] / "manifests").glob("*.toml")):
        root = tomllib.loads(toml.read_text()).get("root", "")
        used |= set(mf._variables(root, known=False)) | {v for v in ("EUROC_ROOT", "TUM_ROOT") if v in root}
    assert used == {"EUROC_ROOT", "TUM_ROOT"} and used < set(DATASET_VARIABLES)
    monkeypatch.delenv("LORISNB_DATASET_VARIABLES", raising=False)
    monkeypatch.setenv("TUM_ROOT", str(data.root / "tum-rgbd"))
    m = _lab(tmp_path, data, "${TUM_ROOT}", "fr2_desk_groundtruth.txt")
    ev = ln.evaluate_manifest(m, tmp_path / "res", progress=False, jobs=1)
    assert ev.sequences().iloc[0]["matched"] == 2223 and not ev.failures
