"""A newcomer's findings (s68): notebook parameters excluding each other as the command line's options
do, papermill's infinity, advice fitting where a check runs, one format hint, evaluate's own keywords
named, coverage counts said unambiguously, short messages for a table passed as a number, and the
sequence a crosscheck compared."""

from __future__ import annotations

import math

import pandas as pd
import pytest

import lorisnb as ln
from lorisnb.core.lifelong.coverage import coverage_notes
from lorisnb.core.lifelong.sweep import eps_at_cr
from lorisnb.core.spec import validate
from lorisnb.errors import ValidationError
from lorisnb.tools.notebook.params import check_parameters, check_values


@pytest.fixture(scope="module")
def tum(tum_folder):
    return tum_folder


def test_groundtruth_and_manifest_refused_as_the_command_line_refuses_gt_and_manifest(tum):
    values = dict(path=str(tum / "fr2_desk_ORB.txt"), groundtruth=str(tum / "fr2_desk_groundtruth.txt"),
                  manifest="tum-fr1-office")  # fmt: skip
    declared = {n: {"default": None} for n in values}
    for check in (lambda: check_parameters(values, declared, ["evaluate_my_results"]),  # lorisnb report
                  lambda: check_parameters(values, declared, ["evaluate_my_results"], by="evaluate_my_results"),
                  lambda: check_values(values, ["evaluate_my_results"])):  # fmt: skip
        with pytest.raises(ValidationError, match=r"groundtruth=.* and manifest=tum-fr1-office: give one \(--gt and "
                                                  "--manifest"):  # fmt: skip
            check()
    # one of them is fine
    assert check_parameters({k: values[k] for k in ("path", "manifest")}, declared, ["evaluate_my_results"])


def test_papermill_infinity_refused_in_the_notebook_not_in_the_report(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # no run folder of lorisnb report around
    declared = {"eps": {"default": 1.0}, "phi": {"default": 30.0}}
    for name in ("eps", "phi"):
        with pytest.raises(ValidationError, match=rf"{name}=inf: papermill turned the number given with -p {name} "
                                                  "into infinity.*1e400.*papermill -p .* 1e9"):  # fmt: skip
            check_parameters({name: math.inf}, declared, ["metrics_primer"], by="metrics_primer")
    # the report's own check takes inf (it is the report's -p eps inf, passed on as infinity)
    assert check_parameters({"eps": "inf"}, declared, ["metrics_primer"])["eps"] == math.inf
    assert check_parameters({"eps": 2.0}, declared, ["metrics_primer"], by="metrics_primer") == {"eps": 2.0}


def test_text_advice_never_a_number_papermill_makes_infinite():
    with pytest.raises(ValidationError) as e:
        check_values({"eps": "1e400"}, ["metrics_primer"])
    assert "too large to be a number" in str(e.value) and "papermill -p eps 1e400" not in str(e.value)
    # the notebook refuses inf in either spelling: its advice is the notebook's, not the command line's
    assert "write 'inf'" not in str(e.value) and "(papermill -p eps 1e9)" in str(e.value)
    with pytest.raises(ValidationError) as e:
        check_values({"phi": "inf"}, ["metrics_primer"])
    assert "give a number: papermill -p phi inf" not in str(e.value)  # papermill turns inf into infinity: refused
    assert "for no threshold, a number beyond any error (papermill -p phi 1e9)" in str(e.value)
    with pytest.raises(ValidationError, match=r"papermill -p eps 3, or lorisnb report"):  # a finite one as before
        check_values({"eps": "3"}, ["metrics_primer"])


def test_relative_eps_advice_fits_where_the_check_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    declared = {"eps": {"default": 1.0}}
    with pytest.raises(ValidationError) as e:
        check_parameters({"eps": "relative:0.05"}, declared, ["metrics_primer"], by="metrics_primer")
    assert "--notebooks" not in str(e.value) and "this one with metres" in str(e.value)
    with pytest.raises(ValidationError, match="leave this one out with --notebooks"):
        check_parameters({"eps": "relative:0.05"}, declared, ["metrics_primer"])


def test_tum_file_without_gt_hint_said_once_with_the_gt_step(tum):
    ev = ln.evaluate(tum / "fr2_desk_ORB.txt")
    said = ev.failures[0].error if ev.failures else ""
    if not said:
        pytest.fail("the TUM file read as an OpenLORIS result did not fail")
    assert said.count("this looks like a TUM trajectory file") == 1, said
    assert "give its ground truth with --gt FILE" in said


def test_unknown_keyword_names_evaluates_own_and_the_near_one(icra20):
    path = icra20 / "lifelong" / "ds-slam" / "cafe-1.txt"
    for kw, near in (("data", "data_root"), ("algorithm", "algorithms"), ("trials", "trials_by")):
        with pytest.raises(ValidationError) as e:
            ln.evaluate(path, **{kw: 1})
        said = str(e.value)
        assert f"(did you mean {near!r}?)" in said and "data_root, algorithms, scenes, trials_by" in said, said
        assert "eps" in said  # the spec's options are still listed
    with pytest.raises(ValidationError, match=r"not a keyword of evaluate_pairs \(did you mean 'gt_fmt'\?\)"):
        ln.evaluate_pairs(path, path, gt_fmtt="tum")
    with pytest.raises(ValidationError, match=r"not a keyword of evaluate_manifest.*'trials_by'"):
        ln.evaluate_manifest("tum-fr1-office", path, trials="x")
    with pytest.raises(ValidationError, match=r"epsilon: not a keyword of evaluate \(did you mean 'eps'"):
        ln.evaluate(path, epsilon=3)


def test_coverage_note_says_output_for_how_many_of_how_many():
    cover = pd.DataFrame([dict(suite="", algorithm="ds-slam", scene="corridor", sequences=1, expected=5,
                               coverage=0.2, missing_seqs="2, 3, 4, 5", missing_trials="")])  # fmt: skip
    (note,) = coverage_notes(cover)
    assert "corridor sequence(s) 2, 3, 4, 5 (output for 1 of its 5 sequences)" in note
    assert "(1 of 5)" not in note


def test_a_table_passed_as_a_number_is_named_not_printed(icra20):
    ev = ln.evaluate(icra20 / "lifelong" / "ds-slam" / "cafe-1.txt")
    with pytest.raises(ValidationError) as e:
        eps_at_cr(ev.errors, ev.durations(), 0.5)  # target and durations swapped
    said = str(e.value)
    assert len(said) < 200 and "<DataFrame of " in said and "eps_at_cr(errors, target, durations)" in said, said
    frame = pd.DataFrame({"a": range(100)})
    for check in (lambda: validate.threshold("eps", frame), lambda: validate.positive("x", frame.a, "m"),
                  lambda: validate.seed(list(range(100)))):  # fmt: skip
        with pytest.raises(ValidationError) as e:
            check()
        assert len(str(e.value)) < 200, str(e.value)


def test_crosscheck_names_the_sequence_it_compared(data, icra20):
    from lorisnb.tools.peers.crosscheck import crosscheck_openloris

    pytest.importorskip("evo")
    table = crosscheck_openloris(icra20 / "lifelong" / "ds-slam" / "cafe-1.txt", data_root=data.root)
    assert table.attrs["compared"].startswith("sequence 1 of cafe-1.txt (")
    assert "--seq N" in table.attrs["compared"]
