"""evo's option spellings on the command line get lorisnb's option named (one table, EVO_OPTIONS),
and a TUM file given without --gt gets the format hint once, with the --gt step."""

from __future__ import annotations

import pytest

from lorisnb.cli import main


@pytest.fixture(scope="module")
def tum(tum_folder):
    return tum_folder


@pytest.mark.parametrize(
    "given, named",
    [
        (["--t_max_diff", "0.05"], "evo's --t_max_diff is lorisnb's --max-diff"),
        (["--max_diff", "0.05"], "--max_diff is spelled --max-diff"),
        (["--align_origin"], "evo's --align_origin is lorisnb's --align-origin"),
        (["--n_to_align", "5"], "evo's --n_to_align is lorisnb's --align-frames"),
        (["-as"], "evo's -as is lorisnb's --align sim3"),
    ],
)
def test_evo_spelling_names_lorisnbs_option(tum, capsys, given, named):
    with pytest.raises(SystemExit) as e:
        main(["evaluate", str(tum / "fr2_desk_ORB.txt"), "--gt", str(tum / "fr2_desk_groundtruth.txt"), *given])
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert "unrecognized arguments" in err and named in err, err


def test_unknown_option_not_evo_gets_no_hint(tum, capsys):
    with pytest.raises(SystemExit):
        main(["evaluate", str(tum / "fr2_desk_ORB.txt"), "--frobnicate"])
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.endswith("unrecognized arguments: --frobnicate"), err


def test_tum_without_gt_hint_once(tum, capsys):
    rc = main(["evaluate", str(tum / "fr2_desk_ORB.txt"), "--no-progress"])
    err = capsys.readouterr().err
    line = next(x for x in err.splitlines() if x.startswith("error:"))
    assert rc != 0 and line.count("this looks like a TUM trajectory file") == 1, line
    assert line.endswith("and give its ground truth with --gt FILE (evaluate_pairs in Python)"), line


def test_crosscheck_of_an_openloris_file_prints_the_sequence_it_compared(data, icra20, capsys):
    """``crosscheck GT EST --format openloris`` compares one sequence of a file that holds several:
    the output said none (a user could not tell sequence 2 was left out); it names it first."""
    gt = data.root / "openloris-scene" / "groundtruth" / "gt_cafe_1.txt"
    if not gt.is_file():
        pytest.skip("the cafe-1 ground truth is not in this data folder")
    for extra, seq in (([], 1), (["--seq", "2"], 2)):
        rc = main(["crosscheck", str(gt), str(icra20 / "lifelong" / "ds-slam" / "cafe-1.txt"), "--format", "openloris",
                   *extra])  # fmt: skip
        out = capsys.readouterr().out
        assert rc in (0, 1) and out.splitlines()[0].startswith(f"compared: sequence {seq} of cafe-1.txt ("), out[:300]
