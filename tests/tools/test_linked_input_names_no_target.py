"""An input found through a link leading outside the results folder (the file itself, or an
algorithm folder above it) that fails to parse: its error said where the link leads (``(a link to
/elsewhere/x.txt`` or ``(in a linked folder, at /tmp/sëcret dir/sub/cafe-1-2-odom.txt``), and a report
run kept the second in findings/input_errors.csv, index.html and report.html. It names the input as
found below the results folder and says ``a link leading outside the results folder``, never where."""

from __future__ import annotations

import os
import shutil
import unicodedata
import warnings

import pytest

from lorisnb.cli import main

SECRET = "SECRETLINE x\n"


def _received(tmp_path, icra20, target):
    """A results folder ``res`` (orbslam2_rgbd copied) whose ``odom`` results, one bad file among
    them, lie in ``sëcret dir/sub`` outside it: the folder linked in, or the file alone."""
    elsewhere = tmp_path / "sëcret dir" / "sub"
    elsewhere.mkdir(parents=True)
    bad = elsewhere / "cafe-1-2-odom.txt"
    bad.write_text(SECRET + (icra20 / "per-seq" / "odom" / "cafe-1-2-odom.txt").read_text())
    res = tmp_path / "res"
    shutil.copytree(icra20 / "per-seq" / "orbslam2_rgbd", res / "orbslam2_rgbd")
    if target == "folder":
        (res / "odom").symlink_to(elsewhere, target_is_directory=True)
    else:
        (res / "odom").mkdir()
        (res / "odom" / bad.name).symlink_to(bad)
    return res, elsewhere


def _leaks(text: str, elsewhere) -> bool:
    """Whether ``text`` names the folder the link leads to (any Unicode form, or its name alone)."""
    return any(unicodedata.normalize(f, s) in text for f in ("NFC", "NFD") for s in (str(elsewhere), "sëcret"))


@pytest.mark.parametrize("target", ["folder", "file"])
@pytest.mark.parametrize("given", ["absolute", "relative"])
def test_an_error_about_an_input_found_through_a_link_names_it_as_found(
    tmp_path, data, icra20, capsys, monkeypatch, target, given
):
    res, elsewhere = _received(tmp_path, icra20, target)
    monkeypatch.chdir(tmp_path)
    rc = main(["evaluate", str(res) if given == "absolute" else "res", "--data", str(data.root), "--no-progress"])
    err = capsys.readouterr().err
    found = (res if given == "absolute" else res.relative_to(tmp_path)) / "odom" / "cafe-1-2-odom.txt"
    how = "in the folder odom, a link leading" if target == "folder" else "a link leading"
    assert rc == 1 and (f"error: {found}, line 1: not a trajectory file as expected ({how} outside the results "
                        "folder: its content is not shown)") in err, err  # fmt: skip
    assert not _leaks(err, elsewhere) and "SECRETLINE" not in err, err


def test_a_report_run_holds_no_path_a_linked_folder_leads_to(tmp_path, data, icra20, monkeypatch):
    """The tester's repro: ``lorisnb report --results res`` whose ``odom`` folder is linked from
    ``sëcret dir/sub``: no file of the run names that folder (its input errors, index.html,
    report.html, the notebook's table), and the failure is listed with its path below {results}."""
    res, elsewhere = _received(tmp_path, icra20, "folder")
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "runs" / "r7"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rc = main(["report", "--results", "res", "--data", str(data.root), "--out", str(out), "--no-progress",
                   "--notebooks", "per_sequence_benchmark"])  # fmt: skip
    assert rc in (0, 1), rc
    errors = (out / "findings" / "input_errors.csv").read_text()
    assert ("{results}/odom/cafe-1-2-odom.txt, line 1: not a trajectory file as expected (in the folder odom, a link "
            "leading outside the results folder: its content is not shown)") in errors, errors  # fmt: skip
    for p in (x for x in out.rglob("*") if x.is_file()):
        text = p.read_bytes().decode("utf-8", "replace")
        assert not _leaks(text, elsewhere) and "SECRETLINE" not in text, p
    assert "in the folder odom, a link leading outside" in (out / "index.html").read_text()


def test_a_loop_below_a_linked_results_folder_is_named_as_found(tmp_path, data, icra20):
    """A results folder reached through a link (``lab`` -> ``sëcret dir/res``) holding a link back to
    a folder it is in: the warning named the loop's target by its real path, inside ``sëcret dir``;
    it names it as found, below ``lab``."""
    import lorisnb as ln

    real = tmp_path / "sëcret dir" / "res"
    shutil.copytree(icra20 / "per-seq" / "orbslam2_rgbd", real / "orbslam2_rgbd")
    (real / "orbslam2_rgbd" / "again").symlink_to(real, target_is_directory=True)
    lab = tmp_path / "lab"
    lab.symlink_to(real, target_is_directory=True)
    with pytest.warns(ln.LorisWarning, match="lead back to a folder they are in") as caught:
        ev = ln.evaluate(lab, data_root=data, scenes=["cafe"], progress=False, jobs=1)
    said = [str(w.message) for w in caught if "lead back" in str(w.message)]
    assert said == [f"1 linked folder(s) lead back to a folder they are in, not walked again: "
                    f"{lab / 'orbslam2_rgbd' / 'again'} -> {lab}"], said  # fmt: skip
    assert not _leaks(said[0], real.parent) and len(ev.errors) == 2
    assert os.path.realpath(lab) == str(real)
