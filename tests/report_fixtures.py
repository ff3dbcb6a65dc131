"""A lab's own results folder with trials, made from the bundled icra20 per-seq results in a
temporary folder: trial 1 is the file as published, trials 2 and 3 lose the last 10 % and 25 % of
their pose lines (a tracker that stopped early), so the trials differ the way real runs do."""

from __future__ import annotations

from pathlib import Path

#: algorithm folder -> bundled file names of cafe seq 1, cafe seq 2 and home seq 1
FILES = {
    "orb": ["cafe_1_1_orbslam2-original.txt", "cafe_1_2_orbslam2-original.txt", "home_1_1_orbslam2-original.txt"],
    "odom": ["cafe-1-1-odom.txt", "cafe-1-2-odom.txt", "home-1-1-odom.txt"],
}
SOURCE = {"orb": "orbslam2_rgbd", "odom": "odom"}
KEEP = {1: 1.0, 2: 0.9, 3: 0.75}  # share of pose lines each trial keeps


def truncated(text: str, keep: float) -> str:
    lines = text.splitlines(keepends=True)
    poses = [i for i, line in enumerate(lines) if line[:1].isdigit()]
    cut = poses[int(len(poses) * keep)] if keep < 1 else len(lines)
    return "".join(lines[:cut])


def trial_results(root: Path, icra20: Path) -> Path:
    """``root/<alg>/<scene>_<seq>_trial<k>.txt`` for the algorithms of :data:`FILES`; returns root."""
    for alg, names in FILES.items():
        for name, label in zip(names, ["cafe_1", "cafe_2", "home_1"], strict=True):
            text = (icra20 / "per-seq" / SOURCE[alg] / name).read_text()
            for k, keep in KEEP.items():
                p = root / alg / f"{label}_trial{k}.txt"
                p.parent.mkdir(parents=True, exist_ok=True)
                p.write_text(truncated(text, keep))
    return root


def fake_notebook(name, out_dir, params, **kw):
    """A notebook run standing for papermill's in a report (fast): a one-cell notebook and its page
    in the notebook's folder (``report.run_notebook``'s place in the tests)."""
    import nbformat

    from lorisnb.tools.report.notebooks import NotebookRun

    (out_dir / name).mkdir()
    nbformat.write(nbformat.v4.new_notebook(cells=[nbformat.v4.new_markdown_cell("a page")]),
                   str(out_dir / name / f"{name}.ipynb"))  # fmt: skip
    (out_dir / name / f"{name}.html").write_text("<p>page</p>")
    return NotebookRun(name)


def fake_papermill_notebook(name, out_dir, params, **kw):
    """:func:`fake_notebook` as papermill leaves it: where it was executed (its ``output_path``, an
    absolute path of this machine) in its metadata."""
    import nbformat

    from lorisnb.tools.report.notebooks import NotebookRun

    (out_dir / name).mkdir()
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_markdown_cell("a page")])
    nb.metadata["papermill"] = {"output_path": str(out_dir / name / f"{name}.ipynb"), "input_path": "x.ipynb"}
    nbformat.write(nb, str(out_dir / name / f"{name}.ipynb"))
    (out_dir / name / f"{name}.html").write_text("<p>page</p>")
    return NotebookRun(name)
