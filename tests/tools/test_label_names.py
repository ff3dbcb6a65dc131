"""Names: algorithm, scene and file labels are compared and grouped as Unicode NFC (a folder
named in NFD on macOS and one typed in NFC are one algorithm), and control characters in a
name are escaped where the terminal shows them (tables and lines keep their rows)."""

from __future__ import annotations

import shutil
import unicodedata

import lorisnb as ln
from lorisnb.cli import main

NFC, NFD = unicodedata.normalize("NFC", "algé"), unicodedata.normalize("NFD", "algé")
FILES = ("cafe_1_1_orbslam2-original.txt", "cafe_1_2_orbslam2-original.txt")


def two_spellings(root, icra20):
    assert NFC != NFD and len(NFC) == 4 and len(NFD) == 5
    for folder, name in zip((NFC, NFD), FILES, strict=True):
        (root / folder).mkdir(parents=True)
        shutil.copy(icra20 / "per-seq" / "orbslam2_rgbd" / name, root / folder / name)
    return root


def test_one_algorithm_whatever_the_normal_form_of_its_folder_name(tmp_path, data, icra20, capsys):
    res = two_spellings(tmp_path / "res", icra20)
    ev = ln.evaluate(res, data_root=data, progress=False)
    table = ev.sequences()
    assert list(table["algorithm"].unique()) == [NFC] and len(table) == 2
    one = ln.evaluate(icra20 / "per-seq" / "orbslam2_rgbd", data_root=data, progress=False).sequences()
    for name in FILES:  # the same values as the files scored under their own folder: only the label changed
        mine = table[table["file"].str.endswith(name)].iloc[0]
        theirs = one[one["file"].str.endswith(name)].iloc[0]
        assert mine["ate_rmse"] == theirs["ate_rmse"] and mine["cr"] == theirs["cr"]
    scenes = ev.scenes()
    assert (scenes["algorithm"] == NFC).all() and len(scenes) == 1  # grouped as one
    kept = ln.evaluate(res, data_root=data, progress=False, algorithms=[NFD]).sequences()
    assert len(kept) == 2  # a filter typed in NFD names the NFC label
    rc = main(["evaluate", str(res), "--data", str(data.root), "--no-progress"])
    out = capsys.readouterr().out
    assert rc == 0 and out.count(NFC) >= 3 and NFD not in out  # two sequences and one scene row, one name


def test_control_characters_in_a_name_are_escaped_in_terminal_tables(tmp_path, data, icra20, capsys):
    res = tmp_path / "res"
    bad = "orb\nslam\x1b[31m"
    (res / bad).mkdir(parents=True)
    shutil.copy(icra20 / "per-seq" / "orbslam2_rgbd" / FILES[0], res / bad / FILES[0])
    rc = main(["evaluate", str(res), "--data", str(data.root), "--no-progress"])
    out = capsys.readouterr().out
    assert rc == 0 and "orb\\nslam\\x1b[31m" in out and "\x1b" not in out
    lines = out.splitlines()
    row = next(line for line in lines if "orb\\nslam" in line)
    assert "cafe" in row  # the name and the rest of its row on one line


def test_tables_written_with_either_normal_form_are_one_algorithm_to_diff(tmp_path, data, icra20, capsys):
    """A table written where the folder was NFD (an older lorisnb, another tool) against one in NFC:
    diff compares the algorithm's sequences, it does not call them missing and added."""
    res = tmp_path / "res" / NFC
    res.mkdir(parents=True)
    shutil.copy(icra20 / "per-seq" / "orbslam2_rgbd" / FILES[0], res / FILES[0])
    table = ln.evaluate(res.parent, data_root=data, progress=False).sequences()
    table.to_csv(tmp_path / "nfc.csv", index=False)
    table.assign(algorithm=NFD).to_csv(tmp_path / "nfd.csv", index=False)
    from lorisnb.tools.decisions.runs import read_table

    assert list(read_table(tmp_path / "nfd.csv")["algorithm"]) == [NFC]
    rc = main(["diff", str(tmp_path / "nfc.csv"), str(tmp_path / "nfd.csv")])
    out = capsys.readouterr().out
    assert rc == 0 and "verdict: ok" in out and "regressed" not in out
