"""Per-student data (teaching/README.md, "Per-student data"): every value a student's variant can
draw, question by question, run through lab 1's own cells on the sample data. At each value the
instructor's answer passes, each typical mistake the question's check names fails with its hint,
and an answer right at another value fails (a number copied from a classmate with another variant
scores nothing); the README's count of what copied numbers score is computed here."""

from __future__ import annotations

import ast
import contextlib
import io
import itertools
from pathlib import Path

import nbformat
import numpy as np
import pytest

from lorisnb.errors import AnswerError
from lorisnb.tools import teaching as teach
from lorisnb.tools.teaching import _prose as variants
from lorisnb.tools.teaching.autograde import lab_spec

ROOT = Path(__file__).resolve().parents[2]
LAB = "lab1_lifelong_metrics"
SOURCE_NB = ROOT / "teaching" / "source" / LAB / f"{LAB}.ipynb"
NB = nbformat.read(SOURCE_NB, as_version=4)
SPEC = lab_spec(SOURCE_NB)


def _gid(cell: nbformat.NotebookNode) -> str:
    return str(cell.get("metadata", {}).get("nbgrader", {}).get("grade_id", ""))


CELLS = {_gid(c): c for c in NB.cells}

#: answer cell -> (its test cell, the variant's attribute its answer depends on, the values it can take)
QUESTIONS = {
    "B1_prediction": ("test_B1_prediction", "lost_length", variants.LOST_LENGTHS),
    "C2_prediction": ("test_C2_prediction", "reloc_delay", variants.RELOC_DELAYS),
    "D1_alignment": ("test_D1_alignment", "reloc_delay", variants.RELOC_DELAYS),
    "E1_threshold": ("test_E1_threshold", "target_cr", variants.TARGET_CRS),
    "F_timeline": ("test_F_timeline", "timeline_eps", variants.TIMELINE_EPS),
    "G1_difficulty": ("test_G1_difficulty", "ate_seq", variants.ATE_SEQS),
}

_SCAN = "next(e for e in {grid} if ev_orb.scenes(eps=e, phi=phi, delta=delta, tau=tau)['cr'].iloc[0] >= target_cr)"

#: answer cell -> the typical mistakes its check names, as a student writes them, and the hint each gets
MISTAKES: dict[str, list[tuple[str, str]]] = {
    "B1_prediction": [
        ("predicted_cr_lost = 1.0", "delta cap"),  # the last pose before the gap holds through it
        ("predicted_cr_lost = 1 - (lost_window[1] - lost_window[0]) / T", "gap last pose"),
        ("predicted_cr_lost = 100 * (1 - (lost_window[1] - lost_window[0] - delta) / T)", "fraction"),
    ],
    "C2_prediction": [("predicted_cs_r_wrong = float(np.exp(-reloc_delay / tau))", "first pose")],
    "D1_alignment": [
        (  # the demonstration's: per-sequence alignment for both
            "per_seq = ln.score(simulated_errors(gt, wrong_reloc, seqs=[1, 2], mode='per-seq'), eps, phi, delta, tau)\n"
            "cr_visit2_lifelong = cr_visit2_per_seq = per_seq.set_index('seq').loc[2, 'cr']\n",
            "alignment",
        ),
        (
            "life = ln.score(simulated_errors(gt, wrong_reloc, seqs=[1, 2]), eps, phi, delta, tau)\n"
            "cr_visit2_lifelong = cr_visit2_per_seq = life.set_index('seq').loc[2, 'cr']\n",
            "alignment",
        ),
        (  # the two swapped
            "life = ln.score(simulated_errors(gt, wrong_reloc, seqs=[1, 2]), eps, phi, delta, tau).set_index('seq')\n"
            "per = ln.score(simulated_errors(gt, wrong_reloc, seqs=[1, 2], mode='per-seq'), eps, phi, delta, tau)\n"
            "cr_visit2_lifelong, cr_visit2_per_seq = per.set_index('seq').loc[2, 'cr'], life.loc[2, 'cr']\n",
            "alignment",
        ),
    ],
    "E1_threshold": [
        (
            "from lorisnb.core.lifelong.sweep import eps_at_cr\n"
            "eps_for_cr = eps_at_cr(ev_orb.errors, target_cr, ev_orb.durations(), np.inf, delta)['eps'].iloc[0]\n",
            "phi ignored",
        ),
        (  # phi converted to radians: no eps reaches the target, eps_at_cr says NaN
            "from lorisnb.core.lifelong.sweep import eps_at_cr\n"
            "eps_for_cr = eps_at_cr(ev_orb.errors, target_cr, ev_orb.durations(), np.radians(phi), delta)['eps'].iloc[0]\n",
            "degrees radians",
        ),
        (f"eps_for_cr = {_SCAN.format(grid='np.linspace(0.05, 2.0, 40)')}\n", "coarse grid"),  # the curve's grid
        (f"eps_for_cr = {_SCAN.format(grid='np.round(np.arange(0.1, 2.01, 0.1), 2)')}\n", "coarse grid"),
    ],
    "F_timeline": [
        (  # the demonstration's: read off the CR-T column
            "silent_in_visit2 = int(((life['seq'] == 2) & (life['matched'] == 0)).sum())\n"
            "best_row = life_scenes.sort_values('cr_t', ascending=False).iloc[0]\n"
            "best_algorithm, best_cr = best_row['algorithm'], best_row['cr_t']\n",
            "cr vs crt",
        ),
        (
            "silent_in_visit2 = int(((life['seq'] == 2) & (life['matched'] == 0)).sum())\n"
            "best_row = life_scenes.sort_values('cr', ascending=False).iloc[0]\n"
            "best_algorithm, best_cr = best_row['algorithm'], round(100 * best_row['cr'], 1)\n",
            "fraction",
        ),
        (  # the row's other number, at its bottom right
            "silent_in_visit2 = int(((life['seq'] == 2) & (life['matched'] == 0)).sum())\n"
            "best_row = life_scenes.sort_values('cr', ascending=False).iloc[0]\n"
            "best_algorithm, best_cr = best_row['algorithm'], round(best_row['c_ate_rmse'], 3)\n",
            "timeline label",
        ),
    ],
    "G1_difficulty": [
        ("ate_percent_cafe = orb_seq['ate_rmse'] / gt_seq.path_length", "percent"),
        ("ate_percent_cafe = 100 * orb_seq['ate_rmse'] / gt_seq.extent", "extent vs length"),
        ("ate_percent_cafe = 100 * orb_seq['ate_mean'] / gt_seq.path_length", "rmse vs mean"),
        ("ate_percent_cafe = 100 * orb_seq['c_ate_rmse'] / gt_seq.path_length", "c ate"),
    ],
}

#: E1's scan without the delta cap finds the right eps at every target: the one typical mistake the
#: sample data cannot show (teaching/README.md, "Does every typical mistake show on the sample data?")
E1_DELTA_CAP = (
    "from lorisnb.core.lifelong.sweep import eps_at_cr\n"
    "eps_for_cr = eps_at_cr(ev_orb.errors, target_cr, ev_orb.durations(), phi, np.inf)['eps'].iloc[0]\n"
)


def _key(v: variants.LabVariant, attribute: str) -> object:
    return v.lost_window[1] - v.lost_window[0] if attribute == "lost_length" else getattr(v, attribute)


def _seeds() -> dict[tuple[str, object], int]:
    """(attribute, value) -> a seed whose variant has it, for every value of every question (and
    every start of B1's window), found among the first seeds; the first value of each drawn."""
    want = {(a, v) for _, a, values in QUESTIONS.values() for v in values}
    want |= {("lost_start", v) for v in variants.LOST_STARTS} | {("late_start", v) for v in variants.LATE_STARTS}
    found: dict[tuple[str, object], int] = {}
    for seed in range(5000):
        v = teach.lab_variant(None, seed=seed)
        keys = {(a, _key(v, a)) for a in {a for a, _ in want} - {"lost_start"}} | {("lost_start", v.lost_window[0])}
        assert keys <= want, f"seed {seed} draws a value outside the declared ones: {keys - want}"
        for k in keys:
            found.setdefault(k, seed)
        if len(found) == len(want):
            return found
    raise AssertionError(f"values never drawn: {sorted(want - set(found))}")


SEEDS = _seeds()


def _names(source: str, ctx: type) -> set[str]:
    tree = ast.parse(source)
    names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name) and isinstance(n.ctx, ctx)}
    if ctx is ast.Store:
        names |= {n.name for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
        names |= {(a.asname or a.name).split(".")[0] for n in ast.walk(tree) if isinstance(n, (ast.Import, ast.ImportFrom)) for a in n.names}  # fmt: skip
    return names


def _locked_cells_needed(upto: str, names: set[str]) -> list[str]:
    """The lab's own code cells before ``upto`` (no answer, no test cell) whose names ``names``
    need, directly or through each other, in the notebook's order."""
    order = [c for c in NB.cells if c.cell_type == "code"]
    order = order[: order.index(CELLS[upto])]
    keep: list[str] = []
    need = set(names)
    for cell in reversed(order):
        meta = cell.get("metadata", {}).get("nbgrader", {})
        if meta.get("solution") or meta.get("grade") or "parameters" in cell.metadata.get("tags", []):
            continue
        if _names(cell.source, ast.Store) & need or _gid(cell) == "setup":
            keep.insert(0, _gid(cell))
            need |= _names(cell.source, ast.Load)
    return keep


class _Lab:
    """The lab as it runs for one seed: the parameters, then the lab's cells a question needs (run
    once per seed), with the figures not drawn."""

    def __init__(self, out: Path) -> None:
        self.out = out
        self.scopes: dict[int, tuple[dict, set[str]]] = {}

    def scope(self, seed: int, cells: list[str]) -> dict:
        if seed not in self.scopes:
            scope: dict = {}
            exec(next(c.source for c in NB.cells if "parameters" in c.metadata.get("tags", [])), scope)  # noqa: S102
            scope.update(seed=seed, output_dir=str(self.out / str(seed)))
            self.scopes[seed] = (scope, set())
        scope, done = self.scopes[seed]
        with contextlib.redirect_stdout(io.StringIO()):
            for gid in cells:
                if gid not in done:
                    exec(CELLS[gid].source, scope)  # noqa: S102 (the lab's own cells)
                    done.add(gid)
                    if gid == "setup":  # no figure is drawn or written
                        scope["plot_timeline"] = lambda *a, **k: None
                        scope["out"] = type("Out", (), {"figure": staticmethod(lambda *a, **k: None)})()
        return scope

    def run(self, seed: int, answer: str, source: str | None = None, values: dict | None = None) -> str:
        """The answer cell ``answer`` (its ``source``, else the instructor's; or, as the grader
        does, the answer's ``values`` put in place of its names) then its test cell: what it printed."""
        test = QUESTIONS[answer][0]
        cell = source if source is not None else CELLS[answer].source
        scope = dict(
            self.scope(seed, _locked_cells_needed(test, _names(cell, ast.Load) | _names(CELLS[test].source, ast.Load)))
        )
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            if values is None:
                exec(cell, scope)  # noqa: S102
            else:
                scope.update(values)
            exec(CELLS[test].source, scope)  # noqa: S102
        return buf.getvalue()

    def answer(self, seed: int, answer: str) -> dict:
        """The graded values of the instructor's answer at ``seed`` (what a classmate would copy)."""
        scope = dict(self.scope(seed, _locked_cells_needed(answer, _names(CELLS[answer].source, ast.Load))))
        with contextlib.redirect_stdout(io.StringIO()):
            exec(CELLS[answer].source, scope)  # noqa: S102
        return {n: scope[n] for n in SPEC.values[answer]}


@pytest.fixture(scope="module")
def lab(tmp_path_factory) -> _Lab:
    return _Lab(tmp_path_factory.mktemp("variants"))


CASES = [(answer, value) for answer, (_, _, values) in QUESTIONS.items() for value in values]


@pytest.mark.parametrize(("answer", "value"), CASES, ids=[f"{a}-{v}" for a, v in CASES])
@pytest.mark.thorough
def test_each_variant_passes_the_answer_and_gives_each_mistake_its_hint(lab, answer, value):
    """At every value a student can draw, the instructor's answer passes and each typical mistake
    the check names fails with its hint (the old lab varied B1 only: E1's target, F's eps, G1's
    sequence and D1's delay did not exist)."""
    _, attribute, _ = QUESTIONS[answer]
    seed = SEEDS[(attribute, value)]
    v = teach.lab_variant(None, seed=seed)
    assert _key(v, attribute) == value
    assert attribute == "lost_length" or f"{value:g}" in v.describe()  # the lab says the student's variant
    printed = lab.run(seed, answer)
    assert "✓" in printed and "✗" not in printed
    for source, hint in MISTAKES[answer]:
        with pytest.raises(AnswerError, match=rf"\nHint \({hint}\)"):
            lab.run(seed, answer, source)
    if answer == "E1_threshold":  # the known exception: without the cap, the same eps
        assert "✓" in lab.run(seed, answer, E1_DELTA_CAP)


def test_every_answer_in_the_table_of_mistakes_is_an_answer_of_the_lab():
    assert set(MISTAKES) == set(QUESTIONS) <= set(SPEC.values)
    assert {q.grade_id for q in SPEC.questions} >= {t for t, _, _ in QUESTIONS.values()}


def _copied(lab: _Lab, answer: str) -> tuple[float, dict]:
    """The chance that the answer of a classmate drawn at random passes at one's own variant (both
    drawn uniformly: each pair of values, the classmate's values put in place of the answer's
    names, as the grader does), and the right answer at each value."""
    _, attribute, values = QUESTIONS[answer]
    right = {v: lab.answer(SEEDS[(attribute, v)], answer) for v in values}
    passes = {}
    for mine, theirs in itertools.product(values, repeat=2):
        try:
            lab.run(SEEDS[(attribute, mine)], answer, values=right[theirs])
            passes[mine, theirs] = True
        except AnswerError:
            passes[mine, theirs] = False
    assert all(passes[v, v] for v in values)  # one's own answer, read back, passes
    return float(np.mean(list(passes.values()))), right


def copy_scores(lab: _Lab) -> tuple[float, float, dict[str, dict]]:
    """What a notebook of numbers copied from a classmate scores: at worst (another variant in every
    question that varies) and on average (a classmate drawn at random); the right answers of each
    question that varies, value by value."""
    worst = mean = 0.0
    rights = {}
    for q in SPEC.questions:
        (answer,) = q.answers
        if answer not in QUESTIONS or answer == "C2_prediction":  # C2: CS-R = 0 at every delay
            worst, mean = worst + q.points, mean + q.points
            continue
        p, rights[answer] = _copied(lab, answer)
        assert p == pytest.approx(1 / len(QUESTIONS[answer][2])), answer  # only one's own value passes
        mean += q.points * p
    return worst, mean, rights


@pytest.mark.thorough
def test_readme_says_what_copied_numbers_score(lab):
    """The README's "Which answers differ between students" table and its count, computed."""
    worst, mean, rights = copy_scores(lab)
    text = " ".join((ROOT / "teaching" / "README.md").read_text().split())
    total = SPEC.max_points

    def column(answer: str, name: str) -> list[float]:
        return [float(r[name]) for r in rights[answer].values()]

    d1, e1 = column("D1_alignment", "cr_visit2_per_seq"), column("E1_threshold", "eps_for_cr")
    f2, g1 = column("F_timeline", "best_cr"), column("G1_difficulty", "ate_percent_cafe")
    assert set(column("D1_alignment", "cr_visit2_lifelong")) == {0.0}
    assert {r["best_algorithm"] for r in rights["F_timeline"].values()} == {"vins_mono_color_imu_with_loop"}
    assert len({r["silent_in_visit2"] for r in rights["F_timeline"].values()}) == 1
    for quoted in (
        f"copied numbers score {worst:g} of {total:g}",
        f"on average {mean:.1f} of {total:g}",
        f"({len(variants.LOST_LENGTHS)} possible answers)",
        f"({len(d1)} possible answers: visit 2 re-localizes after {variants.RELOC_DELAYS[0]:g}, "
        f"{variants.RELOC_DELAYS[1]:g}, ..., {variants.RELOC_DELAYS[-1]:g} s, so its per-sequence CR is about "
        f"1 - delay / {lab.scope(0, ['setup'])['gt'].sequences[2].duration:.0f} s, {max(d1):.3f} down to {min(d1):.3f}",
        f"({len(e1)} possible answers: a target CR of "
        + ", ".join(f"{t:g}" for t in variants.TARGET_CRS)
        + ", whose eps are "
        + ", ".join(f"{e:.3f}" for e in e1[:-1])
        + f" and {e1[-1]:.3f} m)",
        f"({len(f2)} possible answers: the timeline at eps = "
        + ", ".join(f"{e:g}" for e in variants.TIMELINE_EPS)
        + f" m, where the best algorithm's CR is {min(f2):.3f} to {max(f2):.3f};",
        f"({len(g1)} possible answers: cafe-1 or cafe-2, whose ATE RMSE is "
        + " % and ".join(f"{v:.2f}" for v in g1)
        + " % of the path length)",
    ):
        assert quoted in text, quoted


def test_readme_says_why_the_other_values_are_left_out(lab):
    """The README's reasons for what does not vary more, computed on the sample data at the lab's
    thresholds: E1's targets, F's best algorithm, G1's two sequences."""
    from lorisnb.core.lifelong.sweep import eps_at_cr

    scope = lab.scope(0, _locked_cells_needed("test_F_timeline", {"ev_orb", "ev_life", "gt"}))
    phi, delta, tau, ev_orb, data = scope["phi"], scope["delta"], scope["tau"], scope["ev_orb"], scope["data"]
    text = " ".join((ROOT / "teaching" / "README.md").read_text().split())

    # E1: the targets from 0.2 to 0.4 whose eps is on the curve (2 m at most) where every mistake is
    # clearly off, less one whose eps is within the tolerance (0.01 m) of another's
    def eps(target: float, p: float) -> float:
        return float(eps_at_cr(ev_orb.errors, target, ev_orb.durations(), p, delta)["eps"].iloc[0])

    curve = {e: float(ev_orb.scenes(eps=e, phi=phi, delta=delta, tau=tau)["cr"].iloc[0])
             for e in np.round(np.arange(0.05, 2.001, 0.05), 2)}  # fmt: skip

    def scan(target: float, step: float) -> float:
        return next(e for e, cr in curve.items() if round(e / step, 6) % 1 == 0 and cr >= target)

    clear = {}
    for t in np.round(np.arange(0.2, 0.4001, 0.005), 3):
        right = eps(t, phi)
        if right > max(curve):
            continue
        if right - eps(t, np.inf) > 0.06 and min(scan(t, 0.05), scan(t, 0.1)) - right > 0.015:
            clear[float(t)] = right
    assert 0.285 in clear and abs(clear[0.285] - clear[0.29]) <= 0.01
    assert tuple(t for t in clear if t != 0.285) == variants.TARGET_CRS
    assert all(abs(a - b) > 0.01 for a, b in itertools.combinations([clear[t] for t in variants.TARGET_CRS], 2))
    above = [eps(t, phi) for t in np.round(np.arange(0.31, 0.4001, 0.005), 3)]
    assert min(above) >= 3.5 and max(curve) == 2.0 and max(variants.TARGET_CRS) == 0.305
    assert (
        "E1's targets are those from 0.2 to 0.4, in steps of 0.005, whose eps is on the curve (2 m at most) and "
        "where a scan that leaves phi out misses the right eps by more than 0.06 m and scans on 5 cm and 10 cm grids "
        "(the curve's, and a coarser one) by more than 0.015 m (the tolerance is 0.01 m), less 0.285, whose eps is "
        "within the tolerance of 0.29's; above 0.305 the eps jumps to 3.5 m and more" in text
    )

    # F: VINS-Mono is the best at every eps of a timeline; without it DS-SLAM, whose CR and CR-T are
    # closer than the check's tolerance
    for e in variants.TIMELINE_EPS:
        scenes = scope["ev_life"].scenes(eps=e, phi=phi, delta=delta, tau=tau).set_index("algorithm")
        assert scenes["cr"].idxmax() == "vins_mono_color_imu_with_loop"
        second = scenes.drop("vins_mono_color_imu_with_loop")
        ds = second.loc["ds-slam"]
        assert second["cr"].idxmax() == "ds-slam" and abs(ds["cr_t"] - ds["cr"]) < 0.005
    assert (
        "without it in the figure DS-SLAM would be, whose CR and CR-T there are less than the check's tolerance, "
        "0.005, apart" in text
    )

    # G1: ORB-SLAM2 on the RGB-D camera is correct at every pose of cafe: its C-ATE is its ATE
    import lorisnb as ln

    rgbd = ln.evaluate(sorted((data.icra20 / "per-seq" / "orbslam2_rgbd").glob("cafe*.txt")), data_root=data)
    rows = rgbd.sequences(eps=scope["eps"], phi=phi, delta=delta, tau=tau)
    assert len(rows) == 2 and np.allclose(rows["c_ate_rmse"], rows["ate_rmse"])
    assert sorted(scope["gt"].sequences) == [1, 2] and data.scenes_with_groundtruth() == ["cafe"]
    assert "on the RGB-D camera, are correct at every pose, so their C-ATE is their ATE" in text
