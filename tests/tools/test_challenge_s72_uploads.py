"""Uploads refused where the scorer would refuse them, and what a team is told (s72): an OpenLORIS
file with a misspelt ``frame:`` (or none, or no ``seq:`` block) was taken (201), failed at scoring
and used up a submission; a ``seq: 7`` of no sequence of the challenge was taken and failed as "in
no phase this submission's scores are shown in", where a TUM file named cafe-1-7.txt was refused at
upload; a hidden sequence whose file failed was listed both as scored and as a failure; an absolute
form file name was told to be a path inside an archive no one sent."""

from __future__ import annotations

import io
import json
import re
import time
from types import SimpleNamespace

import pytest
from challenge_fixtures import cafe_files, challenge_file, zipped

pytest.importorskip("fastapi")
from fastapi.testclient import TestClient  # noqa: E402

from lorisnb.io.datasets.paths import scene_durations  # noqa: E402
from lorisnb.tools.challenge import store  # noqa: E402
from lorisnb.tools.challenge.app import create_app  # noqa: E402
from lorisnb.tools.challenge.board import submission_view  # noqa: E402
from lorisnb.tools.challenge.config import read_challenge, sequences_of  # noqa: E402
from lorisnb.tools.challenge.scoring import score_folder  # noqa: E402
from lorisnb.tools.challenge.uploads import PLAN, Limits, keep_upload  # noqa: E402

LIMITS = "submissions_per_day = 2"
#: A TUM file of 60 poses whose stamps (1000 s on) miss every ground truth of cafe.
MISSING = b"".join(b"%d %.1f 0 0 0 0 0 1\n" % (1000 + k, 0.1 * k) for k in range(60))


@pytest.fixture()
def server(tmp_path, data):
    challenge = read_challenge(challenge_file(tmp_path, data, limits=LIMITS))
    app = create_app(challenge, score=False)
    engine = app.state.server.engine
    token = store.add_team(engine, "team", time.time() + 7000)
    with TestClient(app) as client:
        yield SimpleNamespace(client=client, token=token, engine=engine, challenge=challenge)


def post(s, files):
    return s.client.post("/api/submissions", files=files, headers={"Authorization": f"Bearer {s.token}"})


def nothing_kept(s) -> None:
    uploads = s.challenge.folder / "uploads"
    assert not uploads.exists() or list(uploads.iterdir()) == []
    assert store.all_submissions(s.engine) == []


def _good(data) -> str:
    """ds-slam's cafe-1-1 result (OpenLORIS: scene: cafe, frame: d400_color, seq: 1)."""
    return cafe_files(data, "ds-slam")[0].read_text()


def _header_faults(data) -> dict[str, str]:
    good = _good(data)
    assert "frame: d400_color" in good and "seq: 1" in good
    return {
        "misspelt frame": good.replace("frame: d400_color", "frame: d400_colour", 1),
        "markup frame": good.replace("frame: d400_color", "frame: <b>x</b>", 1),
        "no frame": good.replace("frame: d400_color", "", 1),
        "no seq block": "scene: cafe\nframe: base_link\n# no poses yet\n",
    }


@pytest.mark.parametrize("fault", ["misspelt frame", "markup frame", "no frame", "no seq block"])
def test_a_header_the_scorer_refuses_is_refused_at_upload_in_its_words(server, data, tmp_path, fault):
    """The upload is refused (400), nothing kept and no submission counted, with the words the
    scorer says of the same file (the scorer's failure, scored from a folder holding it alone)."""
    body = _header_faults(data)[fault]
    r = post(server, [("files", ("x.txt", body.encode()))])
    assert r.status_code == 400, r.text
    error = r.json()["error"]
    nothing_kept(server)
    # the same file, scored: the scorer's own failure, which the refusal must say
    files = tmp_path / "scored" / "files"
    files.mkdir(parents=True)
    (files / "x.txt").write_text(body)
    result = score_folder(files, server.challenge.data, server.challenge.spec, groundtruth=tmp_path / "gt")
    [failure] = result["failures"]
    assert failure["file"] == "x.txt" and error in (f"x.txt, {failure['error']}", f"x.txt: {failure['error']}"), (
        error, failure)  # fmt: skip
    if fault == "misspelt frame":
        assert "unknown frame 'd400_colour'; expected one of base_link, d400_color" in error, error
    # the limit of 2 a day is untouched: two good uploads still go in
    for _ in range(2):
        assert post(server, [("files", ("cafe-1-1.txt", _good(data).encode()))]).status_code == 201


def test_a_seq_of_no_sequence_of_the_challenge_is_refused_as_a_tum_name_is(server, data):
    """``seq: 7`` (cafe has 1 and 2) in an OpenLORIS file, first block or a later one, is refused at
    upload with the words a TUM file named cafe-1-7.txt is refused with, naming its line."""
    good = _good(data)
    tum = post(server, [("files", ("cafe-1-7.txt", MISSING))])
    assert tum.status_code == 400, tum.text
    tum_said = tum.json()["error"].split(": ", 1)[1]
    assert tum_said.startswith("names sequence cafe-1-7, which is not one of this challenge's; expected one of "), (
        tum_said
    )
    first = good.replace("seq: 1", "seq: 7", 1)
    line = first.splitlines().index("seq: 7") + 1
    later = good + "seq: 7\n1560004890.0 1 0 0 0 0 0 1\n"
    for name, body, at in (("a.txt", first, line), ("b.txt", later, len(later.splitlines()) - 1)):
        r = post(server, [("files", ("u.zip", zipped({name: body.encode()})))])
        assert r.status_code == 400, r.text
        assert r.json()["error"] == f"{name}, line {at}: 'seq: 7': {tum_said}", r.json()
    nothing_kept(server)
    assert post(server, [("files", ("cafe-1-1.txt", good.encode()))]).status_code == 201  # seq: 1 is taken


def test_an_absolute_form_file_name_is_not_said_to_be_in_an_archive(server, data):
    form = post(server, [("files", ("/abs/cafe-1-1.txt", _good(data).encode()))])
    assert form.status_code == 400, form.text
    said = form.json()["error"]
    assert said.startswith("upload: '/abs/cafe-1-1.txt': an absolute path; expected the file's name") and (
        "archive" not in said
    ), said
    member = post(server, [("files", ("u.zip", zipped({"/abs/cafe-1-1.txt": _good(data).encode()})))])
    assert member.status_code == 400 and "expected a path inside the archive" in member.json()["error"], member.text
    nothing_kept(server)


def test_a_hidden_sequence_whose_file_failed_is_a_failure_only(tmp_path, data):
    """Development shows cafe-1; cafe-2 shows once the final closes. ds-slam's cafe-1-2 (scored)
    is listed under "Scored, not shown yet"; a TUM cafe-1-2 missing its ground truth (not scored) is
    a failure only, told without a value, on the JSON and on the page."""
    challenge = read_challenge(challenge_file(tmp_path, data))
    durations = scene_durations(challenge.scenes, challenge.data)
    one, two = cafe_files(data, "ds-slam")

    def scored(files: list[tuple[str, bytes]]) -> dict:
        sub = tmp_path / f"sub{len(list(tmp_path.glob('sub*')))}"
        keep_upload([(n, io.BytesIO(b)) for n, b in files], sub, Limits(10, 10**8), "auto", sequences_of(durations),
                    challenge.spec)  # fmt: skip
        plain = json.loads((sub / PLAN).read_text()) if (sub / PLAN).is_file() else {}
        result = score_folder(sub / "files", challenge.data, challenge.spec, plain=plain, groundtruth=tmp_path / "gt",
                              views=[tuple(v) for v in challenge.views(sequences_of(durations), challenge.phase(
                                  "development"))])  # fmt: skip
        row = dict(id="s", team="t", phase="development", status="scored", created=time.time(), finished=time.time(),
                   files="[]", bytes=1, result=json.dumps(result), error=None)  # fmt: skip
        return submission_view(row, challenge, durations, time.time())

    failed = scored([(one.name, one.read_bytes()), ("cafe-1-2.txt", MISSING)])
    assert [r["seq"] for r in failed["rows"]] == [1]
    assert failed["hidden_sequences"] == [], failed["hidden_sequences"]
    [failure] = failed["failures"]
    assert failure["file"] == "cafe-1-2.txt" and failure["hidden"], failure
    assert failure["error"].startswith("cafe 2: no estimate stamp falls inside the ground truth's time span; the "
                                       "reason in full is shown once phase 'final' closes ("), failure  # fmt: skip
    assert not re.search(r"\d+\.\d+|\d{4,}", failure["error"].split(" closes (")[0]), failure  # no value
    # a file of cafe-2 that scored: named as scored, not yet shown (so the test can fail)
    both = scored([(one.name, one.read_bytes()), (two.name, two.read_bytes())])
    assert [(h["scene"], h["seq"], h["files"]) for h in both["hidden_sequences"]] == [("cafe", 2, [two.name])]
    assert both["failures"] == []
    # a scored file and a failed one of cafe-2, as trials: only the scored one is named as scored
    mixed = scored([(one.name, one.read_bytes()), ("cafe-1-2_trial1.txt", two.read_bytes()),
                    ("cafe-1-2_trial2.txt", MISSING)])  # fmt: skip
    assert [h["files"] for h in mixed["hidden_sequences"]] == [["cafe-1-2_trial1.txt"]], mixed["hidden_sequences"]
    assert [f["file"] for f in mixed["failures"]] == ["cafe-1-2_trial2.txt"]


def test_the_submission_page_lists_a_failed_hidden_file_once(server, data):
    """The page of the submission above: cafe-1-2.txt under the failures, no "Scored, not shown yet"."""
    one = cafe_files(data, "ds-slam")[0]
    r = post(server, [("files", (one.name, one.read_bytes())), ("files", ("cafe-1-2.txt", MISSING))])
    assert r.status_code == 201, r.text
    sid = r.json()["id"]
    challenge = server.challenge
    durations = scene_durations(challenge.scenes, challenge.data)
    views = [tuple(v) for v in challenge.views(sequences_of(durations), challenge.phase("development"))]
    folder = challenge.folder / "uploads" / sid
    plain = json.loads((folder / PLAN).read_text())
    result = score_folder(folder / "files", challenge.data, challenge.spec, plain=plain,
                          groundtruth=challenge.folder / "groundtruth", views=views)  # fmt: skip
    claimed = store.claim_next(server.engine)
    assert claimed is not None and claimed[0] == sid
    assert store.finish(server.engine, sid, claimed[1], "scored", result, None, 1.0)
    page = server.client.get(f"/submissions/{sid}").text
    assert 'id="hidden-sequences"' not in page, page
    assert "cafe-1-2.txt" in page and "no estimate stamp falls inside" in page
    view = server.client.get(f"/api/submissions/{sid}").json()
    assert view["hidden_sequences"] == [] and [f["file"] for f in view["failures"]] == ["cafe-1-2.txt"], view
