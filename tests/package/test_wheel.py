"""A wheel of lorisnb installed outside the checkout runs `lorisnb evaluate` and `lorisnb report`
with `--data`: the notebooks ship as package data and nothing assumes the source tree."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """A fresh venv with lorisnb from its wheel (dependencies from this environment's
    site-packages through a .pth file, which does not activate the editable install)."""
    base = tmp_path_factory.mktemp("wheel")
    dist = base / "dist"
    subprocess.run(
        [sys.executable, "-m", "build", "--wheel", "--no-isolation", "--outdir", str(dist), str(ROOT)],
        check=True,
        capture_output=True,
        cwd=base,
    )
    wheel = next(dist.glob("lorisnb-*.whl"))
    venv = base / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    py = venv / "bin" / "python"
    site = Path(
        subprocess.run(
            [str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
            check=True,
            capture_output=True,
            text=True,
        ).stdout.strip()
    )
    (site / "deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--no-deps", "--no-index", "--target", str(site), str(wheel)],
        check=True,
        capture_output=True,
    )
    return venv, base


def _run(venv: Path, cwd: Path, *args: str) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k not in ("LORISNB_DATA", "PYTHONPATH")}
    env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    return subprocess.run(
        [str(venv / "bin" / "python"), "-m", "lorisnb.cli", *args],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )


def test_wheel_evaluates_and_reports_outside_the_checkout(installed, data, tmp_path):
    venv, _ = installed
    where = subprocess.run(
        [str(venv / "bin" / "python"), "-c", "import lorisnb; print(lorisnb.__file__)"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert str(ROOT) not in where and "site-packages" in where
    src = data.icra20 / "per-seq" / "orbslam2_rgbd" / "cafe_1_1_orbslam2-original.txt"
    r = _run(venv, tmp_path, "evaluate", str(src), "--data", str(data.root), "--csv", "out.csv", "--no-progress")
    assert r.returncode == 0, r.stderr
    row = pd.read_csv(tmp_path / "out.csv").iloc[0]
    assert row["matched"] == 1708 and row["ate_rmse"] == pytest.approx(0.472544, abs=1e-6)  # issue #2 reference
    # the built-in manifests ship in the wheel: the OpenLORIS one gives the same row
    r = _run(venv, tmp_path, "evaluate", str(src), "--manifest", "openloris", "--data", str(data.root),
             "--csv", "out2.csv", "--no-progress")  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert pd.read_csv(tmp_path / "out2.csv").iloc[0]["ate_rmse"] == row["ate_rmse"]
    # and a TUM pair under TUM's conventions
    tum = data.tum
    r = _run(venv, tmp_path, "evaluate", str(tum / "fr2_desk_ORB.txt"), "--gt", str(tum / "fr2_desk_groundtruth.txt"),
             "--conventions", "tum", "--csv", "tum.csv", "--no-progress")  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert pd.read_csv(tmp_path / "tum.csv").iloc[0]["matched"] == 2223
    r = _run(
        venv,
        tmp_path,
        "report",
        "--data",
        str(data.root),
        "--out",
        "rep",
        "--notebooks",
        "metrics_primer",
        "-p",
        "quick",
        "true",
        "--no-progress",
    )
    assert r.returncode == 0, r.stdout + r.stderr
    assert (tmp_path / "rep" / "index.html").exists()
    assert (tmp_path / "rep" / "metrics_primer" / "primer_cases.csv").exists()
    # no data given and none beside the folder: a clear error naming where it looked
    r = _run(venv, tmp_path, "evaluate", str(src), "--no-progress")
    assert r.returncode == 2 and "could not find its data" in r.stderr and str(tmp_path) in r.stderr


def test_wheel_runs_the_primer_and_a_lab_with_no_data_folder(installed, tmp_path):
    """A student's start (issue 26): the wheel installed, no ../shared and no LORISNB_DATA; the primer
    (shipped in the package) and lab 1 (handed out as a notebook; here the instructor version, so
    that every check runs) run on the sample data inside the package, and every check passes."""
    import nbformat

    venv, _ = installed
    assert not any((p / "shared" / "data").exists() for p in (tmp_path, *tmp_path.parents))
    lab = ROOT / "teaching" / "source" / "lab1_lifelong_metrics" / "lab1_lifelong_metrics.ipynb"
    shutil.copyfile(lab, tmp_path / lab.name)
    script = (
        "import sys, pathlib, papermill as pm, lorisnb.notebooks as n\n"
        "primer = pathlib.Path(n.__file__).parent / 'metrics_primer.ipynb'\n"
        "pm.execute_notebook(str(primer), 'primer_run.ipynb', parameters={'quick': True, 'output_dir': 'primer_out'},"
        " kernel_name='python3', progress_bar=False)\n"
        "pm.execute_notebook(sys.argv[1], 'lab_run.ipynb', parameters={'output_dir': 'lab_out'},"
        " kernel_name='python3', progress_bar=False)\n"
    )
    env = {k: v for k, v in os.environ.items() if k not in ("LORISNB_DATA", "PYTHONPATH")}
    env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    env["MPLBACKEND"] = "Agg"
    r = subprocess.run(
        [str(venv / "bin" / "python"), "-c", script, lab.name],
        cwd=tmp_path, env=env, capture_output=True, text=True, timeout=900,
    )  # fmt: skip
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]

    def printed(name: str) -> str:
        nb = nbformat.read(tmp_path / name, as_version=4)
        return "".join(
            o.get("text", "") for c in nb.cells if c.cell_type == "code" for o in c.outputs if o.output_type == "stream"
        )

    for name in ("primer_run.ipynb", "lab_run.ipynb"):
        out = printed(name)
        assert "using the small sample data shipped with lorisnb" in out and "site-packages" in out, out[:500]
    assert (tmp_path / "primer_out" / "primer_cases.csv").exists()
    lab_out = printed("lab_run.ipynb")
    checks = sum(
        c.source.count("teach.check_") for c in nbformat.read(lab, as_version=4).cells if c.cell_type == "code"
    )
    assert "✗" not in lab_out and lab_out.count("✓") >= checks, lab_out  # check_alignment_cr prints two


def test_wheel_carries_the_compiled_rotation_kernel(installed, tmp_path):
    """The wheel built here (a C compiler at hand) holds lorisnb.core.trajectory._rotations, which the
    installed lorisnb uses for KITTI's rotation blocks."""
    venv, _ = installed
    if shutil.which((sysconfig.get_config_var("CC") or "cc").split()[0]) is None:
        pytest.skip("no C compiler here: the wheel is built without the kernel")
    r = subprocess.run(
        [
            str(venv / "bin" / "python"),
            "-c",
            "import sys; from lorisnb.core import matrices; print(sys.modules[matrices._kernel.__module__].__file__)",
        ],
        cwd=tmp_path,
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0 and "site-packages" in r.stdout and str(ROOT) not in r.stdout, r.stderr
