"""An output option that writes a file refuses a path ending in a slash (a folder's name):
``--csv outs/new.csv/`` wrote a file ``outs/new.csv`` (pathlib drops the slash). Folder options
(``--parquet``, ``history --out``) take it (adversarial finding 7)."""

from __future__ import annotations

import pytest

from lorisnb.cli import main

TUM = "tum-rgbd"


@pytest.mark.parametrize("option", ["--csv", "--parquet"])
def test_a_file_option_refuses_a_trailing_slash(data, tmp_path, capsys, option):
    est, gt = str(data.root / TUM / "fr2_desk_ORB.txt"), str(data.root / TUM / "fr2_desk_groundtruth.txt")
    name = "new.csv" if option == "--csv" else "new_pq"
    rc = main(["evaluate", est, "--gt", gt, option, str(tmp_path / "outs" / name) + "/", "--no-progress"])
    err = capsys.readouterr().err
    if option == "--parquet":  # a folder option: the slash is what it means
        pytest.importorskip("pyarrow")
        assert rc == 0 and (tmp_path / "outs" / name).is_dir(), err
        return
    assert rc == 2, err
    assert f"--csv {tmp_path / 'outs' / name}/: ends in a slash, which names a folder; --csv writes a file" in err
    assert not (tmp_path / "outs").exists()  # nothing written, no folder made


def test_every_file_output_of_diff_refuses_it(data, tmp_path, capsys):
    (tmp_path / "orb").mkdir()
    (tmp_path / "orb" / "desk.txt").write_bytes((data.root / TUM / "fr2_desk_ORB.txt").read_bytes())
    gt = str(data.root / TUM / "fr2_desk_groundtruth.txt")
    for option, name in (("--json", "v.json"), ("--junit", "v.xml"), ("--markdown", "v.md"), ("--badge", "b.svg")):
        rc = main(
            ["diff", str(tmp_path / "orb"), str(tmp_path / "orb"), "--gt", gt, option, str(tmp_path / name) + "/"]
        )
        assert rc == 2 and "ends in a slash" in capsys.readouterr().err, option
        assert not (tmp_path / name).exists()
