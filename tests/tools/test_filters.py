"""A ``scenes`` or ``algorithms`` filter that names nothing in the inputs is refused (trial finding
6), by one validator (``lorisnb.core.spec.validate.present``) behind every entry point: Python's
``evaluate``, ``lorisnb report -p scenes/algorithms`` (before any notebook runs) and the notebooks
(through ``evaluate``); a notebook's ``results_dir`` must exist. It used to drop every input and
say "no input file was found"."""

from __future__ import annotations

import shutil

import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.spec import validate
from lorisnb.errors import ValidationError
from lorisnb.tools.notebook.params import check_values
from lorisnb.tools.notebook.start import setup


@pytest.fixture
def results(tmp_path, icra20):
    """orbslam2 and odom on cafe 1 and home 1 (real files)."""
    res = tmp_path / "results"
    for alg, names in {
        "orbslam2_rgbd": ["cafe_1_1_orbslam2-original.txt", "home_1_1_orbslam2-original.txt"],
        "odom": ["cafe-1-1-odom.txt", "home-1-1-odom.txt"],
    }.items():
        (res / alg).mkdir(parents=True)
        for n in names:
            shutil.copy(icra20 / "per-seq" / alg / n, res / alg / n)
    return res


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        (dict(scenes=["nope"]), r"scenes: 'nope' name\(s\) nothing in the inputs, which hold scenes: cafe, home$"),
        (dict(scenes=["Cafe"]), r"hold scenes: cafe, home; 'Cafe': did you mean 'cafe'\? \(names are case-sensitive\)"),
        (dict(scenes="office"), r"'office' name\(s\) nothing .* scenes: cafe, home"),
        (dict(scenes=["cafe", "market"]), r"'market' name\(s\) nothing"),
        (dict(algorithms=["nope"]), r"algorithms: 'nope' .* which hold algorithms: odom, orbslam2_rgbd$"),
        (dict(algorithms=["ODOM"]), r"'ODOM': did you mean 'odom'\? \(names are case-sensitive\)"),
        (dict(algorithms=["orbslam2_rgb"]), r"'orbslam2_rgb': did you mean 'orbslam2_rgbd'\?$"),
        (dict(algorithms=["odom"], scenes=["market"]), r"'market' name\(s\) nothing .* scenes: cafe, home"),
    ],
)
def test_a_filter_naming_nothing_is_refused(results, kw, message):
    with pytest.raises(ValidationError, match=message):
        ln.evaluate(results, **kw)


def test_filters_that_name_inputs_keep_exactly_them(results):
    ev = ln.evaluate(results, scenes=["home"], algorithms=["odom"])
    assert [(f.algorithm, f.scene) for f in ev.errors] == [("odom", "home")] and not ev.failures
    assert ev.sequences()["cr"].between(0, 1).all() and ev.exit_status() == 0


def test_the_validator_alone():
    assert validate.present("scenes", ["cafe"], ["home", "cafe", "cafe"]) == ["cafe"]
    with pytest.raises(ValidationError, match=r"which hold scenes: none"):
        validate.present("scenes", ["cafe"], [])


def test_report_refuses_before_any_notebook_runs(results, tmp_path, capsys):
    for name, value, want in (
        ("scenes", '["nope"]', "'nope' name(s) nothing in the inputs, which hold scenes: cafe, home"),
        ("scenes", '["Cafe"]', "did you mean 'cafe'?"),
        ("algorithms", '["nope"]', "which hold algorithms: odom, orbslam2_rgbd"),
        ("scenes", "5", "expected a name or a list of names"),
    ):
        out = tmp_path / f"run-{name}-{len(value)}"
        assert main(["report", "--results", str(results), "--out", str(out), "-p", name, value, "--no-progress"]) == 2
        assert want in capsys.readouterr().err and not out.exists()


def test_notebook_parameters_checked_by_setup(tmp_path):
    for params, want in (
        ({"results_dir": str(tmp_path / "missing")}, "results_dir=.*missing: no such folder"),
        ({"path": str(tmp_path / "missing.txt")}, "path=.*: no such file or folder"),
        ({"scenes": 3}, "scenes=3: expected a name or a list of names"),
        ({"quick": "maybe"}, "quick='maybe' .*expected True or False"),
    ):
        with pytest.raises(ValidationError, match=want):
            setup("per_sequence_benchmark", output_dir=tmp_path / "nb", parameters=params)
        with pytest.raises(ValidationError, match=want):
            check_values(params)
    assert not (tmp_path / "nb").exists()  # refused before the output folder is made


def test_a_file_of_a_scene_without_ground_truth_is_skipped_unread(tmp_path, icra20, monkeypatch):
    """A result file whose ``scene:`` header names a scene with no ground truth in the data (office:
    not public) is skipped from its header, before its poses are read (69 of the bundled tree's
    223 files): the skip says why as before; a file whose header names no scene is still read."""
    from lorisnb.tools.evaluation import jobs

    res = tmp_path / "results" / "odom"
    res.mkdir(parents=True)
    office = shutil.copy(icra20 / "per-seq" / "odom" / "office-1-1-odom.txt", res / "office-1-1-odom.txt")
    shutil.copy(icra20 / "per-seq" / "odom" / "cafe-1-1-odom.txt", res / "cafe-1-1-odom.txt")
    read = []
    real = jobs.read_openloris
    monkeypatch.setattr(jobs, "read_openloris", lambda path, **kw: read.append(path.name) or real(path, **kw))
    ev = ln.evaluate(tmp_path / "results", jobs=1)
    assert read == ["cafe-1-1-odom.txt"]
    assert [f.path.name for f in ev.skipped] == ["office-1-1-odom.txt"]
    assert "ground truth of scene 'office' not found" in ev.skipped[0].error
    text = open(office).read().replace("scene: office", "")  # no scene named: read in full, which says why
    open(office, "w").write(text)
    ev = ln.evaluate(tmp_path / "results", jobs=1)
    assert "office-1-1-odom.txt" in read and [f.path.name for f in ev.failures] == ["office-1-1-odom.txt"]
