"""``lorisnb report``'s ``-p`` values reach the notebooks and ``run.json`` in one canonical form
(adversarial batch s70): ``-p scale on``, ``-p scale Yes`` and ``-p scale true`` all aligned Sim(3),
but run.json kept ``"on"``, ``"Yes"`` and ``true`` as typed, so the nightly gate found no comparable
baseline (exit 2) and ``diff`` refused "different evaluation specs"; the notebooks got ``"Yes"`` as
typed. And ``-p results_dir /tmp`` with ``--results`` scanned all of /tmp before refusing the two
folders."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import nbformat
import pytest

from lorisnb.errors import ValidationError
from lorisnb.tools.decisions.runs import load_run, spec_differences
from lorisnb.tools.notebook import params as nbparams
from lorisnb.tools.notebook.params import check_parameters
from lorisnb.tools.report import build

#: name -> spellings that mean the same setting, and the one form each becomes
EQUIVALENT = {
    "scale": (["on", "Yes", "TRUE", True, 1, " sim3 "], True),
    "official_interpolation": ([True], True),
    "eps": (["PAPER", " paper"], "paper"),
    "phi": ([30, 30.0, "30"], 30.0),
    "seed": ([3, 3.0, "3"], 3),
    "alpha": (["0.05", 0.05], 0.05),
    "metric": (["CR", "cr"], "cr"),
    "conventions": (["TUM", "tum"], "tum"),
    "rpe_delta": ([1, 1.0, "1"], 1.0),
    "rpe_unit": (["M", "m"], "m"),
    "sim_trials": ([5, 5.0], 5),
    "sim_eps": ([1, "1", 1.0], 1.0),
    "rpe_metres": ([5, 5.0], 5.0),
    "eps_grid": ([1, [1], ["1"], [1.0]], [1.0]),
    "phi_grid": ([[10, 20], ["10", 20.0]], [10.0, 20.0]),
    "algorithms": (["dso", ["dso"]], ["dso"]),
    "relative_to": (["Length", "length"], "length"),
    "gt_fmt": (["EuRoC", "euroc"], "euroc"),
}


@pytest.mark.parametrize("name", sorted(EQUIVALENT))
def test_equivalent_spellings_are_one_value(name):
    spellings, expected = EQUIVALENT[name]
    declared = {name: {"default": "None"}, "groundtruth": {"default": "None"}}
    given = {"groundtruth": str(Path(__file__))} if name == "gt_fmt" else {}  # (gt_fmt needs it)
    got = [check_parameters({**given, name: s}, declared)[name] for s in spellings]
    assert all(g == expected and type(g) is type(expected) for g in got), (spellings, got)
    assert [nbparams.canonical(name, s) for s in spellings] == [expected] * len(spellings)


def test_a_value_no_rule_knows_and_none_stay_as_given():
    assert nbparams.canonical("output_dir", "x") == "x" and nbparams.canonical("scale", None) is None


def _notebook(folder: Path) -> None:
    book = nbformat.v4.new_notebook()
    book.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    cell = nbformat.v4.new_code_cell('data_root = None\nresults_dir = None\noutput_dir = None\nscale = "auto"')
    cell.metadata["tags"] = ["parameters"]
    book.cells = [cell, nbformat.v4.new_code_cell("open('scale.txt', 'w').write(repr(scale))")]
    folder.mkdir()
    nbformat.write(book, folder / "shows_scale.ipynb")


def test_runs_at_equivalent_scales_record_one_spec_and_compare(data, tmp_path):
    """Two report runs, ``-p scale on`` and ``-p scale true``: the notebook receives True in both, and
    run.json's spec is the same, so diff and the gate compare them (it said ``spec scale: "on" ...
    against true`` and judged nothing)."""
    results = tmp_path / "mine"
    for rel in ("dso/cafe-1-1-all.txt", "orbslam2_rgbd/cafe_1_1_orbslam2-original.txt"):
        (results / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(data.icra20 / "per-seq" / rel, results / rel)
    _notebook(tmp_path / "nbs")
    runs = []
    for name, scale in (("a_on", "on"), ("b_yes", "Yes"), ("c_true", True)):
        run_dir, done = build.run_report(tmp_path / "nightly" / name, {"scale": scale, "data_root": str(data.root)},
                                         notebooks_dir=tmp_path / "nbs", results=results, progress=False, jobs=1)  # fmt: skip
        assert [r.status for r in done] == ["ok"], [r.error for r in done]
        assert (run_dir / "shows_scale" / "scale.txt").read_text() == "True"
        assert json.loads((run_dir / "parameters.json").read_text())["scale"] is True
        spec = json.loads((run_dir / "run.json").read_text())["spec"]["values"]
        assert spec["scale"] is True and spec["align"] == "sim3"
        runs.append(load_run(run_dir))
    assert spec_differences(runs[0], runs[2]) == [] and spec_differences(runs[1], runs[2]) == []


def test_results_and_another_results_dir_are_refused_before_any_file_is_read(data, tmp_path, monkeypatch):
    """``--results A -p results_dir B``: refused before B (or A) is scanned for result files (``-p
    results_dir /tmp`` read all of /tmp first)."""
    (tmp_path / "a" / "alg").mkdir(parents=True)
    (tmp_path / "a" / "alg" / "cafe-1-1.txt").write_text("0 0 0 0 0 0 0 1\n")
    (tmp_path / "b").mkdir()

    def scanned(*args, **kwargs):
        raise AssertionError("a folder was scanned for result files before the conflict was refused")

    monkeypatch.setattr(nbparams, "result_files", scanned)
    monkeypatch.setattr(build, "result_files", scanned)
    with pytest.raises(ValidationError, match="--results and -p results_dir name two folders; give one"):
        build.run_report(tmp_path / "out", {"results_dir": str(tmp_path / "b")}, results=tmp_path / "a", progress=False)
    assert not (tmp_path / "out").exists()


def _words(data, tmp_path, every: int):
    """every_number's "why they differ" on the bundled fr2/desk pair, the estimate thinned to one pose
    in ``every`` (as ``awk 'NR%60==1'`` makes one pose every ~2 s)."""
    import lorisnb as ln
    from lorisnb.tools.notebook.prose import every_number_words
    from lorisnb.tools.peers import every_number as en

    tum = data.root / "tum-rgbd"
    lines = (tum / "fr2_desk_ORB.txt").read_text().splitlines(keepends=True)
    est = tmp_path / f"est {every}.txt"
    est.write_text("".join(lines[::every]))
    gt = tum / "fr2_desk_groundtruth.txt"
    with pytest.warns(Warning):  # the pair's own warnings (a repeated stamp, gaps in the ground truth)
        wide = en.side_by_side(en.every_number(est, gt))
        truth = ln.read_trajectory(gt, "tum")
    return every_number_words(wide, truth, ln.read_trajectory(est, "tum")), wide


def test_every_number_compares_what_it_computed(data, tmp_path):
    """With one pose every ~2 s, one frame is a LONGER step than 1 s and evo's RPE LARGER: it said "a
    smaller number for a shorter step" (typed), and "a desk-sized scene" of any path under 100 m."""
    sparse, wide = _words(data, tmp_path, 60)
    rpe = wide.loc[("RPE translation RMSE", "m")]
    assert rpe["evo"] > rpe[["openloris", "tum", "rpg"]].max()  # the data: larger over the ~2 s step
    assert "(here 2 s, the median time between this estimate's poses, longer than 1 s)" in sparse
    assert f"gives {rpe['evo']:.4f} m, a larger number for a longer step, not a worse run" in sparse
    assert "shorter step" not in sparse and "smaller number" not in sparse and "desk-sized" not in sparse
    assert "says nothing about a path of 20.3 m, shorter than the devkit's shortest segment (100 m)" in sparse
    dense, wide = _words(data, tmp_path, 1)
    assert "shorter than 1 s) gives 0.0035 m, a smaller number for a shorter step, not a better run" in dense
    assert "within evo's tighter one of 0.01 s" in dense  # the presets' tolerances: 0.01 s against 0.02 s


def test_every_number_refuses_a_users_file_before_writing_anything(data, tmp_path):
    """A file of the user's named as the figure every_number writes last: refused in its first cell
    (setup), before every_number.csv and the marker are written (it was refused when the figure cell ran)."""
    from lorisnb.errors import OutputError
    from lorisnb.tools.notebook.start import OUTPUTS_MARKER, setup

    out = tmp_path / "nb out"
    out.mkdir()
    (out / "every_number_ate.png").write_bytes(b"mine")
    with pytest.raises(OutputError, match="every_number_ate.png exists and this notebook did not write it"):
        setup("every_number", str(data.root), str(out), parameters={})
    assert sorted(p.name for p in out.iterdir()) == ["every_number_ate.png"]
    assert not (out / OUTPUTS_MARKER).exists()


def test_every_listed_output_is_one_the_notebook_writes():
    """:data:`NOTEBOOK_OUTPUTS` names only files its notebook's source writes (by out.table, out.figure
    or out.path), at the parameters' defaults and with the simulated section on: checked ahead, a name
    the notebook no longer writes would refuse a user's file for nothing."""
    import re

    from lorisnb.tools.notebook.start import NOTEBOOK_OUTPUTS
    from lorisnb.tools.report.build import notebook_path

    for name, outputs in NOTEBOOK_OUTPUTS.items():
        source = "\n".join("".join(c["source"]) for c in nbformat.read(notebook_path(name), 4).cells)
        written = set(re.findall(r"out\.(?:table|figure)\([^\n]*\"(\w+)\"[,)]", source))
        listed = outputs({"metric": "cr"})
        assert set(listed.get("tables", [])) | set(listed.get("figures", [])) <= written, name
        for f in listed.get("files", []):
            assert f'out.path(f"{{metric}}_table.{f.rsplit(".", 1)[1]}")' in source, (name, f)
