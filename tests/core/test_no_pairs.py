"""Sequences with no RPE pair (shorter than the RPE step, cut by --t-end, a handful of poses) and
inputs evo refuses: NaN statistics with a warning, or a one-line error, never a traceback; the
rest of the evaluation scored as usual. Real data: TUM freiburg1_xyz (rgbdslam against its ground
truth) and the ICRA 2020 ORB-SLAM2 result of cafe 1-1."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pandas as pd
import pytest
from helpers import write

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.lifelong.sweep import sweep
from lorisnb.core.metrics.relations import error_statistics, masked_statistics

ORB = "per-seq/orbslam2_rgbd/cafe_1_1_orbslam2-original.txt"
RPE = ["rpe_trans_rmse", "rpe_rot_rmse", "c_rpe_trans_rmse", "rpe_trans_mean", "rpe_rot_max", "c_rpe_rot_median"]


@pytest.fixture
def tum(data, tmp_path):
    """(ground truth, full estimate, its first 5 poses, a file of comments only)."""
    gt, est = data.tum / "freiburg1_xyz-groundtruth.txt", data.tum / "freiburg1_xyz-rgbdslam.txt"
    lines = [x for x in est.read_text().splitlines() if x.strip() and not x.startswith("#")]
    five = write(tmp_path, "in/est_five.txt", "\n".join(lines[:5]) + "\n")
    comments = write(tmp_path, "in/est_comments.txt", "# only comments\n# x\n")
    return gt, est, five, comments


def test_masked_statistics_of_no_value_is_nan():
    """No value at all (a sequence with no RPE pair) over any grid of masks: NaN everywhere, the
    grid's shape, as error_statistics promises for an empty array."""
    for shape in ((3, 2), (1,), (4, 1, 2)):
        out = masked_statistics(np.zeros(0), np.zeros((*shape, 0), bool))
        assert set(out) == {"mean", "median", "std", "min", "max", "sse"}
        assert all(a.shape == shape and np.isnan(a).all() for a in out.values())
    assert all(math.isnan(v) for v in error_statistics(np.zeros(0)).values())


def _run(capsys, tmp_path, args, name="out.csv"):
    out = tmp_path / name
    rc = main(["evaluate", *map(str, args), "--no-progress", "--csv", str(out)])
    return rc, pd.read_csv(out), capsys.readouterr().err


@pytest.mark.parametrize(
    "which, options, delta",
    [
        ("five", [], "1 s"),
        ("full", ["--rpe-delta", "100"], "100 s"),
        ("full", ["--t-end", "1305031103"], "1 s"),
        ("five", ["--conventions", "tum"], "1 s"),
        ("five", ["--conventions", "evo", "--rpe-delta", "10"], "10 frame(s)"),
        ("full", ["--conventions", "evo", "--rpe-delta", "100", "--rpe-unit", "m"], "100 m"),
        ("five", ["--rpe-delta", "50", "--rpe-unit", "m", "--rpe-all-pairs"], "50 m"),
    ],
)
def test_evaluate_a_sequence_without_rpe_pair(tum, tmp_path, capsys, which, options, delta):
    gt, est, five, _ = tum
    path = five if which == "five" else est
    rc, table, err = _run(capsys, tmp_path, [path, "--gt", gt, *options])
    assert rc == 0 and "Traceback" not in err and len(table) == 1
    row = table.iloc[0]
    assert row["rpe_pairs"] == 0 and row["c_rpe_pairs"] == 0
    assert all(math.isnan(row[c]) for c in RPE)
    assert row["matched"] > 0 and np.isfinite(row["ate_rmse"]) and np.isfinite(row["cr"])
    assert f"{path.name}, seq 1: no RPE pair over {delta}" in err and "statistics are NaN" in err
    # the other metrics are those of the same evaluation with an RPE step that has pairs
    if "--t-end" not in options and which == "full":
        kept = [o for o in options if o not in ("--rpe-delta", "100", "--rpe-unit", "m")]
        rc2, ref, err2 = _run(capsys, tmp_path, [path, "--gt", gt, *kept], "ref.csv")
        assert rc2 == 0 and ref["rpe_pairs"].iloc[0] > 0 and "no RPE pair" not in err2
        for c in ("matched", "ate_rmse", "aoe_rmse", "cr", "cr_t", "cs_r", "ate_median", "c_ate_max"):
            assert row[c] == pytest.approx(ref[c].iloc[0], rel=1e-12)


def test_t_end_leaves_less_than_the_rpe_step(tum, tmp_path, capsys):
    gt, est, _, _ = tum
    rc, table, _ = _run(capsys, tmp_path, [est, "--gt", gt, "--t-end", "1305031103"])
    row = table.iloc[0]
    assert rc == 0 and 0 < row["matched"] < 788  # 24 poses before the cut, CR over the cut ground truth
    assert row["matched"] == 24 and row["cr"] == pytest.approx(0.1930, abs=1e-4)


def test_openloris_folder_with_a_short_file_keeps_every_row(icra20, data, tmp_path, capsys):
    """One file's only sequence is shorter than 1 s: the batch goes on, the good file's numbers are
    those of the file evaluated alone, the short one has NaN RPE and a warning naming it."""
    text = (icra20 / ORB).read_text()
    write(tmp_path, "olf/orb/a.txt", text)
    write(tmp_path, "olf/ds/b.txt", "".join(text.splitlines(keepends=True)[:14]))
    rc, table, err = _run(capsys, tmp_path, [tmp_path / "olf", "--data", data.root])
    assert rc == 0 and len(table) == 2
    short, good = table.set_index("algorithm").loc["ds"], table.set_index("algorithm").loc["orb"]
    assert short["matched"] == 7 and short["rpe_pairs"] == 0 and math.isnan(short["rpe_trans_rmse"])
    assert "ds/b.txt, seq 1: no RPE pair over 1 s" in err and "orb/a.txt" not in err.split("no RPE pair")[0][-20:]
    alone = ln.evaluate(icra20 / ORB, data_root=data.root, progress=False).sequences().iloc[0]
    for c in ("ate_rmse", "cr", "rpe_trans_rmse", "rpe_pairs"):
        assert good[c] == pytest.approx(alone[c], rel=1e-12)
    assert good["ate_rmse"] == pytest.approx(0.4725, abs=1e-4)
    # the lifelong file whose second sequence is a few poses: every row, NaN RPE for that one
    seq2 = "\n".join(text.splitlines()[7:12])
    write(tmp_path, "ll/orb/two.txt", text + "\nseq: 2\n" + seq2.replace("15600048", "15600049") + "\n")
    for mode in ("--lifelong", "--per-seq"):
        main(["evaluate", str(tmp_path / "ll"), "--data", str(data.root), "--no-progress", mode, "--csv",
              str(tmp_path / f"ll{mode}.csv")])  # fmt: skip
        assert "Traceback" not in capsys.readouterr().err
        t = pd.read_csv(tmp_path / f"ll{mode}.csv")
        assert list(t["seq"]) == [1, 2]


def test_python_api_without_rpe_pair(tum):
    """evaluate, sequences, scenes, sweeps and score of a sequence with no RPE pair: NaN, the warning
    once, no exception, in every unit."""
    gt, _, five, _ = tum
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ln.LorisWarning)
        ev = ln.evaluate_pairs(five, gt, progress=False)
    assert any("est_five.txt, seq 1: no RPE pair over 1 s" in str(w.message) for w in caught)
    assert any("no RPE pair" in w for w in ev.warnings)
    seq = ev.sequences(eps=0.01, phi=5)
    assert seq["rpe_pairs"].iloc[0] == 0 and seq[RPE].isna().all(axis=None)
    assert ev.scenes()["cr"].iloc[0] == pytest.approx(ev.sequences()["cr"].iloc[0])
    grid = sweep(ev.errors, eps=[0.01, 0.1, np.inf], phi=[5, np.inf], columns="all")  # with the RPE statistics
    assert len(grid) == 6 and grid[RPE].isna().all(axis=None) and (grid["rpe_pairs"] == 0).all()
    for unit, delta in (("m", 50.0), ("deg", 170.0), ("rad", 3.0), ("f", 100)):
        s = ln.score(ev.errors, rpe_delta=delta, rpe_unit=unit)
        assert s["rpe_pairs"].iloc[0] == 0 and s[RPE].isna().all(axis=None)
        assert s["cr"].iloc[0] == pytest.approx(ev.sequences()["cr"].iloc[0])


# --- crosscheck: evo's exceptions become lorisnb's ------------------------------------------


@pytest.mark.thorough
def test_crosscheck_delta_without_pairs_gives_nan_rows(tum, tmp_path, capsys):
    """evo raises FilterException when a delta gives no pair: lorisnb's crosscheck says so in NaN
    rows (exit status 1: not everything asked was compared), never a traceback."""
    from evo.core import filters, metrics

    gt, est, five, _ = tum
    out = tmp_path / "cc.csv"
    for path, extra in ((est, ["--rpe-metres", "50"]), (five, [])):
        assert main(["crosscheck", str(gt), str(path), *extra, "--csv", str(out), "--force"]) == 1
        err = capsys.readouterr().err
        assert "Traceback" not in err and "2 RPE quantities not compared: no RPE pair" in err
        t = pd.read_csv(out)
        none = t[t["note"].str.startswith("no RPE pair", na=False)]
        assert list(none["quantity"]) == ["rpe_trans_rmse", "rpe_rot_rmse"]
        assert none[["lorisnb", "evo"]].isna().all(axis=None) and "give a smaller delta" in none["note"].iloc[0]
        ident = t["note"].str.startswith("identical pairs", na=False)
        assert ident.sum() >= 17 and t.loc[ident, "agrees"].all()
    # evo itself refuses that delta on these poses (what the rows report)
    poses = ln.read_tum(five)
    se3 = [np.eye(4)] * len(poses)
    for k, p in enumerate(poses.positions):
        se3[k] = np.eye(4)
        se3[k][:3, 3] = p
    with pytest.raises(filters.FilterException):
        metrics.id_pairs_from_delta(se3, 1.0, metrics.Unit.meters)


def test_crosscheck_of_a_file_without_poses(tum, capsys):
    gt, _, _, comments = tum
    for extra in ([], ["--conventions", "evo"]):
        assert main(["crosscheck", str(gt), str(comments), *extra]) == 1
        err = capsys.readouterr().err
        assert "the estimate has no poses" in err and "nan" not in err and "Traceback" not in err


def test_crosscheck_evo_conventions_without_rpe_pair(tum, tmp_path, capsys):
    """--conventions evo on one pose: evo_rpe raises, lorisnb gives NaN with a warning; the table
    says so and the other statistics still agree with evo."""
    gt, est, _, _ = tum
    one = write(tmp_path, "in/est_one.txt", est.read_text().splitlines()[3] + "\n")
    out = tmp_path / "cc.csv"
    assert main(["crosscheck", str(gt), str(one), "--conventions", "evo", "--csv", str(out)]) == 1
    err = capsys.readouterr().err
    assert "Traceback" not in err and "est_one.txt, seq 1: no RPE pair over 1 frame(s)" in err
    t = pd.read_csv(out)
    rpe = t[t["quantity"].str.startswith("rpe_")]
    assert len(rpe) == 14 and rpe[["lorisnb", "evo"]].isna().all(axis=None)
    assert rpe["note"].str.contains("evo_rpe raises").all()
    ape = t[t["quantity"].str.match(r"^(ate|aoe)_") & t["evo"].notna()]
    assert len(ape) == 14 and ape["agrees"].all()


@pytest.mark.thorough
def test_evo_errors_become_lorisnb_errors(tum, tmp_path, capsys):
    """A file evo's reader refuses (commas) and poses evo cannot compute with (NaN rows): one line,
    exit status 1, naming the file or what evo was doing; the classic crosscheck shows lorisnb's
    rows and says evo refuses the file."""
    from lorisnb.tools.peers.crosscheck_reading import crosscheck_reading, evo_read

    gt, est, _, _ = tum
    lines = est.read_text().splitlines()
    comma = write(tmp_path, "in/est_comma.txt", "\n".join(x.replace(" ", ",") for x in lines) + "\n")
    with pytest.raises(ln.ParseError, match="est_comma.txt: evo cannot read this file as tum"):
        evo_read(comma, "tum")
    row = crosscheck_reading(comma).iloc[0]
    assert row["lorisnb"] == 788 and math.isnan(row["evo"]) and row["note"].startswith("evo refuses the file")
    assert main(["crosscheck", str(gt), str(comma), "--conventions", "evo"]) == 1
    assert "est_comma.txt: evo cannot read this file as tum" in capsys.readouterr().err
    out = tmp_path / "cc.csv"
    assert main(["crosscheck", str(gt), str(comma), "--csv", str(out)]) == 0  # lorisnb reads it: every row compared
    assert pd.read_csv(out)["note"].str.startswith("evo refuses the file").sum() == 1
    body = [x for x in lines if not x.startswith("#")]
    nanrow = write(tmp_path, "in/est_nan.txt", "\n".join(body[:100] + ["1305031106.0 nan nan nan nan nan nan nan"]
                                                         + body[100:]) + "\n")  # fmt: skip
    for conv in ("evo", "tum"):
        assert main(["crosscheck", str(gt), str(nanrow), "--conventions", conv]) == 1
        err = capsys.readouterr().err
        assert "error: evo cannot evaluate this pair" in err and "Traceback" not in err


@pytest.mark.thorough
def test_crosscheck_gives_lorisnb_cr(tum, tmp_path):
    """CR, CR-T and CS-R rows hold lorisnb's values (those of evaluate on the same pair and
    options); evo's column is empty."""
    gt, est, _, _ = tum
    for extra, scale in (([], False), (["--scale"], True)):
        out = tmp_path / f"cc{scale}.csv"
        assert main(["crosscheck", str(gt), str(est), *extra, "--csv", str(out)]) == 0
        t = pd.read_csv(out).set_index("quantity")
        ref = ln.evaluate_pairs(est, gt, scale=scale, progress=False).sequences().iloc[0]
        for q in ("cr", "cr_t", "cs_r"):
            assert t.loc[q, "lorisnb"] == pytest.approx(ref[q], rel=1e-12) and math.isnan(t.loc[q, "evo"])
            assert "evo has no equivalent" in t.loc[q, "note"]
        assert t.loc["cr", "lorisnb"] == pytest.approx(0.8839, abs=1e-4)


def test_compare_with_a_short_and_an_empty_algorithm(tum, tmp_path, capsys):
    """compare over trials where one algorithm has no RPE pair and the other no pose at all: every
    metric ranks without an exception, and a test with nothing to compare says so (not 'p nan')."""
    gt, _, five, comments = tum
    for alg, src in (("a", five), ("b", comments)):
        for k in (1, 2):
            write(tmp_path, f"cmp/{alg}/t{k}.txt", src.read_text())
    for metric in ("cr", "cs_r", "c_ate_rmse"):
        rc = main(["compare", str(tmp_path / "cmp"), "--gt", str(gt), "--metric", metric, "--trials-by", r"t(\d+)",
                   "--no-progress"])  # fmt: skip
        out = capsys.readouterr()
        assert rc in (0, 1) and "Traceback" not in out.err and "p nan" not in out.err + out.out
    assert "no two algorithms both have a value of c_ate_rmse there" in out.err + out.out


@pytest.mark.parametrize(
    "options", [[], ["--conventions", "tum"], ["--conventions", "evo", "--rpe-delta", "10", "--columns", "all"]]
)
def test_sweep_of_a_sequence_without_rpe_pair(tum, tmp_path, capsys, options):
    gt, _, five, _ = tum
    out = tmp_path / "sw.csv"
    rc = main(["sweep", str(five), "--gt", str(gt), "--eps", "0.01,inf", "--phi", "5,inf", *options, "--csv", str(out),
               "--no-progress"])  # fmt: skip
    err = capsys.readouterr().err
    assert rc == 0 and "Traceback" not in err and "est_five.txt, seq 1: no RPE pair" in err
    t = pd.read_csv(out)
    assert len(t) == 4 and t.loc[np.isinf(t["eps"]) & np.isinf(t["phi"]), "cr"].iloc[0] == pytest.approx(
        0.0377, abs=1e-4
    )
