"""An answer whose cell the returned notebook lacks is unanswered (the adversarial pass grading2 on
GRADER_VERSION 11, student ``fnometa``): B1's cell with its nbgrader metadata removed, computing the
reference with the lab's ``simulate_and_score``, scored 1/1 (the prediction was graded from the lab's
run where its cell was) while a note said the cell was missing and "graded as unanswered"; the same
for a formula (its def in the cell without metadata) and a value answer."""

from __future__ import annotations

from pathlib import Path

import nbformat
import pytest
from test_teaching_added_below import _settings

pytestmark = pytest.mark.xdist_group("grading")

ROOT = Path(__file__).resolve().parents[2]
LAB = "lab1_lifelong_metrics"
SOURCE_NB = ROOT / "teaching" / "source" / LAB / f"{LAB}.ipynb"

FB1 = "_fe, _t = simulate_and_score(Faults(lost=(lost_window,)))\npredicted_cr_lost = float(_t.loc[1, 'cr'])\n"


@pytest.mark.slow
def test_an_answer_whose_cell_lost_its_metadata_scores_0_whatever_computes_it(tmp_path):
    from lorisnb.tools.teaching.autograde import grade_submission, lab_spec

    nb = nbformat.read(SOURCE_NB, as_version=4)  # the instructor's answers: every question right
    for cell in nb.cells:
        gid = cell.metadata.get("nbgrader", {}).get("grade_id")
        if gid in ("B1_prediction", "C1_cs_r", "D1_alignment"):
            cell.metadata.pop("nbgrader")  # an added cell now, run in its place, its answer right
            cell.source = FB1 if gid == "B1_prediction" else cell.source
    release = tmp_path / "release"
    release.mkdir()
    path = tmp_path / "fnometa" / f"{LAB}.ipynb"
    path.parent.mkdir()
    nbformat.write(nb, path)
    res = grade_submission(lab_spec(SOURCE_NB), release, path, "fnometa", _settings())
    lost = {s.question: s.message for s in res.scores if s.points < s.max_points}
    assert set(lost) == {"test_B1_prediction", "test_C1_cs_r", "test_D1_alignment"}, (lost, res.notes)
    for gid in ("B1_prediction", "C1_cs_r", "D1_alignment"):
        assert f"the notebook has no answer cell {gid}" in lost[f"test_{gid}"], lost
    assert res.points == res.max_points - 1 - 2 - 2
    assert any("lacks the answer cells B1_prediction, C1_cs_r, D1_alignment" in n for n in res.notes), res.notes
