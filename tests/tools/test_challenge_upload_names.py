"""The names an upload's files are kept and scored under (:func:`lorisnb.tools.challenge.uploads.kept_name`):
a suffix in upper case (``CAFE-1-1.TXT``) was accepted, then skipped by the scorer's folder walk,
and the submission "scored" with no row and no failure; trial folders (``run_1/a.txt``,
``run_2/b.txt``) lost their folder and failed as duplicates; a trial number past 64 bits failed the
scoring with an internal error. A file of nothing scored is a failure naming it."""

from __future__ import annotations

import io
import json

import pytest
from challenge_fixtures import challenge_file, zipped

from lorisnb.tools.challenge.config import read_challenge, sequences_of
from lorisnb.tools.challenge.scoring import score_folder
from lorisnb.tools.challenge.uploads import PLAN, Limits, UploadRefused, keep_upload
from lorisnb.tools.evaluation.runner import evaluate

pytest.importorskip("fastapi")
LIMITS = Limits(20, 50_000_000)


def _poses(path) -> bytes:
    return b"\n".join(line for line in path.read_bytes().split(b"\n") if line[:1].isdigit()) + b"\n"


@pytest.fixture
def challenge(tmp_path, data):
    return read_challenge(challenge_file(tmp_path, data, final_closed=True))


def _score(challenge, sub):
    plain = json.loads((sub / PLAN).read_text()) if (sub / PLAN).is_file() else {}
    return score_folder(sub / "files", challenge.data, challenge.spec, plain=plain, groundtruth=sub.parent / "gt")


def _keep(challenge, sub, files):
    from lorisnb.io.datasets.paths import scene_durations

    seqs = sequences_of(scene_durations(challenge.scenes, challenge.data))
    return keep_upload([(n, io.BytesIO(b)) for n, b in files], sub, LIMITS, "auto", seqs)


def test_an_upper_case_suffix_is_scored(tmp_path, data, challenge):
    """TUM and EuRoC files with .TXT, .CSV, .Txt (in a zip) are kept with the suffix the scorer
    reads, and scored as the same poses named in lower case are (cafe-1: 1139 matched, CR 0.999137)."""
    tum = _poses(data.icra20 / "per-seq" / "odom" / "cafe-1-1-odom.txt")
    csv = b"\n".join(b",".join(line.split()) for line in tum.split(b"\n"))
    rows = {}
    for k, files in enumerate([[("CAFE-1-1.TXT", tum)], [("cafe-1-1.CSV", csv)], [("r.zip", zipped({"cafe-1-1.Txt": tum}))],
                               [("cafe-1-1.txt", tum)]]):  # fmt: skip
        sub = tmp_path / "uploads" / str(k)
        names = _keep(challenge, sub, files)
        out = _score(challenge, sub)
        assert out["failures"] == [], out["failures"]
        rows[names[0]] = [(r["scene"], r["seq"], r["matched"], round(r["cr"], 6)) for r in out["rows"]]
    assert set(rows) == {"CAFE-1-1.txt", "cafe-1-1.csv", "cafe-1-1.txt"}
    assert all(r == [("cafe", 1, 1139, 0.999137)] for r in rows.values()), rows


def test_a_file_of_nothing_scored_is_a_failure_naming_it(tmp_path, data, challenge):
    """A file the scorer's walk does not read was dropped with "nothing was evaluated", named for no
    file: the submission scored with no row, no failure. (A file kept with .TXT by a server of
    before is read now: the walk takes a suffix in any case.)"""
    poses = _poses(data.icra20 / "per-seq" / "odom" / "cafe-1-1-odom.txt")
    for name, scored in (("cafe-1-1.dat", False), ("CAFE-1-1.TXT", True)):
        sub = tmp_path / "uploads" / name
        (sub / "files").mkdir(parents=True)
        (sub / "files" / name).write_bytes(poses)
        (sub / PLAN).write_text(json.dumps({name: dict(format="tum", scene="cafe", seq=1)}))
        out = _score(challenge, sub)
        if scored:
            assert out["failures"] == [] and [(r["scene"], r["seq"], r["matched"]) for r in out["rows"]] == [
                ("cafe", 1, 1139)
            ]
            continue
        assert out["rows"] == []
        assert [(f["file"], f["status"], f["sequences"]) for f in out["failures"]] == [(name, "failed", [("cafe", 1)])]
        assert "nothing was evaluated" in out["failures"][0]["error"]


def test_trial_folders_are_trials(tmp_path, data, challenge):
    """run_1/ and run_2/ are trials 1 and 2, as ``lorisnb evaluate`` reads the folder: kept as
    a_trial1.txt and b_trial2.txt, each scored as evaluate scores its trial (the same rows)."""
    per_seq = data.icra20 / "per-seq"
    one, two = (per_seq / "ds-slam" / "cafe-1-1.txt"), (per_seq / "vins_mono_color_imu_with_loop" / "cafe-1-1.txt")
    sub = tmp_path / "uploads" / "trials"
    names = _keep(
        challenge, sub, [("t.zip", zipped({"run_1/a.txt": one.read_bytes(), "run_2/b.txt": two.read_bytes()}))]
    )
    assert names == ["a_trial1.txt", "b_trial2.txt"]
    out = _score(challenge, sub)
    assert out["failures"] == [], out["failures"]
    got = sorted((r["trial"], r["seq"], r["matched"], round(r["cr"], 6)) for r in out["rows"])
    local = tmp_path / "local" / "alg"
    for k, src in ((1, one), (2, two)):
        (local / f"run_{k}").mkdir(parents=True)
        (local / f"run_{k}" / "a.txt").write_bytes(src.read_bytes())
    ev = evaluate([tmp_path / "local"], challenge.spec, data_root=challenge.data, jobs=1, progress=False)
    want = sorted((int(r["trial"]), int(r["seq"]), int(r["matched"]), round(r["cr"], 6)) for r in ev.sequence_rows())
    assert got == want
    assert [t for t, *_ in got] == [1, 2] and got[0][3] != got[1][3]


def test_a_trial_number_past_64_bits_is_refused_at_upload(tmp_path, data, challenge):
    """cafe-1-1_trial99999999999999999999.txt was accepted, then failed scoring with
    OverflowError ("tell the organizers"); refused now, saying the largest trial number taken."""
    tum = _poses(data.icra20 / "per-seq" / "odom" / "cafe-1-1-odom.txt")
    for k, name in enumerate(["cafe-1-1_trial99999999999999999999.txt", "run_99999999999999999999/cafe-1-1.txt"]):
        with pytest.raises(UploadRefused, match=r"trial number 99999999999999999999, too large; expected a trial "
                           r"number of at most 9223372036854775807"):  # fmt: skip
            _keep(challenge, tmp_path / "uploads" / str(k), [("r.zip", zipped({name: tum}))])
        assert not (tmp_path / "uploads" / str(k) / "files").exists()
    sub = tmp_path / "uploads" / "fits"  # the largest taken is scored as a trial
    assert _keep(challenge, sub, [(f"cafe-1-1_trial{2**63 - 1}.txt", tum)]) == [f"cafe-1-1_trial{2**63 - 1}.txt"]
    out = _score(challenge, sub)
    assert [(r["trial"], r["matched"]) for r in out["rows"]] == [(2**63 - 1, 1139)], out["failures"]
