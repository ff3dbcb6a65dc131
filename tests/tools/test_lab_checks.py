"""The lab's checks as students meet them: a formula that hands its inputs to lorisnb (or reads the
check's own reference through the call stack) is refused, not given full marks; the usual
off-by-one and unit slips are named, also on the hidden tests' real sequences; a NaN or an array
answer is told with lorisnb's number; the simulator refuses fault times after the end of the
sequence (stamps typed for seconds), which changed nothing. Runs on the sample data shipped with
lorisnb (a verbatim subset of OpenLORIS-Scene), so it needs no data folder."""

from __future__ import annotations

import inspect

import numpy as np
import pytest

import lorisnb as ln
from lorisnb.core.metrics import openloris as metrics
from lorisnb.core.simulate import Faults, simulated_errors
from lorisnb.errors import AnswerError, ValidationError
from lorisnb.io.datasets.paths import sample_data
from lorisnb.tools import teaching as teach


@pytest.fixture(scope="module")
def gt():
    return ln.load_groundtruth("cafe", sample_data())


@pytest.fixture(scope="module")
def hidden():
    """The lab's hidden cases (its test cells' own faults and thresholds), on cafe-1 and cafe-2."""
    from lorisnb.tools.teaching.errorrates import hidden_cases

    return dict(
        correctness=hidden_cases("A1_correctness"),
        correct_rate=hidden_cases("B2_correct_rate"),
        cs_r=hidden_cases("C1_cs_r"),
    )


def _fails(check, fn, *cases) -> str:
    with pytest.raises(AnswerError) as exc:
        check(fn, *cases)
    return str(exc.value)


def _right_cr(stamps, correct, t_min, t_max, delta):
    return float(np.sum(np.minimum(np.diff(np.append(stamps, t_max)), delta) * correct) / (t_max - t_min))


# --- a solution that reads the answer ------------------------------------------------------------


def _delegates_correctness(ate_m, aoe_deg, eps, phi):
    return metrics.correctness(ate_m, aoe_deg, eps, phi)


def _delegates_cr(stamps, correct, t_min, t_max, delta):
    return teach._checks._cr(stamps, correct, t_min, t_max, delta)


def _reads_the_reference(t0, t_min, first_correct, tau):
    checker = next(f.frame for f in inspect.stack() if "reference" in f.frame.f_locals)
    return checker.f_locals["reference"](t0=t0, t_min=t_min, first_correct=first_correct, tau=tau)


@pytest.mark.parametrize(
    ("check", "fn", "kind", "called"),
    [
        (teach.check_correctness, _delegates_correctness, "correctness", "lorisnb.core.metrics.openloris.correctness"),
        (teach.check_correct_rate, _delegates_cr, "correct_rate", "lorisnb.tools.teaching._checks._cr"),
        (teach.check_cs_r, _reads_the_reference, "cs_r", "lorisnb.tools.teaching._checks._csr"),
    ],
)
def test_a_formula_that_returns_lorisnbs_own_answer_is_refused(check, fn, kind, called, hidden):
    """It scored full marks (18/18 in `make grade`); now the visible and the hidden checks both say
    which lorisnb function it called."""
    for cases in ((), (hidden[kind],)):
        msg = _fails(check, fn, *cases)
        assert f"calls lorisnb's own `{called}`" in msg and "Write the formula yourself" in msg, msg


def test_a_formula_using_only_numpy_still_passes_and_a_lazy_lorisnb_attribute_is_not_a_call(hidden, capsys):
    def right(stamps, correct, t_min, t_max, delta):
        ln.core  # a lazy attribute of lorisnb (module __getattr__), no lorisnb function called  # noqa: B018
        return _right_cr(stamps, correct, t_min, t_max, delta)

    assert teach.check_correct_rate(right) and teach.check_correct_rate(right, hidden["correct_rate"])
    assert capsys.readouterr().out.count("✓ correct_rate matches lorisnb") == 2


# --- the usual slips, named ----------------------------------------------------------------------


def _shifted(stamps, correct, t_min, t_max, delta):  # off by one: each interval credited to the next pose
    return float(np.sum(np.minimum(np.diff(stamps), delta) * correct[1:]) / (t_max - t_min))


def _last_holds_delta(stamps, correct, t_min, t_max, delta):  # off by one: the last pose holds delta, not to t_max
    held = np.append(np.minimum(np.diff(stamps), delta), delta)
    return float(np.sum(held * correct) / (t_max - t_min))


def _cut_at_delta(stamps, correct, t_min, t_max, delta):  # a pose longer than delta dropped, not capped
    dt = np.diff(np.append(stamps, t_max))
    return float(np.sum(np.where(dt < delta, dt, 0.0) * correct) / (t_max - t_min))


def _each_holds_delta(stamps, correct, t_min, t_max, delta):
    return float(np.count_nonzero(correct) * delta / (t_max - t_min))


def _crt_counts_poses(stamps, correct, t_min, t_max, delta):
    return float(np.mean(correct))


def _csr_absolute_time(t0, t_min, first_correct, tau):  # forgot t_min: exp(-stamp / tau)
    return float(np.exp(-t0 / tau)) if first_correct else 0.0


@pytest.mark.parametrize(
    ("check", "fn", "kind", "hint"),
    [
        (teach.check_correct_rate, _shifted, "correct_rate", "held backward"),
        (teach.check_correct_rate, _last_holds_delta, "correct_rate", "last pose"),
        (teach.check_correct_rate, _cut_at_delta, "correct_rate", "delta cut"),
        (teach.check_correct_rate, _each_holds_delta, "correct_rate", "held delta"),
        (teach.check_correct_rate_tracking, _crt_counts_poses, "correct_rate", "poses not time"),
        (teach.check_cs_r, _csr_absolute_time, "cs_r", "absolute time"),
    ],
)
def test_off_by_one_and_unit_slips_are_named(check, fn, kind, hint, hidden):
    msg = _fails(check, fn)
    assert f"\nHint ({hint}):" in msg, msg
    if fn is not _last_holds_delta:  # the hidden sequences end on a wrong pose: its time is 0 either way
        msg = _fails(check, fn, hidden[kind])
        assert f"\nHint ({hint}):" in msg, msg


def test_forgetting_t_min_on_real_stamps_is_not_told_tau_inverted_alone(hidden):
    """On real stamps (1.56e9 s) exp(-t0 / tau) is 0, as is exp(-(t0 - t_min) * tau): the answer
    matches both mistakes, and the hint names the one the learner most likely made too."""
    msg = _fails(teach.check_cs_r, _csr_absolute_time, hidden["cs_r"])
    case = hidden["cs_r"][0]  # the first case the answer fails: tracked from the first pose, so CS-R is above 0
    assert case["first_correct"] and np.exp(-case["t0"] / case["tau"]) == 0.0
    want = np.exp(-(case["t0"] - case["t_min"]) / case["tau"])
    assert "you return 0, too low" in msg and f"{want:.6g}" not in msg and f"{want:.4g}" not in msg  # a hidden case
    assert "\nHint (absolute time):" in msg and "t0 - t_min" in msg


def test_nan_and_array_answers_say_what_lorisnb_gives():
    def nan_when_wrong(t0, t_min, first_correct, tau):
        return float(np.exp(-(t0 - t_min) / tau)) if first_correct else float("nan")

    msg = _fails(teach.check_cs_r, nan_when_wrong)
    assert "cs_r returned NaN on case 3 (t0=130.0, t_min=100.0, first_correct=False, tau=60.0); lorisnb gives 0" in msg
    assert "\nHint (nan):" in msg

    def per_pose(stamps, correct, t_min, t_max, delta):  # the sum forgotten
        return np.minimum(np.diff(np.append(stamps, t_max)), delta) * correct / (t_max - t_min)

    msg = _fails(teach.check_correct_rate, per_pose)
    assert "expected one number, got ndarray of shape (171,) (171 values)" in msg and "np.sum" in msg
    assert len(msg) < 300, msg  # not the array's repr


def test_ate_percent_made_of_the_mean_ate_gets_the_rmse_hint():
    data = sample_data()
    gt = ln.load_groundtruth("cafe", data)
    files = sorted((data.icra20 / "per-seq" / "orbslam2_rgbd").glob("cafe*.txt"))
    row = ln.evaluate(files, data_root=data).sequences(eps=1.0, phi=30.0, delta=1.0, tau=60.0).set_index("seq").loc[1]
    seq1 = gt.sequences[1]
    mean_answer = 100 * row["ate_mean"] / seq1.path_length
    assert mean_answer == pytest.approx(1.4429, abs=1e-3) and 100 * row["ate_rmse"] / seq1.path_length == pytest.approx(
        1.5496, abs=1e-3
    )
    with pytest.raises(AnswerError) as exc:
        teach.check_ate_percent(mean_answer, row["ate_rmse"], row["c_ate_rmse"], seq1, ate_mean=row["ate_mean"])
    want = 100 * row["ate_rmse"] / seq1.path_length
    assert f"you answered {mean_answer:.4g}, too low" in str(exc.value)  # lorisnb's number not given
    assert f"{want:.4g}" not in str(exc.value) and f"{want:.3g}" not in str(exc.value)
    assert "\nHint (rmse vs mean):" in str(exc.value)


def test_the_hidden_tests_fail_a_solution_fitted_to_the_visible_cases(hidden, capsys):
    """A learner who copies lorisnb's numbers from the visible checks' messages passes them; the
    hidden cases (real sequences) do not let it through."""
    visible = {(c["t_min"], c["delta"]): _right_cr(**c) for c in teach.CR_CASES}

    def fitted(stamps, correct, t_min, t_max, delta):
        return visible.get((t_min, delta), 0.5)

    assert teach.check_correct_rate(fitted)
    msg = _fails(teach.check_correct_rate, fitted, hidden["correct_rate"])
    want = _right_cr(**hidden["correct_rate"][0])
    assert "you return 0.5, too high" in msg and f"{want:.6g}" not in msg and f"{want:.3g}" not in msg


# --- the simulator: fault times are seconds from the start ---------------------------------------


@pytest.mark.parametrize(
    ("faults", "said"),
    [
        (lambda t0: Faults(lost=((t0 + 15.0, t0 + 35.0),)), "lost interval (1560004900.4, 1560004920.4)"),
        (lambda t0: Faults(wrong_reloc_at_s=t0 + 10.0), "wrong_reloc_at_s=1560004895.4"),
        (lambda t0: Faults(init_delay_s=t0 + 20.0), "init_delay_s=1560004905.4"),
        (lambda t0: Faults(lost=((60.0, 80.0),)), "lost interval (60.0, 80.0)"),
    ],
)
def test_fault_times_after_the_end_are_refused_not_ignored(gt, faults, said):
    """Stamps typed for seconds: the loss interval and the wrong re-localization changed nothing
    (2281 of 2281 poses kept, exit 0), the init delay left no pose."""
    seq1 = gt.sequences[1]
    assert len(seq1) == 2281 and seq1.duration == pytest.approx(56.98, abs=0.01)
    with pytest.raises(ValidationError) as exc:
        simulated_errors(gt, faults(float(seq1.stamps[0])), seqs=[1])
    msg = str(exc.value)
    assert msg.startswith("cafe-1: Faults(") and said in msg, msg
    assert "lasts 57.0 s" in msg and "seconds from the start of the sequence" in msg and "not stamps" in msg


def test_fault_times_up_to_the_end_still_work(gt):
    """The fault explorer's sliders reach the sequence's duration; a loss to infinity is fine."""
    d = gt.sequences[1].duration
    s = ln.score(simulated_errors(gt, Faults(init_delay_s=d, lost=((d, d + 5.0),)), seqs=[1]), 1.0, 30.0, 1.0, 60.0)
    assert int(s["matched"].iloc[0]) <= 1
    s = ln.score(simulated_errors(gt, Faults(lost=((15.0, np.inf),)), seqs=[1]), 1.0, 30.0, 1.0, 60.0).iloc[0]
    assert s["matched"] == 601 and s["cr"] == pytest.approx((15.0 + 1.0) / d, abs=0.005)  # + delta: the last pose holds


# --- an answer cell that disables the checks -----------------------------------------------------


def test_an_answer_cell_cannot_replace_or_empty_the_checks(capsys):
    """`teach.check_correctness = lambda *a, **k: True` in an answer cell scored full marks (the
    grader runs the notebook in one kernel); emptying the default cases passed a constant."""
    namespace = {"teach": teach}
    for cell in ("teach.check_correctness = lambda *a, **k: True", "del teach.check_value", "teach.CR_CASES = []"):
        with pytest.raises(AnswerError, match="cannot be (replaced|removed): the checks grade your answers"):
            exec(cell, namespace)
    assert teach.check_correctness.__module__ == "lorisnb.tools.teaching._checks"
    msg = _fails(teach.check_correct_rate, lambda **kw: 0.0, [])
    assert "no case to check it on" in msg
    teach.learner_note = "other names are free"  # a learner's own attribute is not refused
    del teach.learner_note


def _e1():
    """Exercise E1's data: ORB-SLAM2 on the T265 per sequence, cafe (the sample data)."""
    data = sample_data()
    ev = ln.evaluate(sorted((data.icra20 / "per-seq" / "orbslam2_t265").glob("cafe*.txt")), data_root=data)
    return ev.errors, ev.durations()


def test_eps_at_cr_with_phi_in_radians_is_told_degrees_not_a_formula_nan():
    """Exercise E1 with np.radians(phi): eps_at_cr finds no eps (NaN), and the check said only
    'your answer is NaN'."""
    from lorisnb.core.lifelong.sweep import eps_at_cr

    errors, durations = _e1()
    answer = eps_at_cr(errors, 0.3, durations, np.radians(30.0), 1.0)["eps"].iloc[0]
    assert np.isnan(answer)
    with pytest.raises(AnswerError) as exc:
        teach.check_eps_at_cr(answer, errors, durations, 0.3, 30.0, 1.0)
    msg = str(exc.value)
    want = eps_at_cr(errors, 0.3, durations, 30.0, 1.0)["eps"].iloc[0]
    assert "your answer is NaN" in msg and "with phi = 30 degrees an eps does reach it" in msg
    assert f"{want:.4g}" not in msg and f"{want:.3g}" not in msg  # the eps itself is not given
    assert "\nHint (degrees radians):" in msg and "Hint (nan)" not in msg


def test_e1_scan_without_phi_fails_on_the_sample_data_with_its_hint():
    """Issue 46: each typical mistake of E1 must fail on the data the lab runs on. ORB-SLAM2 on the
    T265 drifts in orientation, so a scan that leaves phi out finds a smaller eps (about 0.53 m
    against 0.63 m); the right scan passes."""
    from lorisnb.core.lifelong.sweep import eps_at_cr

    errors, durations = _e1()
    right = eps_at_cr(errors, 0.3, durations, 30.0, 1.0)["eps"].iloc[0]
    no_phi = eps_at_cr(errors, 0.3, durations, np.inf, 1.0)["eps"].iloc[0]
    assert right - no_phi > 0.05
    assert teach.check_eps_at_cr(right, errors, durations, 0.3, 30.0, 1.0)
    with pytest.raises(AnswerError, match=r"Hint \(phi ignored\)"):
        teach.check_eps_at_cr(no_phi, errors, durations, 0.3, 30.0, 1.0)


def test_a_rounded_answer_is_not_told_two_equal_numbers():
    """`round(cr, 6)`: the message read 'you return 0.366667; lorisnb gives 0.366667'."""

    def rounded(stamps, correct, t_min, t_max, delta):
        return round(_right_cr(stamps, correct, t_min, t_max, delta), 6)

    msg = _fails(teach.check_correct_rate, rounded)
    assert (
        "you return 0.366667; lorisnb gives 0.366666667 (they differ by 3.3e-07" in msg
        and "rounded to 6 decimal(s)?" in msg
    )


def test_lorisnbs_own_function_given_as_the_answer_is_refused(hidden):
    """`correctness = ln.core.metrics.correctness` in the answer cell: the check called lorisnb's
    function from lorisnb, which did not look like the learner calling it."""
    import functools

    for fn in (metrics.correctness, functools.partial(metrics.correctness)):
        for cases in ((), (hidden["correctness"],)):
            msg = _fails(teach.check_correctness, fn, *cases)
            assert "calls lorisnb's own `lorisnb.core.metrics.openloris.correctness`" in msg, msg
