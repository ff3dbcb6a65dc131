"""``lorisnb evaluate``'s printed tables: scored without the error statistics unless printed (evo's
conventions print some), the same text as the table that is written with ``--csv``."""

from __future__ import annotations

import pandas as pd

from lorisnb.cli import main


def _printed(capsys, args: list[str]) -> str:
    assert main(["evaluate", *args, "--no-progress"]) == 0
    return capsys.readouterr().out


def test_printed_without_statistics_as_with_the_written_table(icra20, tmp_path, capsys):
    """Real icra20 results: the per-sequence and per-scene tables printed from the lean rows (no
    ``--csv``) are the text printed from the full table when one is written."""
    args = [str(icra20 / "lifelong" / "maslam"), str(icra20 / "lifelong" / "orbslam2_t265"), "--scale", "auto"]
    lean = _printed(capsys, args)
    full = _printed(capsys, [*args, "--csv", str(tmp_path / "t.csv")])
    assert lean == full and "per scene" in lean and lean.count("maslam") >= 10
    table = pd.read_csv(tmp_path / "t.csv")
    assert len(table) == 30 and table["ate_median"].notna().sum() >= 10  # the statistics written
    assert "ate_median" not in lean


def test_evo_conventions_print_their_statistics(data, tmp_path, capsys):
    """Under evo's conventions the printed rows keep evo's statistics (ate_mean, ate_median,
    ate_max), the values of the table written."""
    g, e = data.tum / "fr2_desk_groundtruth.txt", data.tum / "fr2_desk_ORB.txt"
    args = [str(e), "--gt", str(g), "--conventions", "evo"]
    lean = _printed(capsys, args)
    full = _printed(capsys, [*args, "--csv", str(tmp_path / "t.csv")])
    assert lean == full and "ate_median" in lean
    row = pd.read_csv(tmp_path / "t.csv").iloc[0]
    assert f"{row['ate_median']:.4f}" in lean and row["ate_median"] > 0


def _kept_poses(monkeypatch, argv: list[str]) -> list[bool]:
    """``keep_poses`` of each evaluation a command line runs (the real evaluation, recorded)."""
    from lorisnb.tools.evaluation import runner

    seen: list[bool] = []
    real = runner.evaluate, runner.evaluate_pairs

    def recording(fn):
        def run(*args, **kwargs):
            seen.append(kwargs.get("keep_poses", True))
            return fn(*args, **kwargs)

        return run

    monkeypatch.setattr(runner, "evaluate", recording(real[0]))
    monkeypatch.setattr(runner, "evaluate_pairs", recording(real[1]))
    assert main([*argv, "--no-progress"]) in (0, 1)
    return seen


def test_commands_that_read_only_tables_have_only_the_scores_sent_back(icra20, data, tmp_path, monkeypatch, capsys):
    """``evaluate`` printing or writing its table, ``compare`` and ``diff`` of result folders let the
    workers send back only the scores (``keep_poses=False``); ``--relative``, KITTI's preset and
    ``sweep`` (another setting per grid point) keep each pose's errors; the printed text is the
    same either way."""
    folder = str(icra20 / "lifelong" / "maslam")
    g, e = str(data.tum / "fr2_desk_groundtruth.txt"), str(data.tum / "fr2_desk_ORB.txt")
    assert _kept_poses(monkeypatch, ["evaluate", folder, "--csv", str(tmp_path / "t.csv")]) == [False]
    assert _kept_poses(monkeypatch, ["compare", folder]) == [False]
    assert _kept_poses(monkeypatch, ["diff", folder, folder]) == [False, False]
    assert _kept_poses(monkeypatch, ["evaluate", e, "--gt", g, "--relative"]) == [True]
    assert _kept_poses(monkeypatch, ["evaluate", e, "--gt", g, "--conventions", "kitti"]) == [True]
    assert _kept_poses(monkeypatch, ["sweep", folder, "--eps", "1,2", "--phi", "10"]) == [True]
    capsys.readouterr()
    lean = _printed(capsys, [folder])
    monkeypatch.setattr("lorisnb.cli.commands.tables_only", lambda spec: True)  # every pose kept: the same text
    assert _printed(capsys, [folder]) == lean


def test_printing_the_table_imports_no_pandas(icra20):
    """``lorisnb evaluate`` printing its table (no ``--csv``) reads the lean rows: pandas is not
    imported in its process (beside the workers it took a core from them), while a table written
    with ``--csv`` imports it. Real icra20 files, in a fresh interpreter, in parallel (forked workers)."""
    import subprocess
    import sys
    import tempfile
    from pathlib import Path

    folder = icra20 / "lifelong" / "maslam"
    probe = (
        "import sys, os; from lorisnb.cli import main; "
        "sys.stdout = open(os.devnull, 'w'); sys.stderr = open(os.devnull, 'w'); "
        f"rc = main(['evaluate', {str(folder)!r}, '--scale', 'auto', '--no-progress', '--jobs', '2', *sys.argv[1:]]); "
        "sys.__stdout__.write(f\"{rc} {'pandas' in sys.modules}\")"
    )

    def run(*more: str) -> str:
        return subprocess.run([sys.executable, "-c", probe, *more], capture_output=True, text=True, check=True,
                              timeout=300).stdout  # fmt: skip

    assert run() == "0 False"
    with tempfile.TemporaryDirectory() as tmp:
        assert run("--csv", str(Path(tmp) / "t.csv")) == "0 True"
