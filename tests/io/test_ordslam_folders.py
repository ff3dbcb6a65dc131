"""ORDSLAM folders as the real download may hold them: sequences at different frame rates, a
ground truth of sparse key frames, estimates in another time base, a .txt file that is no
trajectory. All files are synthetic, written here (the 27 GB dataset is not bundled)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from lorisnb.errors import ParseError
from lorisnb.io.readers.ordslam import find_ordslam
from lorisnb.tools.notebook.indoor_outdoor import ordslam_difficulty, ordslam_stats

QUAT = [0.0, 0.0, 0.0, 1.0]


def _positions(n: int) -> np.ndarray:
    k = np.arange(n, dtype=float)
    return np.column_stack([0.05 * k, np.sin(k / 10), 0.01 * k])  # about 5 cm per key frame


def _write(path: Path, first: np.ndarray, positions: np.ndarray, sep: str = " ") -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    rows = np.column_stack([first, positions, np.tile(QUAT, (len(positions), 1))])
    path.write_text("\n".join(sep.join(f"{v:.6f}" for v in r) for r in rows) + "\n")
    return path


def _noisy(positions: np.ndarray, seed: int = 0) -> np.ndarray:
    return positions + np.random.default_rng(seed).normal(scale=0.01, size=positions.shape)


def test_estimate_in_another_time_base_is_not_scored(tmp_path):
    """Ground truth in Unix seconds, the estimate in seconds from its start: no pose can be matched.
    It used to enter the tables as a sequence tracked 0 % of the time; now it is a 'not scored'
    problem naming the two time spans."""
    p = _positions(100)
    t = 1_600_000_000.0 + 0.2 * np.arange(100)
    _write(tmp_path / "s5_13-00_fill.txt", t, p)
    _write(tmp_path / "s6_13-00_fill.txt", t, p)
    _write(tmp_path / "estimates" / "orb" / "s5_13-00_fill.txt", t - t[0], _noisy(p))
    _write(tmp_path / "estimates" / "orb" / "s6_13-00_fill.txt", t, _noisy(p))
    table, problems = ordslam_difficulty(find_ordslam(tmp_path))
    assert list(table["sequence"]) == ["s6_13-00_fill.txt"] and table["tracked_share"].iloc[0] == pytest.approx(1.0)
    assert list(problems["status"]) == ["not scored"]
    assert problems["file"].iloc[0] == str(tmp_path / "estimates" / "orb" / "s5_13-00_fill.txt")
    err = problems["error"].iloc[0]
    assert "no estimate stamp falls inside the ground truth's time span (estimate 0.000..19.800 s" in err
    assert "ground truth and the estimate need the same time base" in err


def test_groundtruth_sparser_than_max_gap_is_not_scored(tmp_path):
    """Key-frame ground truth one pose a second, the estimate at 30 Hz, max_gap 0.5 s: nothing can
    be associated. Not a 0 % tracked row, but a problem that says what to raise."""
    p = _positions(30)
    _write(tmp_path / "s5_13-00_fill.txt", np.arange(30) + 0.5, p)
    te = 0.5 + np.arange(0, 29 * 30) / 30
    pe = np.column_stack([np.interp(te - 0.5, np.arange(30), p[:, i]) for i in range(3)])
    _write(tmp_path / "estimates" / "orb" / "s5_13-00_fill.txt", te + 1e-4, pe)
    folder = find_ordslam(tmp_path)
    table, problems = ordslam_difficulty(folder, max_gap=0.5)
    assert table.empty and list(problems["status"]) == ["not scored"]
    assert "within max_gap=0.5 s; the ground truth's poses are 1 s apart (median)" in problems["error"].iloc[0]
    table, problems = ordslam_difficulty(folder, max_gap=1.5)
    assert problems.empty and table["ate_rmse_m"].iloc[0] < 1e-3 and table["tracked_share"].iloc[0] > 0.99


def _mixed_rates(root: Path) -> Path:
    """Two sequences of frame numbers, one at 15 fps, one at 30 fps (every 3rd frame marked)."""
    p = _positions(90)
    frames = 3 * np.arange(90)  # 270 frames: 18 s at 15 fps, 9 s at 30 fps
    _write(root / "scenario5" / "08h" / "fill.txt", frames, p, sep=",")
    _write(root / "scenario6" / "22-30" / "std.txt", frames, p, sep=",")
    _write(root / "estimates" / "orb" / "scenario5" / "08h" / "fill.txt", frames, _noisy(p), sep=",")
    _write(root / "estimates" / "orb" / "scenario6" / "22-30" / "std.txt", frames, _noisy(p, 1), sep=",")
    (root / "catalog.csv").write_text("file,scenario,time,depth_mode,fps\nscenario5/08h/fill.txt,5,8,fill,15\n")
    return root


def test_catalog_fps_reads_each_sequence_at_its_own_rate(tmp_path):
    """A folder of mixed frame rates: the catalog's fps column overrides the folder's fps for that
    file and its estimates (one fps for all used to give the 15 fps sequence half its duration)."""
    folder = find_ordslam(_mixed_rates(tmp_path))
    stats = ordslam_stats(folder, fps=30).set_index("sequence")
    assert stats.loc["scenario5/08h/fill.txt", "duration_s"] == pytest.approx(267 / 15)
    assert stats.loc["scenario6/22-30/std.txt", "duration_s"] == pytest.approx(267 / 30)
    assert stats.loc["scenario5/08h/fill.txt", "fps"] == 15 and stats.loc["scenario6/22-30/std.txt", "fps"] == 30
    assert stats.loc["scenario5/08h/fill.txt", "light"] == "day"
    assert stats.loc["scenario6/22-30/std.txt", "group"] == "very difficult"
    table, problems = ordslam_difficulty(folder, fps=30)
    assert problems.empty
    table = table.set_index("sequence")
    assert table.loc["scenario5/08h/fill.txt", "duration_s"] == pytest.approx(267 / 15)
    assert table["tracked_share"].tolist() == pytest.approx([1.0, 1.0])


@pytest.mark.parametrize("value", ["fast", "0", "-15", "inf"])
def test_catalog_bad_fps_names_file_line_row_column(tmp_path, value):
    root = _mixed_rates(tmp_path)
    (root / "catalog.csv").write_text(f"file,scenario,time,depth_mode,fps\nscenario5/08h/fill.txt,5,8,fill,{value}\n")
    with pytest.raises(ParseError, match=rf"catalog.csv, line 2: row 1, column fps: '{value}'; expected a positive"):
        find_ordslam(root)


def test_unreadable_groundtruth_is_listed_not_fatal(tmp_path):
    """A .txt that is no trajectory (a readme of the download) among the ground truth: with a
    problems list it is listed and left out, the other sequences counted."""
    _mixed_rates(tmp_path)
    (tmp_path / "readme.txt").write_text("ORDSLAM dataset\nrecorded with a ZED camera\n")
    folder = find_ordslam(tmp_path)
    with pytest.raises(ParseError, match="readme.txt"):
        ordslam_stats(folder, fps=30)
    problems: list[dict] = []
    stats = ordslam_stats(folder, fps=30, problems=problems)
    assert len(stats) == 2 and [p["file"] for p in problems] == [str(tmp_path / "readme.txt")]
    assert problems[0]["status"] == "failed" and problems[0]["kind"] == "ORDSLAM ground truth"
    assert "readme.txt, line 2" in problems[0]["error"]


@pytest.mark.slow
def test_notebook_on_an_awkward_ordslam_folder(tmp_path):
    from test_notebooks import _kernel, run  # noqa: F401  (the kernel fixture of the notebook tests)

    from lorisnb.tools.report.build import kernel_env

    kernel_env()
    root = _mixed_rates(tmp_path / "ordslam")
    (root / "readme.txt").write_text("ORDSLAM dataset\nrecorded with a ZED camera\n")
    p = _positions(50)
    t = 1_600_000_000.0 + 0.2 * np.arange(50)
    _write(root / "s1_17-00_standard.txt", t, p)
    _write(root / "estimates" / "orb" / "s1_17-00_standard.txt", t - t[0], p)  # another time base
    out = run("indoor_vs_outdoor", tmp_path / "nb", ordslam_dir=str(root), ordslam_fps=30.0)
    errors = pd.read_csv(out / "input_errors.csv").set_index("file")
    assert errors.loc[str(root / "readme.txt"), "status"] == "failed"
    assert errors.loc[str(root / "estimates" / "orb" / "s1_17-00_standard.txt"), "status"] == "not scored"
    stats = pd.read_csv(out / "trajectory_stats.csv").query("dataset == 'ORDSLAM'").set_index("sequence")
    assert stats.loc["scenario5/08h/fill.txt", "duration_s"] == pytest.approx(267 / 15)
    assert stats.loc["s1_17-00_standard.txt", "light"] == "dusk"
    meas = pd.read_csv(out / "difficulty_per_sequence.csv").query("dataset == 'ORDSLAM'")
    assert sorted(meas["sequence"]) == ["scenario5/08h/fill.txt", "scenario6/22-30/std.txt"]
    text = (tmp_path / "nb" / "indoor_vs_outdoor.ipynb").read_text()
    assert f"ORDSLAM (your folder, every scenario with an estimate): {meas['ate_pct_length'].median():.2f} %." in text


def test_upper_case_names_are_read_and_hidden_folders_are_not(tmp_path):
    """``S5_13-00_FILL.TXT`` and its estimate were passed over without a word (a case-sensitive
    ``*.txt``), and the copy JupyterLab keeps in ``.ipynb_checkpoints`` was read as a sequence."""
    p = _positions(100)
    t = 1_600_000_000.0 + 0.2 * np.arange(100)
    _write(tmp_path / "S5_13-00_FILL.TXT", t, p)
    _write(tmp_path / "s6_20h_std.txt", t, p)
    _write(tmp_path / ".ipynb_checkpoints" / "s6_20h_std-checkpoint.txt", t, p)
    _write(tmp_path / "~s6_20h_std.txt", t, p)
    _write(tmp_path / "estimates" / "orb" / "S5_13-00_FILL.TXT", t, _noisy(p))
    _write(tmp_path / "estimates" / "orb" / ".ipynb_checkpoints" / "x-checkpoint.txt", t, _noisy(p))
    folder = find_ordslam(tmp_path)
    assert [g.name for g in folder.groundtruth] == ["S5_13-00_FILL.TXT", "s6_20h_std.txt"]
    assert [e.name for e in folder.estimates["orb"]] == ["S5_13-00_FILL.TXT"]
    table, problems = ordslam_difficulty(folder)
    assert list(table["sequence"]) == ["S5_13-00_FILL.TXT"] and problems.empty
