"""``diff`` of two result folders that share no algorithm: two identical folders holding their
result files directly (no ``<algorithm>/`` folder) made each file's algorithm its folder's name,
``base`` and ``cand``, and were judged a regression (every BASE sequence missing, every CAND one
new). It is refused, saying why and what to do."""

from __future__ import annotations

import shutil

from lorisnb.cli import main


def test_two_flat_result_folders_are_refused_not_judged_a_regression(icra20, tmp_path, capsys):
    src = icra20 / "per-seq" / "orbslam2_rgbd"
    for side in ("base", "cand"):
        (tmp_path / side).mkdir()
        for f in sorted(src.glob("cafe*.txt")):
            shutil.copy(f, tmp_path / side / f.name)
    rc = main(["diff", str(tmp_path / "base"), str(tmp_path / "cand"), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2, err
    assert "BASE and CAND share no algorithm (BASE: base; CAND: cand)" in err
    assert "result files directly in a folder you gave are one algorithm named after that folder (base/, cand/)" in err
    # the same files in a folder named for the algorithm on each side: judged, identical, ok
    for side in ("base", "cand"):
        (tmp_path / side / "orb").mkdir()
        for f in (tmp_path / side).glob("*.txt"):
            f.rename(tmp_path / side / "orb" / f.name)
    rc = main(["diff", str(tmp_path / "base"), str(tmp_path / "cand"), "--no-progress"])
    out = capsys.readouterr()
    assert rc == 0 and "verdict: ok" in out.out, out.out + out.err


def test_a_renamed_algorithm_is_refused_with_its_names(icra20, tmp_path, capsys):
    for side, alg in (("base", "orb"), ("cand", "orb2")):
        shutil.copytree(icra20 / "per-seq" / "orbslam2_rgbd", tmp_path / side / alg)
    rc = main(["diff", str(tmp_path / "base"), str(tmp_path / "cand"), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and "share no algorithm (BASE: orb; CAND: orb2)" in err and "lorisnb compare" in err, err
