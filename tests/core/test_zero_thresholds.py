"""eps = 0 (only poses without any position error are correct) is one value in every form and on
every surface: metres, ``relative:0`` (it was refused while ``--eps 0`` was accepted), relative
grids, sweeps relative to the extent, ``eps_fraction``; negative and NaN fractions are refused by
the same rule (:func:`lorisnb.core.spec.validate.fraction`)."""

from __future__ import annotations

import pytest
from helpers import write

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.lifelong.sweep import sweep
from lorisnb.core.metrics.difficulty import difficulty_measures
from lorisnb.errors import ValidationError
from lorisnb.tools.evaluation.runner import evaluate_manifest, evaluate_pairs
from lorisnb.tools.notebook.grids import check_grid

GT = "freiburg1_xyz-groundtruth.txt"


@pytest.fixture(scope="module")
def itself(data, tmp_path_factory):
    """The real ground truth scored against a copy of itself without alignment: every ATE exactly 0."""
    copy = tmp_path_factory.mktemp("self") / "copy.txt"
    copy.write_bytes((data.tum / GT).read_bytes())
    return evaluate_pairs(copy, data.tum / GT, conventions="tum", align="none", jobs=1)


@pytest.mark.parametrize("eps", [0, 0.0, "0", "relative:0", "relative:0.0"])
def test_eps_zero_in_every_form_counts_exact_poses_correct(itself, eps):
    assert (itself.errors[0].sequences[0].ate == 0).all()
    row = itself.sequences(eps=eps, phi=180).iloc[0]
    assert row["cr"] == pytest.approx(1.0) and row["c_matched"] == row["matched"]


def test_relative_zero_on_every_surface(data, tmp_path, capsys, itself):
    copy = write(tmp_path, "copy.txt", (data.tum / GT).read_bytes())
    args = ["evaluate", str(copy), "--gt", str(data.tum / GT), "--conventions", "tum", "--align", "none"]
    assert main([*args, "--eps", "relative:0", "--phi", "180"]) == 0
    assert "1.0000" in capsys.readouterr().out
    assert ln.make_spec("tum", eps="relative:0").eps == "relative:0.0"
    write(tmp_path, "res/self/xyz.txt", (data.tum / GT).read_bytes())
    m = write(tmp_path, "m.toml", f'root = "{data.tum}"\neps = "relative:0"\nphi = 180\n[conventions]\npreset = "tum"\n'
              f'align = "none"\n[[session]]\nname = "xyz"\ngroundtruth = "{GT}"\n')  # fmt: skip
    assert evaluate_manifest(m, tmp_path / "res").sequences()["cr"].iloc[0] == pytest.approx(1.0)
    assert check_grid("relative_grid", [0, 0.05]) == [0.0, 0.05]
    sw = sweep(itself.errors, [0.0, 0.01], [180.0], relative_to="extent")
    assert sw["cr"].tolist() == pytest.approx([1.0, 1.0])
    gt = ln.read_tum(data.tum / GT)
    assert difficulty_measures(itself.errors[0].sequences[0], gt, eps_fraction=0)["cr_scaled"] == pytest.approx(1.0)


@pytest.mark.parametrize("bad", ["relative:-0.1", "relative:nan", "relative:x", "relative:inf"])
def test_bad_fractions_are_refused_with_one_message(bad):
    with pytest.raises(ValidationError, match="expected a fraction of the ground truth's size"):
        ln.make_spec(eps=bad)
    with pytest.raises(ValidationError, match="relative_grid|eps"):
        check_grid("relative_grid", [bad.split(":")[1]])
