"""A seed is checked by one validator (``lorisnb.core.spec.validate.seed``) at every entry point
(trial finding 4): the command line's ``--seed`` of compare and diff, report ``-p seed``, the
Python functions that take a seed and a notebook's ``seed`` parameter. A negative seed was a
numpy traceback (``np.random.default_rng(-1)``)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from lorisnb.cli import main
from lorisnb.core.simulate import Faults
from lorisnb.core.spec import validate
from lorisnb.core.stats import inference as stats
from lorisnb.core.stats.permutation import difference_interval
from lorisnb.errors import ValidationError
from lorisnb.tools.notebook.params import check_parameters

BAD = [-1, "-1", 1.5, "1.5", True, "x", None, float("nan")]


@pytest.mark.parametrize("value", BAD)
def test_the_validator_refuses(value):
    with pytest.raises(ValidationError, match=r"seed=.*expected a whole number >= 0"):
        validate.seed(value)


@pytest.mark.parametrize(("value", "want"), [(0, 0), (7, 7), ("7", 7), (np.int64(3), 3), (2.0, 2), (2**70, 2**70)])
def test_the_validator_accepts_whole_numbers(value, want):
    assert validate.seed(value) == want and isinstance(validate.seed(value), int)


def _table() -> pd.DataFrame:
    """Two algorithms on two sequences of one scene, with two trials each (the test samples)."""
    rows = [
        dict(algorithm=a, scene="cafe", seq=s, trial=k, cr=v, gt_duration=100.0, matched=10)
        for a, base in (("a", 0.5), ("b", 0.7)) for s in (1, 2) for k, v in enumerate((base, base + 0.1))
    ]  # fmt: skip
    return pd.DataFrame(rows)


@pytest.mark.parametrize("value", [-1, 1.5, True])
def test_python_functions_refuse(value):
    t = _table()
    for call in (
        lambda: stats.confidence_intervals(t, metrics=["cr"], seed=value),
        lambda: stats.pairwise(t, "cr", seed=value),
        lambda: difference_interval([np.array([1.0, 2.0])], [np.array([0.0, 1.0])], None, 0.05, seed=value),
        lambda: Faults(seed=value),
    ):
        with pytest.raises(ValidationError, match="seed.*expected a whole number >= 0"):
            call()
    assert stats.confidence_intervals(t, metrics=["cr"], seed=np.int64(1))["value"].notna().all()


@pytest.mark.parametrize("value", ["-1", "1.5", "x"])
def test_command_line_refuses_with_usage_error(icra20, capsys, value):
    with pytest.raises(SystemExit) as exc:
        main(["compare", str(icra20 / "per-seq"), "--seed", value, "--no-progress"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"--seed={value}: expected a whole number >= 0" in err and "Traceback" not in err


def test_diff_takes_no_seed(icra20, capsys):
    """diff's verdict samples nothing (issue 44: one t-test per comparison, Holm over the diff), so a
    seed cannot apply to it and is refused, not dropped."""
    odom = str(icra20 / "per-seq" / "odom")
    with pytest.raises(SystemExit) as exc:
        main(["diff", odom, odom, "--seed", "1", "--no-progress"])
    assert exc.value.code == 2 and "unrecognized arguments: --seed" in capsys.readouterr().err


def test_report_and_notebook_parameter_refused_before_anything_runs(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["report", "--out", str(out), "--notebooks", "compare_algorithms", "-p", "seed", "-1"]) == 2
    assert "seed=-1: expected a whole number >= 0" in capsys.readouterr().err and not out.exists()
    with pytest.raises(ValidationError, match="seed=-1"):
        check_parameters({"seed": -1}, {"seed": {}})
