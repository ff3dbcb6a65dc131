"""evo's options in the evaluation spec (issue 23): the ``evo`` preset's values, validation and
refusals with one message on every surface, and each option against evo itself (evo's readers and
API run as evo_ape / evo_rpe run them: :func:`lorisnb.tools.peers.crosscheck_evo.evo_statistics`)."""

from __future__ import annotations

import math

import pandas as pd
import pytest

from lorisnb.cli import main
from lorisnb.core.spec.evalspec import EvalSpec, make_spec
from lorisnb.errors import ValidationError
from lorisnb.tools.peers.crosscheck_evo import crosscheck_evo

GT, EST = "freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"
T0 = 1305031102.1758  # the first ground-truth stamp of fr1_xyz, seconds


def test_the_evo_preset_is_evos_defaults():
    s = EvalSpec.preset("evo")
    assert (s.association, s.max_diff, s.repeated, s.align, s.align_frames) == (
        "evo-nearest",
        0.01,
        "keep",
        "none",
        None,
    )
    assert (s.rpe_delta, s.rpe_unit, s.rpe_pairs, s.rpe_all_pairs, s.rpe_tolerance) == (1.0, "frames", "estimate",
                                                                                       False, 0.1)  # fmt: skip
    assert (
        "evo's nearest stamps within 0.01 s" in s.describe() and "consecutive pairs along the estimate" in s.describe()
    )
    full = make_spec("evo", motion_filter="0.1 5", t_start=1.5, project_to_plane="xy", relation="full", downsample=9)
    assert EvalSpec.parse(full.canonical()) == full
    assert full.motion_filter == (0.1, 5.0)


@pytest.mark.parametrize(
    "options, message",
    [
        (dict(rpe_tolerance=0.2), "only for evo's all pairs"),
        (dict(rpe_pairs="reference", rpe_unit="s"), "the same along either trajectory"),
        (dict(t_start=10.0, t_end=5.0), "after"),
        (dict(motion_filter=[0.1]), "two numbers"),
        (dict(motion_filter=[-1, 2]), ">= 0"),
        (dict(project_to_plane="xyz"), "project_to_plane"),
        (dict(relation="everything"), "relation"),
        (dict(rpe_unit="deg", rpe_delta=200), "[0, 180]"),
        (dict(rpe_unit="frames", rpe_delta=1.5), "whole number"),
        (dict(align="origin", align_frames=3), "first pose only"),
        (dict(rpe_all_pairs="sometimes"), "rpe_all_pairs"),
    ],
)
def test_bad_evo_options_are_refused_with_their_name(options, message):
    with pytest.raises(ValidationError, match=message.replace("[", r"\[").replace("]", r"\]")):
        make_spec("evo", **options).refuse_inapplicable("pair")


def test_the_command_line_refuses_them_the_same_way(data, capsys):
    for extra, message in ((["--rpe-tolerance", "0.2"], "--rpe-tolerance: only for evo's all pairs"),
                           (["--t-start", "10", "--t-end", "5"], "--t-start 10 is after --t-end 5"),
                           (["--motion-filter", "x", "1"], "--motion-filter")):  # fmt: skip
        rc = main(["evaluate", str(data.tum / EST), "--gt", str(data.tum / GT), "--conventions", "evo", *extra])
        assert rc == 2 and message in capsys.readouterr().err


@pytest.mark.parametrize(
    "options",
    [
        dict(t_start=T0 + 5.0, t_end=T0 + 20.0, align="se3"),
        dict(downsample=300, align="sim3"),
        dict(motion_filter=(0.02, 2.0), align="se3"),
        dict(project_to_plane="xy", align="se3"),
        dict(project_to_plane="yz"),
        dict(align="origin"),
        dict(align="scale", rpe_unit="m", rpe_delta=0.25),
        dict(association="evo-interpolate", align="se3", max_diff=0.02),
        dict(t_offset=0.004, align="se3"),
        dict(align_frames=100, align="se3", rpe_unit="rad", rpe_delta=0.05, rpe_all_pairs=True),
        dict(align="sim3", rpe_unit="deg", rpe_delta=3.0, rpe_pairs="reference"),
    ],
    ids=lambda o: ",".join(f"{k}={v}" for k, v in o.items()),
)
@pytest.mark.thorough
def test_each_option_equals_evo(data, options):
    table = crosscheck_evo(data.tum / GT, data.tum / EST, make_spec("evo", **options))
    stats = table[~table["quantity"].str.contains(":")]
    assert len(stats) == 30 and stats["agrees"].all(), stats[~stats["agrees"]]
    pairs = stats.set_index("quantity").loc["rpe_pairs", "evo"]  # evo's count: len(error_array)
    rpe = stats[stats["quantity"].str.startswith("rpe_") & (stats["quantity"] != "rpe_pairs")]
    assert (rpe["n_pairs"] == pairs).all()
    first = next(iter(options))  # the option under test: without it, other numbers
    plain = crosscheck_evo(
        data.tum / GT, data.tum / EST, make_spec("evo", **{k: v for k, v in options.items() if k != first})
    )
    changed = stats.set_index("quantity")["lorisnb"] != plain[~plain["quantity"].str.contains(":")].set_index(
        "quantity")["lorisnb"]  # fmt: skip
    assert changed.any()  # the option changes the numbers


def test_evo_interpolate_when_the_groundtruth_is_the_shorter(data, tmp_path):
    # evo interpolates the *longer* trajectory at the matched stamps of the shorter one: here the estimate
    lines = (data.tum / GT).read_text().splitlines()
    rows = [ln for ln in lines if not ln.startswith("#")][::8]
    g = tmp_path / "sparse_gt.txt"
    g.write_text("\n".join(rows) + "\n")
    for association in ("evo-interpolate", "evo-nearest"):
        spec = make_spec("evo", association=association, align="se3", max_diff=0.05)
        table = crosscheck_evo(g, data.tum / EST, spec)
        stats = table[~table["quantity"].str.contains(":")]
        assert stats["agrees"].all(), stats[~stats["agrees"]]


def test_manifest_and_python_take_the_preset(data, tmp_path):
    import lorisnb as ln

    ev = ln.evaluate_pairs(data.tum / EST, data.tum / GT, conventions="evo", align="se3", relation="full")
    row = ev.sequences().iloc[0]
    assert row["relation"] == "full" and math.isfinite(row["ape_rmse"]) and row["ape_rmse"] > row["ate_rmse"]
    m = tmp_path / "m.toml"
    m.write_text(
        f'name = "fr1"\nroot = "{data.tum}"\n[conventions]\npreset = "evo"\nalign = "se3"\n'
        f'[[session]]\nname = "xyz"\ngroundtruth = "{GT}"\nestimate = "{EST}"\n'
    )
    algo = tmp_path / "results" / "rgbdslam"
    algo.mkdir(parents=True)
    (algo / EST).write_bytes((data.tum / EST).read_bytes())
    via_manifest = ln.evaluate_manifest(m, tmp_path / "results").sequences().iloc[0]
    assert via_manifest["ate_rmse"] == pytest.approx(row["ate_rmse"], rel=1e-12)
    assert via_manifest["matched"] == row["matched"]
    assert isinstance(ev.sequences(), pd.DataFrame)


@pytest.mark.parametrize(
    ("preset", "align", "expected"),
    [("evo", None, "none"), ("openloris", None, "se3"), ("rpg", None, "se3"), ("vio", None, "posyaw"),
     ("evo", "origin", "origin"), ("openloris", "none", "none")],
)  # fmt: skip
def test_scale_off_takes_the_scale_out_of_the_alignment_and_nothing_else(preset, align, expected):
    """``--scale off`` was SE(3) whatever the alignment: ``--conventions evo --scale off`` (no scale
    correction, evo's default) aligned the trajectories and gave ``evo_ape -a``'s number."""
    given = {} if align is None else {"align": align}
    assert make_spec(preset, scale="off", **given).align == expected
    for scaled in ("sim3", "scale"):  # an alignment with a scale, and no scale: refused
        with pytest.raises(ValidationError, match="give one"):
            make_spec(preset, scale="off", align=scaled)


def test_evo_with_scale_off_is_evos_default(data, tmp_path):
    t = data.tum
    pair = [str(t / "freiburg1_xyz-rgbdslam.txt"), "--gt", str(t / "freiburg1_xyz-groundtruth.txt")]
    tables = []
    for extra in ([], ["--scale", "off"]):
        out = tmp_path / f"t{len(extra)}.csv"
        assert main(["evaluate", *pair, "--conventions", "evo", *extra, "--csv", str(out), "--no-progress"]) == 0
        tables.append(pd.read_csv(out))
    assert tables[0]["ate_rmse"][0] == tables[1]["ate_rmse"][0]
    ape = _evo_ape_rmse(t / "freiburg1_xyz-groundtruth.txt", t / "freiburg1_xyz-rgbdslam.txt")
    assert tables[1]["ate_rmse"][0] == pytest.approx(ape, rel=1e-12)


def _evo_ape_rmse(gt_path, est_path) -> float:
    """evo_ape's translation RMSE without alignment (its default), by evo's Python API."""
    from evo.core import metrics, sync
    from evo.tools import file_interface

    ref = file_interface.read_tum_trajectory_file(str(gt_path))
    est = file_interface.read_tum_trajectory_file(str(est_path))
    ref, est = sync.associate_trajectories(ref, est, max_diff=0.01)
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((ref, est))
    return float(ape.get_statistic(metrics.StatisticsType.rmse))
