"""Write demonstration submissions for `make grade` from the released labs (never overwriting a
student folder that exists):

- ``submitted/demo-correct/<lab>/``: the release with every answer cell filled with the
  instructor's solution (must score full marks);
- ``submitted/demo-mistakes/<lab>/``: the release with the typical wrong answers of
  :data:`MISTAKES` (the forgotten delta cap, CR-T for CR in B2 and F2, radians, per-sequence alignment, ...),
  so the feedback shows the checks' hints.

    python demo_submissions.py            # from teaching/, after `nbgrader generate_assignment`
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import nbformat

HERE = Path(__file__).resolve().parent

#: answer cell (nbgrader grade_id) -> what a student who makes the typical mistake writes
MISTAKES = {
    "A1_correctness": "def correctness(ate_m, aoe_deg, eps, phi):\n    return (ate_m <= eps) & (aoe_deg <= np.radians(phi))\n",
    "B1_prediction": "predicted_cr_lost = 1.0\n",
    "B2_correct_rate": (
        "def correct_rate(stamps, correct, t_min, t_max, delta):\n"
        "    held = np.minimum(np.diff(np.append(stamps, t_max)), delta)\n"
        "    return float(np.sum(held * correct) / (t_max - stamps[0]))\n"
    ),
    "B3_prediction": "predicted_cr_t_late = 1 - late_start / T\n",
    "C1_cs_r": "def cs_r(t0, t_min, first_correct, tau):\n    return float(np.exp(-(t0 - t_min) / tau))\n",
    "E1_threshold": (  # phi left out of the scan: every pose with a small ATE counts, however it is turned
        "from lorisnb.core.lifelong.sweep import eps_at_cr\n"
        "eps_for_cr = eps_at_cr(ev_orb.errors, target_cr, ev_orb.durations(), np.inf, delta)['eps'].iloc[0]\n"
    ),
    "D1_alignment": (
        "per_seq = ln.score(simulated_errors(gt, wrong_reloc, seqs=[1, 2], mode='per-seq'), eps, phi, delta, tau)\n"
        "cr_visit2_lifelong = cr_visit2_per_seq = per_seq.set_index('seq').loc[2, 'cr']\n"
        "print(f'CR of visit 2: {cr_visit2_lifelong:.3f}')\n"
    ),
    "F_timeline": (  # F2 read off the CR-T column: the right algorithm, its CR-T for its CR
        "silent_in_visit2 = int(((life['seq'] == 2) & (life['matched'] == 0)).sum())\n"
        "best_row = life_scenes.sort_values('cr_t', ascending=False).iloc[0]\n"
        "best_algorithm, best_cr = best_row['algorithm'], best_row['cr_t']\n"
    ),
}

SOLUTION = re.compile(r"^[ \t]*### BEGIN SOLUTION[ \t]*\n(.*?)^[ \t]*### END SOLUTION[ \t]*\n?", re.S | re.M)
STUB = re.compile(r"^[ \t]*# YOUR CODE HERE\n[ \t]*raise NotImplementedError\(\)[ \t]*\n?", re.M)


def _grade_id(cell: nbformat.NotebookNode) -> str | None:
    return cell.get("metadata", {}).get("nbgrader", {}).get("grade_id")


def solutions(source_nb: Path) -> dict[str, str]:
    """grade_id -> the solution code of each answer cell of the instructor notebook."""
    nb = nbformat.read(source_nb, as_version=4)
    out = {}
    for cell in nb.cells:
        meta = cell.get("metadata", {}).get("nbgrader", {})
        if meta.get("solution") and cell.cell_type == "code":
            out[meta["grade_id"]] = cell.source
    return out


def fill(release_nb: Path, answers: dict[str, str], use_solution: bool) -> nbformat.NotebookNode:
    """The released notebook with each stub replaced by the solution's lines (``use_solution``)."""
    nb = nbformat.read(release_nb, as_version=4)
    for cell in nb.cells:
        gid = _grade_id(cell)
        if gid not in answers or cell.cell_type != "code" or not use_solution:
            continue
        sol = SOLUTION.search(answers[gid])
        body = sol.group(1) if sol else ""
        cell.source = STUB.sub(lambda _m, b=body: b, cell.source, count=1)
    return nb


def fill_cells(nb: nbformat.NotebookNode, answers: dict[str, str]) -> nbformat.NotebookNode:
    """Each answer cell named in ``answers`` replaced whole, as a student would have written it."""
    for cell in nb.cells:
        if _grade_id(cell) in answers and cell.cell_type == "code":
            cell.source = answers[_grade_id(cell)]
    return nb


def main(course: Path = HERE) -> int:
    """Demo students in ``course``'s submitted/ from its release/ (``make grade``: the COURSE folder)."""
    release = course / "release"
    labs = sorted(p for p in release.iterdir() if p.is_dir()) if release.is_dir() else []
    if not labs:
        print("no released lab: run `make student` first", file=sys.stderr)
        return 1
    for lab in labs:
        for nb_path in sorted(lab.glob("*.ipynb")):
            sols = solutions(HERE / "source" / lab.name / nb_path.name)
            for student, answers, use_solution in (("demo-correct", sols, True), ("demo-mistakes", sols, True)):
                dest = course / "submitted" / student / lab.name / nb_path.name
                if dest.exists():
                    print(f"kept {dest.relative_to(course)} (exists)")
                    continue
                dest.parent.mkdir(parents=True, exist_ok=True)
                nb = fill(nb_path, answers, use_solution)
                if student == "demo-mistakes":  # the solutions, except the typical mistakes
                    nb = fill_cells(nb, MISTAKES)
                nbformat.write(nb, dest)
                print(f"wrote {dest.relative_to(course)}")
    return 0


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1]).resolve() if len(sys.argv) > 1 else HERE))
