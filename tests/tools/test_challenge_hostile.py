"""Hostile uploads and requests to the challenge server: each refused with its status and a
message saying what was expected, nothing of it kept on disk or in the database, and the server
serving on. Most run in one process (TestClient, no scoring); the slow client needs a real
socket (uvicorn on 127.0.0.1)."""

from __future__ import annotations

import io
import json
import shutil
import socket
import stat
import subprocess
import threading
import time
import zipfile
from pathlib import Path

import pytest
from challenge_fixtures import cafe_files, challenge_file

pytest.importorskip("fastapi")
import uvicorn  # noqa: E402
from fastapi.testclient import TestClient  # noqa: E402

from lorisnb.errors import ParseError  # noqa: E402
from lorisnb.io.datasets.paths import SAMPLE_DATA  # noqa: E402
from lorisnb.tools.challenge import store  # noqa: E402
from lorisnb.tools.challenge.app import create_app  # noqa: E402
from lorisnb.tools.challenge.config import read_challenge  # noqa: E402

LIMITS = "upload_mb = 1\nunpacked_mb = 2\nfiles = 5\nsubmissions_per_day = 3\nupload_seconds = 1"


@pytest.fixture()
def hostile(tmp_path, data):
    challenge = read_challenge(challenge_file(tmp_path, data, limits=LIMITS))
    app = create_app(challenge, score=False)
    engine = app.state.server.engine
    token = store.add_team(engine, "team", time.time() + 7000)
    with TestClient(app) as client:
        yield dict(client=client, token=token, engine=engine, challenge=challenge, app=app)


def post(h, files, token=None, **kw):
    headers = {"Authorization": f"Bearer {h['token'] if token is None else token}"} if token != "" else {}
    return h["client"].post("/api/submissions", files=files, headers=headers, **kw)


def zipped(members: dict[str, bytes], compression=zipfile.ZIP_DEFLATED) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression) as z:
        for name, body in members.items():
            z.writestr(name, body)
    return buf.getvalue()


def nothing_kept(h) -> None:
    uploads = h["challenge"].folder / "uploads"
    assert not uploads.exists() or list(uploads.iterdir()) == []
    assert store.all_submissions(h["engine"]) == []


RESULT = b"scene: cafe\nframe: base_link\n\nseq: 1\n1560004885.5 1 2 3 0 0 0 1\n"


@pytest.mark.parametrize(
    "members, status, words",
    [
        ({"../evil.txt": RESULT}, 400, "climbs out"),
        ({"a/../../evil.txt": RESULT}, 400, "climbs out"),
        ({"/etc/evil.txt": RESULT}, 400, "absolute path"),
        ({"a\\..\\evil.txt": RESULT}, 400, "Windows path"),
        ({"C:evil.txt": RESULT}, 400, "Windows path"),
        (
            {".hidden.txt": RESULT},
            400,
            "character 1 is '.' (a hidden file: leave it out of the upload), which cannot start a name",
        ),
        ({"x.pdf": RESULT}, 415, "expected result files in a format lorisnb reads: OpenLORIS result files (.txt)"),
        ({"inner.zip": zipped({"a.txt": RESULT})}, 415, "an archive inside the archive"),
        ({"run.bag": b"#ROSBAG V2.0\n"}, 415, "a ROS bag; the challenge takes no ROS bags"),
        ({"a.txt": RESULT, "b/a.txt": RESULT}, 400, "a second file named 'a.txt'"),
        ({"bin.txt": b"\x00\x01binary" * 10}, 400, "a binary file"),
        ({"empty.txt": b"  \n"}, 400, "empty"),
        ({f"f{i}.txt": RESULT for i in range(6)}, 413, "at most 5"),
        ({"bomb.txt": b"0" * 1_500_000}, 413, "zip bomb"),  # 1.5 MB of one byte: ~1000x
        ({"big.txt": b"0" * 3_000_000}, 413, "over the challenge's limit of 2 MB"),  # declared size
    ],
)
def test_archive_refused(hostile, members, status, words):
    r = post(hostile, [("files", ("r.zip", zipped(members)))])
    assert r.status_code == status, r.text
    assert words in r.json()["error"]
    nothing_kept(hostile)


def test_archive_of_links_refused(hostile):
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        link = zipfile.ZipInfo("link.txt")
        link.external_attr = (stat.S_IFLNK | 0o777) << 16
        z.writestr(link, "/work/shared/data/openloris-scene/groundtruth/gt_cafe_1.txt")
    r = post(hostile, [("files", ("r.zip", buf.getvalue()))])
    assert r.status_code == 400 and "symbolic link" in r.json()["error"]
    nothing_kept(hostile)


def test_archive_that_lies_about_its_size(hostile):
    """A member whose header declares a small size but holds more is stopped at the limit while
    being read (the declared sizes are not trusted)."""
    body = bytes(range(256)) * 12_000  # 3 MB, not compressible below the ratio check
    raw = bytearray(zipped({"big.txt": body}, zipfile.ZIP_STORED))
    info = zipfile.ZipFile(io.BytesIO(bytes(raw))).getinfo("big.txt")
    # no honest archive: the sizes in the central directory say 100 bytes
    at = bytes(raw).rfind(b"PK\x01\x02")
    raw[at + 24 : at + 28] = (100).to_bytes(4, "little")
    raw[at + 20 : at + 24] = (100).to_bytes(4, "little")
    r = post(hostile, [("files", ("r.zip", bytes(raw)))])
    assert r.status_code in (400, 413), r.text
    assert info.file_size == len(body)
    nothing_kept(hostile)


def test_encrypted_and_broken_archives(hostile):
    raw = bytearray(zipped({"a.txt": RESULT}, zipfile.ZIP_STORED))
    at = bytes(raw).rfind(b"PK\x01\x02")
    raw[at + 8] |= 0x1  # the central directory's flag: encrypted
    r = post(hostile, [("files", ("r.zip", bytes(raw)))])
    assert r.status_code == 400 and "encrypted" in r.json()["error"]
    r = post(hostile, [("files", ("r.zip", b"PK\x03\x04 not really a zip"))])
    assert r.status_code == 400 and "not a readable zip archive" in r.json()["error"]
    nothing_kept(hostile)


@pytest.mark.parametrize(
    "name, body, status, words",
    [
        ("../../x.txt", RESULT, 400, "climbs out"),
        ("notes.docx", RESULT, 415, "TUM (.txt, .csv) or EuRoC CSV (.csv) files named after their sequence"),
        ("run.mcap", b"\x89MCAP0\r\n", 415, "the challenge takes no ROS bags"),
        ("x.txt", b"\x89PNG\r\n\x1a\n\x00\x00", 400, "binary"),
        (
            "x.txt",
            RESULT.decode().encode("utf-16"),
            400,
            "text in UTF-16 or UTF-32 (NUL bytes between the characters); save",
        ),
        ("x.txt", RESULT.decode().encode("utf-32-le"), 400, "text in UTF-16 or UTF-32"),
        ("x.txt", "é".encode("latin-1") * 20, 400, "not UTF-8 text"),
        # a small file's last byte: the allowance for a character cut at a chunk's end is not the file's end
        ("x.txt", RESULT + "é".encode("latin-1"), 400, f"not UTF-8 text (byte {len(RESULT)})"),
        ("x.txt", RESULT + "é".encode()[:1] + b"\n", 400, f"not UTF-8 text (byte {len(RESULT)})"),
        # not UTF-8 past the first chunk
        ("x.txt", RESULT + b"#" * 70_000 + b"\xff\n", 400, f"not UTF-8 text (byte {len(RESULT) + 70_000})"),
    ],
)
def test_file_refused(hostile, name, body, status, words):
    r = post(hostile, [("files", (name, body))])
    assert r.status_code == status and words in r.json()["error"], r.text
    nothing_kept(hostile)


def test_a_character_cut_by_a_chunk_is_taken(hostile):
    """UTF-8 is checked across chunks: a character cut at a chunk's end is read with the next."""
    from lorisnb.tools.challenge.uploads import CHUNK

    pad = CHUNK - len(RESULT) - 3  # '# ' and the pad: é's two bytes either side of the chunk's end
    body = RESULT + b"# " + b"a" * pad + "é".encode() + b"\n"
    assert body[CHUNK - 1 : CHUNK + 1] == "é".encode()
    r = post(hostile, [("files", ("x.txt", body))])
    assert r.status_code == 201, r.text


def test_a_form_with_no_file_chosen(hostile):
    """A browser's form sent with no file chosen has a files part named '': it said 'a file name
    with control characters'."""
    body = (b'--XX\r\nContent-Disposition: form-data; name="token"\r\n\r\n' + hostile["token"].encode()
            + b'\r\n--XX\r\nContent-Disposition: form-data; name="files"; filename=""\r\n'
            b"Content-Type: application/octet-stream\r\n\r\n\r\n--XX--\r\n")  # fmt: skip
    headers = {"Content-Type": "multipart/form-data; boundary=XX"}
    r = hostile["client"].post("/submit", content=body, headers=headers)
    assert r.status_code == 400 and "no file chosen" in r.text and "control characters" not in r.text
    auth = {"Authorization": f"Bearer {hostile['token']}"}
    r = hostile["client"].post("/api/submissions", content=body, headers=headers | auth)
    assert r.status_code == 400 and r.json()["error"].startswith("no file chosen; choose the files to upload")
    nothing_kept(hostile)


def test_huge_upload_refused_before_it_is_read(hostile, data):
    big = b"1560004885.5 1 2 3 0 0 0 1\n" * 60_000  # 1.6 MB, over upload_mb = 1
    r = post(hostile, [("files", ("big.txt", big))])
    assert r.status_code == 413 and "over the challenge's limit of 1 MB" in r.json()["error"]

    def chunks():  # no Content-Length: counted while it arrives
        for _ in range(40):
            yield b"x" * 50_000

    r = hostile["client"].post("/api/submissions", content=chunks(),
                               headers={"Authorization": f"Bearer {hostile['token']}",
                                        "Content-Type": "multipart/form-data; boundary=b"})  # fmt: skip
    assert r.status_code == 413 and "limit of 1 MB" in r.json()["error"]
    nothing_kept(hostile)


def test_malformed_requests(hostile):
    h = hostile
    auth = {"Authorization": f"Bearer {h['token']}"}
    bad = b'--b\r\nContent-Disposition: form-data; name="files"; filename="a.txt"\r\n\r\nabc'  # never ends
    r = h["client"].post("/api/submissions", content=bad, headers=auth | {"Content-Type": "multipart/form-data"})
    assert r.status_code == 400 and "malformed upload" in r.json()["error"]
    # a body cut off after a boundary (here before its only file's part ends, or after it) parses as a
    # shorter form: its missing closing boundary says it is cut off
    part = b'--b\r\nContent-Disposition: form-data; name="files"; filename="a.txt"\r\n\r\n' + RESULT
    for cut in (b"--b\r\n", part + b"\r\n--b", part + b"\r\n--b\r\n"):
        r = h["client"].post(
            "/api/submissions", content=cut, headers=auth | {"Content-Type": "multipart/form-data; boundary=b"}
        )
        assert (
            r.status_code == 400 and "malformed upload (the body ends before its closing boundary" in r.json()["error"]
        )
    r = h["client"].post("/api/submissions", content=b"{}", headers=auth | {"Content-Type": "application/json"})
    assert r.status_code == 400 and "no file in the upload" in r.json()["error"]
    r = h["client"].post("/api/submissions", data={"files": "not a file"}, headers=auth)
    assert r.status_code == 400 and "holds text, not files" in r.json()["error"]
    r = h["client"].post("/api/submissions", content=b"x", headers=auth | {"Content-Length": "lots"})
    assert r.status_code == 400 and "expected a number of bytes" in r.json()["error"]
    nothing_kept(h)


def test_tokens_refused(hostile):
    h = hostile
    files = [("files", ("a.txt", RESULT))]
    assert "no token" in post(h, files, token="").json()["error"]
    r = post(h, files, token="guessed-token")
    assert r.status_code == 401 and "unknown token" in r.json()["error"]
    old = store.add_team(h["engine"], "late", time.time() - 1)
    r = post(h, files, token=old)
    assert r.status_code == 401 and "expired" in r.json()["error"] and "'late'" in r.json()["error"]
    r = h["client"].get("/api/admin", headers={"Authorization": f"Bearer {h['token']}"})
    assert r.status_code == 403 and "needs the admin token" in r.json()["error"]
    page = h["client"].post("/submit", files=files, data={"token": "wrong"})  # the browser form
    assert page.status_code == 401 and 'id="error"' in page.text and "unknown token" in page.text
    nothing_kept(h)


def test_admin_token_does_not_submit(hostile):
    """The admin's token is refused for a submission (it would be ranked as a team), saying to add
    a team; nothing is kept, and the admin page still opens with it."""
    admin = store.add_team(hostile["engine"], "organizers", time.time() + 7000, admin=True)
    r = post(hostile, [("files", ("a.txt", RESULT))], token=admin)
    assert r.status_code == 403 and "is the admin token, which does not submit" in r.json()["error"]
    assert "lorisnb challenge add-team class.toml NAME" in r.json()["error"]
    page = hostile["client"].post("/submit", files=[("files", ("a.txt", RESULT))], data={"token": admin})
    assert page.status_code == 403 and "does not submit" in page.text
    nothing_kept(hostile)
    assert hostile["client"].get("/api/admin", headers={"Authorization": f"Bearer {admin}"}).status_code == 200


TUM = b"1560004885.5 1 2 3 0 0 0 1\n1560004885.7 1 2 3 0 0 0 1\n"
KITTI = b"1 0 0 1 0 1 0 2 0 0 1 3\n1 0 0 1.1 0 1 0 2 0 0 1 3\n"
EUROC = b"#timestamp [ns],p_x,p_y,p_z,q_w,q_x,q_y,q_z\n1560004885500000000,1,2,3,1,0,0,0\n"


@pytest.mark.parametrize(
    "name, body, fmt, status, words",
    [
        ("cafe-1-2.txt", KITTI, None, 415, "a KITTI pose file holds no stamps, and the correct rate (CR) is taken over time"),
        ("my-run.txt", TUM, None, 400, "a TUM trajectory file names no sequence; expected its name to name it as "
         "OpenLORIS names sequences, <scene>-1-<seq> (e.g. cafe-1-2.txt)"),
        ("run.csv", EUROC, None, 400, "a EuRoC CSV file names no sequence"),
        ("cafe-1-3.txt", TUM, None, 400, "names sequence cafe-1-3, which is not one of this challenge's; expected one "
         "of cafe-1-1, cafe-1-2"),
        ("office-1-1.csv", EUROC, None, 400, "expected one of cafe-1-1, cafe-1-2"),
        ("cafe-1-2.txt", b"hello world\n", None, 415, "not recognised as any format lorisnb reads"),
        ("cafe-1-2.txt", RESULT, "tum", 415, "this looks like an OpenLORIS file ('scene:' and 'frame:' headers, "
         "'seq: N' blocks of 'stamp x y z qx qy qz qw'), but the upload's format is tum"),
        ("cafe-1-2.txt", TUM, "euroc", 415, "this looks like a TUM trajectory file"),
        ("cafe-1-2.txt", TUM, "kitti", 415, "format kitti: a KITTI pose file holds no stamps"),
        ("cafe-1-2.txt", TUM, "bag", 415, "format bag: the challenge takes no ROS bags"),
        ("cafe-1-2.txt", TUM, "xyz", 400, "format 'xyz': expected auto (each file's format recognised from its "
         "content), openloris, tum or euroc"),
        ("x.txt", RESULT.replace(b"cafe", b"corridor"), None, 400, "x.txt: an OpenLORIS result file of corridor (its "
         "scene: header), which is not one of this challenge's scenes; expected cafe"),
        ("cafe-1-1.txt", RESULT.replace(b"cafe", b"Office_1"), "openloris", 400, "file of office (its scene: header)"),
    ],
)  # fmt: skip
def test_formats_refused(hostile, name, body, fmt, status, words):
    """A file of a format the challenge cannot score, a plain trajectory file whose name names no
    sequence of the challenge, a file of no format lorisnb reads and a format field that does not
    fit are refused, saying what is taken; nothing is kept."""
    r = post(hostile, [("files", (name, body))], data={"format": fmt} if fmt else None)
    assert r.status_code == status and words in r.json()["error"], r.text
    nothing_kept(hostile)


def test_formats_taken(hostile):
    """TUM and EuRoC files named after their sequence are taken, their format recognised or given,
    with their plan beside them; OpenLORIS files need none."""
    r = post(hostile, [("files", ("cafe-1-2.txt", TUM)), ("files", ("cafe_1_1_v2.csv", EUROC)),
                       ("files", ("a.txt", RESULT))])  # fmt: skip
    assert r.status_code == 201, r.text
    folder = hostile["challenge"].folder / "uploads" / r.json()["id"]
    assert json.loads((folder / "plan.json").read_text()) == {
        "cafe-1-2.txt": {"format": "tum", "scene": "cafe", "seq": 2},
        "cafe_1_1_v2.csv": {"format": "euroc", "scene": "cafe", "seq": 1},
    }
    r = post(hostile, [("files", ("Cafe-1-1_trial2.txt", TUM))], data={"format": "tum"})
    assert r.status_code == 201, r.text
    plan = hostile["challenge"].folder / "uploads" / r.json()["id"] / "plan.json"
    assert json.loads(plan.read_text()) == {"Cafe-1-1_trial2.txt": {"format": "tum", "scene": "cafe", "seq": 1}}
    r = post(hostile, [("files", ("a.txt", RESULT))], data={"format": "openloris"})
    assert (
        r.status_code == 201 and not (hostile["challenge"].folder / "uploads" / r.json()["id"] / "plan.json").exists()
    )


def test_openloris_headers_without_a_space_recognised(hostile, data):
    """VINS-Mono's published results write their headers without a space ('scene:cafe'), which the
    OpenLORIS reader reads: the format registry recognises them too, so they are taken (the load
    run of make bench sends them), not refused as of no format."""
    from lorisnb.io.readers.registry import recognise, sample

    files = cafe_files(data, "vins_mono_color_imu_with_loop")
    assert files[0].read_text().startswith("scene:cafe\n") and recognise(sample(files[0])) == ["openloris"]
    r = post(hostile, [("files", (p.name, p.read_bytes())) for p in files])
    assert r.status_code == 201, r.text
    assert not (hostile["challenge"].folder / "uploads" / r.json()["id"] / "plan.json").exists()


def test_too_many_submissions(hostile, data):
    h = hostile
    files = [("files", (p.name, p.read_bytes())) for p in cafe_files(data, "ds-slam")]
    for _ in range(3):
        assert post(h, files).status_code == 201
    r = post(h, files)
    assert r.status_code == 429 and "3 submissions in the last 24 hours" in r.json()["error"]
    assert len(store.all_submissions(h["engine"])) == 3
    assert store.queue_counts(h["engine"])["queued"] == 3


def test_closed_challenge(hostile):
    server = hostile["app"].state.server
    server.clock = lambda: hostile["challenge"].opens - 1  # not open yet
    r = post(hostile, [("files", ("a.txt", RESULT))])
    assert r.status_code == 403 and "no phase is open now" in r.json()["error"]
    assert "No phase is open now" in hostile["client"].get("/submit").text
    nothing_kept(hostile)


def test_challenge_file_refused(tmp_path, data):
    path = challenge_file(tmp_path, data)
    text = path.read_text()
    for old, new, words in [
        ('title = "Class', 'titel = "Class', "unknown key 'titel'"),
        ('scenes = ["cafe"]', 'scenes = ["office"]', "'office' has no ground truth"),
        ("sequences = { cafe = [1] }", "sequences = { cafe = [0] }", "expected a list of sequence numbers"),
        ('leaderboard = "after-close"', 'leaderboard = "never"', "leaderboard"),
        ("workers = 1", "workers = 0", "expected a whole number of 1 or more"),
        ("[limits]", '[spec]\nmode = "sideways"\n[limits]', "[spec]"),
        # a typo'd option would be dropped: phi inf, orientation never checked, the ranking changed
        ("[limits]", "[spec]\nphy = 30\n[limits]", "[spec]: unknown key 'phy'"),
        # a sequence the ground truth does not have: the phase would rank on nothing
        ("sequences = { cafe = [1] }", "sequences = { cafe = [1, 7] }", "sequence(s) 7 of cafe; expected some of 1, 2"),
    ]:
        assert old in text
        path.write_text(text.replace(old, new, 1))
        with pytest.raises(ParseError, match=None) as err:
            read_challenge(path)
        assert words in str(err.value) and str(path) in str(err.value)


@pytest.mark.parametrize(
    "old, new, words",
    [
        ("[challenge]\n", '[challenge]\ndatabase = "nonsense"\n', ["database = 'nonsense'", "not a database URL",
                                                                   "expected an SQLAlchemy database URL"]),
        ("[challenge]\n", '[challenge]\ndatabase = "sqlite:////nonexistent/dir/x.db"\n',
         ["database = 'sqlite:////nonexistent/dir/x.db'", "the folder /nonexistent/dir does not exist",
          "expected a database file in an existing folder"]),
        ("[challenge]\n", '[challenge]\ndatabase = "nosuchdb://h/x"\n', ["SQLAlchemy has no database 'nosuchdb'"]),
        ('folder = "{folder}"', 'folder = "{afile}"', ["folder = '", "is a file; expected a folder"]),
        ('folder = "{folder}"', 'folder = "{afile}/sub"', ["lies under the file", "expected a folder"]),
        ('groundtruth = "{root}"', 'groundtruth = "/nonexistent"', ["groundtruth = '/nonexistent'",
                                                                    "expected groundtruth to name a data root"]),
        ('groundtruth = "{root}"', 'groundtruth = "{root}/openloris-scene/groundtruth"',
         ["expected groundtruth to name a data root", "is inside the data root {root}: name that"]),
    ],
)  # fmt: skip
def test_challenge_keys_checked_at_start(tmp_path, data, capsys, old, new, words):
    """A wrong database (no URL, an SQLite file in a folder that does not exist), a folder that is a
    file, a groundtruth that is no data root: each refused when the file is read, naming the file,
    the key and what is expected, by serve and add-team alike (a database was a traceback of
    SQLAlchemy's, a folder one of mkdir's); no advice on --data or LORISNB_DATA, which serve has not."""
    from lorisnb.cli import main

    path = challenge_file(tmp_path, data)
    (tmp_path / "afile").write_text("x")
    names = dict(folder=tmp_path / "server", afile=tmp_path / "afile", root=data.root)
    old, new = old.format(**names), new.format(**names)
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(ParseError) as err:
        read_challenge(path)
    said = str(err.value)
    for w in [str(path), *(w.format(**names) for w in words)]:
        assert w in said, said
    for w in ("--data", "LORISNB_DATA", "data_root=", "Traceback"):
        assert w not in said, said
    assert main(["challenge", "add-team", str(path), "a team"]) != 0
    out = capsys.readouterr()
    assert "Traceback" not in out.err and words[0].format(**names) in out.err


def test_a_database_that_cannot_be_opened_is_said(tmp_path):
    from lorisnb.errors import LorisError

    with pytest.raises(LorisError, match=r"database sqlite:///.*: cannot be opened \(OperationalError"):
        store.connect(f"sqlite:///{tmp_path / 'afile' / 'x.db'}" if (tmp_path / "afile").write_text("x") else "")


def test_bundled_class_challenge():
    """The README's class challenge reads: the bundled cafe ground truth, cafe-1 in development
    (live), both sequences in the final (after it closes), the paper's thresholds; reading it
    creates nothing."""
    path = Path(__file__).resolve().parents[2] / "teaching" / "challenge" / "class.toml"
    c = read_challenge(path)
    assert c.data.root == SAMPLE_DATA and c.data.scenes_with_groundtruth() == ["cafe"]
    dev, final = c.phases
    assert dev.keeps("cafe", 1) and not dev.keeps("cafe", 2) and dev.leaderboard == "live"
    assert final.keeps("cafe", 2) and final.leaderboard == "after-close" and dev.closes == final.opens
    assert c.spec.eps == "paper" and c.spec.phi == 30.0 and c.metric == "cr"
    assert not c.folder.exists()
    # the folder the README's two commands make in a checkout (database, uploads, ground truths) is
    # ignored by git: they leave nothing for git status to show
    root = path.parents[2]
    if shutil.which("git") and (root / ".git").exists():
        for made in ("challenge.db", "challenge.db-wal", "uploads/0123456789abcdef/files/cafe-1-1.txt"):
            check = subprocess.run(["git", "-C", str(root), "check-ignore", "-q", "--no-index", str(c.folder / made)])
            assert check.returncode == 0, made


def test_make_bench_section_points_to_the_load_run():
    """The guide's ``make bench`` section names the challenge server's load run it prints, and
    where its figures are."""
    text = (Path(__file__).resolve().parents[2] / "docs" / "guide" / "many-files.md").read_text()
    section = text[text.index("## Speed and memory against the floors") :]
    section = section[: section.index("\n## ", 4)] if "\n## " in section[4:] else section
    assert "benchmarks/challenge_load.py" in section and "LORISNB_BENCH_SERVE=0" in section
    assert "(challenge-server.md)" in section


def test_slow_client_refused_and_server_serves_on(tmp_path, data):
    """A client that sends its headers and then trickles (slowloris) is answered 408 after the
    challenge's upload_seconds, while another client is served meanwhile."""
    challenge = read_challenge(challenge_file(tmp_path, data, limits=LIMITS))
    app = create_app(challenge, score=False)
    token = store.add_team(app.state.server.engine, "slow", time.time() + 7000)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_level="error"))
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    try:
        for _ in range(100):
            if server.started:
                break
            time.sleep(0.05)
        slow = socket.create_connection(("127.0.0.1", port), timeout=10)
        slow.sendall(b"POST /api/submissions HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer " + token.encode()
                     + b"\r\nContent-Type: multipart/form-data; boundary=b\r\nContent-Length: 100000\r\n\r\n--b\r\n")  # fmt: skip
        import httpx

        t0 = time.monotonic()
        assert httpx.get(f"http://127.0.0.1:{port}/api/health", timeout=5).status_code == 200
        got = b""
        while not (b"\r\n\r\n" in got and got.rstrip().endswith(b"}")) and (chunk := slow.recv(4096)):
            got += chunk  # headers, then the JSON body
        reply = got.decode()
        took = time.monotonic() - t0
        slow.close()
        assert reply.startswith("HTTP/1.1 408") and "longer than the challenge's 1 s" in reply
        assert took < 5
        assert httpx.get(f"http://127.0.0.1:{port}/", timeout=5).status_code == 200
    finally:
        server.should_exit = True
        thread.join(10)


def test_scoring_over_its_memory_limit_fails_with_the_reason(tmp_path, data):
    """A submission whose scoring needs more memory than the challenge allows (here 64 MB of
    address space, far below what numpy alone maps) is failed with the limit named."""
    challenge = read_challenge(challenge_file(tmp_path, data, limits="score_memory_mb = 64"))
    app = create_app(challenge)
    token = store.add_team(app.state.server.engine, "greedy", time.time() + 7000)
    with TestClient(app) as client:
        files = [("files", (p.name, p.read_bytes())) for p in cafe_files(data, "ds-slam")]
        r = client.post("/api/submissions", files=files, headers={"Authorization": f"Bearer {token}"})
        assert r.status_code == 201
        end = time.monotonic() + 120
        while (view := client.get(f"/api/submissions/{r.json()['id']}").json())["status"] in ("queued", "scoring"):
            assert time.monotonic() < end
            time.sleep(0.2)
        assert view["status"] == "failed", view
        assert "memory limit of 64 MB" in view["error"], view["error"]
        assert client.get("/api/health").json()["queue"]["failed"] == 1


def _spin(cpu_seconds: int) -> None:
    from lorisnb.tools.challenge.scoring import _limit

    _limit(cpu_seconds, 4_000_000_000)
    while True:
        pass


def test_scoring_over_its_time_limit_is_stopped():
    """The CPU-time limit of a scoring process stops a process that runs on (here one spinning past
    1 CPU second), and its end is told as that limit."""
    import multiprocessing

    from lorisnb.tools.challenge.scoring import stopped

    p = multiprocessing.get_context("fork").Process(target=_spin, args=(1,))
    t = time.monotonic()
    p.start()
    p.join(30)
    assert not p.is_alive() and time.monotonic() - t < 20
    assert stopped(p.exitcode, 1) == "scoring exceeded the challenge's limit of 1 CPU seconds"
    assert "exit status 3" in stopped(3, 1)


def test_framework_refusals_in_the_server_s_words(hostile):
    """A route that does not exist, a method a route does not take and a form that does not parse
    are answered as the server's own refusals: ``{"error": ...}`` naming the request on the API,
    the error page elsewhere; and the server serves on."""
    client = hostile["client"]
    r = client.get("/api/nosuch")
    assert r.status_code == 404 and "GET /api/nosuch: no such page" in r.json()["error"]
    assert "/api/leaderboard" in r.json()["error"]
    r = client.get("/api/submissions")
    assert r.status_code == 405 and r.json()["error"] == "GET /api/submissions: not allowed; expected POST"
    r = client.get("/nosuch")
    assert r.status_code == 404 and 'id="error"' in r.text and "no such page" in r.text
    r = client.post("/team", content=b"xx", headers={"Content-Type": "multipart/form-data"})
    assert r.status_code == 400 and 'id="error"' in r.text and "POST /team" in r.text
    assert client.get("/api/health").status_code == 200


def _abort_under_a_limit(memory_bytes: int) -> None:
    import faulthandler
    import os

    faulthandler.disable()  # pytest's: no traceback of the abort on the test's output
    from lorisnb.tools.challenge.scoring import _limit

    _limit(30, memory_bytes)
    os.abort()  # as Arrow does when an allocation fails under RLIMIT_AS: no MemoryError


def test_scoring_that_aborts_under_its_memory_limit_names_the_limit():
    """Arrow aborts (SIGABRT, exit status -6) where an allocation fails under the memory limit;
    that was told as 'the scorer stopped (exit status -6); tell the organizers'. A scorer ended by
    SIGABRT, SIGSEGV or SIGBUS under the limit is told as the limit; SIGKILL names both limits."""
    import multiprocessing
    import signal

    from lorisnb.tools.challenge.scoring import stopped

    p = multiprocessing.get_context("fork").Process(target=_abort_under_a_limit, args=(700_000_000,))
    p.start()
    p.join(30)
    assert p.exitcode == -signal.SIGABRT
    said = stopped(p.exitcode, 120, 700)
    assert said.startswith("scoring needed more than the challenge's memory limit of 700 MB") and "SIGABRT" in said
    assert "memory limit of 700 MB" in stopped(-signal.SIGSEGV, 120, 700)
    assert "120 CPU seconds or of 700 MB of memory" in stopped(-signal.SIGKILL, 120, 700)
    assert stopped(-signal.SIGXCPU, 120, 700) == "scoring exceeded the challenge's limit of 120 CPU seconds"
    assert "(exit status 3); tell the organizers" in stopped(3, 120, 700)


@pytest.mark.parametrize(
    "url", ["sqlite://", "sqlite:///", "sqlite:///:memory:", "sqlite:///file:x?mode=memory&uri=true"]
)
def test_an_in_memory_database_is_refused(tmp_path, url):
    """An in-memory SQLite URL passed the start check and lost add-team's token (serve: 'no such table')."""
    path = tmp_path / "c.toml"
    path.write_text(f'[challenge]\ngroundtruth = "{SAMPLE_DATA}"\ndatabase = "{url}"\nopens = 2026-01-01T00:00:00Z\ncloses = 2030-12-31T23:59:59Z\n'
                    '[[phase]]\nname = "dev"\nscenes = ["cafe"]\n', encoding="utf-8")  # fmt: skip
    with pytest.raises(ParseError, match="in-memory"):
        read_challenge(path)


def test_a_relative_sqlite_path_is_the_challenge_files(tmp_path, monkeypatch):
    """sqlite:///rel.db was opened relative to the current folder: add-team and serve started in
    two folders used two databases."""
    path = tmp_path / "c.toml"
    path.write_text(f'[challenge]\ngroundtruth = "{SAMPLE_DATA}"\ndatabase = "sqlite:///rel.db"\nopens = 2026-01-01T00:00:00Z\ncloses = 2030-12-31T23:59:59Z\n'
                    '[[phase]]\nname = "dev"\nscenes = ["cafe"]\n', encoding="utf-8")  # fmt: skip
    monkeypatch.chdir(tmp_path.parent)
    assert read_challenge(path).database == f"sqlite:///{tmp_path / 'rel.db'}"
