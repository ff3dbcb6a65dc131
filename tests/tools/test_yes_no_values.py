"""Yes/no values and lists (trial finding 11): ``progress`` and a notebook's ``quick`` go through the
flag validator (a string is refused, never truth-tested); ``quick`` never drops a grid the user
gave; a comma list with an empty item is refused; a negative value after an option reaches the
option's validator (``--eps -1,1``) instead of argparse's "expected one argument"."""

from __future__ import annotations

import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.spec import validate
from lorisnb.errors import ValidationError
from lorisnb.tools.notebook.grids import GRIDS, notebook_grids
from lorisnb.tools.notebook.params import check_values


def test_progress_is_a_flag(icra20, capsys):
    one = icra20 / "per-seq" / "odom" / "cafe-1-1-odom.txt"
    for value in ("no", "false", 0, 1, None):
        with pytest.raises(ValidationError, match=r"progress=.*expected True or False"):
            ln.evaluate(one, progress=value)
    ev = ln.evaluate(one, progress=False)
    assert len(ev.errors) == 1 and "evaluating" not in capsys.readouterr().err  # no bar


def test_quick_is_a_flag_and_never_drops_a_given_grid():
    for value in ("maybe", "yes", 1, None):
        with pytest.raises(ValidationError, match="quick=.*expected True or False"):
            notebook_grids("threshold_sensitivity", value)
        if value is not None:
            with pytest.raises(ValidationError, match="quick="):
                check_values({"quick": value})
    mine = notebook_grids("threshold_sensitivity", True, eps_grid=[0.25, 2], phi_grid="15,45")
    assert mine["eps_grid"] == [0.25, 2.0] and mine["phi_grid"] == [15.0, 45.0]  # given: kept, quick or not
    assert mine["delta_grid"] == GRIDS["threshold_sensitivity"]["delta_grid"][1]  # not given: the quick default
    full = notebook_grids("compare_algorithms", False)
    assert full == {k: v[0] for k, v in GRIDS["compare_algorithms"].items()}
    with pytest.raises(ValidationError, match="eps_grid=-1"):
        notebook_grids("threshold_sensitivity", True, eps_grid=[-1, 2])
    with pytest.raises(ValidationError, match=r"relative_grid=5(\.0)?: a fraction .* at most 1"):
        notebook_grids("threshold_sensitivity", True, relative_grid=[0.1, 5])
    with pytest.raises(ValidationError, match="tau_grid: not a grid of compare_algorithms"):
        notebook_grids("compare_algorithms", True, tau_grid=[10])


@pytest.mark.parametrize("text", ["1,,2", "1,2,", ",1", " , "])
def test_an_empty_list_item_is_refused(text):
    with pytest.raises(ValidationError, match="an empty item between commas|an empty list"):
        validate.threshold_list("eps", text)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--eps", "1,,2"], "argument --eps: eps=1,,2: an empty item between commas"),
        (["--eps", "-1,1"], "argument --eps: eps=-1: expected 'paper', 'relative:F', a number of metres >= 0"),
        (["--eps=-1,1"], "argument --eps: eps=-1: expected 'paper', 'relative:F', a number of metres >= 0"),
        (["--phi", "-inf"], "argument --phi: phi=-inf: expected a number of degrees >= 0"),
        (["--delta", "-1e-3,1"], "argument --delta: delta=-1e-3: expected a number of seconds > 0"),
    ],
)
def test_sweep_lists_reach_their_validator(icra20, capsys, args, message):
    with pytest.raises(SystemExit) as exc:
        main(["sweep", str(icra20 / "per-seq" / "odom" / "cafe-1-1-odom.txt"), *args, "--no-progress"])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and message in err and "expected one argument" not in err


def test_a_negative_value_that_is_valid_is_taken(icra20, tmp_path, capsys):
    """``--t-offset -1e-3`` (argparse alone took it for an option) shifts the estimate's clock."""
    one = icra20 / "per-seq" / "odom" / "cafe-1-1-odom.txt"
    csv = tmp_path / "t.csv"
    assert main(["evaluate", str(one), "--t-offset", "-1e-3", "--csv", str(csv), "--no-progress"]) == 0
    capsys.readouterr()
    got = pd.read_csv(csv).iloc[0]
    want = ln.evaluate(one, t_offset=-1e-3).sequences().iloc[0]
    assert got["matched"] == want["matched"] > 0 and got["ate_rmse"] == pytest.approx(want["ate_rmse"], rel=1e-9)


def test_quick_keeps_a_count_given():
    from lorisnb.tools.notebook.grids import quick_default

    assert quick_default("sim_trials", None, 6, 5, True) == 5 and quick_default("sim_trials", None, 6, 5, False) == 6
    assert quick_default("sim_trials", 8, 6, 5, True) == 8  # given: kept, quick or not
    for bad in (0, 2.5, -3):
        with pytest.raises(ValidationError, match="sim_trials=.*positive whole number"):
            quick_default("sim_trials", bad, 6, 5, True)


@pytest.mark.parametrize(
    ("name", "values", "said"),
    [("eps", "1,1", "1 and 1"), ("eps", "inf,Infinity", "inf and Infinity"), ("tau", [60, 60.0], "60 and 60.0"),
     ("delta", "0.5,1,0.50", "0.5 and 0.50"), ("eps", ["paper", 1, "paper"], "paper and paper")],
)  # fmt: skip
def test_a_value_twice_in_a_list_is_refused_everywhere(icra20, capsys, name, values, said):
    """``sweep --eps 1,1`` printed its rows and then failed on "several results" (exit 2), and
    ``ln.sweep(errors, eps=[1, 1])`` returned every row twice: one check refuses a setting given
    twice, for the command line, Python's sweep and the notebooks' grids."""
    with pytest.raises(ValidationError, match=f"{said} are the same value; expected each value once"):
        validate.threshold_list(name, values)
    one = icra20 / "per-seq" / "odom" / "cafe-1-1-odom.txt"
    with pytest.raises(ValidationError, match="are the same value"):
        ln.sweep(ln.evaluate(one, progress=False).errors, **{name: values})
    with pytest.raises(ValidationError, match="are the same value"):
        notebook_grids("threshold_sensitivity", False, **{f"{name}_grid": values})
    if isinstance(values, str):
        with pytest.raises(SystemExit) as exc:
            main(["sweep", str(one), f"--{name}", values, "--no-progress"])
        assert exc.value.code == 2 and f"{said} are the same value" in capsys.readouterr().err


def test_digits_are_decimals_a_float_holds(icra20, capsys):
    """``--digits 100`` printed 100 decimals of float noise; 0 (whole numbers) was refused."""
    one = str(icra20 / "per-seq" / "odom" / "cafe-1-1-odom.txt")
    for bad in ("18", "100", "-1", "2.5", "nan"):
        with pytest.raises(SystemExit):
            main(["evaluate", one, f"--digits={bad}", "--no-progress"])
        assert "expected a whole number of decimals from 0 to 17" in capsys.readouterr().err
    assert main(["evaluate", one, "--digits", "0", "--no-progress"]) == 0
    row = capsys.readouterr().out.splitlines()[1].split()  # the sequence row: whole numbers, no point
    assert row[0] == "odom" and all("." not in v for v in row[5:])


@pytest.mark.parametrize(
    ("notebook", "parameters", "said"),
    [
        ("evo_crosscheck", {"all_files": "no"}, "all_files='no' \\(str\\): expected True or False"),
        ("indoor_vs_outdoor", {"rpe_metres": -1}, "rpe_metres=-1: expected a positive number of metres"),
        ("indoor_vs_outdoor", {"relative_to": "bogus"}, "relative_to=bogus: expected one of extent, length"),
        ("indoor_vs_outdoor", {"ordslam_fps": 30}, "-p ordslam_fps: only applies with -p ordslam_dir"),
        ("evaluate_my_results", {"fmt": "kitti"}, "-p fmt: only applies with -p groundtruth"),
        ("evaluate_my_results", {"conventions": "tumm"}, "conventions=tumm: expected one of"),
        ("compare_algorithms", {"sim_trials": -3}, "sim_trials=-3: expected a positive whole number"),
        ("metrics_primer", {"scene": "kitchen"}, "scene=kitchen: expected one of"),
        ("metrics_primer", {"tau": None}, "-p tau null: the notebooks need a value \\(default 60.0\\)"),
    ],
)
def test_report_parameters_are_checked_before_any_notebook_runs(notebook, parameters, said):
    """Each ran its notebook and failed inside it (exit 1), or was used as given: ``all_files="no"``
    ran every file, ``rpe_metres -1`` gave negative RPE percentages, ``fmt`` without ``groundtruth``
    was ignored, ``null`` replaced the notebook's default with None."""
    from lorisnb.tools.notebook.params import check_parameters
    from lorisnb.tools.report.notebooks import declared_by

    with pytest.raises(ValidationError, match=said):
        check_parameters(parameters, declared_by([notebook], None))


def test_report_parameters_reach_the_notebook_normalized(tmp_path, monkeypatch, data):
    """A relative ``--data``/``results_dir`` named the current folder's at the check and none in the
    notebook, which runs in its own folder; ``-p scene Cafe`` and ``-p eps '"1"'`` were checked but
    passed on as typed (the primer failed on them)."""
    from lorisnb.tools.notebook.params import check_parameters
    from lorisnb.tools.report.notebooks import declared_by

    monkeypatch.chdir(data.root.parent)
    rel = data.root.name
    out = check_parameters({"data_root": rel, "scene": "Cafe", "eps": "1"}, declared_by(["metrics_primer"], None))
    assert out["data_root"] == str(data.root.resolve()) and out["scene"] == "cafe" and out["eps"] == 1.0
    assert check_parameters({"eps": "paper"}, declared_by(["metrics_primer"], None))["eps"] == "paper"


def test_a_report_run_may_not_lie_in_the_data_root(tmp_path, data):
    """``--out`` inside the data root wrote the run among the data, exit 0."""
    from lorisnb.tools.report.build import run_report

    copy = tmp_path / "data"
    (copy / "openloris-scene").mkdir(parents=True)
    for part in ("groundtruth", "extrinsics.json", "icra20_results"):
        src = data.root / "openloris-scene" / part
        (copy / "openloris-scene" / part).symlink_to(src)
    with pytest.raises(ln.OutputError, match="lies in the input .*data of this report"):
        run_report(copy / "run", parameters={"data_root": str(copy)}, notebooks=["metrics_primer"], progress=False)
    assert not (copy / "run").exists()


def test_quick_trims_the_bundled_results_only():
    """``quick`` keeps a few scenes and algorithms of the bundled results where none are given;
    what the user gives, and results the user gives, are evaluated whole."""
    from lorisnb.tools.notebook.grids import QUICK_INPUTS, quick_inputs

    assert quick_inputs("lifelong_benchmark", True, None, None, None) == QUICK_INPUTS["lifelong_benchmark"]
    assert quick_inputs("lifelong_benchmark", True, None, ["market"], None) == (
        ["market"],
        QUICK_INPUTS["lifelong_benchmark"][1],
    )
    assert quick_inputs("per_sequence_benchmark", True, "/my/results", None, None) == (None, None)
    assert quick_inputs("per_sequence_benchmark", False, None, None, None) == (None, None)
    assert quick_inputs("threshold_sensitivity", True, None, None, None) == (["cafe", "home"], None)
    with pytest.raises(ValidationError, match="quick='yes'"):
        quick_inputs("threshold_sensitivity", "yes", None, None, None)
