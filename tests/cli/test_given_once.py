"""An option of one value given twice with different values is refused on every subcommand:
argparse keeps the last and drops the first, so ``sweep --eps 0.05 --eps 0.1`` swept 0.1 alone
and ``evaluate --eps relative:0.1 --eps 1`` scored eps 1 m, both with exit status 0."""

from __future__ import annotations

import argparse

import pytest

from lorisnb.cli import build_parser, main
from lorisnb.core.spec import validate


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def test_every_single_value_option_of_every_command_refuses_a_second_value():
    subs = _subparsers(build_parser())
    checked = 0
    for name, sub in subs.items():
        for action in sub._actions:
            if action.option_strings and action.nargs is None and isinstance(action, argparse._StoreAction):
                assert type(action).__name__ == "Once", (name, action.option_strings)
                checked += 1
    assert checked > 50 and {"evaluate", "sweep", "compare", "diff", "report", "crosscheck"} <= set(subs)


@pytest.mark.parametrize(
    "argv, flag",
    [
        (["sweep", "x", "--eps", "0.05", "--eps", "0.1"], "--eps"),
        (["evaluate", "x", "--eps", "relative:0.1", "--eps", "1"], "--eps"),
        (["evaluate", "x", "--phi=10", "--phi=20"], "--phi"),
        (["compare", "x", "--conventions", "tum", "--conventions", "rpg"], "--conventions"),
        (["report", "--jobs", "1", "--jobs", "2"], "--jobs"),
    ],
)
def test_a_second_different_value_is_a_usage_error(argv, flag, capsys):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"{flag} given twice" in err and "give it once" in err
    if argv[0] == "sweep":
        assert "comma-separated" in err


def test_the_same_value_twice_and_separate_parses_are_accepted():
    parser = build_parser()
    args = parser.parse_args(["evaluate", "x", "--phi", "10", "--phi", "10"])
    assert args.phi == 10.0
    again = parser.parse_args(["evaluate", "x", "--phi", "20"])  # a new parse forgets the last one's values
    assert again.phi == 20.0


def test_a_report_parameter_given_twice_with_different_values_is_refused(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["report", "--out", str(out), "--no-progress", "-p", "eps", "3", "-p", "eps", "5"]) == 2
    assert "-p eps given twice (3, then 5)" in capsys.readouterr().err
    assert not out.exists()  # refused before any notebook ran
    # --data and -p data_root naming two folders: -p won, silently (as --results and -p results_dir, refused)
    assert main(["report", "--out", str(out), "--no-progress", "--data", str(tmp_path), "-p", "data_root",
                 str(tmp_path / "other")]) == 2  # fmt: skip
    assert "--data and -p data_root name two folders" in capsys.readouterr().err and not out.exists()
    # -p data_root null (the default) with --data: --data was dropped and the default root used; it is used
    assert main(["report", "--out", str(out), "--no-progress", "--data", str(tmp_path), "-p", "data_root", "null"]) == 2
    assert f"It looked at: {tmp_path} (argument): not a data root" in capsys.readouterr().err and not out.exists()


def test_every_value_of_every_command_refuses_to_be_empty(capsys):
    """``--gt "$GT"`` with ``GT`` unset: ``--gt ""`` was read as no ``--gt`` (the file scored as an
    OpenLORIS result against the data root's ground truth, exit 0). Every option and argument
    that takes a value now refuses an empty one, as the Python API refuses an empty path."""
    parser = build_parser()
    subs = _subparsers(parser)
    checked = 0
    for name, sub in subs.items():
        for action in sub._actions:
            if type(action) is argparse._HelpAction or not isinstance(action, argparse._StoreAction):
                continue
            assert type(action).__name__ in ("Once", "Given"), (name, action.dest)
            checked += 1
    assert checked > 80
    for argv, name in [
        (["evaluate", "est.txt", "--gt", ""], "--gt"),
        (["evaluate", "est.txt", "--gt", "gt.txt", "--gt-times", " "], "--gt-times"),
        (["evaluate", ""], "FILE_OR_DIR"),
        (["crosscheck", "", "est.txt"], "gt"),
        (["report", "--notebooks", "metrics_primer", ""], "--notebooks"),
        (["sweep", "x", "--trials-by", ""], "--trials-by"),
    ]:
        with pytest.raises(SystemExit) as exc:
            parser.parse_args(argv)
        assert exc.value.code == 2
        assert f"{name}: an empty value (an unset shell variable?)" in capsys.readouterr().err


def test_words_are_read_as_python_reads_them():
    """``ln.make_spec(align="SE3")`` was accepted and ``--align SE3`` refused; ``rpe_unit="M"`` was
    kept as "M" and failed every file later. Every option of fixed words now goes through
    ``validate.choice`` (any case, spaces around), on the command line as in Python."""
    parser = build_parser()
    checked = 0
    for sub in _subparsers(parser).values():
        for action in sub._actions:
            if isinstance(action.choices, (list, tuple)):
                func = action.type.__closure__[0].cell_contents if action.type and action.type.__closure__ else None
                assert getattr(func, "func", None) is validate.choice, action.dest
                checked += 1
    assert checked > 20
    args = parser.parse_args(["evaluate", "x", "--align", "SE3", "--format", " TUM", "--rpe-unit", "M",
                              "--conventions", "Tum"])  # fmt: skip
    assert (args.align, args.format, args.rpe_unit, args.conventions) == ("se3", "tum", "m", "tum")
    from lorisnb.core.spec.evalspec import make_spec

    assert make_spec("openloris", rpe_unit="M").rpe_unit == "m"
    assert make_spec("openloris", rpe_unit="D").rpe_unit == "deg"
    assert make_spec("openloris", align="SE3").align == "se3"
    with pytest.raises(SystemExit):
        parser.parse_args(["evaluate", "x", "--align", "rotate"])


def test_help_offers_no_option_its_command_refuses(capsys):
    """``compare --help`` described ``--parquet DIR`` (and --relative, --relation, --kitti-plot),
    which compare then refused; the options each command refuses are out of its help, and still
    refused by name when given."""
    from lorisnb.cli.options import UNUSED

    for command, unused in UNUSED.items():
        with pytest.raises(SystemExit):
            main([command, "--help"])
        shown = capsys.readouterr().out
        for dest in unused:
            assert f"--{dest.replace('_', '-')} " not in shown, (command, dest)
        flag = f"--{next(iter(unused)).replace('_', '-')}"
        extra = ["OUT"] if next(iter(unused)) not in ("relative", "kitti_plot") else []
        assert main([command, "a", "b", flag, *extra]) == 2
        assert f"{flag}: not used by lorisnb {command}" in capsys.readouterr().err
