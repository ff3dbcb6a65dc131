"""What the ground truth's reader notices reaches the user as the estimate's notes do (a pair's,
a manifest's, the data root's OpenLORIS ground truth): poses skipped, stamps repeated, each with its
file and line (they went nowhere: not printed, not in ``ev.warnings``, no Python warning). A ground
truth whose stamps go back in time (one stamp written in nanoseconds, an hour early, 0) is refused,
naming the line, never sorted into a ground-truth time of 10^18 s (CR 0, exit 0)."""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.errors import LorisWarning


def _lines(path: Path) -> list[str]:
    return path.read_text().splitlines(keepends=True)


def _gt_with(tmp_path: Path, data, line: int, edit, name: str = "gt.txt") -> Path:
    """A copy of fr2_desk's ground truth with 1-based ``line`` changed by ``edit``."""
    lines = _lines(data.tum / "fr2_desk_groundtruth.txt")
    lines[line - 1] = edit(lines[line - 1])
    out = tmp_path / name
    out.write_text("".join(lines))
    return out


def _nan_pose(text: str) -> str:
    stamp, *_ = text.split()
    return f"{stamp} nan nan nan 0 0 0 1\n"


def _in_ns(text: str) -> str:
    stamp, *rest = text.split()
    return " ".join([str(int(float(stamp) * 1e9)), *rest]) + "\n"


def _manifest(tmp_path: Path, gt: Path) -> Path:
    """A manifest of one session (fr2_desk's ground truth ``gt``, beside it) and a results folder."""
    est = tmp_path / "results" / "orb"
    est.mkdir(parents=True, exist_ok=True)
    shutil.copy(tmp_path / "orb.txt", est / "desk.txt")
    m = tmp_path / "m.toml"
    m.write_text(f'name = "t"\nscene = "tum"\n[[session]]\nname = "desk"\ngroundtruth = "{gt.name}"\n')
    return m


@pytest.fixture
def est(tmp_path, data) -> Path:
    path = tmp_path / "orb.txt"
    shutil.copy(data.tum / "fr2_desk_ORB.txt", path)
    return path


def test_a_pairs_groundtruth_notes_reach_every_surface(tmp_path, data, est, capsys):
    gt = _gt_with(tmp_path, data, 5000, _nan_pose)
    said = f"{gt}: 1 pose(s) with NaN values skipped (first at line 5000)"
    with pytest.warns(LorisWarning) as caught:
        ev = ln.evaluate_pairs(est, gt)
    assert said in [str(w.message) for w in caught]
    assert said in ev.warnings and ev.exit_status() == 0
    assert main(["evaluate", str(est), "--gt", str(gt), "--no-progress"]) == 0
    assert f"warning: {said}" in capsys.readouterr().err
    # a manifest's ground truth is read by the same code
    m = _manifest(tmp_path, gt)
    with pytest.warns(LorisWarning) as caught:
        ev = ln.evaluate_manifest(m, tmp_path / "results")
    assert said in [str(w.message) for w in caught] and said in ev.warnings
    assert round(ev.sequences()["cr"].iloc[0], 4) == round(ln.evaluate_pairs(est, gt).sequences()["cr"].iloc[0], 4)


@pytest.mark.parametrize(
    "edit, line, back",
    [
        (_in_ns, 5000, 5001),  # one stamp in nanoseconds: the next line goes back from it
        (lambda t: f"{float(t.split()[0]) - 3600:.4f} " + " ".join(t.split()[1:]) + "\n", 5000, 5000),  # an hour early
        (lambda t: "0 " + " ".join(t.split()[1:]) + "\n", 5000, 5000),  # a stamp 0
    ],
)
def test_a_groundtruth_going_back_in_time_is_refused(tmp_path, data, est, capsys, edit, line, back):
    """Sorted, the ns stamp made the ground truth 1.3e18 s long (CR 0.0000, exit 0); now the input
    fails naming the line, on every route that reads a plain ground truth."""
    gt = _gt_with(tmp_path, data, line, edit)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ev = ln.evaluate_pairs(est, gt, spec="tum")
    assert not ev.errors and ev.exit_status() == 1
    (failure,) = ev.failures
    assert f"{gt}, line {back}: the ground truth's stamp" in failure.error and "goes back" in failure.error
    assert failure.kind == "ParseError"
    assert main(["evaluate", str(est), "--gt", str(gt), "--conventions", "tum", "--no-progress"]) == 1
    assert f"line {back}: the ground truth's stamp" in capsys.readouterr().err
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ev = ln.evaluate_manifest(_manifest(tmp_path, gt), tmp_path / "results")
    assert not ev.errors and f"line {back}: the ground truth's stamp" in ev.failures[0].error


def test_a_repeated_groundtruth_stamp_is_still_read_and_said(tmp_path, data, est):
    """fr2_desk's own ground truth repeats one stamp (line 10863): read as before (the same numbers)
    and, now, said."""
    gt = data.tum / "fr2_desk_groundtruth.txt"
    with pytest.warns(LorisWarning, match=r"fr2_desk_groundtruth.txt: timestamps are not increasing .* line 10863"):
        ev = ln.evaluate_pairs(est, gt, spec="tum")
    row = ev.sequences().iloc[0]
    assert row["matched"] == 2223 and round(row["cr"], 4) == 0.85 and ev.exit_status() == 0


def _data_copy(tmp_path: Path, data, edit) -> Path:
    root = tmp_path / "data"
    shutil.copytree(data.root / "openloris-scene" / "groundtruth", root / "openloris-scene" / "groundtruth")
    shutil.copy(data.root / "openloris-scene" / "extrinsics.json", root / "openloris-scene" / "extrinsics.json")
    path = root / "openloris-scene" / "groundtruth" / "gt_cafe_1.txt"
    path.chmod(0o644)
    lines = _lines(path)
    i = next(k for k, t in enumerate(lines) if t.startswith("seq: 2"))  # line i+1 is seq 2's header
    lines[i - 10] = edit(lines[i - 10])  # a pose of seq 1
    path.write_text("".join(lines))
    return root


def test_the_data_roots_groundtruth_notes_reach_the_user(tmp_path, data, icra20):
    est = icra20 / "per-seq" / "orbslam2_rgbd" / "cafe_1_1_orbslam2-original.txt"
    root = _data_copy(tmp_path, data, _nan_pose)
    with pytest.warns(LorisWarning, match=r"gt_cafe_1.txt.*NaN") as caught:
        ev = ln.evaluate(est, data_root=root)
    said = [str(w.message) for w in caught if "gt_cafe_1.txt" in str(w.message)]
    assert said and said[0] in ev.warnings and ev.exit_status() == 0
    root = _data_copy(tmp_path / "b", data, lambda t: "0 " + " ".join(t.split()[1:]) + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ev = ln.evaluate(est, data_root=root)
    assert not ev.errors and "gt_cafe_1.txt" in ev.failures[0].error and "goes back" in ev.failures[0].error
