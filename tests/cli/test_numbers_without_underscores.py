"""One number syntax for user values: Python's float() and int() read '1_0' as 10, while the file
readers refuse 1_000; every user value (command-line options, manifest keys, -p parameters) goes
through lorisnb.core.spec.validate, which now refuses underscores (adversarial finding 7)."""

from __future__ import annotations

import shutil

import pytest

from lorisnb.cli import main
from lorisnb.errors import ParseError, ValidationError
from lorisnb.io.datasets.manifest import read_manifest
from lorisnb.tools.notebook.params import check_values

TUM = "tum-rgbd"


@pytest.mark.parametrize(
    "argv",
    [
        ["evaluate", "EST", "--gt", "GT", "--eps", "1_0"],
        ["evaluate", "EST", "--gt", "GT", "--max-gap", "0_5"],
        ["evaluate", "EST", "--gt", "GT", "--conventions", "tartanair", "--tartanair-seed", "1_0"],
        ["sweep", "EST", "--gt", "GT", "--eps", "0.1,1_0"],
        ["crosscheck", "GT", "EST", "--seq", "1_0"],  # was int(): 10
    ],
)
def test_an_underscore_is_refused_on_the_command_line(data, argv, capsys):
    est, gt = str(data.root / TUM / "fr2_desk_ORB.txt"), str(data.root / TUM / "fr2_desk_groundtruth.txt")
    with pytest.raises(SystemExit) as exc:
        main([{"EST": est, "GT": gt}.get(a, a) for a in argv])
    assert exc.value.code == 2
    assert "is not a number: write it without underscores" in capsys.readouterr().err


def test_an_underscore_is_refused_in_a_manifest_and_a_parameter(data, tmp_path):
    shutil.copy(data.root / TUM / "fr2_desk_groundtruth.txt", tmp_path / "gt.txt")
    m = tmp_path / "m.toml"
    m.write_text('eps = "1_0"\n[[session]]\nname = "desk"\ngroundtruth = "gt.txt"\n')
    with pytest.raises(ParseError, match="eps=1_0 is not a number: write it without underscores"):
        read_manifest(m)
    with pytest.raises(ValidationError, match="delta=1_0 is not a number"):
        check_values({"delta": "1_0"})


def test_the_same_number_without_it_is_taken(data, capsys):
    est, gt = str(data.root / TUM / "fr2_desk_ORB.txt"), str(data.root / TUM / "fr2_desk_groundtruth.txt")
    assert main(["evaluate", est, "--gt", gt, "--eps", "10", "--no-progress"]) == 0
    assert "eps 10.0, phi inf deg" in capsys.readouterr().err
