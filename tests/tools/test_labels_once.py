"""Each file's labels (algorithm, file, suite, trial) are computed once per process and path
(:func:`lorisnb.tools.evaluation.inputs.labels`): the folder relative paths are read from is part
of what they are computed from."""

from __future__ import annotations

import shutil

import lorisnb as ln


def test_labels_follow_the_current_folder(icra20, tmp_path, monkeypatch):
    """A root typed as ``.`` is named by the folder it is in: evaluating ``.`` inside two algorithm
    folders in turn (a notebook that changes folder) gives each its own algorithm, not the first
    one's label again (labels are computed once per process and path, the folder part of the key)."""
    for alg in ("algA", "algB"):
        (tmp_path / alg).mkdir()
        shutil.copy(icra20 / "lifelong" / "maslam" / "home.txt", tmp_path / alg / "home.txt")
    seen = []
    for alg in ("algA", "algB"):
        monkeypatch.chdir(tmp_path / alg)
        seen.append(set(ln.evaluate(".", progress=False, jobs=1, keep_poses=False).sequences()["algorithm"]))
    assert seen == [{"algA"}, {"algB"}]
