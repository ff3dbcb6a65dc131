"""lorisnb's ``tum``, ``rpg`` and ``vio`` presets against the tools that define them, on inputs made
from the real TUM pairs (../shared/data/tum-rgbd) with a fixed seed: estimate stamps exactly
``max_diff`` from a ground-truth stamp (some repeated), three estimate stamps per ground-truth
interval with exact ties, a late and scaled estimate (``t_offset``), gaps in both files, a short run;
first-N alignment, se3 / sim3 / posyaw / none, rpg's relative error at custom and default lengths.

REF holds what the tools themselves gave on exactly these files, on 2026-11-26:

- ``tum``: TUM RGB-D benchmark tools, github.com/jbriales/rgbd_benchmark_tools commit
  80723c9c9530481ec7dc92d3c3f77575f6a25bec (TUM's scripts as distributed), converted to Python 3
  with lib2to3 and ``numpy.linalg.linalg.svd`` read as ``numpy.linalg.svd``:
  ``associate.associate(read_file_list(GT), read_file_list(EST), offset, max_difference)`` then
  ``evaluate_ate.align`` and its RMSE, as ``evaluate_ate.py GT EST --offset O --max_difference D``
  prints it (offset -1.7 for the ``late_scaled`` files, max_difference 0.01 for ``*_limit_0.01``,
  else 0.02). Value: (pairs, ATE RMSE m).
- ``rpg M N``: rpg_trajectory_evaluation, github.com/uzh-rpg/rpg_trajectory_evaluation commit
  8c8ceec55c5c5094a6494208cfc5f54afe0bbc4d (Python 3 by lib2to3, ``np.linalg.linalg.svd`` read as
  ``np.linalg.svd``): ``trajectory_loading.load_estimate_and_associate(GT, EST, matches, max_diff=D)``,
  ``align_utils.alignTrajectory(p_es, p_gt, q_es, q_gt, M, N)`` (identity for ``none``), the aligned
  poses as ``Trajectory.align_trajectory`` builds them, ``compute_trajectory_errors.compute_absolute_error``.
  Value: (pairs, RMSE of e_trans m, RMSE of e_rot deg, scale).
- ``rel ...``: the same load and ``alignTrajectory(..., 'sim3', -1)`` scale, then
  ``compute_trajectory_errors.compute_relative_error(p_es, q_es, p_gt, q_gt, eye(4), L, 0.2 L,
  get_distance_from_start(p_gt), scale)`` at L in [0.3, 1.0] m, or at rpg's default lengths (10..50 %
  of the whole ground-truth file's path length, truncated to cm, as ``Trajectory`` computes them).
  Value per length: (L m, samples, mean e_trans_perc %, mean e_rot_deg_per_m deg/m).

rpg reads every row (``np.loadtxt``): a repeated estimate stamp is two poses there, so the rpg rows
are compared with ``repeated="keep"``; TUM's ``read_file_list`` is a dict (the last row of a
repeated stamp), the ``tum`` preset's ``repeated="drop"``.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import lorisnb as ln
from lorisnb.cli import main

FR1 = ("freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt")
FR2 = ("fr2_desk_groundtruth.txt", "fr2_desk_ORB.txt")


def _load(path: Path) -> np.ndarray:
    return np.loadtxt(path, comments="#")


def _save(path: Path, rows: np.ndarray, stamp: str = "%.6f") -> Path:
    lines = [" ".join([stamp % r[0]] + ["%.9g" % v for v in r[1:]]) for r in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


def make_cases(tum: Path, out: Path) -> dict[str, tuple[Path, Path]]:
    """name -> (ground truth, estimate) files written into ``out``."""
    rng = np.random.default_rng(20261126)
    cases: dict[str, tuple[Path, Path]] = {}
    for tag, (g, e) in (("fr1", FR1), ("fr2", FR2)):
        gt_path = tum / g
        G, E = _load(gt_path), _load(tum / e)
        # estimate stamps at ground-truth stamps +- max_diff (at the limit) or +- max_diff / 2, 4 decimals:
        # some land on the same stamp (a repeated estimate stamp)
        for md in (0.02, 0.01):
            idx = np.sort(rng.choice(len(G), 300, replace=False))
            shift = md * rng.choice([-1.0, 1.0, 0.5], 300)
            rows = np.column_stack([G[idx, 0] + shift, G[idx, 1:] + rng.normal(0, 0.01, (300, 7))])
            rows = rows[np.argsort(np.round(rows[:, 0], 4), kind="stable")]  # in time order, as written
            cases[f"{tag}_limit_{md}"] = (gt_path, _save(out / f"{tag}_limit_{md}.txt", rows, "%.4f"))
        # three estimate poses per ground-truth interval (many candidates for one ground-truth stamp),
        # two of them exactly halfway (ties)
        gs = G[:600, 0]
        mids = (gs[1:] + gs[:-1]) / 2
        st = np.sort(np.concatenate([mids, mids + 0.001, gs[:-1] + 0.0005]))
        pose = np.column_stack([np.interp(st, G[:, 0], G[:, k]) for k in range(1, 8)])
        rows = np.column_stack([st, pose + rng.normal(0, 0.01, pose.shape)])
        cases[f"{tag}_many"] = (gt_path, _save(out / f"{tag}_many.txt", rows, "%.5f"))
        # the estimate 1.7 s late, scaled by 3.7 (t_offset -1.7 undoes the delay, sim3 the scale)
        rows = E.copy()
        rows[:, 0] += 1.7
        rows[:, 1:4] *= 3.7
        cases[f"{tag}_late_scaled"] = (gt_path, _save(out / f"{tag}_late_scaled.txt", rows))
        # gaps in both files
        keep_e = np.ones(len(E), bool)
        for _ in range(5):
            a = rng.integers(0, len(E) - 50)
            keep_e[a : a + rng.integers(5, 50)] = False
        keep_g = np.ones(len(G), bool)
        for _ in range(5):
            a = rng.integers(0, len(G) - 80)
            keep_g[a : a + rng.integers(5, 80)] = False
        cases[f"{tag}_gaps"] = (
            _save(out / f"{tag}_gaps_gt.txt", G[keep_g]),
            _save(out / f"{tag}_gaps.txt", E[keep_e]),
        )
        # a short run: 12 poses
        a = len(E) // 2 + int(rng.integers(0, 100))  # inside the ground truth
        cases[f"{tag}_short"] = (gt_path, _save(out / f"{tag}_short.txt", E[a : a + 12]))
    return cases


REF = {
    "fr1_gaps": {
        "rel 0.3 1.0": [
            (0.3, 466, 6.5743885939155415, 2.709272071755246),
            (1.0, 476, 1.8430027020089577, 0.8083266704105019),
        ],
        "rel default": [
            (0.91, 478, 2.0727778832223622, 0.879569022789903),
            (1.82, 439, 1.0344855198962128, 0.48801001453428594),
            (2.74, 391, 0.6687855873681273, 0.317443215213319),
            (3.65, 324, 0.5919113273361508, 0.2856981238895411),
            (4.57, 272, 0.43704502823726255, 0.20546054206221465),
        ],
        "rpg none -1": (604, 0.021078983222875457, 0.7160800339498563, 1.0),
        "rpg posyaw -1": (604, 0.014561944641327451, 1.5544361272153626, 1.0),
        "rpg posyaw 1": (604, 0.020341534230807628, 0.7116889695964477, 1.0),
        "rpg posyaw 20": (604, 0.01676440935497376, 3.1536675027125485, 1.0),
        "rpg se3 -1": (604, 0.013638762239620477, 2.539320767225856, 1.0),
        "rpg se3 1": (604, 0.02036922780881679, 0.7059778508720677, 1.0),
        "rpg se3 5": (604, 0.2522827557278546, 88.07776816762306, 1.0),
        "rpg sim3 -1": (604, 0.013610853976597295, 2.539320767225856, 1.0045495084229141),
        "rpg sim3 20": (604, 0.045671935496450884, 9.800895700182824, 0.8379873058004591),
        "tum": (604, 0.013638762239620492),
    },
    "fr1_late_scaled": {"tum": (786, 0.49645357524832867)},
    "fr1_limit_0.01": {
        "rel 0.3 1.0": [
            (0.3, 263, 7.89197809114945, 8.455705402284423),
            (1.0, 259, 2.2984705643337127, 2.5086580559355207),
        ],
        "rel default": [
            (0.91, 260, 2.5166840060388758, 2.7692312656624876),
            (1.83, 225, 1.2604445245815576, 1.406787374310117),
            (2.74, 193, 0.9001321590854764, 0.9986563515869752),
            (3.66, 168, 0.6627524441437477, 0.6678070928728774),
            (4.57, 152, 0.5064746796250253, 0.5535244873844778),
        ],
        "rpg none -1": (300, 0.017576295405284333, 1.945030837947725, 1.0),
        "rpg posyaw -1": (300, 0.01756924263309313, 1.9466011341168874, 1.0),
        "rpg posyaw 1": (300, 0.018502502319070104, 1.9991332543356537, 1.0),
        "rpg posyaw 20": (300, 0.018312613256667765, 2.0511241645856133, 1.0),
        "rpg se3 -1": (300, 0.017549874851893587, 1.9711589743093514, 1.0),
        "rpg se3 1": (300, 0.018517574951244738, 2.0285808708907895, 1.0),
        "rpg se3 5": (300, 0.2666754332552342, 108.48880724722507, 1.0),
        "rpg sim3 -1": (300, 0.017501454644821463, 1.9711589743093514, 0.9931209545497495),
        "rpg sim3 20": (300, 0.05092998018744575, 16.689234435498758, 0.9856665032351595),
        "tum": (296, 0.017575977024733038),
    },
    "fr1_limit_0.02": {
        "rel 0.3 1.0": [
            (0.3, 269, 8.600946440574408, 8.920127317338984),
            (1.0, 259, 2.5905609921678527, 2.5639226937739092),
        ],
        "rel default": [
            (0.91, 261, 2.8031967904018913, 2.8821980870378137),
            (1.83, 227, 1.3864358500361331, 1.4863493979144482),
            (2.74, 201, 0.8671931005959262, 0.9367675945866152),
            (3.66, 175, 0.7374908489107058, 0.7124040381734197),
            (4.57, 158, 0.5298841949366806, 0.5674672898563591),
        ],
        "rpg none -1": (300, 0.018475875083886234, 2.0210396580769716, 1.0),
        "rpg posyaw -1": (300, 0.018434039518255153, 2.0253131888487097, 1.0),
        "rpg posyaw 1": (300, 0.025330496319047113, 2.162680428831789, 1.0),
        "rpg posyaw 20": (300, 0.01851386640149168, 2.021135326175787, 1.0),
        "rpg se3 -1": (300, 0.018425121130700182, 2.0389780085303952, 1.0),
        "rpg se3 1": (300, 0.02669054123469347, 2.344397571968816, 1.0),
        "rpg se3 5": (300, 0.10418169919894209, 38.77086703330686, 1.0),
        "rpg sim3 -1": (300, 0.01830647479092808, 2.0389780085303952, 0.9888040775146114),
        "rpg sim3 20": (300, 0.08168418058634405, 29.846829591728458, 0.994742709965264),
        "tum": (298, 0.018430245943719382),
    },
    "fr1_many": {
        "rel 0.3 1.0": [
            (0.3, 534, 7.708968196713767, 8.573449946994618),
            (1.0, 363, 2.241201075823971, 2.591580209994407),
        ],
        "rel default": [
            (0.91, 383, 2.499109485740292, 2.7534339443667033),
            (1.83, 146, 1.4544442791151655, 1.3737712733210865),
            (2.74, 0, None, None),
            (3.66, 0, None, None),
            (4.57, 0, None, None),
        ],
        "rpg none -1": (601, 0.01737511695706871, 1.9856273719486903, 1.0),
        "rpg posyaw -1": (601, 0.017361705406866577, 1.9903303858732972, 1.0),
        "rpg posyaw 1": (601, 0.030402479894102694, 2.0005635696183566, 1.0),
        "rpg posyaw 20": (601, 0.018667185397587462, 2.6328159715501513, 1.0),
        "rpg se3 -1": (601, 0.017351948682782312, 2.9482423998497373, 1.0),
        "rpg se3 1": (601, 0.027712601835903867, 3.1599579794667343, 1.0),
        "rpg se3 5": (601, 0.25588873152635006, 88.50370004758612, 1.0),
        "rpg sim3 -1": (601, 0.01723153669527931, 2.9482423998497373, 0.988070998448355),
        "rpg sim3 20": (601, 0.10947018530554373, 160.9626976569848, 0.5015301522946837),
        "tum": (601, 0.017351948682782323),
    },
    "fr1_short": {
        "rpg none -1": (12, 0.01546481505978432, 0.5440896259122752, 1.0),
        "rpg posyaw -1": (12, 0.007524924099787049, 3.3531837080326112, 1.0),
        "rpg posyaw 1": (12, 0.009820903384774246, 0.52914009302022, 1.0),
        "rpg se3 -1": (12, 0.007374630979446918, 30.855291645791812, 1.0),
        "rpg se3 1": (12, 0.00984047295918218, 0.5369241880738622, 1.0),
        "rpg se3 5": (12, 0.01152930816069838, 58.37354337645435, 1.0),
        "rpg sim3 -1": (12, 0.006945110151192032, 30.855291645791812, 1.1040234406159193),
        "tum": (12, 0.00737463097944693),
    },
    "fr2_gaps": {
        "rel 0.3 1.0": [
            (0.3, 1743, 3.7425033245306025, 1.9965152307253964),
            (1.0, 1816, 1.142582803775076, 0.596421957936629),
        ],
        "rel default": [
            (2.03, 1693, 0.7191615410704375, 0.39126776433777954),
            (4.06, 1585, 0.6130860914281856, 0.2864941499844594),
            (6.09, 1365, 0.6940522280602683, 0.25490518382254324),
            (8.12, 1136, 0.6823289558970621, 0.21919339195620716),
            (10.15, 895, 0.5869714029477238, 0.17577577300444666),
        ],
        "rpg none -1": (2023, 3.1760464775093644, 132.4996995191089, 1.0),
        "rpg posyaw -1": (2023, 1.963009086265713, 122.36887777473193, 1.0),
        "rpg posyaw 1": (2023, 3.21482494916635, 117.90201977119254, 1.0),
        "rpg posyaw 20": (2023, 2.9866557291121625, 119.68411377233723, 1.0),
        "rpg se3 -1": (2023, 0.00816200028348182, 0.9917493705256923, 1.0),
        "rpg se3 1": (2023, 0.04257902290599661, 1.299637543084435, 1.0),
        "rpg se3 5": (2023, 0.7679105145226639, 34.36533592845967, 1.0),
        "rpg sim3 -1": (2023, 0.006203138852112911, 0.9917493705256923, 0.9969833749280417),
        "rpg sim3 20": (2023, 0.3899457687207623, 13.688106524462992, 1.012039885700692),
        "tum": (2023, 0.008162000283481031),
    },
    "fr2_late_scaled": {"tum": (2223, 4.776533324327836)},
    "fr2_limit_0.01": {
        "rel 0.3 1.0": [
            (0.3, 250, 13.261664034946152, 8.418851462068),
            (1.0, 263, 3.8740363434654634, 2.6437336246967185),
        ],
        "rel default": [
            (2.03, 253, 2.4150868312732703, 1.2566849753825826),
            (4.06, 231, 1.7037139112713837, 0.6370325182116531),
            (6.1, 198, 1.4419602978016566, 0.4289561389790172),
            (8.13, 174, 1.135533811500081, 0.320058435749467),
            (10.16, 130, 0.7835249699996093, 0.273075434495978),
        ],
        "rpg none -1": (300, 0.017810930634018767, 2.000782163863857, 1.0),
        "rpg posyaw -1": (300, 0.017739137007876576, 2.0014914026619004, 1.0),
        "rpg posyaw 1": (300, 0.05446040653983783, 2.315139948470175, 1.0),
        "rpg posyaw 20": (300, 0.026783688220597745, 2.04563551950745, 1.0),
        "rpg se3 -1": (300, 0.017711253614245876, 2.0028909412233906, 1.0),
        "rpg se3 1": (300, 0.06428069911574041, 2.6425219848180213, 1.0),
        "rpg se3 5": (300, 0.13188702209121497, 5.728745798672035, 1.0),
        "rpg sim3 -1": (300, 0.017704891006888428, 2.0028909412233906, 0.9997257316728839),
        "rpg sim3 20": (300, 0.05632510500264105, 2.8744826539958335, 1.0149697401161688),
        "tum": (300, 0.017711253614245873),
    },
    "fr2_limit_0.02": {
        "rel 0.3 1.0": [
            (0.3, 228, 14.706459643314146, 8.346859469471726),
            (1.0, 253, 4.132817706218701, 2.5484529859018568),
        ],
        "rel default": [
            (2.03, 237, 2.506039416500394, 1.301968998552478),
            (4.06, 231, 1.6467301628389759, 0.6011889938034244),
            (6.1, 195, 1.3608610533371575, 0.40803861964870364),
            (8.13, 157, 1.1400606216184723, 0.3006735344980195),
            (10.16, 122, 0.8365553249083599, 0.22247288442977853),
        ],
        "rpg none -1": (300, 0.017843414630196057, 1.9496389340207603, 1.0),
        "rpg posyaw -1": (300, 0.017813254346360895, 1.9502102035043696, 1.0),
        "rpg posyaw 1": (300, 0.03909815082475332, 2.1128353697634035, 1.0),
        "rpg posyaw 20": (300, 0.020044264996906695, 1.9677541718702836, 1.0),
        "rpg se3 -1": (300, 0.017810638952620084, 1.951022068869636, 1.0),
        "rpg se3 1": (300, 0.05530722389077769, 2.4760326804173265, 1.0),
        "rpg se3 5": (300, 1.3318566820232878, 67.271194978454, 1.0),
        "rpg sim3 -1": (300, 0.017810529552943297, 1.951022068869636, 1.0000364297909399),
        "rpg sim3 20": (300, 0.03722858571825086, 2.049073332712073, 0.9881822286636636),
        "tum": (300, 0.017810638952620094),
    },
    "fr2_many": {
        "rel 0.3 1.0": [(0.3, 349, 7.972351334799453, 9.89423988920597), (1.0, 0, None, None)],
        "rel default": [
            (2.03, 0, None, None),
            (4.06, 0, None, None),
            (6.1, 0, None, None),
            (8.13, 0, None, None),
            (10.16, 0, None, None),
        ],
        "rpg none -1": (603, 0.01741355288573341, 1.957532989981721, 1.0),
        "rpg posyaw -1": (603, 0.017409665845862052, 1.960320318152372, 1.0),
        "rpg posyaw 1": (603, 0.0214625841064332, 2.0610759508763064, 1.0),
        "rpg posyaw 20": (603, 0.01741923440969264, 1.9630665184346572, 1.0),
        "rpg se3 -1": (603, 0.017406393431581568, 2.2051695233493382, 1.0),
        "rpg se3 1": (603, 0.021993571657343957, 2.666989046059135, 1.0),
        "rpg se3 5": (603, 0.1272722411628717, 44.508782316609725, 1.0),
        "rpg sim3 -1": (603, 0.01718178498488314, 2.2051695233493382, 0.9773729690042868),
        "rpg sim3 20": (603, 0.17934233863178078, 22.693493966919448, 0.021493670573403543),
        "tum": (603, 0.01740639343158157),
    },
    "fr2_short": {
        "rpg none -1": (12, 4.81684544487114, 133.19271087289388, 1.0),
        "rpg posyaw -1": (12, 0.03227626010284591, 118.36767453151643, 1.0),
        "rpg posyaw 1": (12, 0.06076891037585333, 118.36258654651857, 1.0),
        "rpg se3 -1": (12, 0.003480046669292692, 36.45294790994779, 1.0),
        "rpg se3 1": (12, 0.0045384474370039115, 0.33389316268929836, 1.0),
        "rpg se3 5": (12, 0.006892450259492378, 127.31462608684551, 1.0),
        "rpg sim3 -1": (12, 0.0031385716807432996, 36.45294790994779, 0.924606461199613),
        "tum": (12, 0.0034800466692927615),
    },
}


REL = 1e-9


@pytest.fixture(scope="module")
def cases(data, tmp_path_factory):
    return make_cases(data.tum, tmp_path_factory.mktemp("tum_rpg_cases"))


def _max_diff(name: str) -> float:
    return 0.01 if name.endswith("0.01") else 0.02


def _row(est: Path, gt: Path, conventions: str, **options):
    """The one sequence row of ``evaluate_pairs``; plausibility warnings (a scaled estimate, few
    poses) are not what these tests check."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ln.LorisWarning)
        ev = ln.evaluate_pairs(est, gt, conventions=conventions, jobs=1, **options)
    table = ev.sequences()
    assert len(table) == 1, ev
    return ev, table.iloc[0]


@pytest.mark.parametrize("name", sorted(REF))
def test_tum_evaluate_ate_on_generated_pairs(cases, name):
    gt, est = cases[name]
    pairs, ate = REF[name]["tum"]
    offset = -1.7 if "late" in name else 0.0
    _, row = _row(est, gt, "tum", max_diff=_max_diff(name), t_offset=offset)
    assert row["matched"] == pairs
    assert row["ate_rmse"] == pytest.approx(ate, rel=REL)


RPG_NAMES = sorted(n for n in REF if "late" not in n)


@pytest.mark.parametrize("name", RPG_NAMES)
def test_rpg_absolute_errors_on_generated_pairs(cases, name):
    gt, est = cases[name]
    for key, value in REF[name].items():
        if not key.startswith("rpg "):
            continue
        pairs, ate, aoe, scale = value
        method, n = key.split()[1], int(key.split()[2])
        opts = {} if n == -1 else {"align_frames": n}
        # the vio preset is rpg's posyaw; rpg reads every row of a repeated stamp
        conv = "vio" if method == "posyaw" else "rpg"
        if method != "posyaw":
            opts["align"] = method
        _, row = _row(est, gt, conv, max_diff=_max_diff(name), repeated="keep", **opts)
        assert row["matched"] == pairs, key
        assert row["ate_rmse"] == pytest.approx(ate, rel=REL), key
        assert row["aoe_rmse"] == pytest.approx(aoe, rel=1e-9, abs=1e-9), key
        assert row["scale"] == pytest.approx(scale, rel=REL), key


@pytest.mark.parametrize("name", [n for n in RPG_NAMES if "short" not in n])
def test_rpg_relative_errors_on_generated_pairs(cases, name):
    gt, est = cases[name]
    ev, _ = _row(est, gt, "rpg", max_diff=_max_diff(name), repeated="keep")
    for key, lengths in (("rel 0.3 1.0", [0.3, 1.0]), ("rel default", None)):
        table = ev.relative() if lengths is None else ev.relative(lengths=lengths)
        got = {round(float(r.length), 6): r for r in table.itertuples()}
        expected = [v for v in REF[name][key] if v[1] >= 2]  # rpg: "Too few samples! Will not compute."
        for length, samples, trans_perc, deg_per_m in expected:
            r = got[round(length, 6)]
            assert r.samples == samples, (key, length)
            assert r.trans_perc_mean == pytest.approx(trans_perc, rel=1e-9), (key, length)
            assert r.rot_deg_per_m_mean == pytest.approx(deg_per_m, rel=1e-8), (key, length)
        assert len(table) == len(expected), key


def test_tum_preset_keeps_the_last_row_of_a_repeated_stamp_as_tum(cases):
    """fr1_limit_0.01 has 300 estimate rows on 296 distinct stamps: TUM (a dict) pairs 296."""
    gt, est = cases["fr1_limit_0.01"]
    assert len(np.unique(np.loadtxt(est)[:, 0])) == REF["fr1_limit_0.01"]["tum"][0] == 296
    assert REF["fr1_limit_0.01"]["rpg se3 -1"][0] == 300  # rpg: every row


@pytest.mark.parametrize("preset, ref", [("rpg", "rpg sim3 -1"), ("vio", "rpg posyaw -1")])
def test_rpg_preset_pairs_every_row_as_rpg(cases, preset, ref):
    """rpg_trajectory_evaluation reads every row (``np.loadtxt``) and pairs each: the rpg and vio
    presets dropped the earlier rows of a repeated stamp (296 pairs instead of rpg's 300)."""
    gt, est = cases["fr1_limit_0.01"]
    pairs, ate, _, scale = REF["fr1_limit_0.01"][ref]
    _, row = _row(est, gt, preset, max_diff=0.01)
    assert row["matched"] == pairs
    assert row["ate_rmse"] == pytest.approx(ate, rel=REL)


def _cli(capsys, *args: str) -> tuple[int, str]:
    code = main(["evaluate", *args, "--no-progress", "--jobs", "1"])
    out = capsys.readouterr()
    return code, out.out + out.err


@pytest.mark.parametrize("align", ["se3", "sim3"])
def test_degenerate_fit_names_only_remedies_that_run(cases, capsys, align):
    """A fit on the first 2 matched poses (the rotation about their line is arbitrary) is refused;
    every remedy the message names must itself run: for sim3, '--align-frames 1' alone is refused
    ('a scale needs 2 poses'), so the message offered a dead end."""
    gt, est = cases["fr1_gaps"]
    base = [str(est), "--gt", str(gt), "--conventions", "rpg", "--align", align]
    code, text = _cli(capsys, *base, "--align-frames", "2")
    assert code == 1
    msg = next(line for line in text.splitlines() if "can be determined" in line)
    remedies = [part.split(")")[0] for part in msg.split("(--")[1:]]
    assert remedies, msg
    for remedy in remedies:
        if "N" in remedy.split():
            continue  # --align-frames N: a placeholder
        extra = ("--" + remedy).split()
        options = [*base[:-2], "--align", align] if "--align" not in extra else base[:-2]
        code, out = _cli(capsys, *options, *extra)
        assert code == 0, (remedy, out)
    # the first-pose fit the sim3 message names is rpg's se3 on one pose
    if align == "sim3":
        assert "--align se3 --align-frames 1" in msg
        _, row = _row(est, gt, "rpg", align="se3", align_frames=1, repeated="keep")
        assert row["ate_rmse"] == pytest.approx(REF["fr1_gaps"]["rpg se3 1"][1], rel=REL)


def test_align_frames_above_the_matched_poses_is_said(cases, capsys):
    """rpg refuses n_aligned above the matched poses (AssertionError); lorisnb fits on all of them, which
    the conventions line still calls 'the first N': now a warning says so."""
    gt, est = cases["fr1_short"]
    code, text = _cli(capsys, str(est), "--gt", str(gt), "--conventions", "rpg", "--align-frames", "50")
    assert code == 0
    assert "align_frames=50 (--align-frames) but only 12 poses are matched" in text
    ref = REF["fr1_short"]["rpg sim3 -1"]
    _, row = _row(est, gt, "rpg", align_frames=50)
    assert row["ate_rmse"] == pytest.approx(ref[1], rel=REL)


#: TUM's ``evaluate_rpe.py`` (same repository and commit as ``tum`` above, Python 3 by lib2to3, its h5py
#: import left out): ``evaluate_trajectory(read_trajectory(GT), read_trajectory(EST), param_max_pairs=0,
#: param_fixed_delta=True, param_delta=D, param_delta_unit=U, param_offset=O, param_scale=S)``, i.e.
#: ``evaluate_rpe.py GT EST --fixed_delta --max_pairs 0 --delta D --delta_unit U --offset O --scale S``.
#: Key: (pair, D, U, O, S); value: (pairs, translational RMSE m, translational mean m, rotational RMSE deg).
#: "fr1" / "fr2" are the bundled files themselves, the others the generated files above.
TUM_RPE = {
    ("fr1", 1.0, "s", 0.0, 1.0): (753, 0.021217444079126714, 0.019523663952437948, 0.9344804594167394),
    ("fr1", 10, "f", 0.0, 2.0): (773, 0.1099321789184242, 0.09902233562036222, 0.6764570545074282),
    ("fr2", 0.5, "s", 0.013, 1.0): (2028, 0.0064727356662098645, 0.005782303361957811, 0.5064276505822543),
    ("fr2", 0.2, "m", 0.0, 1.0): (1960, 0.006977650253406777, 0.006364731846856918, 0.4464054848481982),
    ("fr2", 5, "deg", 0.0, 1.0): (2003, 0.006340114555308015, 0.00566805331073827, 0.3955631998589287),
    ("fr2_gaps", 1, "f", 0.0, 1.0): (1856, 0.0033973014329903603, 0.002976152530949805, 0.2659596638345321),
    ("fr1_many", 1.0, "s", 0.0, 1.0): (1496, 0.025880299332099573, 0.023724428231943106, 2.846047350559436),
    ("fr2_late_scaled", 1.0, "s", -1.7, 1 / 3.7): (
        1998,
        0.007161111774263525,
        0.006501852131797886,
        0.45500542298954605,
    ),
}


@pytest.mark.parametrize("key", list(TUM_RPE), ids=lambda k: "-".join(map(str, k)))
def test_tum_evaluate_rpe_is_reproduced(data, cases, key):
    """lorisnb's own RPE (the presets' default) pairs associated poses and composes the paper's
    error; TUM's evaluate_rpe.py pairs every estimate pose, matches the ground truth within two of
    its median steps, never ends a pair at the last pose and composes B A^-1: rpe.tum_rpe is that
    tool, to the pair (there was no way to get its numbers)."""
    from lorisnb.core.metrics.pairs import tum_rpe

    name, delta, unit, offset, scale = key
    files = {"fr1": (data.tum / FR1[0], data.tum / FR1[1]), "fr2": (data.tum / FR2[0], data.tum / FR2[1])}
    gt_path, est_path = files.get(name) or cases[name]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ln.LorisWarning)  # fr2's ground truth repeats a stamp: its last pose
        gt, est = ln.read_trajectory(gt_path, "tum"), ln.read_trajectory(est_path, "tum")
    r = tum_rpe(gt.stamps, gt.positions, gt.quaternions, est.stamps, est.positions, est.quaternions,
                delta, unit, offset, scale)  # fmt: skip
    pairs, trans_rmse, trans_mean, rot_rmse = TUM_RPE[key]
    assert r["trans"].size == pairs
    assert np.sqrt(np.mean(r["trans"] ** 2)) == pytest.approx(trans_rmse, rel=1e-12)
    assert np.mean(r["trans"]) == pytest.approx(trans_mean, rel=1e-12)
    assert np.sqrt(np.mean(r["rot"] ** 2)) == pytest.approx(rot_rmse, rel=1e-9)
