"""A lifelong file whose first sequence matches nothing, and the warnings about the sequence a
lifelong alignment was fitted on, against the official OpenLORIS-Scene tool.

The inputs are made here from the bundled cafe and home ground truth with a fixed seed (the helpers of
``test_official_stress``). REFERENCE holds the official tool's numbers on exactly these files
(``benchmark/evaluate.py`` of openloris-scene-tools ce6a4839f618bf036d3f3dbae14561bfc7413641, run as
in ``test_official_stress``'s docstring, at eps 3 m, phi 30 deg, delta 1 s, tau 60 s).

When the first ``seq:`` block matches no ground-truth stamp (its stamps shifted away, or an empty,
failed block), the official ``transform_world_frame`` returns before fitting: no sequence is aligned,
and the second sequence, left in its own world frame, scores ATE 20 m and CR 0. lorisnb aligns on
the first sequence with matches by default (ATE 0.05 m, CR 1) and says so; ``official_lifelong``
(``--official-lifelong``) gives the official numbers. With Sim(3), a first sequence of one matched
pose stops the official tool (``umeyama_align`` divides by the estimate's zero spread: a NaN scale, then
``LinAlgError: Array must not contain infs or NaNs``); lorisnb's warning says so.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from test_official_stress import FIELDS, _estimate, _file, _rot

import lorisnb as ln
from lorisnb.errors import LorisWarning, ValidationError

SEED = 20270301
NAN = math.nan
EPS, PHI = 3.0, 30.0


def _cases(data_root) -> dict[str, str]:
    """name -> file text of each input, from the real ground truth."""
    rng = np.random.default_rng(SEED)
    cafe = ln.load_groundtruth("cafe", data_root=data_root).sequences
    home = ln.load_groundtruth("home", data_root=data_root).sequences
    world = (_rot(rng, 40), rng.normal(size=3) * 3)
    st1, p1, q1 = _estimate(rng, cafe[1], np.arange(0, len(cafe[1]), 3), 0.0, 0.03, 1.0, world)
    st2, p2, q2 = _estimate(rng, cafe[2], np.arange(0, len(cafe[2]), 2), 0.0, 0.03, 1.0, world)
    empty = (np.zeros(0), np.zeros((0, 3)), np.zeros((0, 4)))
    blocks = [(s, *_estimate(rng, home[s], np.arange(0, len(home[s]), 2), 0.003, 0.02, 0.7, world))
              for s in (1, 2, 3)]  # fmt: skip
    blocks[0] = (1, *(x[100:101] for x in blocks[0][1:]))  # one matched pose
    return {
        "first_nomatch": _file("cafe", [(1, st1 + 5000.0, p1, q1), (2, st2, p2, q2)]),
        "first_empty": _file("cafe", [(1, *empty), (2, st2, p2, q2)]),
        "first_three": _file("cafe", [(1, st1[50:53], p1[50:53], q1[50:53]), (2, st2, p2, q2)]),
        "home_first1": _file("home", blocks),
    }


# the official tool's numbers (FIELDS' order) at EPS, PHI: case -> seq -> values
# fmt: off
REFERENCE = {
    "first_nomatch": {
        1: (0.0, NAN, NAN, NAN, NAN, 0.0, 0.0, 0.0, 0.0, 0.0, 761.0, 0.0),
        2: (1803.0, 26.534653574459973, 40.002893913556534, NAN, NAN, 0.0, 0.0, 0.0, 0.0, 0.0, 1803.0, 89.9723539352417),
    },
    "first_empty": {
        1: (0.0, NAN, NAN, NAN, NAN, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        2: (1803.0, 26.534653574459973, 40.002893913556534, NAN, NAN, 0.0, 0.0, 0.0, 0.0, 0.0, 1803.0, 89.9723539352417),
    },
}
# fmt: on


@pytest.fixture(scope="module")
def cases(data, tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("official_lifelong")
    out = {}
    for name, text in _cases(data.root).items():
        (folder / f"{name}.txt").write_text(text)
        out[name] = folder / f"{name}.txt"
    return out


def _evaluate(path: Path, data, **kw):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LorisWarning)
        ev = ln.evaluate(path, data_root=data.root, jobs=1, **kw)
    return ev, [str(w.message) for w in caught if issubclass(w.category, LorisWarning)]


def _same(want: float, got: float) -> bool:
    if math.isnan(want) or math.isnan(got):
        return math.isnan(want) and math.isnan(got)
    return got == pytest.approx(want, rel=1e-8, abs=1e-9)


def _differences(table: pd.DataFrame, reference: dict[int, tuple]) -> list[str]:
    assert sorted(table.index) == sorted(reference)
    return [
        f"seq {seq} {column}: official {want!r}, lorisnb {float(table.loc[seq, column])!r}"
        for seq, values in reference.items()
        for (_, column), want in zip(FIELDS, values, strict=True)
        if not _same(want, float(table.loc[seq, column]))
    ]


@pytest.mark.parametrize("name", ["first_nomatch", "first_empty"])
def test_official_lifelong_gives_the_official_numbers(cases, data, name):
    """official_lifelong: no alignment at all, as the official tool, and every number is its."""
    ev, said = _evaluate(cases[name], data, official_interpolation=True, official_lifelong=True)
    table = ev.sequences(eps=EPS, phi=PHI).set_index("seq")
    assert _differences(table, REFERENCE[name]) == []
    assert ev.errors[0].aligned_on is None
    assert any("no alignment is applied to any sequence, as the official tool does" in s for s in said)
    assert "aligned on the first sequence, none if it matches nothing (the official tool's)" in ev.conventions


@pytest.mark.parametrize("name", ["first_nomatch", "first_empty"])
def test_default_aligns_on_the_first_sequence_with_matches_and_says_so(cases, data, name):
    """lorisnb's default: aligned on sequence 2 (its ATE is the estimate's noise), with a warning
    naming the official behaviour and the option that gives it; the conventions line says which
    sequence a lifelong alignment is fitted on (not "their first")."""
    ev, said = _evaluate(cases[name], data, official_interpolation=True)
    row = ev.sequences(eps=EPS, phi=PHI).set_index("seq").loc[2]
    official = REFERENCE[name][2]
    assert ev.errors[0].aligned_on == 2 and row["ate_rmse"] < 0.1 < official[1] and row["cr"] > 0.99
    assert any("computed on sequence 2" in s and "official_lifelong" in s for s in said)
    assert "aligned on the first sequence with matches" in ev.conventions
    assert "aligned on their first;" not in ev.conventions


def test_command_line_official_lifelong(cases, data, tmp_path):
    from lorisnb.cli import main

    out = tmp_path / "o.csv"
    args = ["evaluate", str(cases["first_nomatch"]), "--data", str(data.root), "--official-interpolation",
            "--official-lifelong", "--eps", str(EPS), "--phi", str(PHI), "--no-progress", "--csv", str(out)]  # fmt: skip
    assert main(args) == 0
    assert _differences(pd.read_csv(out).set_index("seq"), REFERENCE["first_nomatch"]) == []


@pytest.mark.parametrize("options", [{"mode": "per-seq"}, {"align": "none"}], ids=["per-seq", "align-none"])
def test_official_lifelong_is_refused_where_it_cannot_apply(options):
    spec = ln.make_spec(official_lifelong=True, **options)
    with pytest.raises(ValidationError, match="official_lifelong: the official tool's alignment of a lifelong"):
        spec.refuse_inapplicable("openloris")
    assert ln.make_spec(official_lifelong=True).refuse_inapplicable("openloris") == []
    for kind in ("pair", "manifest"):  # not inputs of the official tool
        with pytest.raises(ValidationError, match=f"but a {kind} is not an input of the official tool"):
            ln.make_spec(official_lifelong=True).refuse_inapplicable(kind)
    with pytest.raises(ValidationError, match="expected True or False"):
        ln.make_spec(official_lifelong="yes")
    assert ln.EvalSpec.parse(ln.make_spec(official_lifelong=True).canonical()).official_lifelong


def test_command_line_refuses_official_lifelong_per_seq(cases, data, capsys):
    from lorisnb.cli import main

    assert main(["evaluate", str(cases["first_nomatch"]), "--data", str(data.root), "--official-lifelong",
                 "--per-seq", "--no-progress"]) != 0  # fmt: skip
    assert "--official-lifelong: the official tool's alignment of a lifelong" in capsys.readouterr().err


def test_lever_warning_names_the_sequence_the_alignment_was_fitted_on(cases, data):
    """The lifelong alignment is fitted on sequence 1 (3 poses: no lever); sequence 2's AOE is large:
    the warning is about sequence 2's AOE and names sequence 1's 3 matched positions as such."""
    _, said = _evaluate(cases["first_three"], data)
    lever = [s for s in said if "hold the alignment's rotation by a lever" in s]
    assert len(lever) == 1
    assert ", seq 2: its median AOE" in lever[0]
    assert "the alignment was fitted on seq 1, whose 3 matched positions" in lever[0]


def test_few_poses_warning_names_file_and_sequence(cases, data):
    """The 'fitted on all of only N matched poses' warning names FILE, seq N as every other does."""
    _, said = _evaluate(cases["first_three"], data)
    few = [s for s in said if "alignment is fitted on all of only 3 matched poses" in s]
    assert len(few) == 1 and few[0].startswith(f"{cases['first_three']}, seq 1: the se3 alignment")


def test_degenerate_warning_under_sim3_says_the_official_tool_stops(cases, data):
    """One matched pose in the first sequence: under SE(3) the official tool aligns with its own
    arbitrary rotation; under Sim(3) it stops (LinAlgError). The warning says which."""
    _, sim3 = _evaluate(cases["home_first1"], data, scale=True)
    _, se3 = _evaluate(cases["home_first1"], data, scale=False)
    (a,) = [s for s in sim3 if "so its rotation is arbitrary" in s]
    (b,) = [s for s in se3 if "so its rotation is arbitrary" in s]
    assert "seq 1:" in a and "LinAlgError" in a and "aligns all the same" not in a
    assert "--align-frames 1, --align none" not in a  # refused with Sim(3): a scale needs 2 poses
    assert "aligns all the same, with its own arbitrary rotation" in b and "LinAlgError" not in b
