"""Options that cannot change a command's result are refused by it (exit 2, naming the option and
what to use), never accepted with exit 0 while only the ``spec`` text changes: the KITTI and
TartanAir preset options change only their own columns, which sweep's table, compare's metrics and
diff's comparison do not hold (adversarial finding 4)."""

from __future__ import annotations

import shutil

import pandas as pd
import pytest

from lorisnb.cli import main

TUM = "tum-rgbd"


@pytest.fixture(scope="module")
def pair(data, tmp_path_factory):
    """The real fr2_desk pair: an algorithm folder of one estimate, and its ground truth."""
    d = tmp_path_factory.mktemp("pair")
    (d / "orb").mkdir()
    shutil.copy(data.root / TUM / "fr2_desk_ORB.txt", d / "orb" / "fr2_desk.txt")
    return d, str(data.root / TUM / "fr2_desk_groundtruth.txt")


def _run(argv: list[str], capsys) -> tuple[int, str]:
    capsys.readouterr()
    try:
        rc = main([*argv, "--no-progress", "--jobs", "1"])
    except SystemExit as exc:
        rc = int(exc.code or 0)
    return rc, capsys.readouterr().err


PRESET_OPTIONS = [
    ("tartanair", ["--tartanair-scale"]),
    ("tartanair", ["--tartanair-seed", "0"]),  # 0 too: a value given, not an option left out
    ("tartanair", ["--tartanair-seed", "4"]),
    ("kitti", ["--kitti-precision", "double"]),
]


@pytest.mark.parametrize(("preset", "option"), PRESET_OPTIONS)
@pytest.mark.parametrize("command", ["sweep", "compare", "diff"])
def test_preset_options_are_refused_where_no_column_holds_them(command, preset, option, pair, tmp_path, capsys):
    folder, gt = pair
    paths = [str(folder), str(folder)] if command == "diff" else [str(folder)]
    argv = [command, *paths, "--gt", gt, "--conventions", preset]
    out = tmp_path / "t.csv"
    rc, err = _run([*argv, *option, "--csv", str(out)], capsys)
    assert rc == 2, err[-500:]
    assert f"error: {option[0]}: not used by lorisnb {command}; use lorisnb evaluate --conventions {preset}" in err
    assert not out.exists()  # refused before any work
    rc, err = _run([*argv, "--csv", str(out)], capsys)  # without it: the command runs
    assert rc == 0, err[-500:]


def test_evaluate_still_takes_them_and_they_change_its_tartanair_columns(pair, tmp_path, capsys):
    """The control: where the columns are (evaluate's table), the options change their numbers."""
    folder, gt = pair
    base = ["evaluate", str(folder), "--gt", gt, "--conventions", "tartanair"]
    assert _run([*base, "--csv", str(tmp_path / "a.csv")], capsys)[0] == 0
    assert _run([*base, "--tartanair-scale", "--csv", str(tmp_path / "b.csv")], capsys)[0] == 0
    a, b = pd.read_csv(tmp_path / "a.csv"), pd.read_csv(tmp_path / "b.csv")
    assert a["tartanair_ate"].iloc[0] != b["tartanair_ate"].iloc[0]
    assert a["cr"].iloc[0] == b["cr"].iloc[0] and a["ate_rmse"].iloc[0] == b["ate_rmse"].iloc[0]
    assert a["tartanair_ate"].iloc[0] == pytest.approx(0.00814, abs=1e-4)  # metres: fr2_desk ORB, 8 mm


def test_help_of_sweep_compare_diff_offers_none_of_them(capsys):
    for command in ("sweep", "compare", "diff"):
        with pytest.raises(SystemExit):
            main([command, "--help"])
        text = capsys.readouterr().out
        assert "--tartanair-scale" not in text and "--kitti-precision" not in text, command
