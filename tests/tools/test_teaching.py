"""The lab checks teach: a right answer passes, and each typical wrong answer, written as a learner
would write it, fails with an AnswerError (an AssertionError, for nbgrader) whose hint names the
mistake (issue 26). Fast; needs no data except the last test (a real sequence)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from lorisnb.core.simulate import Faults, simulated_errors
from lorisnb.errors import AnswerError
from lorisnb.tools import teaching as teach

# --- Eq. (1) ---------------------------------------------------------------------------------


def correctness_right(ate_m, aoe_deg, eps, phi):
    return (np.asarray(ate_m) <= eps) & (np.asarray(aoe_deg) <= phi)


def correctness_loop(ate_m, aoe_deg, eps, phi):  # right, written with a loop and a list
    return [bool(a <= eps and o <= phi) for a, o in zip(ate_m, aoe_deg, strict=True)]


CORRECTNESS_WRONG = [
    (lambda ate_m, aoe_deg, eps, phi: (ate_m <= eps) | (aoe_deg <= phi), "and or"),
    (lambda ate_m, aoe_deg, eps, phi: np.logical_or(ate_m <= eps, aoe_deg <= phi), "and or"),
    (lambda ate_m, aoe_deg, eps, phi: (ate_m < eps) & (aoe_deg < phi), "inclusive"),
    (lambda ate_m, aoe_deg, eps, phi: (ate_m < eps) & (aoe_deg <= phi), "inclusive"),
    (lambda ate_m, aoe_deg, eps, phi: (ate_m <= eps) & (aoe_deg <= np.deg2rad(phi)), "degrees radians"),
    (lambda ate_m, aoe_deg, eps, phi: (ate_m <= eps) & (np.deg2rad(aoe_deg) <= phi), "degrees radians"),
    (lambda ate_m, aoe_deg, eps, phi: ate_m <= eps, "ate only"),
    (lambda ate_m, aoe_deg, eps, phi: (ate_m <= phi) & (aoe_deg <= eps), "swapped"),
    (lambda ate_m, aoe_deg, eps, phi: ate_m <= eps and aoe_deg <= phi, "element-wise"),
    (lambda ate_m, aoe_deg, eps, phi: aoe_deg <= phi, "aoe only"),
]

# --- Eq. (2), (3) ----------------------------------------------------------------------------


def cr_right(stamps, correct, t_min, t_max, delta):
    held = np.minimum(np.diff(np.append(stamps, t_max)), delta)
    return (held * correct).sum() / (t_max - t_min)


def cr_no_cap(stamps, correct, t_min, t_max, delta):
    held = np.diff(np.append(stamps, t_max))
    return (held * correct).sum() / (t_max - t_min)


def cr_divides_by_tracking_time(stamps, correct, t_min, t_max, delta):
    held = np.minimum(np.diff(np.append(stamps, t_max)), delta)
    return (held * correct).sum() / (t_max - stamps[0])


def cr_counts_poses(stamps, correct, t_min, t_max, delta):
    return np.count_nonzero(correct) / len(correct)


def cr_counts_every_pose(stamps, correct, t_min, t_max, delta):
    return np.minimum(np.diff(np.append(stamps, t_max)), delta).sum() / (t_max - t_min)


def cr_drops_last_pose(stamps, correct, t_min, t_max, delta):
    held = np.minimum(np.diff(stamps), delta)
    return (held * correct[:-1]).sum() / (t_max - t_min)


def cr_last_pose_uncapped(stamps, correct, t_min, t_max, delta):
    held = list(np.minimum(np.diff(stamps), delta)) + [t_max - stamps[-1]]
    return float(np.dot(held, correct) / (t_max - t_min))


def cr_held_since_previous(stamps, correct, t_min, t_max, delta):
    gaps = np.diff(stamps, prepend=t_min)
    return np.where(correct, np.clip(gaps, 0, delta), 0).sum() / (t_max - t_min)


def cr_over_estimate_span(stamps, correct, t_min, t_max, delta):
    held = np.minimum(np.diff(np.append(stamps, t_max)), delta)
    return held @ np.asarray(correct, float) / (stamps[-1] - stamps[0])


def cr_forgets_return(stamps, correct, t_min, t_max, delta):
    (np.minimum(np.diff(np.append(stamps, t_max)), delta) * correct).sum() / (t_max - t_min)


def crt_right(stamps, correct, t_min, t_max, delta):
    return cr_right(stamps, correct, stamps[0], t_max, delta)


# --- Eq. (4) ---------------------------------------------------------------------------------


def csr_right(t0, t_min, first_correct, tau):
    return np.exp(-(t0 - t_min) / tau) if first_correct else 0.0


CSR_WRONG = [
    (lambda t0, t_min, first_correct, tau: np.exp(-(t0 - t_min) / tau), "first pose"),
    (lambda t0, t_min, first_correct, tau: np.exp((t0 - t_min) / tau) if first_correct else 0.0, "tau sign"),
    (lambda t0, t_min, first_correct, tau: max(0.0, 1 - (t0 - t_min) / tau) * first_correct, "linear"),
    (lambda t0, t_min, first_correct, tau: np.exp(-(t0 - t_min) * tau) * first_correct, "the waiting time over"),
    (
        lambda t0, t_min, first_correct, tau: np.exp(-tau / np.float64(t0 - t_min)) * first_correct,
        "the waiting time over",
    ),
]


@pytest.mark.parametrize(
    "check, fn",
    [
        (teach.check_correctness, correctness_right),
        (teach.check_correctness, correctness_loop),
        (teach.check_correct_rate, cr_right),
        (teach.check_correct_rate_tracking, crt_right),
        (teach.check_cs_r, csr_right),
    ],
)
def test_right_answers_pass(check, fn, capsys):
    assert check(fn) is True
    assert capsys.readouterr().out.startswith("✓")


@pytest.mark.parametrize(
    "check, fn, hint",
    [(teach.check_correctness, f, h) for f, h in CORRECTNESS_WRONG]
    + [
        (teach.check_correct_rate, cr_no_cap, "forgot the delta cap"),
        (teach.check_correct_rate, cr_divides_by_tracking_time, "CR vs CR-T"),
        (teach.check_correct_rate, cr_counts_poses, "share of TIME, not of poses"),
        (teach.check_correct_rate, cr_counts_every_pose, "only correct poses earn time"),
        (teach.check_correct_rate, cr_drops_last_pose, "the last pose holds too"),
        (teach.check_correct_rate, cr_last_pose_uncapped, "capped at delta like the others"),
        (teach.check_correct_rate, cr_held_since_previous, "holds FORWARD"),
        (teach.check_correct_rate, cr_over_estimate_span, "ground truth's span"),
        (teach.check_correct_rate, lambda **kw: 100 * cr_right(**kw), "not percentages"),
        (teach.check_cs_r, lambda **kw: 100 * csr_right(**kw), "not percentages"),
        (teach.check_correct_rate, cr_forgets_return, "did you forget `return`"),
        (teach.check_correct_rate_tracking, cr_right, "CR-T vs CR"),
        (teach.check_correct_rate, lambda **kw: 1 / 0, "ZeroDivisionError"),
    ]
    + [(teach.check_cs_r, f, h) for f, h in CSR_WRONG],
)
def test_typical_wrong_answers_get_their_hint(check, fn, hint):
    with pytest.raises(AnswerError) as exc:
        check(fn)
    msg = str(exc.value)
    assert isinstance(exc.value, AssertionError) and msg.startswith("✗")
    assert hint in msg, msg
    if hint not in ("ZeroDivisionError", "did you forget `return`"):
        assert "\nHint (" in msg


def test_a_wrong_answer_no_mistake_explains_still_says_what_is_wrong():
    with pytest.raises(AnswerError) as exc:
        teach.check_correctness(lambda ate_m, aoe_deg, eps, phi: np.zeros(len(ate_m), bool))
    msg = str(exc.value)
    assert "poses differ on case 1" in msg and "Eq. (1) says True" in msg and "Hint" not in msg
    with pytest.raises(AnswerError, match="not written yet"):
        teach.check_cs_r(lambda **kw: (_ for _ in ()).throw(NotImplementedError()))
    with pytest.raises(AnswerError, match="expected the function you wrote"):
        teach.check_cs_r(0.5)
    with pytest.raises(AnswerError, match="returned shape"):
        teach.check_correctness(lambda ate_m, aoe_deg, eps, phi: True)


@pytest.mark.parametrize(
    "answer, hint",
    [
        (0.70, "forgot the delta cap"),
        (0.50, "CR vs CR-T"),
        (80.5, "not percentages"),
        (0.2, None),
        (..., None),
        ("about 0.8", None),
    ],
)
def test_check_value_names_the_mistake_its_value_matches(answer, hint):
    mistakes = {"delta_cap": 0.70, "cr_vs_crt": 0.50}
    assert teach.check_value("CR", 0.81, 0.80, mistakes=mistakes)
    with pytest.raises(AnswerError) as exc:
        teach.check_value("CR", answer, 0.80, mistakes=mistakes, fraction=True)
    assert (hint in str(exc.value)) if hint else "Hint" not in str(exc.value)
    with pytest.raises(AnswerError) as exc:  # not a rate: no percent hint
        teach.check_value("eps (m)", 80.5, 0.80)
    assert "Hint" not in str(exc.value)
    with pytest.raises(AnswerError, match="no answer yet"):
        teach.check_value("CR", ..., 0.8)
    with pytest.raises(ValueError, match="unknown mistake"):
        teach.check_value("CR", 0.8, 0.8, mistakes={"typo": 1.0})


def test_check_choice():
    assert teach.check_choice("visit", 2, 2, "look for the red cross")
    assert teach.check_choice("algorithm", " ORB ", "orb", "")
    with pytest.raises(AnswerError, match="look for the red cross"):
        teach.check_choice("visit", 1, 2, "look for the red cross")
    # numpy's numbers and bools are Python's; True is not the visit 1, nor 1 the answer True
    assert teach.check_choice("visit", np.int64(2), 2, "")
    assert teach.check_choice("re-localized", np.bool_(True), True, "")
    for answer, expected, kind in ((True, 1, "a number"), (1, True, "True or False"), ("2", 2, "a number"),
                                   (2, "orb", "a text"), ([2], 2, "a number")):  # fmt: skip
        with pytest.raises(AnswerError, match=f"expected {kind}. look"):
            teach.check_choice("visit", answer, expected, "look for the red cross")


def test_check_correctness_wants_booleans():
    """Numbers per pose would be truth-tested (any non-zero ATE counted correct): refused, saying
    what to return; the right comparison passes."""
    assert teach.check_correctness(lambda ate_m, aoe_deg, eps, phi: (ate_m <= eps) & (aoe_deg <= phi))
    for wrong in (
        lambda ate_m, aoe_deg, eps, phi: ((ate_m <= eps) & (aoe_deg <= phi)).astype(int),
        lambda ate_m, aoe_deg, eps, phi: np.minimum(eps - ate_m, phi - aoe_deg),
    ):
        with pytest.raises(AnswerError, match="expected True/False per pose"):
            teach.check_correctness(wrong)


def test_checks_on_cases_from_a_real_sequence():
    """The hidden tests' cases: a simulated lifelong run on the real cafe ground truth, where the
    second visit re-localizes wrongly; the right functions pass, the no-cap CR and the CS-R that
    ignores the first pose fail with their hints."""
    import lorisnb as ln
    from lorisnb.io.datasets.paths import sample_data

    gt = ln.load_groundtruth("cafe", sample_data())
    fe = simulated_errors(
        gt,
        {1: Faults(position_noise_m=0.05, lost=((20.0, 40.0),)), 2: Faults(wrong_reloc_at_s=0.0, init_delay_s=10.0)},
        seqs=[1, 2],
    )
    cases = teach.cases_from(fe, 1.0, 30.0, 1.0, 60.0)
    assert len(cases["cs_r"]) == 2 and cases["cs_r"][1]["first_correct"] is False
    assert teach.check_correctness(correctness_right, cases["correctness"])
    assert teach.check_correct_rate(cr_right, cases["correct_rate"])
    assert teach.check_cs_r(csr_right, cases["cs_r"])
    row = ln.score(fe, 1.0, 30.0, 1.0, 60.0).set_index("seq")
    assert cr_right(**cases["correct_rate"][0]) == pytest.approx(row.loc[1, "cr"], abs=1e-12)
    with pytest.raises(AnswerError, match="delta cap"):
        teach.check_correct_rate(cr_no_cap, cases["correct_rate"])
    with pytest.raises(AnswerError, match="first pose"):
        teach.check_cs_r(CSR_WRONG[0][0], cases["cs_r"])


@pytest.fixture(scope="module")
def sample():
    from lorisnb.io.datasets.paths import sample_data

    return sample_data()


def test_lab_checks_compute_their_reference_and_name_the_mistake(sample):
    """The lab checks whose reference lorisnb computes (so the student version shows no solution):
    the right answers pass; the typical wrong ones get their hint."""
    import lorisnb as ln
    from lorisnb.core.lifelong.sweep import eps_at_cr

    gt = ln.load_groundtruth("cafe", sample)
    faults = {1: Faults(position_noise_m=0.05), 2: Faults(wrong_reloc_at_s=0.0, wrong_reloc_offset_m=(4.0, 0.0, 0.0))}
    life = ln.score(simulated_errors(gt, faults, seqs=[1, 2]), 1.0, 30.0, 1.0, 60.0).set_index("seq").loc[2, "cr"]
    per = ln.score(simulated_errors(gt, faults, seqs=[1, 2], mode="per-seq"), 1.0, 30.0, 1.0, 60.0)
    per = per.set_index("seq").loc[2, "cr"]
    assert life == 0.0 and per > 0.99
    assert teach.check_alignment_cr(life, per, gt, faults, 2, 1.0, 30.0, 1.0, 60.0)
    for a, b in ((per, per), (per, life), (life, life)):
        with pytest.raises(AnswerError, match=r"Hint \(alignment\): per-sequence vs lifelong alignment"):
            teach.check_alignment_cr(a, b, gt, faults, 2, 1.0, 30.0, 1.0, 60.0)

    ev = ln.evaluate(sorted((sample.icra20 / "per-seq" / "orbslam2_rgbd").glob("cafe*.txt")), data_root=sample)
    want = eps_at_cr(ev.errors, 0.4, ev.durations(), 30.0, 1.0)["eps"].iloc[0]
    assert want == pytest.approx(0.6265, abs=1e-3)
    assert teach.check_eps_at_cr(want, ev.errors, ev.durations(), 0.4, 30.0, 1.0)
    with pytest.raises(AnswerError, match="you answered 2"):
        teach.check_eps_at_cr(2.0, ev.errors, ev.durations(), 0.4, 30.0, 1.0)
    with pytest.raises(AnswerError, match=r"Hint \(coarse grid\)"):  # a scan of eps in steps of 0.05 m
        teach.check_eps_at_cr(0.65, ev.errors, ev.durations(), 0.4, 30.0, 1.0)

    row = ev.sequences(eps=1.0, phi=30.0).set_index("seq").loc[1]
    seq1 = gt.sequences[1]
    pct = 100 * row["ate_rmse"] / seq1.path_length
    assert teach.check_ate_percent(pct, row["ate_rmse"], row["c_ate_rmse"], seq1)
    for wrong, hint in (
        (pct / 100, "percent"),
        (100 * row["ate_rmse"] / seq1.extent, "extent vs length"),
    ):
        with pytest.raises(AnswerError, match=rf"Hint \({hint}\)"):
            teach.check_ate_percent(wrong, row["ate_rmse"], row["c_ate_rmse"], seq1)

    lifelong = ln.evaluate(sorted((sample.icra20 / "lifelong").glob("*/cafe*.txt")), data_root=sample)
    table = lifelong.sequences(eps=1.0, phi=30.0)
    scenes = ln.aggregate_scenes(table, lifelong.durations())
    assert teach.check_silent_sequences(2, table, 2)  # infinitam and orbslam2_t265 output nothing in visit 2
    with pytest.raises(AnswerError, match="you answered 1"):
        teach.check_silent_sequences(1, table, 2)
    assert teach.check_best_cr("vins_mono_color_imu_with_loop", scenes)
    with pytest.raises(AnswerError, match="longest blue bars"):
        teach.check_best_cr("ds-slam", scenes)
    # a late starter that tracks well once running: best by CR-T, not by CR
    toy = pd.DataFrame({"algorithm": ["steady", "late"], "cr": [0.6, 0.4], "cr_t": [0.7, 0.95]})
    with pytest.raises(AnswerError, match=r"Hint \(cr vs crt\)"):
        teach.check_best_cr("late", toy)


def test_f2_cr_read_off_as_cr_t_fails_with_its_hint_on_the_sample_data(sample):
    """F2 asks the best algorithm's CR over cafe too: there the best by CR is also the best by CR-T,
    so only the number can tell the two apart. On the sample data its CR-T is more than ten times
    the check's tolerance (0.005) away from its CR; the CR-T, the CR in percent and the row's other
    number (its C-ATE RMSE) each fail with their hint."""
    import lorisnb as ln

    lifelong = ln.evaluate(sorted((sample.icra20 / "lifelong").glob("*/cafe*.txt")), data_root=sample)
    scenes = ln.aggregate_scenes(lifelong.sequences(eps=1.0, phi=30.0, delta=1.0, tau=60.0), lifelong.durations())
    row = scenes.set_index("algorithm").loc["vins_mono_color_imu_with_loop"]
    assert scenes.sort_values("cr_t")["algorithm"].iloc[-1] == row.name  # the name alone cannot tell
    assert row["cr_t"] - row["cr"] > 10 * 0.005, (row["cr"], row["cr_t"])
    assert teach.check_best_cr(row.name, scenes, cr=row["cr"])
    assert teach.check_best_cr(row.name, scenes, cr=round(row["cr"], 3))  # the figure's label, 83.7 %
    assert teach.check_best_cr(row.name, scenes, cr=round(row["cr"], 2))
    for wrong, hint in (
        (row["cr_t"], "cr vs crt"),
        (100 * row["cr"], "fraction"),
        (row["c_ate_rmse"], "timeline label"),
    ):
        with pytest.raises(AnswerError, match=rf"Hint \({hint}\)"):
            teach.check_best_cr(row.name, scenes, cr=wrong)
    with pytest.raises(AnswerError, match="no answer yet"):
        teach.check_best_cr(row.name, scenes, cr=...)
