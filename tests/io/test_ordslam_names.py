"""ORDSLAM sequence names, catalog.csv, and how estimates find their ground truth in nested
folders (the README's own ``scenario6/20h/standard.txt`` style).

The files are synthetic, written by the tests from bundled OpenLORIS ground truth (the real 27 GB
dataset is not bundled), as in test_ordslam.py."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import lorisnb as ln
from lorisnb.io.readers.ordslam import describe_sequence, find_ordslam
from lorisnb.tools.notebook.indoor_outdoor import ordslam_difficulty, ordslam_stats


@pytest.fixture(scope="module")
def segment():
    gt = ln.load_groundtruth("cafe").sequences[1]
    sel = np.flatnonzero(gt.stamps - gt.stamps[0] < 30)[::3]
    return gt.subset(sel)


def _tum(path, stamps, positions, quats):
    path.parent.mkdir(parents=True, exist_ok=True)
    rows = np.column_stack([stamps, positions, quats])
    path.write_text("\n".join(" ".join(f"{v:.17g}" for v in r) for r in rows) + "\n")


def _quiet(name, catalog=None):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return describe_sequence(name, catalog)


def _fields(d):
    """(scenario, difficulty, time, depth mode), None for an unknown scenario or time (NaN in a table)."""
    known = [None if not isinstance(v, str) and v != v else v for v in (d["scenario"], d["time"])]
    return known[0], d["difficulty"], known[1], d["depth_mode"]


@pytest.mark.parametrize(
    "name, expected",
    [
        ("s5_13-00_fill.txt", (5, "difficult", "13:00", "fill")),
        ("ordslam/S6_22-30_FILLED.txt", (6, "very difficult", "22:30", "fill")),
        ("scenario6/20h/standard.txt", (6, "very difficult", "20:00", "standard")),
        ("scenario_2/8h30/std.txt", (2, "simple", "08:30", "standard")),
        ("sc4 16:30 Fill.txt", (4, "medium", "16:30", "fill")),
        # four levels deep: only the last three parts were read, losing the scenario (NaN, "no scenario token")
        ("scenario5/13-00/fill/groundtruth.txt", (5, "difficult", "13:00", "fill")),
        ("scenario5/13h00/day/fill.txt", (5, "difficult", "13:00", "fill")),
        ("ordslam/s6/outdoor/20h/run/standard.txt", (6, "very difficult", "20:00", "standard")),
    ],
)
def test_documented_name_patterns_are_read_without_warning(name, expected):
    assert _fields(_quiet(name)) == expected


@pytest.mark.parametrize(
    "name, expected, complaint",
    [
        ("s5_fill_v2.txt", (5, "difficult", None, "fill"), "time of day: no time of day token"),
        ("seq01_s5_fill.txt", (5, "difficult", None, "fill"), "time of day: no time of day token"),
        ("s5_fill_run3.txt", (5, "difficult", None, "fill"), "time of day: no time of day token"),
        ("s7_13-00_fill.txt", (None, "unknown", "13:00", "fill"), "scenario 7 is not one of the dataset page's"),
        ("s0_13-00_fill.txt", (None, "unknown", "13:00", "fill"), "scenario 0 is not one of"),
        ("scene5_13h.txt", (None, "unknown", "13:00", "unknown"), "scenario: no scenario token; expected"),
        ("s5/s6_13h_fill.txt", (None, "unknown", "13:00", "fill"), r"scenario: tokens disagree \(\[5, 6\]\)"),
        ("s5_13h_20h_std.txt", (5, "difficult", None, "standard"), "time of day: tokens disagree"),
    ],
)
def test_stray_digits_are_not_read_and_gaps_are_said(name, expected, complaint):
    with pytest.warns(ln.LorisWarning, match=f"^{name}: could not read from the name: .*{complaint}"):
        d = describe_sequence(name)
    assert _fields(d) == expected
    assert d["light"] == ("day" if d["time"] else "unknown")


def _catalog_folder(tmp_path, segment, text):
    q = segment.rotations().as_quat()
    for name in ("a.txt", "b.txt", "deep/c.txt", "x/same.txt", "y/same.txt"):
        _tum(tmp_path / name, segment.stamps, segment.positions, q)
    (tmp_path / "catalog.csv").write_text(text)
    return tmp_path


def test_catalog_is_normalized(tmp_path, segment):
    root = _catalog_folder(
        tmp_path,
        segment,
        "file,scenario,time,depth_mode\na.txt,5,20h,Fill\nb.txt, 6 ,8,STD\ndeep/c.txt,4,13-30,\nx/same.txt,,,\n",
    )
    seq = find_ordslam(root).sequences().set_index("path")
    got = {p[len(str(root)) + 1 :]: _fields(r) for p, r in seq.iterrows() if not p.endswith("y/same.txt")}
    assert got["a.txt"] == (5, "difficult", "20:00", "fill")
    assert got["b.txt"] == (6, "very difficult", "08:00", "standard")
    assert got["deep/c.txt"] == (4, "medium", "13:30", "unknown")
    assert got["x/same.txt"] == (None, "unknown", None, "unknown")  # listed with empty cells: unknown, no name reading


@pytest.mark.parametrize(
    "row, where",
    [
        ("a.txt,five,13:00,fill", "line 2: row 1, column scenario: 'five'; expected a scenario number 1-6"),
        ("a.txt,7,13:00,fill", "line 2: row 1, column scenario: '7'; expected a scenario number 1-6"),
        ("a.txt,5.5,13:00,fill", "line 2: row 1, column scenario: '5.5'"),
        ("a.txt,5,13.5,fill", "line 2: row 1, column time: '13.5'; expected a time of day HH-MM"),
        ("a.txt,5,25:00,fill", "line 2: row 1, column time: '25:00'"),
        ("a.txt,5,20h,dense", "line 2: row 1, column depth_mode: 'dense'; expected a depth mode fill"),
        ("same.txt,5,20h,fill", r"line 2: row 1, column file: 'same.txt'; .*several ground-truth files are named so \(x/same.txt, y/same"),
        ("nope.txt,5,20h,fill", "line 2: row 1, column file: 'nope.txt'; .*no such ground-truth file"),
        ("b.txt,5,20h,fill\nb.txt,6,20h,fill", r"line 3: row 2, column file: 'b.txt'; expected each file once \(already on row 1\)"),
    ],
)  # fmt: skip
def test_catalog_errors_name_file_row_and_column(tmp_path, segment, row, where):
    root = _catalog_folder(tmp_path, segment, f"file,scenario,time,depth_mode\n{row}\n")
    with pytest.raises(ln.ParseError, match=f"catalog.csv, {where}"):
        find_ordslam(root)


def test_catalog_columns_are_checked(tmp_path, segment):
    root = _catalog_folder(tmp_path, segment, "file,scenario,hour\na.txt,5,13\n")
    with pytest.raises(
        ln.ParseError, match=r"catalog.csv, line 1: unknown column\(s\) \['hour'\]; expected columns file"
    ):
        find_ordslam(root)


def _nested(root, segment, estimates):
    """Ground truth of scenarios 5 and 6 under the same file name, and estimates at ``estimates``
    (relative path -> noise in metres): the estimate is the ground truth moved rigidly, plus noise."""
    rng = np.random.default_rng(1)
    q = segment.rotations().as_quat()
    for rel in ("scenario5/13h/standard.txt", "scenario6/20h/standard.txt"):
        _tum(root / rel, segment.stamps, segment.positions, q)
    motion = Rotation.from_euler("z", 30, degrees=True)
    for rel, noise in estimates.items():
        p = motion.apply(segment.positions + rng.normal(scale=noise, size=segment.positions.shape)) + 1.0
        _tum(root / "estimates" / "slam" / rel, segment.stamps, p, (motion * segment.rotations()).as_quat())
    return find_ordslam(root)


def test_nested_estimates_meet_their_own_groundtruth(tmp_path, segment):
    folder = _nested(tmp_path, segment, {"scenario5/13h/standard.txt": 0.02, "scenario6/20h/standard.txt": 0.2})
    table, problems = ordslam_difficulty(folder)
    assert problems.empty
    t = table.set_index("sequence")
    assert list(t.index) == ["scenario5/13h/standard.txt", "scenario6/20h/standard.txt"]
    assert list(t["group"]) == ["difficult", "very difficult"] and list(t["light"]) == ["day", "night"]
    # the noise put in comes back out: sqrt(3) * sigma, within sampling error; 10 x apart
    assert t.loc["scenario5/13h/standard.txt", "ate_rmse_m"] == pytest.approx(0.02 * np.sqrt(3), rel=0.25)
    assert t.loc["scenario6/20h/standard.txt", "ate_rmse_m"] == pytest.approx(0.2 * np.sqrt(3), rel=0.25)
    stats = ordslam_stats(folder)
    assert list(stats["sequence"]) == list(t.index) and list(stats["group"]) == ["difficult", "very difficult"]


def test_ambiguous_or_unmatched_estimates_are_refused_by_name(tmp_path, segment):
    folder = _nested(tmp_path, segment, {"standard.txt": 0.02, "scenario5/20h/standard.txt": 0.02})
    table, problems = ordslam_difficulty(folder)
    assert table.empty and list(problems["status"]) == ["failed", "failed"]
    err = dict(zip([p.split("estimates/slam/")[1] for p in problems["file"]], problems["error"], strict=True))
    assert err["standard.txt"].startswith(
        "ambiguous: ground-truth files scenario5/13h/standard.txt, scenario6/20h/standard.txt are all named standard.txt"
    )
    assert err["scenario5/20h/standard.txt"].startswith("no ground-truth file scenario5/20h/standard.txt")
    assert (
        "ground truth with that name: scenario5/13h/standard.txt, scenario6/20h/standard.txt"
        in err["scenario5/20h/standard.txt"]
    )


def test_bare_name_estimate_still_meets_a_unique_groundtruth(tmp_path, segment):
    q = segment.rotations().as_quat()
    _tum(tmp_path / "deep" / "s5_13-00_fill.txt", segment.stamps, segment.positions, q)
    _tum(tmp_path / "estimates" / "slam" / "s5_13-00_fill.txt", segment.stamps, segment.positions + 0.5, q)
    table, problems = ordslam_difficulty(find_ordslam(tmp_path))
    assert problems.empty and list(table["sequence"]) == ["deep/s5_13-00_fill.txt"]
    assert table["ate_rmse_m"].iloc[0] == pytest.approx(0.0, abs=1e-9)  # a pure shift: Horn alignment removes it


def test_a_folder_reads_every_level_below_its_root(tmp_path, segment):
    """``scenario5/13-00/fill/groundtruth.txt`` in an ORDSLAM folder: scenario 5 (difficult), 13:00,
    fill, without a warning; the folders above the dataset's own are not read (``s6`` here)."""
    root = tmp_path / "s6" / "ord"
    _tum(
        root / "scenario5/13-00/fill/groundtruth.txt", segment.stamps, segment.positions, segment.rotations().as_quat()
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        seqs = find_ordslam(root).sequences()
    assert _fields(seqs.iloc[0]) == (5, "difficult", "13:00", "fill")
